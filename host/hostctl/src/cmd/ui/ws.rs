//! The WebSocket at `/ws`: one page's session. On connecting the page is sent the snapshot
//! (`hello` and the latest message of each kind), then every message the device thread
//! publishes; the page's text messages are commands (see [`super::wire`]). Each page has a
//! client number (sent first, as `{"type": "you", "client": n}`) and is the controller or a
//! viewer ([`super::control`]); leaving releases control.
//!
//! Limits: a message or frame from the page over [`MAX_WS_MESSAGE`] bytes closes the socket
//! with code 1009 and the limit as the reason; every other way the server ends a session
//! closes it with a code and a one-line reason too (a binary message: 1003; the server
//! stopping: 1001; a protocol error: 1002). The page is pinged every [`PING_PERIOD`] (its
//! browser answers), so a live page is never idle for the connection's idle timeout. A page
//! that reads too slowly loses display frames (it is told how many), never the device's
//! samples.

use super::app::{reply_json, submit, App};
use super::wire::parse_command;
use axum::extract::ws::{close_code, CloseFrame, Message, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::response::Response;
use serde_json::{json, Value};
use std::sync::atomic::Ordering;
use std::time::Duration;
use tokio::sync::broadcast::error::RecvError;

/// Largest message (and frame) the page may send: commands are a few hundred bytes.
pub const MAX_WS_MESSAGE: usize = 64 << 10;
/// Period of the pings sent to the page.
pub const PING_PERIOD: Duration = Duration::from_secs(10);

/// `GET /ws`: the upgrade (the guard has already checked Host, Origin and the token).
pub async fn ws(State(app): State<App>, up: WebSocketUpgrade) -> Response {
    up.max_message_size(MAX_WS_MESSAGE)
        .max_frame_size(MAX_WS_MESSAGE)
        .on_upgrade(move |socket| session(app, socket))
}

/// Closes `socket` with `code` and `reason`, then waits briefly so that the page reads the close
/// frame before the socket goes (unread input would otherwise reset the connection).
async fn close(mut socket: WebSocket, code: u16, reason: &str) {
    let frame = CloseFrame {
        code,
        reason: reason.into(),
    };
    if socket.send(Message::Close(Some(frame))).await.is_ok() {
        // Until the page's own close frame arrives, or the time is up (when the socket can no
        // longer be read, e.g. after an oversize frame, the time is simply waited out).
        let _ = tokio::time::timeout(Duration::from_millis(500), async {
            loop {
                match socket.recv().await {
                    Some(Ok(Message::Close(_))) => break,
                    Some(Ok(_)) => {}
                    Some(Err(_)) | None => std::future::pending::<()>().await,
                }
            }
        })
        .await;
    }
}

/// The messages a page is sent on connecting.
fn first_messages(app: &App) -> Vec<String> {
    match app.shared.snapshot.lock() {
        Ok(s) => std::iter::once(s.hello.to_string())
            .chain(s.latest.iter().map(|(_, v)| v.to_string()))
            .collect(),
        Err(_) => Vec::new(),
    }
}

/// How a session ends: the close frame to send, if any.
type End = Option<(u16, String)>;

async fn session(app: App, mut socket: WebSocket) {
    // Subscribe first: nothing published after the snapshot is missed.
    let mut rx = app.shared.tx.subscribe();
    let (me, became) = app.shared.control.join();
    if let Some(ev) = became {
        app.shared.publish("control", ev);
    }
    let you = json!({"type": "you", "client": me}).to_string();
    for text in std::iter::once(you).chain(first_messages(&app)) {
        if socket.send(Message::Text(text.into())).await.is_err() {
            leave(&app, me);
            return;
        }
    }
    let (reply_tx, mut reply_rx) = tokio::sync::mpsc::unbounded_channel::<Value>();
    let mut check = tokio::time::interval(Duration::from_millis(200));
    let mut ping = tokio::time::interval_at(tokio::time::Instant::now() + PING_PERIOD, PING_PERIOD);
    let end: End = loop {
        let out = tokio::select! {
            _ = check.tick() => if app.shared.stop.load(Ordering::Relaxed) {
                break Some((close_code::AWAY, "hostctl ui stopped".into()));
            } else { None },
            _ = ping.tick() => Some(Message::Ping(Vec::new().into())),
            m = rx.recv() => match m {
                Ok(msg) => Some(msg),
                Err(RecvError::Lagged(n)) => {
                    Some(Message::Text(json!({"type": "lagged", "frames": n}).to_string().into()))
                }
                Err(RecvError::Closed) => {
                    break Some((close_code::AWAY, "the device connection ended".into()));
                }
            },
            r = reply_rx.recv() => r.map(|v| Message::Text(v.to_string().into())),
            m = socket.recv() => match incoming(&app, me, m, &reply_tx) {
                Ok(reply) => reply,
                Err(end) => break end,
            },
        };
        if let Some(msg) = out {
            if socket.send(msg).await.is_err() {
                break None;
            }
        }
    };
    leave(&app, me);
    if let Some((code, reason)) = end {
        close(socket, code, &reason).await;
    }
}

/// Page `me` is gone: control is free again if it held it.
fn leave(app: &App, me: u64) {
    if let Some(ev) = app.shared.control.leave(me) {
        app.shared.publish("control", ev);
    }
}

/// One message from the page: a command is run (its answer comes through `replies`); a bad
/// command is answered at once. `Err` ends the session.
fn incoming(
    app: &App,
    me: u64,
    m: Option<Result<Message, axum::Error>>,
    replies: &tokio::sync::mpsc::UnboundedSender<Value>,
) -> Result<Option<Message>, End> {
    match m {
        Some(Ok(Message::Text(t))) => match parse_command(t.as_bytes()) {
            Ok(env) => {
                let app = app.clone();
                let tx = replies.clone();
                tokio::spawn(async move {
                    let id = env.id.clone();
                    let r = submit(&app, env, me).await;
                    let _ = tx.send(reply_json(&id, r));
                });
                Ok(None)
            }
            Err((id, e)) => Ok(Some(Message::Text(
                reply_json(&id, Err(e)).to_string().into(),
            ))),
        },
        Some(Ok(Message::Binary(_))) => Err(Some((
            close_code::UNSUPPORTED,
            "binary messages are not accepted: commands are JSON text".into(),
        ))),
        Some(Ok(Message::Close(_))) | None => Err(None),
        Some(Ok(Message::Ping(_) | Message::Pong(_))) => Ok(None),
        Some(Err(e)) => Err(Some(refusal(&e))),
    }
}

/// The close frame for a read error: over the size limit (1009) or a protocol error (1002).
fn refusal(e: &axum::Error) -> (u16, String) {
    let text = e.to_string();
    if text.contains("too long") || text.contains("Space limit exceeded") {
        (
            close_code::SIZE,
            format!("message over the {} KiB limit", MAX_WS_MESSAGE >> 10),
        )
    } else {
        let mut reason = format!("refused: {text}");
        // A close reason is at most 123 bytes.
        while reason.len() > 120 {
            reason.pop();
        }
        (close_code::PROTOCOL, reason)
    }
}
