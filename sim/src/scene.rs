//! TOML scenes: device, controller, effects, initial state, run length and solver. std only.
//!
//! Units: a scene is either **dimensionless** (`device.mu/beta/sigma`, `controller.tau_d`,
//! `initial.xi/xidot` in ticks and ticks per period) or **physical** (`device.mass_kg`,
//! `viscous_ns_per_m`, `coulomb_n`, `resolution_m`, `controller.stiffness_n_per_m`, `period_s`,
//! `extra_delay_s`, `initial.position_m/velocity_m_per_s`), converted once with Table I.
//! Every effect is stated explicitly in `[effects]` (all keys required). Unknown keys, missing
//! keys, mixed unit systems and out-of-range values are errors that name the key and the
//! allowed range. The composition is resolved once in [`Scene::simulate`]: the exact solver is
//! monomorphised for the effect set ([`crate::exact::dispatch`]).
//!
//! Invariant: a [`Scene`] returned by [`Scene::from_toml`] is valid for its solver.

use crate::exact::{dispatch, ExactSim, History, Visitor};
use crate::params::{Effects, Params};
use crate::plant::Motion;
use crate::reference::{AmpFilter, Hand, Method, RefModel, RefSim};
use serde::Deserialize;
use std::fmt;

/// A scene error (message names the key and the allowed range).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneError(pub String);

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for SceneError {}

fn err<T>(key: &str, value: impl fmt::Display, allowed: &str) -> Result<T, SceneError> {
    Err(SceneError(format!(
        "{key} = {value}: allowed range is {allowed}"
    )))
}

fn missing<T>(key: &str, allowed: &str) -> Result<T, SceneError> {
    Err(SceneError(format!("{key} is missing ({allowed})")))
}

/// Checks `lo (<|<=) value <= hi` and finiteness.
fn check(
    key: &str,
    v: f64,
    lo: f64,
    lo_open: bool,
    hi: f64,
    allowed: &str,
) -> Result<f64, SceneError> {
    let ok = v.is_finite() && (if lo_open { v > lo } else { v >= lo }) && v <= hi;
    if ok {
        Ok(v)
    } else {
        err(key, v, allowed)
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    device: RawDevice,
    #[serde(default)]
    controller: RawController,
    effects: RawEffects,
    initial: RawInitial,
    run: RawRun,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDevice {
    mu: Option<f64>,
    beta: Option<f64>,
    sigma: Option<f64>,
    mass_kg: Option<f64>,
    viscous_ns_per_m: Option<f64>,
    coulomb_n: Option<f64>,
    resolution_m: Option<f64>,
    /// Rotary device (issue 10): Δ = 2π/counts_per_rev rad.
    counts_per_rev: Option<u32>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawController {
    stiffness_n_per_m: Option<f64>,
    period_s: Option<f64>,
    extra_delay_s: Option<f64>,
    tau_d: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEffects {
    zoh: bool,
    quantization: bool,
    coulomb: bool,
    viscous: bool,
    delay: bool,
    one_sided_wall: bool,
    amplifier: RawAmp,
    hand: RawHand,
    stiction: Option<crate::rich::scene::RawStiction>,
    cogging: Option<crate::rich::scene::RawCogging>,
    transmission: Option<crate::rich::scene::RawTransmission>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
enum RawAmp {
    None {
        force_limit_n: Option<f64>,
        deadband_n: Option<f64>,
    },
    /// Pure delay of eq. (5): T_A = 2δ_A/ω_A.
    Delay {
        omega: Option<f64>,
        zeta: Option<f64>,
        cutoff_hz: Option<f64>,
        damping: Option<f64>,
        force_limit_n: Option<f64>,
        deadband_n: Option<f64>,
    },
    /// Second-order low-pass filter.
    SecondOrder {
        omega: Option<f64>,
        zeta: Option<f64>,
        cutoff_hz: Option<f64>,
        damping: Option<f64>,
        force_limit_n: Option<f64>,
        deadband_n: Option<f64>,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
enum RawHand {
    None,
    Dimensionless {
        mu: f64,
        beta: f64,
        kappa: f64,
    },
    Physical {
        mass_kg: f64,
        damping_ns_per_m: f64,
        stiffness_n_per_m: f64,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawInitial {
    xi: Option<f64>,
    xidot: Option<f64>,
    position_m: Option<f64>,
    velocity_m_per_s: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRun {
    periods: u64,
    solver: RawSolver,
    #[serde(default)]
    history: History,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
enum RawSolver {
    Exact,
    Rk4 { steps_per_period: u32 },
    Dopri { rtol: f64, atol: f64 },
}

/// (K, T, Δ) of a physical scene: N/m, s, m.
type Scale = (f64, f64, f64);

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
    /// The physical plant and controller (physical scenes only; issue 10 effects).
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
    pub fn from_toml(text: &str) -> Result<Self, SceneError> {
        let raw: RawScene = toml::from_str(text).map_err(|e| SceneError(e.to_string()))?;
        let e = &raw.effects;
        let (RawAmp::None {
            force_limit_n,
            deadband_n,
        }
        | RawAmp::Delay {
            force_limit_n,
            deadband_n,
            ..
        }
        | RawAmp::SecondOrder {
            force_limit_n,
            deadband_n,
            ..
        }) = e.amplifier;
        let keys = crate::rich::scene::RichKeys {
            counts_per_rev: raw.device.counts_per_rev,
            stiction: e.stiction,
            cogging: e.cogging,
            transmission: e.transmission,
            force_limit_n,
            deadband_n,
        };
        let (mut scene, scale) = Self::resolve(raw)?;
        scene.rich = crate::rich::scene::attach(&scene, scale, keys)?;
        Ok(scene)
    }

    fn resolve(raw: RawScene) -> Result<(Self, Option<Scale>), SceneError> {
        let d = &raw.device;
        let c = &raw.controller;
        let dimless = d.mu.is_some() || d.beta.is_some() || d.sigma.is_some();
        let physical = d.mass_kg.is_some()
            || d.viscous_ns_per_m.is_some()
            || d.coulomb_n.is_some()
            || d.resolution_m.is_some()
            || d.counts_per_rev.is_some();
        if dimless == physical {
            return Err(SceneError(
                "device: give either mu, beta, sigma (dimensionless) or mass_kg, viscous_ns_per_m, \
                 coulomb_n, resolution_m (physical), not both or neither"
                    .into(),
            ));
        }
        // Scale (K, T, Δ) for physical scenes.
        let mut scale = None;
        let (mu, beta, sigma, mut tau_d);
        if dimless {
            mu = check(
                "device.mu",
                d.mu.map_or_else(|| missing("device.mu", "> 0"), Ok)?,
                0.0,
                true,
                1e12,
                "(0, 1e12]",
            )?;
            beta = check(
                "device.beta",
                d.beta.map_or_else(|| missing("device.beta", ">= 0"), Ok)?,
                0.0,
                false,
                1e6,
                "[0, 1e6]",
            )?;
            sigma = check(
                "device.sigma",
                d.sigma
                    .map_or_else(|| missing("device.sigma", ">= 0"), Ok)?,
                0.0,
                false,
                1e6,
                "[0, 1e6]",
            )?;
            if c.stiffness_n_per_m.is_some() || c.period_s.is_some() || c.extra_delay_s.is_some() {
                return Err(SceneError(
                    "controller: stiffness_n_per_m, period_s, extra_delay_s belong to physical scenes; \
                     a dimensionless scene uses controller.tau_d"
                        .into(),
                ));
            }
            tau_d = check(
                "controller.tau_d",
                c.tau_d.unwrap_or(0.0),
                0.0,
                false,
                250.0,
                "[0, 250] periods",
            )?;
        } else {
            let m = check(
                "device.mass_kg",
                d.mass_kg
                    .map_or_else(|| missing("device.mass_kg", "kg, > 0"), Ok)?,
                0.0,
                true,
                1e6,
                "(0, 1e6] kg",
            )?;
            let b = check(
                "device.viscous_ns_per_m",
                d.viscous_ns_per_m
                    .map_or_else(|| missing("device.viscous_ns_per_m", "N s/m, >= 0"), Ok)?,
                0.0,
                false,
                1e9,
                "[0, 1e9] N s/m",
            )?;
            let cc = check(
                "device.coulomb_n",
                d.coulomb_n
                    .map_or_else(|| missing("device.coulomb_n", "N, >= 0"), Ok)?,
                0.0,
                false,
                1e9,
                "[0, 1e9] N",
            )?;
            let delta = check(
                "device.resolution_m",
                match (d.resolution_m, d.counts_per_rev) {
                    (Some(_), Some(_)) => {
                        return Err(SceneError(
                            "device: give resolution_m or counts_per_rev, not both".into(),
                        ))
                    }
                    (None, Some(n)) => crate::rich::scene::rotary_resolution(n)?,
                    (r, None) => r.map_or_else(|| missing("device.resolution_m", "m, > 0"), Ok)?,
                },
                0.0,
                true,
                1.0,
                "(0, 1] m",
            )?;
            let k = check(
                "controller.stiffness_n_per_m",
                c.stiffness_n_per_m
                    .map_or_else(|| missing("controller.stiffness_n_per_m", "N/m, > 0"), Ok)?,
                0.0,
                true,
                1e12,
                "(0, 1e12] N/m",
            )?;
            let t = check(
                "controller.period_s",
                c.period_s
                    .map_or_else(|| missing("controller.period_s", "s, > 0"), Ok)?,
                0.0,
                true,
                10.0,
                "(0, 10] s",
            )?;
            if c.tau_d.is_some() {
                return Err(SceneError(
                    "controller.tau_d belongs to dimensionless scenes; use controller.extra_delay_s".into(),
                ));
            }
            let td = check(
                "controller.extra_delay_s",
                c.extra_delay_s.unwrap_or(0.0),
                0.0,
                false,
                250.0 * t,
                "[0, 250 periods] s",
            )?;
            mu = m / (k * t * t);
            beta = b / (k * t);
            sigma = cc / (k * delta);
            tau_d = td / t;
            scale = Some((k, t, delta));
        }
        let e = &raw.effects;
        let mut amp = None;
        let amp_params = |omega: Option<f64>,
                          zeta: Option<f64>,
                          hz: Option<f64>,
                          damp: Option<f64>,
                          key: &str|
         -> Result<(f64, f64), SceneError> {
            match (omega, zeta, hz, damp, scale) {
                (Some(w), Some(z), None, None, None) => Ok((
                    check(&format!("{key}.omega"), w, 0.0, true, 1e9, "(0, 1e9] rad/period")?,
                    check(&format!("{key}.zeta"), z, 0.0, true, 100.0, "(0, 100]")?,
                )),
                (None, None, Some(f), Some(z), Some((_, t, _))) => Ok((
                    check(&format!("{key}.cutoff_hz"), f, 0.0, true, 1e12, "(0, 1e12] Hz")? * 2.0 * std::f64::consts::PI * t,
                    check(&format!("{key}.damping"), z, 0.0, true, 100.0, "(0, 100]")?,
                )),
                _ => Err(SceneError(format!(
                    "{key}: dimensionless scenes give omega (rad/period) and zeta; physical scenes give cutoff_hz and damping"
                ))),
            }
        };
        match raw.effects.amplifier {
            RawAmp::None { .. } => {}
            RawAmp::Delay {
                omega,
                zeta,
                cutoff_hz,
                damping,
                ..
            } => {
                let (w, z) = amp_params(omega, zeta, cutoff_hz, damping, "effects.amplifier")?;
                if !e.delay {
                    return Err(SceneError(
                        "effects.amplifier: kind = \"delay\" needs effects.delay = true".into(),
                    ));
                }
                tau_d += 2.0 * z / w;
            }
            RawAmp::SecondOrder {
                omega,
                zeta,
                cutoff_hz,
                damping,
                ..
            } => {
                let (w, z) = amp_params(omega, zeta, cutoff_hz, damping, "effects.amplifier")?;
                amp = Some(AmpFilter { omega: w, zeta: z });
            }
        }
        if !e.delay && tau_d > 0.0 {
            return err("controller.tau_d", tau_d, "0 when effects.delay = false");
        }
        if tau_d > 250.0 {
            return err("controller.tau_d", tau_d, "total delay [0, 250] periods");
        }
        let hand = match raw.effects.hand {
            RawHand::None => None,
            RawHand::Dimensionless { mu, beta, kappa } => {
                if scale.is_some() {
                    return Err(SceneError(
                        "effects.hand: a physical scene uses kind = \"physical\"".into(),
                    ));
                }
                Some(Hand {
                    mu: check("effects.hand.mu", mu, 0.0, false, 1e12, "[0, 1e12]")?,
                    beta: check("effects.hand.beta", beta, 0.0, false, 1e9, "[0, 1e9]")?,
                    kappa: check("effects.hand.kappa", kappa, 0.0, false, 1e9, "[0, 1e9]")?,
                })
            }
            RawHand::Physical {
                mass_kg,
                damping_ns_per_m,
                stiffness_n_per_m,
            } => {
                let Some((k, t, _)) = scale else {
                    return Err(SceneError(
                        "effects.hand: a dimensionless scene uses kind = \"dimensionless\"".into(),
                    ));
                };
                Some(Hand {
                    mu: check(
                        "effects.hand.mass_kg",
                        mass_kg,
                        0.0,
                        false,
                        1e6,
                        "[0, 1e6] kg",
                    )? / (k * t * t),
                    beta: check(
                        "effects.hand.damping_ns_per_m",
                        damping_ns_per_m,
                        0.0,
                        false,
                        1e9,
                        "[0, 1e9] N s/m",
                    )? / (k * t),
                    kappa: check(
                        "effects.hand.stiffness_n_per_m",
                        stiffness_n_per_m,
                        0.0,
                        false,
                        1e12,
                        "[0, 1e12] N/m",
                    )? / k,
                })
            }
        };
        let i = &raw.initial;
        let init = match (i.xi, i.xidot, i.position_m, i.velocity_m_per_s, scale) {
            (Some(x), Some(v), None, None, None) => Motion {
                x: check("initial.xi", x, -1e12, false, 1e12, "[-1e12, 1e12] ticks")?,
                v: check(
                    "initial.xidot",
                    v,
                    -1e12,
                    false,
                    1e12,
                    "[-1e12, 1e12] ticks/period",
                )?,
            },
            (None, None, Some(x), Some(v), Some((_, t, delta))) => Motion {
                x: check("initial.position_m", x, -1e6, false, 1e6, "[-1e6, 1e6] m")? / delta,
                v: check(
                    "initial.velocity_m_per_s",
                    v,
                    -1e6,
                    false,
                    1e6,
                    "[-1e6, 1e6] m/s",
                )? * t
                    / delta,
            },
            (_, _, _, _, None) => {
                return Err(SceneError(
                    "initial: a dimensionless scene gives xi and xidot".into(),
                ))
            }
            _ => {
                return Err(SceneError(
                    "initial: a physical scene gives position_m and velocity_m_per_s".into(),
                ))
            }
        };
        let r = &raw.run;
        if r.periods == 0 || r.periods > 100_000_000 {
            return err("run.periods", r.periods, "[1, 1e8]");
        }
        let solver = match r.solver {
            RawSolver::Exact => Solver::Exact,
            RawSolver::Rk4 { steps_per_period } => {
                if !(1..=100_000).contains(&steps_per_period) {
                    return err(
                        "run.solver.steps_per_period",
                        steps_per_period,
                        "[1, 100000]",
                    );
                }
                Solver::Reference(Method::Rk4 { steps_per_period })
            }
            RawSolver::Dopri { rtol, atol } => Solver::Reference(Method::Dopri {
                rtol: check("run.solver.rtol", rtol, 1e-15, false, 1.0, "[1e-15, 1]")?,
                atol: check("run.solver.atol", atol, 1e-300, false, 1.0, "[1e-300, 1]")?,
            }),
        };
        if solver == Solver::Exact && (amp.is_some() || hand.is_some() || !e.zoh) {
            return Err(SceneError(
                "run.solver: kind = \"exact\" needs effects.zoh = true, amplifier kind \"none\" or \"delay\" \
                 and hand kind \"none\"; use rk4 or dopri"
                    .into(),
            ));
        }
        if !e.zoh && tau_d > 0.0 {
            return err("effects.zoh", false, "true when a delay is simulated");
        }
        let effects = Effects {
            quantization: e.quantization,
            coulomb: e.coulomb,
            viscous: e.viscous,
            delay: e.delay,
            one_sided: e.one_sided_wall,
        };
        Ok((
            Self {
                params: Params {
                    mu,
                    beta,
                    sigma,
                    tau_d,
                },
                effects,
                zoh: e.zoh,
                amp,
                hand,
                init,
                periods: r.periods,
                solver,
                history: r.history,
                rich: None,
            },
            scale,
        ))
    }

    /// Simulates the scene, calling `out` at τ = 0 and at every sample instant.
    pub fn simulate(&self, out: &mut dyn FnMut(&Row)) -> Result<(), SceneError> {
        if let Some(rich) = self.rich.as_ref().filter(|r| r.needs_rich_loop()) {
            return crate::rich::scene::simulate(self, rich, out);
        }
        match self.solver {
            Solver::Exact => {
                dispatch::<_, true>(
                    self.params,
                    self.effects,
                    self.init,
                    self.history,
                    Drive {
                        periods: self.periods,
                        out,
                    },
                )
                .map_err(|e| SceneError(e.to_string()))?;
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
                let sim =
                    RefSim::new(model, method, self.init).map_err(|e| SceneError(e.to_string()))?;
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
        let row = |s: &S, a: crate::exact::PeriodAudit| {
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
        (self.out)(&row(&s, Default::default()));
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
        assert!(
            e.0.contains("device.sigma") && e.0.contains("[0, 1e6]"),
            "{e}"
        );
        let e =
            Scene::from_toml(&BASE.replace("sigma = 1.0", "sigma = 1.0\nsigmaa = 2")).unwrap_err();
        assert!(e.0.contains("sigmaa"), "{e}");
        let e = Scene::from_toml(&BASE.replace("delay = false\n", "")).unwrap_err();
        assert!(e.0.contains("delay"), "{e}");
        let e = Scene::from_toml(&BASE.replace("mu = 100.0", "mass = 1.0")).unwrap_err();
        assert!(e.0.contains("mass"), "{e}");
    }
}
