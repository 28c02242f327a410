//! The device's travel (`effects.travel`, issue 46): end stops as one-sided springs and dampers
//! on the motor, stepped exactly by the linear engine with contact and release located as
//! events. Checked against Dormand–Prince 5(4) at tight tolerance (an independent integrator
//! that sees the stop force only as a function of the state), against the static balance at a
//! stop, and against the plant without travel while the motor stays inside it.

use stiffwall_sim::rich::{
    OdeMethod, PlantModel, RichPlant, Travel, HARD_STOP_DAMPING_RATIO, HARD_STOP_HZ,
};
use stiffwall_sim::scene::Scene;

const DELTA: f64 = 20e-6;
const T: f64 = 1e-3;

fn with_travel(min_m: f64, max_m: f64) -> PlantModel {
    let rigid = PlantModel::rigid(0.05, 0.01, 0.06, DELTA).unwrap();
    PlantModel {
        travel: Some(Travel::with_defaults(
            min_m,
            max_m,
            None,
            None,
            rigid.mass_kg,
        )),
        ..rigid
    }
}

/// A sign-changing command (N) that drives the motor back and forth over ±5 mm and more.
fn command(i: u32) -> f64 {
    let t = f64::from(i);
    0.5 * (t * 0.013).sin() + 0.1 * (t * 0.171).sin()
}

#[test]
fn a_hard_stop_by_default_is_a_1_khz_contact_damped_at_0_7_with_the_motor_mass() {
    let m = with_travel(-1e-3, 1e-3);
    let tr = m.travel.unwrap();
    let w = 2.0 * std::f64::consts::PI * HARD_STOP_HZ;
    assert!((tr.stop_stiffness_n_per_m / (0.05 * w * w) - 1.0).abs() < 1e-12);
    let zeta = tr.stop_damping_ns_per_m / (2.0 * (tr.stop_stiffness_n_per_m * 0.05).sqrt());
    assert!((zeta - HARD_STOP_DAMPING_RATIO).abs() < 1e-12);
}

#[test]
fn pushed_against_the_upper_stop_the_motor_rests_where_the_stop_balances_the_push() {
    let m = with_travel(-1e-3, 1e-3);
    let mut p = RichPlant::new(&m).unwrap();
    assert!(p.is_exact());
    let push = 0.3;
    for _ in 0..3000 {
        p.advance(push, T);
    }
    let tr = m.travel.unwrap();
    // At rest against the stop: the stop holds the push less what friction holds (0 ≤ |F_stop|
    // within c of the push).
    let f = p.stop_force_n();
    assert!(
        f < 0.0 && (-f - push).abs() <= m.coulomb_n + 1e-9,
        "stop force {f}"
    );
    let depth = p.position_m() - tr.max_m;
    assert!(
        depth > 0.0 && depth < push / tr.stop_stiffness_n_per_m * 1.01,
        "{depth}"
    );
    assert!(p.velocity_m_per_s().abs() < 1e-9);
}

#[test]
fn the_exact_contacts_agree_with_dormand_prince_through_many_impacts_on_both_stops() {
    let m = with_travel(-2e-3, 2e-3);
    let mut exact = RichPlant::new(&m).unwrap();
    let mut dp = RichPlant::with_method(
        &m,
        Some(OdeMethod::Dopri {
            rtol: 1e-12,
            atol: 1e-9,
        }),
    )
    .unwrap();
    dp.set_tolerance_period(T);
    let (mut err, mut hi, mut lo, mut worst_depth) = (0.0f64, 0, 0, 0.0f64);
    for i in 0..6000 {
        let u = command(i);
        exact.advance(u, T);
        dp.advance(u, T);
        err = err.max((exact.position_m() - dp.position_m()).abs() / DELTA);
        let f = exact.stop_force_n();
        if f < 0.0 {
            hi += 1;
        } else if f > 0.0 {
            lo += 1;
        }
        let x = exact.position_m();
        worst_depth = worst_depth.max((x - 2e-3).max(-2e-3 - x));
    }
    eprintln!("exact vs DP5 with stops: {err:e} counts; {hi} ticks on the upper stop, {lo} on the lower, deepest {worst_depth:e} m");
    assert!(hi > 100 && lo > 100, "both stops were hit: {hi} {lo}");
    assert!(err < 0.05, "{err} counts");
    // A 1 kHz stop under a 0.6 N push sinks in by about F/k = 0.6/(0.05 (2π 1e3)²) ≈ 0.3 µm,
    // more on impact.
    assert!(worst_depth < 20e-6, "{worst_depth}");
}

#[test]
fn inside_the_travel_the_stops_change_nothing() {
    let free = PlantModel::rigid(0.05, 0.01, 0.06, DELTA).unwrap();
    let bounded = with_travel(-1.0, 1.0);
    let mut a = RichPlant::new(&free).unwrap();
    let mut b = RichPlant::new(&bounded).unwrap();
    for i in 0..4000 {
        let u = command(i);
        a.advance(u, T);
        b.advance(u, T);
        assert_eq!(b.stop_force_n(), 0.0);
        let e = (a.position_m() - b.position_m()).abs() / DELTA;
        assert!(e < 1e-6, "tick {i}: {e} counts");
        assert_eq!(a.encoder_count(), b.encoder_count(), "tick {i}");
    }
}

#[test]
fn the_stop_only_pushes_so_a_motor_pulled_away_separates() {
    let m = with_travel(-1e-3, 1e-3);
    let mut p = RichPlant::new(&m).unwrap();
    p.set_state(1e-3 - 1e-6, 0.2);
    let mut left = false;
    for _ in 0..200 {
        p.advance(-0.5, 1e-4);
        assert!(p.stop_force_n() <= 0.0);
        if p.position_m() < 0.9e-3 {
            left = true;
            break;
        }
    }
    assert!(left, "pulled away from the stop");
}

fn scene(travel: &str, initial: &str) -> String {
    format!(
        "[device]\nmass_kg = 0.05\nviscous_ns_per_m = 0.01\ncoulomb_n = 0.06\nresolution_m = 2e-5\n\
         [controller]\nstiffness_n_per_m = 500.0\nperiod_s = 0.001\nextra_delay_s = 0.0\n\
         [effects]\nzoh = true\nquantization = true\ncoulomb = true\nviscous = true\n\
         delay = false\none_sided_wall = false\namplifier = {{ kind = \"none\" }}\n\
         hand = {{ kind = \"none\" }}\n{travel}\n\
         [initial]\n{initial}\n[run]\nperiods = 10\nsolver = {{ kind = \"exact\" }}\n"
    )
}

#[test]
fn travel_keys_are_read_with_hard_stop_defaults_and_bad_values_are_refused_by_name() {
    let ok = Scene::from_toml(&scene(
        "travel = { min_m = -0.03, max_m = 0.05 }",
        "position_m = 0.0\nvelocity_m_per_s = 0.0",
    ))
    .unwrap();
    let tr = ok.rich.unwrap().model.travel.unwrap();
    assert_eq!((tr.min_m, tr.max_m), (-0.03, 0.05));
    let given = Scene::from_toml(&scene(
        "travel = { min_m = -0.03, max_m = 0.05, stop_stiffness_n_per_m = 2e4, stop_damping_ns_per_m = 3.0 }",
        "position_m = 0.0\nvelocity_m_per_s = 0.0",
    ))
    .unwrap();
    let tr = given.rich.unwrap().model.travel.unwrap();
    assert_eq!(
        (tr.stop_stiffness_n_per_m, tr.stop_damping_ns_per_m),
        (2e4, 3.0)
    );
    let cases = [
        (
            "travel = { min_m = 0.05, max_m = 0.05 }",
            "effects.travel.max_m",
        ),
        (
            "travel = { min_m = nan, max_m = 0.05 }",
            "effects.travel.min_m",
        ),
        (
            "travel = { min_m = -0.05, max_m = inf }",
            "effects.travel.max_m",
        ),
        (
            "travel = { min_m = -0.05, max_m = 0.05, stop_stiffness_n_per_m = 0.0 }",
            "effects.travel.stop_stiffness_n_per_m",
        ),
        (
            "travel = { min_m = -0.05, max_m = 0.05, stop_damping_ns_per_m = -1.0 }",
            "effects.travel.stop_damping_ns_per_m",
        ),
        (
            "travel = { min_m = -0.05, max_m = 0.05, extra = 1.0 }",
            "extra",
        ),
        ("travel = { max_m = 0.05 }", "min_m"),
    ];
    for (t, key) in cases {
        let e = Scene::from_toml(&scene(t, "position_m = 0.0\nvelocity_m_per_s = 0.0"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(key), "{t}: {e}");
    }
    let outside = Scene::from_toml(&scene(
        "travel = { min_m = -0.03, max_m = 0.05 }",
        "position_m = 0.06\nvelocity_m_per_s = 0.0",
    ))
    .unwrap_err()
    .to_string();
    assert!(outside.contains("initial.position_m"), "{outside}");
}
