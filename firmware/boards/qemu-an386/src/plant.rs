//! The simulated bench: motor, encoder and current amplifier of the paper's Sec. V rig
//! (Maxon RE35, 8192 counts/rev, 14-bit output), simulated exactly by `stiffwall-sim`.
//!
//! Units: SI (rad, rad/s, N·m). The encoder is read at the sample instant; the force code
//! written by the servo is held (ZOH) for one servo period; the amplifier is ideal (the rig's
//! 3 kHz amplifier lag is negligible at 1 kHz, Sec. V).

use stiffwall_firmware::{BoardInfo, Encoder, ForceOutput};
use stiffwall_sim::PhysicalPlant;

/// Rotor inertia, kg·m² (Sec. V).
pub const INERTIA: f64 = 6.28e-6;
/// Viscous friction, N·m·s/rad (Sec. V).
pub const VISCOUS: f64 = 9e-6;
/// Coulomb friction, N·m (Sec. V).
pub const COULOMB: f64 = 2e-3;
/// Encoder counts per revolution (Sec. V).
pub const COUNTS_PER_REV: u32 = 8192;
/// Torque per output code, N·m: a 14-bit bipolar output (±8191 codes) spanning ±0.1 N·m.
pub const TORQUE_PER_CODE: f32 = 0.1 / 8191.0;

/// What the firmware is told about this board.
pub fn board_info() -> BoardInfo {
    BoardInfo {
        name: "qemu-an386",
        resolution: core::f32::consts::TAU / COUNTS_PER_REV as f32,
        counts_per_rev: COUNTS_PER_REV,
        // A 16-bit hardware counter, so the firmware's wrap handling is exercised.
        encoder_bits: 16,
        force_per_code: TORQUE_PER_CODE,
        max_code: 8191,
        min_rate_hz: 100,
        max_rate_hz: 10_000,
    }
}

/// Simulated motor + encoder + amplifier.
#[derive(Debug)]
pub struct Bench {
    plant: PhysicalPlant,
    torque: f64,
}

impl Bench {
    /// The rig at rest at angle 0.
    pub fn new() -> Self {
        let resolution = core::f64::consts::TAU / f64::from(COUNTS_PER_REV);
        // The constants above are valid, so this cannot fail; trap if they ever are not.
        let plant = match PhysicalPlant::new(INERTIA, VISCOUS, COULOMB, resolution) {
            Ok(p) => p,
            Err(_) => cortex_m::asm::udf(),
        };
        Self { plant, torque: 0.0 }
    }

    /// Advances the rig by one servo period with the torque last written.
    pub fn advance(&mut self, period_s: f64) {
        self.plant.advance(self.torque, period_s);
    }
}

impl Bench {
    /// The raw 16-bit quadrature counter at this instant: the low 16 bits of the true count.
    pub fn raw_count(&self) -> u32 {
        (self.plant.encoder_count() as i32 as u32) & 0xffff
    }

    /// Applies an output code (held until the next call).
    pub fn set_code(&mut self, code: i32) {
        self.torque = f64::from(code) * f64::from(TORQUE_PER_CODE);
    }
}

/// The encoder as sampled at a servo instant.
#[derive(Debug, Clone, Copy)]
pub struct Sampled(pub u32);

impl Encoder for Sampled {
    fn count(&mut self) -> u32 {
        self.0
    }
}

/// The output code the servo wrote this tick.
#[derive(Debug, Clone, Copy, Default)]
pub struct Written(pub i32);

impl ForceOutput for Written {
    fn write(&mut self, code: i32) {
        self.0 = code;
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
