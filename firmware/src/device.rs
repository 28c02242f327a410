//! The command handler for the main loop: frames in, replies and telemetry batches out.
//!
//! Units: `now` is the servo tick (used only to age partial telemetry batches); bytes on the
//! link are protocol frames ([`stiffwall_proto::frame`]).
//!
//! Invariants:
//! - Every complete well-formed frame gets exactly one reply: the answer, or `Error { code,
//!   detail }`. Frames that fail to decode (distinct code per framing failure) are coalesced:
//!   a run of consecutive bad frames with the same code is answered by one `Error`, whose
//!   detail is the usual one for a single frame and `ErrorDetail::Repeated { count }` for
//!   `count` ≥ 2 frames, so every bad frame is accounted for and a flood of them costs one
//!   reply per run, not one per frame. Bytes are read only while the reply queue (counting the
//!   pending run) has room, so no reply is ever lost; a slow link back-pressures the reader.
//! - Fairness: replies and telemetry share the link. While a telemetry batch is ready, at most
//!   [`REPLY_BUDGET`] replies are sent before it, so neither a flood of requests nor one of bad
//!   frames starves telemetry, and replies still leave at a bounded share of the link.
//! - A refused request (bad range, busy, store failure) changes nothing. `SetConfig` is
//!   validated field by field ([`crate::config::validate`]) before it reaches the servo.
//! - Telemetry batches hold consecutive samples only. The device counts lost samples from the
//!   gaps in the servo's sample numbers, so `TelemetryBatch::dropped` is exact: between two
//!   batches, `seq` jumps by exactly the growth of `dropped`.
//! - `ExperimentDone` is sent after the last telemetry sample of the experiment.
//! - No allocation; bounded work per `poll`.

use crate::channels::{DecidedEnd, HostPort, ServoCmd, ServoEvent};
use crate::config::{validate, BoardInfo, ConfigError};
use crate::hal::{ByteLink, ConfigStorage};
use crate::store::ConfigStore;
use core::sync::atomic::Ordering;
use heapless::Deque;
use stiffwall_proto::{
    encode, ConfigField, DeviceMsg, ErrorCode, ErrorDetail, ExciteProfile, FaultReport,
    FrameDecoder, HostMsg, Request, ServoConfig, TelemetryBatch, MAX_FRAME, MAX_TABLE,
    PROTOCOL_VERSION, TELEMETRY_BATCH,
};

/// Replies queued at most.
const REPLIES: usize = 4;
/// Bytes read per `poll` at most.
const READ_BUDGET: usize = 512;
/// Frames started per `poll` at most.
const FRAME_BUDGET: usize = 4;
/// Replies sent at most in a row while a telemetry batch is ready to go.
pub const REPLY_BUDGET: u8 = 2;
/// Longest experiment, ticks.
pub const MAX_EXPERIMENT_TICKS: u32 = 10_000_000;
/// Largest release deflection, effective ticks.
pub const MAX_DEFLECTION: i32 = 1 << 20;
/// Largest impact launch velocity, thousandths of an effective count per tick.
pub const MAX_LAUNCH_MILLITICKS: i32 = 1_000_000;

/// Counters for diagnostics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DeviceStats {
    /// Frames decoded and handled.
    pub frames_ok: u32,
    /// Frames that failed to decode.
    pub frames_bad: u32,
    /// Requests refused (range, busy, store).
    pub refused: u32,
}

/// The main-loop side of the firmware.
#[derive(Debug)]
pub struct Device<'a, S: ConfigStorage> {
    board: BoardInfo,
    config: ServoConfig,
    defaults: ServoConfig,
    store: ConfigStore<S>,
    port: HostPort<'a>,
    decoder: FrameDecoder,
    tx: [u8; MAX_FRAME],
    tx_len: usize,
    tx_pos: usize,
    replies: Deque<DeviceMsg, REPLIES>,
    /// The current run of bad frames: code, detail of its first frame, frames in the run.
    rejected: Option<(ErrorCode, ErrorDetail, u32)>,
    /// Replies sent since the last telemetry batch (saturating at [`REPLY_BUDGET`]).
    replies_in_row: u8,
    batch: TelemetryBatch,
    batch_tick: u32,
    batch_cut: bool,
    next_seq: u32,
    dropped: u32,
    pending_event: Option<ServoEvent>,
    /// The next test as `PrepareTest` prepared it: (its config, min run, within one count,
    /// decay base).
    end_rule: Option<(ServoConfig, u32, bool, u32)>,
    rate_change: Option<u32>,
    shutdown: Option<u8>,
    stats: DeviceStats,
}

fn seq_reached(next: u32, target: u32) -> bool {
    next.wrapping_sub(target) as i32 >= 0
}

fn invalid(field: ConfigField, min: f64, max: f64) -> DeviceMsg {
    DeviceMsg::Error {
        code: ErrorCode::InvalidArgument,
        detail: ErrorDetail::Field { field, min, max },
    }
}

/// The one reply to a run of `count` bad frames with `code` (`detail`: that of the first).
fn rejected_reply((code, detail, count): (ErrorCode, ErrorDetail, u32)) -> DeviceMsg {
    DeviceMsg::Error {
        code,
        detail: if count > 1 {
            ErrorDetail::Repeated { count }
        } else {
            detail
        },
    }
}

/// A config refused: the field and its range.
fn invalid_config(e: ConfigError) -> DeviceMsg {
    DeviceMsg::Error {
        code: ErrorCode::InvalidConfig,
        detail: ErrorDetail::Field {
            field: e.field,
            min: e.min,
            max: e.max,
        },
    }
}

/// The servo's command queue had no room for the request's command (transient: the host
/// repeats the request).
fn queue_full() -> DeviceMsg {
    DeviceMsg::Error {
        code: ErrorCode::QueueFull,
        detail: ErrorDetail::None,
    }
}

fn busy(text: &str) -> DeviceMsg {
    DeviceMsg::Error {
        code: ErrorCode::Busy,
        detail: ErrorDetail::Text(heapless::String::try_from(text).unwrap_or_default()),
    }
}

impl<'a, S: ConfigStorage> Device<'a, S> {
    /// A device for `board`: loads the newest valid stored config (falling back to `defaults`
    /// when none is stored or it fails validation). Build the [`crate::Servo`] with
    /// [`Device::config`].
    pub fn new(
        board: BoardInfo,
        store: ConfigStore<S>,
        port: HostPort<'a>,
        defaults: ServoConfig,
    ) -> Self {
        let mut store = store;
        let config = match store.load() {
            Some(c) if validate(&c, &board).is_ok() => c,
            _ => defaults,
        };
        Self {
            board,
            config,
            defaults,
            store,
            port,
            decoder: FrameDecoder::new(),
            tx: [0; MAX_FRAME],
            tx_len: 0,
            tx_pos: 0,
            replies: Deque::new(),
            rejected: None,
            replies_in_row: 0,
            batch: TelemetryBatch {
                seq: 0,
                dropped: 0,
                samples: heapless::Vec::new(),
            },
            batch_tick: 0,
            batch_cut: false,
            next_seq: 0,
            dropped: 0,
            pending_event: None,
            end_rule: None,
            rate_change: None,
            shutdown: None,
            stats: DeviceStats::default(),
        }
    }

    /// The active configuration.
    pub fn config(&self) -> &ServoConfig {
        &self.config
    }

    /// The board facts.
    pub fn board(&self) -> &BoardInfo {
        &self.board
    }

    /// The configured servo rate, Hz.
    pub fn servo_rate_hz(&self) -> u32 {
        self.config.servo_rate_hz
    }

    /// A new servo rate the board must program (once per change).
    pub fn take_rate_change(&mut self) -> Option<u32> {
        self.rate_change.take()
    }

    /// An exit code the host asked the board to end its run with (`Shutdown`), once, after
    /// the acknowledgement has been queued; boards that cannot exit ignore it.
    pub fn take_shutdown(&mut self) -> Option<u8> {
        if self.tx_pos < self.tx_len || !self.replies.is_empty() || self.rejected.is_some() {
            return None; // let the Ack leave first
        }
        self.shutdown.take()
    }

    /// Diagnostic counters.
    pub fn stats(&self) -> DeviceStats {
        self.stats
    }

    /// Samples lost on the device so far (from sample-number gaps).
    pub fn dropped(&self) -> u32 {
        self.dropped
    }

    /// The config store.
    pub fn store_mut(&mut self) -> &mut ConfigStore<S> {
        &mut self.store
    }

    /// One main-loop step: read and handle frames, collect telemetry, send what the link takes.
    pub fn poll(&mut self, now: u32, link: &mut impl ByteLink) {
        // 1. Requests (only while a reply has room; the pending run of bad frames holds one).
        let mut budget = READ_BUDGET;
        while budget > 0 && self.replies.len() + usize::from(self.rejected.is_some()) < REPLIES {
            budget -= 1;
            let Some(b) = link.read() else { break };
            match self.decoder.feed::<HostMsg>(b) {
                None => {}
                Some(Ok(msg)) => {
                    self.stats.frames_ok = self.stats.frames_ok.wrapping_add(1);
                    // The run's reply goes first: replies keep the order of the frames.
                    self.flush_rejected();
                    let reply = self.handle(msg);
                    if matches!(reply, DeviceMsg::Error { .. }) {
                        self.stats.refused = self.stats.refused.wrapping_add(1);
                    }
                    let _ = self.replies.push_back(reply);
                }
                Some(Err(e)) => {
                    self.stats.frames_bad = self.stats.frames_bad.wrapping_add(1);
                    self.stats.refused = self.stats.refused.wrapping_add(1);
                    match &mut self.rejected {
                        Some((code, _, count)) if *code == e.code() && *count < u32::MAX => {
                            *count += 1;
                        }
                        _ => {
                            self.flush_rejected();
                            self.rejected = Some((e.code(), e.detail(), 1));
                        }
                    }
                }
            }
        }
        // 2. Telemetry into the batch.
        self.collect(now);
        // 3. Experiment end, after its samples.
        if self.pending_event.is_none() {
            self.pending_event = self.port.events.dequeue();
        }
        if let Some(ServoEvent::ExperimentDone {
            kind,
            completed,
            faults,
            next_seq,
        }) = self.pending_event
        {
            if seq_reached(self.next_seq, next_seq)
                && self.batch.samples.is_empty()
                && self.replies.len() + usize::from(self.rejected.is_some()) < REPLIES
            {
                let _ = self.replies.push_back(DeviceMsg::ExperimentDone {
                    kind,
                    completed,
                    faults,
                });
                self.pending_event = None;
            } else if seq_reached(self.next_seq, next_seq) {
                self.batch_cut = true;
            }
        }
        // 4. Transmit.
        for _ in 0..FRAME_BUDGET {
            while self.tx_pos < self.tx_len {
                let Some(&b) = self.tx.get(self.tx_pos) else {
                    break;
                };
                if !link.write(b) {
                    return;
                }
                self.tx_pos += 1;
            }
            if !self.next_frame(now) {
                return;
            }
            self.collect(now);
        }
    }

    /// Queues the reply to the pending run of bad frames, if any (the caller keeps a slot free).
    fn flush_rejected(&mut self) {
        if let Some(r) = self.rejected.take() {
            let _ = self.replies.push_back(rejected_reply(r));
        }
    }

    /// Moves samples from the servo queue into the batch (consecutive numbers only).
    fn collect(&mut self, now: u32) {
        while self.batch.samples.len() < TELEMETRY_BATCH && !self.batch_cut {
            let Some(item) = self.port.telemetry.peek().copied() else {
                break;
            };
            let gap = item.seq.wrapping_sub(self.next_seq);
            if gap != 0 && !self.batch.samples.is_empty() {
                self.batch_cut = true;
                break;
            }
            let _ = self.port.telemetry.dequeue();
            self.dropped = self.dropped.wrapping_add(gap);
            self.next_seq = item.seq.wrapping_add(1);
            if self.batch.samples.is_empty() {
                self.batch.seq = item.seq;
                self.batch_tick = now;
            }
            let _ = self.batch.samples.push(item.sample);
        }
        self.batch.dropped = self.dropped;
    }

    /// Encodes the next frame into `tx`; `false` if there is nothing to send.
    fn next_frame(&mut self, now: u32) -> bool {
        let flush_ticks = (self.config.servo_rate_hz / 100).max(1);
        let telemetry_ready = !self.batch.samples.is_empty()
            && (self.batch.samples.len() >= TELEMETRY_BATCH
                || self.batch_cut
                || now.wrapping_sub(self.batch_tick) >= flush_ticks
                || self.pending_event.is_some());
        let reply_turn = !(telemetry_ready && self.replies_in_row >= REPLY_BUDGET);
        let reply = if reply_turn {
            // Older replies first, then the run of bad frames (newer than every queued reply).
            self.replies
                .pop_front()
                .or_else(|| self.rejected.take().map(rejected_reply))
        } else {
            None
        };
        let msg = if let Some(r) = reply {
            self.replies_in_row = self.replies_in_row.saturating_add(1).min(REPLY_BUDGET);
            r
        } else if telemetry_ready {
            self.replies_in_row = 0;
            self.batch_cut = false;
            let b = core::mem::replace(
                &mut self.batch,
                TelemetryBatch {
                    seq: 0,
                    dropped: self.dropped,
                    samples: heapless::Vec::new(),
                },
            );
            DeviceMsg::Telemetry(b)
        } else {
            self.batch_cut = false;
            return false;
        };
        match encode(&msg, &mut self.tx) {
            Ok(f) => {
                self.tx_len = f.len();
                self.tx_pos = 0;
                true
            }
            Err(_) => false,
        }
    }

    fn send_servo(&mut self, cmd: ServoCmd) -> bool {
        self.port.commands.enqueue(cmd).is_ok()
    }

    fn experiment_running(&self) -> bool {
        self.port.shared.experiment.load(Ordering::Relaxed)
    }

    fn apply(&mut self, cfg: ServoConfig, ok: DeviceMsg) -> DeviceMsg {
        if let Err(e) = validate(&cfg, &self.board) {
            return invalid_config(e);
        }
        if self.experiment_running() {
            return busy("experiment running");
        }
        if !self.send_servo(ServoCmd::Config(cfg)) {
            return queue_full();
        }
        if cfg.servo_rate_hz != self.config.servo_rate_hz {
            self.rate_change = Some(cfg.servo_rate_hz);
        }
        self.config = cfg;
        match ok {
            DeviceMsg::Config(_) => DeviceMsg::Config(cfg),
            other => other,
        }
    }

    /// `Err((min, max))` of the offending argument.
    fn check_profile(&self, p: &ExciteProfile) -> Result<(), (f64, f64)> {
        let mc = self.board.max_code;
        let code_ok = |c: i32| c.unsigned_abs() <= mc.unsigned_abs();
        let nyq = f64::from(self.config.servo_rate_hz) / 2.0;
        let bad_code = (-f64::from(mc), f64::from(mc));
        match *p {
            ExciteProfile::Steps {
                low,
                high,
                half_period_ticks,
            } => {
                if !code_ok(low) || !code_ok(high) {
                    return Err(bad_code);
                }
                if half_period_ticks == 0 {
                    return Err((1.0, f64::from(u32::MAX)));
                }
            }
            ExciteProfile::Chirp {
                amplitude,
                f0_hz,
                f1_hz,
            } => {
                if !code_ok(amplitude) {
                    return Err(bad_code);
                }
                for f in [f0_hz, f1_hz] {
                    if !(f.is_finite() && f >= 0.0 && f64::from(f) <= nyq) {
                        return Err((0.0, nyq));
                    }
                }
            }
            ExciteProfile::Table { len, hold_ticks } => {
                if len == 0 || usize::from(len) > MAX_TABLE {
                    return Err((1.0, MAX_TABLE as f64));
                }
                if hold_ticks == 0 {
                    return Err((1.0, f64::from(u16::MAX)));
                }
            }
        }
        Ok(())
    }

    /// Handles one request; returns the reply.
    pub fn handle(&mut self, msg: HostMsg) -> DeviceMsg {
        let ack = |r| DeviceMsg::Ack(r);
        match msg {
            HostMsg::Hello { protocol_version } => self.hello(protocol_version),
            HostMsg::GetConfig => DeviceMsg::Config(self.config),
            HostMsg::SetConfig(cfg) => self.apply(cfg, ack(Request::SetConfig)),
            HostMsg::LoadDefaults => {
                let d = self.defaults;
                self.apply(d, DeviceMsg::Config(d))
            }
            HostMsg::SaveConfig => match self.store.save(&self.config) {
                Ok(()) => ack(Request::SaveConfig),
                Err(_) => DeviceMsg::Error {
                    code: ErrorCode::StoreFailed,
                    detail: ErrorDetail::None,
                },
            },
            HostMsg::StreamStart { decimation } => {
                if decimation == 0 {
                    invalid(ConfigField::Argument, 1.0, f64::from(u16::MAX))
                } else {
                    self.queued(ServoCmd::Stream { decimation }, Request::StreamStart)
                }
            }
            HostMsg::StreamStop => {
                self.queued(ServoCmd::Stream { decimation: 0 }, Request::StreamStop)
            }
            HostMsg::Release {
                deflection_ticks,
                ticks,
            } => self.start_test(Request::Release, deflection_ticks, None, ticks),
            HostMsg::Impact {
                start_ticks,
                velocity_milliticks,
                ticks,
            } => self.start_test(
                Request::Impact,
                start_ticks,
                Some(velocity_milliticks),
                ticks,
            ),
            HostMsg::Excite { profile, ticks } => self.excite(profile, ticks),
            HostMsg::TableChunk { offset, values } => {
                if usize::from(offset) + values.len() > MAX_TABLE {
                    return invalid(
                        ConfigField::Argument,
                        0.0,
                        (MAX_TABLE - values.len()) as f64,
                    );
                }
                self.queued(ServoCmd::TableChunk { offset, values }, Request::TableChunk)
            }
            HostMsg::Heartbeat => {
                self.port.shared.heartbeat.fetch_add(1, Ordering::Relaxed);
                ack(Request::Heartbeat)
            }
            HostMsg::GetFaults => self.fault_report(),
            HostMsg::ClearFaults => self.queued(ServoCmd::ClearFaults, Request::ClearFaults),
            HostMsg::Stop => self.queued(ServoCmd::Stop, Request::Stop),
            HostMsg::Shutdown { exit_code } => {
                self.shutdown = Some(exit_code);
                ack(Request::Shutdown)
            }
            HostMsg::PrepareTest {
                config,
                min_run_ticks,
                within_one_count,
                decay_base_ticks,
            } => self.prepare_test(config, min_run_ticks, within_one_count, decay_base_ticks),
        }
    }

    /// The reply to `Hello`: the device's identity, or a version mismatch.
    fn hello(&self, protocol_version: u8) -> DeviceMsg {
        if protocol_version == PROTOCOL_VERSION {
            DeviceMsg::HelloReply(self.board.device_info(self.config.servo_rate_hz))
        } else {
            DeviceMsg::Error {
                code: ErrorCode::VersionMismatch,
                detail: ErrorDetail::Version {
                    got: protocol_version,
                    expected: PROTOCOL_VERSION,
                },
            }
        }
    }

    /// `cmd` queued for the servo, acknowledged as `done`; busy when the queue is full.
    fn queued(&mut self, cmd: ServoCmd, done: Request) -> DeviceMsg {
        if self.send_servo(cmd) {
            DeviceMsg::Ack(done)
        } else {
            queue_full()
        }
    }

    /// Starts an excitation of `ticks` ticks (the profile plus the wall's centring spring and
    /// damper, none with K = 0 and B = 0) after checking its length and profile.
    fn excite(&mut self, profile: ExciteProfile, ticks: u32) -> DeviceMsg {
        if ticks == 0 || ticks > MAX_EXPERIMENT_TICKS {
            return invalid(ConfigField::Argument, 1.0, f64::from(MAX_EXPERIMENT_TICKS));
        }
        if let Err((min, max)) = self.check_profile(&profile) {
            return invalid(ConfigField::Argument, min, max);
        }
        if self.port.shared.faults.load(Ordering::Relaxed) != 0 {
            return busy("faults latched");
        }
        if self.send_servo(ServoCmd::Excite { profile, ticks }) {
            self.port.shared.experiment.store(true, Ordering::Relaxed);
            DeviceMsg::Ack(Request::Excite)
        } else {
            queue_full()
        }
    }

    /// The latched faults, the tick of the first, and whether the servo is in safe mode.
    fn fault_report(&self) -> DeviceMsg {
        let latched = self.port.shared.faults.load(Ordering::Relaxed);
        DeviceMsg::Faults(FaultReport {
            latched,
            first_tick: if latched != 0 {
                self.port.shared.first_fault_tick.load(Ordering::Relaxed)
            } else {
                0
            },
            safe_mode: latched != 0,
        })
    }

    /// `HostMsg::PrepareTest`: checks and keeps the next test's config and end rule.
    fn prepare_test(
        &mut self,
        config: ServoConfig,
        min_run: u32,
        one_count: bool,
        decay_base: u32,
    ) -> DeviceMsg {
        if let Err(e) = validate(&config, &self.board) {
            return invalid_config(e);
        }
        if config.servo_rate_hz != self.config.servo_rate_hz {
            let hz = f64::from(self.config.servo_rate_hz);
            return invalid_config(ConfigError {
                field: ConfigField::ServoRateHz,
                min: hz,
                max: hz,
            });
        }
        if min_run.max(decay_base) > MAX_EXPERIMENT_TICKS {
            return invalid(ConfigField::Argument, 0.0, f64::from(MAX_EXPERIMENT_TICKS));
        }
        if self.experiment_running() {
            return busy("experiment running");
        }
        self.end_rule = Some((config, min_run, one_count, decay_base));
        DeviceMsg::Ack(Request::PrepareTest)
    }

    /// Starts a release test (`velocity_milli` None: hold at `at`) or an impact test (launch
    /// from `at` at `velocity_milli`), with the pending [`HostMsg::PrepareTest`] rule.
    fn start_test(
        &mut self,
        request: Request,
        at: i32,
        velocity_milli: Option<i32>,
        ticks: u32,
    ) -> DeviceMsg {
        if ticks == 0 || ticks > MAX_EXPERIMENT_TICKS {
            return invalid(ConfigField::Argument, 1.0, f64::from(MAX_EXPERIMENT_TICKS));
        }
        // An impact starts off the wall (non-zero); a release may start on it.
        let at_ok = at.unsigned_abs() <= MAX_DEFLECTION.unsigned_abs()
            && (velocity_milli.is_none() || at != 0);
        if !at_ok {
            let m = f64::from(MAX_DEFLECTION);
            return invalid(ConfigField::Argument, -m, m);
        }
        if let Some(v) = velocity_milli {
            // Toward the wall: the velocity's sign is opposite to the start's.
            let toward = -at.signum() * v;
            if !(1..=MAX_LAUNCH_MILLITICKS).contains(&toward) {
                let m = f64::from(MAX_LAUNCH_MILLITICKS);
                return if at < 0 {
                    invalid(ConfigField::Argument, 1.0, m)
                } else {
                    invalid(ConfigField::Argument, -m, -1.0)
                };
            }
        }
        if self.port.shared.faults.load(Ordering::Relaxed) != 0 {
            return busy("faults latched");
        }
        // The test's config: the prepared one, or the active one.
        let cfg = self.end_rule.map_or(self.config, |r| r.0);
        if cfg.stiffness <= 0.0 {
            return invalid(
                ConfigField::Stiffness,
                f64::from(f32::MIN_POSITIVE),
                f64::from(self.board.max_stiffness(cfg.coarsen_shift)),
            );
        }
        let end = self
            .end_rule
            .map(|(run, min_run, one_count, decay_base)| DecidedEnd {
                min_run,
                one_count,
                decay_base,
                run,
                park: self.config,
            });
        let cmd = match velocity_milli {
            None => ServoCmd::Release {
                deflection: at,
                ticks,
                end,
            },
            Some(v) => ServoCmd::Impact {
                start: at,
                velocity_milli: v,
                ticks,
                end,
            },
        };
        if !self.send_servo(cmd) {
            return queue_full();
        }
        self.end_rule = None;
        self.port.shared.experiment.store(true, Ordering::Relaxed);
        DeviceMsg::Ack(request)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::channels::Channels;
    use crate::hal::{HeldCode, SampledCount};
    use crate::servo::Servo;
    use crate::store::MemStorage;
    use std::collections::VecDeque;
    use std::vec::Vec;
    use stiffwall_proto::frame::decode_frame;

    #[derive(Default)]
    struct Link {
        rx: VecDeque<u8>,
        tx: Vec<u8>,
        tx_room: Option<usize>,
    }
    impl ByteLink for Link {
        fn read(&mut self) -> Option<u8> {
            self.rx.pop_front()
        }
        fn write(&mut self, b: u8) -> bool {
            if let Some(r) = &mut self.tx_room {
                if *r == 0 {
                    return false;
                }
                *r -= 1;
            }
            self.tx.push(b);
            true
        }
    }
    impl Link {
        fn send(&mut self, m: &HostMsg) {
            let mut buf = [0u8; MAX_FRAME];
            self.rx.extend(encode(m, &mut buf).unwrap());
        }
        fn frames(&mut self) -> Vec<DeviceMsg> {
            let mut out = Vec::new();
            let mut cur = Vec::new();
            for b in self.tx.drain(..) {
                cur.push(b);
                if b == 0 {
                    out.push(decode_frame::<DeviceMsg>(&mut cur).unwrap());
                    cur.clear();
                }
            }
            self.tx = cur;
            out
        }
    }

    #[test]
    fn hello_config_and_refusal() {
        let mut ch = Channels::new();
        let (sp, hp) = ch.split();
        let b = BoardInfo::default();
        let mut dev = Device::new(
            b,
            ConfigStore::new(MemStorage::default()),
            hp,
            ServoConfig::default(),
        );
        let mut servo: Servo<'_> = Servo::new(b, dev.config(), sp);
        let mut link = Link::default();
        link.send(&HostMsg::Hello {
            protocol_version: PROTOCOL_VERSION,
        });
        link.send(&HostMsg::Hello {
            protocol_version: 9,
        });
        link.send(&HostMsg::SetConfig(ServoConfig {
            coarsen_shift: 40,
            ..ServoConfig::default()
        }));
        link.send(&HostMsg::GetConfig);
        for t in 0..10 {
            dev.poll(t, &mut link);
            servo.tick(t, &mut SampledCount(0), &mut HeldCode(0));
        }
        let f = link.frames();
        assert_eq!(f.len(), 4);
        assert!(
            matches!(&f[0], DeviceMsg::HelloReply(i) if i.protocol_version == PROTOCOL_VERSION && i.board == "generic")
        );
        assert_eq!(
            f[1],
            DeviceMsg::Error {
                code: ErrorCode::VersionMismatch,
                detail: ErrorDetail::Version {
                    got: 9,
                    expected: PROTOCOL_VERSION
                }
            }
        );
        assert_eq!(
            f[2],
            DeviceMsg::Error {
                code: ErrorCode::InvalidConfig,
                detail: ErrorDetail::Field {
                    field: ConfigField::CoarsenShift,
                    min: 0.0,
                    max: 16.0
                }
            }
        );
        assert_eq!(f[3], DeviceMsg::Config(ServoConfig::default()));
    }

    /// Requests beyond the servo's command queue are answered `QueueFull` (a code of its own,
    /// no text), and accepted again once the servo has taken the queued commands.
    #[test]
    fn a_full_command_queue_answers_queue_full_by_its_code() {
        let mut ch = Channels::new();
        let (sp, hp) = ch.split();
        let b = BoardInfo::default();
        let mut dev = Device::new(
            b,
            ConfigStore::new(MemStorage::default()),
            hp,
            ServoConfig::default(),
        );
        let mut servo: Servo<'_> = Servo::new(b, dev.config(), sp);
        let mut link = Link::default();
        let sent = 3 * crate::channels::COMMAND_QUEUE;
        for _ in 0..sent {
            link.send(&HostMsg::ClearFaults);
        }
        for t in 0..(4 * sent as u32) {
            dev.poll(t, &mut link);
        }
        let f = link.frames();
        assert_eq!(f.len(), sent);
        let acked = f
            .iter()
            .filter(|m| **m == DeviceMsg::Ack(Request::ClearFaults))
            .count();
        let full = DeviceMsg::Error {
            code: ErrorCode::QueueFull,
            detail: ErrorDetail::None,
        };
        assert!(
            (1..=crate::channels::COMMAND_QUEUE).contains(&acked),
            "{f:?}"
        );
        assert!(f[acked..].iter().all(|m| *m == full), "{f:?}");
        // The servo takes the queued commands; the next request is accepted.
        for t in 0..(2 * sent as u32) {
            servo.tick(t, &mut SampledCount(0), &mut HeldCode(0));
        }
        link.send(&HostMsg::ClearFaults);
        for t in 0..8 {
            dev.poll(t, &mut link);
        }
        assert_eq!(link.frames(), [DeviceMsg::Ack(Request::ClearFaults)]);
    }

    /// `PrepareTest` with a bad rule or config is refused naming the field and its range and
    /// changes nothing; a prepared release runs with its config while `GetConfig` shows the
    /// active one, ends settled, and is used once.
    #[test]
    fn a_prepared_test_is_checked_runs_its_config_and_is_used_once() {
        let mut ch = Channels::new();
        let (sp, hp) = ch.split();
        let b = BoardInfo::default();
        let active = ServoConfig {
            stiffness: 0.0,
            heartbeat_timeout_ms: 0,
            ..ServoConfig::default()
        };
        let wall = ServoConfig {
            stiffness: 100.0,
            damping: 0.1,
            ..active
        };
        let mut dev = Device::new(b, ConfigStore::new(MemStorage::default()), hp, active);
        let mut servo: Servo<'_> = Servo::new(b, dev.config(), sp);
        let mut link = Link::default();
        let mut run = |link: &mut Link, dev: &mut Device<'_, MemStorage>, ticks: u32| {
            for t in 0..ticks {
                dev.poll(t, link);
                servo.tick(t, &mut SampledCount(0), &mut HeldCode(0));
            }
            link.frames()
                .into_iter()
                .filter(|m| !matches!(m, DeviceMsg::Telemetry(_)))
                .collect::<Vec<_>>()
        };
        let prepare = |config, decay_base_ticks| HostMsg::PrepareTest {
            config,
            min_run_ticks: 50,
            within_one_count: false,
            decay_base_ticks,
        };
        link.send(&prepare(wall, MAX_EXPERIMENT_TICKS + 1));
        link.send(&prepare(
            ServoConfig {
                coarsen_shift: 40,
                ..wall
            },
            0,
        ));
        // Nothing prepared: the active K = 0 wall cannot be tested.
        link.send(&HostMsg::Release {
            deflection_ticks: 0,
            ticks: 5000,
        });
        let f = run(&mut link, &mut dev, 40);
        let field = |code, field, min, max| DeviceMsg::Error {
            code,
            detail: ErrorDetail::Field { field, min, max },
        };
        assert_eq!(
            f[..2],
            [
                field(ErrorCode::InvalidArgument, ConfigField::Argument, 0.0, 1e7),
                field(
                    ErrorCode::InvalidConfig,
                    ConfigField::CoarsenShift,
                    0.0,
                    16.0
                ),
            ]
        );
        assert!(
            matches!(
                &f[2],
                DeviceMsg::Error {
                    code: ErrorCode::InvalidArgument,
                    detail: ErrorDetail::Field {
                        field: ConfigField::Stiffness,
                        ..
                    }
                }
            ),
            "{f:?}"
        );
        link.send(&prepare(wall, 5000));
        link.send(&HostMsg::Release {
            deflection_ticks: 0,
            ticks: 5000,
        });
        link.send(&HostMsg::GetConfig);
        // Held at count 0 (its target) for the hold's settling time, then 50 ticks at rest.
        let f = run(&mut link, &mut dev, 400);
        assert!(f.contains(&DeviceMsg::Config(active)), "{f:?}");
        assert!(
            f.contains(&DeviceMsg::ExperimentDone {
                kind: stiffwall_proto::ExperimentKind::Release,
                completed: true,
                faults: 0
            }),
            "{f:?}"
        );
        // Used once: the next release is tested with the active (K = 0) config: refused.
        link.send(&HostMsg::Release {
            deflection_ticks: 0,
            ticks: 5000,
        });
        let f = run(&mut link, &mut dev, 10);
        assert!(
            matches!(
                &f[0],
                DeviceMsg::Error {
                    code: ErrorCode::InvalidArgument,
                    detail: ErrorDetail::Field {
                        field: ConfigField::Stiffness,
                        ..
                    }
                }
            ),
            "{f:?}"
        );
    }

    #[test]
    fn slow_link_keeps_every_reply() {
        let mut ch = Channels::new();
        let (_sp, hp) = ch.split();
        let b = BoardInfo::default();
        let mut dev = Device::new(
            b,
            ConfigStore::new(MemStorage::default()),
            hp,
            ServoConfig::default(),
        );
        let mut link = Link {
            tx_room: Some(0),
            ..Link::default()
        };
        for _ in 0..20 {
            link.send(&HostMsg::GetFaults);
        }
        let mut got = Vec::new();
        for t in 0..2000 {
            link.tx_room = Some(3);
            dev.poll(t, &mut link);
            got.extend(link.frames());
        }
        assert_eq!(got.len(), 20);
        assert!(got.iter().all(|m| matches!(m, DeviceMsg::Faults(_))));
    }

    /// Replies to the bad frames of a flood: (frames they stand for, reply frames).
    fn bad_frames_answered(frames: &[DeviceMsg]) -> (u64, usize) {
        let mut n = 0;
        let mut replies = 0;
        for m in frames {
            if let DeviceMsg::Error { code, detail } = m {
                assert_eq!(*code, ErrorCode::Cobs, "{m:?}");
                replies += 1;
                n += match detail {
                    ErrorDetail::Repeated { count } => {
                        assert!(*count >= 2, "{m:?}");
                        u64::from(*count)
                    }
                    ErrorDetail::None => 1,
                    other => panic!("unexpected detail {other:?}"),
                };
            }
        }
        (n, replies)
    }

    /// Issue 11, item 1: `01 00` (an empty-payload frame) written at 40 bytes per servo tick
    /// (40 KB/s at 1 kHz) while streaming one sample per tick over a link taking 200 bytes per
    /// tick. Every telemetry sample gets out (no gap, nothing dropped on the device) and every
    /// bad frame is answered (the counts of the coalesced error replies add up).
    #[test]
    fn flood_of_bad_frames_does_not_starve_telemetry() {
        let mut ch = Channels::new();
        let (sp, hp) = ch.split();
        let b = BoardInfo::default();
        let mut dev = Device::new(
            b,
            ConfigStore::new(MemStorage::default()),
            hp,
            ServoConfig::default(),
        );
        let mut servo: Servo<'_> = Servo::new(b, dev.config(), sp);
        let mut link = Link::default();
        link.send(&HostMsg::StreamStart { decimation: 1 });
        let flood_ticks = 3000u32;
        let per_tick = 20usize;
        let mut frames = Vec::new();
        for t in 0..flood_ticks + 200 {
            if t < flood_ticks {
                for _ in 0..per_tick {
                    link.rx.extend([0x01, 0x00]);
                }
            }
            link.tx_room = Some(200);
            dev.poll(t, &mut link);
            servo.tick(t, &mut SampledCount(0), &mut HeldCode(0));
            frames.extend(link.frames());
        }
        assert!(link.rx.is_empty(), "the device kept up with the flood");
        let sent = u64::from(flood_ticks) * per_tick as u64;
        let (answered, replies) = bad_frames_answered(&frames);
        assert_eq!(answered, sent, "every bad frame accounted for");
        assert_eq!(u64::from(dev.stats().frames_bad), sent);
        // Coalesced: at most one reply per poll for the 20 bad frames each tick brings.
        assert!(
            replies <= flood_ticks as usize,
            "coalesced: {replies} replies"
        );
        assert_eq!(dev.dropped(), 0, "no sample dropped on the device");
        let mut next = None;
        let mut samples = 0u32;
        for m in &frames {
            if let DeviceMsg::Telemetry(tb) = m {
                assert_eq!(tb.dropped, 0);
                if let Some(n) = next {
                    assert_eq!(tb.seq, n, "consecutive batches");
                }
                next = Some(tb.seq + tb.samples.len() as u32);
                samples += tb.samples.len() as u32;
            }
        }
        // Streaming starts within the first ticks; all but the last batch's worth are out.
        assert!(
            samples + 2 * TELEMETRY_BATCH as u32 + 5 >= flood_ticks + 200,
            "{samples} samples of {}",
            flood_ticks + 200
        );
    }

    /// A flood of well-formed requests (each answered) still leaves telemetry its share: with
    /// [`REPLY_BUDGET`] replies per batch, no sample is dropped while the link has room.
    #[test]
    fn flood_of_requests_shares_the_link_with_telemetry() {
        let mut ch = Channels::new();
        let (sp, hp) = ch.split();
        let b = BoardInfo::default();
        let mut dev = Device::new(
            b,
            ConfigStore::new(MemStorage::default()),
            hp,
            ServoConfig::default(),
        );
        let mut servo: Servo<'_> = Servo::new(b, dev.config(), sp);
        let mut link = Link::default();
        link.send(&HostMsg::StreamStart { decimation: 1 });
        let mut acks = 0;
        let mut samples = 0u32;
        for t in 0..3000u32 {
            for _ in 0..4 {
                link.send(&HostMsg::Heartbeat);
            }
            link.tx_room = Some(400);
            dev.poll(t, &mut link);
            servo.tick(t, &mut SampledCount(0), &mut HeldCode(0));
            for m in link.frames() {
                match m {
                    DeviceMsg::Ack(Request::Heartbeat) => acks += 1,
                    DeviceMsg::Telemetry(tb) => samples += tb.samples.len() as u32,
                    _ => {}
                }
            }
        }
        assert_eq!(dev.dropped(), 0, "no sample dropped on the device");
        assert!(
            samples + 2 * TELEMETRY_BATCH as u32 + 5 >= 3000,
            "{samples}"
        );
        assert!(acks > 3000, "replies still flow: {acks}");
    }
}
