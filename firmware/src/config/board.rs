//! The board description: fixed facts about the board the firmware runs on ([`BoardInfo`]),
//! the config ranges that follow from them, and the handshake reply.
//!
//! Units: Δ in m (rad) per raw count, force (torque) in N (N·m) per output code, rates in Hz.
//! Invariant: every bound here is derived from the board's facts and the limits of
//! [`super::limits`]; nothing is stored besides the facts.

use super::limits::{MAX_GAIN_CODES, MAX_JUMP_COUNTS, VEL_WINDOW};
use stiffwall_proto::{DeviceInfo, Limits, MAX_COARSEN_SHIFT, MAX_DELAY_TICKS};

/// Fixed facts about the board the firmware runs on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoardInfo {
    /// Board name.
    pub name: &'static str,
    /// Encoder resolution Δ, m (rad) per raw count.
    pub resolution: f32,
    /// Counts per revolution (rotary), 0 for linear devices.
    pub counts_per_rev: u32,
    /// Hardware counter width, bits, 1..=32 (16 and 32 are usual).
    pub encoder_bits: u8,
    /// Force (N) or torque (N·m) per output code.
    pub force_per_code: f32,
    /// Largest output code magnitude (e.g. 2047 for a 12-bit bipolar DAC).
    pub max_code: i32,
    /// Lowest servo rate the board supports, Hz.
    pub min_rate_hz: u32,
    /// Highest servo rate the board supports, Hz.
    pub max_rate_hz: u32,
}

impl Default for BoardInfo {
    /// A generic simulated board: 8192 counts/rev rotary encoder on a 16-bit counter, 16-bit
    /// bipolar output with 10 µN·m per code, 100 Hz – 20 kHz.
    fn default() -> Self {
        Self {
            name: "generic",
            resolution: core::f32::consts::TAU / 8192.0,
            counts_per_rev: 8192,
            encoder_bits: 16,
            force_per_code: 1.0e-5,
            max_code: 32767,
            min_rate_hz: 100,
            max_rate_hz: 20_000,
        }
    }
}

impl BoardInfo {
    /// Largest stiffness at coarsening shift `shift`, N/m (N·m/rad).
    #[must_use]
    pub fn max_stiffness(&self, shift: u8) -> f32 {
        2.0 * MAX_GAIN_CODES * self.force_per_code / self.delta_eff(shift)
    }

    /// Largest damping at shift `shift` and rate `rate_hz`, N·s/m.
    #[must_use]
    pub fn max_damping(&self, shift: u8, rate_hz: u32) -> f32 {
        MAX_GAIN_CODES * self.force_per_code / (self.delta_eff(shift) * rate_hz as f32)
    }

    /// Δ_eff = 2^shift · Δ, m (rad).
    #[must_use]
    pub fn delta_eff(&self, shift: u8) -> f32 {
        self.resolution * (1u32 << u32::from(shift.min(31))) as f32
    }

    /// Largest force limit, N (N·m).
    #[must_use]
    pub fn max_force(&self) -> f32 {
        self.max_code as f32 * self.force_per_code
    }

    /// Largest over-velocity threshold at `rate_hz`, m/s.
    #[must_use]
    pub fn max_velocity(&self, rate_hz: u32) -> f32 {
        (MAX_JUMP_COUNTS as f32) * self.resolution * rate_hz as f32 / VEL_WINDOW as f32
    }

    /// The handshake reply for this board at `rate_hz`.
    #[must_use]
    pub fn device_info(&self, rate_hz: u32) -> DeviceInfo {
        let s = |x: &str| heapless::String::try_from(x).unwrap_or_default();
        DeviceInfo {
            protocol_version: stiffwall_proto::PROTOCOL_VERSION,
            firmware_name: s("stiffwall"),
            firmware_version: s(env!("CARGO_PKG_VERSION")),
            board: s(self.name),
            servo_rate_hz: rate_hz,
            counts_per_rev: self.counts_per_rev,
            resolution: self.resolution,
            encoder_bits: self.encoder_bits,
            force_per_code: self.force_per_code,
            max_code: self.max_code,
            limits: Limits {
                min_rate_hz: self.min_rate_hz,
                max_rate_hz: self.max_rate_hz,
                max_stiffness: self.max_stiffness(0),
                max_force: self.max_force(),
                max_delay_ticks: MAX_DELAY_TICKS,
                max_coarsen_shift: MAX_COARSEN_SHIFT,
                telemetry_batch: stiffwall_proto::TELEMETRY_BATCH as u16,
                max_table: stiffwall_proto::MAX_TABLE as u16,
            },
        }
    }
}
