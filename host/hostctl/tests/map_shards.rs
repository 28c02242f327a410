//! `hostctl map --shard` and `map merge` against hostile or broken shard files (issues 11, 13):
//! every refusal case of `map merge`, resume, an interrupted shard, order independence, and
//! the bounds of `map`'s flags. Each refusal must be a clean error (exit 2), never a panic.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn hostctl() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hostctl"))
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "stiffwall-map-shards-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const COMMON: [&str; 12] = [
    "map",
    "--mu",
    "100",
    "--xidot0",
    "1,5",
    "--beta",
    "0:1.5:5",
    "--sigma",
    "0:2:4",
    "--periods",
    "500",
    "--quiet",
];

fn make_shards(d: &Path, n: usize, extra: &[&str]) -> Vec<PathBuf> {
    (0..n)
        .map(|k| {
            let s = d.join(format!("shard{k}.json"));
            let o = hostctl()
                .args(COMMON)
                .args(extra)
                .arg("--shard")
                .arg(format!("{k}/{n}"))
                .arg("--out")
                .arg(&s)
                .output()
                .unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            s
        })
        .collect()
}

fn merge(inputs: &[PathBuf], out: &Path) -> Output {
    hostctl()
        .args(["map", "merge"])
        .args(inputs)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

/// Merge must fail cleanly (exit 2, not a panic's 101) with `want` in the message.
fn refused(inputs: &[PathBuf], d: &Path, want: &str) {
    let out = d.join("merged-refused.json");
    let o = merge(inputs, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "want a clean refusal, got: {err}");
    assert!(err.contains(want), "want {want:?} in: {err}");
    assert!(!out.exists(), "a refused merge must not write its output");
}

/// An edit of a shard file's JSON.
type Edit = dyn Fn(&mut Value);

fn edit(src: &Path, dst: &Path, f: impl FnOnce(&mut Value)) -> PathBuf {
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(src).unwrap()).unwrap();
    f(&mut v);
    std::fs::write(dst, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    dst.to_path_buf()
}

#[test]
fn merge_is_order_independent_and_refuses_every_bad_set_of_shards() {
    let d = dir("refuse");
    let s = make_shards(&d, 3, &[]);
    // Order does not matter: byte-identical results.
    let (m1, m2) = (d.join("m1.json"), d.join("m2.json"));
    assert!(merge(&s, &m1).status.success());
    let rev = vec![s[2].clone(), s[0].clone(), s[1].clone()];
    assert!(merge(&rev, &m2).status.success());
    assert_eq!(std::fs::read(&m1).unwrap(), std::fs::read(&m2).unwrap());

    // Duplicate and missing shards.
    refused(
        &[s[0].clone(), s[1].clone(), s[0].clone(), s[2].clone()],
        &d,
        "shard 0/3 given twice",
    );
    refused(&s[..2], &d, "missing shards: 2/3");
    // Shards of different splits.
    let other = make_shards(&dir("refuse-other"), 2, &[]);
    refused(&[s[0].clone(), other[1].clone()], &d, "a shard of 3");
    // A mismatched sweep (another delay-line history), named by field.
    let zero = make_shards(&dir("refuse-zero"), 3, &["--history", "zero"]);
    refused(
        &[s[0].clone(), s[1].clone(), zero[2].clone()],
        &d,
        "history differs",
    );
    // A truncated file.
    let text = std::fs::read_to_string(&s[1]).unwrap();
    let cut = d.join("cut.json");
    std::fs::write(&cut, &text[..text.len() / 2]).unwrap();
    refused(&[s[0].clone(), cut, s[2].clone()], &d, "truncated");

    // Edited files: shard index out of range, n = 0, n = 1e18, periods = 0, a huge grid, an extra panel,
    // a point contradicting its index, a dropped point, an edited spec with a stale hash.
    let cases: Vec<(&str, Box<Edit>)> = vec![
        (
            "need 0 <= k < n",
            Box::new(|v| v["shard"] = serde_json::json!([5, 3])),
        ),
        (
            "need 0 <= k < n",
            Box::new(|v| v["shard"] = serde_json::json!([1, 0])),
        ),
        (
            "1 <= n <= 100000",
            Box::new(|v| v["shard"] = serde_json::json!([0, 1_000_000_000_000_000_000u64])),
        ),
        ("periods = 0", Box::new(|v| v["spec"]["periods"] = 0.into())),
        (
            "n = 1000000000",
            Box::new(|v| {
                v["spec"]["beta"]["n"] = 1_000_000_000u64.into();
                v["spec"]["sigma"]["n"] = 1_000_000_000u64.into();
            }),
        ),
        (
            "3 panels, but the spec has 2",
            Box::new(|v| {
                let p = v["panels"][0].clone();
                v["panels"].as_array_mut().unwrap().push(p);
            }),
        ),
        (
            "contradict its index",
            Box::new(|v| v["panels"][1]["points"][2]["beta"] = 0.123.into()),
        ),
        (
            "points; shard 1/3 of a 20-point grid has 7",
            Box::new(|v| {
                v["panels"][0]["points"].as_array_mut().unwrap().pop();
            }),
        ),
        ("spec_crc64", Box::new(|v| v["spec"]["mu"] = 101.0.into())),
    ];
    for (i, (want, f)) in cases.iter().enumerate() {
        let bad = edit(&s[1], &d.join(format!("bad{i}.json")), f);
        refused(&[s[0].clone(), bad, s[2].clone()], &d, want);
    }
}

#[test]
fn rerunning_a_complete_shard_is_a_no_op_and_force_recomputes() {
    let d = dir("resume");
    let s = make_shards(&d, 2, &[]);
    let before = std::fs::read(&s[1]).unwrap();
    let o = hostctl()
        .args(COMMON)
        .args(["--shard", "1/2", "--out"])
        .arg(&s[1])
        .output()
        .unwrap();
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("nothing to do"), "{err}");
    assert!(!err.contains("computed in"), "{err}");
    assert_eq!(std::fs::read(&s[1]).unwrap(), before);
    // A truncated result is not "complete": it is recomputed.
    std::fs::write(&s[1], &before[..before.len() / 3]).unwrap();
    let o = hostctl()
        .args(COMMON)
        .args(["--shard", "1/2", "--out"])
        .arg(&s[1])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("computed in"));
    assert!(merge(&s, &d.join("m.json")).status.success());
    // --force recomputes a complete one.
    let o = hostctl()
        .args(COMMON)
        .args(["--shard", "1/2", "--force", "--out"])
        .arg(&s[1])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("computed in"));
}

#[test]
fn a_killed_shard_leaves_no_file_merge_accepts() {
    let d = dir("killed");
    let done = make_shards(&d, 2, &[]);
    std::fs::remove_file(&done[1]).unwrap();
    // A long shard, killed mid-run.
    let mut child = hostctl()
        .args([
            "map", "--mu", "100", "--xidot0", "5", "--beta", "0:1:40", "--sigma", "0:2:40",
        ])
        .args([
            "--periods",
            "20000000",
            "--quiet",
            "--threads",
            "1",
            "--shard",
            "1/2",
        ])
        .arg("--out")
        .arg(&done[1])
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        !done[1].exists(),
        "a killed shard must not leave its output file"
    );
    // Whatever it left in the directory, merge accepts no set including it.
    for entry in std::fs::read_dir(&d).unwrap() {
        let p = entry.unwrap().path();
        if p != done[0] {
            let o = merge(&[done[0].clone(), p.clone()], &d.join("m.json"));
            assert!(!o.status.success(), "merge accepted {}", p.display());
        }
    }
}

#[test]
fn map_flags_are_bounded_and_negative_values_name_their_flag() {
    let cases: [(&[&str], &str); 4] = [
        (
            &["--threads", "100000"],
            "--threads 100000: allowed range is [1, ",
        ),
        (&["--threads", "0"], "--threads 0: allowed range is [1, "),
        (&["--mu", "-1"], "--mu -1: allowed range is > 0"),
        (
            &["--tau-d", "-0.5"],
            "--tau-d -0.5: allowed range is [0, 250]",
        ),
    ];
    for (flags, want) in cases {
        let o = hostctl()
            .args([
                "map",
                "--beta",
                "0:1:2",
                "--sigma",
                "0:1:2",
                "--periods",
                "10",
                "--quiet",
            ])
            .args(flags)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flags:?}: {err}");
        assert!(err.contains(want), "{flags:?}: want {want:?} in {err}");
    }
    let o = hostctl()
        .args([
            "map",
            "--beta",
            "-1:1:3",
            "--sigma",
            "0:1:2",
            "--periods",
            "10",
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("--beta: allowed range is >= 0"));
}

#[test]
fn unwritable_out_or_plot_is_refused_before_the_run() {
    let d = dir("unwritable");
    for flag in ["--out", "--plot"] {
        let t0 = std::time::Instant::now();
        let target = d.join("no/such/dir/map.svg");
        let o = hostctl()
            .args([
                "map",
                "--beta",
                "0:1:30",
                "--sigma",
                "0:2:30",
                "--periods",
                "2000000",
            ])
            .args(["--quiet", "--threads", "1", flag])
            .arg(&target)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flag}: {err}");
        assert!(err.contains("no/such/dir/map.svg"), "{flag}: {err}");
        assert!(
            t0.elapsed().as_secs() < 20,
            "{flag}: refused only after the run"
        );
    }
}
