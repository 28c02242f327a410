//! Stability regions of the (β, σ) plane and the dissipation criteria (12), (15)–(19).
//!
//! Units: everything here is dimensionless (Table I): β, σ friction ratios; ξ̇ in encoder ticks
//! per sampling period; ξ̈ in ticks per period²; τ_D in periods. Only [`velocity_limit_m_s`]
//! returns a physical value (m/s, or rad/s for rotational devices).
//!
//! Boundary conventions: the criteria are the paper's non-strict inequalities (`≥`), so a point
//! exactly on a critical line satisfies them. Region membership follows the same convention:
//! β = ½ (or β = ½ + τ_D) counts as the high-viscosity side, σ = ½ as the high-Coulomb side.
//!
//! Invariants: every input must be finite; β, σ, τ_D, ξ̇_max, ξ̈_max must be ≥ 0. `None` for a
//! velocity or acceleration bound means "unbounded". Non-finite or negative input is a
//! [`ParamError`].

use crate::params::{check_non_negative, check_positive, ParamError, PhysicalParams};

/// A region of Fig. 3 (τ_D = 0) or Fig. 5 (τ_D > 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Region {
    /// β ≥ ½, σ ≥ ½ (τ_D = 0): passive, globally stable.
    A,
    /// β ≥ ½ (+τ_D), σ < ½: stable limit cycles below one encoder tick.
    B,
    /// β < ½ (+τ_D), σ < ½: unstable, may generate energy at all times.
    C,
    /// β < ½ (+τ_D), σ ≥ ½, below the critical line of (12)/(19): locally unstable.
    D,
    /// β < ½ (+τ_D), σ ≥ ½, on or above the critical line: locally stable, energy decreasing.
    E,
    /// τ_D > 0, β ≥ ½ + τ_D, σ ≥ ½ + ξ̈_max(τ_D² + τ_D): (19) holds at every velocity.
    F1,
    /// τ_D > 0, β ≥ ½ + τ_D, ½ ≤ σ < ½ + ξ̈_max(τ_D² + τ_D): brief energy generation at low
    /// speed, dissipation over extended motions; stable.
    F2,
}

impl Region {
    /// One-line meaning of the region (Sec. III-B and III-D).
    #[must_use]
    pub fn meaning(&self) -> &'static str {
        match self {
            Self::A => "passive, globally stable: friction dissipates all spurious energy",
            Self::B => "stable limit cycle with amplitude below one encoder tick",
            Self::C => "unstable: may generate energy at all times",
            Self::D => "locally unstable: energy may grow from this initial velocity",
            Self::E => "locally stable: energy decreases while |velocity| stays below the limit",
            Self::F1 => {
                "stable (delay): energy decreases at every velocity, given max acceleration"
            }
            Self::F2 => {
                "stable (delay): brief energy generation at low speed, dissipated over motion"
            }
        }
    }

    /// Short label, `"A"` … `"E"`, `"F1"`, `"F2"`.
    #[must_use]
    pub fn label(&self) -> &'static str {
        match self {
            Self::A => "A",
            Self::B => "B",
            Self::C => "C",
            Self::D => "D",
            Self::E => "E",
            Self::F1 => "F1",
            Self::F2 => "F2",
        }
    }

    /// Stability rank, 0 = most stable. Along the ray of growing K (Fig. 4) the rank never
    /// decreases: A/F1 (0) → B, E, F2 (1) → D (2) → C (3).
    #[must_use]
    pub fn rank(&self) -> u8 {
        match self {
            Self::A | Self::F1 => 0,
            Self::B | Self::E | Self::F2 => 1,
            Self::D => 2,
            Self::C => 3,
        }
    }

    /// Whether the paper labels the region stable (globally or locally): A, B, E, F1, F2.
    #[must_use]
    pub fn is_stable(&self) -> bool {
        !matches!(self, Self::C | Self::D)
    }
}

impl core::fmt::Display for Region {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.label())
    }
}

/// Product that is 0 when either factor is 0 (0·∞ from an overflowed factor is 0, not NaN).
fn mul0(a: f64, b: f64) -> f64 {
    if a == 0.0 || b == 0.0 {
        0.0
    } else {
        a * b
    }
}

fn check_bs(beta: f64, sigma: f64) -> Result<(), ParamError> {
    check_non_negative("beta", beta)?;
    check_non_negative("sigma", sigma)?;
    Ok(())
}

fn check_opt(name: &'static str, v: Option<f64>) -> Result<(), ParamError> {
    if let Some(v) = v {
        check_non_negative(name, v)?;
    }
    Ok(())
}

/// Left-hand side of (12) multiplied by ξ̇ (the form (51)): ξ̇(β − ½) + (σ − ½).
/// Non-negative iff the first inequality of (12) holds at velocity ξ̇ > 0.
#[must_use]
pub fn criterion_12_margin(beta: f64, sigma: f64, xidot: f64) -> f64 {
    xidot * (beta - 0.5) + (sigma - 0.5)
}

/// Dissipation criterion (12) for τ_D = 0: (β − ½) + (σ − ½)/ξ̇_max ≥ 0 and σ ≥ ½.
/// Written as (51) so that ξ̇_max = 0 is allowed; `None` means unbounded velocity (then the
/// criterion is β ≥ ½ and σ ≥ ½, region A).
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn criterion_12(beta: f64, sigma: f64, xidot_max: Option<f64>) -> Result<bool, ParamError> {
    check_bs(beta, sigma)?;
    check_opt("xidot_max", xidot_max)?;
    Ok(sigma >= 0.5
        && match xidot_max {
            None => beta >= 0.5,
            Some(v) => criterion_12_margin(beta, sigma, v) >= 0.0,
        })
}

/// Criterion (16), sampling without quantization: (β − ½) + σ/ξ̇_max ≥ 0, evaluated as
/// ξ̇_max(β − ½) + σ ≥ 0; `None` (unbounded velocity) gives Colgate's β ≥ ½ (17).
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn criterion_16(beta: f64, sigma: f64, xidot_max: Option<f64>) -> Result<bool, ParamError> {
    check_bs(beta, sigma)?;
    check_opt("xidot_max", xidot_max)?;
    Ok(match xidot_max {
        None => beta >= 0.5,
        Some(v) => v * (beta - 0.5) + sigma >= 0.0,
    })
}

/// Left-hand side of (19): σ − ½ − ξ̈(τ_D² + τ_D) + ξ̇(β − ½ − τ_D).
#[must_use]
pub fn criterion_19_margin(beta: f64, sigma: f64, tau_d: f64, xidot: f64, xiddot: f64) -> f64 {
    sigma - 0.5 - mul0(xiddot, tau_d * tau_d + tau_d) + mul0(xidot, beta - 0.5 - tau_d)
}

/// Delayed dissipation criterion (19), required at every speed |ξ̇| ≤ ξ̇_max. Since (59) is
/// linear in |ξ̇|, that means (19) at ξ̇_max **and** at ξ̇ = 0 (σ ≥ ½ + ξ̈_max(τ_D² + τ_D)); the
/// second clause is the delayed analogue of the clause σ ≥ ½ of (12), and for τ_D = 0 this
/// function equals [`criterion_12`]. `None` = unbounded; an unbounded ξ̈_max with τ_D > 0 never
/// satisfies the criterion.
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn criterion_19(
    beta: f64,
    sigma: f64,
    tau_d: f64,
    xidot_max: Option<f64>,
    xiddot_max: Option<f64>,
) -> Result<bool, ParamError> {
    check_bs(beta, sigma)?;
    check_non_negative("tau_d", tau_d)?;
    check_opt("xidot_max", xidot_max)?;
    check_opt("xiddot_max", xiddot_max)?;
    let sigma_star = match sigma_star(tau_d, xiddot_max) {
        Some(s) => s,
        None => return Ok(false),
    };
    if sigma < sigma_star {
        return Ok(false);
    }
    let beta_star = 0.5 + tau_d;
    Ok(match xidot_max {
        None => beta >= beta_star,
        Some(v) => (sigma - sigma_star) + mul0(v, beta - beta_star) >= 0.0,
    })
}

/// σ* = ½ + ξ̈_max(τ_D² + τ_D), the zero-velocity end of the critical line of (19); `None`
/// when it is unbounded (τ_D > 0 with unbounded acceleration).
fn sigma_star(tau_d: f64, xiddot_max: Option<f64>) -> Option<f64> {
    let g = tau_d * tau_d + tau_d;
    if g == 0.0 {
        return Some(0.5);
    }
    xiddot_max.map(|a| 0.5 + mul0(a, g))
}

/// Region of Fig. 3 for τ_D = 0 (Sec. III-B), with the critical line of (12) drawn for
/// ξ̇_max (`None` = unbounded velocity, which leaves no region E).
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn classify(beta: f64, sigma: f64, xidot_max: Option<f64>) -> Result<Region, ParamError> {
    classify_delayed(beta, sigma, 0.0, xidot_max, Some(0.0))
}

/// Region of Fig. 5 for τ_D > 0 (Sec. III-D); for τ_D = 0 identical to [`classify`] (A–E).
///
/// Our reading of Fig. 5 (the figure is not in the text), with β* = ½ + τ_D and
/// σ* = ½ + ξ̈_max(τ_D² + τ_D):
/// - F1: β ≥ β*, σ ≥ σ* ((19) holds at every speed);
/// - F2: β ≥ β*, ½ ≤ σ < σ* (fails only at low speed);
/// - B: β ≥ β*, σ < ½; C: β < β*, σ < ½ (the DF analysis: (70) has limit cycles iff σ < ½,
///   and (72) needs β ≤ τ_L = β* for large unstable ones);
/// - E: β < β*, σ ≥ ½ and (19) holds at ξ̇_max (so σ ≥ σ* + ξ̇_max(β* − β));
/// - D: β < β*, σ ≥ ½ otherwise.
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn classify_delayed(
    beta: f64,
    sigma: f64,
    tau_d: f64,
    xidot_max: Option<f64>,
    xiddot_max: Option<f64>,
) -> Result<Region, ParamError> {
    check_bs(beta, sigma)?;
    check_non_negative("tau_d", tau_d)?;
    check_opt("xidot_max", xidot_max)?;
    check_opt("xiddot_max", xiddot_max)?;
    let delayed = tau_d > 0.0;
    let beta_star = 0.5 + tau_d;
    let high_beta = beta >= beta_star;
    if sigma < 0.5 {
        return Ok(if high_beta { Region::B } else { Region::C });
    }
    if high_beta {
        if !delayed {
            return Ok(Region::A);
        }
        return Ok(match sigma_star(tau_d, xiddot_max) {
            Some(s) if sigma >= s => Region::F1,
            _ => Region::F2,
        });
    }
    if criterion_19(beta, sigma, tau_d, xidot_max, xiddot_max)? {
        Ok(Region::E)
    } else {
        Ok(Region::D)
    }
}

/// Velocity limit (15): the largest |ξ̇| for which (12) holds, ξ̇_max = (σ − ½)/(½ − β).
/// `None` when unbounded (β ≥ ½, σ ≥ ½); `Some(0.0)` when no velocity satisfies (12) (σ < ½).
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn velocity_limit(beta: f64, sigma: f64) -> Result<Option<f64>, ParamError> {
    velocity_limit_delayed(beta, sigma, 0.0, 0.0)
}

/// Delayed analogue of (15) from (19): ξ̇_max = (σ − σ*)/(½ + τ_D − β) with
/// σ* = ½ + ξ̈_max(τ_D² + τ_D). `None` when unbounded, `Some(0.0)` when σ < σ*.
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn velocity_limit_delayed(
    beta: f64,
    sigma: f64,
    tau_d: f64,
    xiddot_max: f64,
) -> Result<Option<f64>, ParamError> {
    check_bs(beta, sigma)?;
    check_non_negative("tau_d", tau_d)?;
    check_non_negative("xiddot_max", xiddot_max)?;
    let sigma_star = 0.5 + mul0(xiddot_max, tau_d * tau_d + tau_d);
    let s = sigma - sigma_star;
    let beta_star = 0.5 + tau_d;
    let d = beta_star - beta;
    Ok(if s < 0.0 {
        Some(0.0)
    } else if d <= 0.0 {
        None
    } else {
        // Lower by ulps until the criterion, evaluated as in `criterion_19`, holds at it.
        Some(settle_down(s / d, |v| s + mul0(v, beta - beta_star) >= 0.0))
    })
}

/// Lowers a non-negative `v` by ulps (at most 64) until `holds(v)`.
fn settle_down(mut v: f64, holds: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..64 {
        if holds(v) || v <= 0.0 {
            return v;
        }
        v = v.next_down();
    }
    v
}

/// Delayed velocity limit when the acceleration bound is that of a harmonic motion at the
/// wall's natural frequency, ξ̈_max = ξ̇_max/√μ (dimensionless ω_n = 1/√μ, from (10)):
/// ξ̇_max = (σ − ½)/(½ + τ_D − β + (τ_D² + τ_D)/√μ). Equals (15) for τ_D = 0.
///
/// # Errors
/// [`ParamError`] on non-finite or out-of-range input (μ must be > 0).
pub fn velocity_limit_harmonic(
    mu: f64,
    beta: f64,
    sigma: f64,
    tau_d: f64,
) -> Result<Option<f64>, ParamError> {
    check_positive("mu", mu)?;
    check_bs(beta, sigma)?;
    check_non_negative("tau_d", tau_d)?;
    let s = sigma - 0.5;
    let d = 0.5 + tau_d - beta + (tau_d * tau_d + tau_d) / libm::sqrt(mu);
    Ok(if s < 0.0 {
        Some(0.0)
    } else if d <= 0.0 {
        None
    } else {
        Some(s / d)
    })
}

/// Physical velocity limit (15): ẋ_max = (2c − KΔ)/(KT − 2b), in m/s (rad/s when rotational);
/// with delay, the delayed limit of [`velocity_limit_harmonic`] converted by ẋ = ξ̇Δ/T.
/// `None` when unbounded, `Some(0.0)` when no velocity satisfies the criterion.
///
/// # Errors
/// [`ParamError`] when a parameter is out of range.
pub fn velocity_limit_m_s(p: &PhysicalParams) -> Result<Option<f64>, ParamError> {
    let d = p.to_dimensionless()?;
    Ok(velocity_limit_harmonic(d.mu, d.beta, d.sigma, d.tau_d)?.map(|x| p.velocity_from_xidot(x)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fig3_regions() {
        assert_eq!(classify(0.6, 0.6, None).unwrap(), Region::A);
        assert_eq!(classify(0.6, 0.4, Some(3.0)).unwrap(), Region::B);
        assert_eq!(classify(0.4, 0.4, Some(3.0)).unwrap(), Region::C);
        // critical line through (1/2, 1/2) with slope -xidot = -2: sigma = 1/2 + 2(1/2 - beta)
        assert_eq!(classify(0.25, 0.9, Some(2.0)).unwrap(), Region::D);
        assert_eq!(classify(0.25, 1.0, Some(2.0)).unwrap(), Region::E);
        assert_eq!(classify(0.25, 1.1, Some(2.0)).unwrap(), Region::E);
        assert_eq!(classify(0.25, 1.1, None).unwrap(), Region::D);
    }

    #[test]
    fn fig5_regions() {
        let (t, a) = (1.0, 0.1); // beta* = 1.5, sigma* = 0.5 + 0.1*2 = 0.7
        let c = |b, s, v| classify_delayed(b, s, t, v, Some(a)).unwrap();
        assert_eq!(c(1.6, 0.8, None), Region::F1);
        assert_eq!(c(1.6, 0.6, None), Region::F2);
        assert_eq!(c(1.6, 0.4, None), Region::B);
        assert_eq!(c(1.0, 0.4, Some(1.0)), Region::C);
        assert_eq!(c(1.0, 0.6, Some(1.0)), Region::D);
        assert_eq!(c(1.0, 1.3, Some(1.0)), Region::E); // 0.7 + 1*(0.5) = 1.2
        assert_eq!(c(1.0, 1.1, Some(1.0)), Region::D);
    }

    #[test]
    fn velocity_limit_15() {
        assert_eq!(velocity_limit(0.6, 0.7).unwrap(), None);
        assert_eq!(velocity_limit(0.6, 0.4).unwrap(), Some(0.0));
        let v = velocity_limit(0.25, 1.0).unwrap().unwrap();
        assert!((v - 2.0).abs() < 1e-12);
        assert!(criterion_12(0.25, 1.0, Some(v)).unwrap());
        assert!(!criterion_12(0.25, 1.0, Some(v * (1.0 + 1e-9))).unwrap());
    }

    #[test]
    fn non_finite_is_error() {
        assert!(classify(f64::NAN, 1.0, None).is_err());
        assert!(classify(0.1, 1.0, Some(f64::INFINITY)).is_err());
        assert!(criterion_19(0.1, 1.0, -1.0, None, None).is_err());
    }
}
