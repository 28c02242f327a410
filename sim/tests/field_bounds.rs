//! Issue 47 item 5: a physical scene's or plant file's device and controller keys are refused
//! outside their field's one plausible range (`scene::field_bounds`), naming the key, the value
//! and the range, with one message per field whatever the value; every preset, every file of
//! `sim/plants/`, `sim/plants-holdout/` and `sim/scenes/` lies inside the ranges.

use stiffwall_sim::rich::PlantModel;
use stiffwall_sim::scene::field_bounds::{self as fb, FieldBounds};
use stiffwall_sim::scene::Scene;

const PHYS: &str = r#"
[device]
mass_kg = 0.25
viscous_ns_per_m = 0.01
coulomb_n = 0.06
resolution_m = 20e-6
[controller]
stiffness_n_per_m = 2400.0
period_s = 1e-3
extra_delay_s = 1e-3
virtual_damping_ns_per_m = 1.0
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
periods = 100
solver = { kind = "exact" }
"#;

/// `PHYS` with `key = old` replaced by `key = new`.
fn with(key: &str, old: &str, new: &str) -> String {
    let from = format!("{key} = {old}\n");
    assert!(PHYS.contains(&from), "{from}");
    PHYS.replace(&from, &format!("{key} = {new}\n"))
}

/// Each key beyond each of its bounds: refused naming the key, the value and the field's text,
/// the same text whichever bound (the damping's 1e4 and its 1000 K T, the delay's 0.1 s and its
/// 60 periods); a scene and a plant file say the same.
#[test]
fn each_bound_is_refused_with_the_fields_one_message() {
    let cases: [(&str, &str, &[&str], &FieldBounds); 9] = [
        (
            "mass_kg",
            "0.25",
            &["1e300", "0.0", "-1.0", "2e3"],
            &fb::MASS,
        ),
        (
            "viscous_ns_per_m",
            "0.01",
            &["-1.0", "2e4", "nan"],
            &fb::VISCOUS,
        ),
        ("coulomb_n", "0.06", &["-0.1", "1e5"], &fb::COULOMB),
        (
            "resolution_m",
            "20e-6",
            &["1.0", "0.02", "1e-11", "0.0"],
            &fb::RESOLUTION,
        ),
        (
            "stiffness_n_per_m",
            "2400.0",
            &["0.0", "1e9", "-5.0"],
            &fb::STIFFNESS,
        ),
        (
            "period_s",
            "1e-3",
            &["31557600.0", "0.2", "1e-7", "0.0"],
            &fb::PERIOD,
        ),
        // 0.1 s is within [0, 0.1] s but 100 periods: the second bound, the same message.
        (
            "extra_delay_s",
            "1e-3",
            &["-1e-3", "0.2", "0.1", "0.061"],
            &fb::DELAY,
        ),
        // 1e9 is above 1e4; 2401 is within it but above 1000 K T = 2400: one message.
        (
            "virtual_damping_ns_per_m",
            "1.0",
            &["-1.0", "1e9", "2401.0"],
            &fb::DAMPING,
        ),
        ("mass_kg", "0.25", &["inf"], &fb::MASS),
    ];
    for (key, old, bads, bounds) in cases {
        for bad in bads {
            let text = with(key, old, bad);
            for e in [
                Scene::from_toml(&text).unwrap_err().to_string(),
                PlantModel::from_scene_toml(&text).unwrap_err().to_string(),
            ] {
                assert!(e.contains(key), "{key} = {bad}: {e}");
                assert!(
                    e.ends_with(&format!("allowed range is {}", bounds.allowed)),
                    "{key} = {bad}: {e}"
                );
            }
        }
        assert!(Scene::from_toml(&with(key, old, old)).is_ok());
    }
}

/// A rotary device's encoder: 16 to 1e9 counts per revolution.
#[test]
fn counts_per_rev_is_bounded() {
    let rotary =
        |n: &str| PHYS.replace("resolution_m = 20e-6\n", &format!("counts_per_rev = {n}\n"));
    for n in ["16", "8192", "1000000000"] {
        assert!(Scene::from_toml(&rotary(n)).is_ok(), "{n}");
    }
    for n in ["15", "2000000000"] {
        let e = Scene::from_toml(&rotary(n)).unwrap_err().to_string();
        assert!(e.contains("device.counts_per_rev"), "{n}: {e}");
        assert!(e.ends_with(fb::COUNTS_PER_REV.allowed), "{n}: {e}");
    }
}

/// Every preset and every physical file of the repository lies inside the ranges.
#[test]
fn presets_and_files_are_inside() {
    for d in &stiffwall_core::devices::DEVICES {
        let p = d.params;
        let r = p.rotational;
        for (f, v) in [
            (fb::MASS, p.mass),
            (fb::VISCOUS, p.viscous),
            (fb::COULOMB, p.coulomb),
            (fb::RESOLUTION, p.resolution),
            (fb::PERIOD, p.period_s),
            (fb::STIFFNESS, p.stiffness),
        ] {
            assert!(f.check("x", v, r).is_ok(), "{}: {} = {v}", d.name, f.field);
        }
    }
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/");
    let mut n = 0;
    for dir in ["plants", "plants/travel", "plants-holdout", "scenes"] {
        for e in std::fs::read_dir(format!("{root}{dir}")).unwrap() {
            let path = e.unwrap().path();
            if path.extension().is_some_and(|x| x == "toml") {
                let text = std::fs::read_to_string(&path).unwrap();
                let ok = if dir == "scenes" {
                    Scene::from_toml(&text).map(|_| ())
                } else {
                    PlantModel::from_scene_toml(&text).map(|_| ())
                };
                assert!(ok.is_ok(), "{}: {ok:?}", path.display());
                n += 1;
            }
        }
    }
    assert!(n >= 40, "{n} files");
}
