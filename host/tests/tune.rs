//! `tune` on the virtual device with known plant parameters (issue 6 acceptance):
//! identification accuracy, the set K against the true largest settling K found here
//! independently, repeatability, and bad input.

use stiffwall_core::params::PhysicalParams;
use stiffwall_host::device::client::Client;
use stiffwall_host::device::virtual_device::{spawn, Spec};
use stiffwall_host::tune::procedure::{self, deflection_for, Settings, DEFAULT_XIDOT};
use stiffwall_host::tune::release::classify;
use stiffwall_sim::PhysicalPlant;

fn preset(name: &str) -> PhysicalParams {
    stiffwall_core::devices::find(name).expect("preset").params
}

fn connect(p: PhysicalParams) -> Client {
    let counts_per_rev = if p.rotational {
        (std::f64::consts::TAU / p.resolution).round() as u32
    } else {
        0
    };
    let (vd, port) = spawn(Spec {
        plant: p,
        counts_per_rev,
        fast: true,
        initial_position: 0.0,
        scene: None,
    })
    .unwrap();
    Client::connect(port, Some(Box::new(vd))).unwrap()
}

/// Independent release test: the exact plant of `stiffwall-sim` with the spring of eq. (2)
/// written out here (F = −KΔ(n + ½), n = ⌊x/Δ⌋, held for one period), no firmware involved.
/// Starts at rest in the middle of cell `d`, like a device held at deflection d.
fn sim_release_settles(p: &PhysicalParams, k: f64, d: i32, ticks: usize) -> bool {
    let mut plant = PhysicalPlant::new(p.mass, p.viscous, p.coulomb, p.resolution).unwrap();
    plant.set_state((f64::from(d) + 0.5) * p.resolution, 0.0);
    let mut counts = Vec::with_capacity(ticks);
    for _ in 0..ticks {
        let n = plant.encoder_count();
        counts.push(n);
        let force = -k * p.resolution * (n as f64 + 0.5);
        plant.advance(force, p.period_s);
        if counts.len() > 200 && n.unsigned_abs() > 100_000 {
            return false;
        }
    }
    classify(&counts, false).settled()
}

/// Brute-force bisection (in K) of the largest K whose simulated release settles, with the
/// deflection that tune uses for velocity v.
fn true_k_max(p: &PhysicalParams, v: f64, lo: f64, hi: f64) -> f64 {
    let test = |k: f64| {
        let d = deflection_for(p, k, v);
        let natural = std::f64::consts::TAU * (p.mass / k).sqrt() / p.period_s;
        sim_release_settles(p, k, d, (60.0 * natural).clamp(1500.0, 30_000.0) as usize)
    };
    assert!(test(lo), "the lower bracket {lo} must settle");
    assert!(!test(hi), "the upper bracket {hi} must fail");
    let (mut lo, mut hi) = (lo, hi);
    while hi / lo > 1.001 {
        let mid = (lo * hi).sqrt();
        if test(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

#[test]
fn tune_identifies_the_rig_and_sets_k_within_80_to_100_percent_of_the_true_limit() {
    let truth = preset("maxon-re35");
    let mut c = connect(truth);
    let before = c.get_config().unwrap();
    let o = procedure::tune(&mut c, &Settings::default(), true, &|_| {}).unwrap();
    let m_err = o.identified.mass[0] / truth.mass - 1.0;
    let c_err = o.identified.coulomb[0] / truth.coulomb - 1.0;
    assert!(m_err.abs() < 0.05, "mass off by {:.1} %", 100.0 * m_err);
    assert!(
        c_err.abs() < 0.10,
        "Coulomb friction off by {:.1} %",
        100.0 * c_err
    );
    let v = DEFAULT_XIDOT * truth.resolution / truth.period_s;
    let k_true = true_k_max(
        &truth,
        v,
        o.predicted.guaranteed * 0.5,
        o.predicted.expected * 4.0,
    );
    let ratio = o.k_set / k_true;
    eprintln!(
        "k_set {:.5} k_true {:.5} ratio {:.3} trials {}",
        o.k_set,
        k_true,
        ratio,
        o.search.trials.len()
    );
    assert!(
        (0.8..=1.0).contains(&ratio),
        "K set {:.5} vs true {:.5} (ratio {ratio:.3})",
        o.k_set,
        k_true
    );
    assert_eq!(
        c.get_config().unwrap(),
        before,
        "dry run leaves the config untouched"
    );
}

#[test]
fn repeated_tunes_agree_within_5_percent_and_a_real_run_saves() {
    let truth = preset("maxon-re35");
    let a = procedure::tune(&mut connect(truth), &Settings::default(), true, &|_| {}).unwrap();
    let mut c = connect(truth);
    let b = procedure::tune(&mut c, &Settings::default(), false, &|_| {}).unwrap();
    assert!(
        (a.k_set / b.k_set - 1.0).abs() < 0.05,
        "{} vs {}",
        a.k_set,
        b.k_set
    );
    assert!(b.saved);
    let cfg = c.get_config().unwrap();
    assert!(
        (f64::from(cfg.stiffness) / b.k_set - 1.0).abs() < 1e-6,
        "K set on the device"
    );
}

#[test]
fn bad_max_velocity_is_refused_before_touching_the_device() {
    let bin = env!("CARGO_BIN_EXE_hostctl");
    for v in ["0", "NaN", "-1", "inf"] {
        let out = std::process::Command::new(bin)
            .args(["tune", "--fast", "--dry-run", "--max-velocity", v])
            .output()
            .unwrap();
        assert!(!out.status.success(), "{v}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("--max-velocity must be finite and > 0"),
            "{v}: {err}"
        );
        assert!(
            !err.contains("connecting"),
            "refused before connecting: {err}"
        );
    }
    let mut c = connect(preset("maxon-re35"));
    let before = c.get_config().unwrap();
    let s = Settings {
        max_velocity: Some(0.0),
        ..Settings::default()
    };
    assert!(procedure::tune(&mut c, &s, false, &|_| {}).is_err());
    assert_eq!(c.get_config().unwrap(), before);
}
