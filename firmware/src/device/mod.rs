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
//!   validated field by field ([`crate::config::validate`]) before it reaches the servo, and
//!   `SetProfile` element by element ([`crate::profile::validate`]).
//! - The haptic profile (`SetProfile`, protocol 5): the device keeps the wire [`Profile`] (for
//!   `GetProfile`, for `SaveConfig`, which saves it with the config, and to compile it again
//!   when a `SetConfig` changes the rate or the shift: a config under which the active profile
//!   is out of range is refused with `InvalidProfile`); it compiles it in the main loop and
//!   queues the table for the servo with one `ServoCmd::Profile`. Boot loads both and queues the
//!   stored profile for the servo's first tick.
//! - Telemetry batches hold consecutive samples only. The device counts lost samples from the
//!   gaps in the servo's sample numbers, so `TelemetryBatch::dropped` is exact: between two
//!   batches, `seq` jumps by exactly the growth of `dropped`.
//! - `ExperimentDone` is sent after the last telemetry sample of the experiment.
//! - No allocation; bounded work per `poll`.
//!
//! Layout: this module holds the [`Device`] and its state; `link` the main-loop step
//! ([`Device::poll`]: frames in, telemetry batches, replies out); `requests` the answer to
//! each request ([`Device::handle`]).

use crate::channels::{HostPort, ServoCmd, ServoEvent};
use crate::config::{validate, BoardInfo};
use crate::hal::ConfigStorage;
use crate::numeric::{Fx64, Numeric};
use crate::store::ConfigStore;
use heapless::Deque;
use stiffwall_proto::{
    DeviceMsg, ErrorCode, ErrorDetail, FrameDecoder, Profile, ServoConfig, TelemetryBatch,
    MAX_FRAME,
};

mod link;
#[cfg(test)]
mod profile_tests;
mod requests;
#[cfg(test)]
mod tests;

/// Replies queued at most.
const REPLIES: usize = 4;
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

/// A run of consecutive bad frames with one error code, answered by one reply.
#[derive(Debug)]
struct RejectedRun {
    /// The frames' error code.
    code: ErrorCode,
    /// The detail of the run's first frame.
    detail: ErrorDetail,
    /// Frames in the run, ≥ 1.
    count: u32,
}

/// The next test as `PrepareTest` prepared it (the servo's [`crate::channels::DecidedEnd`]
/// once the test starts, with the active config to park).
#[derive(Debug, Clone, Copy)]
struct EndRule {
    /// The test's config, applied on the tick it starts.
    config: ServoConfig,
    /// Shortest settled run, ticks (0: no settled end).
    min_run: u32,
    /// A toggle between neighbouring counts counts as settled.
    one_count: bool,
    /// Base length of the decay checkpoints, ticks (0: none).
    decay_base: u32,
}

/// The main-loop side of the firmware (`N`: the servo's numeric back-end, whose gain forms
/// the compiled profile is in).
#[derive(Debug)]
pub struct Device<'a, S: ConfigStorage, N: Numeric = Fx64> {
    board: BoardInfo,
    config: ServoConfig,
    /// The active haptic profile as it arrived (empty: the config's wall).
    profile: Profile,
    defaults: ServoConfig,
    store: ConfigStore<S>,
    port: HostPort<'a, N>,
    decoder: FrameDecoder,
    tx: [u8; MAX_FRAME],
    tx_len: usize,
    tx_pos: usize,
    replies: Deque<DeviceMsg, REPLIES>,
    /// The current run of bad frames.
    rejected: Option<RejectedRun>,
    /// Replies sent since the last telemetry batch (saturating at [`REPLY_BUDGET`]).
    replies_in_row: u8,
    batch: TelemetryBatch,
    batch_tick: u32,
    batch_cut: bool,
    next_seq: u32,
    dropped: u32,
    pending_event: Option<ServoEvent>,
    /// The next test as `PrepareTest` prepared it.
    end_rule: Option<EndRule>,
    rate_change: Option<u32>,
    shutdown: Option<u8>,
    stats: DeviceStats,
}

impl<'a, S: ConfigStorage, N: Numeric> Device<'a, S, N> {
    /// A device for `board`: loads the newest valid stored config and its profile (falling
    /// back to `defaults` and no profile when none is stored or the config fails validation;
    /// to the config alone when the profile does). Build the [`crate::Servo`] with
    /// [`Device::config`]; a stored profile is queued for the servo's first tick.
    pub fn new(
        board: BoardInfo,
        store: ConfigStore<S>,
        port: HostPort<'a, N>,
        defaults: ServoConfig,
    ) -> Self {
        let mut store = store;
        let (config, profile) = match store.load_with_profile() {
            Some((c, p)) if validate(&c, &board).is_ok() => {
                let p = if crate::profile::validate(&p, &c, &board).is_ok() {
                    p
                } else {
                    Profile::default()
                };
                (c, p)
            }
            _ => (defaults, Profile::default()),
        };
        let mut device = Self {
            board,
            config,
            profile: Profile::default(),
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
        };
        if !profile.elements.is_empty() {
            // Fresh queues: room for the table and its command.
            if device.send_profile(&profile, &config) {
                device.profile = profile;
            }
        }
        device
    }

    /// Compiles `profile` for `cfg` and queues it for the servo (the table, then its
    /// `ServoCmd::Profile`); false, nothing queued, when either queue has no room.
    fn send_profile(&mut self, profile: &Profile, cfg: &ServoConfig) -> bool {
        if !self.port.profiles.ready() || !self.port.commands.ready() {
            return false;
        }
        let table = crate::profile::compile::<N>(profile, cfg, &self.board);
        // Both have room, and only this end adds to them: neither enqueue fails.
        self.port.profiles.enqueue(table).is_ok()
            && self.port.commands.enqueue(ServoCmd::Profile).is_ok()
    }

    /// The active haptic profile (empty: the config's wall).
    pub fn profile(&self) -> &Profile {
        &self.profile
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
}
