//! Messages of the stiffwall protocol (postcard-serialized, no allocation).
//!
//! Units: physical quantities at this API are SI: positions in m (rad for rotary devices),
//! forces in N (N·m), stiffness in N/m (N·m/rad), damping in N·s/m (N·m·s/rad), energy in J,
//! rates in Hz. Device-side quantities are integers named for their unit: `*_code` is a force
//! output code (one code = `DeviceInfo::force_per_code`), `count` / `*_counts` raw encoder counts
//! (one count = `DeviceInfo::resolution`), `*_ticks` servo ticks (one tick = 1 / servo rate)
//! or, for `deflection_ticks`, *effective* encoder ticks Δ_eff = 2^`coarsen_shift` counts (the
//! paper's Δ).
//!
//! Invariant: the enum variant order is part of the wire format; append new variants at the end
//! and bump [`crate::PROTOCOL_VERSION`] when an existing one changes.

use heapless::{String, Vec};
use serde::{Deserialize, Serialize};

use crate::damper::DamperLaw;
use crate::profile::{Profile, ProfileField};

/// Protocol version carried in the first byte of every frame and in the handshake.
/// Bump on any incompatible change of a message or of the framing.
///
/// Version 2: [`ServoConfig`] ends with [`ServoConfig::damper`] (the wall damper's
/// [`DamperLaw`]); [`ConfigField::Damper`] names it in a refusal.
///
/// Version 3: [`ServoConfig`] ends with the travel window [`ServoConfig::travel_min`] and
/// [`ServoConfig::travel_max`] (after `damper`); [`ConfigField::TravelMin`] and
/// [`ConfigField::TravelMax`] name them in a refusal; the supervisor's fault bit
/// [`fault::TRAVEL`] is new.
///
/// Version 4: [`ErrorCode::QueueFull`] answers a request the servo's command queue had no room
/// for (before: `Busy` with the text "servo queue full", which a host could only recognise by
/// its text); a version-3 host would not decode it, so the handshake refuses one.
///
/// Version 5: haptic profiles ([`crate::profile`]): [`HostMsg::SetProfile`],
/// [`HostMsg::GetProfile`], [`DeviceMsg::Profile`], [`Request::SetProfile`],
/// [`ErrorCode::InvalidProfile`] and [`ErrorDetail::ProfileField`], all appended.
pub const PROTOCOL_VERSION: u8 = 5;

/// Telemetry samples per [`TelemetryBatch`].
pub const TELEMETRY_BATCH: usize = 24;
/// Values per [`HostMsg::TableChunk`].
pub const TABLE_CHUNK: usize = 32;
/// Maximum length of an uploaded excitation table (entries).
pub const MAX_TABLE: usize = 1024;
/// Maximum extra delay T_V in servo ticks (delay ring length − 1).
pub const MAX_DELAY_TICKS: u8 = 31;
/// Maximum encoder coarsening shift.
pub const MAX_COARSEN_SHIFT: u8 = 16;
/// Length of short text fields (names, versions).
pub const NAME_LEN: usize = 24;
/// Last decay checkpoint index of [`HostMsg::PrepareTest`] (checkpoints j = 0..=8: the
/// test runs at most twice its base length).
pub const DECAY_LAST_CHECK: u32 = 8;
/// Checkpoints per base length of [`HostMsg::PrepareTest`] (step ⌊b/8⌋).
pub const DECAY_CHECKS_PER_BASE: u32 = 8;
/// Shortest window, counts, compared at a decay checkpoint of [`HostMsg::PrepareTest`].
pub const DECAY_MIN_WINDOW: u32 = 50;

/// Messages from the host to the device.
// No allocation: a profile (`SetProfile`) is stored inline (no Box), as the device's telemetry
// batch is.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum HostMsg {
    /// Handshake. Answered by [`DeviceMsg::HelloReply`], or `Error(VersionMismatch)`.
    Hello {
        /// The host's [`crate::PROTOCOL_VERSION`].
        protocol_version: u8,
    },
    /// Read the active servo configuration. Answer: [`DeviceMsg::Config`].
    GetConfig,
    /// Validate and apply a configuration (not persisted). Answer: `Ack` or `Error(InvalidConfig)`
    /// naming the field and its range; a refused config changes nothing.
    SetConfig(ServoConfig),
    /// Persist the active configuration to the config store. Answer: `Ack` or `Error(StoreFailed)`.
    SaveConfig,
    /// Apply the firmware defaults (not persisted). Answer: [`DeviceMsg::Config`].
    LoadDefaults,
    /// Start telemetry: one sample every `decimation` servo ticks (≥ 1). Answer: `Ack`.
    StreamStart {
        /// Servo ticks per sample, 1..=65535.
        decimation: u16,
    },
    /// Stop telemetry. Answer: `Ack`.
    StreamStop,
    /// Release test (paper Fig. 8): hold at `deflection_ticks` effective ticks from the wall
    /// with zero velocity, release into the wall and run `ticks` servo ticks, streaming every
    /// tick. Answer: `Ack`, later [`DeviceMsg::ExperimentDone`].
    Release {
        /// Initial deflection in effective encoder ticks (Δ_eff), relative to the wall position.
        deflection_ticks: i32,
        /// Servo ticks to run after the release, 1..=10⁷.
        ticks: u32,
    },
    /// Open-loop excitation, streaming every tick: the profile's code plus the configured
    /// wall's centring spring and damper (see [`ExciteProfile`]; with K = 0 and B = 0, the
    /// default, the wall is off and the output is the profile's code alone). Answer: `Ack`,
    /// later [`DeviceMsg::ExperimentDone`].
    Excite {
        /// The force profile.
        profile: ExciteProfile,
        /// Servo ticks to run, 1..=10⁷.
        ticks: u32,
    },
    /// Upload a piece of the excitation table used by [`ExciteProfile::Table`]. Answer: `Ack`.
    TableChunk {
        /// Index of the first value in the table.
        offset: u16,
        /// Force codes.
        values: Vec<i16, TABLE_CHUNK>,
    },
    /// Host keep-alive; an experiment aborts into safe mode when heartbeats stop for longer
    /// than `ServoConfig::heartbeat_timeout_ms`. Answer: `Ack`.
    Heartbeat,
    /// Read the latched faults. Answer: [`DeviceMsg::Faults`].
    GetFaults,
    /// Clear latched faults and leave safe mode. Answer: `Ack` (with the faults still present
    /// re-latching on the next tick if their cause persists).
    ClearFaults,
    /// Abort a running experiment (wall back on). Answer: `Ack`.
    Stop,
    /// End the firmware's run with `exit_code` (0 = success), where the board can: the QEMU
    /// image exits through semihosting after acknowledging. Boards that cannot (real hardware)
    /// acknowledge and keep running. Answer: `Ack`.
    Shutdown {
        /// Exit status for the emulator (0 = success).
        exit_code: u8,
    },
    /// Impact test: hold at `start_ticks` effective ticks from the wall until still, then move
    /// the hold target toward the wall at `velocity_milliticks` thousandths of an effective
    /// tick per servo tick; when the count reaches the wall (count 0 coming from below, −1
    /// coming from above) the device is released into the configured wall (one-sided or not)
    /// and `ticks` servo ticks run, streaming every tick (samples flagged `HOLD` while launched,
    /// `RELEASED` from contact). Answer: `Ack`, later [`DeviceMsg::ExperimentDone`] with kind
    /// [`ExperimentKind::Impact`].
    Impact {
        /// Start position, effective ticks from the wall, non-zero, |·| ≤ 2²⁰.
        start_ticks: i32,
        /// Launch velocity, effective ticks per 1000 servo ticks, pointing at the wall (sign
        /// opposite to `start_ticks`), 1..=10⁶ in magnitude.
        velocity_milliticks: i32,
        /// Servo ticks to run after contact, 1..=10⁷.
        ticks: u32,
    },
    /// Run the next `Release` or `Impact` with `config` in place of the active configuration,
    /// from its first tick to its last, and end it on the device as soon as its released
    /// counts decide it: so that neither where the test ends nor the state the device is
    /// left in depends on when the host reacts (a host that sets a stiff wall with
    /// `SetConfig` and then starts a test lets the wall act for the link's latency first).
    /// With L the released phase's length so far, the test ends at the first L at which
    /// - it has *settled*: the last max(`min_run_ticks`, ⌈L/3⌉) effective counts are all
    ///   equal (with `within_one_count`: all within one count, max − min ≤ 1, a wall
    ///   toggling between two neighbouring counts); or
    /// - with `decay_base_ticks` = b > 0, L is a *decay checkpoint* L_j = b + j·max(⌊b/8⌋, 1)
    ///   (j = 0..=[`DECAY_LAST_CHECK`]) at which the oscillation no longer shrinks: with
    ///   w = max(⌊L/4⌋, [`DECAY_MIN_WINDOW`]), 2w > L, or the range (max − min) of the last w
    ///   counts is not smaller than that of the w before them; or L is the last checkpoint.
    ///
    /// However the test ends (decided, its full length, `Stop`, a fault), the active
    /// configuration is back on the tick it ends (`GetConfig` shows the active one
    /// throughout). Used by the next release or impact test only; a later `PrepareTest`
    /// replaces it. Answer: `Ack`; `Error(InvalidConfig)` naming the field of `config` and its
    /// range (as `SetConfig`; its servo rate must be the active one); `Error(InvalidArgument)`
    /// naming `Argument` and 0..=10⁷; `Error(Busy)` while an experiment runs.
    PrepareTest {
        /// The test's configuration.
        config: ServoConfig,
        /// Shortest constant (or within-one-count) run that ends the test, servo ticks,
        /// 0..=10⁷ (0 = no settled end).
        min_run_ticks: u32,
        /// Count a toggle between two neighbouring counts as settled.
        within_one_count: bool,
        /// Base length b of the decay checkpoints, servo ticks, 0..=10⁷ (0 = none).
        decay_base_ticks: u32,
    },
    /// Validate and apply a haptic profile (protocol 5; not persisted until `SaveConfig`,
    /// which saves it with the config). The servo takes it between two ticks, whole: no tick
    /// renders part of it. An empty profile renders the config's own wall again. Answer: `Ack`;
    /// `Error(InvalidProfile)` with [`ErrorDetail::ProfileField`] naming the element, its field
    /// and the allowed range (a refused profile changes nothing); `Error(Busy)` while an
    /// experiment runs.
    SetProfile(Profile),
    /// Read the active profile (protocol 5). Answer: [`DeviceMsg::Profile`].
    GetProfile,
}

/// Messages from the device to the host.
// No allocation: the telemetry batch is stored inline (no Box).
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum DeviceMsg {
    /// Answer to `Hello`.
    HelloReply(DeviceInfo),
    /// The active configuration.
    Config(ServoConfig),
    /// A request was accepted.
    Ack(Request),
    /// A batch of telemetry samples.
    Telemetry(TelemetryBatch),
    /// Latched faults.
    Faults(FaultReport),
    /// An experiment ended (completed, aborted by `Stop`, or by a fault).
    ExperimentDone {
        /// Which experiment.
        kind: ExperimentKind,
        /// `true` when it ran its full tick count, or settled under [`HostMsg::PrepareTest`].
        completed: bool,
        /// Fault bits ([`fault`]) latched when it ended.
        faults: u32,
    },
    /// A malformed or refused request.
    Error {
        /// What went wrong.
        code: ErrorCode,
        /// Details (field and range, versions, tag).
        detail: ErrorDetail,
    },
    /// The active haptic profile (protocol 5; empty: the config's wall).
    Profile(Profile),
}

/// Request kinds, echoed in [`DeviceMsg::Ack`].
#[allow(missing_docs)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Request {
    SetConfig,
    SaveConfig,
    LoadDefaults,
    StreamStart,
    StreamStop,
    Release,
    Excite,
    TableChunk,
    Heartbeat,
    ClearFaults,
    Stop,
    Shutdown,
    Impact,
    PrepareTest,
    /// `SetProfile` (protocol 5).
    SetProfile,
}

/// Experiment kinds.
#[allow(missing_docs)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ExperimentKind {
    Release,
    Excite,
    Impact,
}

/// Open-loop excitation profiles (force codes).
///
/// The code output on each tick of an excitation is the profile's code plus the configured
/// wall's *centring spring*: the spring of eq. (2) with the config's stiffness K acting on
/// both sides of `wall_position` whatever [`ServoConfig::wall`] says (the same fixed-point
/// code as the release test's hold spring: beyond the spring's count clamp, where its force
/// alone exceeds the force limit, it keeps its value there), plus the wall's virtual damper
/// (`damping` B with its [`ServoConfig::damper`] law), summed with saturation, then delayed
/// and clamped to the force limit like any code. So a host can run a chirp against a weak,
/// known spring that keeps the device centred. With K = 0 and B = 0 (the defaults) the output
/// is exactly the profile's code and samples carry [`flags::WALL_OFF`]. A sample's
/// `force_code` is always the total code output. The energy monitor is off during an
/// excitation; the other supervisor checks (including the travel window) act.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum ExciteProfile {
    /// Square wave: `high` for `half_period_ticks`, then `low`, repeated.
    Steps {
        /// Force code of the low half.
        low: i32,
        /// Force code of the high half.
        high: i32,
        /// Ticks per half period, ≥ 1.
        half_period_ticks: u32,
    },
    /// Linear chirp `amplitude · sin(φ)`, frequency from `f0_hz` to `f1_hz` over the run.
    Chirp {
        /// Amplitude in force codes.
        amplitude: i32,
        /// Start frequency, Hz, in [0, servo rate / 2].
        f0_hz: f32,
        /// End frequency, Hz, in [0, servo rate / 2].
        f1_hz: f32,
    },
    /// The uploaded table (see [`HostMsg::TableChunk`]), each entry held `hold_ticks` ticks,
    /// repeated.
    Table {
        /// Entries used, 1..=[`MAX_TABLE`].
        len: u16,
        /// Ticks per entry, ≥ 1.
        hold_ticks: u16,
    },
}

/// Wall geometry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum WallMode {
    /// The spring of eq. (2) acts on both sides of the wall position.
    Bidirectional,
    /// The wall occupies counts ≥ the wall position and pushes toward negative counts; no
    /// force outside it.
    OneSided,
}

/// What the device does after a fault.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SafeMode {
    /// Output zero force.
    ZeroForce,
    /// Output the virtual damping `ServoConfig::safe_damping` only.
    Damping,
}

/// The servo configuration (Get/SetConfig, stored in the config store).
///
/// Ranges are checked by the firmware (`stiffwall_firmware::config::validate`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ServoConfig {
    /// Wall stiffness K, N/m (N·m/rad). ≥ 0, and K·Δ_eff/2 ≤ 2^14 output codes (the
    /// firmware's `MAX_GAIN_CODES`, which its config validation enforces).
    pub stiffness: f32,
    /// Virtual damping B, N·s/m, on the backward-difference velocity. ≥ 0.
    pub damping: f32,
    /// Servo rate 1/T, Hz.
    pub servo_rate_hz: u32,
    /// Extra delay T_V, servo ticks, 0..=[`MAX_DELAY_TICKS`].
    pub extra_delay_ticks: u8,
    /// Encoder coarsening shift s (Δ_eff = 2^s counts), 0..=[`MAX_COARSEN_SHIFT`].
    pub coarsen_shift: u8,
    /// Bidirectional spring or one-sided wall.
    pub wall: WallMode,
    /// Wall position (origin of eq. (2)), raw encoder counts.
    pub wall_position: i32,
    /// Force limit, N (N·m), > 0; the output is clamped to it.
    pub force_limit: f32,
    /// Over-velocity fault threshold, m/s (rad/s); 0 disables. Compare eq. (15).
    pub max_velocity: f32,
    /// Energy monitor on/off.
    pub energy_monitor: bool,
    /// Energy fault threshold on the storage function H_T (35), J; must exceed 0.
    pub energy_limit: f32,
    /// Energy monitor growth score that trips the fault (oscillation peaks that grew), 1..=64.
    pub energy_growth_cycles: u8,
    /// Encoder-jump fault threshold, raw counts per tick, ≥ 1.
    pub encoder_jump_counts: u32,
    /// Heartbeat timeout during experiments, ms; 0 disables.
    pub heartbeat_timeout_ms: u32,
    /// Behaviour after a fault.
    pub safe_mode: SafeMode,
    /// Virtual damping in safe mode `Damping`, N·s/m, ≥ 0.
    pub safe_damping: f32,
    /// How the wall's virtual damper (`damping`) turns the count difference into a velocity
    /// (also in a release or impact test's released phase; the tests' hold dampers and the
    /// safe-mode damping are plain differences). Added in protocol 2, last so that the fields
    /// above keep their bytes; absent from a self-describing record (a recording's JSON header
    /// written before it) it is [`DamperLaw::legacy`], the law such a record ran with.
    #[serde(default = "DamperLaw::legacy")]
    pub damper: DamperLaw,
    /// Travel window, lower end: the supervisor latches [`fault::TRAVEL`] (and enters
    /// `safe_mode`) on the first tick the raw count (the unwrapped encoder count, the frame of
    /// `wall_position`) is below it; `None` (the default) for no lower end. With both ends set
    /// it must be below `travel_max`. Added in protocol 3, after `damper`; absent from a
    /// self-describing record written before it, it is `None`.
    #[serde(default)]
    pub travel_min: Option<i32>,
    /// Travel window, upper end, raw counts: [`fault::TRAVEL`] when the raw count is above it;
    /// `None` (the default) for no upper end. With both ends set it must exceed `travel_min`
    /// (the window `[travel_min, travel_max]` holds at least two counts). Protocol 3.
    #[serde(default)]
    pub travel_max: Option<i32>,
}

impl Default for ServoConfig {
    /// Safe, board-independent defaults: no wall force (K = 0) until the host sets one,
    /// 1 kHz, no extra delay, no coarsening, bidirectional wall at count 0, 0.1 N force limit,
    /// velocity fault off, energy monitor on (1 J, 4 growing peaks), 1000-count jump limit,
    /// 500 ms heartbeat timeout, zero force in safe mode, the damper's dead band of one count
    /// ([`DamperLaw::default`]), no travel window.
    fn default() -> Self {
        Self {
            stiffness: 0.0,
            damping: 0.0,
            servo_rate_hz: 1000,
            extra_delay_ticks: 0,
            coarsen_shift: 0,
            wall: WallMode::Bidirectional,
            wall_position: 0,
            force_limit: 0.1,
            max_velocity: 0.0,
            energy_monitor: true,
            energy_limit: 1.0,
            energy_growth_cycles: 4,
            encoder_jump_counts: 1000,
            heartbeat_timeout_ms: 500,
            safe_mode: SafeMode::ZeroForce,
            safe_damping: 0.0,
            damper: DamperLaw::default(),
            travel_min: None,
            travel_max: None,
        }
    }
}

/// Fixed facts about the device (answer to `Hello`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DeviceInfo {
    /// The device's [`crate::PROTOCOL_VERSION`].
    pub protocol_version: u8,
    /// Firmware name.
    pub firmware_name: String<NAME_LEN>,
    /// Firmware version (semver).
    pub firmware_version: String<NAME_LEN>,
    /// Board name.
    pub board: String<NAME_LEN>,
    /// Servo rate currently configured, Hz.
    pub servo_rate_hz: u32,
    /// Encoder counts per revolution for rotary devices, 0 for linear ones.
    pub counts_per_rev: u32,
    /// Encoder resolution Δ (one raw count), m or rad.
    pub resolution: f32,
    /// Width of the hardware encoder counter, bits (16 or 32).
    pub encoder_bits: u8,
    /// Force (N) or torque (N·m) per output code.
    pub force_per_code: f32,
    /// Largest output code magnitude.
    pub max_code: i32,
    /// Limits of the configuration fields.
    pub limits: Limits,
}

/// Configuration limits advertised in the handshake.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// Lowest servo rate, Hz.
    pub min_rate_hz: u32,
    /// Highest servo rate, Hz.
    pub max_rate_hz: u32,
    /// Largest stiffness, N/m (N·m/rad), at coarsening shift 0.
    pub max_stiffness: f32,
    /// Largest force limit, N (N·m) (= max_code · force_per_code).
    pub max_force: f32,
    /// Largest extra delay, ticks.
    pub max_delay_ticks: u8,
    /// Largest coarsening shift.
    pub max_coarsen_shift: u8,
    /// Samples per telemetry batch.
    pub telemetry_batch: u16,
    /// Excitation table capacity, entries.
    pub max_table: u16,
}

/// One servo tick as seen by the host.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Sample {
    /// Servo tick counter (wraps).
    pub tick: u32,
    /// Unwrapped raw encoder count relative to the wall position (saturated to i32).
    pub count: i32,
    /// Force code written to the output this tick (after delay and clamp).
    pub force_code: i32,
    /// Status bits, [`flags`].
    pub flags: u16,
    /// Energy estimate: the potential part of H_T (35) at this count (equal to H_T at turning
    /// points), in units of K·Δ_eff²/8 (dimensionless ×8), saturating.
    pub energy: u32,
}

/// Sample status bits.
pub mod flags {
    /// Safe mode active (a fault is latched).
    pub const SAFE_MODE: u16 = 1 << 0;
    /// Release experiment: holding phase.
    pub const HOLD: u16 = 1 << 1;
    /// Release experiment: released phase.
    pub const RELEASED: u16 = 1 << 2;
    /// Excitation experiment running.
    pub const EXCITE: u16 = 1 << 3;
    /// The output was clamped to the force limit.
    pub const CLAMPED: u16 = 1 << 4;
    /// The wall is off (one-sided wall outside contact, or an excitation without a centring
    /// spring or damper: K = 0 and B = 0).
    pub const WALL_OFF: u16 = 1 << 5;
    /// The energy monitor saw a turning point this tick.
    pub const TURN: u16 = 1 << 6;
}

/// Fault bits (latched until `ClearFaults`).
pub mod fault {
    /// The energy monitor saw sustained energy growth.
    pub const ENERGY_GROWTH: u32 = 1 << 0;
    /// The energy estimate exceeded `energy_limit`.
    pub const ENERGY_LIMIT: u32 = 1 << 1;
    /// Velocity above `max_velocity`.
    pub const OVER_VELOCITY: u32 = 1 << 2;
    /// Host heartbeat lost during an experiment.
    pub const HEARTBEAT: u32 = 1 << 3;
    /// Encoder count jumped more than `encoder_jump_counts` in one tick.
    pub const ENCODER_JUMP: u32 = 1 << 4;
    /// The energy monitor saw a persistent oscillation of more than one count ("buzz").
    pub const BUZZ: u32 = 1 << 5;
    /// The raw count left the travel window [`super::ServoConfig::travel_min`,
    /// [`super::ServoConfig::travel_max`]] (protocol 3).
    pub const TRAVEL: u32 = 1 << 6;

    /// Every fault bit with its machine name (kebab-case: the CLI's text and JSON) and its
    /// label for people (the live view's banner), in bit order.
    pub const NAMES: [(u32, &str, &str); 7] = [
        (ENERGY_GROWTH, "energy-growth", "energy growth"),
        (ENERGY_LIMIT, "energy-limit", "energy limit"),
        (OVER_VELOCITY, "over-velocity", "over-velocity"),
        (HEARTBEAT, "heartbeat", "heartbeat lost"),
        (ENCODER_JUMP, "encoder-jump", "encoder jump"),
        (BUZZ, "buzz", "buzz"),
        (TRAVEL, "travel", "outside travel"),
    ];

    /// Every fault bit above, or-ed.
    pub const ALL: u32 =
        ENERGY_GROWTH | ENERGY_LIMIT | OVER_VELOCITY | HEARTBEAT | ENCODER_JUMP | BUZZ | TRAVEL;
}

/// A sequence of telemetry samples.
///
/// Sequence: every sample the servo produces gets the next sample number, whether or not it
/// reaches the host. `seq` is the number of `samples[0]`; the samples of one batch are
/// consecutive. `dropped` counts, cumulatively since boot, samples lost because the device's
/// telemetry queue was full: a host that sees `seq` jump by G between batches sees `dropped`
/// grow by exactly G when the loss happened on the device (any other gap was lost on the link).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct TelemetryBatch {
    /// Sample number of the first sample.
    pub seq: u32,
    /// Cumulative samples dropped on the device.
    pub dropped: u32,
    /// The samples.
    pub samples: Vec<Sample, TELEMETRY_BATCH>,
}

/// Latched faults.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FaultReport {
    /// Latched fault bits, [`fault`].
    pub latched: u32,
    /// Servo tick of the first latched fault (0 if none).
    pub first_tick: u32,
    /// Safe mode active.
    pub safe_mode: bool,
}

/// Error codes of [`DeviceMsg::Error`] (and of host-side decoding).
#[allow(missing_docs)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ErrorCode {
    /// Frame longer than [`crate::MAX_FRAME`].
    Oversize,
    /// CRC mismatch.
    Crc,
    /// Invalid COBS encoding or frame too short.
    Cobs,
    /// Unknown message tag.
    UnknownTag,
    /// Payload does not deserialize.
    Deserialize,
    /// Protocol version differs.
    VersionMismatch,
    /// `SetConfig` refused: see detail.
    InvalidConfig,
    /// Config store failed.
    StoreFailed,
    /// Request refused in the current state (e.g. an experiment running, faults latched).
    Busy,
    /// Request parameters out of range (experiments, table chunks).
    InvalidArgument,
    /// The servo's command queue is full (it takes one command per tick): transient, the
    /// request may be repeated unchanged (protocol version 4).
    QueueFull,
    /// `SetProfile` refused: see detail ([`ErrorDetail::ProfileField`]; protocol 5).
    InvalidProfile,
}

/// Fields of [`ServoConfig`] (for error details).
#[allow(missing_docs)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ConfigField {
    Stiffness,
    Damping,
    ServoRateHz,
    ExtraDelayTicks,
    CoarsenShift,
    Wall,
    WallPosition,
    ForceLimit,
    MaxVelocity,
    EnergyMonitor,
    EnergyLimit,
    EnergyGrowthCycles,
    EncoderJumpCounts,
    HeartbeatTimeoutMs,
    SafeMode,
    SafeDamping,
    /// Experiment / table parameters.
    Argument,
    /// [`ServoConfig::damper`] (protocol 2; its range is the dead band's, in counts).
    Damper,
    /// [`ServoConfig::travel_min`] (protocol 3).
    TravelMin,
    /// [`ServoConfig::travel_max`] (protocol 3; refused when not above `travel_min`, with the
    /// range `[travel_min + 1, i32::MAX]`).
    TravelMax,
}

impl ConfigField {
    /// The field's name in [`ServoConfig`] (`"argument"` for experiment / table parameters).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Stiffness => "stiffness",
            Self::Damping => "damping",
            Self::ServoRateHz => "servo_rate_hz",
            Self::ExtraDelayTicks => "extra_delay_ticks",
            Self::CoarsenShift => "coarsen_shift",
            Self::Wall => "wall",
            Self::WallPosition => "wall_position",
            Self::ForceLimit => "force_limit",
            Self::MaxVelocity => "max_velocity",
            Self::EnergyMonitor => "energy_monitor",
            Self::EnergyLimit => "energy_limit",
            Self::EnergyGrowthCycles => "energy_growth_cycles",
            Self::EncoderJumpCounts => "encoder_jump_counts",
            Self::HeartbeatTimeoutMs => "heartbeat_timeout_ms",
            Self::SafeMode => "safe_mode",
            Self::SafeDamping => "safe_damping",
            Self::Argument => "argument",
            Self::Damper => "damper",
            Self::TravelMin => "travel_min",
            Self::TravelMax => "travel_max",
        }
    }
}

impl core::fmt::Display for ConfigField {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// Details of an error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ErrorDetail {
    /// Nothing more.
    None,
    /// A field outside its allowed range `[min, max]` (or not finite).
    Field {
        /// Which field.
        field: ConfigField,
        /// Smallest allowed value.
        min: f64,
        /// Largest allowed value.
        max: f64,
    },
    /// Version mismatch.
    Version {
        /// Version received.
        got: u8,
        /// Version expected.
        expected: u8,
    },
    /// Unknown message tag.
    Tag(u32),
    /// Short text.
    Text(String<NAME_LEN>),
    /// `count` (≥ 2) consecutive bad frames with the same error code, answered by this one
    /// reply (the device coalesces framing errors so that a flood of bad frames cannot crowd
    /// telemetry off the link). Appended last: the tags of the variants above are unchanged.
    Repeated {
        /// Bad frames this reply stands for.
        count: u32,
    },
    /// A profile element's field outside its allowed range `[min, max]` (or not finite;
    /// protocol 5).
    ProfileField {
        /// The element's index in the profile (0-based).
        element: u8,
        /// Which field.
        field: ProfileField,
        /// Smallest allowed value.
        min: f64,
        /// Largest allowed value.
        max: f64,
    },
}

#[cfg(test)]
mod tests {
    use super::{fault, ServoConfig};
    use crate::damper::{DamperLaw, ParseDamperLawError, MAX_DEADBAND_COUNTS};
    use std::string::ToString;

    /// The default config's postcard bytes, written out by hand from postcard's rules (f32:
    /// 4 bytes LE; u32: varint; i32: zigzag varint; u8 and bool: one byte; an enum: its
    /// variant index as a varint, then its fields; an `Option`: `00` for `None`, `01` then the
    /// value for `Some`).
    #[test]
    fn default_config_literal_bytes_end_with_the_damper_and_the_travel_window() {
        #[rustfmt::skip]
        let protocol_2 = std::vec![
            0x00, 0x00, 0x00, 0x00, // stiffness 0.0
            0x00, 0x00, 0x00, 0x00, // damping 0.0
            0xe8, 0x07,             // servo_rate_hz 1000 = 0x68 | 0x80, 1000 >> 7 = 7
            0x00,                   // extra_delay_ticks 0
            0x00,                   // coarsen_shift 0
            0x00,                   // wall: Bidirectional (variant 0)
            0x00,                   // wall_position 0 (zigzag 0)
            0xcd, 0xcc, 0xcc, 0x3d, // force_limit 0.1 = 0x3dcccccd
            0x00, 0x00, 0x00, 0x00, // max_velocity 0.0
            0x01,                   // energy_monitor true
            0x00, 0x00, 0x80, 0x3f, // energy_limit 1.0 = 0x3f800000
            0x04,                   // energy_growth_cycles 4
            0xe8, 0x07,             // encoder_jump_counts 1000
            0xf4, 0x03,             // heartbeat_timeout_ms 500 = 0x74 | 0x80, 500 >> 7 = 3
            0x00,                   // safe_mode: ZeroForce (variant 0)
            0x00, 0x00, 0x00, 0x00, // safe_damping 0.0
            0x01, 0x01,             // damper: DeadBand (variant 1), counts 1
        ];
        let mut want = protocol_2.clone();
        want.extend_from_slice(&[
            0x00, // travel_min: None
            0x00, // travel_max: None
        ]);
        let mut buf = [0u8; 64];
        let c = ServoConfig::default();
        assert_eq!(postcard::to_slice(&c, &mut buf).unwrap(), &want[..]);
        // Difference is variant 0 with no fields: one byte.
        let mut diff = protocol_2.clone();
        diff.truncate(diff.len() - 2);
        diff.push(0x00);
        diff.extend_from_slice(&[0x00, 0x00]);
        let d = ServoConfig {
            damper: DamperLaw::Difference,
            ..c
        };
        assert_eq!(postcard::to_slice(&d, &mut buf).unwrap(), &diff[..]);
        assert_eq!(postcard::from_bytes::<ServoConfig>(&diff), Ok(d));
        // A travel window: Some(-5) = 01, zigzag 9; Some(1000) = 01, zigzag 2000 = d0 0f.
        let t = ServoConfig {
            travel_min: Some(-5),
            travel_max: Some(1000),
            ..c
        };
        let mut travel = protocol_2.clone();
        travel.extend_from_slice(&[0x01, 0x09, 0x01, 0xd0, 0x0f]);
        assert_eq!(postcard::to_slice(&t, &mut buf).unwrap(), &travel[..]);
        assert_eq!(postcard::from_bytes::<ServoConfig>(&travel), Ok(t));
        // A protocol-2 config (no travel bytes) does not decode as a protocol-3 one, nor a
        // protocol-1 one (no damper byte either).
        assert!(postcard::from_bytes::<ServoConfig>(&protocol_2).is_err());
        assert!(postcard::from_bytes::<ServoConfig>(&protocol_2[..protocol_2.len() - 2]).is_err());
    }

    #[test]
    fn damper_law_text_round_trips_and_refuses_other_spellings() {
        assert_eq!(DamperLaw::default(), DamperLaw::DeadBand { counts: 1 });
        assert_eq!(DamperLaw::Difference.to_string(), "difference");
        assert_eq!(DamperLaw::Difference.name(), "difference");
        assert_eq!(DamperLaw::DeadBand { counts: 3 }.name(), "dead-band-3");
        for c in 1..=MAX_DEADBAND_COUNTS {
            let law = DamperLaw::DeadBand { counts: c };
            assert_eq!(law.to_string().parse(), Ok(law));
            assert_eq!(law.dead_band(), c);
        }
        assert_eq!("difference".parse(), Ok(DamperLaw::Difference));
        assert_eq!(DamperLaw::Difference.dead_band(), 0);
        for (bad, counts) in [
            ("dead-band-0", 0),
            ("dead-band-9", 9),
            ("dead-band-256", 256),
            ("dead-band-99999999999", u32::MAX),
        ] {
            let e = bad.parse::<DamperLaw>().unwrap_err();
            assert_eq!(
                e,
                ParseDamperLawError::DeadBandOutOfRange { counts },
                "{bad}"
            );
            let m = e.to_string();
            assert!(m.contains("1..=8") && m.contains("`difference`"), "{m}");
        }
        for bad in [
            "",
            "Difference",
            "dead-band",
            "dead-band-",
            "dead-band-01",
            "dead-band-+1",
            "dead-band--1",
            "dead-band-1 ",
            " difference",
            "deadband-1",
            "DeadBand",
        ] {
            let e = bad.parse::<DamperLaw>().unwrap_err();
            assert_eq!(e, ParseDamperLawError::Unknown, "{bad:?}");
            assert!(
                e.to_string()
                    .contains("`difference` and `dead-band-N` with N in 1..=8"),
                "{e}"
            );
        }
    }

    #[test]
    fn every_fault_bit_has_one_name_in_bit_order() {
        let bits = fault::NAMES.map(|(b, _, _)| b);
        assert_eq!(
            bits,
            [
                fault::ENERGY_GROWTH,
                fault::ENERGY_LIMIT,
                fault::OVER_VELOCITY,
                fault::HEARTBEAT,
                fault::ENCODER_JUMP,
                fault::BUZZ,
                fault::TRAVEL,
            ]
        );
        for (i, (b, name, label)) in fault::NAMES.iter().enumerate() {
            assert_eq!(*b, 1 << i, "{name}");
            assert!(!name.contains(' ') && !label.is_empty(), "{name} / {label}");
        }
        assert_eq!(fault::ALL, bits.iter().fold(0, |a, b| a | b));
        assert_eq!(
            fault::NAMES.last(),
            Some(&(fault::TRAVEL, "travel", "outside travel"))
        );
    }
}
