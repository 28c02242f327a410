//! The validated scene as data: [`Scene`] (dimensionless, Table I units), its [`Solver`], the
//! physical plant of a physical scene ([`RichScene`]) and the output [`Row`]. std only.
//!
//! Units: Table I (τ in sampling periods, ξ in ticks, φ in K·Δ, energies in K·Δ²), except
//! [`RichScene`], which is SI (its [`PlantModel`] and [`Controller`]). Invariant: a value built
//! by [`Scene::from_toml`] passes its solver's validation; this module only holds the types.

use crate::dopri::OdeMethod;
use crate::exact::History;
use crate::params::{Effects, Params};
use crate::plant::Motion;
use crate::reference::{AmpFilter, Hand, Method};
use crate::rich::{Controller, PlantModel};

/// Which solver runs a scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Solver {
    /// The exact event-driven solver.
    Exact,
    /// A reference integrator.
    Reference(Method),
}

/// A validated scene in dimensionless units.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// μ, β, σ, τ_D (τ_D includes an amplifier modelled as a pure delay).
    pub params: Params,
    /// Dimensionless virtual damping β_v = B/(K·T) of the wall law (0: spring only; a
    /// physical scene's `controller.virtual_damping_ns_per_m`).
    pub beta_v: f64,
    /// Effects shared with the exact solver.
    pub effects: Effects,
    /// Sample-and-hold (false: continuous spring, reference solvers only).
    pub zoh: bool,
    /// Amplifier filter (reference solvers only).
    pub amp: Option<AmpFilter>,
    /// Hand (reference solvers only).
    pub hand: Option<Hand>,
    /// Initial state.
    pub init: Motion,
    /// Number of sampling periods to simulate.
    pub periods: u64,
    /// Solver.
    pub solver: Solver,
    /// Delay-line history.
    pub history: History,
    /// The physical plant and controller with the effects beyond the paper (physical scenes
    /// only; [`crate::rich`]).
    pub rich: Option<RichScene>,
}

/// One output row, at a sample instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// Sample index h (τ = h).
    pub period: u64,
    /// ξ(h).
    pub xi: f64,
    /// ξ̇(h).
    pub xidot: f64,
    /// Force applied at the start of the next period.
    pub phi_a: f64,
    /// H_T(h) (35).
    pub h_t: f64,
    /// E_d over the previous period (28).
    pub e_d: f64,
    /// E_g over the previous period (29).
    pub e_g: f64,
    /// Residual of (26) over the previous period.
    pub residual: f64,
}

/// The physical plant and controller of a physical scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RichScene {
    /// The plant.
    pub model: PlantModel,
    /// The controller (boot configuration of the virtual device).
    pub controller: Controller,
    /// Engine of the sampled loop: `None` exact, otherwise the scene's reference integrator.
    pub method: Option<OdeMethod>,
}

impl RichScene {
    /// Whether the sampled loop on [`crate::rich::RichPlant`] (rather than the paper-model
    /// solvers) must run the scene.
    #[must_use]
    pub fn needs_rich_loop(&self) -> bool {
        self.model.has_new_effects()
    }
}
