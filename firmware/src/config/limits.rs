//! The table of validation limits: every bound [`super::validate`] checks a field against,
//! named once here with its unit, and the fixed-point bounds the derived gains rely on.
//!
//! Bounds that depend on the board (rate range, stiffness, damping, force, velocity) are
//! computed by [`super::BoardInfo`] from the constants below; the rest are these constants.
//! Every range is inclusive, `[MIN_…, MAX_…]`. Invariant: a config within every range derives
//! gains that fit their fixed-point formats (see [`super::Gains`]).

pub use stiffwall_proto::{MAX_COARSEN_SHIFT, MAX_DEADBAND_COUNTS, MAX_DELAY_TICKS};

/// Largest |gain| accepted, output codes per count (keeps `I16F16` and `I32F32` in range).
pub const MAX_GAIN_CODES: f32 = 16384.0;
/// Largest force clamp, codes (keeps the spring product far from the `i32` range).
pub const MAX_LIMIT_CODES: i32 = 1 << 24;
/// Smallest extra delay, ticks ([`MAX_DELAY_TICKS`] is the largest).
pub const MIN_DELAY_TICKS: u8 = 0;
/// Smallest coarsening shift, bits ([`MAX_COARSEN_SHIFT`] is the largest).
pub const MIN_COARSEN_SHIFT: u8 = 0;
/// Smallest stiffness, N/m (N·m/rad); the largest is [`super::BoardInfo::max_stiffness`].
pub const MIN_STIFFNESS: f32 = 0.0;
/// Smallest damping (of the wall and of safe mode), N·s/m (N·m·s/rad); the largest is
/// [`super::BoardInfo::max_damping`].
pub const MIN_DAMPING: f32 = 0.0;
/// Smallest over-velocity threshold, m/s (rad/s; 0 = off); the largest is
/// [`super::BoardInfo::max_velocity`].
pub const MIN_VELOCITY: f32 = 0.0;
/// Smallest energy limit, J (any positive energy).
pub const MIN_ENERGY_J: f32 = f32::MIN_POSITIVE;
/// Largest energy limit, J.
pub const MAX_ENERGY_J: f32 = 1.0e6;
/// Smallest energy-monitor growth score that trips, oscillation peaks.
pub const MIN_GROWTH_CYCLES: u32 = 1;
/// Largest energy-monitor growth score that trips, oscillation peaks.
pub const MAX_GROWTH_CYCLES: u32 = 64;
/// Smallest encoder-jump threshold, counts per tick.
pub const MIN_JUMP_COUNTS: u32 = 1;
/// Largest encoder-jump threshold, counts per tick.
pub const MAX_JUMP_COUNTS: u32 = 1 << 30;
/// Smallest heartbeat timeout, ms (0 = off).
pub const MIN_HEARTBEAT_MS: u32 = 0;
/// Largest heartbeat timeout, ms.
pub const MAX_HEARTBEAT_MS: u32 = 600_000;
/// Smallest dead band of the dead-band damper law, effective counts per tick (no dead band is
/// the `difference` law); [`MAX_DEADBAND_COUNTS`] is the largest.
pub const MIN_DEADBAND_COUNTS: u8 = 1;
/// Velocity window of the over-velocity check, ticks (power of two): the largest velocity
/// threshold is [`MAX_JUMP_COUNTS`] per this many ticks.
pub const VEL_WINDOW: usize = 8;
