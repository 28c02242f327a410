//! Physical device/loop parameters and their dimensionless form (the paper's Table I).
//!
//! Units: [`PhysicalParams`] is SI. For a linear device mass is kg, viscous friction N·s/m,
//! Coulomb friction N, resolution m, stiffness N/m; for a rotational device (`rotational: true`)
//! the same fields are kg·m², N·m·s/rad, N·m, rad and N·m/rad. Times are seconds in both cases.
//! [`Dimensionless`] holds μ = m/(K T²), β = b/(K T), σ = c/(K Δ), τ_D = T_D/T (Table I).
//! Beside them, for a spring + damper wall of virtual damping B (N·s/m or N·m·s/rad), the
//! dimensionless virtual damping is β_v = B/(K T) (not in Table I; the paper's wall has B = 0;
//! see `criteria::beta_v` and `criteria::k_max_exact_linear`).
//!
//! Invariants: a value that passed validation is finite; m, T, Δ, K are > 0; b, c, T_D are ≥ 0.
//! Every failed check returns a [`ParamError`] naming the parameter and the allowed range.

use core::fmt;

/// A parameter outside its allowed range. `Display` gives e.g.
/// `mass must be finite and > 0 (got -1)`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum ParamError {
    /// The value is NaN or infinite.
    NotFinite {
        /// Parameter name, e.g. `"mass"`.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// The allowed range, e.g. `"finite and > 0"`.
        allowed: &'static str,
    },
    /// The value is finite but outside the allowed range.
    OutOfRange {
        /// Parameter name, e.g. `"period"`.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// The allowed range, e.g. `"finite and > 0"`.
        allowed: &'static str,
    },
}

impl ParamError {
    /// Name of the offending parameter.
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            Self::NotFinite { name, .. } | Self::OutOfRange { name, .. } => name,
        }
    }

    /// The refused value.
    #[must_use]
    pub fn value(&self) -> f64 {
        match self {
            Self::NotFinite { value, .. } | Self::OutOfRange { value, .. } => *value,
        }
    }

    /// Allowed range of the offending parameter, in words.
    #[must_use]
    pub fn allowed(&self) -> &'static str {
        match self {
            Self::NotFinite { allowed, .. } | Self::OutOfRange { allowed, .. } => allowed,
        }
    }
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotFinite {
                name,
                value,
                allowed,
            }
            | Self::OutOfRange {
                name,
                value,
                allowed,
            } => write!(f, "{name} must be {allowed} (got {value})"),
        }
    }
}

impl core::error::Error for ParamError {}

/// Allowed-range text for strictly positive parameters.
pub const POSITIVE: &str = "finite and > 0";
/// Allowed-range text for non-negative parameters.
pub const NON_NEGATIVE: &str = "finite and >= 0";

/// Checks `value` is finite and > 0.
///
/// # Errors
/// [`ParamError`] naming `name` when the check fails.
pub fn check_positive(name: &'static str, value: f64) -> Result<f64, ParamError> {
    if !value.is_finite() {
        Err(ParamError::NotFinite {
            name,
            value,
            allowed: POSITIVE,
        })
    } else if value <= 0.0 {
        Err(ParamError::OutOfRange {
            name,
            value,
            allowed: POSITIVE,
        })
    } else {
        Ok(value)
    }
}

/// Checks `value` is finite and ≥ 0.
///
/// # Errors
/// [`ParamError`] naming `name` when the check fails.
pub fn check_non_negative(name: &'static str, value: f64) -> Result<f64, ParamError> {
    if !value.is_finite() {
        Err(ParamError::NotFinite {
            name,
            value,
            allowed: NON_NEGATIVE,
        })
    } else if value < 0.0 {
        Err(ParamError::OutOfRange {
            name,
            value,
            allowed: NON_NEGATIVE,
        })
    } else {
        Ok(value)
    }
}

/// Checks `value` is finite and inside `lo ..= hi` (`lo` excluded when `lo_open`); `allowed`
/// states that range in words for the error, e.g. `"finite and in (0, 1e12]"`.
///
/// # Errors
/// [`ParamError`] naming `name` when the check fails.
pub fn check_range(
    name: &'static str,
    value: f64,
    lo: f64,
    lo_open: bool,
    hi: f64,
    allowed: &'static str,
) -> Result<f64, ParamError> {
    if !value.is_finite() {
        return Err(ParamError::NotFinite {
            name,
            value,
            allowed,
        });
    }
    let above_lo = if lo_open { value > lo } else { value >= lo };
    if above_lo && value <= hi {
        Ok(value)
    } else {
        Err(ParamError::OutOfRange {
            name,
            value,
            allowed,
        })
    }
}

/// Checks `value` is finite (any sign).
///
/// # Errors
/// [`ParamError::NotFinite`] naming `name` when the value is NaN or infinite.
pub fn check_finite(name: &'static str, value: f64) -> Result<f64, ParamError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ParamError::NotFinite {
            name,
            value,
            allowed: "finite",
        })
    }
}

/// Physical parameters of one device DOF and its control loop, SI units (eq. (1), (2), (6)).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PhysicalParams {
    /// Inertia m: kg (linear) or kg·m² (rotational). Must be > 0.
    pub mass: f64,
    /// Viscous friction b: N·s/m (linear) or N·m·s/rad (rotational). Must be ≥ 0.
    pub viscous: f64,
    /// Dynamic Coulomb friction c: N (linear) or N·m (rotational). Must be ≥ 0.
    pub coulomb: f64,
    /// Encoder (position quantum) resolution Δ: m (linear) or rad (rotational). Must be > 0.
    pub resolution: f64,
    /// Sampling period T: s. Must be > 0.
    pub period_s: f64,
    /// Virtual wall stiffness K: N/m (linear) or N·m/rad (rotational). Must be > 0.
    pub stiffness: f64,
    /// Combined loop delay T_D = T_A + T_V of eq. (6), excluding the ZOH: s. Must be ≥ 0.
    pub delay_s: f64,
    /// Whether the quantities are rotational (angles, torques) rather than linear.
    pub rotational: bool,
}

/// Dimensionless parameters of Table I.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Dimensionless {
    /// μ = m/(K T²), dimensionless inertia.
    pub mu: f64,
    /// β = b/(K T), dimensionless viscous friction.
    pub beta: f64,
    /// σ = c/(K Δ), dimensionless Coulomb friction.
    pub sigma: f64,
    /// τ_D = T_D/T, loop delay in sampling periods.
    pub tau_d: f64,
}

impl Dimensionless {
    /// The paper's base scene (Sec. IV): μ = 100, β = 0.1, σ = 1, τ_D = 0.
    pub const BASE: Self = Self {
        mu: 100.0,
        beta: 0.1,
        sigma: 1.0,
        tau_d: 0.0,
    };

    /// Validates every field: μ > 0, β ≥ 0, σ ≥ 0, τ_D ≥ 0, all finite.
    ///
    /// # Errors
    /// [`ParamError`] naming the first field out of range.
    pub fn validate(&self) -> Result<Self, ParamError> {
        check_positive("mu", self.mu)?;
        check_non_negative("beta", self.beta)?;
        check_non_negative("sigma", self.sigma)?;
        check_non_negative("tau_d", self.tau_d)?;
        Ok(*self)
    }

    /// Inverse of Table I: the physical parameters that give these dimensionless values for the
    /// chosen stiffness K, period T and resolution Δ (m = μKT², b = βKT, c = σKΔ, T_D = τ_D T).
    ///
    /// # Errors
    /// [`ParamError`] when a dimensionless field or K, T, Δ is out of range, or the product is
    /// not finite.
    pub fn to_physical(
        &self,
        stiffness: f64,
        period_s: f64,
        resolution: f64,
        rotational: bool,
    ) -> Result<PhysicalParams, ParamError> {
        self.validate()?;
        check_positive("stiffness", stiffness)?;
        check_positive("period", period_s)?;
        check_positive("resolution", resolution)?;
        let p = PhysicalParams {
            mass: self.mu * stiffness * period_s * period_s,
            viscous: self.beta * stiffness * period_s,
            coulomb: self.sigma * stiffness * resolution,
            resolution,
            period_s,
            stiffness,
            delay_s: self.tau_d * period_s,
            rotational,
        };
        p.validate()
    }
}

/// The scale of Table I: stiffness K, sampling period T and resolution Δ (SI, as in
/// [`PhysicalParams`]). Every conversion between physical and dimensionless quantities of this
/// crate goes through it, so each ratio of Table I is written once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    /// K: N/m (N·m/rad). > 0.
    pub stiffness: f64,
    /// T: s. > 0.
    pub period_s: f64,
    /// Δ: m (rad). > 0.
    pub resolution: f64,
}

impl Scale {
    /// A validated scale.
    ///
    /// # Errors
    /// [`ParamError`] naming `stiffness`, `period` or `resolution` when not finite and > 0.
    pub fn new(stiffness: f64, period_s: f64, resolution: f64) -> Result<Self, ParamError> {
        Ok(Self {
            stiffness: check_positive("stiffness", stiffness)?,
            period_s: check_positive("period", period_s)?,
            resolution: check_positive("resolution", resolution)?,
        })
    }

    /// μ = m/(K T²).
    #[must_use]
    pub fn mu(&self, mass: f64) -> f64 {
        ratio(mass, self.stiffness * self.period_s * self.period_s, || {
            mass / self.stiffness / self.period_s / self.period_s
        })
    }

    /// β = b/(K T).
    #[must_use]
    pub fn beta(&self, viscous: f64) -> f64 {
        ratio(viscous, self.stiffness * self.period_s, || {
            viscous / self.stiffness / self.period_s
        })
    }

    /// σ = c/(K Δ).
    #[must_use]
    pub fn sigma(&self, coulomb: f64) -> f64 {
        ratio(coulomb, self.stiffness * self.resolution, || {
            coulomb / self.stiffness / self.resolution
        })
    }

    /// τ_D = T_D/T (any time in s → periods).
    #[must_use]
    pub fn tau(&self, time_s: f64) -> f64 {
        time_s / self.period_s
    }

    /// A stiffness relative to K, κ = k/K (e.g. the hand's stiffness).
    #[must_use]
    pub fn kappa(&self, stiffness: f64) -> f64 {
        stiffness / self.stiffness
    }

    /// ξ = x/Δ (position in ticks).
    #[must_use]
    pub fn xi(&self, position: f64) -> f64 {
        position / self.resolution
    }

    /// ξ̇ = ẋT/Δ (velocity in ticks per period).
    #[must_use]
    pub fn xidot(&self, velocity: f64) -> f64 {
        velocity * self.period_s / self.resolution
    }

    /// ẋ = ξ̇Δ/T (inverse of [`Scale::xidot`]).
    #[must_use]
    pub fn velocity(&self, xidot: f64) -> f64 {
        xidot * self.resolution / self.period_s
    }

    /// ξ̈ = ẍT²/Δ (acceleration in ticks per period²).
    #[must_use]
    pub fn xiddot(&self, acceleration: f64) -> f64 {
        acceleration * self.period_s * self.period_s / self.resolution
    }

    /// A frequency in rad/s → radians per period, ωT.
    #[must_use]
    pub fn omega(&self, rad_per_s: f64) -> f64 {
        rad_per_s * self.period_s
    }
}

/// `num / den`, or `step_by_step()` when the product `den` overflowed or underflowed (then
/// dividing factor by factor keeps the ratio finite and non-zero where it can be).
fn ratio(num: f64, den: f64, step_by_step: impl FnOnce() -> f64) -> f64 {
    if den.is_normal() {
        num / den
    } else {
        step_by_step()
    }
}

/// Amplifier delay of eq. (5): a second-order amplifier of cut-off ω_A and damping ratio δ_A
/// acts, at low frequency, as the pure delay T_A = 2δ_A/ω_A. With ω_A in rad per period the
/// result is in periods; with rad/s, in seconds.
#[must_use]
pub fn amplifier_delay(omega: f64, damping_ratio: f64) -> f64 {
    2.0 * damping_ratio / omega
}

impl PhysicalParams {
    /// The scale (K, T, Δ) of these parameters, unvalidated.
    #[must_use]
    pub fn scale(&self) -> Scale {
        Scale {
            stiffness: self.stiffness,
            period_s: self.period_s,
            resolution: self.resolution,
        }
    }

    /// Validates every field (see the field docs for the ranges).
    ///
    /// # Errors
    /// [`ParamError`] naming the first field out of range.
    pub fn validate(&self) -> Result<Self, ParamError> {
        check_positive("mass", self.mass)?;
        check_non_negative("viscous", self.viscous)?;
        check_non_negative("coulomb", self.coulomb)?;
        check_positive("resolution", self.resolution)?;
        check_positive("period", self.period_s)?;
        check_positive("stiffness", self.stiffness)?;
        check_non_negative("delay", self.delay_s)?;
        Ok(*self)
    }

    /// Table I: μ = m/(K T²), β = b/(K T), σ = c/(K Δ), τ_D = T_D/T.
    ///
    /// # Errors
    /// [`ParamError`] when a field is out of range, or when a dimensionless value overflows /
    /// underflows to a value outside its range (e.g. μ = 0 from an extreme ratio).
    pub fn to_dimensionless(&self) -> Result<Dimensionless, ParamError> {
        self.validate()?;
        let s = self.scale();
        let d = Dimensionless {
            mu: s.mu(self.mass),
            beta: s.beta(self.viscous),
            sigma: s.sigma(self.coulomb),
            tau_d: s.tau(self.delay_s),
        };
        d.validate()
    }

    /// The same device and loop with another stiffness K.
    #[must_use]
    pub fn with_stiffness(&self, stiffness: f64) -> Self {
        Self { stiffness, ..*self }
    }

    /// Physical velocity (m/s or rad/s) → dimensionless ξ̇ = ẋT/Δ (Table I).
    #[must_use]
    pub fn xidot_from_velocity(&self, velocity: f64) -> f64 {
        self.scale().xidot(velocity)
    }

    /// Dimensionless ξ̇ → physical velocity ẋ = ξ̇Δ/T (m/s or rad/s).
    #[must_use]
    pub fn velocity_from_xidot(&self, xidot: f64) -> f64 {
        self.scale().velocity(xidot)
    }

    /// Physical acceleration (m/s² or rad/s²) → dimensionless ξ̈ = ẍT²/Δ.
    #[must_use]
    pub fn xiddot_from_acceleration(&self, acceleration: f64) -> f64 {
        self.scale().xiddot(acceleration)
    }

    /// Unit label of positions: `"m"` or `"rad"`.
    #[must_use]
    pub fn length_unit(&self) -> &'static str {
        if self.rotational {
            "rad"
        } else {
            "m"
        }
    }
}

/// Encoder resolution Δ = 2π/N (rad) of a rotary encoder with `counts_per_rev` counts.
///
/// # Errors
/// [`ParamError`] when `counts_per_rev` is not finite and > 0.
pub fn resolution_from_counts_per_rev(counts_per_rev: f64) -> Result<f64, ParamError> {
    check_positive("counts_per_rev", counts_per_rev)?;
    Ok(core::f64::consts::TAU / counts_per_rev)
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
    fn error_message_names_field_and_range() {
        let p = PhysicalParams {
            mass: -1.0,
            ..phantom()
        };
        let e = p.to_dimensionless().unwrap_err();
        assert_eq!(e.name(), "mass");
        assert_eq!(
            alloc_free_display(&e).as_str(),
            "mass must be finite and > 0 (got -1)"
        );
        let p = PhysicalParams {
            period_s: f64::NAN,
            ..phantom()
        };
        assert!(matches!(
            p.to_dimensionless(),
            Err(ParamError::NotFinite { name: "period", .. })
        ));
    }

    /// Formats into a fixed buffer (no alloc in this crate, even in tests).
    fn alloc_free_display(e: &ParamError) -> Buf {
        use core::fmt::Write;
        let mut b = Buf::default();
        write!(b, "{e}").unwrap();
        b
    }

    struct Buf {
        bytes: [u8; 128],
        len: usize,
    }
    impl Default for Buf {
        fn default() -> Self {
            Self {
                bytes: [0; 128],
                len: 0,
            }
        }
    }
    impl Buf {
        fn as_str(&self) -> &str {
            core::str::from_utf8(&self.bytes[..self.len]).unwrap()
        }
    }
    impl core::fmt::Write for Buf {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            let end = self.len + s.len();
            if end > self.bytes.len() {
                return Err(core::fmt::Error);
            }
            self.bytes[self.len..end].copy_from_slice(s.as_bytes());
            self.len = end;
            Ok(())
        }
    }

    #[test]
    fn round_trip_phantom() {
        let p = phantom();
        let d = p.to_dimensionless().unwrap();
        let q = d
            .to_physical(p.stiffness, p.period_s, p.resolution, false)
            .unwrap();
        assert!((q.mass - p.mass).abs() < 1e-15);
        assert!((q.viscous - p.viscous).abs() < 1e-15);
        assert!((q.coulomb - p.coulomb).abs() < 1e-15);
    }
}
