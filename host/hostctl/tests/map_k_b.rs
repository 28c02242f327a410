//! `hostctl map --k-b` (issue 19, item 2): the (K, B) map of one device. Checked against Table I
//! computed here from the plant file's numbers, against the (β, σ) map of the same dimensionless
//! point, against closed forms of the linear boundary, and for clean refusals of bad input.

use serde_json::Value;
use std::path::PathBuf;
use std::process::{Command, Output};

const PLANT: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../sim/plants/phantom-realistic.toml"
);
// [device] and [controller] of that file.
const M: f64 = 0.03;
const B_DEV: f64 = 0.005;
const C: f64 = 0.038;
const RES: f64 = 2.91e-05;
const T: f64 = 0.001;

fn hostctl() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hostctl"))
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("stiffwall-map-kb-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn kb(device: &[&str], extra: &[&str], out: &PathBuf) -> Output {
    hostctl()
        .args([
            "map",
            "--k-b",
            "--periods",
            "3000",
            "--quiet",
            "--threads=2",
        ])
        .args(device)
        .args(["--k-axis", "200:2600:7", "--b-axis", "0:1:6", "--out"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

fn json(p: &PathBuf) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-300)
}

#[test]
fn plant_file_map_is_table_one_and_its_boundary_the_closed_forms() {
    let d = dir("plant");
    let (out, img) = (d.join("kb.json"), d.join("kb.png"));
    let o = kb(
        &["--plant", PLANT],
        &["--plot", img.to_str().unwrap()],
        &out,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("not simulated: stiction"), "{err}");
    assert!(std::fs::metadata(&img).unwrap().len() > 1000);
    let v = json(&out);
    assert_eq!(v["kind"], "k-b");
    assert_eq!(v["units"]["b"], "N·s/m");
    let ignored = v["plant"]["ignored"].as_array().unwrap();
    assert!(ignored.iter().any(|s| s == "transmission"), "{ignored:?}");
    let pts = v["points"].as_array().unwrap();
    assert_eq!(pts.len(), 42);
    let f = |p: &Value, k: &str| p[k].as_f64().unwrap();
    for p in pts {
        let (k, b) = (f(p, "k"), f(p, "b"));
        assert!(close(f(p, "mu"), M / (k * T * T), 1e-12), "{p}");
        assert!(close(f(p, "beta"), B_DEV / (k * T), 1e-12), "{p}");
        assert!(close(f(p, "sigma"), C / (k * RES), 1e-12), "{p}");
        assert!(close(f(p, "beta_v"), b / (k * T), 1e-12) || b == 0.0, "{p}");
        // Coulomb friction and quantization do not make a linear-stable wall grow.
        if p["class"] == "growing" {
            assert_eq!(p["linear_stable"], false, "{p}");
        }
    }
    assert!(pts.iter().any(|p| p["class"] == "growing"));
    let bnd = v["boundary"].as_array().unwrap();
    assert_eq!(bnd.len(), 101);
    // B = 0: the ZOH spring K_max ≈ 2b/T (Colgate–Schenkel's bound, exact to O(bT/m)).
    assert!(
        close(f(&bnd[0], "k_max"), 2.0 * B_DEV / T, 1e-2),
        "{}",
        bnd[0]
    );
    // Small B: (b + B)/(T/2) (Hulin et al.), within 3 % at B = 0.1 N·s/m ≪ m/T = 30.
    let p10 = &bnd[10];
    assert!(close(f(p10, "b"), 0.1, 1e-12));
    assert!(
        close(f(p10, "k_max"), (B_DEV + 0.1) / (T / 2.0), 3e-2),
        "{p10}"
    );
}

#[test]
fn physical_numbers_give_the_plant_files_points_and_the_beta_sigma_maps_classes() {
    let d = dir("numbers");
    let (a, b) = (d.join("file.json"), d.join("numbers.json"));
    assert!(kb(&["--plant", PLANT], &[], &a).status.success());
    let nums = [
        "--mass",
        "0.03",
        "--viscous",
        "0.005",
        "--coulomb",
        "0.038",
        "--resolution",
        "2.91e-5",
        "--period",
        "0.001",
    ];
    let o = kb(&nums, &[], &b);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (va, vb) = (json(&a), json(&b));
    assert_eq!(va["points"], vb["points"]);
    assert_eq!(va["boundary"], vb["boundary"]);
    // Two points (one damped) against `hostctl map` at their (mu, beta, sigma, beta_v).
    for i in [8usize, 40] {
        let p = &va["points"][i];
        let one = |k: &str| format!("{0}:{0}:1", p[k]);
        let m = d.join(format!("map{i}.json"));
        let o = hostctl()
            .args(["map", "--xidot0", "5", "--periods", "3000", "--quiet"])
            .args(["--mu", &p["mu"].to_string(), "--beta", &one("beta")])
            .args([
                "--sigma",
                &one("sigma"),
                "--beta-v",
                &p["beta_v"].to_string(),
            ])
            .arg("--out")
            .arg(&m)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let q = &json(&m)["panels"][0]["points"][0];
        assert_eq!(q["class"], p["class"], "{p} vs {q}");
        assert_eq!(q["h_end"], p["h_end"], "{p} vs {q}");
    }
}

#[test]
fn bad_k_b_input_is_refused_naming_the_flag_and_nothing_is_written() {
    let d = dir("bad");
    let plant = ["--plant", PLANT];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["--k-axis", "0:100:3"],
            "--k-axis lo = 0: allowed range is > 0",
        ),
        (vec!["--k-axis", "-5:100:3"], "--k-axis lo = -5"),
        (vec!["--k-axis", "NaN:100:3"], "--k-axis"),
        (
            vec!["--b-axis", "-1:2:3"],
            "--b-axis lo = -1: allowed range is >= 0",
        ),
        (vec!["--b-axis", "0:inf:3"], "--b-axis"),
        (vec!["--b-axis", "0:300:3"], "B <= 1000*K*T"),
        (vec!["--k-axis", "1:2:0"], "--k-axis"),
        (vec!["--mass", "1"], "--mass cannot be combined"),
        (vec!["--mu", "100"], "--mu"),
        (vec!["--beta-v", "1"], "--beta-v"),
        (vec!["--xidot0", "1,5"], "--xidot0"),
    ];
    for (extra, want) in cases {
        let (out, img) = (d.join("kb.json"), d.join("kb.png"));
        let mut axes = vec![];
        for (flag, default) in [("--k-axis", "200:2600:3"), ("--b-axis", "0:1:3")] {
            if !extra.contains(&flag) {
                axes.extend([flag, default]);
            }
        }
        let o = hostctl()
            .args(["map", "--k-b", "--periods", "100", "--quiet"])
            .args(plant)
            .args(&axes)
            .args(&extra)
            .args([
                "--out",
                out.to_str().unwrap(),
                "--plot",
                img.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        assert!(err.contains(want), "{extra:?}: want {want:?} in {err}");
        assert!(!out.exists() && !img.exists(), "{extra:?} wrote a file");
    }
    // No device at all, and a missing plant file.
    for (args, want) in [
        (vec![], "--k-b needs a device"),
        (
            vec!["--plant", "/nonexistent/p.toml"],
            "--plant /nonexistent/p.toml",
        ),
        (vec!["--mass", "-1"], "--mass"),
        (vec!["--device", "phantom-1.0", "--delay", "1"], "--delay"),
        (vec!["--device", "phantom-1.0", "--delay", "NaN"], "--delay"),
        (
            vec!["--device", "phantom-1.0", "--period", "-1"],
            "--period",
        ),
    ] {
        let o = hostctl()
            .args(["map", "--k-b", "--k-axis", "1:2:2", "--b-axis", "0:0:1"])
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: want {want:?} in {err}");
    }
}
