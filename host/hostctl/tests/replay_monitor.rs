//! `hostctl replay` part (c): the firmware's energy monitor run over a recording finds the
//! energy growth of a region-C release at the tick where the device latched it.
//!
//! The device's latch tick is read from the recording itself (the first sample with the
//! SAFE_MODE flag), not from replay's output. Every other fault is configured out of reach
//! (energy limit and velocity threshold at their maxima, encoder jumps allowed up to 2^30
//! counts, the recorder keeps the heartbeat), so that safe mode means ENERGY_GROWTH.

use std::path::PathBuf;
use std::process::Command;
use stiffwall_proto::flags;

fn hostctl(args: &[&str]) -> (bool, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .args(args)
        .output()
        .expect("run hostctl");
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("stiffwall-replay-monitor-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

#[test]
fn replay_finds_the_growth_of_a_region_c_release_where_the_device_latched_it() {
    let f = tmp("region-c.csv");
    // maxon-re35 (c = 2e-3 N·m, b = 9e-6 N·m·s/rad, Δ = 2π/8192) at K = 8 N·m/rad, 1 kHz:
    // σ = c/(KΔ) ≈ 0.33, β = b/(KT) ≈ 0.0011: region C, the oscillation grows (from 3 ticks;
    // the virtual amplifier's full scale, 0.066 N·m, clamps the spring beyond ≈ 10 ticks).
    let args = [
        "record",
        f.to_str().unwrap(),
        "--seconds",
        "3",
        "--stiffness",
        "8",
        "--energy-monitor",
        "on",
        "--energy-limit",
        "1000000",
        "--max-velocity",
        "0",
        "--encoder-jump",
        "1073741824",
        "--release",
        "3",
        "--fast",
    ];
    let (ok, out, err) = hostctl(&args);
    assert!(ok, "record failed:\n{out}\n{err}");
    let rec = stiffwall_client::read_recording(&f).unwrap();
    // The device's latch: the first sample in safe mode, after the release.
    let released = rec
        .rows
        .iter()
        .position(|r| r.sample.flags & flags::RELEASED != 0)
        .expect("the device released");
    let latch = rec.rows[released..]
        .iter()
        .find(|r| r.sample.flags & flags::SAFE_MODE != 0)
        .expect("region C: the device's energy monitor latched");
    let (ok, json, err) = hostctl(&["replay", f.to_str().unwrap(), "--json"]);
    assert!(ok, "replay failed:\n{json}\n{err}");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let m = &v["monitor"];
    assert_eq!(m["device_monitor_on"], true, "{json}");
    let events = m["events"].as_array().expect("events");
    let growth: Vec<_> = events
        .iter()
        .filter(|e| e["fault"] == "ENERGY_GROWTH")
        .collect();
    let first = growth
        .first()
        .unwrap_or_else(|| panic!("no growth event: {m}"));
    assert_eq!(first["tick"], latch.sample.tick, "{m}");
    assert_eq!(first["seq"], latch.seq, "{m}");
    assert_eq!(first["device_latched_here"], true, "{m}");
    // The peak that tripped is an energy the recording shows at a turning point before.
    let peak_e8 = first["peak_e8"].as_u64().unwrap();
    assert!(
        rec.rows[released..]
            .iter()
            .take_while(|r| r.seq < latch.seq)
            .any(|r| u64::from(r.sample.energy) == peak_e8),
        "peak e8 {peak_e8} not among the recorded energies"
    );
    // No event before the release's growth, none in the hold phase.
    assert!(events
        .iter()
        .all(|e| e["tick"].as_u64() >= Some(u64::from(latch.sample.tick))));
    // The text report names the event and its tick.
    let (ok, text, _) = hostctl(&["replay", f.to_str().unwrap()]);
    assert!(ok);
    assert!(
        text.contains(&format!(
            "tick {} (seq {}): ENERGY_GROWTH",
            latch.sample.tick, latch.seq
        )),
        "{text}"
    );
}

#[test]
fn replay_monitor_is_quiet_on_a_region_a_release_and_skips_decimated_recordings() {
    let f = tmp("region-a.csv");
    // K = 0.8 N·m/rad: below the guaranteed limit of the maxon-re35 rig (0.88 by (12) at
    // 5 ticks/period, README), so the release settles.
    let (ok, out, err) = hostctl(&[
        "record",
        f.to_str().unwrap(),
        "--seconds",
        "2",
        "--stiffness",
        "0.8",
        "--release",
        "10",
        "--fast",
    ]);
    assert!(ok, "{out}\n{err}");
    let rec = stiffwall_client::read_recording(&f).unwrap();
    assert!(rec
        .rows
        .iter()
        .all(|r| r.sample.flags & flags::SAFE_MODE == 0));
    let (ok, json, err) = hostctl(&["replay", f.to_str().unwrap(), "--json"]);
    assert!(ok, "{json}\n{err}");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(
        v["monitor"]["events"].as_array().map(Vec::len),
        Some(0),
        "{json}"
    );
    assert!(
        v["monitor"]["turning_points"].as_u64().unwrap() > 0,
        "{json}"
    );

    let g = tmp("decimated.csv");
    let (ok, _, err) = hostctl(&[
        "record",
        g.to_str().unwrap(),
        "--seconds",
        "0.2",
        "--decimation",
        "4",
        "--fast",
    ]);
    assert!(ok, "{err}");
    let (_, text, _) = hostctl(&["replay", g.to_str().unwrap()]);
    assert!(
        text.contains("(c) energy monitor skipped: the energy monitor needs every servo tick"),
        "{text}"
    );
}
