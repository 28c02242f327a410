//! Per-interval bounds on the generated energy E_g (29) of Sec. VI, as published and as tight.
//!
//! Units: dimensionless; displacements in ticks, energies in K·Δ². For an interval [l, τ₁] with
//! l = h + τ_D, τ₁ ∈ [l, l + 1], constant force φ_A = −⌊ξ(h)⌋ − ½, let d = ξ(τ₁) − ξ(l) and
//! d₀ = ξ(l) − ξ(h) (d₀ = 0 without delay). Then
//!
//!   E_g = ∫_{ξ(l)}^{ξ(τ₁)} (⌊ξ⌋ − ⌊ξ(h)⌋) dξ.
//!
//! - [`paper_47`]: ½d² + ½|d|                       (eq. (47), τ_D = 0)
//! - [`paper_58`]: ½d² + (½ + |d₀|)|d|              (eq. (58), with τ_D|ξ̇(η)| = |d₀|)
//! - [`tight`]:    ∫_{s·d₀}^{s·d₀+|d|} ⌈u⌉ du, s = sgn d — the least upper bound given (d, d₀),
//!   from ⌊a⌋ − ⌊b⌋ ≤ ⌈a − b⌉. For d₀ = 0 it is c|d| − c(c−1)/2 with c = ⌈|d|⌉, i.e.
//!   ½d² + ½|d| + ½δ(1−δ) with δ = frac|d|: (47) is short by up to ⅛ (erratum, see
//!   `docs/model-notes-sim.md`: the step (45)→(46) uses |⌊ξ₁⌋ − ⌊ξ₀⌋| ≤ |ξ₁ − ξ₀|, false).
//!
//! Invariant: all functions are pure and finite for finite inputs.

use crate::math::floor_fast;

/// Generated energy over an interval of constant force: φ_A·d + H_e(ξ₁) − H_e(ξ_l).
#[must_use]
pub fn generated(phi_a: f64, xi_l: f64, xi_1: f64) -> f64 {
    phi_a * (xi_1 - xi_l) + crate::exact::potential(xi_1) - crate::exact::potential(xi_l)
}

/// The paper's bound (47).
#[must_use]
pub fn paper_47(d: f64) -> f64 {
    0.5 * d * d + 0.5 * d.abs()
}

/// The paper's bound (58) with the delay term |ξ(l) − ξ(h)| = τ_D|ξ̇(η)| (57).
#[must_use]
pub fn paper_58(d: f64, d0: f64) -> f64 {
    0.5 * d * d + (0.5 + d0.abs()) * d.abs()
}

/// ∫₀ᵘ ⌈w⌉ dw = u²/2 + u − ½⌊u⌋ − ½ρ(u)², valid for every real u.
#[must_use]
pub fn ceil_integral(u: f64) -> f64 {
    let fl = floor_fast(u);
    let r = u - fl;
    0.5 * u * u + u - 0.5 * fl - 0.5 * r * r
}

/// The tight bound: sup of E_g over all positions with the given d and d₀.
#[must_use]
pub fn tight(d: f64, d0: f64) -> f64 {
    let a = if d >= 0.0 { d0 } else { -d0 };
    ceil_integral(a + d.abs()) - ceil_integral(a)
}

#[cfg(test)]
mod tests {
    use super::*;

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
