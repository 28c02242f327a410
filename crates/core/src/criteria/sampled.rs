//! The undamped criteria (the wall of eq. (2), B = 0): Colgate–Schenkel, Abbott–Okamura,
//! Hulin and the exact sampled linear boundary of Gil–Avello–Rubio, with the sampled-system
//! machinery (characteristic polynomial, Schur test, delay split) that the damped criteria of
//! [`super::damped`] reuse. Units and invariants: see [`super`].

use crate::params::{ParamError, PhysicalParams};

/// Largest supported ⌊T_D/T⌋ for [`k_max_gil_avello_rubio`].
pub const MAX_DELAY_PERIODS: usize = 60;
/// Largest degree of the characteristic polynomial (⌊τ_D⌋ + 3).
pub const MAX_DEGREE: usize = MAX_DELAY_PERIODS + 3;
/// Relative tolerance of the bisection on K in [`k_max_gil_avello_rubio`].
pub const GIL_REL_TOL: f64 = 1e-12;

pub(super) fn base(p: &PhysicalParams) -> Result<PhysicalParams, ParamError> {
    p.with_stiffness(1.0).validate()
}

/// Colgate & Schenkel, "Passivity of a class of sampled-data systems: Application to haptic
/// interfaces", ACC 1994 (the paper's ref. 7): passivity iff b > KT/2 + |B|. With B = 0:
/// K < 2b/T. Quantization, Coulomb friction and delay are not modelled. Returns the supremum
/// 2b/T (strict inequality: K must stay below it).
///
/// # Errors
/// [`ParamError`] when a parameter is out of range.
pub fn k_max_colgate_schenkel(p: &PhysicalParams) -> Result<f64, ParamError> {
    let p = base(p)?;
    Ok(2.0 * p.viscous / p.period_s)
}

/// Abbott & Okamura, "Effects of position quantization and sampling rate on virtual-wall
/// passivity", IEEE T-RO 21(5), 2005 (the paper's ref. 15): for a mass with viscous and Coulomb
/// friction, sampled, with encoder resolution Δ, the virtual wall is passive iff
/// K < min(2b/T, 2f_c/Δ) (with B = 0; the 2b/T term is Colgate's, the 2f_c/Δ term the
/// quantization one). Implemented exactly as that formula, as we recall it from the paper;
/// in this model it coincides with the boundary of region A ([`crate::limits::k_max_passive`])
/// up to the strict vs non-strict inequality.
///
/// # Errors
/// [`ParamError`] when a parameter is out of range.
pub fn k_max_abbott_okamura(p: &PhysicalParams) -> Result<f64, ParamError> {
    let p = base(p)?;
    Ok(f64::min(
        2.0 * p.viscous / p.period_s,
        2.0 * p.coulomb / p.resolution,
    ))
}

/// Small-damping linear approximation of the stability boundary with delay attributed to
/// Hulin, Preusche & Hirzinger (IROS 2006, "Stability boundary for haptic rendering: influence
/// of physical damping"): K_max ≈ 2b/(T + 2T_D) = b/(T/2 + T_D). The same value is the
/// limit of (19) for v → ∞ and a = 0. Formula as we recall it; compare with
/// [`k_max_gil_avello_rubio`], which is exact for the linear model.
///
/// # Errors
/// [`ParamError`] when a parameter is out of range.
pub fn k_max_hulin(p: &PhysicalParams) -> Result<f64, ParamError> {
    let p = base(p)?;
    Ok(p.viscous / (0.5 * p.period_s + p.delay_s))
}

/// (1 − e^{−x})/x with its series near 0.
pub(super) fn p1(x: f64) -> f64 {
    if x < 1e-3 {
        1.0 - x / 2.0 + x * x / 6.0 - x * x * x / 24.0
    } else {
        -libm::expm1(-x) / x
    }
}

/// (x − 1 + e^{−x})/x² with its series near 0.
pub(super) fn p2(x: f64) -> f64 {
    if x < 1e-3 {
        0.5 - x / 6.0 + x * x / 24.0 - x * x * x / 120.0
    } else {
        (x + libm::expm1(-x)) / (x * x)
    }
}

/// Exact boundary for τ_D = 0 in g = KT²/m: the characteristic polynomial is
/// z² − (1 + e − g·p₂)z + (e + g·ñ₀) with p₂ = (x − 1 + e)/x², ñ₀ = (1 − e − xe)/x², and the
/// Jury conditions give g < (1 − e)/ñ₀ (|c₀| < 1) and g < 2(1 + e)/(p₂ − ñ₀) (P(−1) > 0, binding
/// only for x = bT/m ≳ 2). Evaluated with series near x = 0, so it keeps full precision where
/// the polynomial test cannot (roots within ~x of z = 1).
pub(super) fn g_max_no_delay(x: f64) -> f64 {
    let n0 = if x < 1e-3 {
        0.5 - x / 3.0 + x * x / 8.0 - x * x * x / 30.0 + x * x * x * x / 144.0
    } else {
        (-libm::expm1(-x) - x * libm::exp(-x)) / (x * x)
    };
    let one_minus_e = -libm::expm1(-x);
    let g1 = one_minus_e / n0;
    if x < 1e-3 {
        return g1;
    }
    let e = libm::exp(-x);
    let g2 = 2.0 * (1.0 + e) / (p2(x) - n0);
    f64::min(g1, g2)
}

/// Characteristic polynomial of the sampled linear loop (see [`gil_avello_rubio_stable`]),
/// coefficients of z^0..=z^n, with x = bT/m, g = KT²/m, τ_D = d + f.
pub(super) fn char_poly(x: f64, g: f64, d: usize, f: f64) -> ([f64; MAX_DEGREE + 1], usize) {
    let e = libm::exp(-x);
    let num = numerator(x, f);
    let n = d + 3;
    let mut c = [0.0; MAX_DEGREE + 1];
    c[d + 3] += 1.0;
    c[d + 2] -= 1.0 + e;
    c[d + 1] += e;
    c[2] += g * num[2];
    c[1] += g * num[1];
    c[0] += g * num[0];
    (c, n)
}

/// Coefficients of z^0..=z^2 of N(z) = z·N₀(z) + N₁(z), the loop numerator of [`char_poly`].
pub(super) fn numerator(x: f64, f: f64) -> [f64; 3] {
    // Normalised units: time in periods, mass 1, damping rate x per period.
    let gamma = |h: f64| (h * h * p2(x * h), h * p1(x * h));
    let e = libm::exp(-x);
    let phi12 = p1(x);
    let (g0x, g0v) = gamma(1.0 - f);
    let (gfx, gfv) = gamma(f);
    let g1x = gfx + (1.0 - f) * p1(x * (1.0 - f)) * gfv;
    let g1v = libm::exp(-x * (1.0 - f)) * gfv;
    let (a0, b0) = (g0x, phi12 * g0v - e * g0x);
    let (a1, b1) = (g1x, phi12 * g1v - e * g1x);
    [b1, b0 + a1, a0]
}

/// Schur–Cohn–Jury test: whether every root of Σ c[i] zⁱ (degree n) lies strictly inside the
/// unit circle. Reduction: with leading a_n and constant a_0, require |a_0| < |a_n| and recurse
/// on (a_n p(z) − a_0 z^n p(1/z))/z. (Assumes a_n > 0 after the first step, which the
/// normalisation below keeps when |a_0| < |a_n|.)
pub(super) fn schur_stable<const L: usize>(mut c: [f64; L], mut n: usize) -> bool {
    while n > 0 {
        let (an, a0) = (c[n], c[0]);
        let shrinking = a0.abs() < an.abs();
        if !shrinking {
            return false;
        }
        let mut next = [0.0; L];
        // a_n·p − a_0·p* written as a_n(p − p*) + (a_n − a_0)p*: near the stability boundary
        // p is nearly self-reciprocal and this form avoids cancelling two O(1) products.
        let dn = an - a0;
        for (i, slot) in next.iter_mut().enumerate().take(n) {
            *slot = an * (c[i + 1] - c[n - 1 - i]) + dn * c[n - 1 - i];
        }
        // Normalise to keep the coefficients O(1).
        let scale = next[n - 1].abs();
        let usable = scale > 0.0 && scale.is_finite();
        if !usable {
            return false;
        }
        for v in next.iter_mut().take(n) {
            *v /= scale;
        }
        c = next;
        n -= 1;
    }
    true
}

pub(super) fn split_delay(p: &PhysicalParams) -> Result<(usize, f64), ParamError> {
    let tau = p.delay_s / p.period_s;
    #[allow(clippy::cast_precision_loss)]
    let in_range = tau <= MAX_DELAY_PERIODS as f64;
    if !in_range {
        return Err(ParamError::OutOfRange {
            name: "delay",
            value: p.delay_s,
            allowed: "finite, >= 0 and at most 60 sampling periods",
        });
    }
    let d = libm::floor(tau);
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    Ok((d as usize, tau - d))
}

/// Whether the sampled *linear* loop (no quantization, no Coulomb friction) is asymptotically
/// stable at `p.stiffness`: plant 1/(ms² + bs) driven through a ZOH, spring −K·x sampled every
/// T, applied after the delay T_D. This is the model of Gil, Avello & Rubio, "Stability
/// analysis of a 1 DOF haptic interface using the Routh–Hurwitz criterion", IEEE TCST 12(4),
/// 2004, who treat integer delays; a fractional delay τ_D = d + f is handled exactly by
/// splitting each ZOH interval at fT (the modified z-transform): with Φ(h), Γ(h) the exact
/// discretisation of ẋ = v, mv̇ = −bv + u over h, x_{k+1} = Φ(T)x_k + Γ((1−f)T)u_{k−d} +
/// Φ((1−f)T)Γ(fT)u_{k−d−1}, whose characteristic polynomial
/// z^{d+1}(z − 1)(z − e^{−bT/m}) + (KT²/m)(z N₀(z) + N₁(z)) is tested with the Schur–Cohn–Jury
/// recursion (equivalent to Routh–Hurwitz on the bilinear-transformed polynomial).
///
/// # Errors
/// [`ParamError`] when a parameter is out of range or τ_D > [`MAX_DELAY_PERIODS`].
pub fn gil_avello_rubio_stable(p: &PhysicalParams) -> Result<bool, ParamError> {
    let p = p.validate()?;
    let (d, f) = split_delay(&p)?;
    let x = p.viscous * p.period_s / p.mass;
    let g = p.stiffness * p.period_s / p.mass * p.period_s;
    let (c, n) = char_poly(x, g, d, f);
    Ok(schur_stable(c, n))
}

/// Bisection of g between `lo` (stable) and `hi` (unstable) to relative tolerance
/// [`GIL_REL_TOL`] (or until the midpoint no longer separates them): the last stable value.
pub(crate) fn bisect_stable(mut lo: f64, mut hi: f64, stable: impl Fn(f64) -> bool) -> f64 {
    while hi - lo > GIL_REL_TOL * hi {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Exact largest K of the sampled linear loop of [`gil_avello_rubio_stable`] (Gil, Avello &
/// Rubio 2004): bisection on g = KT²/m between a stable and an unstable value found by
/// doubling/halving, to relative tolerance [`GIL_REL_TOL`]; assumes the stable set of K is an
/// interval (0, K_max), as the root locus of this loop is. Returns the last stable value, or 0
/// when no positive K is stable (b = 0: the undamped sampled spring is never stable).
/// For τ_D = 0 the boundary is evaluated in closed form (Jury conditions of the quadratic,
/// see `g_max_no_delay`): K_max = (m/T²)·min((1 − e)x²/(1 − e − xe), 2(1 + e)x²/(x(1 + e) −
/// 2(1 − e))), x = bT/m, e = e^{−x}, which tends to Colgate's 2b/T for small x. With delay the
/// polynomial test loses relative accuracy ≈ 1e-16/x in K, so for x = bT/m below ~1e-8 expect
/// only a few significant digits.
///
/// # Errors
/// [`ParamError`] when a parameter is out of range or τ_D > [`MAX_DELAY_PERIODS`].
pub fn k_max_gil_avello_rubio(p: &PhysicalParams) -> Result<f64, ParamError> {
    let p = base(p)?;
    let (d, f) = split_delay(&p)?;
    let x = p.viscous * p.period_s / p.mass;
    let damped = x > 0.0;
    if !damped {
        return Ok(0.0);
    }
    if d == 0 && f == 0.0 {
        return Ok(g_max_no_delay(x) * p.mass / p.period_s / p.period_s);
    }
    let stable = |g: f64| {
        let (c, n) = char_poly(x, g, d, f);
        schur_stable(c, n)
    };
    // Bracket: find hi unstable, lo stable.
    let mut hi = 4.0 * x;
    let mut iters = 0;
    while stable(hi) && iters < 2000 {
        hi *= 2.0;
        iters += 1;
    }
    let mut lo = hi;
    iters = 0;
    loop {
        lo *= 0.5;
        iters += 1;
        if stable(lo) {
            break;
        }
        if iters > 2000 || lo == 0.0 {
            return Ok(0.0);
        }
    }
    Ok(bisect_stable(lo, lo * 2.0, stable) * p.mass / p.period_s / p.period_s)
}
