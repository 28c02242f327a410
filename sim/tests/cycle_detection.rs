//! Cycle detection (`stiffwall_sim::classify`, `Thresholds::cycle_detection`) changes nothing
//! but the time: the Fig. 6 and Fig. 7 panels at 5×10⁴ periods classify point by point
//! identically with and without it (every field of every `MapPoint`, bit for bit), and random
//! points that end by cycle detection give the brute-force outcome.
//!
//! The panel test runs ~12 k points twice: release build only
//! (`cargo test --release -p stiffwall-sim --test cycle_detection`).

use proptest::prelude::*;
use stiffwall_sim::classify::{Outcome, Thresholds};
use stiffwall_sim::map::{run_with, simulate_point_th, Axis, MapSpec, RunOptions};
use stiffwall_sim::{History, Params};

fn panel(tau_d: f64, xidot0: f64, beta: Axis, sigma: Axis) -> MapSpec {
    MapSpec {
        mu: 100.0,
        tau_d,
        xidot0,
        beta,
        sigma,
        periods: 50_000,
        history: History::HoldInitial,
        damping: 0.0,
    }
}

/// The same outcome field by field (bits of the f64s), the cycle report apart.
fn same(a: &Outcome, b: &Outcome) -> bool {
    a.class == b.class
        && a.periods_run == b.periods_run
        && a.h0.to_bits() == b.h0.to_bits()
        && a.h_end.to_bits() == b.h_end.to_bits()
        && a.h_max.to_bits() == b.h_max.to_bits()
        && a.tail_amplitude.to_bits() == b.tail_amplitude.to_bits()
        && a.tail_speed.to_bits() == b.tail_speed.to_bits()
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "2 x 12 k points x 5e4 periods: cargo test --release"
)]
fn fig6_fig7_panels_identical_with_and_without_cycle_detection() {
    let ax = |lo, hi, n| Axis { lo, hi, n };
    let grids = [
        // Fig. 6 on the paper's grid (the benchmark set).
        ("fig6 paper grid", 0.0, ax(0.0, 1.2, 21), ax(0.0, 2.0, 34)),
        // Fig. 6 as drawn in docs/figures/fig6-tau0.png.
        ("fig6 docs grid", 0.0, ax(0.0, 1.0, 34), ax(0.0, 2.0, 21)),
        // Fig. 7 as drawn in docs/figures/fig7-tau1.25.png.
        ("fig7 docs grid", 1.25, ax(0.0, 3.0, 34), ax(0.0, 2.0, 21)),
    ];
    let mut by_cycle = 0;
    let mut by_exact = 0;
    for (name, tau_d, beta, sigma) in grids {
        for v in [1.0, 5.0, 10.0, 20.0] {
            let spec = panel(tau_d, v, beta, sigma);
            let idx: Vec<usize> = (0..spec.len()).collect();
            let on = run_with(&spec, &idx, &|| {}, RunOptions::default());
            let off = run_with(
                &spec,
                &idx,
                &|| {},
                RunOptions {
                    cycle_detection: false,
                },
            );
            assert_eq!(off.cycle_points(), 0);
            assert_eq!(on.points.len(), off.points.len());
            for (a, b) in on.points.iter().zip(&off.points) {
                // MapPoint's derived PartialEq compares the f64s by value; bits too, for NaN.
                assert_eq!(a, b, "{name}, xidot0 {v}");
                for (x, y) in [(a.h0, b.h0), (a.h_end, b.h_end)] {
                    assert_eq!(x.to_bits(), y.to_bits(), "{name}, xidot0 {v}: {a:?}");
                }
                assert_eq!(
                    a.tail_amplitude.to_bits(),
                    b.tail_amplitude.to_bits(),
                    "{name}, xidot0 {v}: {a:?}"
                );
            }
            eprintln!(
                "{name}, xidot0 {v}: {} of {} points ended by cycle detection ({} exact)",
                on.cycle_points(),
                on.points.len(),
                on.exact_cycle_points()
            );
            by_cycle += on.cycle_points();
            by_exact += on.exact_cycle_points();
        }
    }
    // The detection does fire on these panels (on most persistent points), both kinds.
    assert!(
        by_cycle > 1000,
        "{by_cycle} points ended by cycle detection"
    );
    assert!(
        by_exact > 500,
        "{by_exact} points ended by exact repetition"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(debug_assertions) { 16 } else { 128 }))]

    /// A random point (β, σ, ξ̇₀, τ_D, history, horizon) that ends by cycle detection (cases
    /// where it does not are rejected) classifies the same as by brute force, every field of
    /// the outcome bit for bit. The region is that of the persistent limit cycles (region B:
    /// β > ½, σ < ½, and the delayed B of Fig. 7), with decaying and growing points mixed in.
    #[test]
    fn points_ended_by_cycle_detection_classify_as_brute_force(
        beta in 0.4f64..3.0,
        sigma in 0.0f64..0.6,
        xidot0 in 0.2f64..20.0,
        tau_d in prop_oneof![Just(0.0), Just(0.0), 0.0f64..2.0],
        zero_history in any::<bool>(),
        periods in if cfg!(debug_assertions) { 500u64..3_000 } else { 1_000u64..30_000 },
    ) {
        let history = if zero_history { History::Zero } else { History::HoldInitial };
        let on = Thresholds::default();
        let off = Thresholds { cycle_detection: false, ..Thresholds::default() };
        let p = Params { mu: 100.0, beta, sigma, tau_d };
        let a = simulate_point_th(p, xidot0, periods, history, &on);
        prop_assume!(a.cycle.is_some());
        let b = simulate_point_th(p, xidot0, periods, history, &off);
        prop_assert!(b.cycle.is_none());
        prop_assert!(same(&a, &b), "with {a:?}\nwithout {b:?}");
    }
}

/// Persistent limit cycles that repeat bit for bit end by cycle detection at every horizon
/// relation (cycle found before or inside the tail window, horizon a multiple of the period or
/// not), and the outcome matches brute force at each.
#[test]
fn limit_cycles_end_by_detection_at_every_horizon() {
    let off = Thresholds {
        cycle_detection: false,
        ..Thresholds::default()
    };
    let cases: [(f64, f64, f64, &[u64]); 3] = [
        (
            2.5,
            0.3,
            1.25,
            &[4_096, 4_097, 5_000, 7_777, 20_000, 50_000, 50_001],
        ),
        (0.45, 0.2, 0.0, &[50_000, 49_999, 60_007]),
        (1.5, 0.1, 0.5, &[50_000, 50_011]),
    ];
    let mut ended = 0;
    for (beta, sigma, tau_d, horizons) in cases {
        for &periods in horizons {
            let run = |th: &Thresholds| {
                let p = Params {
                    mu: 100.0,
                    beta,
                    sigma,
                    tau_d,
                };
                simulate_point_th(p, 5.0, periods, History::HoldInitial, th)
            };
            let (a, b) = (run(&Thresholds::default()), run(&off));
            assert!(
                same(&a, &b),
                "({beta},{sigma},{tau_d}) {periods}: {a:?} vs {b:?}"
            );
            ended += usize::from(a.cycle.is_some());
        }
    }
    assert_eq!(ended, 12, "runs ended by cycle detection");
}

/// With the virtual damper (the state then holds the previous count too) and through the
/// delayed solver, detection on and off classify alike on a small grid of limit cycles.
#[test]
fn damped_and_delayed_solvers_classify_alike() {
    use stiffwall_sim::classify::classify;
    use stiffwall_sim::exact::{Full, NoDelay};
    use stiffwall_sim::{Motion, Params};
    let off = Thresholds {
        cycle_detection: false,
        ..Thresholds::default()
    };
    let on = Thresholds::default();
    let periods = if cfg!(debug_assertions) {
        3_000
    } else {
        30_000
    };
    let mut ended = 0;
    for beta_v in [0.0, 0.05, 0.3, 1.0] {
        for beta in [0.3, 0.55, 0.8, 1.1] {
            for sigma in [0.05, 0.2, 0.4] {
                for tau_d in [0.0, 0.75] {
                    let p = Params {
                        mu: 100.0,
                        beta,
                        sigma,
                        tau_d,
                    };
                    let init = Motion { x: 0.0, v: 5.0 };
                    let (a, b) = if tau_d == 0.0 {
                        let s = NoDelay::new(p, init, History::HoldInitial)
                            .unwrap()
                            .with_beta_v(beta_v)
                            .unwrap();
                        (
                            classify(&mut s.clone(), periods, &on),
                            classify(&mut s.clone(), periods, &off),
                        )
                    } else {
                        let s = Full::new(p, init, History::HoldInitial)
                            .unwrap()
                            .with_beta_v(beta_v)
                            .unwrap();
                        (
                            classify(&mut s.clone(), periods, &on),
                            classify(&mut s.clone(), periods, &off),
                        )
                    };
                    assert!(
                        same(&a, &b),
                        "{beta_v} {beta} {sigma} {tau_d}: {a:?} vs {b:?}"
                    );
                    ended += usize::from(a.cycle.is_some());
                }
            }
        }
    }
    assert!(ended > 10, "{ended} runs ended by cycle detection");
}

/// Maps with the virtual damper (`MapSpec::damping`, the damper's previous count in the
/// state): Fig. 6 panels on the paper's grid classify identically with and without detection.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "4 x 714 points x 5e4 periods twice: cargo test --release"
)]
fn damped_map_panels_identical_with_and_without_cycle_detection() {
    let mut by_cycle = 0;
    for (damping, v) in [(0.3, 5.0), (2.0, 5.0), (0.3, 20.0), (2.0, 1.0)] {
        let spec = MapSpec {
            damping,
            ..panel(
                0.0,
                v,
                Axis {
                    lo: 0.0,
                    hi: 1.2,
                    n: 21,
                },
                Axis {
                    lo: 0.0,
                    hi: 2.0,
                    n: 34,
                },
            )
        };
        let idx: Vec<usize> = (0..spec.len()).collect();
        let on = run_with(&spec, &idx, &|| {}, RunOptions::default());
        let off = run_with(
            &spec,
            &idx,
            &|| {},
            RunOptions {
                cycle_detection: false,
            },
        );
        assert_eq!(on.points, off.points, "damping {damping}, xidot0 {v}");
        by_cycle += on.cycle_points();
    }
    assert!(by_cycle > 100, "{by_cycle} points ended by cycle detection");
}
