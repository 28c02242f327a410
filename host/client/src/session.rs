//! One telemetry session with a device, shared by `hostctl stream` and `hostctl record`:
//! the plan (what to stream), the pump (the stream loop with its gap bookkeeping), and the
//! lossless recorder on top of it (file format: [`crate::recording`]).
//!
//! Units: `seconds` in a [`Plan`] is *device* time (servo ticks / servo rate), so a `--fast`
//! virtual device covers the same sample numbers as a paced one, only sooner; a plan covers
//! exactly ⌈seconds · rate / decimation⌉ sample numbers. Wall-clock figures (samples per wall
//! second) are reported separately in [`Stats`].
//!
//! Invariants: every sample received is passed on once, in order; every gap in the device's
//! sample numbers is counted where it happened and attributed to the device (its `dropped`
//! counter grew) or to the link; a disconnect or a silent device ends the session with what
//! was received ([`End`]) instead of an error. The recorder flushes at least every 100 ms.

use crate::client::{Client, HEARTBEAT_PERIOD};
use crate::error::ClientError;
use crate::recording::{Header, RecordingError, Writer};
use std::io::Write;
use std::time::{Duration, Instant};
use stiffwall_proto::{HostMsg, ServoConfig, TelemetryBatch};

/// Why a session could not run (device trouble *during* a stream is not an error: it ends the
/// stream, see [`End`]).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SessionError {
    /// A number of the plan out of range (`name`: `"decimation"` or `"seconds"`; `range` in
    /// words, e.g. `"within [1, 65535]"`).
    #[error("{name} must be {range} (got {got})")]
    OutOfRange {
        /// The plan's field.
        name: &'static str,
        /// Its allowed range, in words.
        range: &'static str,
        /// The value given.
        got: String,
    },
    /// A release test was asked for with a decimation other than 1.
    #[error("a release test needs decimation 1 (experiments stream every tick)")]
    ReleaseNeedsEveryTick,
    /// The device failed before the stream started.
    #[error(transparent)]
    Client(#[from] ClientError),
    /// The recording could not be written.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// A [`pump`] sink failed.
    #[error(transparent)]
    Sink(Box<dyn std::error::Error + Send + Sync>),
}

/// Whether Ctrl-C ([`crate::cancel::ctrl_c`]) was pressed.
#[must_use]
pub fn interrupted() -> bool {
    crate::cancel::ctrl_c().is_cancelled()
}

/// What to stream.
#[derive(Debug, Clone, Copy)]
pub struct Plan {
    /// Servo ticks per sample (≥ 1).
    pub decimation: u16,
    /// Sample numbers to cover (None: until interrupted).
    pub samples: Option<u64>,
    /// Run a release test from this deflection while streaming.
    pub release: Option<i32>,
}

impl Plan {
    /// Validated plan; `seconds` None means until interrupted.
    pub fn new(decimation: i64, seconds: Option<f64>, rate_hz: u32) -> Result<Self, SessionError> {
        if !(1..=65_535).contains(&decimation) {
            return Err(SessionError::OutOfRange {
                name: "decimation",
                range: "within [1, 65535]",
                got: decimation.to_string(),
            });
        }
        let samples = match seconds {
            None => None,
            Some(s) if s.is_finite() && s > 0.0 && s <= 1.0e6 => {
                Some(((s * f64::from(rate_hz.max(1)) / decimation as f64).ceil() as u64).max(1))
            }
            Some(s) => {
                return Err(SessionError::OutOfRange {
                    name: "seconds",
                    range: "a finite number within (0, 1e6]",
                    got: s.to_string(),
                })
            }
        };
        Ok(Self {
            decimation: decimation as u16,
            samples,
            release: None,
        })
    }
}

/// How a stream ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum End {
    /// All planned samples covered.
    Complete,
    /// Ctrl-C, or the client's [`crate::Cancel`] token.
    Interrupted,
    /// The device closed the connection or a read failed (message).
    Disconnected(String),
    /// No telemetry for too long.
    Silent(Duration),
}

/// Bookkeeping of one stream.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Stats {
    /// Samples received (and passed on).
    pub received: u64,
    /// Sample numbers missing between received samples.
    pub missing: u64,
    /// Of those, dropped on the device (its queue was full).
    pub device_dropped: u64,
    /// Of those, lost on the link.
    pub link_lost: u64,
    /// Frames that failed to decode during the stream.
    pub bad_frames: u64,
    /// Gap events (places where samples are missing).
    pub gap_events: u64,
    /// First and last sample numbers received.
    pub first_seq: Option<u32>,
    /// Last sample number received.
    pub last_seq: Option<u32>,
    /// Wall time streamed, s.
    pub wall_s: f64,
}

impl Stats {
    /// One-line summary.
    #[must_use]
    pub fn summary(&self) -> String {
        format!(
            "received {}, missing {} in {} gap(s) (device-dropped {}, link-lost {}), bad frames {}, {:.3} s wall, {:.0} samples/s",
            self.received,
            self.missing,
            self.gap_events,
            self.device_dropped,
            self.link_lost,
            self.bad_frames,
            self.wall_s,
            self.received as f64 / self.wall_s.max(1e-9)
        )
    }
}

/// Streams telemetry per `plan`, calling `sink(batch_seq, samples, missing_before,
/// device_dropped_of_those, stats)` for every batch (trimmed to the plan). Stops streaming
/// (best effort) before returning. Errors only for failures before the stream started
/// and the sink's own errors (a sink's error of its own: [`SessionError::Sink`]).
pub fn pump(
    client: &mut Client,
    plan: &Plan,
    mut sink: impl FnMut(u32, &[stiffwall_proto::Sample], u64, u64, &Stats) -> Result<(), SessionError>,
) -> Result<(End, Stats), SessionError> {
    let failed = SessionError::Client;
    let cfg = client.get_config().map_err(failed)?;
    let rate = f64::from(cfg.servo_rate_hz.max(1));
    let silence = Duration::from_secs_f64((3.0 * f64::from(plan.decimation) / rate).max(2.0));
    let bad0 = client.gaps().bad_frames;
    let experiment = start(client, plan)?;
    let mut st = Stats::default();
    let mut next: Option<u32> = None;
    let mut last_dropped = 0u32;
    let started = Instant::now();
    let mut last_data = Instant::now();
    let mut last_hb = Instant::now();
    let end = loop {
        let batch = match poll(client, experiment, silence, &mut last_hb, last_data) {
            Ok(Some(b)) => b,
            Ok(None) => continue,
            Err(end) => break end,
        };
        last_data = Instant::now();
        st.bad_frames = client.gaps().bad_frames - bad0;
        let first = *st.first_seq.get_or_insert(batch.seq);
        let (missing, dev) = match next {
            Some(expect) => match count_gap(&mut st, plan, expect, first, &batch, last_dropped) {
                Some(gap) => gap,
                // A stale or repeated batch: never written twice.
                None => continue,
            },
            None => (0, 0),
        };
        last_dropped = batch.dropped;
        let take = planned_take(plan, &batch, first);
        if take == 0 {
            // The batch lies past the plan's end: samples missing before it inside the plan
            // are a trailing gap, counted above and written here (an empty batch at the
            // plan's end), so the file accounts for every planned sample.
            if let (Some(expect), true) = (next, missing > 0) {
                let end_seq = expect.wrapping_add(missing as u32);
                st.wall_s = started.elapsed().as_secs_f64();
                if let Err(e) = sink(end_seq, &[], missing, dev, &st) {
                    let _ = client.stream_stop();
                    return Err(e);
                }
            }
            break End::Complete;
        }
        let samples = &batch.samples[..take];
        st.received += take as u64;
        st.last_seq = Some(batch.seq.wrapping_add(take as u32 - 1));
        next = Some(batch.seq.wrapping_add(batch.samples.len() as u32));
        st.wall_s = started.elapsed().as_secs_f64();
        if let Err(e) = sink(batch.seq, samples, missing, dev, &st) {
            let _ = client.stream_stop();
            return Err(e);
        }
        if let Some(n) = plan.samples {
            if u64::from(next.unwrap_or(first).wrapping_sub(first)) >= n {
                break End::Complete;
            }
        }
    };
    st.wall_s = started.elapsed().as_secs_f64();
    stop(client, experiment, &end);
    Ok((end, st))
}

/// One wait for telemetry: ends the stream on cancellation, sends the heartbeat when due
/// (during an `experiment`) and waits up to 50 ms for the next batch. `Ok(None)`: no batch
/// yet, and the last (at `last_data`) is not older than `silence`; `Err`: how the stream ended.
fn poll(
    client: &mut Client,
    experiment: bool,
    silence: Duration,
    last_hb: &mut Instant,
    last_data: Instant,
) -> Result<Option<TelemetryBatch>, End> {
    if client.cancel_token().is_cancelled() {
        return Err(End::Interrupted);
    }
    if experiment && last_hb.elapsed() >= HEARTBEAT_PERIOD {
        if let Err(e) = client.send(&HostMsg::Heartbeat) {
            return Err(End::Disconnected(format!("{e:#}")));
        }
        *last_hb = Instant::now();
    }
    match client.next_batch(Duration::from_millis(50)) {
        Ok(Some(b)) => Ok(Some(b)),
        Ok(None) => {
            if last_data.elapsed() > silence {
                return Err(End::Silent(last_data.elapsed()));
            }
            Ok(None)
        }
        Err(e) => Err(End::Disconnected(format!("{e:#}"))),
    }
}

/// How many of `batch`'s samples lie inside the plan (the session's first sample at `first`).
fn planned_take(plan: &Plan, batch: &TelemetryBatch, first: u32) -> usize {
    let mut take = batch.samples.len();
    if let Some(n) = plan.samples {
        let covered = u64::from(batch.seq.wrapping_sub(first));
        take = take.min(n.saturating_sub(covered) as usize);
    }
    take
}

/// Stops the experiment (if one runs) and the stream, best effort, unless the stream `end`ed
/// in a disconnect.
fn stop(client: &mut Client, experiment: bool, end: &End) {
    if !matches!(end, End::Disconnected(_)) {
        if experiment {
            let _ = client.request(&HostMsg::Stop);
        }
        let _ = client.stream_stop();
    }
}

/// Starts the stream (and the plan's release test); whether an experiment runs.
fn start(client: &mut Client, plan: &Plan) -> Result<bool, SessionError> {
    client
        .stream_start(plan.decimation)
        .map_err(SessionError::Client)?;
    let Some(d) = plan.release else {
        return Ok(false);
    };
    if plan.decimation != 1 {
        let _ = client.stream_stop();
        return Err(SessionError::ReleaseNeedsEveryTick);
    }
    let ticks = plan
        .samples
        .unwrap_or(u64::from(u32::MAX))
        .clamp(1, 10_000_000) as u32;
    if let Err(e) = client.request(&HostMsg::Release {
        deflection_ticks: d,
        ticks,
    }) {
        let _ = client.stream_stop();
        return Err(SessionError::Client(e));
    }
    Ok(true)
}

/// The samples missing before `batch` (expected at `expect`; the session's first at `first`),
/// counted into `st`: (missing, of them dropped by the device). Only the part of a gap inside
/// the plan counts. None for a stale or repeated batch (a gap of half the sequence space).
fn count_gap(
    st: &mut Stats,
    plan: &Plan,
    expect: u32,
    first: u32,
    batch: &TelemetryBatch,
    last_dropped: u32,
) -> Option<(u64, u64)> {
    let gap = batch.seq.wrapping_sub(expect);
    if gap >= u32::MAX / 2 {
        return None;
    }
    let gap = match plan.samples {
        Some(n) => u64::from(gap).min(n.saturating_sub(u64::from(expect.wrapping_sub(first)))),
        None => u64::from(gap),
    };
    if gap == 0 {
        return Some((0, 0));
    }
    let dev = u64::from(batch.dropped.wrapping_sub(last_dropped)).min(gap);
    st.missing += gap;
    st.device_dropped += dev;
    st.link_lost += gap - dev;
    st.gap_events += 1;
    Some((gap, dev))
}

/// Header facts of a recording made through `client` now, of the target described as `target`
/// (`virtual_plant`: the virtual device's plant name, when the target is the virtual device).
pub fn header_for_target(
    client: &Client,
    cfg: ServoConfig,
    decimation: u16,
    target: String,
    virtual_plant: Option<String>,
) -> Header {
    Header {
        host_time_unix_s: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64()),
        target,
        virtual_plant,
        decimation,
        device: client.info.clone(),
        config: cfg,
    }
}

/// Result of [`record`].
#[derive(Debug, Clone)]
pub struct Outcome {
    /// How the stream ended.
    pub end: End,
    /// Its bookkeeping.
    pub stats: Stats,
    /// Rows written.
    pub rows: u64,
}

/// Records per `plan` into `out` with `header`; writes the `# end:` note. I/O errors on the
/// file are errors; device trouble is reported in the outcome.
pub fn record<W: Write>(
    client: &mut Client,
    plan: &Plan,
    header: &Header,
    out: W,
    mut progress: impl FnMut(&Stats),
) -> Result<Outcome, SessionError> {
    let mut w = Writer::new(out, header)?;
    let mut last_flush = Instant::now();
    let (end, stats) = pump(client, plan, |seq, samples, _missing, dev, st| {
        w.batch(seq, samples, dev)?;
        if last_flush.elapsed() >= Duration::from_millis(100) {
            w.flush()?;
            last_flush = Instant::now();
            progress(st);
        }
        Ok(())
    })?;
    let how = match &end {
        End::Complete => "complete".to_string(),
        End::Interrupted => "interrupted (Ctrl-C or cancelled)".to_string(),
        End::Disconnected(e) => format!("DISCONNECTED: {e}"),
        End::Silent(d) => format!("DEVICE SILENT for {:.1} s", d.as_secs_f64()),
    };
    w.note(&format!("end: {}; {}", stats.summary(), how))?;
    let rows = w.rows();
    w.finish()?;
    Ok(Outcome { end, stats, rows })
}
