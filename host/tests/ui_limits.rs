//! `hostctl ui`'s limits for a working session, against the real binary on the fast virtual
//! device (issue 22): request bodies, slow and surplus connections, strict request forms,
//! typed commands, WebSocket frames, and the bounded release trace. The values are the ones
//! docs/UI.md lists.

mod ui_support;

use ui_support::{read_frame, send_frame, Server};

#[test]
fn array_values_cannot_smuggle_flags() {
    let s = Server::start(&[]);
    let (_, before) = s.cmd(r#"{"cmd": "get"}"#);
    let smuggle = r#"{"id": 9, "cmd":"config","set":{"stiffness":[0.5,"--wall","one-sided"]}}"#;
    let (code, v) = s.cmd(smuggle);
    assert_eq!(code, 400, "{v}");
    assert_eq!(v["id"], 9);
    let e = v["error"].as_str().unwrap();
    assert!(e.contains("set.stiffness"), "{e}");
    for other in [
        r#"{"cmd":"config","set":{"--wall":"one-sided"}}"#,
        r#"{"cmd":"config","set":{"wall":"--stiffness"}}"#,
        r#"{"cmd":"release","args":{"deflection":"20 --stiffness 9"}}"#,
    ] {
        let (code, v) = s.cmd(other);
        assert_eq!(code, 400, "{other}: {v}");
    }
    let (_, after) = s.cmd(r#"{"cmd": "get"}"#);
    assert_eq!(
        before["result"]["config"], after["result"]["config"],
        "nothing changed"
    );
    // Over the WebSocket: the same refusal, as a reply.
    let mut ws = s.ws();
    send_frame(&mut ws, 1, smuggle.as_bytes()).unwrap();
    loop {
        let (op, p) = read_frame(&mut ws).unwrap();
        if op == 1 {
            let m: serde_json::Value = serde_json::from_slice(&p).unwrap();
            if m["type"] == "reply" {
                assert_eq!(m["ok"], false, "{m}");
                assert!(
                    m["error"].as_str().unwrap().contains("set.stiffness"),
                    "{m}"
                );
                break;
            }
        }
    }
}

/// A 10⁶-tick release: the message the page gets (and a page that opens later is sent) stays
/// bounded, with the trace decimated to at most 4000 points that keep its extremes.
#[test]
fn a_million_tick_release_reaches_the_page_bounded() {
    let s = Server::start(&[]);
    let (code, v) = s.cmd(r#"{"cmd": "config", "set": {"stiffness": 0.8}}"#);
    assert_eq!(code, 200, "{v}");
    let (code, v) = s.cmd(r#"{"cmd": "release", "args": {"deflection": 20, "ticks": 1000000}}"#);
    assert_eq!(code, 200, "{v}");
    let tr = &v["result"]["trace"];
    assert!(
        tr["samples"].as_u64().unwrap() >= 999_000,
        "{}",
        tr["samples"]
    );
    let counts = tr["counts"].as_array().unwrap();
    assert!(counts.len() <= 4000, "{} points", counts.len());
    let top = counts.iter().filter_map(serde_json::Value::as_i64).max();
    assert!(
        top.is_some_and(|x| (x - 20).abs() <= 2),
        "the release's peak kept: {top:?}"
    );
    let reply_bytes = v.to_string().len();
    assert!(reply_bytes < 100_000, "reply: {reply_bytes} bytes");
    // A page opening now is sent the snapshot: hello and the latest of each kind.
    let mut ws = s.ws();
    let mut snapshot = 0;
    loop {
        let (op, p) = read_frame(&mut ws).unwrap();
        if op != 1 {
            break;
        }
        snapshot += p.len();
    }
    assert!(snapshot < 150_000, "snapshot: {snapshot} bytes");
    let rss_kb = std::fs::read_to_string(format!("/proc/{}/status", s.pid()))
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        });
    if let Some(kb) = rss_kb {
        assert!(kb < 64 << 10, "RSS {kb} kB after the release");
    }
}
