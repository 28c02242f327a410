//! Stiffness limits: the largest K satisfying the paper's criteria for a given device.
//!
//! Units: inputs are [`PhysicalParams`] (SI; the `stiffness` field is ignored and replaced by
//! the candidate K), velocities in m/s (rad/s), accelerations in m/s² (rad/s²); results are
//! stiffnesses in N/m (N·m/rad).
//!
//! Every criterion is linear in 1/K once β = b/(KT), σ = c/(KΔ), τ_D = T_D/T, ξ̇ = vT/Δ and
//! ξ̈ = aT²/Δ are substituted (ξ̇, ξ̈ and τ_D do not depend on K), so the admissible set is an
//! interval (0, K_max] and K_max has a closed form; only the "harmonic" delayed variant needs a
//! root finder (bisection, relative tolerance [`K_REL_TOL`]).
//!
//! Boundary convention: criteria are non-strict (`≥`), so K_max itself satisfies them. Each
//! closed form is then checked against this crate's own evaluation of the criterion (through
//! [`PhysicalParams::to_dimensionless`]) and lowered by a few ulps if rounding made it fail,
//! so `criterion(K_max)` holds exactly and `criterion(K_max·(1 + 1e-9))` fails.
//! A result of 0 means no positive stiffness satisfies the criterion.

use crate::params::{check_non_negative, ParamError, PhysicalParams};
use crate::regions::{criterion_12, criterion_19};

/// Relative tolerance of the bisection in [`k_max_delayed_harmonic`].
pub const K_REL_TOL: f64 = 1e-13;

fn base(p: &PhysicalParams) -> Result<PhysicalParams, ParamError> {
    p.with_stiffness(1.0).validate()
}

/// Lowers `k` by ulps (at most 64) until `holds(k)`; returns 0 if it never holds.
fn settle(mut k: f64, holds: impl Fn(f64) -> bool) -> f64 {
    let positive = k > 0.0;
    if !positive || !k.is_finite() {
        return if k.is_finite() { 0.0 } else { k };
    }
    for _ in 0..64 {
        if holds(k) {
            return k;
        }
        k = k.next_down();
    }
    // The closed form was further off than 64 ulps: fall back to a bisection on `holds`.
    let (mut lo, mut hi) = (0.0_f64, k);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if holds(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Whether criterion (12) holds for `p` with stiffness `k` and velocity bound `v` (physical;
/// `None` = unbounded). Evaluation errors (e.g. μ underflowing to 0) count as "fails".
#[must_use]
pub fn holds_12(p: &PhysicalParams, k: f64, v: Option<f64>) -> bool {
    let q = p.with_stiffness(k);
    match q.to_dimensionless() {
        Ok(d) => {
            criterion_12(d.beta, d.sigma, v.map(|v| q.xidot_from_velocity(v))).unwrap_or(false)
        }
        Err(_) => false,
    }
}

/// Whether criterion (19) holds for `p` (with its delay) at stiffness `k`, physical velocity
/// bound `v` and acceleration bound `a`.
#[must_use]
pub fn holds_19(p: &PhysicalParams, k: f64, v: f64, a: f64) -> bool {
    let q = p.with_stiffness(k);
    match q.to_dimensionless() {
        Ok(d) => criterion_19(
            d.beta,
            d.sigma,
            d.tau_d,
            Some(q.xidot_from_velocity(v)),
            Some(q.xiddot_from_acceleration(a)),
        )
        .unwrap_or(false),
        Err(_) => false,
    }
}

/// Largest K keeping the device passive (region A, τ_D = 0): β ≥ ½ and σ ≥ ½ of (17)–(18),
/// i.e. K ≤ min(2b/T, 2c/Δ). The delay field is ignored (the paper proves passivity only for
/// τ_D = 0; see [`k_max_delayed`]).
///
/// # Errors
/// [`ParamError`] when a parameter other than the stiffness is out of range.
pub fn k_max_passive(p: &PhysicalParams) -> Result<f64, ParamError> {
    let p = base(p)?;
    let k = f64::min(2.0 * p.viscous / p.period_s, 2.0 * p.coulomb / p.resolution);
    Ok(settle(k, |k| holds_12(&p, k, None)))
}

/// Largest K satisfying (12) for a physical velocity bound v ≥ 0 (τ_D = 0). Substituting
/// Table I into ξ̇(β − ½) + (σ − ½) ≥ 0 and σ ≥ ½ and multiplying by KΔ > 0:
/// K ≤ 2(bv + c)/(vT + Δ) and K ≤ 2c/Δ.
///
/// # Errors
/// [`ParamError`] when a parameter or the velocity is out of range.
pub fn k_max_at_velocity(p: &PhysicalParams, velocity: f64) -> Result<f64, ParamError> {
    let p = base(p)?;
    let v = check_non_negative("velocity", velocity)?;
    let (b, c, t, dl) = (p.viscous, p.coulomb, p.period_s, p.resolution);
    let k = f64::min(2.0 * (b * v + c) / (v * t + dl), 2.0 * c / dl);
    Ok(settle(k, |k| holds_12(&p, k, Some(v))))
}

/// Largest K satisfying the delayed criterion (19) (with its zero-velocity clause, see
/// [`criterion_19`]) for velocity bound v, acceleration bound a and the delay T_D of `p`.
/// With ξ̇ = vT/Δ, ξ̈ = aT²/Δ, τ_D = T_D/T, multiplying (19) by KΔ gives
/// K ≤ (c + bv)/(Δ/2 + a(T_D² + T·T_D) + v(T/2 + T_D)) and, at ξ̇ = 0,
/// K ≤ c/(Δ/2 + a(T_D² + T·T_D)). For T_D = 0 this equals [`k_max_at_velocity`].
///
/// # Errors
/// [`ParamError`] when a parameter, the velocity or the acceleration is out of range.
pub fn k_max_delayed(
    p: &PhysicalParams,
    velocity: f64,
    acceleration: f64,
) -> Result<f64, ParamError> {
    let p = base(p)?;
    let v = check_non_negative("velocity", velocity)?;
    let a = check_non_negative("acceleration", acceleration)?;
    let (b, c, t, dl, td) = (p.viscous, p.coulomb, p.period_s, p.resolution, p.delay_s);
    let acc_term = a * (td * td + t * td);
    let k = f64::min(
        (c + b * v) / (0.5 * dl + acc_term + v * (0.5 * t + td)),
        c / (0.5 * dl + acc_term),
    );
    Ok(settle(k, |k| holds_19(&p, k, v, a)))
}

/// Largest K satisfying (19) when the acceleration bound is that of a harmonic motion of peak
/// speed v at the wall's natural frequency, a = v·√(K/m) (ξ̈ = ξ̇/√μ). The constraint is then
/// c + bv − K(Δ/2 + v(T/2 + T_D)) − K^{3/2}·v(T_D² + T·T_D)/√m ≥ 0 (and its ξ̇ = 0 clause),
/// decreasing in K; solved by bisection on [0, K(a = 0)] to relative tolerance [`K_REL_TOL`].
///
/// # Errors
/// [`ParamError`] when a parameter or the velocity is out of range.
pub fn k_max_delayed_harmonic(p: &PhysicalParams, velocity: f64) -> Result<f64, ParamError> {
    let p = base(p)?;
    let v = check_non_negative("velocity", velocity)?;
    let (b, c, t, dl, td, m) = (
        p.viscous,
        p.coulomb,
        p.period_s,
        p.resolution,
        p.delay_s,
        p.mass,
    );
    let g = v * (td * td + t * td) / libm::sqrt(m);
    let f_move = |k: f64| c + b * v - k * (0.5 * dl + v * (0.5 * t + td)) - k * libm::sqrt(k) * g;
    let f_rest = |k: f64| c - k * 0.5 * dl - k * libm::sqrt(k) * g;
    let hi = k_max_delayed(&p, v, 0.0)?;
    let root = |f: &dyn Fn(f64) -> f64| {
        let (mut lo, mut hi) = (0.0_f64, hi);
        while hi - lo > K_REL_TOL * hi {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if f(mid) >= 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    };
    let k = f64::min(root(&f_move), root(&f_rest));
    Ok(settle(k, |k| holds_19(&p, k, v, v * libm::sqrt(k / m))))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn phantom() -> PhysicalParams {
        PhysicalParams {
            mass: 0.072,
            viscous: 0.005,
            coulomb: 0.038,
            resolution: 29.1e-6,
            period_s: 1e-3,
            stiffness: 1015.0,
            delay_s: 0.0,
            rotational: false,
        }
    }

    #[test]
    fn passive_is_colgate_for_phantom() {
        let k = k_max_passive(&phantom()).unwrap();
        assert!((k - 10.0).abs() < 1e-9, "{k}");
        assert!(holds_12(&phantom(), k, None));
        assert!(!holds_12(&phantom(), k * (1.0 + 1e-9), None));
    }

    #[test]
    fn at_velocity_matches_velocity_limit() {
        let p = phantom();
        let v = 0.05;
        let k = k_max_at_velocity(&p, v).unwrap();
        // at K the velocity limit (15) equals v
        let vl = crate::regions::velocity_limit_m_s(&p.with_stiffness(k))
            .unwrap()
            .unwrap();
        assert!((vl - v).abs() < 1e-9 * v, "{vl}");
        assert!(holds_12(&p, k, Some(v)));
        assert!(!holds_12(&p, k * (1.0 + 1e-9), Some(v)));
    }

    #[test]
    fn delayed_reduces_to_undelayed() {
        let p = phantom();
        let a = k_max_at_velocity(&p, 0.1).unwrap();
        let b = k_max_delayed(&p, 0.1, 5.0).unwrap();
        assert!((a - b).abs() <= 1e-12 * a);
        let q = PhysicalParams {
            delay_s: 0.5e-3,
            ..p
        };
        let c = k_max_delayed(&q, 0.1, 5.0).unwrap();
        assert!(c < a);
        assert!(holds_19(&q, c, 0.1, 5.0));
        assert!(!holds_19(&q, c * (1.0 + 1e-9), 0.1, 5.0));
        let h = k_max_delayed_harmonic(&q, 0.1).unwrap();
        assert!(holds_19(&q, h, 0.1, 0.1 * libm::sqrt(h / q.mass)));
        let h2 = h * (1.0 + 1e-9);
        assert!(!holds_19(&q, h2, 0.1, 0.1 * libm::sqrt(h2 / q.mass)));
    }
}
