//! `hostctl analyze --damping B` (issue 19 item 1): the JSON `damping` key agrees with the
//! core functions and with Colgate–Schenkel's closed form; bad B is refused; without
//! `--damping` the key is absent.

use std::process::{Command, Output};
use stiffwall_core::{criteria, PhysicalParams};

fn hostctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .arg("analyze")
        .args(args)
        .output()
        .expect("run hostctl")
}

const PLANT: [&str; 14] = [
    "--mass",
    "0.072",
    "--viscous",
    "0.5",
    "--coulomb",
    "0.038",
    "--resolution",
    "29.1e-6",
    "--period",
    "1e-3",
    "--stiffness",
    "2000",
    "--delay",
    "1e-3",
];

fn plant() -> PhysicalParams {
    PhysicalParams {
        mass: 0.072,
        viscous: 0.5,
        coulomb: 0.038,
        resolution: 29.1e-6,
        period_s: 1e-3,
        stiffness: 2000.0,
        delay_s: 1e-3,
        rotational: false,
    }
}

fn json(extra: &[&str]) -> serde_json::Value {
    let mut a = PLANT.to_vec();
    a.extend_from_slice(extra);
    a.push("--json");
    let out = hostctl(&a);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("valid JSON")
}

#[test]
fn damping_json_agrees_with_core_and_closed_form() {
    let b_set = 0.2;
    let v = json(&["--damping", "0.2"]);
    let d = &v["damping"];
    let p = plant();
    let k = criteria::k_max_exact_linear(&p, b_set).unwrap();
    assert_eq!(d["b_set"].as_f64().unwrap(), b_set);
    assert_eq!(d["k_max"].as_f64().unwrap(), k);
    // Colgate–Schenkel with B: 2(b − B)/T, independent closed form.
    let cs = 2.0 * (0.5 - b_set) / 1e-3;
    assert!((d["k_max_colgate_schenkel"].as_f64().unwrap() - cs).abs() < 1e-9 * cs);
    let small = (0.5 + b_set) / (0.5e-3 + 1e-3);
    assert!((d["k_max_small_b"].as_f64().unwrap() - small).abs() < 1e-9 * small);
    // Small-B regime (b, B ≪ m/T = 72): exact boundary within 5 % of the approximation.
    assert!((k - small).abs() < 0.05 * small, "{k} vs {small}");
    assert!((d["beta_v"].as_f64().unwrap() - b_set / (2000.0 * 1e-3)).abs() < 1e-12);
    assert_eq!(d["stable"].as_bool().unwrap(), 2000.0 < k);
    // The table is the core grid up to and including its first K_max = 0 (issue 47).
    let frontier = d["frontier"].as_array().unwrap();
    let f = criteria::frontier(&p, 4.0 * 72.0).unwrap();
    let zero = f.k_max.iter().position(|&k| k == 0.0);
    assert_eq!(
        frontier.len(),
        zero.map_or(criteria::FRONTIER_POINTS, |z| z + 1)
    );
    for (pt, (b, km)) in frontier
        .iter()
        .zip(f.b_n_s_per_m.iter().zip(f.k_max.iter()))
    {
        assert_eq!(pt["b"].as_f64().unwrap(), *b);
        assert_eq!(pt["k_max"].as_f64().unwrap(), *km);
    }
    assert_eq!(
        d["k_max_zero_from_b"].as_f64(),
        zero.map(|z| f.b_n_s_per_m[z])
    );
    // The best B is refined: never below the grid's best nor the user's B, and it is K_max
    // there.
    let (b_opt, k_opt) = (
        d["b_opt"].as_f64().unwrap(),
        d["k_max_opt"].as_f64().unwrap(),
    );
    assert!(k_opt >= f.k_max_opt && k_opt >= k, "{k_opt}");
    assert_eq!(k_opt, criteria::k_max_exact_linear(&p, b_opt).unwrap());
    assert_eq!(
        frontier[0]["k_max"].as_f64().unwrap(),
        criteria::k_max_gil_avello_rubio(&p).unwrap()
    );
}

#[test]
fn without_damping_no_key() {
    let v = json(&[]);
    assert!(v.get("damping").is_none());
}

#[test]
fn bad_damping_refused() {
    for bad in ["-1", "NaN", "inf", "-inf"] {
        let mut a = PLANT.to_vec();
        a.extend_from_slice(&["--damping", bad, "--json"]);
        let out = hostctl(&a);
        assert!(!out.status.success(), "{bad} accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("--damping") && err.contains("[0, 1e4] N·s/m"),
            "{bad}: {err}"
        );
        assert!(out.stdout.is_empty());
    }
}
