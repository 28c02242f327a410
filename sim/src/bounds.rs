//! Per-interval bounds on the generated energy E_g (29) of Sec. VI, as published and as tight.
//!
//! Units: dimensionless; displacements in ticks, energies in K·Δ². For an interval [l, τ₁] with
//! l = h + τ_D, τ₁ ∈ [l, l + 1], constant force φ_A = −⌊ξ(h)⌋ − ½, let d = ξ(τ₁) − ξ(l) and
//! d₀ = ξ(l) − ξ(h) (d₀ = 0 without delay). Then
//!
//!   E_g = ∫_{ξ(l)}^{ξ(τ₁)} (⌊ξ⌋ − ⌊ξ(h)⌋) dξ.
//!
//! The formulas live in `stiffwall_core::energy`; this module names them in the (d, d₀) form
//! the solvers' tests use:
//! - [`paper_47`]: ½d² + ½|d|                       (eq. (47), τ_D = 0)
//! - [`paper_58`]: ½d² + (½ + |d₀|)|d|              (eq. (58), with τ_D|ξ̇(η)| = |d₀|)
//! - [`tight`]:    ∫_{s·d₀}^{s·d₀+|d|} ⌈u⌉ du, s = sgn d — the least upper bound given (d, d₀);
//!   (47) is short of it by up to ⅛ (erratum, see `docs/model-notes-sim.md`: the step
//!   (45)→(46) uses |⌊ξ₁⌋ − ⌊ξ₀⌋| ≤ |ξ₁ − ξ₀|, false).
//!
//! Invariant: all functions are pure and finite for finite inputs (NaN otherwise).

use stiffwall_core::energy;
pub use stiffwall_core::energy::ceil_integral;

/// Generated energy over an interval of constant force: φ_A·d + H_e(ξ₁) − H_e(ξ_l).
#[must_use]
pub fn generated(phi_a: f64, xi_l: f64, xi_1: f64) -> f64 {
    phi_a * (xi_1 - xi_l) + energy::spring_energy(xi_1) - energy::spring_energy(xi_l)
}

/// The paper's bound (47), [`energy::generation_upper_bound`].
#[must_use]
pub fn paper_47(d: f64) -> f64 {
    energy::generation_upper_bound(d).unwrap_or(f64::NAN)
}

/// The paper's bound (58), [`energy::generation_upper_bound_delayed`], with the delay term
/// τ_D|ξ̇(η)| (57) given as the displacement |d₀| = |ξ(l) − ξ(h)|.
#[must_use]
pub fn paper_58(d: f64, d0: f64) -> f64 {
    energy::generation_upper_bound_delayed(d, 1.0, d0).unwrap_or(f64::NAN)
}

/// The tight bound: sup of E_g over all positions with the given d and d₀
/// ([`energy::generation_tight_bound`]).
#[must_use]
pub fn tight(d: f64, d0: f64) -> f64 {
    energy::generation_tight_bound(d, d0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::floor_fast;

    #[test]
    fn tight_equals_paper_at_integer_displacements_without_delay() {
        for n in 0..6 {
            let d = f64::from(n);
            assert!((tight(d, 0.0) - paper_47(d)).abs() < 1e-12);
            assert!((tight(-d, 0.0) - paper_47(d)).abs() < 1e-12);
        }
        // Largest gap: 1/8 at half-integer displacements.
        assert!((tight(0.5, 0.0) - paper_47(0.5) - 0.125).abs() < 1e-12);
    }

    #[test]
    fn counterexample_to_47() {
        // ξ(h) just below a boundary, moving half a tick: E_g ≈ ½ > (47) = 3/8.
        let xh = 1.0 - 1e-9;
        let x1 = xh + 0.5;
        let eg = generated(-floor_fast(xh) - 0.5, xh, x1);
        assert!(eg > paper_47(0.5) + 0.12);
        assert!(eg <= tight(0.5, 0.0));
    }
}
