//! Resolution of a [`RawScene`] into a validated [`Scene`]: unit system, ranges, Table I.
//!
//! Units: a physical scene is converted once through `stiffwall_core`'s Table I
//! ([`PhysicalParams::to_dimensionless`] and [`Scale`]); the amplifier delay is core's eq. (5)
//! ([`amplifier_delay`]). Every range check is `stiffwall_core::params::check_range`, so an
//! error names the TOML key and the allowed range; a physical device's and controller's keys
//! are checked against their field's one range of [`super::field_bounds`] (the command line's
//! too). Invariant: the returned scene passes the
//! solver's own validation (μ > 0, β, σ ≥ 0, 0 ≤ τ_D ≤ [`MAX_TAU_D`]).

use super::error::SceneError;
use super::field_bounds::{
    FieldBounds, COULOMB, COUNTS_PER_REV, MASS, PERIOD, RESOLUTION, STIFFNESS, VISCOUS,
};
use super::plant_keys::rotary_resolution;
use super::raw::{
    RawAmp, RawController, RawDevice, RawHand, RawInitial, RawRun, RawScene, RawSolver,
};
use super::spec::{Scene, Solver};
use crate::params::{Effects, Params, MAX_TAU_D};
use crate::plant::Motion;
use crate::reference::{AmpFilter, Hand, Method};
use crate::rich::WallDamper;
use stiffwall_core::params::{amplifier_delay, check_range, PhysicalParams, Scale};

/// `check_range` with the error converted to a [`SceneError`].
fn range(
    key: &'static str,
    value: f64,
    lo: f64,
    lo_open: bool,
    hi: f64,
    allowed: &'static str,
) -> Result<f64, SceneError> {
    Ok(check_range(key, value, lo, lo_open, hi, allowed)?)
}

fn need(key: &'static str, value: Option<f64>, allowed: &'static str) -> Result<f64, SceneError> {
    value.ok_or(SceneError::Missing { key, allowed })
}

fn conflict<T>(key: &'static str, reason: &'static str) -> Result<T, SceneError> {
    Err(SceneError::Conflict { key, reason })
}

/// [`Params`] of the device and controller, and the Table I scale of a physical scene.
fn device(raw: &RawScene) -> Result<(Params, Option<Scale>), SceneError> {
    let d: &RawDevice = &raw.device;
    let c = &raw.controller;
    let dimless = d.mu.is_some() || d.beta.is_some() || d.sigma.is_some();
    let phys = d.mass_kg.is_some()
        || d.viscous_ns_per_m.is_some()
        || d.coulomb_n.is_some()
        || d.resolution_m.is_some()
        || d.counts_per_rev.is_some();
    if dimless == phys {
        return conflict(
            "device",
            "give either mu, beta, sigma (dimensionless) or mass_kg, viscous_ns_per_m, \
             coulomb_n, resolution_m (physical), not both or neither",
        );
    }
    if dimless {
        dimensionless(d, c)
    } else {
        physical(d, c)
    }
}

/// The device of a dimensionless scene (μ, β, σ; τ_D from `controller.tau_d`).
fn dimensionless(d: &RawDevice, c: &RawController) -> Result<(Params, Option<Scale>), SceneError> {
    let mu = need("device.mu", d.mu, "> 0")?;
    let beta = need("device.beta", d.beta, ">= 0")?;
    let sigma = need("device.sigma", d.sigma, ">= 0")?;
    if c.stiffness_n_per_m.is_some()
        || c.period_s.is_some()
        || c.extra_delay_s.is_some()
        || c.virtual_damping_ns_per_m.is_some()
        || c.damper.is_some()
    {
        return conflict(
            "controller",
            "stiffness_n_per_m, virtual_damping_ns_per_m, damper, period_s, extra_delay_s \
             belong to physical scenes; a dimensionless scene uses controller.tau_d",
        );
    }
    let params = Params {
        mu: range("device.mu", mu, 0.0, true, 1e12, "(0, 1e12]")?,
        beta: range("device.beta", beta, 0.0, false, 1e6, "[0, 1e6]")?,
        sigma: range("device.sigma", sigma, 0.0, false, 1e6, "[0, 1e6]")?,
        tau_d: range(
            "controller.tau_d",
            c.tau_d.unwrap_or(0.0),
            0.0,
            false,
            MAX_TAU_D,
            "[0, 250] periods",
        )?,
    };
    Ok((params, None))
}

/// The device and controller of a physical scene, converted through Table I; every key is
/// checked against its field's one range ([`super::field_bounds`], the same as the command line's).
fn physical(d: &RawDevice, c: &RawController) -> Result<(Params, Option<Scale>), SceneError> {
    let rot = d.counts_per_rev.is_some();
    let m = need("device.mass_kg", d.mass_kg, MASS.allowed)?;
    let b = need(
        "device.viscous_ns_per_m",
        d.viscous_ns_per_m,
        VISCOUS.allowed,
    )?;
    let cc = need("device.coulomb_n", d.coulomb_n, COULOMB.allowed)?;
    let delta = match (d.resolution_m, d.counts_per_rev) {
        (Some(_), Some(_)) => {
            return conflict("device", "give resolution_m or counts_per_rev, not both")
        }
        (None, Some(n)) => {
            COUNTS_PER_REV.check("device.counts_per_rev", f64::from(n), true)?;
            rotary_resolution(n)?
        }
        (r, None) => RESOLUTION.check(
            "device.resolution_m",
            need("device.resolution_m", r, RESOLUTION.allowed)?,
            false,
        )?,
    };
    let k = need(
        "controller.stiffness_n_per_m",
        c.stiffness_n_per_m,
        STIFFNESS.allowed,
    )?;
    let t = need("controller.period_s", c.period_s, PERIOD.allowed)?;
    if c.tau_d.is_some() {
        return conflict(
            "controller.tau_d",
            "belongs to dimensionless scenes; use controller.extra_delay_s",
        );
    }
    let t = PERIOD.check("controller.period_s", t, rot)?;
    let p = PhysicalParams {
        mass: MASS.check("device.mass_kg", m, rot)?,
        viscous: VISCOUS.check("device.viscous_ns_per_m", b, rot)?,
        coulomb: COULOMB.check("device.coulomb_n", cc, rot)?,
        resolution: delta,
        period_s: t,
        stiffness: STIFFNESS.check("controller.stiffness_n_per_m", k, rot)?,
        delay_s: FieldBounds::check_delay(
            "controller.extra_delay_s",
            c.extra_delay_s.unwrap_or(0.0),
            Some(t),
        )?,
        rotational: rot,
    };
    Ok((p.to_dimensionless()?, Some(p.scale())))
}

/// `controller.virtual_damping_ns_per_m` (B, N·s/m or N·m·s/rad; default 0) of a physical
/// scene as the dimensionless β_v = B/(K·T) of the solvers, checked against
/// [`super::field_bounds::DAMPING`]'s range and β_v ≤ [`crate::exact::MAX_BETA_V`], with one
/// message for both. The firmware's own limit (which depends
/// on the board) is checked where the virtual device builds its boot configuration.
fn virtual_damping(raw: &RawScene, scale: Option<Scale>) -> Result<f64, SceneError> {
    let (Some(b), Some(s)) = (raw.controller.virtual_damping_ns_per_m, scale) else {
        return Ok(0.0);
    };
    let kt = s.stiffness * s.period_s;
    let b = FieldBounds::check_damping(
        "controller.virtual_damping_ns_per_m",
        b,
        raw.device.counts_per_rev.is_some(),
        Some(kt),
    )?;
    Ok(b / kt)
}

/// `controller.damper`: the virtual device's damper law, `"difference"` or `"dead-band-N"`
/// (`None` when not given: the firmware's default).
pub(super) fn damper(value: Option<&str>) -> Result<Option<WallDamper>, SceneError> {
    value
        .map(|v| {
            WallDamper::parse(v).ok_or_else(|| SceneError::Damper {
                value: v.to_owned(),
            })
        })
        .transpose()
}

/// Largest amplifier bandwidth ω, rad per sampling period: the reference solvers resolve the
/// filter, so their run time grows linearly with ω (at 1e4 a 1000-period scene takes seconds).
const MAX_AMP_OMEGA: f64 = 1e4;

/// The amplifier: a pure delay added to τ_D, or a filter for the reference solvers.
fn amplifier(
    amp: &RawAmp,
    delay: bool,
    scale: Option<Scale>,
    tau_d: &mut f64,
) -> Result<Option<AmpFilter>, SceneError> {
    const KEY: &str = "effects.amplifier";
    let (omega, zeta, hz, damp, pure_delay) = match *amp {
        RawAmp::None { .. } => return Ok(None),
        RawAmp::Delay {
            omega,
            zeta,
            cutoff_hz,
            damping,
            ..
        } => (omega, zeta, cutoff_hz, damping, true),
        RawAmp::SecondOrder {
            omega,
            zeta,
            cutoff_hz,
            damping,
            ..
        } => (omega, zeta, cutoff_hz, damping, false),
    };
    let (w, z) = match (omega, zeta, hz, damp, scale) {
        (Some(w), Some(z), None, None, None) => (
            range(
                "effects.amplifier.omega",
                w,
                0.0,
                true,
                MAX_AMP_OMEGA,
                "(0, 1e4] rad/period (the reference solvers' run time grows with omega)",
            )?,
            range("effects.amplifier.zeta", z, 0.0, true, 100.0, "(0, 100]")?,
        ),
        (None, None, Some(f), Some(z), Some(s)) => (
            s.omega(
                range(
                    "effects.amplifier.cutoff_hz",
                    f,
                    0.0,
                    true,
                    MAX_AMP_OMEGA / s.omega(core::f64::consts::TAU),
                    "(0, 1e4 / (2 pi T)] Hz, i.e. at most 1e4 rad per sampling period \
                     (1.59 MHz at T = 1 ms): the reference solvers' run time grows with the cutoff",
                )? * core::f64::consts::TAU,
            ),
            range("effects.amplifier.damping", z, 0.0, true, 100.0, "(0, 100]")?,
        ),
        _ => {
            return conflict(
                KEY,
                "dimensionless scenes give omega (rad/period) and zeta; physical scenes give \
                 cutoff_hz and damping",
            )
        }
    };
    if !pure_delay {
        return Ok(Some(AmpFilter { omega: w, zeta: z }));
    }
    if !delay {
        return conflict(KEY, "kind = \"delay\" needs effects.delay = true");
    }
    *tau_d += amplifier_delay(w, z);
    Ok(None)
}

/// The hand in contact, in Table I units.
fn hand(hand: &RawHand, scale: Option<Scale>) -> Result<Option<Hand>, SceneError> {
    Ok(match *hand {
        RawHand::None => None,
        RawHand::Dimensionless { mu, beta, kappa } => {
            if scale.is_some() {
                return conflict("effects.hand", "a physical scene uses kind = \"physical\"");
            }
            Some(Hand {
                mu: range("effects.hand.mu", mu, 0.0, false, 1e12, "[0, 1e12]")?,
                beta: range("effects.hand.beta", beta, 0.0, false, 1e9, "[0, 1e9]")?,
                kappa: range("effects.hand.kappa", kappa, 0.0, false, 1e9, "[0, 1e9]")?,
            })
        }
        RawHand::Physical {
            mass_kg,
            damping_ns_per_m,
            stiffness_n_per_m,
        } => {
            let Some(s) = scale else {
                return conflict(
                    "effects.hand",
                    "a dimensionless scene uses kind = \"dimensionless\"",
                );
            };
            Some(Hand {
                mu: s.mu(range(
                    "effects.hand.mass_kg",
                    mass_kg,
                    0.0,
                    false,
                    1e6,
                    "[0, 1e6] kg",
                )?),
                beta: s.beta(range(
                    "effects.hand.damping_ns_per_m",
                    damping_ns_per_m,
                    0.0,
                    false,
                    1e9,
                    "[0, 1e9] N s/m",
                )?),
                kappa: s.kappa(range(
                    "effects.hand.stiffness_n_per_m",
                    stiffness_n_per_m,
                    0.0,
                    false,
                    1e12,
                    "[0, 1e12] N/m",
                )?),
            })
        }
    })
}

/// The initial state in ticks and ticks per period.
fn initial(i: &RawInitial, scale: Option<Scale>) -> Result<Motion, SceneError> {
    match (i.xi, i.xidot, i.position_m, i.velocity_m_per_s, scale) {
        (Some(x), Some(v), None, None, None) => Ok(Motion {
            x: range("initial.xi", x, -1e12, false, 1e12, "[-1e12, 1e12] ticks")?,
            v: range(
                "initial.xidot",
                v,
                -1e12,
                false,
                1e12,
                "[-1e12, 1e12] ticks/period",
            )?,
        }),
        (None, None, Some(x), Some(v), Some(s)) => Ok(Motion {
            x: s.xi(range(
                "initial.position_m",
                x,
                -1e6,
                false,
                1e6,
                "[-1e6, 1e6] m",
            )?),
            v: s.xidot(range(
                "initial.velocity_m_per_s",
                v,
                -1e6,
                false,
                1e6,
                "[-1e6, 1e6] m/s",
            )?),
        }),
        (_, _, _, _, None) => conflict("initial", "a dimensionless scene gives xi and xidot"),
        _ => conflict(
            "initial",
            "a physical scene gives position_m and velocity_m_per_s",
        ),
    }
}

/// The solver of `[run]`.
fn solver(r: &RawRun) -> Result<Solver, SceneError> {
    if r.periods == 0 || r.periods > 100_000_000 {
        return Err(SceneError::Count {
            key: "run.periods",
            value: r.periods,
            allowed: "[1, 1e8]",
        });
    }
    Ok(match r.solver {
        RawSolver::Exact => Solver::Exact,
        RawSolver::Rk4 { steps_per_period } => {
            if !(1..=100_000).contains(&steps_per_period) {
                return Err(SceneError::Count {
                    key: "run.solver.steps_per_period",
                    value: u64::from(steps_per_period),
                    allowed: "[1, 100000]",
                });
            }
            Solver::Reference(Method::Rk4 { steps_per_period })
        }
        RawSolver::Dopri { rtol, atol } => Solver::Reference(Method::Dopri {
            rtol: range("run.solver.rtol", rtol, 1e-15, false, 1.0, "[1e-15, 1]")?,
            atol: range("run.solver.atol", atol, 1e-300, false, 1.0, "[1e-300, 1]")?,
        }),
    })
}

/// The scene and, for a physical scene, its Table I scale.
pub(super) fn resolve(raw: RawScene) -> Result<(Scene, Option<Scale>), SceneError> {
    let (mut params, scale) = device(&raw)?;
    let beta_v = virtual_damping(&raw, scale)?;
    let e = &raw.effects;
    let amp = amplifier(&e.amplifier, e.delay, scale, &mut params.tau_d)?;
    if !e.delay && params.tau_d > 0.0 {
        range(
            "controller.tau_d",
            params.tau_d,
            0.0,
            false,
            0.0,
            "0 when effects.delay = false",
        )?;
    }
    range(
        "controller.tau_d",
        params.tau_d,
        0.0,
        false,
        MAX_TAU_D,
        "total delay in [0, 250] periods",
    )?;
    let hand = hand(&e.hand, scale)?;
    let init = initial(&raw.initial, scale)?;
    let solver = solver(&raw.run)?;
    if solver == Solver::Exact && (amp.is_some() || hand.is_some() || !e.zoh) {
        return conflict(
            "run.solver",
            "kind = \"exact\" needs effects.zoh = true, amplifier kind \"none\" or \"delay\" \
             and hand kind \"none\"; use rk4 or dopri",
        );
    }
    if !e.zoh && params.tau_d > 0.0 {
        return conflict("effects.zoh", "true when a delay is simulated");
    }
    Ok((
        Scene {
            params,
            beta_v,
            effects: Effects {
                quantization: e.quantization,
                coulomb: e.coulomb,
                viscous: e.viscous,
                delay: e.delay,
                one_sided: e.one_sided_wall,
            },
            zoh: e.zoh,
            amp,
            hand,
            init,
            periods: raw.run.periods,
            solver,
            history: raw.run.history,
            rich: None,
        },
        scale,
    ))
}
