//! `hostctl map` with cycle detection (the default) against `--no-cycle-detection`: the same
//! points, field by field, and the JSON key `cost.cycle_points` counts the points that ended
//! by cycle detection (0 without it; summed by `map merge`).

use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("stiffwall-map-cycles-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Part of Fig. 6 on the paper's grid (β 0–1.2 × 21, σ 0–2 × 34): its region-B corner,
/// where the persistent limit cycles are, at the paper's horizon.
const MAP: [&str; 14] = [
    "map",
    "--mu",
    "100",
    "--xidot0",
    "1,5",
    "--beta",
    "0.42:1.2:14",
    "--sigma",
    "0:0.3:6",
    "--periods",
    "50000",
    "--quiet",
    "--threads",
    "2",
];

fn run(out: &PathBuf, extra: &[&str]) -> Value {
    let o = Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .args(MAP)
        .args(extra)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap()
}

#[test]
fn cycle_detection_changes_no_point_and_is_counted() {
    let d = dir();
    let on = run(&d.join("on.json"), &[]);
    let off = run(&d.join("off.json"), &["--no-cycle-detection"]);
    assert_eq!(on["panels"], off["panels"]);
    assert_eq!(off["cost"]["cycle_points"], 0);
    let n = on["cost"]["cycle_points"].as_u64().unwrap();
    assert!(n > 0, "no point ended by cycle detection");
    // Shards count their own points; the merge sums them.
    let shards: Vec<PathBuf> = (0..2)
        .map(|k| {
            let s = d.join(format!("s{k}.json"));
            run(&s, &["--shard", &format!("{k}/2")]);
            s
        })
        .collect();
    let merged = d.join("merged.json");
    let o = Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .args(["map", "merge"])
        .args(&shards)
        .arg("--out")
        .arg(&merged)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: Value = serde_json::from_str(&std::fs::read_to_string(&merged).unwrap()).unwrap();
    assert_eq!(m["panels"], on["panels"]);
    assert_eq!(m["cost"]["cycle_points"].as_u64(), Some(n));
    let _ = std::fs::remove_dir_all(&d);
}
