//! Numerical kernels of the closed-form solution of μξ̈ + βξ̇ = a (a constant).
//!
//! Units: dimensionless time (sampling periods) or seconds, the formulas are unit-agnostic.
//! With k = β/μ ≥ 0 and x = k·t ≥ 0 the motion over a time t is
//!
//! - v(t) = v₀·e^{−x} + (a/μ)·t·E1(x)
//! - ξ(t) = ξ₀ + v₀·t·E1(x) + (a/μ)·t²·g(x)
//! - ∫₀ᵗ v² = v₀²·t·E1(2x) + 2v₀(a/μ)·t²·G1(x) + (a/μ)²·t³·G2(x)
//!
//! where every auxiliary function is evaluated by its Taylor series for x < 0.5 (so β = 0 is the
//! exact limit x = 0, without any division by β) and by `expm1` otherwise, keeping full relative
//! precision everywhere. Invariants: all functions take x ≥ 0 and return finite positive values.

/// Below this argument the Taylor series are used.
const SERIES_MAX: f64 = 0.5;
/// Number of Taylor terms (enough for 1e-17 relative precision at x = 0.5).
const TERMS: usize = 22;

/// Factorials 0!..=25! as f64.
const fn factorials() -> [f64; 26] {
    let mut f = [1.0; 26];
    let mut i = 1;
    while i < 26 {
        f[i] = f[i - 1] * i as f64;
        i += 1;
    }
    f
}
const FACT: [f64; 26] = factorials();

/// Evaluates Σ_{m<TERMS} (−x)^m · c(m) by Horner's rule.
#[inline]
fn series(x: f64, c: impl Fn(usize) -> f64) -> f64 {
    let mut acc = 0.0;
    let mut m = TERMS;
    while m > 0 {
        m -= 1;
        acc = acc * (-x) + c(m);
    }
    acc
}

/// e^{−x} − 1 (no_std-friendly wrapper over libm).
#[inline]
#[must_use]
pub fn expm1_neg(x: f64) -> f64 {
    libm::expm1(-x)
}

/// E1(x) = (1 − e^{−x})/x, E1(0) = 1.
#[must_use]
pub fn e1(x: f64) -> f64 {
    if x < SERIES_MAX {
        series(x, |m| 1.0 / FACT[m + 1])
    } else {
        -expm1_neg(x) / x
    }
}

/// g(x) = (x − 1 + e^{−x})/x², g(0) = ½.
#[must_use]
pub fn g(x: f64) -> f64 {
    if x < SERIES_MAX {
        series(x, |m| 1.0 / FACT[m + 2])
    } else {
        (x + expm1_neg(x)) / (x * x)
    }
}

/// G1(x) = (E1(x) − E1(2x))/x, G1(0) = ½.
#[must_use]
pub fn g1(x: f64) -> f64 {
    if x < SERIES_MAX {
        series(x, |m| (pow2(m + 1) - 1.0) / FACT[m + 2])
    } else {
        (e1(x) - e1(2.0 * x)) / x
    }
}

/// G2(x) = (x − 2(1 − e^{−x}) + (1 − e^{−2x})/2)/x³, G2(0) = ⅓.
#[must_use]
pub fn g2(x: f64) -> f64 {
    if x < SERIES_MAX {
        series(x, |m| (pow2(m + 2) - 2.0) / FACT[m + 3])
    } else {
        (x + 2.0 * expm1_neg(x) - 0.5 * expm1_neg(2.0 * x)) / (x * x * x)
    }
}

/// ln(1 + y)/y for y ≥ 0, = 1 at y = 0.
#[must_use]
pub fn log1p_over(y: f64) -> f64 {
    if y < 1e-4 {
        // 1 − y/2 + y²/3 − y³/4: truncation error < y⁴/5 < 2e-17.
        1.0 - y * (0.5 - y * (1.0 / 3.0 - y * 0.25))
    } else {
        libm::log1p(y) / y
    }
}

#[inline]
fn pow2(n: usize) -> f64 {
    // Exact for n < 1024.
    f64::from_bits(((1023 + n as u64) & 0x7ff) << 52)
}

/// ⌊x⌋ without a libm call: `stiffwall_core`'s, shared with the storage function (35).
/// Locates an event inside [lo, hi] by the Illinois variant of regula falsi: `lo` is before
/// the event, `hi` past it (with `s_hi` the state there). `eval(t)` returns the event function,
/// whether t is past the event, and the state at t. Secant points that fall outside (lo, hi)
/// or are not finite are replaced by the midpoint. Stops when the bracket is at most `width`
/// (or after 100 evaluations); returns the past-the-event end and its state. Shared by the
/// reference integrators and the exact linear plant engine (`rich::linear`).
pub fn illinois<S: Copy>(
    mut lo: f64,
    mut hi: f64,
    mut f_lo: f64,
    mut f_hi: f64,
    s_hi: S,
    width: f64,
    mut eval: impl FnMut(f64) -> (f64, bool, S),
) -> (f64, S) {
    let mut s_best = s_hi;
    let mut side = 0;
    for _ in 0..100 {
        if hi - lo <= width {
            break;
        }
        let mut c = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        if !(c > lo && c < hi) {
            c = 0.5 * (lo + hi);
        }
        let (fc, past, sc) = eval(c);
        if past {
            hi = c;
            f_hi = fc;
            s_best = sc;
            if side == 1 {
                f_lo *= 0.5;
            }
            side = 1;
        } else {
            lo = c;
            f_lo = fc;
            if side == -1 {
                f_hi *= 0.5;
            }
            side = -1;
        }
    }
    (hi, s_best)
}

pub use stiffwall_core::energy::floor_fast;

/// Encoder count ⌊x⌋ as an integer, saturating at the i64 range (NaN → 0).
#[inline]
#[must_use]
pub fn floor_i64(x: f64) -> i64 {
    floor_fast(x) as i64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
    }

    #[test]
    fn series_and_direct_branches_agree_at_the_switch() {
        let lo = 0.5 - 1e-12;
        let hi = 0.5;
        for f in [e1, g, g1, g2] {
            // The functions vary by < 1e-12 over [lo, hi]: a branch mismatch would be far larger.
            assert!(close(f(lo), f(hi), 1e-11), "{} {}", f(lo), f(hi));
        }
    }

    #[test]
    fn limits_at_zero() {
        assert_eq!(e1(0.0), 1.0);
        assert_eq!(g(0.0), 0.5);
        assert_eq!(g1(0.0), 0.5);
        assert!(close(g2(0.0), 1.0 / 3.0, 1e-16));
        assert_eq!(log1p_over(0.0), 1.0);
    }

    #[test]
    fn against_direct_formulas_for_moderate_x() {
        for &x in &[0.01_f64, 0.1, 0.3, 0.49] {
            let em = (-x).exp_m1();
            assert!(close(e1(x), -em / x, 1e-13));
            assert!(close(g(x), (x + em) / (x * x), 1e-10));
        }
    }

    #[test]
    fn floor_fast_matches_floor() {
        for &x in &[
            -2.5, -2.0, -1e-300, -0.0, 0.0, 0.3, 1.0, 7.999, -4.1e15, 5e15, 1e300, -1e300,
        ] {
            assert_eq!(floor_fast(x), x.floor(), "{x}");
        }
        assert!(floor_fast(f64::NAN).is_nan());
    }
}
