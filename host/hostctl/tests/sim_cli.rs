//! End-to-end tests of `hostctl simulate` and `hostctl map` (the binary, as a user runs it).

use std::path::PathBuf;
use std::process::Command;

fn hostctl() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hostctl"))
}

fn scenes() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../sim/scenes")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("stiffwall-sim-cli-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

#[test]
fn simulate_writes_csv_with_energy_audit() {
    let out = tmp("base.csv");
    let png = tmp("base.png");
    let st = hostctl()
        .arg("simulate")
        .arg(scenes().join("base.toml"))
        .arg("--out")
        .arg(&out)
        .arg("--plot")
        .arg(&png)
        .status()
        .unwrap();
    assert!(st.success());
    let csv = std::fs::read_to_string(&out).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "period,xi,xidot,phi_a,h_t,e_d,e_g,residual"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 2001);
    for r in &rows {
        let scale = r[4].abs().max(1.0);
        assert!(r[7].abs() <= 1e-11 * scale, "residual {r:?}");
    }
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
}

#[test]
fn every_example_scene_runs() {
    for e in std::fs::read_dir(scenes()).unwrap() {
        let p = e.unwrap().path();
        let o = hostctl()
            .arg("simulate")
            .arg(&p)
            .arg("--every")
            .arg("100")
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{}: {}",
            p.display(),
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

#[test]
fn bad_scene_names_the_key_and_range() {
    let base = std::fs::read_to_string(scenes().join("base.toml")).unwrap();
    for (from, to, want) in [
        ("sigma = 1.0", "sigma = -0.5", "device.sigma"),
        ("mu = 100.0", "mu = 0.0", "device.mu"),
        ("periods = 2000", "periods = 0", "run.periods"),
        ("beta = 0.1", "beta = 0.1\nbeta_typo = 1", "beta_typo"),
        (
            "xidot = 5.0",
            "xidot = 5.0\nvelocity_m_per_s = 1",
            "initial",
        ),
        ("mu = 100.0", "mass = 1.0", "mass"),
    ] {
        let bad = tmp("bad.toml");
        std::fs::write(&bad, base.replace(from, to)).unwrap();
        let o = hostctl().arg("simulate").arg(&bad).output().unwrap();
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(want), "want {want:?} in {err}");
    }
    let bad = tmp("range.toml");
    std::fs::write(&bad, base.replace("sigma = 1.0", "sigma = -0.5")).unwrap();
    let o = hostctl().arg("simulate").arg(&bad).output().unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("allowed range is [0, 1e6]"));
}

#[test]
fn map_shards_merge_to_the_full_map() {
    let common = [
        "map",
        "--mu",
        "100",
        "--tau-d",
        "0.5",
        "--xidot0",
        "1,5",
        "--beta",
        "0:1.5:5",
        "--sigma",
        "0:2:4",
        "--periods",
        "3000",
        "--quiet",
    ];
    let full = tmp("full.json");
    assert!(hostctl()
        .args(common)
        .arg("--out")
        .arg(&full)
        .status()
        .unwrap()
        .success());
    let mut shards = Vec::new();
    for k in 0..3 {
        let s = tmp(&format!("shard{k}.json"));
        assert!(hostctl()
            .args(common)
            .arg("--shard")
            .arg(format!("{k}/3"))
            .arg("--out")
            .arg(&s)
            .status()
            .unwrap()
            .success());
        shards.push(s);
    }
    let merged = tmp("merged.json");
    let png = tmp("merged.png");
    assert!(hostctl()
        .args(["map", "merge"])
        .args(&shards)
        .arg("--out")
        .arg(&merged)
        .arg("--plot")
        .arg(&png)
        .arg("--overlay")
        .status()
        .unwrap()
        .success());
    let a: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&full).unwrap()).unwrap();
    let b: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&merged).unwrap()).unwrap();
    assert_eq!(a["panels"], b["panels"]);
    assert_eq!(a["panels"][0]["points"].as_array().unwrap().len(), 20);
    assert!(a["panels"][1]["points"][0]["class"].is_string());
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    // A missing shard is an error.
    let o = hostctl()
        .args(["map", "merge"])
        .args(&shards[..2])
        .arg("--out")
        .arg(tmp("partial.json"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing"));
}
