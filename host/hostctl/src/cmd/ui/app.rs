//! How a command is run, whoever sends it (a page over the WebSocket, a tool over
//! `POST /api/cmd`): [`submit`] answers `abort` and `take_control` itself, has
//! [`super::control`] admit the rest (the controller, the one long operation) and queues them
//! for the device thread; [`reply_json`] is the answer as the page reads it. A leaf of the
//! server: `server.rs` and `ws.rs` both import it.

use super::device::{Request, Shared};
use super::security::Guard;
use super::wire::{Command, Envelope, Reply};
use serde_json::{json, Value};
use std::sync::{mpsc, Arc, Mutex};

/// What the handlers share.
#[derive(Debug, Clone)]
pub struct App {
    /// The request checks.
    pub guard: Arc<Guard>,
    /// State from the device thread.
    pub shared: Arc<Shared>,
    /// Commands to the device thread.
    pub commands: Arc<Mutex<mpsc::Sender<Request>>>,
}

/// Runs a command from client `who` ([`super::control::API_CLIENT`] for the HTTP API):
/// `abort` and `take_control` here, the rest by the device thread once [`super::control`]
/// admitted it; waits for the answer.
pub async fn submit(app: &App, env: Envelope, who: u64) -> Reply {
    let control = &app.shared.control;
    match env.cmd {
        Command::Abort => return control.abort(who),
        Command::TakeControl => {
            if who == super::control::API_CLIENT {
                return Err("take_control is for pages (the HTTP API acts while no page controls the device)".into());
            }
            let ev = control.take(who);
            app.shared.publish("control", ev.clone());
            return Ok(ev);
        }
        _ => {}
    }
    let admitted = control.admit(who, &env.cmd)?;
    if let Some(ev) = admitted.control {
        app.shared.publish("control", ev);
    }
    if let Some(ev) = admitted.op {
        app.shared.publish("op", ev);
    }
    // The device thread clears a reservation when its operation ends, however it ends.
    queue(app, env).await
}

/// Sends a command to the device thread and waits for its answer.
async fn queue(app: &App, env: Envelope) -> Reply {
    let (tx, rx) = tokio::sync::oneshot::channel();
    let sent = app
        .commands
        .lock()
        .map_err(|_| "the device thread stopped".to_string())?
        .send(Request {
            cmd: env.cmd,
            reply: tx,
        });
    if sent.is_err() {
        return Err("the device thread stopped".into());
    }
    rx.await
        .unwrap_or_else(|_| Err("the device thread stopped".into()))
}

/// The answer to a command as the page reads it.
pub fn reply_json(id: &Value, r: Reply) -> Value {
    match r {
        Ok(v) => json!({"type": "reply", "id": id, "ok": true, "result": v}),
        Err(e) => json!({"type": "reply", "id": id, "ok": false, "error": e}),
    }
}
