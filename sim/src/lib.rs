//! `stiffwall-sim`: plants and solvers for the haptic loop of eq. (7)–(9) of Diolaiti et al.
//!
//! Units: the dimensionless model of Table I (τ in sampling periods, ξ in encoder ticks, ξ̇ in
//! ticks per period, φ in K·Δ, energies in K·Δ²) except [`plant::PhysicalPlant`], which is SI.
//!
//! # no_std core (no allocation)
//! - [`exact`]: the exact event-driven solver ([`exact::Exact`], built for a runtime effect set
//!   by [`exact::dispatch`]); ≥ 20 M periods/s on one core.
//! - [`mod@reference`]: fixed-step RK4 and adaptive Dormand–Prince 5(4) with event location, for
//!   comparison and for effects outside the exact solver's reach (amplifier filter, hand).
//! - [`dopri`]: the one Dormand–Prince 5(4) / RK4 stepper (generic over the state dimension,
//!   event location) under both reference integrators.
//! - [`classify`]: growing / persistent / non-monotonically / monotonically decaying.
//! - [`bounds`]: the paper's per-period energy bounds (47), (58) and the tight ones.
//!
//! # Stepping API for the firmware and the virtual device
//! ```
//! use stiffwall_sim::plant::PhysicalPlant;
//! // m = 0.25 kg, b = 0.01 N·s/m, c = 0.06 N, encoder resolution Δ = 20 µm.
//! let mut plant = PhysicalPlant::new(0.25, 0.01, 0.06, 20e-6).unwrap();
//! plant.set_state(0.0, 0.01);
//! let count = plant.encoder_count();            // ⌊x/Δ⌋, read by the servo tick
//! let force_n = -2400.0 * 20e-6 * (count as f64 + 0.5); // eq. (2)
//! let state = plant.advance(force_n, 1e-3);     // exact state one period (1 ms) later
//! assert!(state.x > 0.0);
//! ```
//! In dimensionless units, [`plant::DimensionlessPlant::step_period`]`(phi_a)` returns the exact
//! state at the next sample instant and `encoder_count()` is ⌊ξ⌋;
//! [`plant::DimensionlessPlant::step`]`(phi_a, dtau)` covers fractional delays. The lower-level
//! [`plant::advance`] steps a [`plant::Body`] of (μ, β, σ) or (m, b, c) over one interval.
//!
//! # Plants beyond the paper (issue 10)
//! [`rich`]: stiction, cogging, compliant transmission, amplifier saturation and dead band;
//! [`rich::RichPlant`] is the stepping plant of a scene for the virtual device.
//!
//! # std feature
//! [`scene`] (TOML scenes) and [`map`] (parallel (β, σ) sweeps).
#![cfg_attr(not(feature = "std"), no_std)]
#![warn(missing_docs)]

pub mod bounds;
pub mod classify;
pub mod dopri;
pub mod exact;
pub mod math;
pub mod params;
pub mod plant;
pub mod reference;
pub mod rich;

#[cfg(feature = "std")]
pub mod map;
#[cfg(feature = "std")]
pub mod scene;

pub use exact::{dispatch, dispatch_damped, Exact, ExactSim, History, PeriodAudit, Visitor};
pub use params::{Effects, ParamError, Params};
pub use plant::{Body, DimensionlessPlant, Motion, PhysicalPlant};
