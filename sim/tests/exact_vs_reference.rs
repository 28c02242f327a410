//! The exact solver against Dormand–Prince 5(4) at tight tolerance (state at every sample
//! instant), and its energy balance (26) over 5×10⁴ periods.

use stiffwall_sim::exact::{dispatch, ExactSim, History, Visitor};
use stiffwall_sim::reference::{Method, RefModel, RefSim};
use stiffwall_sim::{Effects, Motion, Params};

struct Collect(u64);
impl Visitor for Collect {
    type Output = Vec<Motion>;
    fn visit<S: ExactSim>(self, mut s: S) -> Vec<Motion> {
        let mut out = vec![s.state()];
        for _ in 0..self.0 {
            s.step_period();
            out.push(s.state());
        }
        out
    }
}

fn case(p: Params, e: Effects, init: Motion, periods: u64) -> (Vec<Motion>, Vec<Motion>) {
    let ex = dispatch::<_, false>(p, e, init, History::HoldInitial, Collect(periods)).unwrap();
    let mut r = RefSim::new(
        RefModel::paper(p, e),
        Method::Dopri {
            rtol: 1e-13,
            atol: 1e-13,
        },
        init,
    )
    .unwrap();
    let mut rf = vec![r.state()];
    for _ in 0..periods {
        r.step_period();
        rf.push(r.state());
    }
    (ex, rf)
}

fn p(mu: f64, beta: f64, sigma: f64, tau_d: f64) -> Params {
    Params {
        mu,
        beta,
        sigma,
        tau_d,
    }
}

#[test]
fn exact_matches_dormand_prince_on_varied_trajectories() {
    let unq = Effects {
        quantization: false,
        ..Effects::ALL
    };
    let one = Effects {
        one_sided: true,
        ..Effects::ALL
    };
    let cases = [
        (p(100.0, 0.1, 1.0, 0.0), Effects::ALL, 0.0, 5.0),
        (p(100.0, 0.1, 1.0, 1.25), Effects::ALL, 0.0, 5.0),
        (p(100.0, 0.0, 0.3, 0.0), Effects::ALL, 0.0, 1.0),
        (p(100.0, 0.7, 0.0, 0.0), Effects::ALL, 0.0, 10.0),
        (p(5.0, 0.2, 0.6, 0.5), Effects::ALL, 0.3, -2.0),
        (p(0.2, 0.05, 0.7, 0.0), Effects::ALL, 0.0, 0.7),
        (p(50.0, 0.3, 0.2, 2.0), unq, 3.0, 0.0),
        (p(20.0, 0.05, 0.4, 0.3), one, 0.0, 3.0),
        (p(100.0, 0.1, 2.0, 0.0), Effects::ALL, 0.0, 20.0),
    ];
    for (i, &(pp, e, x0, v0)) in cases.iter().enumerate() {
        let (ex, rf) = case(pp, e, Motion { x: x0, v: v0 }, 300);
        for (h, (a, b)) in ex.iter().zip(&rf).enumerate() {
            let tol_x = 1e-7 * (1.0 + a.x.abs());
            let tol_v = 1e-7 * (1.0 + a.v.abs());
            assert!(
                (a.x - b.x).abs() <= tol_x && (a.v - b.v).abs() <= tol_v,
                "case {i} period {h}: exact {a:?} vs dopri {b:?}"
            );
        }
    }
}

struct Audit(u64);
impl Visitor for Audit {
    type Output = (f64, f64, f64);
    fn visit<S: ExactSim>(self, mut s: S) -> (f64, f64, f64) {
        let mut worst: f64 = 0.0;
        let mut total = 0.0;
        let mut hmax: f64 = 0.0;
        for _ in 0..self.0 {
            s.step_period();
            let a = s.audit();
            worst = worst.max(a.residual.abs());
            total += a.residual;
            hmax = hmax.max(a.h_start);
        }
        (worst, total, hmax)
    }
}

#[test]
fn exact_energy_balance_is_at_floating_point_level_over_5e4_periods() {
    for &(pp, x0, v0) in &[
        (p(100.0, 0.1, 1.0, 0.0), 0.0, 5.0),
        (p(100.0, 1.2, 2.5, 1.25), 0.0, 5.0),
        (p(100.0, 0.05, 0.2, 0.0), 0.0, 5.0),
        (p(100.0, 0.6, 0.2, 0.0), 0.0, 20.0),
        (p(100.0, 0.0, 0.45, 0.0), 0.0, 1.0),
        (p(3.0, 1.5, 1.0, 0.7), 0.2, 3.0),
    ] {
        let (worst, total, hmax) = dispatch::<_, true>(
            pp,
            Effects::ALL,
            Motion { x: x0, v: v0 },
            History::HoldInitial,
            Audit(50_000),
        )
        .unwrap();
        let scale = hmax.max(1.0);
        assert!(
            worst <= 1e-12 * scale && total.abs() <= 1e-10 * scale,
            "{pp:?}: worst {worst:e}, total {total:e}, H max {hmax}"
        );
    }
}

/// Eq. (5): below its cut-off a second-order amplifier acts like the pure delay 2δ_A/ω_A. The
/// reference integrator with the filter stays much closer to the exact solver with that delay
/// than to the exact solver without it (unquantized spring, so no branch flips).
#[test]
fn fast_second_order_amplifier_approaches_the_pure_delay_of_eq5() {
    use stiffwall_sim::reference::AmpFilter;
    let e = Effects {
        quantization: false,
        ..Effects::ALL
    };
    let (omega, zeta) = (20.0, 0.7);
    let base = p(50.0, 0.3, 0.2, 0.0);
    let init = Motion { x: 0.0, v: 2.0 };
    let mut model = RefModel::paper(base, e);
    model.amp = Some(AmpFilter { omega, zeta });
    model.history = History::Zero;
    let mut r = RefSim::new(
        model,
        Method::Dopri {
            rtol: 1e-11,
            atol: 1e-12,
        },
        init,
    )
    .unwrap();
    let delayed = p(50.0, 0.3, 0.2, 2.0 * zeta / omega);
    let ex_d = dispatch::<_, false>(delayed, e, init, History::Zero, Collect(200)).unwrap();
    let ex_0 = dispatch::<_, false>(base, e, init, History::Zero, Collect(200)).unwrap();
    let (mut err_d, mut err_0) = (0.0f64, 0.0f64);
    for h in 0..=200 {
        let s = r.state();
        err_d = err_d.max((s.x - ex_d[h].x).abs());
        err_0 = err_0.max((s.x - ex_0[h].x).abs());
        r.step_period();
    }
    assert!(
        err_d < 0.1 * err_0,
        "delay model {err_d}, no-delay model {err_0}"
    );
}

mod random {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

        /// Random parameters: the exact solver and Dormand–Prince at tolerance 1e-12 agree at every
        /// sample instant until the trajectory passes within 1e-7 of an encoder boundary at a
        /// sample (where a 1e-10 difference may legitimately pick the other count).
        #[test]
        fn exact_matches_dopri_on_random_trajectories(
            mu in 0.15..300.0f64, beta in 0.0..2.0f64, sigma in 0.0..2.0f64,
            tau_d in prop_oneof![Just(0.0), Just(1.0), 0.0..2.5f64],
            x0 in -3.0..3.0f64, v0 in -10.0..10.0f64,
        ) {
            let pp = p(mu, beta, sigma, tau_d);
            let (ex, rf) = case(pp, Effects::ALL, Motion { x: x0, v: v0 }, 300);
            for (h, (a, b)) in ex.iter().zip(&rf).enumerate() {
                if a.x.abs() > 1e6 {
                    break;
                }
                let tol_x = 1e-7 * (1.0 + a.x.abs());
                let tol_v = 1e-7 * (1.0 + a.v.abs());
                prop_assert!(
                    (a.x - b.x).abs() <= tol_x && (a.v - b.v).abs() <= tol_v,
                    "period {}: exact {:?} vs dopri {:?}", h, a, b
                );
                if (a.x - a.x.round()).abs() < 1e-7 {
                    break;
                }
            }
        }
    }
}

/// Every one of the 32 monomorphised effect sets agrees with the reference integrator run with
/// the same effect flags (100 periods, delay 0.6, one-sided wall entered from outside).
#[test]
fn all_32_effect_sets_match_the_reference() {
    let pp = p(20.0, 0.3, 0.4, 0.6);
    let init = Motion { x: -1.5, v: 2.0 };
    for bits in 0u32..32 {
        let e = Effects {
            quantization: bits & 1 != 0,
            coulomb: bits & 2 != 0,
            viscous: bits & 4 != 0,
            delay: bits & 8 != 0,
            one_sided: bits & 16 != 0,
        };
        let (ex, rf) = case(pp, e, init, 100);
        for (h, (a, b)) in ex.iter().zip(&rf).enumerate() {
            if (a.x - a.x.round()).abs() < 1e-7 {
                break;
            }
            assert!(
                (a.x - b.x).abs() <= 1e-7 * (1.0 + a.x.abs())
                    && (a.v - b.v).abs() <= 1e-7 * (1.0 + a.v.abs()),
                "{e:?} period {h}: exact {a:?} vs dopri {b:?}"
            );
        }
    }
}
