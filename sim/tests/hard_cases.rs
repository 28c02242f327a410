//! Hard cases over wide ranges: μ near the sampling limit 1/π², huge initial velocities, β = 0,
//! σ = 0, σ = ½ exactly, starts exactly on a quantization boundary, sticking exactly at a sample
//! instant, integer and zero delays, 5×10⁴-period horizons. Never NaN, never a Zeno loop (every
//! call returns; the exact solver does at most two closed-form sub-steps per segment).

use proptest::prelude::*;
use stiffwall_sim::exact::{dispatch, storage, ExactSim, History, Visitor};
use stiffwall_sim::reference::{Method, RefModel, RefSim};
use stiffwall_sim::{Effects, Motion, Params};

struct Check(u64);
impl Visitor for Check {
    type Output = Result<(), String>;
    fn visit<S: ExactSim>(self, mut s: S) -> Result<(), String> {
        for _ in 0..self.0 {
            s.step_period();
            let st = s.state();
            if st.x.is_nan() || st.v.is_nan() {
                return Err(format!("NaN at period {}", s.period()));
            }
            if !s.diverged() && (st.x.is_infinite() || st.v.is_infinite()) {
                return Err("infinite state not flagged as diverged".into());
            }
            let a = s.audit();
            if a.residual.is_nan() && !s.diverged() {
                return Err("NaN residual".into());
            }
        }
        Ok(())
    }
}

fn mu_strategy() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(1.0 / (std::f64::consts::PI * std::f64::consts::PI)),
        (0.1013..0.2f64),
        (0.2..1e4f64),
    ]
}

fn beta_strategy() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), (0.0..3.0f64), Just(0.5)]
}

fn sigma_strategy() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), Just(0.5), (0.0..3.0f64)]
}

fn tau_strategy() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), Just(1.0), Just(2.0), (0.0..4.0f64)]
}

fn xi0_strategy() -> impl Strategy<Value = f64> {
    prop_oneof![(-5i32..5).prop_map(f64::from), (-5.0..5.0f64)]
}

fn v0_strategy() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), (-50.0..50.0f64), (-1e9..1e9f64), Just(1e12)]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn exact_never_nan(mu in mu_strategy(), beta in beta_strategy(), sigma in sigma_strategy(),
                       tau_d in tau_strategy(), xi0 in xi0_strategy(), v0 in v0_strategy(),
                       audit in any::<bool>()) {
        let p = Params { mu, beta, sigma, tau_d };
        let init = Motion { x: xi0, v: v0 };
        let r = if audit {
            dispatch::<_, true>(p, Effects::ALL, init, History::HoldInitial, Check(2000))
        } else {
            dispatch::<_, false>(p, Effects::ALL, init, History::Zero, Check(2000))
        };
        prop_assert!(r.unwrap().is_ok());
    }

    #[test]
    fn reference_never_nan(mu in mu_strategy(), beta in beta_strategy(), sigma in sigma_strategy(),
                           tau_d in tau_strategy(), xi0 in xi0_strategy(), v0 in -50.0..50.0f64) {
        let p = Params { mu, beta, sigma, tau_d };
        let mut m = RefModel::paper(p, Effects::ALL);
        if xi0 > 2.0 {
            m.amp = Some(stiffwall_sim::reference::AmpFilter { omega: 1.0 + xi0, zeta: 0.2 * xi0 });
        }
        if xi0 < -2.0 {
            m.hand = Some(stiffwall_sim::reference::Hand { mu: -xi0, beta: 0.3, kappa: 0.1 });
        }
        for method in [Method::Rk4 { steps_per_period: 8 }, Method::Dopri { rtol: 1e-8, atol: 1e-10 }] {
            let s = RefSim::new(m, method, Motion { x: xi0, v: v0 }).unwrap();
            prop_assert!(Check(50).visit(s).is_ok());
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// 5×10⁴-period horizons with the audit on: the residual stays at floating-point level
    /// relative to the energy reached.
    #[test]
    fn long_horizons(mu in mu_strategy(), beta in beta_strategy(), sigma in sigma_strategy(),
                     tau_d in tau_strategy(), v0 in -20.0..20.0f64) {
        struct Long;
        impl Visitor for Long {
            type Output = Result<(), String>;
            fn visit<S: ExactSim>(self, mut s: S) -> Result<(), String> {
                let mu = s.params().mu;
                for _ in 0..50_000 {
                    s.step_period();
                    if s.diverged() { return Ok(()); }
                    let a = s.audit();
                    let st = s.state();
                    let scale = storage(mu, st.x, st.v).max(a.h_start).max(a.e_d).max(1.0);
                    if a.residual.is_nan() || a.residual.abs() > 1e-11 * scale {
                        return Err(format!("residual {a:?} at {}", s.period()));
                    }
                }
                Ok(())
            }
        }
        let p = Params { mu, beta, sigma, tau_d };
        let r = dispatch::<_, true>(p, Effects::ALL, Motion { x: 0.0, v: v0 }, History::HoldInitial, Long);
        prop_assert_eq!(r.unwrap(), Ok(()));
    }
}

/// The mass stops exactly at a sample instant (μ = 1, β = 0, ξ̇₀ = 1, net deceleration 1) and
/// must stay stuck: |φ_C| = ½ ≤ σ.
#[test]
fn sticking_exactly_at_a_sample_instant() {
    let p = Params {
        mu: 1.0,
        beta: 0.0,
        sigma: 0.5,
        tau_d: 0.0,
    };
    let mut s =
        stiffwall_sim::exact::NoDelay::new(p, Motion { x: 0.0, v: 1.0 }, History::HoldInitial)
            .unwrap();
    s.step_period();
    assert_eq!(s.state(), Motion { x: 0.5, v: 0.0 });
    for _ in 0..10 {
        s.step_period();
        assert_eq!(s.state(), Motion { x: 0.5, v: 0.0 });
    }
    assert!(s.at_rest());
}

/// Starting exactly on a boundary ξ₀ = 1 at rest: φ_C = −1.5; with σ = 1.5 exactly it stays.
#[test]
fn start_on_boundary_with_sigma_equal_to_force() {
    let p = Params {
        mu: 10.0,
        beta: 0.1,
        sigma: 1.5,
        tau_d: 0.0,
    };
    let mut s =
        stiffwall_sim::exact::NoDelay::new(p, Motion { x: 1.0, v: 0.0 }, History::HoldInitial)
            .unwrap();
    for _ in 0..100 {
        s.step_period();
    }
    assert_eq!(s.state(), Motion { x: 1.0, v: 0.0 });
    // Just below: slips.
    let p = Params {
        sigma: 1.5 - 1e-12,
        ..p
    };
    let mut s =
        stiffwall_sim::exact::NoDelay::new(p, Motion { x: 1.0, v: 0.0 }, History::HoldInitial)
            .unwrap();
    s.step_period();
    assert!(s.state().x < 1.0);
}

/// Integer delay τ_D = 1 is the same as a one-period-late spring: compare with the reference.
#[test]
fn integer_delay_matches_reference() {
    let p = Params {
        mu: 30.0,
        beta: 0.3,
        sigma: 0.6,
        tau_d: 1.0,
    };
    let init = Motion { x: 0.0, v: 2.0 };
    let mut e = stiffwall_sim::exact::Full::new(p, init, History::HoldInitial).unwrap();
    let mut r = RefSim::new(
        RefModel::paper(p, Effects::ALL),
        Method::Dopri {
            rtol: 1e-12,
            atol: 1e-13,
        },
        init,
    )
    .unwrap();
    for _ in 0..200 {
        e.step_period();
        r.step_period();
        let (a, b) = (e.state(), r.state());
        assert!(
            (a.x - b.x).abs() < 1e-7 && (a.v - b.v).abs() < 1e-7,
            "{a:?} {b:?}"
        );
    }
}
