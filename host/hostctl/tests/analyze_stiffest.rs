//! `hostctl analyze` without `--stiffness` (issue 47 item 3): "how stiff can my device go" on
//! every preset and on a device given by flags, and its predicted walls against what `hostctl
//! tune --fast --dry-run` sets on the virtual device, within the margins README.md's analyze row
//! states: tune's set K is 0.70–0.85 × analyze's prediction at tune's B (analyze's limit, tune
//! sets its margin 0.8 below what it verified), and tune's spring-only K 0.70–1.40 × analyze's
//! spring-only prediction (tune's margin 0.9 below a verified 0.95–1.49 × the
//! describing-function limit), both at tune's maximum velocity. Measured on the seven presets:
//! 0.752–0.798 and 0.764–1.340 (delta: its spring rests above the describing function's
//! limit). Three presets run here (a linear capped one, the rotary uncapped one, delta).

#[path = "support/cli.rs"]
mod cli;
use cli::hostctl;

/// Tune's set K over analyze's prediction at tune's B (README.md, analyze row).
const DAMPED_MARGIN: (f64, f64) = (0.70, 0.85);
/// Tune's spring-only K over analyze's spring-only prediction (README.md, analyze row).
const SPRING_MARGIN: (f64, f64) = (0.70, 1.40);

/// `hostctl ARGS --json`'s document (the run must succeed).
fn json(args: &[&str]) -> serde_json::Value {
    cli::json(&cli::ok(args))
}

fn num(v: &serde_json::Value, path: &[&str]) -> f64 {
    let mut x = v;
    for k in path {
        x = &x[k];
    }
    x.as_f64().unwrap_or_else(|| panic!("{path:?} in {v}"))
}

/// Every preset of `--list-devices` gets the report, in its own units, with positive walls no
/// higher than the quiet ceiling 2c/Δ (computed here from the preset's listed c and Δ).
#[test]
fn every_preset_and_a_flag_device_get_the_report() {
    let list = hostctl(&["analyze", "--list-devices"]);
    let text = String::from_utf8_lossy(&list.stdout).to_string();
    let mut n = 0;
    for line in text.lines().skip(1) {
        let cols: Vec<&str> = line.split_whitespace().collect();
        let (name, c, delta) = (cols[0], cols[3], cols[4]);
        let ceiling = 2.0 * c.parse::<f64>().unwrap() / delta.parse::<f64>().unwrap();
        let v = json(&["analyze", "--device", name, "--json"]);
        let q = num(&v, &["quiet_ceiling"]);
        assert!(
            (q - ceiling).abs() < 1e-3 * ceiling,
            "{name}: {q} vs {ceiling}"
        );
        for path in [
            &["spring_only", "k_predicted"][..],
            &["best_damper", "k_predicted"],
            &["predicted", "k_predicted"],
        ] {
            let k = num(&v, path);
            assert!(k > 0.0 && k <= q, "{name} {path:?}: {k}");
        }
        assert!(num(&v, &["predicted", "k_predicted"]) >= num(&v, &["spring_only", "k_predicted"]));
        let rot = name == "maxon-re35";
        assert_eq!(
            v["units"]["k"],
            if rot { "N·m/rad" } else { "N/m" },
            "{name}"
        );
        let out = hostctl(&["analyze", "--device", name]);
        let t = String::from_utf8_lossy(&out.stdout);
        assert!(t.contains("Predicted stiffest wall at rest: K = "), "{t}");
        assert_eq!(t.contains("N/m"), !rot, "{name}: {t}");
        n += 1;
    }
    assert_eq!(n, 7, "{text}");
    let v = json(&[
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
        "--json",
    ]);
    assert_eq!(num(&v, &["quiet_ceiling"]), 2.0 * 0.05 / 2e-5);
    assert!(v["device"].is_null() && num(&v, &["predicted", "k_predicted"]) > 0.0);
    let v = json(&[
        "analyze",
        "--mass",
        "6e-6",
        "--viscous",
        "1e-5",
        "--coulomb",
        "2e-3",
        "--counts-per-rev",
        "4096",
        "--period",
        "1e-3",
        "--rotational",
        "--json",
    ]);
    assert_eq!(v["units"]["b"], "N·m·s/rad");
    // With --stiffness the report at K is unchanged: no "how stiff" keys.
    let v = json(&[
        "analyze",
        "--device",
        "phantom-1.0",
        "--stiffness",
        "1015",
        "--json",
    ]);
    assert_eq!(v["region"], "E");
    assert!(v.get("spring_only").is_none());
}

/// `tune --fast --dry-run --json` on three presets against analyze's predictions at tune's
/// maximum velocity and B.
#[test]
fn predicted_walls_match_tune_within_the_readme_margins() {
    for name in ["phantom-1.0", "maxon-re35", "delta"] {
        let t = json(&["tune", "--device", name, "--fast", "--dry-run", "--json"]);
        let t = &t["tune"];
        let (k_set, b_set) = (num(t, &["k_set"]), num(t, &["b_set"]));
        let v = num(t, &["max_velocity"]).to_string();
        let b = b_set.to_string();
        let a = json(&[
            "analyze",
            "--device",
            name,
            "--velocity",
            &v,
            "--damping",
            &b,
            "--json",
        ]);
        let spring = num(t, &["k_spring_only"]) / num(&a, &["spring_only", "k_predicted"]);
        assert!(
            (SPRING_MARGIN.0..=SPRING_MARGIN.1).contains(&spring),
            "{name}: spring-only tune/analyze = {spring}"
        );
        assert!(b_set > 0.0, "{name}: tune set no damper");
        let damped = k_set / num(&a, &["at_damping", "k_predicted"]);
        assert!(
            (DAMPED_MARGIN.0..=DAMPED_MARGIN.1).contains(&damped),
            "{name}: damped tune/analyze = {damped} at B = {b_set}"
        );
        eprintln!("{name}: spring {spring:.3}, damped {damped:.3}");
    }
}
