//! The simulated plant behind the emulated board: `stiffwall-sim`'s `RichPlant` (a `--device`
//! preset's rigid plant, or a `--plant` scene file's), advanced in emulated time under the force
//! the board drives, its position read by TIM2 as encoder counts.
//!
//! Units: emulated time in 1/720 MHz units (`periph::UNITS_PER_S`); position in rad (m for a
//! linear device); force in N·m (N). Invariants: the plant is advanced lazily, exactly to the
//! instant the firmware reads the encoder or changes the output, under the force held since the
//! last change (zero-order hold in continuous time, as on hardware); the encoder count is
//! floor(position / Δ_rig) with the Δ of the image's rig record (firmware/boards/nucleo-f446re/
//! src/rig.rs; 2π/8192 rad by default), because the image reports that resolution to the host.
//!
//! Output stage (firmware/boards/nucleo-f446re/README.md): `dac`: V_PA4 = DOR·3.3 V/4096, the
//! op-amp gives 6.81·(V_PA4 − 1.65 V), the amplifier's gain is chosen so that ±1800 codes
//! (±9.876 V) is the rig's full scale `DEVICE_FULL_SCALE` (0.1 N·m by default) exactly; `pwm`: force =
//! ±full scale × duty / 0.98, negative when DIR (PA9) is high. Both are zero while the enable
//! pin (PB10) is low.

use crate::image::Rig;
use stiffwall_sim::rich::RichPlant;

/// Time units per second: 1/720 MHz, which divides evenly into every clock of the 180 MHz tree.
pub const UNITS_PER_S: u64 = 720_000_000;

/// What the board drives at its force output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceState {
    /// Amplifier / bridge enable (PB10 high, push-pull output).
    pub enabled: bool,
    /// DAC output register when the DAC drives PA4.
    pub dac_code: Option<u32>,
    /// PWM duty (0..1) on PA8 when TIM1 drives it.
    pub duty: Option<f64>,
    /// DIR (PA9) high.
    pub dir_high: bool,
}

/// DAC reference (VDDA), V.
pub const VDDA: f64 = 3.3;
/// Op-amp stage gain Rf/R1 (README).
pub const OPAMP_GAIN: f64 = 6.81;
/// Mid-scale voltage V_mid, V.
pub const V_MID: f64 = 1.65;
/// DAC codes at full scale (force.rs `MAX_CODE`, dac build).
pub const DAC_FULL_SCALE_CODES: f64 = 1800.0;
/// PWM duty at full scale (force.rs `DUTY_LIMIT_PERCENT`).
pub const PWM_FULL_SCALE_DUTY: f64 = 0.98;

/// The plant and its coupling to the board's pins.
#[derive(Debug)]
pub struct Coupling {
    plant: Option<RichPlant>,
    /// Time the plant has been advanced to.
    at: u64,
    /// Force applied since `at`, N·m.
    force: f64,
    /// Last output state.
    pub state: Option<ForceState>,
    /// Output changes seen.
    pub changes: u64,
    /// The rig the image describes: its Δ reads the encoder, its full scale sizes the output.
    rig: Rig,
}

impl Coupling {
    /// Couples `plant` (None: a plant that never moves, for bring-up runs) through the default
    /// rig ([`Rig::SEC_V`]).
    pub fn new(plant: Option<RichPlant>) -> Self {
        Self {
            plant,
            at: 0,
            force: 0.0,
            state: None,
            changes: 0,
            rig: Rig::SEC_V,
        }
    }

    /// The rig the plant is coupled through.
    pub fn rig(&self) -> Rig {
        self.rig
    }

    /// The same, through `rig`.
    pub fn with_rig(self, rig: Rig) -> Self {
        Self { rig, ..self }
    }

    /// The force the output stage makes of `s`, N·m (N).
    pub fn force_of(&self, s: ForceState) -> f64 {
        if !s.enabled {
            return 0.0;
        }
        if let Some(code) = s.dac_code {
            let v = f64::from(code) * VDDA / 4096.0;
            let v_amp = OPAMP_GAIN * (v - V_MID);
            let full_scale_v = OPAMP_GAIN * DAC_FULL_SCALE_CODES * VDDA / 4096.0;
            return self.rig.full_scale * v_amp / full_scale_v;
        }
        if let Some(d) = s.duty {
            let f = self.rig.full_scale * d / PWM_FULL_SCALE_DUTY;
            return if s.dir_high { -f } else { f };
        }
        0.0
    }

    /// Advances the plant to `now` under the held force.
    pub fn advance_to(&mut self, now: u64) {
        if now > self.at {
            if let Some(p) = self.plant.as_mut() {
                p.advance(self.force, (now - self.at) as f64 / UNITS_PER_S as f64);
            }
            self.at = now;
        }
    }

    /// A new output state from `now` on.
    pub fn set_force(&mut self, now: u64, s: ForceState) {
        self.advance_to(now);
        self.force = self.force_of(s);
        self.state = Some(s);
        self.changes += 1;
    }

    /// The force held now, N·m.
    pub fn force(&self) -> f64 {
        self.force
    }

    /// The encoder count at `now` (rig resolution).
    pub fn count_at(&mut self, now: u64) -> i64 {
        self.advance_to(now);
        self.count()
    }

    /// The encoder count at the plant's current time.
    pub fn count(&self) -> i64 {
        match &self.plant {
            Some(p) => (p.position_m() / self.rig.resolution).floor() as i64,
            None => 0,
        }
    }

    /// Position, rad (m).
    pub fn position(&self) -> f64 {
        self.plant.as_ref().map_or(0.0, RichPlant::position_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dac_full_scale_and_sign() {
        let s = |code| ForceState {
            enabled: true,
            dac_code: Some(code),
            duty: None,
            dir_high: false,
        };
        let c = Coupling::new(None);
        let full = Rig::SEC_V.full_scale;
        assert!((c.force_of(s(2048 + 1800)) - full).abs() < 1e-12);
        assert!((c.force_of(s(2048 - 1800)) + full).abs() < 1e-12);
        assert_eq!(c.force_of(s(2048)), 0.0);
        let phantom = c.with_rig(Rig {
            counts_per_rev: 0,
            resolution: 29.1e-6,
            full_scale: 8.5,
        });
        assert!((phantom.force_of(s(2048 + 900)) - 4.25).abs() < 1e-9);
        // 0.20 V .. 3.10 V at the pin.
        assert!(((2048.0 - 1800.0) * VDDA / 4096.0 - 0.2).abs() < 0.01);
        assert!(((2048.0 + 1800.0) * VDDA / 4096.0 - 3.1).abs() < 0.01);
    }
}
