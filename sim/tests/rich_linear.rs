//! The exact engine of plants that are linear between events (`stiffwall_sim::rich::linear`):
//! a compliant transmission, a hand and an amplifier filter with its output clamp, with viscous
//! and Coulomb friction and a static/dynamic switch. Each plant is driven by the same
//! stick–slip command sequence through the exact engine and through Dormand–Prince 5(4) at
//! tight tolerance (an independent integrator); the trajectories must agree to a small
//! fraction of a count over thousands of periods, through many stick and clamp events.

use stiffwall_sim::rich::{
    Amplifier, HandSi, OdeMethod, PlantModel, RichPlant, Stiction, Transmission,
};

const DOPRI_TIGHT: Option<OdeMethod> = Some(OdeMethod::Dopri {
    rtol: 1e-12,
    atol: 1e-9,
});

const DELTA: f64 = 20e-6;

fn base() -> PlantModel {
    PlantModel::rigid(0.05, 0.01, 0.06, DELTA).unwrap()
}

/// A deterministic, sign-changing command sequence (N) that makes the motor stick and slip.
fn command(i: u32, scale: f64) -> f64 {
    let t = f64::from(i);
    scale * (0.12 * (t * 0.031).sin() + 0.05 * (t * 0.173).sin())
}

/// Runs both engines over `periods` of 1 ms; returns (largest motor error in counts, largest
/// link error in counts, periods stuck, periods moving).
fn compare(m: &PlantModel, periods: u32, scale: f64) -> (f64, f64, u32, u32) {
    let r = compare_inner(m, periods, scale);
    eprintln!(
        "exact vs DP5: motor {:e}, link {:e} counts; {} stuck, {} moving",
        r.0, r.1, r.2, r.3
    );
    r
}

fn compare_inner(m: &PlantModel, periods: u32, scale: f64) -> (f64, f64, u32, u32) {
    let mut exact = RichPlant::new(m).unwrap();
    assert!(exact.is_exact(), "the linear engine runs this plant");
    assert!(exact.stats().rhs_evals == 0);
    let mut dp = RichPlant::with_method(m, DOPRI_TIGHT).unwrap();
    dp.set_tolerance_period(1e-3);
    let (mut e1, mut e2, mut stuck, mut moving) = (0.0_f64, 0.0_f64, 0, 0);
    for i in 0..periods {
        let u = command(i, scale);
        exact.advance(u, 1e-3);
        dp.advance(u, 1e-3);
        e1 = e1.max((exact.position_m() - dp.position_m()).abs() / DELTA);
        e2 = e2.max((exact.link_position_m() - dp.link_position_m()).abs() / DELTA);
        if exact.is_stuck() {
            stuck += 1;
        } else {
            moving += 1;
        }
    }
    (e1, e2, stuck, moving)
}

#[test]
fn transmission_with_stiction_matches_dopri() {
    let mut m = base();
    m.transmission = Some(Transmission {
        link_mass_kg: 0.04,
        stiffness_n_per_m: 20_000.0,
        damping_ns_per_m: 0.8,
    });
    m.stiction = Some(Stiction {
        static_n: 0.09,
        stribeck_m_per_s: 0.0,
    });
    let (e1, e2, stuck, moving) = compare(&m, 3000, 1.0);
    assert!(
        stuck > 100 && moving > 100,
        "stick–slip: {stuck} / {moving}"
    );
    assert!(e1 < 1e-4 && e2 < 1e-4, "motor {e1:e}, link {e2:e} counts");
}

#[test]
fn hand_and_clamped_filter_match_dopri() {
    let mut m = base();
    m.hand = Some(HandSi {
        mass_kg: 0.1,
        damping_ns_per_m: 0.5,
        stiffness_n_per_m: 30.0,
    });
    // A 300 Hz filter that overshoots (ζ = 0.3) into a 0.1 N clamp.
    m.amplifier = Some(Amplifier {
        cutoff_hz: Some(300.0),
        damping_ratio: 0.3,
        force_limit_n: Some(0.1),
        deadband_n: None,
    });
    m.stiction = Some(Stiction {
        static_n: 0.08,
        stribeck_m_per_s: 0.0,
    });
    let mut exact = RichPlant::new(&m).unwrap();
    let mut clamped = 0;
    for i in 0..3000 {
        exact.advance(command(i, 1.5), 1e-3);
        if exact.actuator_force_n().abs() >= 0.1 {
            clamped += 1;
        }
    }
    assert!(clamped > 10, "the clamp acts ({clamped} periods)");
    let (e1, _, stuck, moving) = compare(&m, 3000, 1.5);
    assert!(stuck > 20 && moving > 100, "stick–slip: {stuck} / {moving}");
    assert!(e1 < 1e-4, "motor {e1:e} counts");
}

#[test]
fn everything_linear_together_matches_dopri() {
    let mut m = base();
    m.transmission = Some(Transmission {
        link_mass_kg: 0.03,
        stiffness_n_per_m: 30_000.0,
        damping_ns_per_m: 0.3,
    });
    m.hand = Some(HandSi {
        mass_kg: 0.05,
        damping_ns_per_m: 0.5,
        stiffness_n_per_m: 50.0,
    });
    m.amplifier = Some(Amplifier {
        cutoff_hz: Some(1000.0),
        damping_ratio: 0.7,
        force_limit_n: Some(0.2),
        deadband_n: Some(0.004),
    });
    let (e1, e2, _, moving) = compare(&m, 5000, 1.0);
    assert!(moving > 100);
    assert!(e1 < 1e-4 && e2 < 1e-4, "motor {e1:e}, link {e2:e} counts");
}

#[test]
fn the_two_mass_resonance_is_exact_without_friction() {
    // Motor 0.05 kg, link 0.02 kg, 5e4 N/m, no damping or friction, under a constant 0.7 N:
    // centre of mass F t²/(2(m₁+m₂)), deflection r = x₁ − x₂ = F m₂/(k(m₁+m₂))(1 − cos ωt),
    // ω = √(k(1/m₁ + 1/m₂)), and x₁ = centre + m₂/(m₁+m₂)·r.
    let mut m = PlantModel::rigid(0.05, 0.0, 0.0, DELTA).unwrap();
    m.transmission = Some(Transmission {
        link_mass_kg: 0.02,
        stiffness_n_per_m: 5e4,
        damping_ns_per_m: 0.0,
    });
    let mut p = RichPlant::new(&m).unwrap();
    assert!(p.is_exact());
    let (m1, m2, k, f): (f64, f64, f64, f64) = (0.05, 0.02, 5e4, 0.7);
    let w = (k * (1.0 / m1 + 1.0 / m2)).sqrt();
    let mut worst = 0.0_f64;
    for i in 1..=300 {
        p.advance(f, 1e-3);
        let t = f64::from(i) * 1e-3;
        let com = f * t * t / (2.0 * (m1 + m2));
        let r = f * m2 / (k * (m1 + m2)) * (1.0 - (w * t).cos());
        let x1 = com + m2 / (m1 + m2) * r;
        worst = worst.max((p.position_m() - x1).abs() / DELTA);
    }
    // DP5 at rtol 1e-12 reaches 5e-9 counts here (docs/BENCHMARKS.md); the closed form does
    // better.
    assert!(worst < 1e-8, "{worst:e} counts");
}

#[test]
fn coulomb_oscillator_stops_where_the_closed_form_says() {
    // A mass on the hand's spring (no viscous friction, no transmission), released from rest
    // at x₀: each half-cycle is a cosine about ±c/k and ends at rest 2c/k closer to the
    // centre; the mass sticks once |k x| ≤ c. Every stop is a located event, so the final
    // position checks the event locator against the analytic sequence.
    let (m_kg, c, k) = (0.05, 0.01, 400.0);
    let mut model = PlantModel::rigid(m_kg, 0.0, c, DELTA).unwrap();
    model.hand = Some(HandSi {
        mass_kg: 0.0,
        damping_ns_per_m: 0.0,
        stiffness_n_per_m: k,
    });
    let x0 = 1.0e-3;
    let mut a: f64 = x0;
    let mut half_cycles = 0;
    while k * a.abs() > c {
        a = -(a - a.signum() * 2.0 * c / k);
        half_cycles += 1;
    }
    assert!(half_cycles >= 10, "{half_cycles}");
    let mut p = RichPlant::new(&model).unwrap();
    assert!(p.is_exact());
    p.set_state(x0, 0.0);
    let w = (k / m_kg).sqrt();
    let t_end = (f64::from(half_cycles) + 2.0) * std::f64::consts::PI / w;
    let periods = (t_end / 1e-3).ceil() as u32;
    for _ in 0..periods {
        p.advance(0.0, 1e-3);
    }
    assert!(p.is_stuck(), "at rest after {half_cycles} half-cycles");
    let err = (p.position_m() - a).abs() / DELTA;
    assert!(
        err < 1e-9,
        "stops at {} m, closed form {a} m ({err:e} counts)",
        p.position_m()
    );
}
