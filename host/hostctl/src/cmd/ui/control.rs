//! Who may change the device, and the one long operation that Abort cancels.
//!
//! - **One controller.** Every page (WebSocket session) gets a client number on connecting
//!   ([`Control::join`]). The first page is the controller; later pages are viewers: they see
//!   everything, and their commands that change the device are refused, naming who controls,
//!   until they send `take_control`. The controller that is taken over is told (the `control`
//!   event names the new controller and the one it replaced). When the controller leaves,
//!   the next page that sends a command becomes the controller. The HTTP API
//!   (`POST /api/cmd`, client [`API_CLIENT`]) is a tool on the same machine with the token: it
//!   may change the device while no page controls it, and is refused like a viewer otherwise.
//! - **One long operation.** A release test or a tune is reserved here *before* it is queued
//!   for the device thread ([`Control::admit`]), so a second one (a double click, another
//!   page) is refused at once instead of running after the first. Its [`Cancel`] token is
//!   what `abort` cancels ([`Control::abort`]); the device thread ends the test, restores the
//!   previous config and clears the reservation ([`Control::finish`]).
//!
//! Invariants: at most one controller and at most one operation at any time; every change of
//! either is published to every page (`control` and `op` events, kept for new pages).

use super::wire::Command;
use serde_json::{json, Value};
use std::sync::Mutex;
use std::time::Instant;
use stiffwall_client::Cancel;

/// The client number of the HTTP API.
pub const API_CLIENT: u64 = 0;

/// The running long operation.
#[derive(Debug, Clone)]
pub struct Op {
    /// `"release"` or `"tune"`.
    pub kind: &'static str,
    /// Cancelled by `abort`.
    pub cancel: Cancel,
    /// When it was admitted.
    pub started: Instant,
}

#[derive(Debug, Default)]
struct State {
    controller: Option<u64>,
    next_id: u64,
    op: Option<Op>,
}

/// Control state of one `hostctl ui` run (see the module header).
#[derive(Debug, Default)]
pub struct Control {
    state: Mutex<State>,
}

/// Whether a command changes the device (or what every page sees) rather than only reading.
fn changes_things(cmd: &Command) -> bool {
    !matches!(cmd, Command::Get)
}

impl Control {
    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        // A poisoned lock still holds consistent plain data.
        self.state
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// A new page: its client number, and the `control` event when it became the controller.
    pub fn join(&self) -> (u64, Option<Value>) {
        let mut s = self.lock();
        s.next_id += 1;
        let id = s.next_id;
        if s.controller.is_none() {
            s.controller = Some(id);
            return (id, Some(control_event(Some(id), None)));
        }
        (id, None)
    }

    /// A page left: the `control` event when it was the controller.
    pub fn leave(&self, id: u64) -> Option<Value> {
        let mut s = self.lock();
        (s.controller == Some(id)).then(|| {
            s.controller = None;
            control_event(None, Some(id))
        })
    }

    /// `take_control` from `id`: the `control` event naming the page taken over.
    pub fn take(&self, id: u64) -> Value {
        let mut s = self.lock();
        let before = s.controller.replace(id);
        control_event(Some(id), before.filter(|&b| b != id))
    }

    /// The controller now.
    pub fn controller(&self) -> Option<u64> {
        self.lock().controller
    }

    /// Checks that `who` may run `cmd` now. Returns the `control` event when `who` became the
    /// controller (no one held control), and for a release or a tune the reserved operation's
    /// token and its `op` event.
    ///
    /// # Errors
    /// `who` is a viewer, or a long operation is running (in the page's words).
    pub fn admit(&self, who: u64, cmd: &Command) -> Result<Admitted, String> {
        let mut s = self.lock();
        let mut admitted = Admitted::default();
        if changes_things(cmd) {
            match s.controller {
                Some(c) if c != who => {
                    return Err(format!(
                        "this page is a viewer: {} controls the device (press Take control to \
                         change it from here)",
                        client_name(c)
                    ))
                }
                None if who != API_CLIENT => {
                    s.controller = Some(who);
                    admitted.control = Some(control_event(Some(who), None));
                }
                _ => {}
            }
        }
        if let Some(op) = &s.op {
            if !matches!(cmd, Command::Get | Command::Velocity(_)) {
                return Err(format!(
                    "a {} is running ({:.0} s so far): press Abort or wait for it to end",
                    op.kind,
                    op.started.elapsed().as_secs_f64()
                ));
            }
        }
        let kind = match cmd {
            Command::Release(_) => "release",
            Command::Tune(_) => "tune",
            _ => return Ok(admitted),
        };
        let op = Op {
            kind,
            cancel: Cancel::on_ctrl_c(),
            started: Instant::now(),
        };
        admitted.cancel = Some(op.cancel.clone());
        admitted.op = Some(op_event(Some(kind)));
        s.op = Some(op);
        Ok(admitted)
    }

    /// `abort` from `who`: cancels the running operation.
    ///
    /// # Errors
    /// `who` is a viewer, or nothing is running.
    pub fn abort(&self, who: u64) -> Result<Value, String> {
        let s = self.lock();
        if let Some(c) = s.controller.filter(|&c| c != who) {
            return Err(format!(
                "this page is a viewer: {} controls the device (press Take control to abort \
                 from here)",
                client_name(c)
            ));
        }
        match &s.op {
            Some(op) => {
                op.cancel.cancel();
                Ok(json!({"aborting": op.kind}))
            }
            None => Err("nothing to abort: no release test or tune is running".into()),
        }
    }

    /// The running operation's token (the device thread checks it).
    pub fn op_cancel(&self) -> Option<Cancel> {
        self.lock().op.as_ref().map(|o| o.cancel.clone())
    }

    /// The device thread finished the operation: the `op` event.
    pub fn finish(&self) -> Value {
        self.lock().op = None;
        op_event(None)
    }
}

/// What [`Control::admit`] decided beside admitting the command.
#[derive(Debug, Default)]
pub struct Admitted {
    /// The `control` event, when the sender became the controller.
    pub control: Option<Value>,
    /// The reserved operation's token (a release or a tune).
    pub cancel: Option<Cancel>,
    /// The `op` event of the reservation.
    pub op: Option<Value>,
}

fn client_name(id: u64) -> String {
    if id == API_CLIENT {
        "the HTTP API".into()
    } else {
        format!("page {id}")
    }
}

fn control_event(controller: Option<u64>, replaced: Option<u64>) -> Value {
    json!({"type": "control", "controller": controller, "replaced": replaced})
}

fn op_event(running: Option<&str>) -> Value {
    json!({"type": "op", "running": running})
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cmd::ui::wire::{ReleaseTest, TuneTest};

    fn release() -> Command {
        Command::Release(ReleaseTest {
            deflection: 20,
            ticks: 3000,
            stiffness: None,
        })
    }

    #[test]
    fn the_first_page_controls_and_a_second_is_a_viewer_until_it_takes_control() {
        let c = Control::default();
        let (a, ev) = c.join();
        assert_eq!(ev.unwrap()["controller"], a);
        let (b, ev) = c.join();
        assert!(ev.is_none());
        let e = c.admit(b, &Command::ClearFaults).unwrap_err();
        assert!(
            e.contains("viewer") && e.contains(&format!("page {a}")),
            "{e}"
        );
        assert!(c.admit(b, &Command::Get).is_ok(), "a viewer may read");
        let ev = c.take(b);
        assert_eq!(
            (ev["controller"].as_u64(), ev["replaced"].as_u64()),
            (Some(b), Some(a))
        );
        assert!(c.admit(a, &Command::ClearFaults).is_err());
        assert!(c.admit(API_CLIENT, &Command::ClearFaults).is_err());
        assert!(c.leave(b).is_some());
        // No controller: the API may act without taking control; a page takes it.
        assert!(c
            .admit(API_CLIENT, &Command::ClearFaults)
            .unwrap()
            .control
            .is_none());
        assert_eq!(
            c.admit(a, &Command::ClearFaults).unwrap().control.unwrap()["controller"],
            a
        );
    }

    #[test]
    fn one_operation_at_a_time_and_abort_cancels_it() {
        let c = Control::default();
        let (a, _) = c.join();
        assert!(c.abort(a).is_err(), "nothing to abort");
        let first = c.admit(a, &Command::Tune(TuneTest::default())).unwrap();
        let token = first.cancel.unwrap();
        let e = c.admit(a, &release()).unwrap_err();
        assert!(
            e.contains("a tune is running") && e.contains("Abort"),
            "{e}"
        );
        assert!(
            c.admit(a, &Command::Tune(TuneTest::default())).is_err(),
            "double click"
        );
        assert!(!token.is_cancelled());
        c.abort(a).unwrap();
        assert!(token.is_cancelled());
        assert_eq!(c.finish()["running"], Value::Null);
        assert!(c.admit(a, &release()).unwrap().cancel.is_some());
    }
}
