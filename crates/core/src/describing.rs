//! Describing-function analysis of Sec. VII, eqs. (62)–(75).
//!
//! Units: dimensionless. Amplitudes M in encoder ticks, frequencies ω in radians per sampling
//! period (physical frequency f = ω/(2πT) Hz), τ_L = ½ + τ_D in periods (the ZOH counted as
//! half a period of delay, Fig. 10).
//!
//! Invariants: inputs are validated (finite; μ, M, τ_L > 0; β, σ ≥ 0); results are finite.
//! Root finding is bisection on a sign-changing, monotone function with absolute tolerance
//! [`OMEGA_TOL`] on ω.

use crate::params::{check_non_negative, check_positive, ParamError};
use core::f64::consts::{FRAC_PI_2, PI};

/// Absolute tolerance of the bisections on ω (rad/period).
pub const OMEGA_TOL: f64 = 1e-13;

/// Above this amplitude the sum of (67) is not evaluated term by term: D(M) = 1 is returned.
/// (67) = 1 + O(M^(-3/2)) (Euler–Maclaurin on the quarter circle; measured
/// |1 − D(M)|·M^(3/2) ≤ 0.38 for M ≥ 10, ≈ 0.3743 at integer M), so at this cap the error of
/// returning 1 is below 2e-8 (checked in the tests).
pub const D_SUM_CAP: f64 = 1.0e5;

/// Describing function of the quantizer (22), eq. (67):
/// D(M) = 2/(πM) + 4/(πM²)·Σ_{l=1}^{⌊M⌋} √(M² − l²). For M > [`D_SUM_CAP`] returns 1.
///
/// # Errors
/// [`ParamError`] unless M is finite and > 0.
pub fn quantizer_df(m: f64) -> Result<f64, ParamError> {
    check_positive("amplitude", m)?;
    if m > D_SUM_CAP {
        return Ok(1.0);
    }
    // ⌊M⌋ ≤ 1e5 here, so the cast is exact.
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let n = libm::floor(m) as u32;
    let mut sum = 0.0;
    for l in 1..=n {
        let l = f64::from(l);
        // (M − l)(M + l) avoids cancellation in M² − l² near l = M.
        sum += libm::sqrt((m - l) * (m + l));
    }
    if n == 0 {
        return Ok(2.0 / (PI * m));
    }
    Ok(2.0 / (PI * m) + 4.0 / (PI * m * m) * sum)
}

/// First term D₁(M) = 2/(πM) of (67), the small-amplitude approximation (Fig. 11(b)).
///
/// # Errors
/// [`ParamError`] unless M is finite and > 0.
pub fn quantizer_df_small(m: f64) -> Result<f64, ParamError> {
    check_positive("amplitude", m)?;
    Ok(2.0 / (PI * m))
}

/// A predicted self-sustained oscillation ξ(τ) = M sin(ωτ) (63).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LimitCycle {
    /// Amplitude M in encoder ticks.
    pub amplitude: f64,
    /// Frequency ω in radians per sampling period.
    pub omega: f64,
}

impl LimitCycle {
    /// Frequency in Hz for sampling period `period_s` (s): ω/(2πT).
    #[must_use]
    pub fn frequency_hz(&self, period_s: f64) -> f64 {
        self.omega / (2.0 * PI * period_s)
    }
}

/// Bisection for the root of an increasing function `f` on (lo, hi) with f(lo) < 0 < f(hi).
fn bisect_increasing(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..200 {
        if hi - lo <= OMEGA_TOL {
            break;
        }
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

fn check_mbs(mu: f64, beta: f64, sigma: f64, tau_l: f64) -> Result<(), ParamError> {
    check_positive("mu", mu)?;
    check_non_negative("beta", beta)?;
    check_non_negative("sigma", sigma)?;
    check_positive("tau_l", tau_l)?;
    if !(FRAC_PI_2 / tau_l).is_finite() {
        return Err(ParamError::OutOfRange {
            name: "tau_l",
            value: tau_l,
            allowed: "finite and > 0 with pi/(2 tau_l) finite",
        });
    }
    Ok(())
}

/// Small-amplitude limit cycle of (68)–(70) with D(M) ≈ 2/(πM): ω is the root in
/// (0, π/(2τ_L)) of σ = ½ sin(τ_Lω) − β cos(τ_Lω)/(2μω) (70) — the right side is strictly
/// increasing in ω, from −∞ (or 0 when β = 0) to ½, so the root is unique — and
/// M = 2 cos(τ_Lω)/(πμω²) (69). `None` when σ ≥ ½ or when no root exists (β = σ = 0).
/// The prediction is self-consistent only when M < 1 (check `amplitude`).
///
/// # Errors
/// [`ParamError`] on non-finite or out-of-range input (μ, τ_L > 0; β, σ ≥ 0).
pub fn small_limit_cycle(
    mu: f64,
    beta: f64,
    sigma: f64,
    tau_l: f64,
) -> Result<Option<LimitCycle>, ParamError> {
    check_mbs(mu, beta, sigma, tau_l)?;
    if sigma >= 0.5 {
        return Ok(None);
    }
    let w_end = FRAC_PI_2 / tau_l;
    let f =
        |w: f64| 0.5 * libm::sin(tau_l * w) - beta * libm::cos(tau_l * w) / (2.0 * mu * w) - sigma;
    // Find a left end with f < 0 (f → −∞ as ω → 0 when β > 0; f(0+) = −σ when β = 0).
    let mut lo = w_end;
    let mut found = false;
    for _ in 0..1100 {
        lo *= 0.5;
        if lo <= 0.0 {
            break;
        }
        if f(lo) < 0.0 {
            found = true;
            break;
        }
    }
    if !found {
        return Ok(None);
    }
    let w = bisect_increasing(f, lo, w_end);
    let m = 2.0 * libm::cos(tau_l * w) / (PI * mu * w * w);
    if !(m.is_finite() && m > 0.0) {
        return Ok(None);
    }
    Ok(Some(LimitCycle {
        amplitude: m,
        omega: w,
    }))
}

/// σ on the line (70) for a given ω ∈ (0, π/(2τ_L)]: ½ sin(τ_Lω) − β cos(τ_Lω)/(2μω).
///
/// # Errors
/// [`ParamError`] on non-finite or out-of-range input (ω must be in (0, π/(2τ_L)]).
pub fn small_cycle_sigma(mu: f64, beta: f64, tau_l: f64, omega: f64) -> Result<f64, ParamError> {
    check_mbs(mu, beta, 0.0, tau_l)?;
    check_omega(omega, tau_l)?;
    let visc = if beta == 0.0 {
        0.0
    } else {
        beta * libm::cos(tau_l * omega) / (2.0 * mu * omega)
    };
    let s = 0.5 * libm::sin(tau_l * omega) - visc;
    if s.is_nan() {
        return Err(ParamError::OutOfRange {
            name: "mu",
            value: mu,
            allowed: "> 0 and not so small that beta/(2 mu omega) overflows",
        });
    }
    Ok(s)
}

fn check_omega(omega: f64, tau_l: f64) -> Result<f64, ParamError> {
    check_positive("omega", omega)?;
    if omega > FRAC_PI_2 / tau_l {
        return Err(ParamError::OutOfRange {
            name: "omega",
            value: omega,
            allowed: "in (0, pi/(2 tau_l)]",
        });
    }
    Ok(omega)
}

/// Frequency of the large-amplitude oscillation, first equation of (71): the root of
/// cos(τ_Lω) = μω² in (0, π/(2τ_L)) (unique: the difference is strictly decreasing).
///
/// # Errors
/// [`ParamError`] unless μ, τ_L are finite and > 0.
pub fn large_cycle_omega(mu: f64, tau_l: f64) -> Result<f64, ParamError> {
    check_mbs(mu, 0.0, 0.0, tau_l)?;
    let w_end = FRAC_PI_2 / tau_l;
    // g(w) = μω² − cos(τ_Lω) is increasing, g(0) = −1 < 0, g(w_end) = μ w_end² > 0.
    Ok(bisect_increasing(
        |w| mu * w * w - libm::cos(tau_l * w),
        0.0,
        w_end,
    ))
}

/// Large-amplitude stability boundary (72): σ = (πM/4)(sin(τ_Lω) − βω) with ω from (71).
/// Below this σ oscillations of amplitude M grow (D(M) ≈ 1). Negative values mean no
/// boundary (β > τ_L-ish: stable for that M).
///
/// # Errors
/// [`ParamError`] on non-finite or out-of-range input (μ, τ_L, M > 0; β ≥ 0).
pub fn large_cycle_sigma(
    mu: f64,
    beta: f64,
    tau_l: f64,
    amplitude: f64,
) -> Result<f64, ParamError> {
    check_mbs(mu, beta, 0.0, tau_l)?;
    check_positive("amplitude", amplitude)?;
    let w = large_cycle_omega(mu, tau_l)?;
    Ok(PI * amplitude / 4.0 * (libm::sin(tau_l * w) - beta * w))
}

/// Low-frequency approximation (73) of the large-cycle frequency: ω ≈ 1/√(μ + τ_L²/2).
///
/// # Errors
/// [`ParamError`] unless μ, τ_L are finite and > 0.
pub fn large_cycle_omega_approx(mu: f64, tau_l: f64) -> Result<f64, ParamError> {
    check_mbs(mu, 0.0, 0.0, tau_l)?;
    Ok(1.0 / libm::sqrt(mu + 0.5 * tau_l * tau_l))
}

/// Approximate boundary (74): σ = (π/4)·M·ω·(τ_L − β) with ω from (73); with ξ̇_max = Mω it is
/// the describing-function counterpart of the critical line of (12)/(19).
///
/// # Errors
/// [`ParamError`] on non-finite or out-of-range input.
pub fn large_cycle_sigma_approx(
    mu: f64,
    beta: f64,
    tau_l: f64,
    amplitude: f64,
) -> Result<f64, ParamError> {
    check_mbs(mu, beta, 0.0, tau_l)?;
    check_positive("amplitude", amplitude)?;
    let w = large_cycle_omega_approx(mu, tau_l)?;
    Ok(PI / 4.0 * amplitude * w * (tau_l - beta))
}

/// Stability bound (75) for M > 1 and μ ≫ τ_L²/2: the system can be stable only if
/// σ ≥ π(τ_L − β)/(4√μ). Returns that minimum σ.
///
/// # Errors
/// [`ParamError`] on non-finite or out-of-range input.
pub fn sigma_min_large(mu: f64, beta: f64, tau_l: f64) -> Result<f64, ParamError> {
    check_mbs(mu, beta, 0.0, tau_l)?;
    Ok(PI / (4.0 * libm::sqrt(mu)) * (tau_l - beta))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn df_limits() {
        for m in [1e-6, 1e-3, 0.1, 0.9] {
            let d = quantizer_df(m).unwrap();
            assert!((d - 2.0 / (PI * m)).abs() < 1e-12 * d);
        }
        for m in [10.0, 10.5, 1e3, 1e3 + 0.5, 1e4, D_SUM_CAP] {
            let d = quantizer_df(m).unwrap();
            assert!((d - 1.0).abs() < 0.4 * libm::pow(m, -1.5), "M={m} D={d}");
        }
    }

    #[test]
    fn small_cycle_satisfies_68() {
        let (mu, beta, sigma, tl) = (100.0, 0.7, 0.3, 0.5);
        let lc = small_limit_cycle(mu, beta, sigma, tl).unwrap().unwrap();
        let (m, w) = (lc.amplitude, lc.omega);
        let d1 = 2.0 / (PI * m);
        assert!((d1 * libm::cos(tl * w) - mu * w * w).abs() < 1e-9);
        assert!((d1 * libm::sin(tl * w) - beta * w - 4.0 * sigma / (PI * m)).abs() < 1e-9);
        assert!(small_limit_cycle(mu, beta, 0.5, tl).unwrap().is_none());
        assert!(small_limit_cycle(mu, 0.0, 0.0, tl).unwrap().is_none());
    }

    /// Sec. VII-C: as σ → ½⁻ the small cycle's ω → π/(2τ_L) and M → 0; M grows as σ drops.
    #[test]
    fn small_cycle_limits() {
        let (mu, beta, tl) = (5.0, 0.8, 1.75);
        let near = small_limit_cycle(mu, beta, 0.5 - 1e-9, tl)
            .unwrap()
            .unwrap();
        assert!((near.omega - FRAC_PI_2 / tl).abs() < 1e-3);
        assert!(near.amplitude < 1e-3);
        let mut prev = 0.0;
        for s in [0.45, 0.35, 0.25, 0.15] {
            let lc = small_limit_cycle(mu, beta, s, tl).unwrap().unwrap();
            assert!(lc.amplitude > prev, "σ={s}");
            prev = lc.amplitude;
            // (70) holds at the solution
            assert!((small_cycle_sigma(mu, beta, tl, lc.omega).unwrap() - s).abs() < 1e-9);
        }
    }

    /// Sec. VII-D: (72) crosses σ = 0 at β = sin(τ_Lω)/ω ≈ τ_L (for μ ≫ τ_L²), and (74)/(75)
    /// vanish at β = τ_L.
    #[test]
    fn large_cycle_boundary_crosses_zero_near_tau_l() {
        let (mu, tl) = (100.0, 0.5 + 1.25);
        let w = large_cycle_omega(mu, tl).unwrap();
        let b0 = libm::sin(tl * w) / w;
        assert!(large_cycle_sigma(mu, b0, tl, 2.0).unwrap().abs() < 1e-12);
        assert!((b0 - tl).abs() < 0.01 * tl, "{b0}");
        assert!(large_cycle_sigma_approx(mu, tl, tl, 2.0).unwrap().abs() < 1e-15);
        assert!(sigma_min_large(mu, tl, tl).unwrap().abs() < 1e-15);
        // below the line (small β, σ = 0) the large-cycle boundary is positive: unstable
        assert!(large_cycle_sigma(mu, 0.0, tl, 1.0).unwrap() > 0.0);
    }

    #[test]
    fn large_cycle_73_close_for_big_mu() {
        let w = large_cycle_omega(100.0, 0.5).unwrap();
        let wa = large_cycle_omega_approx(100.0, 0.5).unwrap();
        assert!((w - wa).abs() < 1e-4 * w, "{w} {wa}");
    }
}
