//! The device thread of `hostctl ui`: the one owner of the [`Client`]. It streams telemetry at
//! one sample per servo tick, passes every sample to the recorder (when one runs) and to the
//! pages (in 25 ms binary frames, see [`super::wire`]), and runs the pages' commands between
//! reads with the same functions as the command-line tools: `config set`'s
//! [`Overrides::set_on`], `experiment release`'s checks and verdict, `tune`'s
//! [`stiffwall_tune::tune`], and `record`'s [`Writer`] and header.
//!
//! Units: device integers in telemetry (ticks, raw counts, output codes, energy in K·Δ_eff²/8);
//! SI for the model and K. Invariants: the recorder sees every batch the device sends, in
//! order, with every gap noted (device-dropped vs link-lost) exactly as `hostctl record`
//! writes it; requests made while streaming queue the telemetry that arrives meanwhile (the
//! client keeps it), so commands never lose samples. A release test runs inside the stream
//! (the firmware streams every tick during experiments), so its trace is live and a recording
//! made meanwhile stays lossless. `tune` needs the link for itself: it is refused while
//! recording, and the stream pauses while it runs. A slow page loses display frames only
//! (counted and shown), never recorded samples.

mod release;
mod state;
mod tune;
pub use release::{check_release_fields, MAX_RELEASE_SECONDS};
use state::Dev;
pub use state::{Request, Setup, Shared, Snapshot};
pub use tune::{page_error, page_settings};

use super::record::{finish_recording, record_batch, record_path, Recorder};
use super::wire::{self, Command, Reply};
use crate::config_flags::Overrides;
use crate::session;
use anyhow::{bail, Context, Result};
use axum::extract::ws::Message;
use serde_json::{json, Value};
use std::io::BufWriter;
use std::sync::atomic::Ordering;
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};
use stiffwall_analysis::live::plane;
use stiffwall_client::Client;
use stiffwall_client::Stats;
use stiffwall_client::Writer;
use stiffwall_proto::{flags, DeviceMsg, ExperimentKind, Sample, ServoConfig};

/// Period of the binary telemetry frames sent to the pages.
pub const FRAME_PERIOD: Duration = Duration::from_millis(25);
/// Period of the status messages.
pub const STATUS_PERIOD: Duration = Duration::from_millis(250);
/// Period of fault polls (`GetFaults`) while the device reports safe mode.
pub const FAULT_POLL: Duration = Duration::from_millis(500);
/// Recordings are flushed at least this often (as `hostctl record`).
pub const FLUSH_PERIOD: Duration = Duration::from_millis(100);

/// Runs the device thread until `shared.stop` or Ctrl-C; finishes a recording cleanly.
///
/// # Errors
/// The device could not be read from the start (later link failures are reported to the
/// pages and end the thread).
pub fn run(
    client: Client,
    setup: Setup,
    shared: Arc<Shared>,
    rx: mpsc::Receiver<Request>,
) -> Result<()> {
    let mut client = client;
    let cfg = client.get_config()?;
    let mut d = Dev {
        client,
        setup,
        shared,
        cfg,
        xidot: stiffwall_tune::DEFAULT_XIDOT,
        streaming: false,
        frame: Vec::new(),
        chunks: 0,
        last_frame: Instant::now(),
        last_status: Instant::now(),
        last_fault_poll: Instant::now(),
        last_sample: None,
        safe_mode: false,
        faults: 0,
        rate: (Instant::now(), 0, 0.0),
        rec: None,
        release: None,
    };
    d.hello();
    d.publish_config();
    d.publish_profile();
    d.poll_faults();
    d.start_stream()?;
    let result = d.main_loop(&rx);
    if let Some(r) = d.rec.take() {
        let how = match &result {
            Ok(()) => "hostctl ui stopped".to_string(),
            Err(e) => format!(
                "DISCONNECTED: {e_text}",
                e_text = crate::cli_error::message(&e)
            ),
        };
        let _ = finish_recording(r, &how);
    }
    if let Err(e) = &result {
        d.shared.publish(
            "device",
            json!({"type": "device", "error": crate::cli_error::message(&e)}),
        );
    }
    let _ = d.client.stream_stop();
    result
}

impl Dev {
    fn main_loop(&mut self, rx: &mpsc::Receiver<Request>) -> Result<()> {
        loop {
            if self.shared.stop.load(Ordering::Relaxed) || stiffwall_client::interrupted() {
                return Ok(());
            }
            while let Ok(req) = rx.try_recv() {
                self.command(req.cmd, req.reply);
            }
            match self.client.recv(Duration::from_millis(5))? {
                Some(DeviceMsg::Telemetry(b)) => self.batch(b.seq, b.dropped, &b.samples)?,
                Some(DeviceMsg::ExperimentDone {
                    kind: ExperimentKind::Release,
                    completed,
                    faults,
                }) => self.release_done(completed, faults),
                Some(_) | None => {}
            }
            self.tick()?;
            if self.setup.pace && self.release.is_none() {
                // The --fast virtual device runs as fast as it is read: pace it to about
                // 24 samples per ms so the pages see a moving trace and the CPU stays free.
                std::thread::sleep(Duration::from_millis(1));
            }
        }
    }

    fn hello(&self) {
        let i = &self.client.info;
        let rotational = i.counts_per_rev > 0;
        let hello = json!({
            "type": "hello",
            "target": self.setup.connect.describe(),
            "device": i,
            "units": if rotational {
                json!({"k": "N·m/rad", "force": "N·m", "b": "N·m·s/rad", "m": "kg·m²", "c": "N·m", "v": "rad/s"})
            } else {
                json!({"k": "N/m", "force": "N", "b": "N·s/m", "m": "kg", "c": "N", "v": "m/s"})
            },
            "record_dir": self.setup.record_dir.display().to_string(),
            "flags": {"safe_mode": flags::SAFE_MODE, "hold": flags::HOLD, "released": flags::RELEASED,
                      "excite": flags::EXCITE, "clamped": flags::CLAMPED, "wall_off": flags::WALL_OFF,
                      "turn": flags::TURN},
        });
        if let Ok(mut s) = self.shared.snapshot.lock() {
            s.hello = hello.clone();
        }
        self.shared.event(&hello);
    }

    fn publish_config(&self) {
        self.shared.publish(
            "config",
            json!({"type": "config", "config": self.cfg,
                   "text": crate::output::config_table(&self.cfg, self.client.info.counts_per_rev > 0)}),
        );
        self.shared.publish(
            "plane",
            plane::plane(
                self.setup.model.as_ref(),
                &self.client.info,
                &self.cfg,
                self.xidot,
            ),
        );
    }

    /// The device's active profile (asked at connect), named and checked by `--profile`'s
    /// file when it is what that file loaded.
    fn publish_profile(&mut self) {
        match self.client.get_profile() {
            Ok(p) => self.shared.publish(
                "profile",
                super::profile::message(&self.client.info, &p, self.setup.profile.as_ref()),
            ),
            Err(e) => self.shared.event(&json!({"type": "log", "level": "error",
                "message": format!("reading the device's profile: {e_text}", e_text = crate::cli_error::message(&e))})),
        }
    }

    fn start_stream(&mut self) -> Result<()> {
        self.client.stream_start(1).context("starting telemetry")?;
        self.streaming = true;
        Ok(())
    }

    /// One telemetry batch: recorder, release test, page frame.
    fn batch(&mut self, seq: u32, dropped: u32, samples: &[Sample]) -> Result<()> {
        if let Some(r) = &mut self.rec {
            if let Err(e) = record_batch(r, seq, dropped, samples, self.client.gaps().bad_frames) {
                let r = self.rec.take().expect("recorder");
                let path = r.path.clone();
                let _ = finish_recording(
                    r,
                    &format!("FAILED: {e_text}", e_text = crate::cli_error::message(&e)),
                );
                self.shared.event(&json!({"type": "log", "level": "error",
                    "message": format!("recording {} stopped: {e_text}", path.display(), e_text = crate::cli_error::message(&e))}));
            }
        }
        if let Some(rel) = &mut self.release {
            let shift = rel.shift();
            for s in samples {
                if s.flags & (flags::HOLD | flags::RELEASED) != 0 && rel.first_tick.is_none() {
                    rel.first_tick = Some(s.tick);
                }
                if s.flags & flags::RELEASED != 0 {
                    rel.counts.push(i64::from(s.count) >> shift);
                }
            }
        }
        if let Some(last) = samples.last() {
            self.last_sample = Some(*last);
            let safe = last.flags & flags::SAFE_MODE != 0;
            if safe != self.safe_mode {
                self.safe_mode = safe;
                self.poll_faults();
            }
        }
        wire::push_chunk(&mut self.frame, seq, samples);
        self.chunks += 1;
        Ok(())
    }

    /// Periodic work: page frames, status, fault polls, heartbeats, release time-out.
    fn tick(&mut self) -> Result<()> {
        if self.last_frame.elapsed() >= FRAME_PERIOD {
            self.last_frame = Instant::now();
            if self.chunks > 0 {
                let msg = wire::frame(self.chunks, &self.frame);
                let _ = self.shared.tx.send(Message::Binary(msg.into()));
                self.frame.clear();
                self.chunks = 0;
            }
        }
        if let Some(r) = &mut self.rec {
            if r.last_flush.elapsed() >= FLUSH_PERIOD {
                r.w.flush()?;
                r.last_flush = Instant::now();
            }
        }
        if self.safe_mode && self.last_fault_poll.elapsed() >= FAULT_POLL {
            self.poll_faults();
        }
        self.release_tick()?;
        if self.last_status.elapsed() >= STATUS_PERIOD {
            self.status();
        }
        Ok(())
    }

    fn status(&mut self) {
        let now = Instant::now();
        let g = self.client.gaps();
        let dt = now.duration_since(self.rate.0).as_secs_f64();
        if dt >= 0.5 {
            self.rate = (now, g.received, (g.received - self.rate.1) as f64 / dt);
        }
        self.last_status = now;
        let rec = self.rec.as_ref().map(|r| {
            json!({"file": r.path.display().to_string(), "rows": r.w.rows(),
                   "missing": r.stats.missing, "seconds": r.start.elapsed().as_secs_f64()})
        });
        let busy = if self.release.is_some() {
            Some("release")
        } else {
            None
        };
        self.shared.publish(
            "status",
            json!({
                "type": "status",
                "received": g.received,
                "missing": g.missing,
                "device_dropped": g.dropped_on_device,
                "bad_frames": g.bad_frames,
                "samples_per_s": self.rate.2,
                "last": self.last_sample,
                "recording": rec,
                "busy": busy,
                "streaming": self.streaming,
            }),
        );
    }

    fn poll_faults(&mut self) {
        self.last_fault_poll = Instant::now();
        match self.client.faults() {
            Ok(f) => {
                self.faults = f.latched;
                self.safe_mode = f.safe_mode;
                self.shared.publish(
                    "faults",
                    json!({"type": "faults", "latched": f.latched, "safe_mode": f.safe_mode,
                           "first_tick": f.first_tick, "names": wire::fault_names(f.latched)}),
                );
            }
            Err(e) => self.shared.event(&json!({"type": "log", "level": "error",
                "message": format!("reading faults: {e_text}", e_text = crate::cli_error::message(&e))})),
        }
    }

    /// Runs one command and answers it (a release test answers when it ends).
    fn command(&mut self, cmd: Command, reply: tokio::sync::oneshot::Sender<Reply>) {
        let r = match cmd {
            Command::Config(set) => self.config(&set),
            Command::ClearFaults => self.clear_faults(),
            Command::Velocity(xidot) => self.velocity(xidot),
            Command::RecordStart(file) => self.record_start(&file),
            Command::RecordStop => self.record_stop(),
            Command::Get => self.get(),
            Command::Tune(args) => self.tune(&args),
            Command::Release(args) => match self.release_start(&args) {
                Ok(()) => {
                    if let Some(rel) = &mut self.release {
                        rel.reply = Some(reply);
                    }
                    return;
                }
                Err(e) => {
                    self.finish_op();
                    Err(crate::cli_error::message(&e))
                }
            },
            Command::Abort | Command::TakeControl => {
                Err("answered by the server, not the device thread".into())
            }
        };
        let _ = reply.send(r);
    }

    /// The running operation ended (however it ended): pages may start another.
    fn finish_op(&self) {
        let ev = self.shared.control.finish();
        self.shared.publish("op", ev);
    }

    fn busy_check(&self, what: &str) -> Result<()> {
        if self.release.is_some() {
            bail!("{what}: a release test is running; wait for its verdict");
        }
        Ok(())
    }

    fn config(&mut self, o: &Overrides) -> Reply {
        let mut run = || -> Result<Value> {
            self.busy_check("config set")?;
            // As `hostctl config set`: bad numbers are refused before the device is asked.
            o.apply(&ServoConfig::default())?;
            if o.is_empty() {
                bail!("config set: give at least one field to change (see `hostctl config set --help`)");
            }
            let cfg = o.set_on(&mut self.client).context("config set")?;
            Ok(json!(cfg))
        };
        let out = run();
        if let Ok(v) = &out {
            if let Ok(cfg) = serde_json::from_value::<ServoConfig>(v.clone()) {
                self.config_changed(cfg);
            }
        }
        out.map_err(|e| crate::cli_error::message(&e))
    }

    fn config_changed(&mut self, cfg: ServoConfig) {
        self.cfg = cfg;
        if let Some(r) = &mut self.rec {
            let _ = r.w.note(&format!(
                "config changed from the page at seq {}: {}",
                r.stats.last_seq.map_or(0, |s| s.wrapping_add(1)),
                serde_json::to_string(&cfg).unwrap_or_default()
            ));
        }
        self.publish_config();
    }

    fn get(&mut self) -> Reply {
        let cfg = self
            .client
            .get_config()
            .map_err(|e| crate::cli_error::message(&e))?;
        let f = self
            .client
            .faults()
            .map_err(|e| crate::cli_error::message(&e))?;
        // The plane message the pages see now (with its (B, K) frontier).
        let plane = self.shared.snapshot.lock().ok().and_then(|s| {
            s.latest
                .iter()
                .find(|(k, _)| *k == "plane")
                .map(|(_, v)| v.clone())
        });
        Ok(
            json!({"config": cfg, "faults": f, "gaps": self.client.gaps(),
                  "release_running": self.release.is_some(), "recording": self.rec.is_some(),
                  "plane": plane}),
        )
    }

    /// Clears the latched faults; when they latch again at once (their cause persists: a K the
    /// device cannot hold, a velocity over the limit), says so in the page's words instead of
    /// answering ok.
    fn clear_faults(&mut self) -> Reply {
        self.client
            .clear_faults()
            .map_err(|e| crate::cli_error::message(&e))?;
        // The servo takes the command on its next tick: a few polls.
        let deadline = Instant::now() + Duration::from_millis(200);
        loop {
            self.poll_faults();
            if self.faults == 0 || Instant::now() > deadline {
                break;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        if self.faults != 0 {
            return Err(format!(
                "the faults latched again at once ({}): their cause persists; set K lower (or 0) \
                 in Config, let the device come to rest, then clear again",
                wire::fault_names(self.faults).join(", ")
            ));
        }
        Ok(json!({"latched": 0}))
    }

    fn velocity(&mut self, xidot: f64) -> Reply {
        if !(xidot.is_finite() && xidot > 0.0 && xidot <= 1e6) {
            return Err(format!(
                "velocity must be a finite number within (0, 1e6] ticks per period (got {xidot})"
            ));
        }
        self.xidot = xidot;
        self.publish_config();
        Ok(json!({"xidot": xidot}))
    }

    fn record_start(&mut self, file: &str) -> Reply {
        let mut run = || -> Result<Value> {
            if let Some(r) = &self.rec {
                bail!("already recording to {}", r.path.display());
            }
            let path = record_path(&self.setup.record_dir, file)?;
            let h = session::header(&self.client, self.cfg, 1, Some(&self.setup.connect));
            let f = std::fs::File::create(&path)
                .with_context(|| format!("creating {}", path.display()))?;
            let w = Writer::new(BufWriter::new(f), &h)?;
            self.rec = Some(Recorder {
                path: path.clone(),
                w,
                stats: Stats::default(),
                last_dropped: None,
                start: Instant::now(),
                last_flush: Instant::now(),
            });
            Ok(json!({"file": path.display().to_string()}))
        };
        let r = run().map_err(|e| crate::cli_error::message(&e));
        self.status();
        r
    }

    fn record_stop(&mut self) -> Reply {
        let Some(r) = self.rec.take() else {
            return Err("not recording".into());
        };
        let out =
            finish_recording(r, "stopped from the page").map_err(|e| crate::cli_error::message(&e));
        self.status();
        out
    }
}
