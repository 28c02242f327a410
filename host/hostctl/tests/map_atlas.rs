//! `hostctl map` with slice axes (issue 13): shards of a μ × τ_D × ξ̇₀ sweep merge to the
//! single-process map point for point, every point carries its cost, and `map atlas` writes its
//! JSON, Markdown and one figure per slice plus a summary.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn hostctl() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hostctl"))
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("stiffwall-map-atlas-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const SWEEP: [&str; 15] = [
    "map",
    "--mu",
    "1:100:3:log",
    "--tau-d",
    "0,1.25",
    "--xidot0",
    "1,5",
    "--beta",
    "0:2:5",
    "--sigma",
    "0:2:4",
    "--periods",
    "400",
    "--quiet",
    "--threads=2",
];

fn run(args: &[&str], out: &Path) {
    let o = hostctl().args(args).arg("--out").arg(out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn json(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn slice_axes_shard_merge_to_the_single_process_map_with_costs() {
    let d = dir("shards");
    let full = d.join("full.json");
    run(&SWEEP, &full);
    let mut shards = Vec::new();
    for k in [3, 0, 4, 2, 1] {
        let s = d.join(format!("s{k}.json"));
        let mut a = SWEEP.to_vec();
        let shard = format!("{k}/5");
        a.extend(["--shard", &shard]);
        run(&a, &s);
        shards.push(s);
    }
    let merged = d.join("merged.json");
    let o = hostctl()
        .args(["map", "merge"])
        .args(&shards)
        .arg("--out")
        .arg(&merged)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (a, b) = (json(&full), json(&merged));
    // 3 mu x 2 tau_d x 2 xidot0 panels, slice-major, 20 points each, identical results.
    let panels = a["panels"].as_array().unwrap();
    assert_eq!(panels.len(), 12);
    assert_eq!(a["panels"], b["panels"]);
    let keys: Vec<(f64, f64, f64)> = panels
        .iter()
        .map(|p| {
            (
                p["mu"].as_f64().unwrap(),
                p["tau_d"].as_f64().unwrap(),
                p["xidot0"].as_f64().unwrap(),
            )
        })
        .collect();
    assert_eq!(keys[0], (1.0, 0.0, 1.0));
    assert_eq!(keys[1], (1.0, 0.0, 5.0));
    assert_eq!(keys[2], (1.0, 1.25, 1.0));
    assert!((keys[4].0 - 10.0).abs() < 1e-12, "{keys:?}");
    assert_eq!(keys[11], (100.0, 1.25, 5.0));
    assert_eq!(a["spec"]["mu"]["log"], true);
    // Cost: one ns/period per point, and the totals add up over the shards.
    for m in [&a, &b] {
        let cost = &m["cost"];
        let ns = cost["ns_per_period"].as_array().unwrap();
        assert_eq!(ns.len(), 12);
        let mut periods = 0u64;
        for (p, c) in panels.iter().zip(ns) {
            let c = c.as_array().unwrap();
            assert_eq!(c.len(), 20);
            assert!(c.iter().all(|x| x.as_f64().unwrap() > 0.0));
            for q in p["points"].as_array().unwrap() {
                periods += q["periods_run"].as_u64().unwrap();
            }
        }
        assert_eq!(cost["periods_total"].as_u64(), Some(periods));
        assert!(cost["ns_per_period_mean"].as_f64().unwrap() > 0.0);
        assert!(cost["core_seconds"].as_f64().unwrap() > 0.0);
        // CPU time as Linux counts it (10 ms ticks, so possibly 0 for this small sweep).
        if cfg!(target_os = "linux") {
            assert!(cost["cpu_seconds"].as_f64().unwrap() >= 0.0, "{cost}");
        }
    }
    // A shard of another slice axis is another sweep.
    let other = d.join("other.json");
    let mut o_args = SWEEP.to_vec();
    o_args[2] = "1:100:3";
    o_args.extend(["--shard", "1/5"]);
    run(&o_args, &other);
    let mut set = shards.clone();
    set[4] = other;
    let o = hostctl()
        .args(["map", "merge"])
        .args(&set)
        .arg("--out")
        .arg(d.join("bad.json"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("mu differs"), "{err}");
    // An edited cost total is refused.
    let mut v = json(&shards[0]);
    v["cost"]["periods_total"] = 1.into();
    let edited = d.join("edited.json");
    std::fs::write(&edited, serde_json::to_string(&v).unwrap()).unwrap();
    let mut set = shards.clone();
    set[0] = edited;
    let o = hostctl()
        .args(["map", "merge"])
        .args(&set)
        .arg("--out")
        .arg(d.join("bad.json"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("cost.periods_total = 1"), "{err}");
}

#[test]
fn atlas_writes_json_markdown_and_a_figure_per_slice() {
    let d = dir("atlas");
    let full = d.join("full.json");
    let mut a = SWEEP.to_vec();
    a[6] = "5";
    run(&a, &full);
    let (out, md, plots) = (d.join("atlas.json"), d.join("atlas.md"), d.join("fig"));
    let o = hostctl()
        .args(["map", "atlas"])
        .arg(&full)
        .arg("--out")
        .arg(&out)
        .arg("--markdown")
        .arg(&md)
        .arg("--plots")
        .arg(&plots)
        .args(["--generated-by", "hostctl map atlas full.json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let atlas = json(&out);
    let panels = atlas["panels"].as_array().unwrap();
    assert_eq!(panels.len(), 6);
    for p in panels {
        let ag = p["agreement"].as_array().unwrap();
        let names: Vec<&str> = ag.iter().map(|x| x["line"].as_str().unwrap()).collect();
        assert_eq!(names, ["worst_case", "df_72", "df_74", "linear_exact"]);
        for x in ag {
            let f = x["fraction"].as_f64().unwrap();
            assert!((0.0..=1.0).contains(&f));
            let sum = x["correct"].as_u64().unwrap()
                + x["false_growth"].as_u64().unwrap()
                + x["missed_growth"].as_u64().unwrap();
            assert_eq!(sum, 20);
        }
    }
    let text = std::fs::read_to_string(&md).unwrap();
    assert!(text.contains("hostctl map atlas full.json"), "{text}");
    assert!(text.contains("](fig/atlas-summary.png)"), "{text}");
    assert!(
        text.contains("[png](fig/atlas-mu10.0000-tau1.25-xidot5.png)"),
        "{text}"
    );
    assert_eq!(text.matches("\n| ").count(), 6 + 2, "{text}");
    let figs = std::fs::read_dir(&plots).unwrap().count();
    assert_eq!(figs, 7);
    assert!(
        std::fs::metadata(plots.join("atlas-summary.png"))
            .unwrap()
            .len()
            > 5000
    );
    // A shard is refused.
    let s = d.join("shard.json");
    let mut sa = a.clone();
    sa.extend(["--shard", "0/2"]);
    run(&sa, &s);
    let o = hostctl().args(["map", "atlas"]).arg(&s).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("merge the shards first"));
}
