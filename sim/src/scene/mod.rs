//! TOML scenes: device, controller, effects, initial state, run length and solver. std only.
//!
//! Units: a scene is either **dimensionless** (`device.mu/beta/sigma`, `controller.tau_d`,
//! `initial.xi/xidot` in ticks and ticks per period) or **physical** (`device.mass_kg`,
//! `viscous_ns_per_m`, `coulomb_n`, `resolution_m`, `controller.stiffness_n_per_m`, `period_s`,
//! `extra_delay_s`, the optional `controller.virtual_damping_ns_per_m` = B of the wall law
//! F = −K·Δ·(n+½) − B·Δ·(n_h − n_(h−1))/T, default 0, solved as β_v = B/(K·T); the optional
//! `controller.damper` = `"difference"` or `"dead-band-N"` is the virtual device's damper law
//! (its boot configuration; the simulators here damp the plain difference),
//! `initial.position_m/velocity_m_per_s`), converted once with Table I of
//! `stiffwall_core`. Every effect is stated explicitly in `[effects]` (all keys required).
//! Unknown keys, missing keys, mixed unit systems and out-of-range values are [`SceneError`]s
//! that name the key and the allowed range. The composition is resolved once in
//! [`Scene::simulate`]: the exact solver is monomorphised for the effect set
//! ([`crate::exact::dispatch`]).
//!
//! Layout (each file imports only those above it; this module sits on top): `error`
//! ([`SceneError`]), `raw` (the serde structs of the whole TOML format, plant effects
//! included), `spec` (the validated [`Scene`], [`Solver`], [`RichScene`], [`Row`] as data),
//! `plant_keys` (the plant-effect keys of issue 10 → [`RichScene`]), `resolve` (checks and unit
//! conversion of the paper's keys), `sampled` (the sampled loop on [`crate::rich::RichPlant`]
//! for scenes with a plant effect), `plant_file` ([`crate::rich::PlantModel::from_scene_toml`]:
//! plant files with defaults), and here [`Scene::from_toml`] and [`Scene::simulate`]. The
//! rich physics ([`crate::rich`]) knows nothing of scenes.
//!
//! Invariant: a [`Scene`] returned by [`Scene::from_toml`] is valid for its solver.

mod error;
pub mod field_bounds;
mod plant_file;
mod plant_keys;
mod raw;
mod resolve;
mod sampled;
mod spec;

pub use error::SceneError;
pub use sampled::simulate as simulate_sampled;
pub use spec::{RichScene, Row, Scene, Solver};

use crate::exact::{dispatch_damped, ExactSim, PeriodAudit, Visitor};
use crate::reference::{RefModel, RefSim};

impl Scene {
    /// Parses and validates a TOML scene.
    ///
    /// # Errors
    /// [`SceneError`] naming the offending key.
    pub fn from_toml(text: &str) -> Result<Self, SceneError> {
        let raw: raw::RawScene = toml::from_str(text)?;
        let damper = raw.controller.damper.clone();
        let e = &raw.effects;
        let (force_limit_n, deadband_n) = e.amplifier.limits();
        let keys = plant_keys::RichKeys {
            counts_per_rev: raw.device.counts_per_rev,
            stiction: e.stiction,
            cogging: e.cogging,
            transmission: e.transmission,
            travel: e.travel,
            force_limit_n,
            deadband_n,
            damper: None,
        };
        let (mut scene, scale) = resolve::resolve(raw)?;
        let keys = plant_keys::RichKeys {
            damper: resolve::damper(damper.as_deref())?,
            ..keys
        };
        let scale = scale.map(|s| (s.stiffness, s.period_s, s.resolution));
        scene.rich = plant_keys::attach(&scene, scale, keys)?;
        Ok(scene)
    }

    /// Simulates the scene, calling `out` at τ = 0 and at every sample instant.
    ///
    /// # Errors
    /// [`SceneError::Solver`] when the solver rejects the parameters (only for a scene built
    /// by hand, not through [`Scene::from_toml`]).
    pub fn simulate(&self, out: &mut dyn FnMut(&Row)) -> Result<(), SceneError> {
        if let Some(rich) = self.rich.as_ref().filter(|r| r.needs_rich_loop()) {
            return sampled::simulate(self, rich, out);
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
                    .and_then(|s| s.with_beta_v(self.beta_v))
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
    use crate::params::Params;

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
