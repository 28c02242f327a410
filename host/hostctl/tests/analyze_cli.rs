//! End-to-end tests of `hostctl analyze` (issue 2, part 3).

use std::process::{Command, Output};

fn hostctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .arg("analyze")
        .args(args)
        .output()
        .expect("run hostctl")
}

fn json(args: &[&str]) -> serde_json::Value {
    let mut a = args.to_vec();
    a.push("--json");
    let out = hostctl(&a);
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("valid JSON")
}

fn fails_naming(args: &[&str], needles: &[&str]) {
    let out = hostctl(args);
    assert!(!out.status.success(), "{args:?} should fail");
    let err = String::from_utf8_lossy(&out.stderr);
    for n in needles {
        assert!(err.contains(n), "{args:?}: stderr {err:?} lacks {n:?}");
    }
}

#[test]
fn phantom_preset_json() {
    let v = json(&["--device", "phantom-1.0", "--stiffness", "1015"]);
    for key in [
        "mu",
        "beta",
        "sigma",
        "tau_d",
        "region",
        "xidot_max",
        "velocity_limit_m_s",
        "k_max_passive",
        "criteria",
        "limit_cycle",
    ] {
        assert!(v.get(key).is_some(), "missing key {key}");
    }
    assert_eq!(v["region"], "E");
    assert!((v["mu"].as_f64().unwrap() - 70.936).abs() < 1e-3);
    assert!((v["sigma"].as_f64().unwrap() - 1.2865).abs() < 1e-3);
    assert!(v["limit_cycle"].is_null());
    // (15): (2c − KΔ)/(KT − 2b) = (0.076 − 0.0295365)/(1.015 − 0.01) m/s
    let vl = v["velocity_limit_m_s"].as_f64().unwrap();
    assert!(
        (vl - (0.076 - 1015.0 * 29.1e-6) / (1.015 - 0.01)).abs() < 1e-9,
        "{vl}"
    );
    assert!((v["k_max_passive"].as_f64().unwrap() - 10.0).abs() < 1e-6);
    let c = &v["criteria"];
    for name in [
        "colgate_schenkel",
        "abbott_okamura",
        "gil_avello_rubio",
        "hulin",
    ] {
        assert!(c[name]["k_max"].as_f64().unwrap() > 0.0, "{name}");
    }
    assert!(v
        .get("k_max_at_velocity")
        .is_some_and(serde_json::Value::is_null));
}

#[test]
fn velocity_and_flags_override_preset() {
    let v = json(&[
        "--device",
        "phantom-1.0",
        "--velocity",
        "0.1",
        "--stiffness",
        "500",
    ]);
    assert_eq!(v["params"]["stiffness"], 500.0);
    let k = v["k_max_at_velocity"].as_f64().unwrap();
    let expect = f64::min(
        2.0 * (0.005 * 0.1 + 0.038) / (0.1e-3 + 29.1e-6),
        2.0 * 0.038 / 29.1e-6,
    );
    assert!((k - expect).abs() < 1e-6 * expect, "{k} vs {expect}");
    // K = 500 is below K_max(0.1 m/s) ≈ 597 N/m: region E at 0.1 m/s
    assert_eq!(v["region"], "E");
    let v = json(&[
        "--device",
        "phantom-1.0",
        "--velocity",
        "0.1",
        "--stiffness",
        "1015",
    ]);
    assert_eq!(v["region"], "D");
}

#[test]
fn limit_cycle_in_region_b() {
    // β = 0.8, σ = 0.3 at K = 1000: b = 0.8 N·s/m, c = 0.3·1000·1e-5 = 3e-3 N
    let v = json(&[
        "--mass",
        "0.1",
        "--viscous",
        "0.8",
        "--coulomb",
        "0.003",
        "--resolution",
        "1e-5",
        "--period",
        "1e-3",
        "--stiffness",
        "1000",
    ]);
    assert_eq!(v["region"], "B");
    let lc = &v["limit_cycle"];
    assert!(lc["amplitude_ticks"].as_f64().unwrap() > 0.0);
    assert!(lc["frequency_hz"].as_f64().unwrap() > 0.0);
}

#[test]
fn delayed_device_gets_f_regions() {
    // β = 2, σ = 1 at τ_D = 1: F1 (β ≥ 1.5, σ ≥ σ* = 0.5 at low speed)
    let v = json(&[
        "--mass",
        "0.1",
        "--viscous",
        "2",
        "--coulomb",
        "0.01",
        "--resolution",
        "1e-5",
        "--period",
        "1e-3",
        "--stiffness",
        "1000",
        "--delay",
        "1e-3",
    ]);
    assert_eq!(v["region"], "F1");
    assert!((v["tau_d"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    let v = json(&[
        "--mass",
        "0.1",
        "--viscous",
        "2",
        "--coulomb",
        "0.01",
        "--resolution",
        "1e-5",
        "--period",
        "1e-3",
        "--stiffness",
        "1000",
        "--delay",
        "1e-3",
        "--velocity",
        "0.1",
        "--acceleration",
        "10",
    ]);
    // ξ̈ = 10·1e-6/1e-5 = 1, σ* = 0.5 + 1·2 = 2.5 > σ = 1 → F2
    assert_eq!(v["region"], "F2");
    assert!(v["k_max_delayed"].as_f64().unwrap() > 0.0);
}

#[test]
fn maxon_rotational_preset_and_counts_per_rev() {
    let v = json(&["--device", "maxon-re35", "--stiffness", "2"]);
    assert_eq!(v["params"]["rotational"], true);
    assert_eq!(v["region"], "E");
    let v2 = json(&[
        "--device",
        "maxon-re35",
        "--counts-per-rev",
        "2048",
        "--stiffness",
        "2",
    ]);
    let r = v2["params"]["resolution"].as_f64().unwrap();
    assert!((r - std::f64::consts::TAU / 2048.0).abs() < 1e-15);
    fails_naming(
        &["--device", "phantom-1.0", "--counts-per-rev", "2048"],
        &["--counts-per-rev", "rotational"],
    );
}

#[test]
fn list_devices_lists_all_presets() {
    let out = hostctl(&["--list-devices"]);
    assert!(out.status.success());
    let s = String::from_utf8_lossy(&out.stdout);
    for n in [
        "delta",
        "freedom6",
        "impulse-engine",
        "mit-toolhandle",
        "omega",
        "phantom-1.0",
        "maxon-re35",
    ] {
        assert!(s.contains(n), "{n} missing from\n{s}");
    }
}

#[test]
fn table_output_is_readable() {
    let out = hostctl(&["--device", "omega", "--stiffness", "14500"]);
    assert!(out.status.success());
    let s = String::from_utf8_lossy(&out.stdout);
    for n in [
        "Region E",
        "velocity limit (15)",
        "gil_avello_rubio",
        "colgate_schenkel",
        "μ = m/(KT²)",
    ] {
        assert!(s.contains(n), "{n} missing from\n{s}");
    }
}

#[test]
fn bad_input_names_field_and_range() {
    fails_naming(
        &["--device", "phantom-1.0", "--mass", "-1"],
        &["--mass", "[1e-9, 1e3] kg", "-1"],
    );
    fails_naming(
        &["--device", "phantom-1.0", "--period", "0"],
        &["--period", "[1e-6, 0.1] s"],
    );
    fails_naming(
        &["--device", "phantom-1.0", "--stiffness", "nan"],
        &["stiffness", "finite"],
    );
    fails_naming(
        &["--device", "phantom-1.0", "--viscous", "-0.1"],
        &["--viscous", "[0, 1e4] N·s/m"],
    );
    fails_naming(
        &["--device", "phantom-1.0", "--velocity", "inf"],
        &["velocity", "finite"],
    );
    fails_naming(
        &["--device", "phantom-2.0"],
        &["unknown device", "phantom-1.0"],
    );
    fails_naming(&["--mass", "1"], &["--viscous"]);
    fails_naming(
        &["--device", "phantom-1.0", "--plot", "/tmp/x.jpg"],
        &[".svg or .png"],
    );
}

#[test]
fn plots_svg_and_png() {
    let dir = std::env::temp_dir().join(format!("stiffwall-analyze-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (dev, file, extra) in [
        ("phantom-1.0", "p.svg", vec![]),
        (
            "omega",
            "o.png",
            vec!["--velocity", "0.01", "--delay", "0.0002"],
        ),
    ] {
        let path = dir.join(file);
        let p = path.to_str().unwrap();
        let mut args = vec!["--device", dev, "--plot", p];
        args.extend(extra);
        let out = hostctl(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let len = std::fs::metadata(&path).unwrap().len();
        assert!(len > 5_000, "{file}: {len} bytes");
    }
    let svg = std::fs::read_to_string(dir.join("p.svg")).unwrap();
    assert!(svg.contains("β = b/(KT)") && svg.contains("operating point"));
    let _ = std::fs::remove_dir_all(&dir);
}
