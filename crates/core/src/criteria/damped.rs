//! The spring + damper wall: exact sampled linear stability boundary and closed forms.
//!
//! Wall law (linear part of the firmware's): u_k = −K·x_k − B·(x_k − x_{k−1})/T, the
//! backward-difference velocity, held by a ZOH and applied after the delay T_D (the same
//! plant, ZOH and delay model as [`super::gil_avello_rubio_stable`]; no extra computation delay,
//! as there). In z: C(z) = −(K + B(1 − z⁻¹)/T)·z^(−τ_D). The dimensionless virtual damping is
//! β_v = B/(K·T) (beside β = b/(K·T) of Table I).
//!
//! Units: `damping_n_s_per_m` is B in N·s/m (N·m·s/rad for rotational devices); results are
//! stiffnesses in N/m (N·m/rad). Invariants: no allocation; B must be finite and ≥ 0 (else a
//! [`ParamError`] naming `damping`); at B = 0 every function returns bit-for-bit what the
//! spring-only function of [`super`] returns (it calls it).

use super::sampled::{
    base, bisect_stable, gil_avello_rubio_stable, k_max_gil_avello_rubio, numerator, schur_stable,
    split_delay, MAX_DEGREE,
};
use crate::params::{check_non_negative, ParamError, PhysicalParams};

/// Length of the coefficient array of the damped characteristic polynomial (degree ⌊τ_D⌋ + 4).
pub const MAX_DEGREE_DAMPED: usize = MAX_DEGREE + 1;
/// Points per decade of the logarithmic scan on K in [`k_max_exact_linear`].
pub const SCAN_PER_DECADE: usize = 40;
/// Decades scanned below the cap in [`k_max_exact_linear`].
pub const SCAN_DECADES: usize = 12;
/// Number of B values of a [`Frontier`].
pub const FRONTIER_POINTS: usize = 33;

/// Checks the virtual damping B: finite and ≥ 0, else a [`ParamError`] naming `damping`.
///
/// # Errors
/// [`ParamError`] naming `damping` with its allowed range `finite and >= 0`.
pub fn check_damping(damping_n_s_per_m: f64) -> Result<f64, ParamError> {
    check_non_negative("damping", damping_n_s_per_m)
}

/// β_v = B/(K·T), the dimensionless virtual damping (companion of Table I's β = b/(K·T)).
#[must_use]
pub fn beta_v(damping_n_s_per_m: f64, stiffness: f64, period_s: f64) -> f64 {
    damping_n_s_per_m / (stiffness * period_s)
}

/// Characteristic polynomial z^{d+2}(z − 1)(z − e) + ((g + g_b)z − g_b)·N(z), with N(z) the
/// numerator of the spring-only loop (`char_poly`), g = KT²/m, g_b = BT/m.
fn char_poly_damped(
    x: f64,
    g: f64,
    g_b: f64,
    d: usize,
    f: f64,
) -> ([f64; MAX_DEGREE_DAMPED + 1], usize) {
    let num = numerator(x, f);
    let e = libm::exp(-x);
    let n = d + 4;
    let mut c = [0.0; MAX_DEGREE_DAMPED + 1];
    c[d + 4] += 1.0;
    c[d + 3] -= 1.0 + e;
    c[d + 2] += e;
    for (i, a) in num.iter().enumerate() {
        c[i + 1] += (g + g_b) * a;
        c[i] -= g_b * a;
    }
    (c, n)
}

/// Whether the sampled linear spring + damper loop is asymptotically stable at `p.stiffness`
/// with virtual damping B (Schur–Cohn–Jury test on [`MAX_DEGREE_DAMPED`]-sized coefficients).
/// At B = 0 returns [`gil_avello_rubio_stable`].
///
/// # Errors
/// [`ParamError`] when a parameter is out of range, τ_D > [`super::MAX_DELAY_PERIODS`], or B
/// is negative, NaN or infinite (named `damping`).
pub fn exact_linear_stable(p: &PhysicalParams, damping_n_s_per_m: f64) -> Result<bool, ParamError> {
    let b_v = check_damping(damping_n_s_per_m)?;
    if b_v == 0.0 {
        return gil_avello_rubio_stable(p);
    }
    let p = p.validate()?;
    let (d, f) = split_delay(&p)?;
    let x = p.viscous * p.period_s / p.mass;
    let g = p.stiffness * p.period_s / p.mass * p.period_s;
    let (c, n) = char_poly_damped(x, g, b_v * p.period_s / p.mass, d, f);
    Ok(schur_stable(c, n))
}

/// Largest stable K of the sampled linear spring + damper loop of [`exact_linear_stable`].
///
/// At B = 0: exactly [`k_max_gil_avello_rubio`]. For B > 0 the stable set of K need not be
/// (0, K_max) (the frontier is not monotone in B and for large B the set shrinks or vanishes),
/// so this scans g = KT²/m on a logarithmic grid of [`SCAN_PER_DECADE`] points per decade over
/// [`SCAN_DECADES`] decades below the cap g ≤ 64·(1 + bT/m + BT/m), takes the largest stable grid
/// point and bisects between it and the next (unstable) grid point to relative tolerance
/// [`GIL_REL_TOL`](super::sampled::GIL_REL_TOL). Returns that supremum of the stable K (the last stable value), or 0 when no
/// grid point is stable. Stable islands narrower than one grid step (≈ 6 %) can be missed.
///
/// # Errors
/// As [`exact_linear_stable`].
pub fn k_max_exact_linear(p: &PhysicalParams, damping_n_s_per_m: f64) -> Result<f64, ParamError> {
    let b_v = check_damping(damping_n_s_per_m)?;
    if b_v == 0.0 {
        return k_max_gil_avello_rubio(p);
    }
    let p = base(p)?;
    let (d, f) = split_delay(&p)?;
    let x = p.viscous * p.period_s / p.mass;
    let g_b = b_v * p.period_s / p.mass;
    let stable = |g: f64| {
        let (c, n) = char_poly_damped(x, g, g_b, d, f);
        schur_stable(c, n)
    };
    let cap = 64.0 * (1.0 + x + g_b);
    #[allow(clippy::cast_precision_loss)]
    let ratio = libm::pow(10.0, 1.0 / SCAN_PER_DECADE as f64);
    let mut hi = cap;
    let mut lo = f64::NAN;
    for _ in 0..=SCAN_PER_DECADE * SCAN_DECADES {
        if stable(hi) {
            lo = hi;
            break;
        }
        hi /= ratio;
    }
    if lo.is_nan() {
        return Ok(0.0);
    }
    let scale = p.mass / p.period_s / p.period_s;
    if lo == cap {
        return Ok(cap * scale);
    }
    Ok(bisect_stable(lo, lo * ratio, stable) * scale)
}

/// Colgate & Schenkel with a damper: passive iff b > KT/2 + |B|, so K < 2(b − B)/T. Returns
/// that supremum, or 0 when B ≥ b (no K is passive).
///
/// # Errors
/// [`ParamError`] when a parameter or B (`damping`) is out of range.
pub fn k_max_colgate_schenkel_damped(
    p: &PhysicalParams,
    damping_n_s_per_m: f64,
) -> Result<f64, ParamError> {
    let b_v = check_damping(damping_n_s_per_m)?;
    let p = base(p)?;
    Ok(f64::max(0.0, 2.0 * (p.viscous - b_v) / p.period_s))
}

/// Small-B linear approximation K_max ≈ (b + B)/(T/2 + T_D) (Hulin et al.; valid for
/// b, B ≪ m/T). At B = 0 it is [`super::k_max_hulin`].
///
/// # Errors
/// [`ParamError`] when a parameter or B (`damping`) is out of range.
pub fn k_max_small_b(p: &PhysicalParams, damping_n_s_per_m: f64) -> Result<f64, ParamError> {
    let b_v = check_damping(damping_n_s_per_m)?;
    let p = base(p)?;
    Ok((p.viscous + b_v) / (0.5 * p.period_s + p.delay_s))
}

/// K_max(B) of [`k_max_exact_linear`] at [`FRONTIER_POINTS`] values of B, and its maximum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frontier {
    /// The B values, N·s/m (N·m·s/rad): the linear grid B_i = B_max·i/(N − 1), i = 0..N−1.
    pub b_n_s_per_m: [f64; FRONTIER_POINTS],
    /// K_max(B_i), N/m (N·m/rad).
    pub k_max: [f64; FRONTIER_POINTS],
    /// The grid B that maximises K_max (the first one on ties).
    pub b_opt_n_s_per_m: f64,
    /// K_max at `b_opt_n_s_per_m`.
    pub k_max_opt: f64,
}

/// The frontier K_max(B) on the linear grid 0..=`b_max_n_s_per_m` (see [`Frontier`]).
///
/// # Errors
/// [`ParamError`] when a parameter is out of range or `b_max_n_s_per_m` (named `damping`) is
/// negative, NaN or infinite.
pub fn frontier(p: &PhysicalParams, b_max_n_s_per_m: f64) -> Result<Frontier, ParamError> {
    let b_max = check_damping(b_max_n_s_per_m)?;
    let mut out = Frontier {
        b_n_s_per_m: [0.0; FRONTIER_POINTS],
        k_max: [0.0; FRONTIER_POINTS],
        b_opt_n_s_per_m: 0.0,
        k_max_opt: f64::NEG_INFINITY,
    };
    for i in 0..FRONTIER_POINTS {
        #[allow(clippy::cast_precision_loss)]
        let b = b_max * i as f64 / (FRONTIER_POINTS - 1) as f64;
        let k = k_max_exact_linear(p, b)?;
        out.b_n_s_per_m[i] = b;
        out.k_max[i] = k;
        if k > out.k_max_opt {
            out.k_max_opt = k;
            out.b_opt_n_s_per_m = b;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests;
