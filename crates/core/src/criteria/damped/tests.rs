//! Tests of the spring + damper boundary: B = 0 identity, closed forms, a direct simulation of
//! the sampled linear loop (independent discretisation), bad input.

use super::*;
use crate::criteria::{gil_avello_rubio_stable, k_max_gil_avello_rubio, k_max_hulin};
use proptest::prelude::*;

fn dev(b: f64, td: f64) -> PhysicalParams {
    PhysicalParams {
        mass: 0.072,
        viscous: b,
        coulomb: 0.038,
        resolution: 29.1e-6,
        period_s: 1e-3,
        stiffness: 1.0,
        delay_s: td,
        rotational: false,
    }
}

/// Steps m·v̇ = −b·v + u exactly over each period (ZOH), u_k = −K·x_k − B·(x_k − x_{k−1})/T
/// applied `d` whole periods later; returns max |x| over the last 2000 steps divided by max |x|
/// over the first 2000 (after an initial offset x_0 = 1e-3).
fn simulate_growth(p: &PhysicalParams, damping: f64, d: usize, steps: usize) -> f64 {
    let (m, b, t) = (p.mass, p.viscous, p.period_s);
    let e = (-b * t / m).exp();
    // Exact ZOH discretisation written from the ODE's solution (not from `numerator`).
    let (xv, xu, vv, vu) = (
        m / b * (1.0 - e),
        (t - m / b * (1.0 - e)) / b,
        e,
        (1.0 - e) / b,
    );
    let mut queue = [0.0_f64; 8];
    let (mut x, mut v, mut x_prev) = (1e-3_f64, 0.0_f64, 1e-3_f64);
    let (mut first, mut last) = (0.0_f64, 0.0_f64);
    for k in 0..steps {
        let u_now = -p.stiffness * x - damping * (x - x_prev) / t;
        queue[k % 8] = u_now;
        let u = if k >= d { queue[(k - d) % 8] } else { 0.0 };
        x_prev = x;
        let x_next = x + xv * v + xu * u;
        v = vv * v + vu * u;
        x = x_next;
        if x.is_nan() || x.abs() > 1e100 {
            return f64::INFINITY; // diverged (also catches NaN)
        }
        if k < 2000 {
            first = first.max(x.abs());
        }
        if k + 2000 >= steps {
            last = last.max(x.abs());
        }
    }
    last / first
}

#[test]
fn boundary_matches_direct_simulation() {
    for b in [0.5, 2.0] {
        for damping in [0.2, 1.0, 5.0, 20.0] {
            for d in 0..=2_usize {
                #[allow(clippy::cast_precision_loss)]
                let p = dev(b, d as f64 * 1e-3);
                let k = k_max_exact_linear(&p, damping).unwrap();
                assert!(k > 0.0, "b={b} B={damping} d={d}");
                assert!(exact_linear_stable(&p.with_stiffness(k * 0.999), damping).unwrap());
                assert!(!exact_linear_stable(&p.with_stiffness(k * 1.001), damping).unwrap());
                let inside = simulate_growth(&p.with_stiffness(k * 0.9), damping, d, 200_000);
                let outside = simulate_growth(&p.with_stiffness(k * 1.1), damping, d, 200_000);
                assert!(
                    inside < 1.0,
                    "b={b} B={damping} d={d}: inside grows {inside}"
                );
                assert!(
                    outside > 1.0,
                    "b={b} B={damping} d={d}: outside decays {outside}"
                );
            }
        }
    }
}

#[test]
fn small_b_approximation_agrees() {
    // b, B ≪ m/T = 72 N·s/m: relative error below 5 % (the spring-only Hulin tolerance of
    // the B = 0 tests), and it shrinks with B.
    for td in [0.0, 0.5e-3, 1e-3, 2e-3] {
        for damping in [0.01, 0.05, 0.2, 0.5] {
            let p = dev(0.005, td);
            let k = k_max_exact_linear(&p, damping).unwrap();
            let approx = k_max_small_b(&p, damping).unwrap();
            assert!(
                (k - approx).abs() < 0.05 * approx,
                "td={td} B={damping}: {k} vs {approx}"
            );
        }
    }
    let p = dev(0.005, 0.0);
    assert_eq!(k_max_small_b(&p, 0.0).unwrap(), k_max_hulin(&p).unwrap());
}

#[test]
fn damper_raises_then_lowers_k_max() {
    // Not monotone: a moderate damper raises K_max, a damper of several m/T destroys it.
    let p = dev(0.5, 1e-3);
    let k0 = k_max_exact_linear(&p, 0.0).unwrap();
    let f = frontier(&p, 4.0 * 72.0).unwrap();
    assert!(f.k_max_opt > 3.0 * k0, "{} vs {k0}", f.k_max_opt);
    let last = f.k_max[FRONTIER_POINTS - 1];
    assert!(last < f.k_max_opt, "{last}");
    assert!(f.b_opt_n_s_per_m > 0.0 && f.b_opt_n_s_per_m < 4.0 * 72.0);
    assert_eq!(f.k_max[0].to_bits(), k0.to_bits());
}

#[test]
fn bad_damping_is_refused() {
    let p = dev(0.5, 0.0);
    for bad in [-1.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let errs = [
            k_max_exact_linear(&p, bad).unwrap_err(),
            exact_linear_stable(&p, bad).unwrap_err(),
            k_max_colgate_schenkel_damped(&p, bad).unwrap_err(),
            k_max_small_b(&p, bad).unwrap_err(),
            frontier(&p, bad).unwrap_err(),
        ];
        for e in errs {
            assert_eq!(e.name(), "damping");
            assert_eq!(e.allowed(), "finite and >= 0");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn zero_damping_is_bit_for_bit(
        m in 0.001_f64..10.0, b in 0.0_f64..5.0, t in 1e-4_f64..1e-2, tau in 0.0_f64..4.0,
    ) {
        let p = PhysicalParams { mass: m, viscous: b, coulomb: 0.0, resolution: 1e-5,
            period_s: t, stiffness: 1.0, delay_s: tau * t, rotational: false };
        let k = k_max_exact_linear(&p, 0.0).unwrap();
        prop_assert_eq!(k.to_bits(), k_max_gil_avello_rubio(&p).unwrap().to_bits());
        // The damped polynomial at B → 0+ agrees with the spring-only test away from the edge.
        if b * t / m > 1e-6 {
            let tiny = 1e-12 * m / t;
            prop_assert!(exact_linear_stable(&p.with_stiffness(k * 0.99), tiny).unwrap());
            prop_assert!(!exact_linear_stable(&p.with_stiffness(k * 1.01), tiny).unwrap());
            prop_assert_eq!(
                exact_linear_stable(&p.with_stiffness(k), 0.0).unwrap(),
                gil_avello_rubio_stable(&p.with_stiffness(k)).unwrap()
            );
        }
    }

    #[test]
    fn passivity_implies_stability(b in 0.01_f64..5.0, frac in 0.0_f64..1.0) {
        // Colgate–Schenkel's passive K (no delay: passivity ignores delay) is at most the exact
        // stable boundary of the same loop.
        let p = dev(b, 0.0);
        let damping = frac * b;
        let cs = k_max_colgate_schenkel_damped(&p, damping).unwrap();
        let exact = k_max_exact_linear(&p, damping).unwrap();
        prop_assert!(cs <= exact * (1.0 + 1e-9), "{} > {}", cs, exact);
    }
}
