//! `hostctl ui`'s limits for a working session, against the real binary on the fast virtual
//! device (issue 22): request bodies, slow and surplus connections, strict request forms,
//! typed commands, WebSocket frames, and the bounded release trace. The values are the ones
//! docs/UI.md lists.

#![cfg(feature = "ui")]

mod ui_support;

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};
use ui_support::{read_close, read_frame, send_frame, Server};

/// `POST /api/map`'s limit (docs/UI.md).
const MAX_MAP_BYTES: usize = 4 << 20;
/// The header-read timeout (docs/UI.md).
const HEADER_TIMEOUT: Duration = Duration::from_secs(5);
/// The connection limit (docs/UI.md).
const MAX_CONNECTIONS: usize = 64;

/// Reads until the server closes (or `limit` passes); returns what arrived and when it ended.
fn read_to_close(s: &mut TcpStream, limit: Duration) -> (String, Duration) {
    let t0 = Instant::now();
    s.set_read_timeout(Some(limit)).unwrap();
    let mut out = Vec::new();
    let mut buf = [0u8; 4096];
    loop {
        match s.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => out.extend_from_slice(&buf[..n]),
        }
    }
    (String::from_utf8_lossy(&out).into_owned(), t0.elapsed())
}

#[test]
fn map_upload_over_the_limit_is_refused_by_its_length_before_the_body() {
    let s = Server::start(&[]);
    let mut c = TcpStream::connect(s.addr).unwrap();
    let head = format!(
        "POST /api/map?token={} HTTP/1.1\r\nHost: {}\r\nContent-Type: application/json\r\n\
         Content-Length: 300000000\r\n\r\n",
        s.token,
        s.host()
    );
    c.write_all(head.as_bytes()).unwrap();
    // No body byte sent: the answer comes from the length alone.
    let (text, t) = read_to_close(&mut c, Duration::from_secs(10));
    assert!(text.starts_with("HTTP/1.1 413"), "{text}");
    assert!(t < Duration::from_secs(3), "{t:?}");
}

#[test]
fn chunked_map_upload_is_cut_off_at_the_limit() {
    let s = Server::start(&[]);
    let mut c = TcpStream::connect(s.addr).unwrap();
    let head = format!(
        "POST /api/map?token={} HTTP/1.1\r\nHost: {}\r\nContent-Type: application/json\r\n\
         Transfer-Encoding: chunked\r\n\r\n",
        s.token,
        s.host()
    );
    c.write_all(head.as_bytes()).unwrap();
    c.set_write_timeout(Some(Duration::from_secs(2))).unwrap();
    let chunk = format!("10000\r\n{}\r\n", " ".repeat(0x10000));
    let mut sent = 0usize;
    // Up to 300 MB, as in the report; the server stops reading at the limit.
    while sent < 300_000_000 {
        if c.write_all(chunk.as_bytes()).is_err() {
            break;
        }
        sent += 0x10000;
    }
    let (text, _) = read_to_close(&mut c, Duration::from_secs(10));
    assert!(
        text.starts_with("HTTP/1.1 413"),
        "{sent} bytes sent: {text:?}"
    );
    // What the sockets' buffers hold beyond the limit, no more.
    assert!(sent < MAX_MAP_BYTES + (16 << 20), "{sent} bytes accepted");
    // A map under the limit is still read (and judged on its content).
    let (code, _) = s.raw(
        &format!(
            "POST /api/map?token={} HTTP/1.1\r\nHost: {}",
            s.token,
            s.host()
        ),
        "{}",
    );
    assert_eq!(code, 422);
}

#[test]
fn a_client_that_never_finishes_its_headers_is_dropped() {
    let s = Server::start(&[]);
    let mut c = TcpStream::connect(s.addr).unwrap();
    c.write_all(format!("GET / HTTP/1.1\r\nHost: {}\r\nX-Slow: ", s.host()).as_bytes())
        .unwrap();
    let (_, t) = read_to_close(&mut c, Duration::from_secs(30));
    assert!(
        t >= HEADER_TIMEOUT - Duration::from_millis(500)
            && t < HEADER_TIMEOUT + Duration::from_secs(2),
        "dropped after {t:?}"
    );
}

#[test]
fn connections_beyond_the_limit_are_refused_and_slots_come_back() {
    let s = Server::start(&[]);
    let partial = format!("GET / HTTP/1.1\r\nHost: {}\r\n", s.host());
    let held: Vec<TcpStream> = (0..MAX_CONNECTIONS)
        .map(|_| {
            let mut c = TcpStream::connect(s.addr).unwrap();
            c.write_all(partial.as_bytes()).unwrap();
            c
        })
        .collect();
    std::thread::sleep(Duration::from_millis(300));
    let mut extra = TcpStream::connect(s.addr).unwrap();
    let (text, t) = read_to_close(&mut extra, Duration::from_secs(3));
    assert!(t < Duration::from_secs(2), "{t:?}");
    assert!(
        text.is_empty() || text.starts_with("HTTP/1.1 503"),
        "{text}"
    );
    // The slow ones are dropped by the header timeout; then the server answers again.
    std::thread::sleep(HEADER_TIMEOUT + Duration::from_secs(1));
    let (code, v) = s.cmd(r#"{"cmd": "get"}"#);
    assert_eq!(code, 200, "{v}");
    drop(held);
}

#[test]
fn duplicate_host_and_absolute_targets_are_refused() {
    let s = Server::start(&[]);
    let (h, t) = (s.host(), &s.token);
    let (code, body) = s.raw(
        &format!("GET /?token={t} HTTP/1.1\r\nHost: {h}\r\nHost: evil.example"),
        "",
    );
    assert_eq!(code, 400, "{body}");
    assert!(body.contains("Host headers"), "{body}");
    for target in [
        "http://evil.example/".to_string(),
        format!("http://evil.example/?token={t}"),
        format!("http://{h}/?token={t}"),
    ] {
        let (code, body) = s.raw(&format!("GET {target} HTTP/1.1\r\nHost: {h}"), "");
        assert_eq!(code, 400, "{target}: {body}");
        assert!(body.contains("origin-form"), "{body}");
    }
    // The security headers are on refusals too, and the page's own request still works.
    let (code, body) = s.raw(&format!("GET /?token={t} HTTP/1.1\r\nHost: {h}"), "");
    assert_eq!(code, 200);
    assert!(body
        .to_ascii_lowercase()
        .contains("x-content-type-options: nosniff"));
    let (code, body) = s.raw(&format!("GET / HTTP/1.1\r\nHost: {h}"), "");
    assert_eq!(code, 403);
    assert!(body
        .to_ascii_lowercase()
        .contains("x-content-type-options: nosniff"));
}

#[test]
fn favicon_is_no_content_not_forbidden() {
    let s = Server::start(&[]);
    let (code, body) = s.raw(
        &format!("GET /favicon.ico HTTP/1.1\r\nHost: {}", s.host()),
        "",
    );
    assert_eq!(code, 204, "{body}");
    let (code, _) = s.raw("GET /favicon.ico HTTP/1.1\r\nHost: evil.example", "");
    assert_eq!(code, 403, "the Host rule still holds");
}

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

#[test]
fn websocket_refusals_close_with_a_reason() {
    let s = Server::start(&[]);
    let mut ws = s.ws();
    send_frame(&mut ws, 1, &vec![b' '; 70_000]).unwrap();
    let (code, reason) = read_close(&mut ws);
    assert_eq!(code, 1009, "{reason}");
    assert!(reason.contains("64 KiB limit"), "{reason}");
    let mut ws = s.ws();
    send_frame(&mut ws, 2, b"\x01\x02").unwrap();
    let (code, reason) = read_close(&mut ws);
    assert_eq!(code, 1003, "{reason}");
    assert!(reason.contains("binary"), "{reason}");
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
