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
use stiffwall_sim::History;

fn panel(tau_d: f64, xidot0: f64, beta: Axis, sigma: Axis) -> MapSpec {
    MapSpec {
        mu: 100.0,
        tau_d,
        xidot0,
        beta,
        sigma,
        periods: 50_000,
        history: History::HoldInitial,
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
                "{name}, xidot0 {v}: {} of {} points ended by cycle detection",
                on.cycle_points(),
                on.points.len()
            );
            by_cycle += on.cycle_points();
        }
    }
    // The detection does fire on these panels (most persistent points are exact limit cycles).
    assert!(by_cycle > 500, "{by_cycle} points ended by cycle detection");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(debug_assertions) { 16 } else { 128 }))]

    /// A random point (β, σ, ξ̇₀, τ_D, history, horizon) classifies the same with cycle
    /// detection as by brute force; the cases that actually end by cycle detection are the
    /// point of the test, so the region and horizons are those of persistent limit cycles
    /// (σ > 0, β in the B/C strip) with some decaying and growing points mixed in.
    #[test]
    fn points_ended_by_cycle_detection_classify_as_brute_force(
        beta in 0.0f64..1.6,
        sigma in 0.0f64..1.0,
        xidot0 in 0.2f64..20.0,
        tau_d in prop_oneof![Just(0.0), Just(0.0), 0.0f64..2.5],
        zero_history in any::<bool>(),
        periods in 1u64..if cfg!(debug_assertions) { 3_000 } else { 30_000 },
    ) {
        let history = if zero_history { History::Zero } else { History::HoldInitial };
        let on = Thresholds::default();
        let off = Thresholds { cycle_detection: false, ..Thresholds::default() };
        let a = simulate_point_th(100.0, beta, sigma, tau_d, xidot0, periods, history, &on);
        let b = simulate_point_th(100.0, beta, sigma, tau_d, xidot0, periods, history, &off);
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
                simulate_point_th(
                    100.0,
                    beta,
                    sigma,
                    tau_d,
                    5.0,
                    periods,
                    History::HoldInitial,
                    th,
                )
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
