//! Dimensionless parameters of eq. (7)–(9) and the effect set of a simulation.
//!
//! Units (Table I): μ = m/(K·T²), β = b/(K·T), σ = c/(K·Δ), τ_D = T_D/T; positions in encoder
//! ticks, velocities in ticks per period, forces in K·Δ. Invariants after [`Params::validate`]:
//! μ > 0, β ≥ 0, σ ≥ 0, 0 ≤ τ_D ≤ [`MAX_TAU_D`], all finite.

/// Largest supported delay in sampling periods (size of the fixed delay line).
pub const MAX_TAU_D: f64 = 250.0;

/// Dimensionless plant and loop parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct Params {
    /// μ = m/(K T²) > 0 (the sampling limit is 1/π², eq. (11)).
    pub mu: f64,
    /// β = b/(K T) ≥ 0.
    pub beta: f64,
    /// σ = c/(K Δ) ≥ 0.
    pub sigma: f64,
    /// τ_D = T_D/T ≥ 0, any real (ZOH not included: it is modelled by the sampling itself).
    pub tau_d: f64,
}

/// A parameter out of range: the field name and the allowed range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParamError {
    /// Field name.
    pub field: &'static str,
    /// Allowed range, human readable.
    pub allowed: &'static str,
}

impl core::fmt::Display for ParamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}: allowed range is {}", self.field, self.allowed)
    }
}

impl Params {
    /// The paper's base scene: μ = 100, β = 0.1, σ = 1, τ_D = 0.
    pub const BASE: Self = Self {
        mu: 100.0,
        beta: 0.1,
        sigma: 1.0,
        tau_d: 0.0,
    };

    /// Checks the invariants, naming the first offending field.
    pub fn validate(&self) -> Result<(), ParamError> {
        if !(self.mu.is_finite() && self.mu > 0.0) {
            return Err(ParamError {
                field: "mu",
                allowed: "finite, > 0",
            });
        }
        if !(self.beta.is_finite() && self.beta >= 0.0) {
            return Err(ParamError {
                field: "beta",
                allowed: "finite, >= 0",
            });
        }
        if !(self.sigma.is_finite() && self.sigma >= 0.0) {
            return Err(ParamError {
                field: "sigma",
                allowed: "finite, >= 0",
            });
        }
        if !(self.tau_d.is_finite() && (0.0..=MAX_TAU_D).contains(&self.tau_d)) {
            return Err(ParamError {
                field: "tau_d",
                allowed: "0 ..= 250 periods",
            });
        }
        Ok(())
    }
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
        assert_eq!(p.validate().unwrap_err().field, "sigma");
        p.sigma = 1.0;
        p.tau_d = f64::NAN;
        assert_eq!(p.validate().unwrap_err().field, "tau_d");
        assert!(Params::BASE.validate().is_ok());
    }
}
