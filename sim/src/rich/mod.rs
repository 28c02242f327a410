//! The plant beyond the paper's model (issue 10): static friction with Stribeck decay,
//! cogging, a compliant transmission, amplifier saturation and dead band, on top of the
//! existing hand, amplifier filter, extra delay and one-sided wall; and the device's travel
//! (issue 46): end stops, a one-sided spring and damper at each end.
//!
//! Units: SI (m, m/s, kg, N, N·s/m, N/m, s); rotary devices (`device.counts_per_rev`) read the
//! same keys in rad, rad/s, kg·m², N·m, N·m·s/rad, N·m/rad.
//!
//! Final names of the contract (PLANT_API.md):
//! - [`PlantModel`] (validated model; [`PlantModel::force_limit_n`], [`PlantModel::is_exact`]),
//!   [`Controller`] (stiffness_n_per_m, period_s, extra_delay_s — includes an amplifier of kind
//!   `"delay"` —, one_sided, quantization);
//! - [`PlantModel::from_scene_toml`]`(text) -> Result<(PlantModel, Controller), SceneError>`
//!   (std): a physical scene, `[initial]` and `[run]` optional — the scene format, its parsing
//!   and its errors live in [`crate::scene`] (which implements this method), not here;
//! - [`RichPlant::new`]`(&model) -> Result<RichPlant, ModelError>` (it validates the public
//!   fields), `set_state(x, v)`, `advance(force_cmd_n, dt_s)`, `encoder_count()`,
//!   `position_m()`, `velocity_m_per_s()`, plus `link_position_m()`, `actuator_force_n()`,
//!   `is_stuck()`, `is_exact()`;
//! - [`RichPlant::with_method`] picks the engine (exact or [`OdeMethod`], the stepper of
//!   [`crate::dopri`]).
//!
//! Modules: [`model`] (parameters and validation), [`friction`] (Stribeck curve, stick rule,
//! closed-form static/dynamic switch), [`linear`] (the exact engine between events),
//! [`plant`] ([`RichPlant`]). The stepper is [`crate::dopri`]. Physical failures (a model
//! value out of range, an engine the model cannot use) are [`ModelError`]s naming the field and
//! the range.
//!
//! Exactness: a rigid plant with a static/dynamic switch (`stribeck_m_per_s = 0`), dead band
//! and saturation is stepped in closed form ([`friction::advance_switch`]); with a
//! transmission, a hand or an amplifier filter (and its output clamp) the plant is linear
//! between events and stepped exactly by [`linear`] (matrix exponential, events located on the
//! closed form); only cogging (sin x₁) and Stribeck decay (exp(−v²)) are nonlinear between
//! events and use the reference integrator. Invariant: no allocation in the stepping plant;
//! the no_std build contains everything; nothing here imports [`crate::scene`].

pub mod friction;
pub mod linear;
pub mod model;
pub mod plant;

pub use crate::dopri::{OdeMethod, OdeStats};
pub use model::{
    Amplifier, Cogging, Controller, HandSi, ModelError, PlantModel, Stiction, Transmission, Travel,
    WallDamper, HARD_STOP_DAMPING_RATIO, HARD_STOP_HZ, MAX_DAMPER_DEAD_BAND,
};
pub use plant::{RichPlant, State, NS};
