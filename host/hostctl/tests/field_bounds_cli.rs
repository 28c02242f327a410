//! Issue 47 item 5: implausible physical flags are refused naming the flag and its field's one
//! range (`stiffwall_sim::scene::field_bounds`), the same text a plant file's key gets, and
//! nothing is written; the README's examples are inside the ranges.

use std::path::PathBuf;
use stiffwall_sim::scene::field_bounds::{self as fb, FieldBounds};

#[path = "support/cli.rs"]
mod cli;
use cli::hostctl;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("stiffwall-bounds-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

const DEVICE: [&str; 10] = [
    "--mass",
    "0.1",
    "--viscous",
    "0.01",
    "--coulomb",
    "0.05",
    "--resolution",
    "2e-5",
    "--period",
    "1e-3",
];

/// `analyze` with `DEVICE`, `flag value` (replacing the flag's value when `DEVICE` has it) and
/// `extra`, plotting to a fresh file: refused (exit 2) naming the flag, the value and the
/// field's text, and the plot is not written.
fn refused(flag: &str, value: &str, extra: &[&str], bounds: &FieldBounds) {
    let mut args: Vec<String> = vec!["analyze".into()];
    let mut given = false;
    for pair in DEVICE.chunks(2) {
        let v = if pair[0] == flag {
            given = true;
            value
        } else {
            pair[1]
        };
        args.extend([pair[0].to_string(), v.to_string()]);
    }
    if !given {
        args.extend([flag.to_string(), value.to_string()]);
    }
    args.extend(extra.iter().map(|s| (*s).to_string()));
    let plot = tmp(&format!("{}-{value}.svg", flag.trim_start_matches('-')));
    args.extend(["--plot".into(), plot.to_str().unwrap().into()]);
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = hostctl(&a);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{a:?}: {err}");
    let want = format!("{flag} must be {}", bounds.allowed);
    assert!(err.contains(&want), "{a:?}: want {want:?} in {err}");
    assert_eq!(err.matches(bounds.allowed).count(), 1, "{err}");
    assert!(
        o.stdout.is_empty() && !plot.exists(),
        "{a:?} wrote something"
    );
}

#[test]
fn each_flag_bound_is_refused_with_its_fields_range() {
    let year = "31557600";
    for (flag, bads, extra, bounds) in [
        (
            "--mass",
            &["1e300", "0", "-1", "5e-10"][..],
            &[][..],
            &fb::MASS,
        ),
        ("--viscous", &["-0.1", "1e5"], &[], &fb::VISCOUS),
        ("--coulomb", &["-1", "2e4", "nan"], &[], &fb::COULOMB),
        (
            "--resolution",
            &["1", "0.02", "1e-11"],
            &[],
            &fb::RESOLUTION,
        ),
        ("--period", &[year, "0.2", "1e-7", "0"], &[], &fb::PERIOD),
        // 0.07 s is within [0, 0.1] s but 70 periods of 1 ms: the same message.
        ("--delay", &["-1e-3", "0.2", "0.07"], &[], &fb::DELAY),
        ("--stiffness", &["0", "1e9", "inf"], &[], &fb::STIFFNESS),
        ("--velocity", &["-1", "1e3"], &[], &fb::VELOCITY),
        ("--damping", &["-1", "1e5"], &[], &fb::DAMPING),
        // 2.5 N·s/m is within [0, 1e4] but above 1000 K T = 2 at K = 2 N/m: the same message.
        ("--damping", &["2.5"], &["--stiffness", "2"], &fb::DAMPING),
    ] {
        for bad in bads {
            refused(flag, bad, extra, bounds);
        }
    }
    // A rotary encoder: counts per revolution and the resolution in rad.
    let rot = [
        "analyze",
        "--mass",
        "6e-6",
        "--viscous",
        "1e-5",
        "--coulomb",
        "2e-3",
        "--period",
        "1e-3",
        "--rotational",
    ];
    for (flag, bad, bounds) in [
        ("--counts-per-rev", "8", &fb::COUNTS_PER_REV),
        ("--counts-per-rev", "1e10", &fb::COUNTS_PER_REV),
        ("--resolution", "1", &fb::RESOLUTION),
    ] {
        let o = hostctl(&[&rot[..], &[flag, bad]].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flag} {bad}: {err}");
        assert!(
            err.contains(&format!("{flag} must be {}", bounds.allowed)),
            "{err}"
        );
    }
    assert!(hostctl(&[&rot[..], &["--resolution", "0.3"]].concat())
        .status
        .success());
}

/// A plant file's key and the flag of the same field get the same range text.
#[test]
fn a_plant_file_says_what_the_flag_says() {
    let plant = "[device]\nmass_kg = 1e300\nviscous_ns_per_m = 0.01\ncoulomb_n = 0.05\n\
                 resolution_m = 2e-5\n\n[effects]\nzoh = true\nquantization = true\ncoulomb = true\n\
                 viscous = true\ndelay = false\none_sided_wall = false\n\
                 amplifier = { kind = \"none\" }\nhand = { kind = \"none\" }\n";
    let path = tmp("heavy.toml");
    std::fs::write(&path, plant).unwrap();
    let o = hostctl(&["info", "--plant", path.to_str().unwrap(), "--fast"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains(&format!(
            "device.mass_kg = 1e300: allowed range is {}",
            fb::MASS.allowed
        )),
        "{err}"
    );
    refused("--mass", "1e300", &[], &fb::MASS);
    // The value as written, not 301 digits.
    let o = hostctl(&["analyze", "--device", "phantom-1.0", "--mass", "1e300"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("(got 1e300)"));
}

/// The README's analyze examples run.
#[test]
fn readme_examples_are_inside() {
    for args in [
        &[
            "analyze",
            "--device",
            "phantom-1.0",
            "--velocity",
            "0.1",
            "--damping",
            "2",
        ][..],
        &[
            "analyze",
            "--mass",
            "0.1",
            "--viscous",
            "0.01",
            "--coulomb",
            "0.05",
            "--resolution",
            "2e-5",
            "--period",
            "1e-3",
            "--stiffness",
            "2000",
        ],
        &[
            "analyze",
            "--device",
            "omega",
            "--stiffness",
            "8000",
            "--velocity",
            "0.05",
        ],
    ] {
        let o = hostctl(args);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}
