//! The device thread's plain state (a leaf of `device`): what it shares with the server
//! ([`Shared`], [`Snapshot`], [`Request`]), the run's fixed facts ([`Setup`]) and the thread's
//! own state (`Dev`, a running `Release`). The behaviour is in `device.rs` (the loop, config,
//! faults, recording), `release.rs` and `tune.rs`, which import this file and not each other.

use crate::cmd::ui::control::Control;
use crate::cmd::ui::record::Recorder;
use crate::cmd::ui::wire::{Command, Reply};
use crate::device::connect::ConnectArgs;
use axum::extract::ws::Message;
use serde_json::Value;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use stiffwall_analysis::live::plane::Model;
use stiffwall_client::Client;
use stiffwall_proto::{Sample, ServoConfig};
use tokio::sync::broadcast;

/// What the pages see on connecting, kept current by the device thread.
#[derive(Debug, Default)]
pub struct Snapshot {
    /// The `hello` message.
    pub hello: Value,
    /// The latest `config`, `plane`, `status`, `faults`, `release` and `tune` messages.
    pub latest: Vec<(&'static str, Value)>,
}

impl Snapshot {
    fn set(&mut self, kind: &'static str, v: Value) {
        match self.latest.iter_mut().find(|(k, _)| *k == kind) {
            Some(slot) => slot.1 = v,
            None => self.latest.push((kind, v)),
        }
    }
}

/// State shared between the device thread and the server.
#[derive(Debug)]
pub struct Shared {
    /// The messages of a newly opened page.
    pub snapshot: Mutex<Snapshot>,
    /// Every message to every page.
    pub tx: broadcast::Sender<Message>,
    /// Set to end the device thread (server shutdown).
    pub stop: AtomicBool,
    /// The controlling page and the running long operation.
    pub control: Control,
}

impl Shared {
    /// New shared state with room for `capacity` queued messages per page.
    #[must_use]
    pub fn new(capacity: usize) -> Self {
        Self {
            snapshot: Mutex::new(Snapshot::default()),
            tx: broadcast::channel(capacity).0,
            stop: AtomicBool::new(false),
            control: Control::default(),
        }
    }

    /// Sends `v` to every page and keeps it as the latest of its `type`.
    pub fn publish(&self, kind: &'static str, v: Value) {
        let text = v.to_string();
        if let Ok(mut s) = self.snapshot.lock() {
            s.set(kind, v);
        }
        let _ = self.tx.send(Message::Text(text.into()));
    }

    /// Sends `v` to every page without keeping it.
    pub fn event(&self, v: &Value) {
        let _ = self.tx.send(Message::Text(v.to_string().into()));
    }
}

/// A command with the channel its answer goes to.
#[derive(Debug)]
pub struct Request {
    /// The command.
    pub cmd: Command,
    /// Where the answer goes.
    pub reply: tokio::sync::oneshot::Sender<Reply>,
}

/// Fixed facts of the run.
#[derive(Debug, Clone)]
pub struct Setup {
    /// How the device was reached (for recordings' headers and the page).
    pub connect: ConnectArgs,
    /// The model of the (β, σ) plane, if known.
    pub model: Option<Model>,
    /// Directory recordings from the page are written to.
    pub record_dir: PathBuf,
    /// Pace the stream (sleep between reads) because the virtual device runs `--fast`.
    pub pace: bool,
    /// The `--profile` file loaded at start (names the active profile's elements, its check).
    pub profile: Option<crate::cmd::ui::profile::Loaded>,
}

/// The thread's state.
pub(super) struct Dev {
    pub(super) client: Client,
    pub(super) setup: Setup,
    pub(super) shared: Arc<Shared>,
    pub(super) cfg: ServoConfig,
    pub(super) xidot: f64,
    pub(super) streaming: bool,
    pub(super) frame: Vec<u8>,
    pub(super) chunks: u32,
    pub(super) last_frame: Instant,
    pub(super) last_status: Instant,
    pub(super) last_fault_poll: Instant,
    pub(super) last_sample: Option<Sample>,
    pub(super) safe_mode: bool,
    pub(super) faults: u32,
    pub(super) rate: (Instant, u64, f64),
    pub(super) rec: Option<Recorder>,
    pub(super) release: Option<Release>,
}

/// A running release test.
pub(super) struct Release {
    pub(super) original: ServoConfig,
    pub(super) test: ServoConfig,
    pub(super) deflection: i32,
    /// Released counts (effective ticks, as `released_counts`).
    pub(super) counts: Vec<i64>,
    /// Tick of the first hold or released sample.
    pub(super) first_tick: Option<u32>,
    pub(super) start: Instant,
    pub(super) limit: Duration,
    pub(super) last_hb: Instant,
    /// `Stop` was sent because the page aborted.
    pub(super) aborted: bool,
    pub(super) reply: Option<tokio::sync::oneshot::Sender<Reply>>,
}

impl Release {
    /// Coarsening shift of the test's config (to turn counts into effective ticks).
    pub(super) fn shift(&self) -> u8 {
        self.test.coarsen_shift
    }
}
