//! The sampled loop of a scene with a plant effect beyond the paper, on a
//! [`crate::rich::RichPlant`]. std only.
//!
//! The controller of eq. (8) (quantised or ideal, one-sided or not) is sampled every period T
//! (plus the virtual damper −β_v·(n_h − n_(h−1)) of [`crate::exact`] when the scene sets
//! `controller.virtual_damping_ns_per_m`), its force delayed by τ_D = n + f periods exactly as
//! in [`crate::exact`] (force F(h−n−1) over [h, h+f), F(h−n) over [h+f, h+1)), and held on the
//! plant.
//!
//! Units: rows are in the scene's dimensionless units (ξ = x₁/Δ, ξ̇ = v₁T/Δ, φ_A = F/(KΔ)); the
//! plant is stepped in SI. The energy audit columns `e_d`, `e_g`, `residual` are 0 (not
//! audited). Invariant: [`simulate`] never panics; it stops after the first row beyond 1e150.

use super::error::SceneError;
use super::spec::{RichScene, Row, Scene};
use crate::exact::History;
use crate::rich::{Controller, RichPlant};

/// The spring of eq. (8) in units of K·Δ at ξ ticks.
fn spring(xi: f64, c: &Controller) -> f64 {
    let f = if c.quantization {
        -crate::math::floor_fast(xi) - 0.5
    } else {
        -xi
    };
    if c.one_sided {
        f.min(0.0)
    } else {
        f
    }
}

/// The wall law of the module header in units of K·Δ at ξ ticks, with the virtual damper
/// −β_v·(n_h − n_(h−1)) when β_v ≠ 0 (as [`crate::exact`]: n = ⌊ξ⌋, or ξ without
/// quantization; on a one-sided wall the whole law acts only in contact, n ≥ 0).
fn law(xi: f64, n_prev: f64, beta_v: f64, c: &Controller) -> f64 {
    if beta_v == 0.0 {
        return spring(xi, c);
    }
    let n = count(xi, c);
    let f = if c.quantization { -n - 0.5 } else { -n } - beta_v * (n - n_prev);
    if c.one_sided && n < 0.0 {
        0.0
    } else {
        f
    }
}

/// The count n_h of the damper's backward difference (ξ itself without quantization).
fn count(xi: f64, c: &Controller) -> f64 {
    if c.quantization {
        crate::math::floor_fast(xi)
    } else {
        xi
    }
}

/// Runs a scene with a [`RichScene`] in the sampled loop of the module header, calling `out`
/// at τ = 0 and at every sample instant ([`crate::scene::simulate_sampled`]; `Scene::simulate`
/// calls it when the scene has a plant effect, tests also on scenes without one).
///
/// # Errors
/// [`SceneError::Effect`] when the plant rejects the model or its engine.
pub fn simulate(
    scene: &Scene,
    rich: &RichScene,
    out: &mut dyn FnMut(&Row),
) -> Result<(), SceneError> {
    let c = rich.controller;
    let (k, t, delta) = (c.stiffness_n_per_m, c.period_s, rich.model.resolution_m);
    let kd = k * delta;
    let mut plant = RichPlant::with_method(&rich.model, rich.method)
        .map_err(|e| SceneError::Effect(e.to_string()))?;
    plant.set_tolerance_period(t);
    plant.set_state(scene.init.x * delta, scene.init.v * delta / t);
    let tau_d = scene.params.tau_d;
    let n = crate::math::floor_fast(tau_d);
    let frac = tau_d - n;
    let n = n as u64;
    const LINE: usize = 256;
    let hist = match scene.history {
        History::HoldInitial => spring(scene.init.x, &c),
        History::Zero => 0.0,
    };
    // As the reference integrators: the filter starts in steady state with the history force.
    plant.set_amplifier_output(hist * kd);
    let mut line = [hist; LINE];
    let delayed = |line: &[f64; LINE], h: u64, j: u64| -> f64 {
        if h < j {
            hist
        } else {
            line[((h - j) as usize) % LINE]
        }
    };
    let mu = scene.params.mu;
    let row = |h: u64, p: &RichPlant, phi: f64| {
        let xi = p.position_m() / delta;
        let xidot = p.velocity_m_per_s() * t / delta;
        Row {
            period: h,
            xi,
            xidot,
            phi_a: phi,
            h_t: crate::exact::storage(mu, xi, xidot),
            e_d: 0.0,
            e_g: 0.0,
            residual: 0.0,
        }
    };
    let beta_v = scene.beta_v;
    let mut n_prev = count(scene.init.x, &c);
    for h in 0..=scene.periods {
        let xi = plant.position_m() / delta;
        line[(h as usize) % LINE] = law(xi, n_prev, beta_v, &c);
        n_prev = count(xi, &c);
        let first = if frac > 0.0 {
            delayed(&line, h, n + 1)
        } else {
            delayed(&line, h, n)
        };
        out(&row(h, &plant, first));
        // Diverged: as the exact solver's driver, stop after the first row beyond 1e150.
        let v = plant.velocity_m_per_s() * t / delta;
        if h == scene.periods || !(xi.abs() <= 1e150 && v.abs() <= 1e150) {
            break;
        }
        if frac > 0.0 {
            plant.advance(first * kd, frac * t);
            plant.advance(delayed(&line, h, n) * kd, (1.0 - frac) * t);
        } else {
            plant.advance(first * kd, t);
        }
    }
    Ok(())
}
