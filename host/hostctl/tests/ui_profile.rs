//! `hostctl ui --profile`: the real binary on the fast virtual device (maxon-re35) loads a
//! profile file, checked against a dry-run tune's JSON, and sends the page its elements (the
//! `profile` message: kinds, spans in counts equal to the lowered file's, margins); a profile
//! that fails the check or does not lower is refused (exit code 2, the file, element, field and
//! range named) before anything is served; without `--profile` the page is told the device's
//! active profile (none on a fresh device).

#![cfg(feature = "ui")]

mod ui_support;

use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};
use stiffwall_tune::profile::{self, overlap, Device, ProfileFile};
use ui_support::{read_frame, tune_json, Server};

fn profiles() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../profiles")
}

/// The JSON messages a newly opened page is sent, until `hello` and `profile` have come.
fn hello_and_profile(s: &Server) -> (Value, Value) {
    let mut ws = s.ws();
    let (mut hello, mut profile) = (None, None);
    let t0 = Instant::now();
    while hello.is_none() || profile.is_none() {
        assert!(t0.elapsed() < Duration::from_secs(20), "no profile message");
        let (op, p) = read_frame(&mut ws).expect("a frame");
        if op != 1 {
            continue;
        }
        let v: Value = serde_json::from_slice(&p).unwrap();
        match v["type"].as_str() {
            Some("hello") => hello = Some(v),
            Some("profile") => profile = Some(v),
            _ => {}
        }
    }
    (hello.unwrap(), profile.unwrap())
}

#[test]
fn the_page_gets_the_loaded_profile_with_its_check() {
    let tune = tune_json("knob");
    let file = profiles().join("knob-24-detents.toml");
    let s = Server::start(&[
        "--device",
        "maxon-re35",
        "--profile",
        file.to_str().unwrap(),
        "--tune-json",
        tune.to_str().unwrap(),
    ]);
    let (hello, m) = hello_and_profile(&s);
    assert_eq!(m["version"], 1);
    assert_eq!(m["source"], "file", "{m}");
    assert_eq!(m["name"], "knob-24-detents");
    assert_eq!(m["pass"], true, "{m}");
    assert_eq!(m["units"]["span"], "counts");
    // The same file lowered here for the device the page was told about.
    let cpr = hello["device"]["counts_per_rev"].as_f64().unwrap();
    let device = Device {
        rotational: true,
        resolution: std::f64::consts::TAU / cpr,
    };
    let text = std::fs::read_to_string(&file).unwrap();
    let lowered = profile::lower(&ProfileFile::from_toml(&text).unwrap(), &device).unwrap();
    let els = m["elements"].as_array().unwrap();
    assert_eq!(els.len(), lowered.elements.len());
    assert_eq!(els.len(), 3, "detents and two end stops");
    for (e, p) in els.iter().zip(&lowered.elements) {
        assert_eq!(e["kind"], p.origin.kind, "{e}");
        assert_eq!(e["index"], p.origin.index);
        assert_eq!(e["wire_kind"], p.element.kind_name());
        let span = overlap::span(&p.element);
        assert_eq!(e["span"]["lo"], serde_json::json!(span.lo), "{e}");
        assert_eq!(e["span"]["hi"], serde_json::json!(span.hi), "{e}");
        let c = &e["check"];
        assert_eq!(c["pass"], true, "{e}");
        let margin = c["margin"].as_f64().unwrap();
        let want = if margin < 1.25 { "near" } else { "ok" };
        assert_eq!(e["state"], want, "{e}");
        assert!(e["numbers"]
            .as_array()
            .unwrap()
            .iter()
            .any(|n| n["name"] == "K" && n["unit"] == "N·m/rad"));
    }
    assert_eq!(els[0]["wire_kind"], "detents");
    assert_eq!(els[0]["geometry"]["count"], 13);
    assert_eq!(els[1]["part"], "lower");
    assert_eq!(els[2]["part"], "upper");
}

#[test]
fn without_profile_the_page_gets_the_devices_own() {
    let s = Server::start(&[]);
    let (_, m) = hello_and_profile(&s);
    assert_eq!(m["source"], "device");
    assert_eq!(m["elements"].as_array().unwrap().len(), 0, "{m}");
    assert_eq!(m["checked_against"], Value::Null);
}

/// `hostctl ui` with `args` that must be refused before serving: its exit code and stderr.
fn refused(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .args(["ui", "--listen", "127.0.0.1:0", "--fast"])
        .args(args)
        .stdin(std::process::Stdio::null())
        .output()
        .expect("run hostctl ui");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(!stdout.contains("http://"), "served: {stdout}");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_profile_that_fails_or_does_not_lower_is_refused() {
    let tune = tune_json("strong");
    let file = profiles().join("too-strong-detent.toml");
    let (code, err) = refused(&[
        "--device",
        "maxon-re35",
        "--profile",
        file.to_str().unwrap(),
        "--tune-json",
        tune.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(2), "{err}");
    for want in [
        "too-strong-detent.toml fails the check",
        "element 1 (detents)",
        "is above its limit",
        "nothing was loaded onto the device",
        "--force-profile",
    ] {
        assert!(err.contains(want), "{want:?} in {err}");
    }
    // A field out of range: the file, element, field and range are named.
    let dir = tune.parent().unwrap();
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "[profile]\nname = \"bad\"\naxis = \"rotary\"\n\n[[element]]\nkind = \"spring\"\n\
         center = 0.0\nstiffness = -3\n",
    )
    .unwrap();
    let (code, err) = refused(&["--profile", bad.to_str().unwrap()]);
    assert_eq!(code, Some(2), "{err}");
    for want in [
        "bad.toml",
        "element 1 (spring)",
        "`stiffness` must be",
        "(got -3)",
        "nothing was loaded",
    ] {
        assert!(err.contains(want), "{want:?} in {err}");
    }
    // --force-profile loads it and the page sees what fails.
    let s = Server::start(&[
        "--device",
        "maxon-re35",
        "--profile",
        file.to_str().unwrap(),
        "--tune-json",
        tune.to_str().unwrap(),
        "--force-profile",
    ]);
    let (_, m) = hello_and_profile(&s);
    assert_eq!(m["pass"], false, "{m}");
    assert_eq!(m["elements"][0]["state"], "fails", "{m}");
    assert!(m["elements"][0]["check"]["margin"].as_f64().unwrap() < 1.0);
}
