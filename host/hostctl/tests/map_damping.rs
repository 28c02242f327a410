//! `hostctl map --beta-v BETA_V` (issue 19, item 2): `--beta-v 0` is bit-for-bit the map
//! without the flag (JSON result and figure), a nonzero damping changes classes where the
//! exact linear analysis and the quantized spring's rest points say it must, and a bad value is
//! refused naming the flag and its range with nothing written. The old spelling `--damping`
//! is refused with a one-line hint to `--beta-v` (issue 36).

use serde_json::Value;
use std::path::PathBuf;
use std::process::{Command, Output};

fn hostctl() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hostctl"))
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "stiffwall-map-damping-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const SMALL: [&str; 11] = [
    "map",
    "--xidot0",
    "1,5",
    "--beta",
    "0:1.5:6",
    "--sigma",
    "0:2:5",
    "--periods",
    "2000",
    "--quiet",
    "--threads=2",
];

fn run(extra: &[&str]) -> Output {
    hostctl().args(SMALL).args(extra).output().unwrap()
}

fn json(path: &PathBuf) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The file without its measured (run-to-run varying) cost and wall time.
fn result_of(mut v: Value) -> Value {
    let o = v.as_object_mut().unwrap();
    o.remove("cost");
    o.remove("seconds");
    v
}

#[test]
fn damping_zero_is_the_map_without_the_flag() {
    let d = dir("zero");
    let (a, b) = (d.join("plain.json"), d.join("zero.json"));
    let (pa, pb) = (d.join("plain.svg"), d.join("zero.svg"));
    let o = run(&["--out", a.to_str().unwrap(), "--plot", pa.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&[
        "--beta-v",
        "0",
        "--out",
        b.to_str().unwrap(),
        "--plot",
        pb.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (va, vb) = (json(&a), json(&b));
    assert!(va["spec"].get("damping").is_none(), "{}", va["spec"]);
    assert_eq!(result_of(va), result_of(vb));
    assert_eq!(std::fs::read(&pa).unwrap(), std::fs::read(&pb).unwrap());
}

/// Classes at μ = 100, β = 0, ξ̇₀ = 5 for σ = 0 and σ = ½.
fn classes(damping: &str) -> Vec<String> {
    let d = dir(&format!("classes-{damping}"));
    let out = d.join("m.json");
    let o = hostctl()
        .args([
            "map",
            "--xidot0",
            "5",
            "--beta",
            "0:0:1",
            "--sigma",
            "0:0.5:2",
            "--periods",
            "20000",
            "--quiet",
            "--beta-v",
            damping,
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v = json(&out);
    if damping != "0" {
        assert_eq!(v["spec"]["damping"], 2.0);
    }
    v["panels"][0]["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["class"].as_str().unwrap().to_owned())
        .collect()
}

#[test]
fn a_damper_stops_the_growth_of_the_undamped_sampled_spring() {
    // Independent predictions: b = 0 gives K_max = 0 (every K grows, core's
    // exact_linear_stable(p, 0) is false), B = 2KT is inside the exact linear boundary
    // (exact_linear_stable(p, 2KT), checked in the sim crate; small-B estimate 2B/T = 4K).
    // With σ = 0 the quantized spring (±½ at counts 0, −1) has no rest point, so the damped
    // wall cannot decay: a persistent cycle; σ = ½ holds the mass there: decay.
    let undamped = classes("0");
    let damped = classes("2");
    let growing = "growing".to_owned();
    assert_eq!(undamped, vec![growing.clone(), growing], "{undamped:?}");
    assert_eq!(damped[0], "persistent", "{damped:?}");
    assert!(damped[1].contains("decay"), "{damped:?}");
}

#[test]
fn bad_damping_is_refused_naming_the_flag_and_range_and_nothing_is_written() {
    let d = dir("bad");
    for bad in ["-1", "NaN", "inf", "1000.5", "-0.001"] {
        let out = d.join("m.json");
        let img = d.join("m.png");
        let o = run(&[
            "--beta-v",
            bad,
            "--out",
            out.to_str().unwrap(),
            "--plot",
            img.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{bad}: {err}");
        assert!(
            err.contains("--beta-v") && err.contains("[0, 1000]"),
            "{bad}: {err}"
        );
        assert!(!out.exists() && !img.exists(), "{bad}: wrote a file");
    }
    // The spring-only overlay is refused on a damped map.
    let img = d.join("overlay.png");
    let o = run(&[
        "--beta-v",
        "1",
        "--overlay",
        "--plot",
        img.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--overlay"), "{err}");
    assert!(!img.exists());
}

#[test]
fn the_old_spelling_damping_is_refused_with_a_one_line_hint() {
    let d = dir("renamed");
    let out = d.join("m.json");
    for value in ["2", "0"] {
        let o = run(&["--damping", value, "--out", out.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(
            err.trim_end(),
            "error: `hostctl map --damping` was renamed: use `--beta-v` (the dimensionless \
             virtual damping B/(K*T))"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(!out.exists(), "wrote a file");
    }
    // The physical damper B of `analyze` keeps its name.
    let o = hostctl()
        .args(["analyze", "--device", "phantom-1.0", "--damping", "0.001"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
