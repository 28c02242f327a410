//! What the firmware is told about the device wired to this board: encoder resolution, counter
//! width, force per output code, servo-rate range, and the boot configuration.
//!
//! **Edit the three `DEVICE_*` constants for your hardware** (they are reported to the host in the
//! handshake, and every SI number on the wire — stiffness, force limit, energies — depends on
//! them). The defaults describe the paper's Sec. V rig, the same device the QEMU image simulates:
//! a rotary motor with a 2048-line encoder (8192 counts/rev after ×4 decoding) and ±0.1 N·m
//! full-scale torque.
//!
//! Units: rad (m for a linear device) per count; N·m (N) per code; Hz.

use crate::force::MAX_CODE;
use stiffwall_firmware::BoardInfo;
use stiffwall_proto::ServoConfig;

/// Encoder counts per revolution after ×4 quadrature decoding (0 for a linear device, and then
/// set `DEVICE_RESOLUTION` in metres per count).
pub const DEVICE_COUNTS_PER_REV: u32 = 8192;
/// Encoder resolution Δ: rad (or m) per count.
pub const DEVICE_RESOLUTION: f32 = core::f32::consts::TAU / DEVICE_COUNTS_PER_REV as f32;
/// Torque (N·m) or force (N) at full-scale output (±`MAX_CODE`): motor torque constant ×
/// amplifier transconductance (A/V) × 9.9 V for the `dac` build (README), motor torque constant
/// × current-regulation limit at 98 % duty for a current-mode H-bridge in the `pwm` build.
pub const DEVICE_FULL_SCALE: f32 = 0.1;

/// Servo rates the board supports, Hz (TIM7 reaches any of them; above 10 kHz telemetry can't
/// keep up with the 921600-baud link anyway).
pub const MIN_RATE_HZ: u32 = 100;
/// Highest servo rate, Hz.
pub const MAX_RATE_HZ: u32 = 10_000;

/// The board facts for the firmware core.
pub fn board_info() -> BoardInfo {
    BoardInfo {
        name: if cfg!(feature = "pwm") {
            "nucleo-f446re-pwm"
        } else {
            "nucleo-f446re-dac"
        },
        resolution: DEVICE_RESOLUTION,
        counts_per_rev: DEVICE_COUNTS_PER_REV,
        // TIM2 is a 32-bit counter (encoder.rs).
        encoder_bits: 32,
        force_per_code: DEVICE_FULL_SCALE / MAX_CODE as f32,
        max_code: MAX_CODE,
        min_rate_hz: MIN_RATE_HZ,
        max_rate_hz: MAX_RATE_HZ,
    }
}

/// Boot configuration when no valid config is stored: the core's safe defaults (wall off,
/// K = 0, until the host sets one; 1 kHz), with the force limit at a quarter of full scale and
/// a 50 mJ energy limit, so a first power-up on real hardware is gentle.
pub fn defaults() -> ServoConfig {
    ServoConfig {
        force_limit: 0.25 * DEVICE_FULL_SCALE,
        energy_limit: 0.05,
        ..ServoConfig::default()
    }
}
