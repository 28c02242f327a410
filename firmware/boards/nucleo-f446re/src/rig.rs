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
//!
//! The highest servo rate is 10 kHz ([`MAX_RATE_HZ`]). Feature `bench-20khz` (a measurement
//! image built only by `cargo xtask board-emu --bench`, never for a real board) raises it to
//! 20 kHz and changes nothing else, so the board emulator can measure the cycles and CPU load
//! at 20 kHz, recording every second sample.

use crate::force::MAX_CODE;
use stiffwall_firmware::BoardInfo;
use stiffwall_proto::ServoConfig;

/// Encoder counts per revolution after ×4 quadrature decoding (0 for a linear device, and then
/// set `DEVICE_RESOLUTION` in metres per count).
#[cfg(not(feature = "rig-phantom"))]
pub const DEVICE_COUNTS_PER_REV: u32 = 8192;
/// Encoder resolution Δ: rad (or m) per count.
#[cfg(not(feature = "rig-phantom"))]
pub const DEVICE_RESOLUTION: f32 = core::f32::consts::TAU / DEVICE_COUNTS_PER_REV as f32;
/// Torque (N·m) or force (N) at full-scale output (±`MAX_CODE`): motor torque constant ×
/// amplifier transconductance (A/V) × 9.9 V for the `dac` build (README), motor torque constant
/// × current-regulation limit at 98 % duty for a current-mode H-bridge in the `pwm` build.
#[cfg(not(feature = "rig-phantom"))]
pub const DEVICE_FULL_SCALE: f32 = 0.1;

// A worked example of a linear device (feature `rig-phantom`, used by the board emulator's
// tests): Table II's SensAble Phantom 1.0, Δ = 29.1 µm at the endpoint and 8.5 N full scale.
/// Linear: no counts per revolution.
#[cfg(feature = "rig-phantom")]
pub const DEVICE_COUNTS_PER_REV: u32 = 0;
/// Encoder resolution Δ at the endpoint, m per count.
#[cfg(feature = "rig-phantom")]
pub const DEVICE_RESOLUTION: f32 = 29.1e-6;
/// Endpoint force at full-scale output, N.
#[cfg(feature = "rig-phantom")]
pub const DEVICE_FULL_SCALE: f32 = 8.5;

/// The rig as one record in flash with a fixed layout, for tools that read the image rather than
/// trust its name (the board emulator couples its plant through it, and refuses a plant the
/// record does not describe): `RIG_MAGIC`, then counts/rev (u32), Δ (f32) and full scale (f32),
/// little-endian, 20 bytes. [`board_info`] reports these same fields to the host.
#[repr(C)]
pub struct RigRecord {
    /// `RIG_MAGIC`: the record's tag and layout version.
    pub magic: [u8; 8],
    /// [`DEVICE_COUNTS_PER_REV`].
    pub counts_per_rev: u32,
    /// [`DEVICE_RESOLUTION`].
    pub resolution: f32,
    /// [`DEVICE_FULL_SCALE`].
    pub full_scale: f32,
}

/// Tag and layout version of [`RigRecord`].
pub const RIG_MAGIC: [u8; 8] = *b"SWRIG\x00\x00\x01";

/// This image's rig.
pub static RIG: RigRecord = RigRecord {
    magic: RIG_MAGIC,
    counts_per_rev: DEVICE_COUNTS_PER_REV,
    resolution: DEVICE_RESOLUTION,
    full_scale: DEVICE_FULL_SCALE,
};

/// Servo rates the board supports, Hz (TIM7 reaches any of them; above 10 kHz telemetry can't
/// keep up with the 921600-baud link anyway).
pub const MIN_RATE_HZ: u32 = 100;
/// Highest servo rate, Hz.
#[cfg(not(feature = "bench-20khz"))]
pub const MAX_RATE_HZ: u32 = 10_000;
/// Highest servo rate of the measurement image (feature `bench-20khz`), Hz: the board
/// emulator's 20 kHz rows, recorded at decimation 2.
#[cfg(feature = "bench-20khz")]
pub const MAX_RATE_HZ: u32 = 20_000;

/// The board facts for the firmware core.
pub fn board_info() -> BoardInfo {
    // Read through an opaque reference, so the record is kept in flash (not folded away) and
    // the host is told exactly what the record says.
    let rig = core::hint::black_box(&RIG);
    BoardInfo {
        name: if cfg!(feature = "pwm") {
            "nucleo-f446re-pwm"
        } else {
            "nucleo-f446re-dac"
        },
        resolution: rig.resolution,
        counts_per_rev: rig.counts_per_rev,
        // TIM2 is a 32-bit counter (encoder.rs).
        encoder_bits: 32,
        force_per_code: rig.full_scale / MAX_CODE as f32,
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
