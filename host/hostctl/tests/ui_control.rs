//! Issue 22: a working session in `hostctl ui` — one controlling page, viewers that take
//! control explicitly, and Abort of a long release test and of tune, each leaving the device
//! with its previous config.

#![cfg(feature = "ui")]

mod ui_support;

use std::net::TcpStream;
use std::time::{Duration, Instant};
use ui_support::{read_frame, send_frame, Server};

/// The next JSON text message on `ws` for which `want` holds (telemetry frames skipped), within
/// 20 s.
fn next_json(ws: &mut TcpStream, want: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
    let t0 = Instant::now();
    loop {
        assert!(
            t0.elapsed() < Duration::from_secs(20),
            "no such message within 20 s"
        );
        let (op, p) = read_frame(ws).expect("a frame");
        if op == 1 {
            let v: serde_json::Value = serde_json::from_slice(&p).expect("JSON text");
            if want(&v) {
                return v;
            }
        }
    }
}

fn send(ws: &mut TcpStream, json: &str) {
    send_frame(ws, 1, json.as_bytes()).expect("send a command");
}

fn reply(ws: &mut TcpStream, id: u64) -> serde_json::Value {
    next_json(ws, |v| v["type"] == "reply" && v["id"] == id)
}

#[test]
fn a_second_page_is_a_viewer_until_it_takes_control_and_the_first_is_told() {
    let s = Server::start(&[]);
    let mut a = s.ws();
    let me_a = next_json(&mut a, |v| v["type"] == "you")["client"]
        .as_u64()
        .unwrap();
    let c = next_json(&mut a, |v| v["type"] == "control");
    assert_eq!(c["controller"], me_a, "the first page controls");
    let mut b = s.ws();
    let me_b = next_json(&mut b, |v| v["type"] == "you")["client"]
        .as_u64()
        .unwrap();
    // The viewer is refused, naming who controls; nothing changes.
    send(
        &mut b,
        r#"{"id": 1, "cmd": "config", "set": {"stiffness": 0.5}}"#,
    );
    let r = reply(&mut b, 1);
    assert_eq!(r["ok"], false, "{r}");
    let e = r["error"].as_str().unwrap();
    assert!(
        e.contains("viewer") && e.contains(&format!("page {me_a}")),
        "{e}"
    );
    let (_, g) = s.cmd(r#"{"cmd": "get"}"#);
    assert_eq!(g["result"]["config"]["stiffness"], 0.0);
    // The HTTP API is refused too while a page controls.
    let (code, v) = s.cmd(r#"{"cmd": "config", "set": {"stiffness": 0.5}}"#);
    assert_eq!(code, 422, "{v}");
    // A viewer may read.
    send(&mut b, r#"{"id": 2, "cmd": "get"}"#);
    assert_eq!(reply(&mut b, 2)["ok"], true);
    // Taking control: the page taken over is told, and is then a viewer itself.
    send(&mut b, r#"{"id": 3, "cmd": "take_control"}"#);
    assert_eq!(reply(&mut b, 3)["ok"], true);
    let told = next_json(&mut a, |v| {
        v["type"] == "control" && v["controller"] == me_b
    });
    assert_eq!(told["replaced"], me_a);
    send(
        &mut b,
        r#"{"id": 4, "cmd": "config", "set": {"stiffness": 0.5}}"#,
    );
    assert_eq!(reply(&mut b, 4)["ok"], true);
    // Every page's view follows the change.
    let cfg = next_json(&mut a, |v| {
        v["type"] == "config" && v["config"]["stiffness"] == 0.5
    });
    assert_eq!(cfg["config"]["stiffness"], 0.5);
    send(
        &mut a,
        r#"{"id": 5, "cmd": "config", "set": {"stiffness": 0.7}}"#,
    );
    assert_eq!(reply(&mut a, 5)["ok"], false);
}

#[test]
fn a_long_release_is_aborted_and_the_config_restored() {
    let s = Server::start(&[]);
    let (code, v) = s.cmd(r#"{"cmd": "config", "set": {"stiffness": 0.8}}"#);
    assert_eq!(code, 200, "{v}");
    let (_, before) = s.cmd(r#"{"cmd": "get"}"#);
    let s = std::sync::Arc::new(s);
    let runner = {
        let s = std::sync::Arc::clone(&s);
        std::thread::spawn(move || {
            // 10⁶ ticks, several seconds even on the fast virtual device.
            s.cmd(r#"{"cmd": "release", "args": {"deflection": 20, "ticks": 1000000, "stiffness": 0.5}}"#)
        })
    };
    // Wait until it runs, then abort it.
    let t0 = Instant::now();
    loop {
        let (_, g) = s.cmd(r#"{"cmd": "get"}"#);
        if g["result"]["release_running"] == true {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "the release never started"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // Another test meanwhile is refused, naming Abort.
    let (code, v) = s.cmd(r#"{"cmd": "release", "args": {"deflection": 20}}"#);
    assert_eq!(code, 422);
    assert!(v["error"].as_str().unwrap().contains("Abort"), "{v}");
    let aborted_at = Instant::now();
    let (code, v) = s.cmd(r#"{"cmd": "abort"}"#);
    assert_eq!(code, 200, "{v}");
    let (code, v) = runner.join().unwrap();
    assert!(
        aborted_at.elapsed() < Duration::from_secs(5),
        "{:?}",
        aborted_at.elapsed()
    );
    assert_eq!(code, 422, "{v}");
    assert!(v["error"].as_str().unwrap().contains("aborted"), "{v}");
    let (_, after) = s.cmd(r#"{"cmd": "get"}"#);
    assert_eq!(after["result"]["config"], before["result"]["config"]);
    assert_eq!(after["result"]["release_running"], false);
    // Nothing left to abort; the next test runs.
    let (code, _) = s.cmd(r#"{"cmd": "abort"}"#);
    assert_eq!(code, 422);
    let (code, v) = s.cmd(r#"{"cmd": "release", "args": {"deflection": 20, "ticks": 2000}}"#);
    assert_eq!(code, 200, "{v}");
}

#[test]
fn a_second_tune_is_refused_and_an_aborted_tune_restores_the_config() {
    let s = std::sync::Arc::new(Server::start(&[]));
    let (code, v) = s.cmd(r#"{"cmd": "config", "set": {"stiffness": 0.3, "damping": 0.0001}}"#);
    assert_eq!(code, 200, "{v}");
    let (_, before) = s.cmd(r#"{"cmd": "get"}"#);
    let runner = {
        let s = std::sync::Arc::clone(&s);
        std::thread::spawn(move || s.cmd(r#"{"cmd": "tune", "args": {"dry-run": false}}"#))
    };
    // The double click: refused at once while the first runs.
    std::thread::sleep(Duration::from_millis(300));
    let (code, refused) = s.cmd(r#"{"cmd": "tune", "args": {"dry-run": false}}"#);
    assert_eq!(code, 422, "{refused}");
    let e = refused["error"].as_str().unwrap();
    assert!(
        e.contains("a tune is running") && e.contains("Abort"),
        "{refused}"
    );
    let (code, v) = s.cmd(r#"{"cmd": "abort"}"#);
    assert_eq!(code, 200, "{v}");
    let (code, v) = runner.join().unwrap();
    assert_eq!(code, 422, "{v}");
    assert!(v["error"].as_str().unwrap().contains("tune aborted"), "{v}");
    let (_, after) = s.cmd(r#"{"cmd": "get"}"#);
    assert_eq!(
        after["result"]["config"], before["result"]["config"],
        "config restored, unsaved"
    );
}
