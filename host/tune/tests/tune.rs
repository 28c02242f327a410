//! `tune` on the virtual device with known plant parameters (issue 6 acceptance): repeatability,
//! fast against real time, static friction, impacts, a launch that cannot reach its speed. The
//! command line's refusals are `host/hostctl/tests/tune.rs`; the set K against the true
//! largest quiet K*, computed without tune's code, is `tests/tests/tune_truth.rs` (the brute
//! force lives in the tests crate).

use stiffwall_client::{spawn_virtual_device, Cancel, Client, Pace, VirtualSpec};
use stiffwall_core::params::PhysicalParams;
use stiffwall_tune::{
    impact, run_test, tune, Damping, Judging, Outcome, Settings, Test, TuneError, WallSides,
    DEFAULT_XIDOT,
};

fn preset(name: &str) -> PhysicalParams {
    stiffwall_core::devices::find(name).expect("preset").params
}

/// `tune` without progress or cancel, `dry_run` as given.
fn tune_with(c: &mut Client, s: &Settings, dry_run: bool) -> Result<Outcome, TuneError> {
    let s = Settings {
        dry_run,
        ..s.clone()
    };
    tune(c, &s, &Cancel::default(), &mut |_| {})
}

fn connect(p: PhysicalParams) -> Client {
    connect_paced(p, true)
}

fn connect_paced(p: PhysicalParams, fast: bool) -> Client {
    let counts_per_rev = if p.rotational {
        (std::f64::consts::TAU / p.resolution).round() as u32
    } else {
        0
    };
    let (vd, port) = spawn_virtual_device(VirtualSpec {
        plant: p,
        counts_per_rev,
        pace: Pace::fast_if(fast),
        initial_position: 0.0,
        output_range: None,
        scene: None,
        travel: None,
        trace: None,
    })
    .unwrap();
    Client::connect(port, Some(Box::new(vd))).unwrap()
}

#[test]
fn repeated_tunes_agree_within_5_percent_and_a_real_run_saves() {
    let truth = preset("maxon-re35");
    let a = tune_with(&mut connect(truth), &Settings::default(), true).unwrap();
    let mut c = connect(truth);
    let b = tune_with(&mut c, &Settings::default(), false).unwrap();
    assert!(
        (a.k_set / b.k_set - 1.0).abs() < 0.05,
        "{} vs {}",
        a.k_set,
        b.k_set
    );
    assert!(b.saved);
    let cfg = c.get_config().unwrap();
    assert!(
        (f64::from(cfg.stiffness) / b.k_set - 1.0).abs() < 1e-6,
        "K set on the device"
    );
}

/// Issue 10 (and 19: the same B): the same plant gives the same K in `--fast` and in real time. Every decision of
/// the tune depends on the device's counts only (tests start from rest with the wall off and
/// end at points computed from their counts), so the two runs must agree exactly, test by test.
/// A rotary rig like maxon-re35 with static friction 1.5 × Coulomb, a lightly damped 250 Hz
/// transmission and a 60 mN·m current limit: a plant the tune does not model.
const STICKY_PLANT: &str = r#"
[device]
mass_kg = 6.28e-6
viscous_ns_per_m = 9e-6
coulomb_n = 2e-3
counts_per_rev = 8192

[controller]
stiffness_n_per_m = 1.0
period_s = 1e-3
extra_delay_s = 0.0

[effects]
zoh = true
quantization = true
coulomb = true
viscous = true
delay = false
one_sided_wall = false
amplifier = { kind = "none", force_limit_n = 0.06 }
hand = { kind = "none" }
stiction = { static_n = 3.0e-3, stribeck_m_per_s = 0.0 }
transmission = { link_mass_kg = 3e-6, stiffness_n_per_m = 5.0, damping_ns_per_m = 1e-4 }
"#;

/// Connects to a virtual device, fast (true) or paced in real time.
type Connector = dyn Fn(bool) -> Client;

fn connect_plant_file(text: &str, fast: bool) -> Client {
    let dir = std::env::temp_dir().join(format!("stiffwall-tune-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("sticky.toml");
    std::fs::write(&path, text).unwrap();
    let (vd, port) =
        spawn_virtual_device(VirtualSpec::from_plant_file(&path, Pace::fast_if(fast)).unwrap())
            .unwrap();
    Client::connect(port, Some(Box::new(vd))).unwrap()
}

// Known limits: on STICKY_PLANT (a lightly damped transmission) the two modes still differ
// (1.014 vs 1.099): the link keeps ringing while the encoder is still, so "at rest" between
// tests is not a frozen state there. On delta the spring-only search's release at 14600 N/m
// from 63 ticks (0.97 of the expected limit) rests in fast mode and not in real time, so
// the two set 13334 and 12948 N/m (2.9 %): the release starts where the previous test left the
// device, within a count, and a wall that close to its limit passes or fails by that (the
// start-dependent failing bands of issue 42). Those two plants are held to 5 %.
#[test]
fn fast_and_real_time_tunes_agree_within_2_to_5_percent_on_four_plants() {
    let plants: Vec<(&str, Box<Connector>)> = vec![
        (
            "maxon-re35",
            Box::new(|f| connect_paced(preset("maxon-re35"), f)),
        ),
        (
            "phantom-1.0",
            Box::new(|f| connect_paced(preset("phantom-1.0"), f)),
        ),
        ("delta", Box::new(|f| connect_paced(preset("delta"), f))),
        // Beyond the model: breakaway 1.5 × Coulomb with Stribeck decay (the DP5 engine,
        // which integrates each period afresh, so idle ticks leave no trace).
        (
            "phantom-stiction",
            Box::new(|f| {
                let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("../../sim/plants/phantom-stiction.toml");
                connect_plant_file(&std::fs::read_to_string(path).unwrap(), f)
            }),
        ),
    ];
    // Both tunes, spring only (`--damping 0`) and the default (K, B) search: the device ends
    // every settled test itself (`PrepareTest`) and parks the wall, so the link's latency
    // changes no verdict.
    let spring_only = Settings {
        damping: Damping::Fixed(0.0),
        ..Settings::default()
    };
    for (name, connect_with) in &plants {
        for s in [&spring_only, &Settings::default()] {
            let fast = tune_with(&mut connect_with(true), s, true).unwrap();
            let started = std::time::Instant::now();
            let paced = tune_with(&mut connect_with(false), s, true).unwrap();
            eprintln!(
                "{name} ({:?}): K fast {:.6} real time {:.6}, B fast {:.4e} real time {:.4e} \
                 ({:.1} s real time), mismatch {:?}",
                s.damping,
                fast.k_set,
                paced.k_set,
                fast.b_set,
                paced.b_set,
                started.elapsed().as_secs_f64(),
                paced.model_mismatch
            );
            // Within 2 % (issue 42's bound on repeated virtual-device runs), not to the last
            // digit: a device that drifts is glided back under the host's watch, so where it
            // restarts (a count or so) follows the link's timing, and a damped search's
            // bisection can take a different branch on it.
            let share = if matches!(*name, "maxon-re35" | "phantom-1.0") {
                0.02
            } else {
                0.05
            };
            let near = |a: f64, b: f64| (a - b).abs() <= share * a.abs().max(b.abs());
            assert!(near(fast.k_set, paced.k_set), "{name}: K set");
            assert!(near(fast.b_set, paced.b_set), "{name}: B set");
            assert!(
                near(fast.k_spring_only, paced.k_spring_only),
                "{name}: spring only"
            );
            assert_eq!(fast.model_mismatch, paced.model_mismatch, "{name}");
            // Every verification test of both runs comes to the same verdict.
            let verdicts = |o: &Outcome| {
                o.verification
                    .iter()
                    .map(|r| (r.test, r.verdict))
                    .collect::<Vec<_>>()
            };
            assert_eq!(verdicts(&fast), verdicts(&paced), "{name}: verification");
        }
    }
}

/// Issue 10: a plant with static friction 1.5 × Coulomb is reported as not fitting the model,
/// and the verification adapts (smaller margin, a longer set with more energies).
#[test]
fn static_friction_is_reported_and_makes_the_verification_thorough() {
    // The spring-only tune's margins (a damped wall's is at most `DAMPED_MARGIN` anyway).
    let spring_only = Settings {
        damping: Damping::Fixed(0.0),
        ..Settings::default()
    };
    let o = tune_with(
        &mut connect_plant_file(STICKY_PLANT, true),
        &spring_only,
        true,
    )
    .unwrap();
    assert!(
        o.model_mismatch
            .iter()
            .any(|f| f.contains("static friction")),
        "{:?}",
        o.model_mismatch
    );
    assert!(o.margin_used < Settings::default().margin);
    assert!(o.verification.len() > 8, "{:?}", o.verification);
    // The rigid preset fits its own model.
    let o = tune_with(
        &mut connect(preset("maxon-re35")),
        &Settings::default(),
        true,
    )
    .unwrap();
    assert!(o.model_mismatch.is_empty(), "{:?}", o.model_mismatch);
}

/// Issue 10: the firmware's impact test on the virtual device. At K below the true limit every
/// impact of the set passes and the launch reaches the commanded speed at contact; far above
/// it an impact through the two-sided wall grows (the verdict, not only the release, fails K).
#[test]
fn impacts_from_both_sides_pass_below_the_limit_and_fail_far_above_it() {
    let truth = preset("maxon-re35");
    let mut c = connect(truth);
    let judging = Judging {
        criterion: Default::default(),
        period_s: truth.period_s,
        force_per_code: f64::from(c.info.force_per_code),
        coulomb_n: truth.coulomb,
        brake_damping: 0.0,
        window: None,
    };
    let base = stiffwall_proto::ServoConfig {
        energy_monitor: true,
        ..c.get_config().unwrap()
    };
    let v_ticks = DEFAULT_XIDOT;
    let natural = |k: f64| std::f64::consts::TAU * (truth.mass / k).sqrt() / truth.period_s;
    // The true limit of this plant at ξ̇ = 5: K*(0) = 1.316 (tests/tests/tune_truth.rs).
    for (k, sides) in [(1.0, WallSides::OneSided), (1.0, WallSides::Both)] {
        for v in [v_ticks, -v_ticks] {
            if sides == WallSides::OneSided && v < 0.0 {
                continue;
            }
            let test = impact(v, natural(k), sides);
            let run = run_test(&mut c, &base, k, test, 3000, 100, &judging).unwrap();
            let (verdict, counts) = (run.verdict, run.counts);
            assert!(verdict.passes(), "K {k} {test:?}: {verdict:?}");
            let d = run.delivered.expect("an impact that reached the wall");
            assert!(d.as_asked(), "K {k} {test:?}: the launch delivered {d:?}");
            // Entry: the first released samples move at about v ticks per tick.
            let entry = (counts[2] - counts[0]) as f64 / 2.0;
            assert!(
                (entry / v - 1.0).abs() < 0.5,
                "entry speed {entry} for {v}: {:?}",
                &counts[..10]
            );
        }
    }
    let test = impact(v_ticks, natural(3.0), WallSides::Both);
    assert!(matches!(test, Test::Impact { .. }));
    let verdict = run_test(&mut c, &base, 3.0, test, 3000, 100, &judging)
        .unwrap()
        .verdict;
    assert!(!verdict.passes(), "K = 3 (above 2 K*): {verdict:?}");
}

/// Issue 21: a current limit (0.2 N on a Phantom 1.0, a fortieth of its peak force) below what
/// the impact launch needs to bring the device to v_max: the launch arrives slower than asked.
/// Tune still sets a wall whose whole verification set passed, and says what the launch did.
const WEAK_AMPLIFIER_PLANT: &str = r#"
[device]
mass_kg = 0.072
viscous_ns_per_m = 0.005
coulomb_n = 0.038
resolution_m = 2.91e-05

[controller]
stiffness_n_per_m = 1000.0
period_s = 0.001
extra_delay_s = 0.0

[effects]
zoh = true
quantization = true
coulomb = true
viscous = true
delay = false
one_sided_wall = false
amplifier = { kind = "none", force_limit_n = 0.2 }
hand = { kind = "none" }
"#;

#[test]
fn a_launch_that_cannot_reach_the_speed_still_gets_a_verified_wall_and_a_finding() {
    for damping in [Damping::Fixed(0.0), Damping::Search] {
        let s = Settings {
            damping,
            ..Settings::default()
        };
        let mut c = connect_plant_file(WEAK_AMPLIFIER_PLANT, true);
        let o = tune_with(&mut c, &s, true).unwrap();
        assert!(o.k_set > 0.0, "{damping:?}: {o:?}");
        assert!(
            o.verification.iter().all(|r| r.verdict.passes()),
            "{damping:?}: every test of the set passed: {:?}",
            o.verification
        );
        assert!(
            o.verification
                .iter()
                .any(|r| matches!(r.test, Test::Impact { .. })),
            "{damping:?}: impacts ran"
        );
        assert!(
            o.model_mismatch
                .iter()
                .any(|f| f.contains("impact launch reached the wall at only")),
            "{damping:?}: {:?}",
            o.model_mismatch
        );
    }
}
