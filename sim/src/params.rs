//! Dimensionless parameters of eq. (7)–(9) and the effect set of a simulation.
//!
//! Units (Table I): μ = m/(K·T²), β = b/(K·T), σ = c/(K·Δ), τ_D = T_D/T; positions in encoder
//! ticks, velocities in ticks per period, forces in K·Δ. [`Params`] and [`ParamError`] are
//! `stiffwall_core`'s [`Dimensionless`](stiffwall_core::Dimensionless) and
//! [`ParamError`](stiffwall_core::ParamError): the model has one home. Invariants after
//! [`validate`]: core's ranges (μ > 0, β ≥ 0, σ ≥ 0, τ_D ≥ 0, all finite) and the solvers'
//! delay-line capacity τ_D ≤ [`MAX_TAU_D`].

use stiffwall_core::params::check_range;
pub use stiffwall_core::params::{Dimensionless as Params, ParamError};

/// Largest supported delay in sampling periods (size of the fixed delay line).
pub const MAX_TAU_D: f64 = 250.0;

/// Checks `p` for the solvers: core's [`Params::validate`] and τ_D ≤ [`MAX_TAU_D`].
///
/// # Errors
/// [`ParamError`] naming the first offending field and its allowed range.
pub fn validate(p: &Params) -> Result<Params, ParamError> {
    p.validate()?;
    check_range(
        "tau_d",
        p.tau_d,
        0.0,
        false,
        MAX_TAU_D,
        "finite and in [0, 250] periods",
    )?;
    Ok(*p)
}

/// Which effects of the model are simulated. Disabled effects are compiled out
/// (see [`crate::exact::dispatch`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct Effects {
    /// Position quantization: spring −⌊ξ(h)⌋ − ½ (eq. (8)) instead of −ξ(h) (eq. (23)).
    pub quantization: bool,
    /// Dynamic Coulomb friction σ (otherwise σ is ignored).
    pub coulomb: bool,
    /// Viscous friction β (otherwise β is ignored).
    pub viscous: bool,
    /// Loop delay τ_D (otherwise τ_D must be 0).
    pub delay: bool,
    /// One-sided wall occupying ξ ≥ 0: the spring only pushes towards −ξ (force clamped ≤ 0).
    pub one_sided: bool,
}

impl Effects {
    /// Every effect of the paper's model (bidirectional spring).
    pub const ALL: Self = Self {
        quantization: true,
        coulomb: true,
        viscous: true,
        delay: true,
        one_sided: false,
    };
    /// No effect: an undamped, unquantized sampled spring without delay.
    pub const NONE: Self = Self {
        quantization: false,
        coulomb: false,
        viscous: false,
        delay: false,
        one_sided: false,
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_names_the_field() {
        let mut p = Params::BASE;
        p.sigma = -1.0;
        assert_eq!(validate(&p).unwrap_err().name(), "sigma");
        p.sigma = 1.0;
        p.tau_d = f64::NAN;
        assert_eq!(validate(&p).unwrap_err().name(), "tau_d");
        assert!(validate(&Params::BASE).is_ok());
    }

    /// The delay line bounds τ_D, beyond core's τ_D ≥ 0.
    #[test]
    fn tau_d_beyond_the_delay_line_is_rejected() {
        let p = Params {
            tau_d: 250.5,
            ..Params::BASE
        };
        assert!(p.validate().is_ok());
        let e = validate(&p).unwrap_err();
        assert_eq!(
            (e.name(), e.allowed()),
            ("tau_d", "finite and in [0, 250] periods")
        );
    }
}
