//! The simulated bench: the Impulse Engine 2000 row of the paper's Table II (m = 0.032 kg,
//! b = 0.02 N·s/m, c = 0.024 N, Δ = 31.4 µm), simulated exactly by `stiffwall-sim`, behind a
//! 16-bit encoder counter and a 16-bit bipolar current output.
//!
//! Why this device and not the Sec. V rig: it is the one Table II device whose viscous friction
//! was measured rather than bounded, so every region of Fig. 3 is reachable at 1 kHz with a
//! usable force resolution (region A: K < 2b/T = 40 N/m is 4 output codes per tick; region C:
//! K > 2c/Δ ≈ 1529 N/m). On the Sec. V rig region A needs K < 0.018 N·m/rad, less than one
//! output code per tick.
//!
//! Units: SI (m, m/s, N). The encoder is read at the sample instant; the force code written by
//! the servo is held (ZOH) for one servo period; the amplifier is ideal.

use stiffwall_firmware::{BoardInfo, Encoder, ForceOutput};
use stiffwall_sim::PhysicalPlant;

/// Mass, kg (Table II, Impulse Engine).
pub const MASS: f64 = 0.032;
/// Viscous friction, N·s/m (Table II).
pub const VISCOUS: f64 = 0.02;
/// Coulomb friction, N (Table II).
pub const COULOMB: f64 = 0.024;
/// Encoder resolution, m (Table II).
pub const RESOLUTION: f64 = 31.4e-6;
/// Force per output code, N: ±32767 codes span ±4.9 N.
pub const FORCE_PER_CODE: f32 = 1.5e-4;

/// What the firmware is told about this board.
pub fn board_info() -> BoardInfo {
    BoardInfo {
        name: "qemu-an386",
        resolution: RESOLUTION as f32,
        counts_per_rev: 0,
        // A 16-bit hardware counter, so the firmware's wrap handling is exercised.
        encoder_bits: 16,
        force_per_code: FORCE_PER_CODE,
        max_code: 32_767,
        min_rate_hz: 100,
        max_rate_hz: 10_000,
    }
}

/// Simulated device + encoder + amplifier.
#[derive(Debug)]
pub struct Bench {
    plant: PhysicalPlant,
    force: f64,
}

impl Bench {
    /// The device at rest at x = 0.
    pub fn new() -> Self {
        // The constants above are valid, so this cannot fail; trap if they ever are not.
        let plant = match PhysicalPlant::new(MASS, VISCOUS, COULOMB, RESOLUTION) {
            Ok(p) => p,
            Err(_) => cortex_m::asm::udf(),
        };
        Self { plant, force: 0.0 }
    }

    /// Advances the device by one servo period with the force last written.
    pub fn advance(&mut self, period_s: f64) {
        self.plant.advance(self.force, period_s);
    }
}

impl Default for Bench {
    fn default() -> Self {
        Self::new()
    }
}

impl Bench {
    /// The raw 16-bit quadrature counter at this instant: the low 16 bits of the true count.
    pub fn raw_count(&self) -> u32 {
        (self.plant.encoder_count() as i32 as u32) & 0xffff
    }

    /// Applies an output code (held until the next call).
    pub fn set_code(&mut self, code: i32) {
        self.force = f64::from(code) * f64::from(FORCE_PER_CODE);
    }
}

impl Encoder for Bench {
    fn count(&mut self) -> u32 {
        self.raw_count()
    }
}

impl ForceOutput for Bench {
    fn write(&mut self, code: i32) {
        self.set_code(code);
    }
}
