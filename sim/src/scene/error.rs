//! [`SceneError`]: why a scene or plant file was rejected. std only.
//!
//! Units: none (messages quote the values as written, in the key's own unit). Invariant: every
//! variant names the TOML key; range errors also give the value and the allowed range, so a
//! message alone says what to change.

use crate::params::ParamError;

/// Why a scene was rejected. Every variant names the TOML key; range errors also the range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// Not a scene in TOML: syntax, an unknown key, a missing table or a wrong type.
    #[error(transparent)]
    Toml(#[from] toml::de::Error),
    /// A value outside its allowed range (the name is the TOML key, e.g. `device.sigma`).
    /// The value is written as `{:?}` (`1e300`, not 301 digits).
    #[error("{} = {:?}: allowed range is {}", .0.name(), .0.value(), .0.allowed())]
    Param(#[from] ParamError),
    /// A key the scene's unit system requires is missing.
    #[error("{key} is missing ({allowed})")]
    Missing {
        /// The TOML key, e.g. `device.mu`.
        key: &'static str,
        /// What the key must hold.
        allowed: &'static str,
    },
    /// An integer key outside its range.
    #[error("{key} = {value}: allowed range is {allowed}")]
    Count {
        /// The TOML key, e.g. `run.periods`.
        key: &'static str,
        /// The value given.
        value: u64,
        /// The allowed range.
        allowed: &'static str,
    },
    /// Keys that do not fit together (mixed unit systems, a solver that cannot run the effects).
    #[error("{key}: {reason}")]
    Conflict {
        /// The TOML key or table.
        key: &'static str,
        /// What is required instead.
        reason: &'static str,
    },
    /// The solver rejected the scene's parameters (never for a scene from
    /// [`crate::scene::Scene::from_toml`]).
    #[error("solver: {0}")]
    Solver(ParamError),
    /// `controller.damper` is not one of its forms (`"difference"`, `"dead-band-N"` with N in
    /// 1..=[`crate::rich::MAX_DAMPER_DEAD_BAND`]).
    #[error(
        "controller.damper = {value:?}: allowed forms are \"difference\" and \"dead-band-N\" with N \
         in 1..={max} (a dead band of N counts per tick; \"difference\" for none)",
        max = crate::rich::MAX_DAMPER_DEAD_BAND
    )]
    Damper {
        /// The value given.
        value: String,
    },
    /// A plant-effect key beyond the paper (stiction, cogging, transmission, amplifier limits,
    /// `counts_per_rev`: [`crate::rich`]) refused; the message names the key and the range.
    #[error("{0}")]
    Effect(String),
}
