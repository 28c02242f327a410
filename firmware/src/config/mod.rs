//! Board facts, configuration validation, and the integer gains derived from a config.
//!
//! - [`board`]: the board description, [`BoardInfo`] (and the ranges that follow from it);
//! - [`limits`]: the one table of validation limits, each bound named once with its unit;
//! - [`validate()`]: the range check of a [`ServoConfig`], refusing with a [`ConfigError`];
//! - [`gains`]: the integer gains the servo runs on, [`Gains`].
//!
//! Units: [`ServoConfig`] is SI (see `stiffwall_proto::msg`); [`Gains`] are in device units:
//! output codes, raw or effective encoder counts (Δ_eff = 2^shift counts), servo ticks.
//!
//! Invariant: [`validate()`] accepts a config only if every derived gain fits its fixed-point
//! range, so [`Gains::from_config`] never saturates for a valid config. A refused config
//! reports the first offending field with its allowed `[min, max]`.
//!
//! [`ServoConfig`]: stiffwall_proto::ServoConfig

pub mod board;
pub mod gains;
pub mod limits;
mod validate;

/// Velocity clamp of the damping terms (defined beside the arithmetic that relies on it).
pub use crate::numeric::DAMPER_V_MAX;
/// The servo's integer helpers, defined beside the numeric back-ends (kept here too for the
/// paths that name them from `config`).
pub use crate::numeric::{AbsBound, RangeBound, Shift};
pub use board::BoardInfo;
pub use gains::{Gains, HOLD_BETA, HOLD_WALL_DAMPING};
pub use limits::{
    MAX_ENERGY_J, MAX_GAIN_CODES, MAX_HEARTBEAT_MS, MAX_JUMP_COUNTS, MAX_LIMIT_CODES, VEL_WINDOW,
};
pub use validate::{validate, ConfigError};

#[cfg(test)]
mod tests;
