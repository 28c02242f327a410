//! The report's effects that need a reference integrator: the cost of the effects only the
//! reference integrator models (amplifier filter, hand, no ZOH), on Freedom 6 of Table II held
//! by the operator of Table II, Dormand-Prince 5(4) at tolerance 1e-8.

use super::{time_per_period, HORIZON};
use std::fmt::Write as _;
use stiffwall_sim::exact::{ExactSim, History};
use stiffwall_sim::reference::{AmpFilter, Hand, Method, RefModel, RefSim};
use stiffwall_sim::{Effects, Motion, Params};

/// Effect sets that need the reference integrator (amplifier filter, hand, no ZOH).
pub fn reference_effects(md: &mut String, min_s: f64) {
    let sets = reference_sets();
    writeln!(
        md,
        "## Effects that need a reference integrator\n\n\
         Dormand-Prince 5(4) at tolerance 1e-8, {HORIZON} periods from xidot0 = 5: Freedom 6 of Table II \
         (mu 104.2, beta 0.004, sigma 1.25) at tau_D = 1 held by the operator of Table II (added mass \
         62.5, damping 2, stiffness 0.25 in Table I units) through a 3 kHz amplifier (omega_A T = 18.8, \
         damping 0.7). The reference model checks its effect flags at run time (one predictable branch \
         each); its cost is dominated by step count, which every effect changes.\n\n\
         | effect set | ns/period | steps/period | events/period |\n|---|---:|---:|---:|"
    )
    .unwrap();
    let init = Motion { x: 0.0, v: 5.0 };
    let m = Method::Dopri {
        rtol: 1e-8,
        atol: 1e-8,
    };
    for (name, model) in sets {
        let mut probe = RefSim::new(model, m, init).expect("valid");
        for _ in 0..HORIZON {
            probe.step_period();
        }
        let st = probe.stats();
        let ns = time_per_period(HORIZON, min_s, || {
            let mut s = RefSim::new(model, m, init).expect("valid");
            for _ in 0..HORIZON {
                s.step_period();
            }
            std::hint::black_box(s.state());
        });
        writeln!(
            md,
            "| {name} | {ns:.0} | {:.1} | {:.2} |",
            st.steps as f64 / HORIZON as f64,
            st.events as f64 / HORIZON as f64
        )
        .unwrap();
    }
    writeln!(md).unwrap();
}

/// The effect sets, named: all of them, each removed, and none.
fn reference_sets() -> Vec<(&'static str, RefModel)> {
    let all = all_effects();
    let e = Effects::ALL;
    vec![
        (
            "all (ZOH, quantization, Coulomb, viscous, delay, 3 kHz amplifier filter, hand)",
            all,
        ),
        (
            "without quantization",
            RefModel {
                effects: Effects {
                    quantization: false,
                    ..e
                },
                ..all
            },
        ),
        (
            "without Coulomb",
            RefModel {
                effects: Effects {
                    coulomb: false,
                    ..e
                },
                ..all
            },
        ),
        (
            "without viscous",
            RefModel {
                effects: Effects {
                    viscous: false,
                    ..e
                },
                ..all
            },
        ),
        (
            "without delay",
            RefModel {
                effects: Effects { delay: false, ..e },
                ..all
            },
        ),
        ("without amplifier filter", RefModel { amp: None, ..all }),
        ("without hand", RefModel { hand: None, ..all }),
        (
            "without ZOH (continuous spring, no delay)",
            RefModel {
                zoh: false,
                effects: Effects { delay: false, ..e },
                ..all
            },
        ),
        (
            "none (continuous linear spring, no friction)",
            RefModel {
                zoh: false,
                effects: Effects::NONE,
                amp: None,
                hand: None,
                ..all
            },
        ),
    ]
}

/// Every effect: Freedom 6 of Table II at K = 2400 N/m, T = 1 ms, held by the operator of
/// Table II, through a 3 kHz amplifier.
fn all_effects() -> RefModel {
    let p = Params {
        mu: 104.2,
        beta: 0.004,
        sigma: 1.25,
        tau_d: 1.0,
    };
    let hand = Some(Hand {
        mu: 62.5,
        beta: 2.0,
        kappa: 0.25,
    });
    let amp = Some(AmpFilter {
        omega: 2.0 * std::f64::consts::PI * 3.0,
        zeta: 0.7,
    });
    RefModel {
        params: p,
        effects: Effects::ALL,
        zoh: true,
        hand,
        amp,
        history: History::HoldInitial,
    }
}
