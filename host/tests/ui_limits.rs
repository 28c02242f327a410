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
