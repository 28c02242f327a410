//! Configuration validation: [`validate`] range-checks a [`ServoConfig`] field by field
//! against the limits of [`super::limits`] and the board's own ranges.
//!
//! Units: the config's (SI, see `stiffwall_proto::msg`); dead band and travel window in counts.
//! Invariant: a refused config reports the first offending field (in the order below) with its
//! allowed inclusive `[min, max]`; nothing else is changed.

use super::board::BoardInfo;
use super::limits::{
    MAX_COARSEN_SHIFT, MAX_DEADBAND_COUNTS, MAX_DELAY_TICKS, MAX_ENERGY_J, MAX_GROWTH_CYCLES,
    MAX_HEARTBEAT_MS, MAX_JUMP_COUNTS, MIN_COARSEN_SHIFT, MIN_DAMPING, MIN_DEADBAND_COUNTS,
    MIN_DELAY_TICKS, MIN_ENERGY_J, MIN_GROWTH_CYCLES, MIN_HEARTBEAT_MS, MIN_JUMP_COUNTS,
    MIN_STIFFNESS, MIN_VELOCITY,
};
use stiffwall_proto::{ConfigField, DamperLaw, ServoConfig};

/// A refused configuration: the field and its allowed range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConfigError {
    /// The offending field.
    pub field: ConfigField,
    /// Smallest allowed value.
    pub min: f64,
    /// Largest allowed value.
    pub max: f64,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.field == ConfigField::Damper {
            // The range is the dead band's, in counts; `difference` is the law without one.
            return write!(
                f,
                "damper: the dead band must be within [{}, {}] counts (use `difference` for no \
                 dead band)",
                self.min, self.max
            );
        }
        if self.field == ConfigField::TravelMax {
            return write!(
                f,
                "travel_max must be above travel_min, within [{}, {}] raw counts",
                self.min, self.max
            );
        }
        write!(
            f,
            "{} must be within [{}, {}]",
            self.field, self.min, self.max
        )
    }
}

impl core::error::Error for ConfigError {}

fn check_f(field: ConfigField, v: f32, min: f32, max: f32) -> Result<(), ConfigError> {
    if v.is_finite() && v >= min && v <= max {
        Ok(())
    } else {
        Err(ConfigError {
            field,
            min: f64::from(min),
            max: f64::from(max),
        })
    }
}

fn check_u(field: ConfigField, v: u32, min: u32, max: u32) -> Result<(), ConfigError> {
    if v >= min && v <= max {
        Ok(())
    } else {
        Err(ConfigError {
            field,
            min: f64::from(min),
            max: f64::from(max),
        })
    }
}

/// Range-checks every field of `cfg` for `board`, in the order: rate, delay, shift, wall
/// (stiffness, damping, force limit), supervisor (velocity, energy, growth, jump, heartbeat,
/// safe damping), damper law, travel window.
///
/// # Errors
/// The first field out of range, with its range.
pub fn validate(cfg: &ServoConfig, board: &BoardInfo) -> Result<(), ConfigError> {
    check_timing(cfg, board)?;
    check_wall(cfg, board)?;
    check_supervisor(cfg, board)?;
    check_damper_law(cfg.damper)?;
    check_travel(cfg)
}

/// The servo rate, the extra delay and the coarsening shift.
fn check_timing(cfg: &ServoConfig, board: &BoardInfo) -> Result<(), ConfigError> {
    use ConfigField as F;
    check_u(
        F::ServoRateHz,
        cfg.servo_rate_hz,
        board.min_rate_hz,
        board.max_rate_hz,
    )?;
    check_u(
        F::ExtraDelayTicks,
        cfg.extra_delay_ticks.into(),
        MIN_DELAY_TICKS.into(),
        MAX_DELAY_TICKS.into(),
    )?;
    check_u(
        F::CoarsenShift,
        cfg.coarsen_shift.into(),
        MIN_COARSEN_SHIFT.into(),
        MAX_COARSEN_SHIFT.into(),
    )
}

/// The wall's stiffness and damping (at the config's shift and rate) and the force limit.
fn check_wall(cfg: &ServoConfig, board: &BoardInfo) -> Result<(), ConfigError> {
    use ConfigField as F;
    let s = cfg.coarsen_shift;
    check_f(
        F::Stiffness,
        cfg.stiffness,
        MIN_STIFFNESS,
        board.max_stiffness(s),
    )?;
    let dmax = board.max_damping(s, cfg.servo_rate_hz);
    check_f(F::Damping, cfg.damping, MIN_DAMPING, dmax)?;
    check_f(
        F::ForceLimit,
        cfg.force_limit,
        board.force_per_code,
        board.max_force(),
    )
}

/// The supervisor's thresholds and the safe mode's damping.
fn check_supervisor(cfg: &ServoConfig, board: &BoardInfo) -> Result<(), ConfigError> {
    use ConfigField as F;
    check_f(
        F::MaxVelocity,
        cfg.max_velocity,
        MIN_VELOCITY,
        board.max_velocity(cfg.servo_rate_hz),
    )?;
    check_f(F::EnergyLimit, cfg.energy_limit, MIN_ENERGY_J, MAX_ENERGY_J)?;
    check_u(
        F::EnergyGrowthCycles,
        cfg.energy_growth_cycles.into(),
        MIN_GROWTH_CYCLES,
        MAX_GROWTH_CYCLES,
    )?;
    check_u(
        F::EncoderJumpCounts,
        cfg.encoder_jump_counts,
        MIN_JUMP_COUNTS,
        MAX_JUMP_COUNTS,
    )?;
    check_u(
        F::HeartbeatTimeoutMs,
        cfg.heartbeat_timeout_ms,
        MIN_HEARTBEAT_MS,
        MAX_HEARTBEAT_MS,
    )?;
    let dsafe = board.max_damping(0, cfg.servo_rate_hz);
    check_f(F::SafeDamping, cfg.safe_damping, MIN_DAMPING, dsafe)
}

/// The dead band of a dead-band damper law (the plain difference has none to check).
fn check_damper_law(law: DamperLaw) -> Result<(), ConfigError> {
    if let DamperLaw::DeadBand { counts } = law {
        check_u(
            ConfigField::Damper,
            counts.into(),
            MIN_DEADBAND_COUNTS.into(),
            MAX_DEADBAND_COUNTS.into(),
        )?;
    }
    Ok(())
}

/// The travel window: with both ends set, `travel_max` above `travel_min`.
fn check_travel(cfg: &ServoConfig) -> Result<(), ConfigError> {
    if let (Some(lo), Some(hi)) = (cfg.travel_min, cfg.travel_max) {
        if hi <= lo {
            return Err(ConfigError {
                field: ConfigField::TravelMax,
                min: f64::from(lo) + 1.0,
                max: f64::from(i32::MAX),
            });
        }
    }
    Ok(())
}
