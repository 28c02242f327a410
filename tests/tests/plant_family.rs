//! The plant family of `sim/plants/` (issue 10, item 4) and the K* search of
//! `stiffwall_tests::kstar`: every file loads and documents itself; the family covers each
//! effect alone and in combination, linear and rotary, fast and slow servo; the search agrees
//! with the paper's exact plant, respects the paper's guaranteed bound, and can fail.

use stiffwall_core::params::PhysicalParams;
use stiffwall_sim::rich::{PlantModel, RichPlant};
use stiffwall_tests::family::{plant_files, plants_dir, PlantCase};
use stiffwall_tests::kstar::{self, Rig, Trial, TrialKind, TrialRun, DEFAULT_XIDOT};

fn cases() -> Vec<PlantCase> {
    plant_files(&plants_dir())
        .expect("sim/plants exists")
        .iter()
        .map(|p| PlantCase::load(p).unwrap_or_else(|e| panic!("{e}")))
        .collect()
}

#[test]
fn every_plant_file_loads_and_starts_with_a_comment_header() {
    let files = plant_files(&plants_dir()).unwrap();
    assert!(files.len() >= 12, "{} plant files", files.len());
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let header: Vec<&str> = text.lines().take_while(|l| l.starts_with('#')).collect();
        assert!(
            header.len() >= 3,
            "{}: a comment header saying what it models and why",
            f.display()
        );
        let case = PlantCase::load(f).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            case.model.has_new_effects()
                || case.model.hand.is_some()
                || case.model.amplifier.is_some(),
            "{}: a plant beyond the paper's model",
            case.name
        );
        // The plant is runnable: a short impact moves it.
        let mut p = case.proto;
        p.set_state(0.0, case.rig.v_max);
        p.advance(0.0, case.controller.period_s);
        assert!(p.encoder_count() >= 1, "{}: moves at v_max", case.name);
    }
}

#[test]
fn the_family_covers_each_effect_alone_and_in_combination() {
    let cases = cases();
    let effects = |c: &PlantCase| {
        let m = &c.model;
        let filter = m.amplifier.is_some_and(|a| a.cutoff_hz.is_some());
        [
            ("stiction", m.stiction.is_some()),
            ("cogging", m.cogging.is_some()),
            ("transmission", m.transmission.is_some()),
            ("amplifier filter", filter),
            ("hand", m.hand.is_some()),
        ]
    };
    for (i, name) in [
        "stiction",
        "cogging",
        "transmission",
        "amplifier filter",
        "hand",
    ]
    .iter()
    .enumerate()
    {
        let alone = cases.iter().any(|c| {
            let e = effects(c);
            e[i].1 && e.iter().filter(|x| x.1).count() == 1
        });
        assert!(alone, "{name} alone");
    }
    assert!(
        cases
            .iter()
            .any(|c| effects(c).iter().filter(|x| x.1).count() >= 4),
        "a plant with at least four effects together"
    );
    assert!(
        cases.iter().any(|c| c.model.counts_per_rev.is_some()),
        "rotary"
    );
    assert!(
        cases.iter().any(|c| c.model.counts_per_rev.is_none()),
        "linear"
    );
    assert!(
        cases.iter().any(|c| c.controller.period_s <= 0.5e-3),
        "fast servo"
    );
    assert!(
        cases.iter().any(|c| c.controller.period_s >= 2e-3),
        "slow servo"
    );
    assert!(
        cases.iter().any(|c| c.controller.one_sided),
        "one-sided wall"
    );
    assert!(cases.iter().any(|c| c.rig.delay_ticks > 0), "extra delay");
    for c in &cases {
        let m = &c.model;
        if let Some(s) = m.stiction {
            let r = s.static_n / m.coulomb_n;
            assert!((1.2..=2.0).contains(&r), "{}: static/Coulomb {r}", c.name);
        }
        if let Some(g) = m.cogging {
            let r = g.amplitude_n / m.coulomb_n;
            assert!((0.05..=0.3).contains(&r), "{}: cogging/Coulomb {r}", c.name);
        }
        if let Some(t) = m.transmission {
            let m2 = t.link_mass_kg + m.hand.map_or(0.0, |h| h.mass_kg);
            let f =
                (t.stiffness_n_per_m * (1.0 / m.mass_kg + 1.0 / m2)).sqrt() / std::f64::consts::TAU;
            let zeta = t.damping_ns_per_m
                / (2.0 * (t.stiffness_n_per_m * m.mass_kg * m2 / (m.mass_kg + m2)).sqrt());
            assert!((25.0..=300.0).contains(&f), "{}: resonance {f} Hz", c.name);
            assert!(zeta <= 0.1, "{}: lightly damped, zeta {zeta}", c.name);
        }
        if let Some(f) = m.amplifier.and_then(|a| a.cutoff_hz) {
            assert!(
                (300.0..=3000.0).contains(&f),
                "{}: amplifier {f} Hz",
                c.name
            );
        }
        assert!(
            m.force_limit_n().is_some(),
            "{}: states its amplifier's range",
            c.name
        );
    }
}

/// K* of the paper's exact plant (PhysicalPlant) and of the same plant as a RichPlant agree:
/// the rich plant without new effects is the paper's plant.
#[test]
fn k_star_of_a_rigid_rich_plant_equals_that_of_the_exact_paper_plant() {
    let p = stiffwall_core::devices::find("maxon-re35").unwrap().params;
    let rig = Rig {
        period_s: p.period_s,
        resolution_m: p.resolution,
        delay_ticks: 0,
        one_sided: false,
        free_exit: false,
        force_limit_n: 1.0,
        damping: 0.0,
        deadband_counts: 0,
        v_max: DEFAULT_XIDOT * p.resolution / p.period_s,
        moving_mass_kg: p.mass,
        wall_offsets: vec![0],
    };
    let exact =
        stiffwall_sim::PhysicalPlant::new(p.mass, p.viscous, p.coulomb, p.resolution).unwrap();
    let rich =
        RichPlant::new(&PlantModel::rigid(p.mass, p.viscous, p.coulomb, p.resolution).unwrap())
            .unwrap();
    let a = kstar::k_star(&exact, &rig, 0.5, 1e3).unwrap();
    let b = kstar::k_star(&rich, &rig, 0.5, 1e3).unwrap();
    eprintln!(
        "maxon-re35 K*: exact plant {:.5}, rich plant {:.5}",
        a.k_star, b.k_star
    );
    assert!((a.k_star / b.k_star - 1.0).abs() < 0.006, "{a:?} vs {b:?}");
}

/// The paper's worst-case criterion (12) at v_max guarantees stability: the brute-force K* of
/// the rigid Table II devices is never below it.
#[test]
fn k_star_is_not_below_the_papers_guaranteed_limit() {
    for name in ["phantom-1.0", "freedom6", "mit-toolhandle", "maxon-re35"] {
        let p: PhysicalParams = stiffwall_core::devices::find(name).unwrap().params;
        let v = DEFAULT_XIDOT * p.resolution / p.period_s;
        let guaranteed = stiffwall_core::limits::k_max_at_velocity(&p, v).unwrap();
        let rig = Rig {
            period_s: p.period_s,
            resolution_m: p.resolution,
            delay_ticks: 0,
            one_sided: false,
            free_exit: false,
            force_limit_n: 1e6,
            damping: 0.0,
            deadband_counts: 0,
            v_max: v,
            moving_mass_kg: p.mass,
            wall_offsets: vec![0],
        };
        let plant =
            stiffwall_sim::PhysicalPlant::new(p.mass, p.viscous, p.coulomb, p.resolution).unwrap();
        let k = kstar::k_star(&plant, &rig, guaranteed * 0.5, 1e9).unwrap();
        eprintln!("{name}: guaranteed {guaranteed:.4}, K* {:.4}", k.k_star);
        assert!(
            k.k_star >= guaranteed * 0.995,
            "{name}: K* {} < guaranteed {guaranteed}",
            k.k_star
        );
    }
}

#[test]
fn the_rest_verdict_fails_chatter_buzz_and_growth() {
    let run = |counts: Vec<i64>| TrialRun {
        counts,
        ..TrialRun::default()
    };
    let toggle: Vec<i64> = (0..300).map(|i| [0, -1][i % 2]).collect();
    assert!(
        !run(toggle.clone()).rests(),
        "toggling between two counts for ever is chatter, not rest"
    );
    assert!(
        run(toggle).within_one_count(),
        "but it stays within one count"
    );
    // Two changes in the window (one excursion and back) still rest; four do not.
    let mut blip = vec![0i64; 300];
    blip[280] = 1;
    assert!(run(blip.clone()).rests());
    blip[290] = 1;
    assert!(!run(blip).rests());
    let buzz: Vec<i64> = (0..300).map(|i| [1, -1, -2, 0][i % 4]).collect();
    assert!(
        !run(buzz).rests(),
        "a persistent 3-count oscillation is buzz"
    );
    let grow: Vec<i64> = (0..300)
        .map(|i| if i % 2 == 0 { i / 10 } else { -(i / 10) })
        .collect();
    assert!(!run(grow).rests());
    let mut stop: Vec<i64> = (0..100).map(|i| 50 - i / 2).collect();
    stop.extend([0; 200]);
    assert!(run(stop).rests());
    assert!(!TrialRun {
        counts: vec![0; 300],
        ran_away: true,
        ..TrialRun::default()
    }
    .rests());
    // One-sided wall: leaving no faster than a passive wall would return passes, faster fails.
    let left = |v: f64| TrialRun {
        counts: vec![3, 1, -2],
        exit: Some((v, 0.1)),
        ..TrialRun::default()
    };
    assert!(left(0.09).rests());
    assert!(!left(0.11).rests());
}

/// The criterion fails a plant that is unstable (region C of Fig. 3: β, σ < ½) and the trial that
/// fails first is reported.
#[test]
fn an_unstable_stiffness_fails_and_a_stable_one_settles() {
    // μ = 100, β = 0.1, σ = 0.2 at K = 1000 N/m, T = 1 ms, Δ = 10 µm.
    let (k, t, d) = (1000.0, 1e-3, 1e-5);
    let plant =
        stiffwall_sim::PhysicalPlant::new(100.0 * k * t * t, 0.1 * k * t, 0.2 * k * d, d).unwrap();
    let rig = Rig {
        period_s: t,
        resolution_m: d,
        delay_ticks: 0,
        one_sided: false,
        free_exit: false,
        force_limit_n: 1e3,
        damping: 0.0,
        deadband_counts: 0,
        v_max: DEFAULT_XIDOT * d / t,
        moving_mass_kg: 0.1,
        wall_offsets: vec![0],
    };
    let (trial, r) = kstar::first_failure(&plant, &rig, k).expect("region C fails");
    assert!(!r.rests());
    eprintln!("region C: first failing trial {trial:?}, peak {}", r.peak());
    // σ = 4 at K = 50 N/m: Coulomb friction stops every trial.
    assert_eq!(kstar::first_failure(&plant, &rig, 50.0), None);
    let imp = kstar::run_trial(
        &plant,
        &rig,
        50.0,
        Trial {
            wall: 0,
            side: -1,
            kind: TrialKind::Impact {
                velocity_m_per_s: rig.v_max,
            },
        },
    );
    // v_max = 5 counts per period: the first periods go almost 5 counts deeper each (friction
    // and the spring slow it a little), below the wall.
    let c = &imp.counts;
    assert!(
        c[0] == -1 && c[1] < c[0] && c[2] < c[1] && c[2] <= -8,
        "{:?}",
        &c[..3]
    );
}
