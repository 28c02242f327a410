//! Storage function and energy terms of Sec. VI (dimensionless).
//!
//! Units: energies are in units of K·Δ² (force K·Δ times length Δ); positions `xi` in encoder
//! ticks, velocities `xidot` in ticks per sampling period.

/// Quantization error ρ(ξ) = ξ − ⌊ξ⌋ of eq. (32), in [0, 1).
#[must_use]
pub fn quantization_error(xi: f64) -> f64 {
    let r = xi - libm::floor(xi);
    // Guard the rounding case where xi is a tiny negative number and xi - floor(xi) == 1.0.
    if r >= 1.0 {
        0.0
    } else {
        r
    }
}

/// Storage function H_T(ξ, ξ̇) of eq. (35): ½μξ̇² + ½ξ² + ½(ρ − ρ²).
#[must_use]
pub fn storage_energy(mu: f64, xi: f64, xidot: f64) -> f64 {
    let rho = quantization_error(xi);
    0.5 * mu * xidot * xidot + 0.5 * xi * xi + 0.5 * (rho - rho * rho)
}
