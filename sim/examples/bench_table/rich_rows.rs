//! Rows of the benchmark for the issue-10 plant effects (`stiffwall_sim::rich`): the cost of
//! each effect in the sampled wall loop, and the accuracy of the engines against independent
//! references (closed form vs Dormand–Prince / RK4).
//!
//! Units: SI plant (Freedom 6 of Table II: m 0.25 kg, b 0.01 N s/m, c 0.06 N, Δ 20 µm) at
//! K = 2400 N/m, T = 1 ms; errors in encoder ticks; times in ns per simulated period.

use super::{time_per_period, HORIZON};
use std::fmt::Write as _;
use stiffwall_sim::rich::{
    Amplifier, Cogging, HandSi, OdeMethod, PlantModel, RichPlant, Stiction, Transmission,
};

const K: f64 = 2400.0;
const T: f64 = 1e-3;
const DELTA: f64 = 20e-6;

fn base() -> PlantModel {
    PlantModel::rigid(0.25, 0.01, 0.06, DELTA).expect("valid")
}

/// The quantised wall of eq. (8), sampled every T, from an impact at 0.1 m/s (5 ticks/period).
fn wall_run(p: &mut RichPlant, periods: u64, mut each: impl FnMut(u64, &RichPlant)) {
    p.set_state(0.0, 0.1);
    for h in 0..periods {
        let n = p.encoder_count() as f64;
        p.advance(-K * DELTA * (n + 0.5), T);
        each(h, p);
    }
}

/// The effects of [`effect_sets`], each as the plant model holds it.
struct Parts {
    stiction: Option<Stiction>,
    stribeck: Option<Stiction>,
    cogging: Option<Cogging>,
    transmission: Option<Transmission>,
    limit: Option<Amplifier>,
    filter: Option<Amplifier>,
    hand: Option<HandSi>,
}

fn parts() -> Parts {
    let stiction = Some(Stiction {
        static_n: 0.09,
        stribeck_m_per_s: 0.0,
    });
    let stribeck = Some(Stiction {
        static_n: 0.09,
        stribeck_m_per_s: 0.002,
    });
    let cogging = Some(Cogging {
        amplitude_n: 0.01,
        period_m: 0.5e-3,
    });
    let transmission = Some(Transmission {
        link_mass_kg: 0.05,
        stiffness_n_per_m: 5e4,
        damping_ns_per_m: 2.0,
    });
    let limit = Some(Amplifier {
        cutoff_hz: None,
        damping_ratio: 0.7,
        force_limit_n: Some(0.5),
        deadband_n: Some(0.002),
    });
    let filter = Some(Amplifier {
        cutoff_hz: Some(1000.0),
        damping_ratio: 0.7,
        force_limit_n: Some(0.5),
        deadband_n: None,
    });
    let hand = Some(HandSi {
        mass_kg: 0.15,
        damping_ns_per_m: 4.8,
        stiffness_n_per_m: 600.0,
    });
    Parts {
        stiction,
        stribeck,
        cogging,
        transmission,
        limit,
        filter,
        hand,
    }
}

/// The plants timed: the paper's, each effect added alone, and all of them.
fn effect_sets() -> Vec<(&'static str, PlantModel)> {
    let Parts {
        stiction,
        stribeck,
        cogging,
        transmission,
        limit,
        filter,
        hand,
    } = parts();
    let b = base();
    vec![
        ("paper plant (m, b, c; closed form)", b),
        (
            "+ stiction, static/dynamic switch (closed form)",
            PlantModel { stiction, ..b },
        ),
        (
            "+ force limit 0.5 N and dead band 2 mN (closed form)",
            PlantModel {
                amplifier: limit,
                ..b
            },
        ),
        (
            "+ stiction with Stribeck decay (DP5)",
            PlantModel {
                stiction: stribeck,
                ..b
            },
        ),
        (
            "+ cogging 10 mN / 0.5 mm (DP5)",
            PlantModel { cogging, ..b },
        ),
        (
            "+ transmission 5e4 N/m, link 0.05 kg (exact, linear)",
            PlantModel { transmission, ..b },
        ),
        (
            "+ amplifier filter 1 kHz with limit (exact, linear)",
            PlantModel {
                amplifier: filter,
                ..b
            },
        ),
        (
            "+ hand of Table II (exact, linear)",
            PlantModel { hand, ..b },
        ),
        (
            "all of the above (DP5)",
            PlantModel {
                stiction: stribeck,
                cogging,
                transmission,
                amplifier: filter,
                hand,
                ..b
            },
        ),
    ]
}

/// Appends both tables to `md`.
pub fn rich_rows(md: &mut String, min_s: f64) {
    writeln!(
        md,
        "## Cost of each plant effect (issue 10, `stiffwall_sim::rich::RichPlant`)\n\n\
         Freedom 6 of Table II in SI (m 0.25 kg, b 0.01 N s/m, c 0.06 N, delta 20 um) behind the \
         quantised wall K = 2400 N/m, T = 1 ms, {HORIZON} periods from an impact at 0.1 m/s \
         (5 ticks/period). Closed-form rows use `friction::advance_switch`; \"exact, linear\" rows \
         the matrix exponential of `rich::linear` (events located on the closed form); the \
         others Dormand-Prince 5(4) at the plant's default tolerance (rtol 1e-9, atol 1e-6 in ticks, \
         ticks/ms, max(F_s, 1 mN)) with event location; steps and events are the integrator's (the exact engines count none).\n\n\
         | plant | ns/period | steps/period | events/period |\n|---|---:|---:|---:|"
    )
    .unwrap();
    for (name, model) in effect_sets() {
        let mut probe = RichPlant::new(&model).expect("valid");
        wall_run(&mut probe, HORIZON, |_, _| {});
        let st = probe.stats();
        let ns = time_per_period(HORIZON, min_s, || {
            let mut p = RichPlant::new(&model).expect("valid");
            wall_run(&mut p, HORIZON, |_, _| {});
            std::hint::black_box(p.position_m());
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
    accuracy_rows(md, min_s);
}

/// Appends the accuracy table: stiction with a force limit, then the transmission.
fn accuracy_rows(md: &mut String, min_s: f64) {
    writeln!(
        md,
        "## Accuracy of the plant effects against an independent reference\n\n\
         Stiction (static 0.09 N, dynamic 0.06 N, no Stribeck decay) with force limit 0.5 N and \
         dead band 2 mN in the wall loop above: each integrator against the closed form (the \
         same trajectory: {HORIZON} periods). Transmission (motor 0.05 kg, link 0.02 kg, \
         5e4 N/m, no damping or friction) under a constant 0.7 N for {HORIZON} periods: against \
         the modal closed form (centre of mass F t^2/2(m1+m2), deflection \
         F m2/(k(m1+m2))(1 - cos wt)). Errors: largest deviation of the motor position at the \
         sample instants, in ticks.\n\n\
         | effect | engine | ns/period | max abs error [ticks] |\n|---|---|---:|---:|"
    )
    .unwrap();
    stiction_accuracy(md, min_s);
    transmission_accuracy(md, min_s);
    writeln!(md).unwrap();
}

/// Stiction with force limit and dead band in the wall loop: each integrator against the
/// closed form.
fn stiction_accuracy(md: &mut String, min_s: f64) {
    let stiction = PlantModel {
        stiction: Some(Stiction {
            static_n: 0.09,
            stribeck_m_per_s: 0.0,
        }),
        amplifier: Some(Amplifier {
            cutoff_hz: None,
            damping_ratio: 0.7,
            force_limit_n: Some(0.5),
            deadband_n: Some(0.002),
        }),
        ..base()
    };
    let mut exact = Vec::new();
    let mut p = RichPlant::new(&stiction).expect("valid");
    wall_run(&mut p, HORIZON, |_, s| exact.push(s.position_m()));
    let ns = time_per_period(HORIZON, min_s, || {
        let mut p = RichPlant::new(&stiction).expect("valid");
        wall_run(&mut p, HORIZON, |_, _| {});
        std::hint::black_box(p.position_m());
    });
    writeln!(
        md,
        "| stiction + limit | closed form | {ns:.0} | 0 (reference) |"
    )
    .unwrap();
    for (name, m) in methods() {
        let mut err: f64 = 0.0;
        let mut p = RichPlant::with_method(&stiction, Some(m)).expect("valid");
        wall_run(&mut p, HORIZON, |h, s| {
            err = err.max((s.position_m() - exact[h as usize]).abs() / DELTA);
        });
        let ns = time_per_period(HORIZON, min_s, || {
            let mut p = RichPlant::with_method(&stiction, Some(m)).expect("valid");
            wall_run(&mut p, HORIZON, |_, _| {});
            std::hint::black_box(p.position_m());
        });
        writeln!(md, "| stiction + limit | {name} | {ns:.0} | {err:.2e} |").unwrap();
    }
}

/// The transmission under a constant force: each engine against the modal closed form.
fn transmission_accuracy(md: &mut String, min_s: f64) {
    let (m1, m2, k, f) = (0.05, 0.02, 5e4, 0.7);
    let trans = PlantModel {
        transmission: Some(Transmission {
            link_mass_kg: m2,
            stiffness_n_per_m: k,
            damping_ns_per_m: 0.0,
        }),
        ..PlantModel::rigid(m1, 0.0, 0.0, DELTA).expect("valid")
    };
    let w = (k * (1.0 / m1 + 1.0 / m2)).sqrt();
    let exact_linear = ("exact (matrix exponential)".to_string(), None);
    let odes = methods().into_iter().map(|(n, m)| (n, Some(m)));
    for (name, m) in std::iter::once(exact_linear).chain(odes) {
        let mut err: f64 = 0.0;
        let mut p = RichPlant::with_method(&trans, m).expect("valid");
        for h in 1..=HORIZON {
            p.advance(f, T);
            let t = h as f64 * T;
            let q = f * m2 / (k * (m1 + m2)) * (1.0 - (w * t).cos());
            let x1 = f * t * t / (2.0 * (m1 + m2)) + m2 / (m1 + m2) * q;
            err = err.max((p.position_m() - x1).abs() / DELTA);
        }
        let ns = time_per_period(HORIZON, min_s, || {
            let mut p = RichPlant::with_method(&trans, m).expect("valid");
            for _ in 0..HORIZON {
                p.advance(f, T);
            }
            std::hint::black_box(p.position_m());
        });
        writeln!(md, "| transmission | {name} | {ns:.0} | {err:.2e} |").unwrap();
    }
}

fn methods() -> Vec<(String, OdeMethod)> {
    let mut v = Vec::new();
    for tol in [1e-6, 1e-9, 1e-12] {
        v.push((
            format!("DP5 rtol {tol:.0e}"),
            OdeMethod::Dopri {
                rtol: tol,
                atol: tol,
            },
        ));
    }
    for steps in [10u32, 100] {
        v.push((
            format!("RK4 {steps} steps/period"),
            OdeMethod::Rk4 {
                step_s: T / f64::from(steps),
            },
        ));
    }
    v
}
