//! TOML scenes: device, controller, effects, initial state, run length and solver. std only.
//!
//! Units: a scene is either **dimensionless** (`device.mu/beta/sigma`, `controller.tau_d`,
//! `initial.xi/xidot` in ticks and ticks per period) or **physical** (`device.mass_kg`,
//! `viscous_ns_per_m`, `coulomb_n`, `resolution_m`, `controller.stiffness_n_per_m`, `period_s`,
//! `extra_delay_s`, the optional `controller.virtual_damping_ns_per_m` = B of the wall law
//! F = −K·Δ·(n+½) − B·Δ·(n_h − n_(h−1))/T, default 0, solved as β_v = B/(K·T),
//! `initial.position_m/velocity_m_per_s`), converted once with Table I of
//! `stiffwall_core`. Every effect is stated explicitly in `[effects]` (all keys required).
//! Unknown keys, missing keys, mixed unit systems and out-of-range values are [`SceneError`]s
//! that name the key and the allowed range. The composition is resolved once in
//! [`Scene::simulate`]: the exact solver is monomorphised for the effect set
//! ([`crate::exact::dispatch`]).
//!
//! Layout: `raw` holds the serde structs of the TOML format, `resolve` the checks and unit
//! conversion, this module the validated [`Scene`] and its runner.
//!
//! Invariant: a [`Scene`] returned by [`Scene::from_toml`] is valid for its solver.

mod raw;
mod resolve;

use crate::exact::{dispatch_damped, ExactSim, History, PeriodAudit, Visitor};
use crate::params::{Effects, ParamError, Params};
use crate::plant::Motion;
use crate::reference::{AmpFilter, Hand, Method, RefModel, RefSim};

/// Why a scene was rejected. Every variant names the TOML key; range errors also the range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// Not a scene in TOML: syntax, an unknown key, a missing table or a wrong type.
    #[error(transparent)]
    Toml(#[from] toml::de::Error),
    /// A value outside its allowed range (the name is the TOML key, e.g. `device.sigma`).
    #[error("{} = {}: allowed range is {}", .0.name(), .0.value(), .0.allowed())]
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
    /// The solver rejected the scene's parameters (never for a scene from [`Scene::from_toml`]).
    #[error("solver: {0}")]
    Solver(ParamError),
    /// A plant-effect key beyond the paper (stiction, cogging, transmission, amplifier limits,
    /// `counts_per_rev`: [`crate::rich`]) refused; the message names the key and the range.
    #[error("{0}")]
    Effect(String),
}

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
    pub rich: Option<crate::rich::scene::RichScene>,
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

impl Scene {
    /// Parses and validates a TOML scene.
    ///
    /// # Errors
    /// [`SceneError`] naming the offending key.
    pub fn from_toml(text: &str) -> Result<Self, SceneError> {
        let raw: raw::RawScene = toml::from_str(text)?;
        let e = &raw.effects;
        let (force_limit_n, deadband_n) = e.amplifier.limits();
        let keys = crate::rich::scene::RichKeys {
            counts_per_rev: raw.device.counts_per_rev,
            stiction: e.stiction,
            cogging: e.cogging,
            transmission: e.transmission,
            force_limit_n,
            deadband_n,
        };
        let (mut scene, scale) = Self::resolve(raw)?;
        let scale = scale.map(|s| (s.stiffness, s.period_s, s.resolution));
        scene.rich = crate::rich::scene::attach(&scene, scale, keys)?;
        Ok(scene)
    }

    /// Simulates the scene, calling `out` at τ = 0 and at every sample instant.
    ///
    /// # Errors
    /// [`SceneError::Solver`] when the solver rejects the parameters (only for a scene built
    /// by hand, not through [`Scene::from_toml`]).
    pub fn simulate(&self, out: &mut dyn FnMut(&Row)) -> Result<(), SceneError> {
        if let Some(rich) = self.rich.as_ref().filter(|r| r.needs_rich_loop()) {
            return crate::rich::scene::simulate(self, rich, out);
        }
        match self.solver {
            Solver::Exact => {
                dispatch_damped::<_, true>(
                    self.params,
                    self.effects,
                    self.init,
                    self.history,
                    self.beta_v,
                    Drive {
                        periods: self.periods,
                        out,
                    },
                )
                .map_err(SceneError::Solver)?;
            }
            Solver::Reference(method) => {
                let model = RefModel {
                    params: self.params,
                    effects: self.effects,
                    zoh: self.zoh,
                    hand: self.hand,
                    amp: self.amp,
                    history: self.history,
                };
                let sim = RefSim::new(model, method, self.init)
                    .and_then(|s| s.with_damping(self.beta_v))
                    .map_err(SceneError::Solver)?;
                Drive {
                    periods: self.periods,
                    out,
                }
                .visit(sim);
            }
        }
        Ok(())
    }
}

struct Drive<'a> {
    periods: u64,
    out: &'a mut dyn FnMut(&Row),
}

impl Visitor for Drive<'_> {
    type Output = ();
    fn visit<S: ExactSim>(self, mut s: S) {
        let mu = s.params().mu;
        let row = |s: &S, a: PeriodAudit| {
            let st = s.state();
            Row {
                period: s.period(),
                xi: st.x,
                xidot: st.v,
                phi_a: s.applied_force(),
                h_t: crate::exact::storage(mu, st.x, st.v),
                e_d: a.e_d,
                e_g: a.e_g,
                residual: a.residual,
            }
        };
        (self.out)(&row(&s, PeriodAudit::default()));
        for _ in 0..self.periods {
            s.step_period();
            (self.out)(&row(&s, s.audit()));
            if s.diverged() {
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#"
[device]
mu = 100.0
beta = 0.1
sigma = 1.0
[effects]
zoh = true
quantization = true
coulomb = true
viscous = true
delay = false
one_sided_wall = false
amplifier = { kind = "none" }
hand = { kind = "none" }
[initial]
xi = 0.0
xidot = 5.0
[run]
periods = 100
solver = { kind = "exact" }
"#;

    #[test]
    fn base_scene_parses_and_runs() {
        let s = Scene::from_toml(BASE).unwrap();
        assert_eq!(s.params, Params::BASE);
        let mut n = 0;
        s.simulate(&mut |_| n += 1).unwrap();
        assert_eq!(n, 101);
    }

    #[test]
    fn errors_name_the_key() {
        let e = Scene::from_toml(&BASE.replace("sigma = 1.0", "sigma = -1.0")).unwrap_err();
        let m = e.to_string();
        assert!(m.contains("device.sigma") && m.contains("[0, 1e6]"), "{e}");
        let e =
            Scene::from_toml(&BASE.replace("sigma = 1.0", "sigma = 1.0\nsigmaa = 2")).unwrap_err();
        assert!(e.to_string().contains("sigmaa"), "{e}");
        let e = Scene::from_toml(&BASE.replace("delay = false\n", "")).unwrap_err();
        assert!(e.to_string().contains("delay"), "{e}");
        let e = Scene::from_toml(&BASE.replace("mu = 100.0", "mass = 1.0")).unwrap_err();
        assert!(e.to_string().contains("mass"), "{e}");
    }

    /// Range errors are structured: the variant carries the key, the value and the range.
    #[test]
    fn range_errors_are_structured() {
        let e = Scene::from_toml(&BASE.replace("xidot = 5.0", "xidot = 1e13")).unwrap_err();
        match e {
            SceneError::Param(p) => {
                assert_eq!(p.name(), "initial.xidot");
                assert!(p.allowed().contains("[-1e12, 1e12]"));
            }
            other => panic!("{other:?}"),
        }
        let e = Scene::from_toml(&BASE.replace("periods = 100", "periods = 0")).unwrap_err();
        assert!(
            matches!(
                e,
                SceneError::Count {
                    key: "run.periods",
                    value: 0,
                    ..
                }
            ),
            "{e:?}"
        );
        let e = Scene::from_toml(&BASE.replace("xi = 0.0", "position_m = 0.0")).unwrap_err();
        assert!(
            matches!(e, SceneError::Conflict { key: "initial", .. }),
            "{e:?}"
        );
    }
}
