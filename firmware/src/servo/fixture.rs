//! Shared fixtures of the servo's unit tests: the binary-exact board, the K = 8 wall, counts
//! and the telemetry drained from a host port.

use super::*;
use crate::channels::HostPort;
use crate::hal::SampledCount as Enc;

/// Binary-exact units: Δ = 2^-13 m, 2^-10 N per code, so k_half = K/16 codes exactly, and at
/// 1024 Hz g_B = 128·B codes per count per tick.
pub(super) fn board() -> BoardInfo {
    BoardInfo {
        resolution: 1.0 / 8192.0,
        force_per_code: 1.0 / 1024.0,
        max_code: 30000,
        encoder_bits: 32,
        ..BoardInfo::default()
    }
}

/// A K = 8 wall (k_half = ½: the spring's code at effective count n is exactly −n) at
/// 1024 Hz, 20 N limit, no heartbeat (no host here).
pub(super) fn wall() -> ServoConfig {
    ServoConfig {
        stiffness: 8.0,
        servo_rate_hz: 1024,
        force_limit: 20.0,
        heartbeat_timeout_ms: 0,
        ..ServoConfig::default()
    }
}

/// The encoder reading of raw count `c`.
pub(super) fn count(c: i32) -> Enc {
    Enc(c as u32)
}

/// The telemetry samples queued so far.
pub(super) fn samples(hp: &mut HostPort<'_>) -> std::vec::Vec<Sample> {
    let mut v = std::vec::Vec::new();
    while let Some(i) = hp.telemetry.dequeue() {
        v.push(i.sample);
    }
    v
}
