//! The exact solver with the virtual damper β_v > 0 against Dormand–Prince 5(4) at tight
//! tolerance with the same damper ([`RefSim::with_damping`]): state at every sample instant, same
//! tolerance as `exact_vs_reference.rs` (1e-7 relative), one- and two-sided, with delay, with
//! and without quantization; and the exact solver's energy balance (26) with the damper.

use stiffwall_sim::exact::{dispatch_damped, ExactSim, History, Visitor};
use stiffwall_sim::reference::{Method, RefModel, RefSim};
use stiffwall_sim::{Effects, Motion, Params};

struct Collect(u64);
impl Visitor for Collect {
    type Output = Vec<(Motion, f64)>;
    fn visit<S: ExactSim>(self, mut s: S) -> Vec<(Motion, f64)> {
        let mut out = vec![(s.state(), 0.0)];
        for _ in 0..self.0 {
            s.step_period();
            out.push((s.state(), s.audit().residual));
        }
        out
    }
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
fn damped_exact_matches_damped_dormand_prince() {
    let unq = Effects {
        quantization: false,
        ..Effects::ALL
    };
    let one = Effects {
        one_sided: true,
        ..Effects::ALL
    };
    let one_unq = Effects {
        one_sided: true,
        ..unq
    };
    let cases = [
        (p(100.0, 0.1, 1.0, 0.0), Effects::ALL, 0.5, 0.0, 5.0),
        (p(100.0, 0.1, 1.0, 1.25), Effects::ALL, 2.0, 0.0, 5.0),
        (p(100.0, 0.0, 0.3, 0.0), Effects::ALL, 1.0, 0.0, 1.0),
        (p(5.0, 0.2, 0.6, 0.5), Effects::ALL, 0.3, 0.3, -2.0),
        (p(50.0, 0.3, 0.2, 2.0), unq, 1.5, 3.0, 0.0),
        (p(100.0, 0.0, 0.0, 1.0), unq, 3.0, 0.0, 4.0),
        (p(20.0, 0.05, 0.4, 0.3), one, 0.8, 0.0, 3.0),
        (p(40.0, 0.02, 0.1, 1.5), one, 4.0, -1.0, 6.0),
        (p(30.0, 0.0, 0.0, 0.75), one_unq, 2.5, -0.5, 3.0),
    ];
    for (i, &(pp, e, beta_v, x0, v0)) in cases.iter().enumerate() {
        let init = Motion { x: x0, v: v0 };
        let ex =
            dispatch_damped::<_, true>(pp, e, init, History::HoldInitial, beta_v, Collect(300))
                .unwrap();
        let mut r = RefSim::new(
            RefModel::paper(pp, e),
            Method::Dopri {
                rtol: 1e-13,
                atol: 1e-13,
            },
            init,
        )
        .unwrap()
        .with_beta_v(beta_v)
        .unwrap();
        let mut moved = false;
        for (h, (a, res)) in ex.iter().enumerate() {
            if h > 0 {
                r.step_period();
            }
            let b = r.state();
            let tol_x = 1e-7 * (1.0 + a.x.abs());
            let tol_v = 1e-7 * (1.0 + a.v.abs());
            assert!(
                (a.x - b.x).abs() <= tol_x && (a.v - b.v).abs() <= tol_v,
                "case {i} period {h}: exact {a:?} vs dopri {b:?}"
            );
            assert!(
                res.abs() <= 1e-9 * (1.0 + a.v * a.v * pp.mu + a.x * a.x),
                "case {i} residual {res}"
            );
            moved |= a.v != 0.0;
        }
        assert!(moved, "case {i} never moved");
    }
}

/// The damper really enters the reference: damped and undamped reference runs differ.
#[test]
fn reference_damper_changes_the_trajectory() {
    let init = Motion { x: 0.0, v: 5.0 };
    let mk = || {
        RefSim::new(
            RefModel::paper(Params::BASE, Effects::ALL),
            Method::Dopri {
                rtol: 1e-10,
                atol: 1e-10,
            },
            init,
        )
        .unwrap()
    };
    let (mut a, mut b) = (mk(), mk().with_beta_v(1.0).unwrap());
    for _ in 0..50 {
        a.step_period();
        b.step_period();
    }
    assert!((a.state().x - b.state().x).abs() > 1e-3);
    assert_eq!(mk().with_beta_v(-1.0).unwrap_err().name(), "beta_v");
}
