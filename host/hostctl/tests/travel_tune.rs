//! A device with a workspace (issue 46), end to end with the real `hostctl` binary and the
//! built-in virtual device: a tune that sets and saves its wall (no `--dry-run`) on a preset
//! with published travel and on plant files with end stops. Judged by the plant's true state
//! (`--trace`), not the encoder: the trace never leaves the travel and never touches a stop
//! (contact force 0 on every tick), and the report's final check (`tune.device_left`) says the
//! device was left at rest, without a fault, within two counts of where it started.

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Runs `hostctl tune --fast --json --trace` with `target` (device options); returns the JSON
/// report and the trace's (position, stop force) rows.
fn tune(target: &[&str], name: &str) -> (serde_json::Value, Vec<(f64, f64)>) {
    let (report, rows, _) = tune_with_progress(target, name);
    (report, rows)
}

/// [`tune`], with the progress lines it printed (stderr) too.
fn tune_with_progress(target: &[&str], name: &str) -> (serde_json::Value, Vec<(f64, f64)>, String) {
    let trace = std::env::temp_dir().join(format!(
        "stiffwall-travel-{name}-{}.csv",
        std::process::id()
    ));
    let trace_arg = trace.to_str().unwrap().to_string();
    let mut args = vec!["tune", "--fast", "--json", "--trace", trace_arg.as_str()];
    args.extend_from_slice(target);
    let out = Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .args(&args)
        .current_dir(repo())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{name}: {stderr}");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let text = std::fs::read_to_string(&trace).unwrap();
    std::fs::remove_file(&trace).ok();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("t_s,position_m,velocity_m_per_s,stop_force_n,count,force_cmd_n")
    );
    let rows = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[1].parse().unwrap(), f[3].parse().unwrap())
        })
        .collect();
    (report, rows, stderr)
}

/// The report's final check and the trace against the travel [lo, hi] (m or rad).
fn check(name: &str, report: &serde_json::Value, rows: &[(f64, f64)], travel: [f64; 2]) {
    let left = &report["tune"]["device_left"];
    assert_eq!(left["ok"], true, "{name}: {left}");
    assert_eq!(left["at_rest"], true, "{name}: {left}");
    assert_eq!(
        left["faults"].as_array().map(Vec::len),
        Some(0),
        "{name}: {left}"
    );
    let moved = left["count"].as_i64().unwrap() - left["start"].as_i64().unwrap();
    assert!(moved.abs() <= 2, "{name}: {left}");
    assert_eq!(report["tune"]["saved"], true, "{name}: saved");
    assert!(rows.len() > 10_000, "{name}: a trace of every tick");
    let (lo, hi) = rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
            (a.min(r.0), b.max(r.0))
        });
    assert!(
        lo > travel[0] && hi < travel[1],
        "{name}: trace {lo}..{hi}, travel {travel:?}"
    );
    assert!(
        rows.iter().all(|r| r.1 == 0.0),
        "{name}: an end stop was touched"
    );
    eprintln!("{name}: trace {lo:.4e}..{hi:.4e} of {travel:?}, left {left}");
}

#[test]
fn a_saved_tune_on_the_phantom_stays_inside_its_travel_and_leaves_it_where_it_was() {
    let (report, rows) = tune(&["--device", "phantom-1.0"], "phantom");
    check("phantom-1.0", &report, &rows, [-0.065, 0.065]);
}

#[test]
fn a_saved_tune_on_the_default_rig_comes_back_to_its_start() {
    let (report, rows) = tune(&[], "maxon");
    // maxon-re35 turns freely: the default window of one turn each way.
    let turn = std::f64::consts::TAU;
    check("maxon-re35", &report, &rows, [-turn, turn]);
}

#[test]
fn plants_with_end_stops_are_tuned_without_touching_them() {
    for (file, travel) in [
        ("linear-3cm-stops.toml", [-0.03, 0.03]),
        ("rotary-knob-135deg.toml", [-2.356, 2.356]),
    ] {
        let path = format!("sim/plants/{file}");
        let (report, rows) = tune(&["--plant", path.as_str()], file);
        check(file, &report, &rows, travel);
    }
}

/// A travel too short for a full-energy release at the default maximum velocity (hard stops
/// 4 mm each side): tune lowers the velocity, says which tests need how much travel, and still
/// never touches a stop.
#[test]
fn a_travel_too_short_for_the_default_velocity_lowers_it_and_says_so() {
    let path = "sim/plants/travel/linear-short-travel.toml";
    let (report, rows, progress) = tune_with_progress(&["--plant", path], "short");
    assert!(
        progress.contains("need") && progress.contains("the maximum velocity is lowered to"),
        "{progress}"
    );
    check("linear-short-travel", &report, &rows, [-0.004, 0.004]);
}
