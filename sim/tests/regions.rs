//! Simulated classes against the analytic regions of Fig. 3 (τ_D = 0) and Fig. 5 (τ_D = 1.25)
//! on a coarse grid (μ = 100, ξ₀ = 0, 2×10⁴ periods). The full 714-point × 5×10⁴-period maps
//! are `hostctl map` (docs/figures/). Their speed (the Fig. 6 set, ≤ 0.5 s; the base scene,
//! ≥ 20 M periods/s on one core) is a benchmark, not a test: `cargo xtask bench`
//! (`sim/examples/bench_table.rs`, docs/BENCHMARKS-sim.md's headline).

use stiffwall_sim::classify::Class;
use stiffwall_sim::map::{region_no_delay, simulate_point};

const PERIODS: u64 = 20_000;

fn grid() -> impl Iterator<Item = (f64, f64)> {
    let betas = [0.0, 0.05, 0.15, 0.25, 0.35, 0.45, 0.55, 0.7, 0.9, 1.0];
    let sigmas = [0.0, 0.1, 0.25, 0.4, 0.6, 0.8, 1.0, 1.3, 1.7, 2.0];
    betas
        .into_iter()
        .flat_map(move |b| sigmas.into_iter().map(move |s| (b, s)))
}

#[test]
fn no_delay_classes_agree_with_fig3_regions() {
    let mut report = Vec::new();
    for v in [1.0, 5.0, 10.0, 20.0] {
        for (b, s) in grid() {
            let o = simulate_point(100.0, b, s, 0.0, v, PERIODS);
            let r = region_no_delay(b, s, v);
            // Same region as stiffwall-core's classifier (away from the critical line, where
            // rounding decides).
            let core = stiffwall_core::regions::classify(b, s, Some(v)).unwrap();
            if (s - 0.5 - v * (0.5 - b)).abs() > 1e-9 {
                assert_eq!(format!("{core:?}"), r.to_string(), "({b},{s}) xidot0 {v}");
            }
            match r {
                // A: globally stable, motion stops.
                'A' => assert!(o.class.decays(), "A ({b},{s}) xidot0 {v}: {o:?}"),
                // B: persistent oscillations; where sigma > 0 they stay below one tick.
                'B' => {
                    assert_eq!(o.class, Class::Persistent, "B ({b},{s}) xidot0 {v}: {o:?}");
                    if s > 0.0 {
                        assert!(o.tail_amplitude < 1.0, "B ({b},{s}) xidot0 {v}: {o:?}");
                    }
                }
                // C: never settles; grows away from the B/C border.
                'C' => {
                    assert!(!o.class.decays(), "C ({b},{s}) xidot0 {v}: {o:?}");
                    if b <= 0.25 && s <= 0.25 && v >= 5.0 {
                        assert_eq!(o.class, Class::Growing, "C ({b},{s}) xidot0 {v}: {o:?}");
                    }
                }
                // E: above the critical line of (12) for this velocity: decays.
                'E' => assert!(o.class.decays(), "E ({b},{s}) xidot0 {v}: {o:?}"),
                _ => {}
            }
            report.push((v, b, s, r, o.class));
        }
    }
    // Region D may grow: at least one D point grows for every velocity >= 5.
    for v in [5.0, 10.0, 20.0] {
        assert!(report
            .iter()
            .any(|&(vv, _, _, r, c)| vv == v && r == 'D' && c == Class::Growing));
    }
}

#[test]
fn below_one_tick_claim_fails_without_coulomb_friction() {
    // Region B with sigma = 0 (viscous friction only): the limit cycle exceeds one tick.
    let o = simulate_point(100.0, 0.515, 0.0, 0.0, 1.0, 50_000);
    assert_eq!(o.class, Class::Persistent);
    assert!(o.tail_amplitude > 1.0, "{o:?}");
}

#[test]
fn delay_1_25_grows_everywhere_below_beta_1_2_for_fast_starts() {
    for v in [5.0, 10.0, 20.0] {
        for b in [0.0, 0.3, 0.6, 0.9, 1.2] {
            for s in [0.0, 0.5, 1.0, 1.5, 2.0] {
                let o = simulate_point(100.0, b, s, 1.25, v, PERIODS);
                assert_eq!(o.class, Class::Growing, "({b},{s}) xidot0 {v}: {o:?}");
            }
        }
    }
    // Far right of Fig. 7 (region F1/F2 of stiffwall-core, beta > 1/2 + tau_D, sigma > 1/2):
    // decays; region B (sigma < 1/2) persists below one tick.
    for v in [1.0, 5.0] {
        let r = stiffwall_core::regions::classify_delayed(3.0, 2.0, 1.25, Some(v), Some(v / 10.0))
            .unwrap();
        assert!(matches!(
            r,
            stiffwall_core::Region::F1 | stiffwall_core::Region::F2
        ));
        let o = simulate_point(100.0, 3.0, 2.0, 1.25, v, PERIODS);
        assert!(o.class.decays(), "xidot0 {v}: {o:?}");
        let o = simulate_point(100.0, 2.5, 0.3, 1.25, v, PERIODS);
        assert_eq!(o.class, Class::Persistent, "xidot0 {v}: {o:?}");
        assert!(o.tail_amplitude < 1.0, "xidot0 {v}: {o:?}");
    }
}
