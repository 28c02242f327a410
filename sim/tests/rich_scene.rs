//! Scene keys of the issue-10 plant effects: every existing scene loads unchanged, the new keys
//! parse as written, bad keys and values name the key and the range, and the sampled loop of
//! `scene::simulate_sampled` reproduces the paper-model solvers on their scenes.

use stiffwall_sim::rich::PlantModel;
use stiffwall_sim::scene::{simulate_sampled, Row, Scene};

const PHYS: &str = r#"
[device]
mass_kg = 0.25
viscous_ns_per_m = 0.01
coulomb_n = 0.06
resolution_m = 20e-6
[controller]
stiffness_n_per_m = 2400.0
period_s = 1e-3
extra_delay_s = 1.25e-3
[effects]
zoh = true
quantization = true
coulomb = true
viscous = true
delay = true
one_sided_wall = false
amplifier = { kind = "none" }
hand = { kind = "none" }
[initial]
position_m = 0.0
velocity_m_per_s = 0.1
[run]
periods = 3000
solver = { kind = "exact" }
"#;

const NEW_KEYS: &str = r#"
stiction = { static_n = 0.09, stribeck_m_per_s = 0.002 }
cogging = { amplitude_n = 0.01, period_m = 0.0005 }
transmission = { link_mass_kg = 0.02, stiffness_n_per_m = 5e4, damping_ns_per_m = 2.0 }
"#;

fn with_effects(extra: &str) -> String {
    PHYS.replace(
        "hand = { kind = \"none\" }\n",
        &format!("hand = {{ kind = \"none\" }}\n{extra}"),
    )
}

fn rows(scene: &Scene) -> Vec<Row> {
    let mut v = Vec::new();
    scene.simulate(&mut |r| v.push(*r)).unwrap();
    v
}

#[test]
fn every_existing_scene_loads_unchanged() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes");
    let mut n = 0;
    for e in std::fs::read_dir(dir).unwrap() {
        let path = e.unwrap().path();
        if path.extension().is_some_and(|x| x == "toml") {
            let s = Scene::from_toml(&std::fs::read_to_string(&path).unwrap())
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            // No new effect: the paper-model solvers still run it.
            assert!(
                s.rich.is_none_or(|r| !r.needs_rich_loop()),
                "{}",
                path.display()
            );
            n += 1;
        }
    }
    assert!(n >= 7);
}

#[test]
fn new_keys_parse_as_written() {
    let text = with_effects(NEW_KEYS)
        .replace(
            "amplifier = { kind = \"none\" }",
            "amplifier = { kind = \"second_order\", cutoff_hz = 1000.0, damping = 0.7, force_limit_n = 8.5 }",
        )
        .replace("kind = \"exact\"", "kind = \"dopri\", rtol = 1e-8, atol = 1e-6");
    let s = Scene::from_toml(&text).unwrap();
    let r = s.rich.unwrap();
    assert!(r.needs_rich_loop());
    let m = r.model;
    assert_eq!(m.stiction.unwrap().static_n, 0.09);
    assert_eq!(m.cogging.unwrap().period_m, 0.0005);
    assert_eq!(m.transmission.unwrap().stiffness_n_per_m, 5e4);
    assert_eq!(m.force_limit_n(), Some(8.5));
    assert!((m.amplifier.unwrap().cutoff_hz.unwrap() - 1000.0).abs() < 1e-9);
    assert!((m.mass_kg - 0.25).abs() < 1e-15 && (m.coulomb_n - 0.06).abs() < 1e-15);
    assert_eq!(r.controller.stiffness_n_per_m, 2400.0);
    assert!((r.controller.extra_delay_s - 1.25e-3).abs() < 1e-15);
    let out = rows(&Scene { periods: 200, ..s });
    assert_eq!(out.len(), 201);
    assert!(out.iter().all(|r| r.xi.is_finite()));
}

#[test]
fn limit_and_deadband_allowed_on_every_amplifier_kind() {
    for amp in [
        "{ kind = \"none\", force_limit_n = 1.0, deadband_n = 0.001 }",
        "{ kind = \"delay\", cutoff_hz = 1000.0, damping = 0.5, force_limit_n = 1.0 }",
    ] {
        let t = PHYS.replace("{ kind = \"none\" }\nhand", &format!("{amp}\nhand"));
        let s = Scene::from_toml(&t).unwrap_or_else(|e| panic!("{amp}: {e}"));
        assert_eq!(s.rich.unwrap().model.force_limit_n(), Some(1.0));
    }
}

#[test]
fn bad_keys_and_values_name_the_key_and_range() {
    let cases: &[(String, &[&str])] = &[
        (
            with_effects("stiction = { static_n = 0.01, stribeck_m_per_s = 0.0 }\n"),
            &["effects.stiction.static_n", "0.01", "[device.coulomb_n, 1e9]"],
        ),
        (
            with_effects("stiction = { static_n = 0.1, stribeck_m_per_s = -1.0 }\n"),
            &["effects.stiction.stribeck_m_per_s", "[0, 1e3]"],
        ),
        (
            with_effects("stiction = { static_n = 0.1, stribek_m_per_s = 0.0 }\n"),
            &["stribek_m_per_s"],
        ),
        (
            with_effects("cogging = { amplitude_n = 0.01, period_m = 0.0 }\n"),
            &["effects.cogging.period_m", "(0, 1e3]"],
        ),
        (
            with_effects(
                "transmission = { link_mass_kg = -1.0, stiffness_n_per_m = 1e4, damping_ns_per_m = 0.0 }\n",
            ),
            &["effects.transmission.link_mass_kg", "(0, 1e6]"],
        ),
        (
            with_effects("transmission = { link_mass_kg = 0.1, stiffness_n_per_m = 1e4 }\n"),
            &["damping_ns_per_m"],
        ),
        (
            PHYS.replace("{ kind = \"none\" }\nhand", "{ kind = \"none\", force_limit_n = 0.0 }\nhand"),
            &["effects.amplifier.force_limit_n", "(0, 1e9]"],
        ),
        (
            PHYS.replace("{ kind = \"none\" }\nhand", "{ kind = \"none\", force_limt_n = 1.0 }\nhand"),
            &["force_limt_n"],
        ),
        (
            // Cogging is nonlinear between events: no exact engine (a transmission has one).
            with_effects("cogging = { amplitude_n = 0.01, period_m = 0.001 }\n"),
            &["run.solver"],
        ),
        (
            PHYS.replace("resolution_m = 20e-6", "resolution_m = 20e-6\ncounts_per_rev = 4096"),
            &["counts_per_rev", "resolution_m"],
        ),
        (
            PHYS.replace("resolution_m = 20e-6", "counts_per_rev = 0"),
            &["device.counts_per_rev", "[16, 1e9]"],
        ),
    ];
    for (text, needles) in cases {
        let e = Scene::from_toml(text).unwrap_err().to_string();
        for n in *needles {
            assert!(e.contains(n), "{n:?} not in {e:?}");
        }
    }
    let dimless = "[device]\nmu = 100.0\nbeta = 0.1\nsigma = 1.0\n[effects]\nzoh = true\n\
        quantization = true\ncoulomb = true\nviscous = true\ndelay = false\none_sided_wall = false\n\
        amplifier = { kind = \"none\" }\nhand = { kind = \"none\" }\n\
        cogging = { amplitude_n = 0.1, period_m = 1.0 }\n\
        [initial]\nxi = 0.0\nxidot = 5.0\n[run]\nperiods = 10\nsolver = { kind = \"exact\" }\n";
    let e = Scene::from_toml(dimless).unwrap_err().to_string();
    assert!(
        e.contains("effects.cogging") && e.contains("physical"),
        "{e}"
    );
}

#[test]
fn plant_files_need_no_initial_or_run_and_read_rotary_units() {
    let text = PHYS
        .split("[initial]")
        .next()
        .unwrap()
        .replace("resolution_m = 20e-6", "counts_per_rev = 8192");
    let (m, c) = PlantModel::from_scene_toml(&text).unwrap();
    assert_eq!(m.counts_per_rev, Some(8192));
    assert!((m.resolution_m - std::f64::consts::TAU / 8192.0).abs() < 1e-18);
    assert_eq!(c.period_s, 1e-3);
    assert!(!c.one_sided && c.quantization);
    let e = PlantModel::from_scene_toml(&text.replace("coulomb_n = 0.06", "coulomb_n = -1"))
        .unwrap_err();
    assert!(
        e.to_string().contains("device.coulomb_n") && e.to_string().contains("[0, 1e4] N"),
        "{e}"
    );
    assert!(PlantModel::from_scene_toml("[device\n").is_err());
}

/// The sampled loop with the exact engine reproduces the exact solver (delay 1.25 periods,
/// quantization, Coulomb, viscous; with and without the virtual damper) period by period: an
/// independent check of its delay line and of the damper's backward difference.
#[test]
fn sampled_loop_matches_the_exact_solver() {
    for (one_sided, damping) in [(false, 0.0), (true, 0.0), (false, 0.6), (true, 0.6)] {
        let text = PHYS
            .replace(
                "one_sided_wall = false",
                &format!("one_sided_wall = {one_sided}"),
            )
            .replace(
                "period_s = 1e-3\n",
                &format!("period_s = 1e-3\nvirtual_damping_ns_per_m = {damping:?}\n"),
            );
        let s = Scene::from_toml(&text).unwrap();
        assert!((s.beta_v - damping / 2.4).abs() < 1e-15);
        let reference = rows(&s);
        let rich = s.rich.unwrap();
        assert!(!rich.needs_rich_loop());
        let mut ours = Vec::new();
        simulate_sampled(&s, &rich, &mut |r| ours.push(*r)).unwrap();
        assert_eq!(ours.len(), reference.len());
        for (a, b) in ours.iter().zip(&reference) {
            let tol = 1e-9 * (1.0 + b.xi.abs() + b.xidot.abs());
            assert!(
                (a.xi - b.xi).abs() < tol,
                "period {}: {} vs {}",
                a.period,
                a.xi,
                b.xi
            );
            assert!((a.xidot - b.xidot).abs() < tol, "period {}", a.period);
        }
    }
}

/// With the hand of Table II and a 3 kHz filter, the loop on `RichPlant` (its own state, field
/// and bisecting driver of `dopri`) follows the reference integrator of `reference.rs` (its own
/// state, field and Illinois driver on the same Dormand–Prince kernel).
#[test]
fn sampled_loop_matches_the_reference_integrator_with_hand_and_filter() {
    let text = include_str!("../scenes/phantom-physical.toml")
        .replace("periods = 2000", "periods = 400")
        .replace("rtol = 1e-9, atol = 1e-12", "rtol = 1e-11, atol = 1e-11")
        .replace(
            "hand = { kind = \"physical\", mass_kg = 0.0, damping_ns_per_m = 0.05, stiffness_n_per_m = 0.0 }",
            "hand = { kind = \"physical\", mass_kg = 0.02, damping_ns_per_m = 0.05, stiffness_n_per_m = 50.0 }",
        );
    let s = Scene::from_toml(&text).unwrap();
    let reference = rows(&s);
    let rich = s.rich.unwrap();
    let mut ours = Vec::new();
    simulate_sampled(&s, &rich, &mut |r| ours.push(*r)).unwrap();
    assert_eq!(ours.len(), reference.len());
    let mut moved = 0.0f64;
    for (a, b) in ours.iter().zip(&reference) {
        assert!(
            (a.xi - b.xi).abs() < 1e-5,
            "period {}: {} vs {}",
            a.period,
            a.xi,
            b.xi
        );
        moved = moved.max(a.xi.abs());
    }
    assert!(moved > 1.0);
}

#[test]
fn a_plant_file_without_controller_boots_a_passive_wall_at_1_khz() {
    // Only [device] and [effects]: T = 1 ms, no extra delay, K with σ = c/(KΔ) = 4.
    let start = PHYS.find("[controller]").expect("PHYS has a controller");
    let end = PHYS[start..].find("\n[effects]").expect("effects follow") + start;
    let text = format!("{}{}", &PHYS[..start], &PHYS[end..])
        .split("[initial]")
        .next()
        .unwrap()
        .to_string();
    assert!(!text.contains("[controller]"));
    let (m, c) = PlantModel::from_scene_toml(&text).unwrap();
    assert_eq!(c.period_s, 1e-3);
    assert_eq!(c.extra_delay_s, 0.0);
    let sigma = m.coulomb_n / (c.stiffness_n_per_m * m.resolution_m);
    assert!((sigma - 4.0).abs() < 1e-9, "σ = {sigma}");
    // A file that states its controller keeps it.
    let (_, c2) = PlantModel::from_scene_toml(PHYS).unwrap();
    assert_ne!(c2.stiffness_n_per_m, c.stiffness_n_per_m);
}

/// `[controller] virtual_damping_ns_per_m` (issue 19): B of the wall, default 0, read as
/// β_v = B/(K·T) by the solvers and as the plant file's boot damping; a negative, NaN,
/// infinite or too large B is refused naming the key and its range.
#[test]
fn virtual_damping_is_read_and_checked() {
    const SNIPPET: &str = r#"
[device]
mass_kg = 0.25
viscous_ns_per_m = 0.01
coulomb_n = 0.06
resolution_m = 20e-6
[controller]
stiffness_n_per_m = 2400.0
virtual_damping_ns_per_m = 1.2
period_s = 1e-3
[effects]
zoh = true
quantization = true
coulomb = true
viscous = true
delay = false
one_sided_wall = true
amplifier = { kind = "none" }
hand = { kind = "none" }
"#;
    let (_, c) = PlantModel::from_scene_toml(SNIPPET).unwrap();
    assert_eq!(c.virtual_damping_ns_per_m, 1.2);
    let (_, c0) = PlantModel::from_scene_toml(PHYS).unwrap();
    assert_eq!(c0.virtual_damping_ns_per_m, 0.0);
    assert_eq!(Scene::from_toml(PHYS).unwrap().beta_v, 0.0);
    let damped = |b: &str| {
        PHYS.replace(
            "period_s = 1e-3\n",
            &format!("period_s = 1e-3\nvirtual_damping_ns_per_m = {b}\n"),
        )
    };
    let s = Scene::from_toml(&damped("1.2")).unwrap();
    assert!((s.beta_v - 0.5).abs() < 1e-15, "{}", s.beta_v);
    assert_eq!(s.rich.unwrap().controller.virtual_damping_ns_per_m, 1.2);
    // The damper changes the trajectory and keeps it finite.
    let (a, b) = (rows(&Scene::from_toml(PHYS).unwrap()), rows(&s));
    assert!(b.iter().all(|r| r.xi.is_finite()));
    assert!(a.iter().zip(&b).any(|(x, y)| x.xi != y.xi));
    // One message whatever the value (issue 47): the range in N·s/m and β_v ≤ 1000 together.
    let range = "in [0, 1e4] N·s/m (N·m·s/rad on a rotary device) and, with the wall's K, at \
                 most 1000 K T";
    for bad in ["-0.1", "nan", "inf", "-inf", "2e9", "2401.0"] {
        let e = Scene::from_toml(&damped(bad)).unwrap_err().to_string();
        assert!(
            e.contains("controller.virtual_damping_ns_per_m") && e.contains(range),
            "{bad}: {e}"
        );
        let e = PlantModel::from_scene_toml(&SNIPPET.replace("= 1.2", &format!("= {bad}")))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("controller.virtual_damping_ns_per_m"),
            "{bad}: {e}"
        );
    }
    // A dimensionless scene has no B in N s/m.
    let dimless = include_str!("../scenes/base.toml").replace(
        "[controller]\n",
        "[controller]\nvirtual_damping_ns_per_m = 1.0\n",
    );
    assert!(dimless.contains("virtual_damping"));
    let e = Scene::from_toml(&dimless).unwrap_err().to_string();
    assert!(e.contains("virtual_damping_ns_per_m"), "{e}");
}

/// `[controller] damper`: the virtual device's damper law, read as written (absent: `None`,
/// the firmware's default), refused naming the key and the allowed forms when misspelt or out
/// of range, and only in physical scenes. The solvers' trajectory does not depend on it.
#[test]
fn damper_law_is_read_and_checked() {
    use stiffwall_sim::rich::{WallDamper, MAX_DAMPER_DEAD_BAND};
    let with = |law: &str| {
        PHYS.replace(
            "period_s = 1e-3\n",
            &format!("period_s = 1e-3\nvirtual_damping_ns_per_m = 1.2\ndamper = {law:?}\n"),
        )
    };
    assert_eq!(PlantModel::from_scene_toml(PHYS).unwrap().1.damper, None);
    assert_eq!(MAX_DAMPER_DEAD_BAND, 8);
    for (law, want) in [
        ("difference", WallDamper::Difference),
        ("dead-band-1", WallDamper::DeadBand(1)),
        ("dead-band-8", WallDamper::DeadBand(8)),
    ] {
        let (_, c) = PlantModel::from_scene_toml(&with(law)).unwrap();
        assert_eq!(c.damper, Some(want), "{law}");
        assert_eq!(want.to_string(), law);
        let s = Scene::from_toml(&with(law)).unwrap();
        assert_eq!(s.rich.unwrap().controller.damper, Some(want));
    }
    let plain = rows(&Scene::from_toml(&with("difference")).unwrap());
    assert_eq!(
        rows(&Scene::from_toml(&with("dead-band-2")).unwrap()),
        plain
    );
    for bad in [
        "dead-band-0",
        "dead-band-9",
        "dead-band-01",
        "dead-band-",
        "dead-band-256",
        "Difference",
        "deadband-1",
        "",
    ] {
        let e = PlantModel::from_scene_toml(&with(bad))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("controller.damper")
                && e.contains(&format!("{bad:?}"))
                && e.contains("\"difference\" and \"dead-band-N\" with N in 1..=8"),
            "{bad}: {e}"
        );
    }
    // Not a string: refused by the TOML layer, naming the key.
    let e = PlantModel::from_scene_toml(
        &PHYS.replace("period_s = 1e-3\n", "period_s = 1e-3\ndamper = 1\n"),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("damper"), "{e}");
    let dimless = include_str!("../scenes/base.toml")
        .replace("[controller]\n", "[controller]\ndamper = \"difference\"\n");
    let e = Scene::from_toml(&dimless).unwrap_err().to_string();
    assert!(e.contains("damper") && e.contains("physical scenes"), "{e}");
}

/// The reference integrators run a scene's virtual damper too: Dormand–Prince on the damped
/// scene follows the exact solver on it (and not the undamped one).
#[test]
fn reference_solver_runs_the_scene_damper() {
    let damped = PHYS
        .replace(
            "period_s = 1e-3\n",
            "period_s = 1e-3\nvirtual_damping_ns_per_m = 1.2\n",
        )
        .replace("periods = 3000", "periods = 300");
    let exact = rows(&Scene::from_toml(&damped).unwrap());
    let dopri = rows(
        &Scene::from_toml(&damped.replace(
            "kind = \"exact\"",
            "kind = \"dopri\", rtol = 1e-11, atol = 1e-11",
        ))
        .unwrap(),
    );
    let undamped =
        rows(&Scene::from_toml(&PHYS.replace("periods = 3000", "periods = 300")).unwrap());
    assert_eq!(exact.len(), dopri.len());
    let worst = exact
        .iter()
        .zip(&dopri)
        .map(|(a, b)| (a.xi - b.xi).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-5, "dopri vs exact, damped: {worst}");
    assert!(exact
        .iter()
        .zip(&undamped)
        .any(|(a, b)| (a.xi - b.xi).abs() > 1e-3));
}
