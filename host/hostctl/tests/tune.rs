//! `hostctl tune`'s refusals of bad input, naming the flags (the procedure itself is tested
//! with its crate, `host/tune/tests/tune.rs`).

use stiffwall_client::{spawn_virtual_device, Cancel, Client, Pace, VirtualSpec};
use stiffwall_core::params::PhysicalParams;
use stiffwall_tune::{tune, Damping, Outcome, Settings, TuneError};

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
fn bad_max_velocity_is_refused_before_touching_the_device() {
    let bin = env!("CARGO_BIN_EXE_hostctl");
    for v in ["0", "NaN", "-1", "inf", "1e300"] {
        let out = std::process::Command::new(bin)
            .args(["tune", "--fast", "--dry-run", "--max-velocity", v])
            .output()
            .unwrap();
        assert!(!out.status.success(), "{v}");
        let err = String::from_utf8_lossy(&out.stderr);
        // The field's one range (issue 47), the refused value as given (not 301 digits).
        assert!(
            err.contains(
                "--max-velocity must be finite and in [0, 100] m/s, or [0, 1e4] rad/s on a \
                 rotary device, and > 0 (got "
            ) && err.contains(&format!("(got {v})").replace("NaN", "NaN")),
            "{v}: {err}"
        );
        assert!(
            !err.contains("connecting"),
            "refused before connecting: {err}"
        );
    }
    let mut c = connect(preset("maxon-re35"));
    let before = c.get_config().unwrap();
    let s = Settings {
        max_velocity: Some(0.0),
        ..Settings::default()
    };
    assert!(tune_with(&mut c, &s, false).is_err());
    assert_eq!(c.get_config().unwrap(), before);
    // 500 passes as rad/s but not as m/s: a linear device refuses it once connected, before
    // any test, with the field's one message.
    let mut c = connect(preset("phantom-1.0"));
    let before = c.get_config().unwrap();
    let s = Settings {
        max_velocity: Some(500.0),
        ..Settings::default()
    };
    let e = tune_with(&mut c, &s, false).unwrap_err().to_string();
    assert!(e.contains("[0, 100] m/s") && e.contains("got 500"), "{e}");
    assert_eq!(c.get_config().unwrap(), before);
}

/// Issue 19: a negative, NaN or infinite `--damping` is refused before connecting, naming the
/// flag and its range; one above the firmware's limit is refused before any test, and the
/// device's config is unchanged.
#[test]
fn a_bad_damper_law_is_refused_naming_the_flag_and_the_allowed_forms() {
    let bin = env!("CARGO_BIN_EXE_hostctl");
    for law in ["dead-band-0", "dead-band-9", "deadband-1", "Difference", ""] {
        let out = std::process::Command::new(bin)
            .args(["tune", "--fast", "--dry-run", "--damper", law])
            .output()
            .unwrap();
        assert!(!out.status.success(), "{law}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--damper"), "{law}: {err}");
        assert!(err.contains("1..=8"), "{law}: {err}");
        assert!(
            !err.contains("connecting"),
            "{law}: refused after connecting: {err}"
        );
    }
}

/// `--accept-chatter` with the plain difference on the default device: the old criterion, whose
/// damped wall chatters (the README's former default), reported test by test; the default
/// criterion's wall rests.
#[test]
fn accept_chatter_reports_the_chatter_it_accepted() {
    let bin = env!("CARGO_BIN_EXE_hostctl");
    let json = |args: &[&str]| -> serde_json::Value {
        let out = std::process::Command::new(bin)
            .args(["tune", "--fast", "--dry-run", "--json"])
            .args(args)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let loud = json(&["--accept-chatter", "--damper", "difference"]);
    let t = &loud["tune"];
    assert_eq!(t["criterion"], "accept-chatter");
    assert_eq!(t["damper"], "difference");
    let chattering: Vec<&serde_json::Value> = t["verification"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["verdict"] == "chatter-accepted")
        .collect();
    // The wall it sets is the former default (4.0776 N·m/rad, B = 5.2791e-3), which an
    // independent simulator found toggling at up to 500 per second with a 5.6 c force swing.
    assert!(!chattering.is_empty(), "{t}");
    assert_eq!(t["rests"], false, "{t}");
    for r in &chattering {
        assert!(r["chatter"]["toggles_per_s"].as_f64().unwrap() > 0.0, "{r}");
        assert!(r["chatter"]["force_pp_c"].as_f64().unwrap() > 0.0, "{r}");
    }
    let quiet = json(&[]);
    assert_eq!(quiet["tune"]["rests"], true, "{}", quiet["tune"]);
    assert_eq!(quiet["tune"]["criterion"], "rest");
}

#[test]
fn bad_damping_is_refused_naming_the_flag_and_its_range() {
    let bin = env!("CARGO_BIN_EXE_hostctl");
    for b in ["-1", "NaN", "inf", "-0.001"] {
        let out = std::process::Command::new(bin)
            .args(["tune", "--fast", "--dry-run", "--damping", b])
            .output()
            .unwrap();
        assert!(!out.status.success(), "{b}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(
                "--damping must be finite, in [0, 1e4] N·s/m (N·m·s/rad on a rotary device)"
            ),
            "{b}: {err}"
        );
        assert!(
            !err.contains("connecting"),
            "{b}: refused after connecting: {err}"
        );
    }
    let mut c = connect(preset("maxon-re35"));
    let before = c.get_config().unwrap();
    let s = Settings {
        damping: Damping::Fixed(1.0),
        ..Settings::default()
    };
    let mut tests = 0;
    let e = tune(&mut c, &s, &Cancel::default(), &mut |_| tests += 1).unwrap_err();
    match &e {
        TuneError::Settings(s) => {
            assert_eq!(s.field, "damping");
            assert!(s.range.starts_with("within [0, "), "{e}");
        }
        other => panic!("{other:?}"),
    }
    // The CLI names the flag.
    let e = stiffwall_host::cmd::tune::flag_error(match &e {
        TuneError::Settings(s) => s,
        _ => unreachable!(),
    });
    assert!(e.contains("--damping must be within [0, "), "{e}");
    assert_eq!(tests, 0, "refused before any test");
    assert_eq!(c.get_config().unwrap(), before);
}
