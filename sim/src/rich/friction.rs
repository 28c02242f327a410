//! Friction of the motor side: the Stribeck curve, the stick rule, and the closed-form step of a
//! rigid mass with a static/dynamic friction switch.
//!
//! Units: SI (N, m/s, kg, s) or the rotary equivalents.
//!
//! **Stick rule (Karnopp-style, with a zero-width velocity window located as an event).**
//! Karnopp's model sticks the mass while |v| is inside a small window and the net non-friction
//! force f_ext is at most the breakaway force F_s. Here the window has zero width: a moving mass
//! slides with friction −F(|v|)·sgn(v) − b·v, where
//! F(|v|) = c + (F_s − c)·exp(−(v/v_s)²) (v_s = 0: F = c); the instant v reaches zero is located
//! (analytically in [`advance_switch`], by the event locator of [`crate::dopri`] otherwise)
//! and the rule picks the next mode: **stuck** while |f_ext| ≤ F_s (the friction then balances
//! f_ext exactly and v stays 0), otherwise **sliding** in the direction of f_ext. A stuck mass
//! breaks away when |f_ext| exceeds F_s (an event too). F_s ≥ c, so a mass that breaks away
//! accelerates (f_ext − F(0⁺)·sgn(f_ext) has the sign of f_ext): no Zeno chattering.
//!
//! Invariants: m > 0, b ≥ 0, 0 ≤ c ≤ F_s; [`advance_switch`] performs at most two closed-form
//! sub-steps, never loops, never allocates.

use crate::math::{e1, g, log1p_over};
use crate::plant::{Body, Motion};

/// Sliding friction magnitude at speed `speed` (≥ 0): c + (F_s − c)·exp(−(v/v_s)²).
#[inline]
#[must_use]
pub fn sliding_n(coulomb_n: f64, static_n: f64, stribeck_m_per_s: f64, speed: f64) -> f64 {
    if stribeck_m_per_s > 0.0 && static_n > coulomb_n {
        let r = speed / stribeck_m_per_s;
        coulomb_n + (static_n - coulomb_n) * libm::exp(-r * r)
    } else {
        coulomb_n
    }
}

/// The stick rule at zero velocity: `0.0` (stuck) when |f_ext| ≤ F_s, otherwise the direction
/// ±1 of the slide.
#[inline]
#[must_use]
pub fn stick_rule(f_ext: f64, static_n: f64) -> f64 {
    if f_ext.abs() <= static_n {
        0.0
    } else if f_ext > 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// Free motion without a zero crossing: (Δx, v₁) for v₀, acceleration term `acc`, duration t.
#[inline]
fn free(body: &Body, v0: f64, acc: f64, t: f64) -> (f64, f64) {
    let x = body.rate * t;
    let e1x = e1(x);
    let p1 = t * e1x;
    let p2 = t * t * g(x);
    let e = 1.0 - x * e1x;
    (v0 * p1 + acc * p2, v0 * e + acc * p1)
}

/// Advances a rigid mass (m, b, dynamic c in `body`) with breakaway force `static_n` ≥ c by `t`
/// under the constant force `f`, exactly (closed form, the rule of the module header with
/// v_s = 0). Returns whether the mass is stuck at the end.
pub fn advance_switch(body: &Body, static_n: f64, m: &mut Motion, f: f64, t: f64) -> bool {
    let mut rem = t;
    let c = body.coulomb;
    if m.v != 0.0 {
        let s = if m.v > 0.0 { 1.0 } else { -1.0 };
        let a = f - c * s;
        let acc = a * body.inv_mass;
        let (dx, v1) = free(body, m.v, acc, rem);
        if v1 * s > 0.0 || a * s >= 0.0 {
            m.x += dx;
            m.v = v1;
            return false;
        }
        // v reaches zero at t* = (m|v0|/|a|)·ln(1 + y)/y, y = k·m|v0|/|a|.
        let t0 = m.v.abs() / acc.abs();
        let tc = (t0 * log1p_over(body.rate * t0)).min(rem);
        let (dx, _) = free(body, m.v, acc, tc);
        m.x += dx;
        m.v = 0.0;
        rem -= tc;
    }
    let s = stick_rule(f, static_n);
    if s == 0.0 {
        return true;
    }
    if rem <= 0.0 {
        return false;
    }
    let acc = (f - c * s) * body.inv_mass;
    let (dx, v1) = free(body, 0.0, acc, rem);
    m.x += dx;
    m.v = v1;
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equals_the_paper_plant_without_stiction() {
        let body = Body::new(0.3, 0.02, 0.05);
        let mut a = Motion { x: 0.0, v: 0.2 };
        let mut b = a;
        for i in 0..200 {
            let f = 0.3 * libm::sin(f64::from(i) * 0.37);
            advance_switch(&body, 0.05, &mut a, f, 1e-3);
            crate::plant::advance::<false>(&body, &mut b, f, 1e-3);
            assert_eq!(a, b);
        }
    }

    #[test]
    fn holds_below_breakaway_and_slides_with_dynamic_friction_above() {
        let body = Body::new(1.0, 0.0, 0.5);
        let mut m = Motion::default();
        assert!(advance_switch(&body, 0.8, &mut m, 0.79, 1.0));
        assert_eq!(m, Motion::default());
        assert!(!advance_switch(&body, 0.8, &mut m, 0.81, 1.0));
        // Slides with c = 0.5: a = 0.31.
        assert!((m.v - 0.31).abs() < 1e-15);
        assert!((m.x - 0.155).abs() < 1e-15);
    }

    #[test]
    fn stribeck_curve_limits() {
        assert_eq!(sliding_n(1.0, 2.0, 0.0, 0.1), 1.0);
        assert_eq!(sliding_n(1.0, 2.0, 0.1, 0.0), 2.0);
        assert!((sliding_n(1.0, 2.0, 0.1, 1.0) - 1.0).abs() < 1e-40);
    }
}
