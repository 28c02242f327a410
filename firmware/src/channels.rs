//! The channels between the servo (interrupt) and the main loop: lock-free SPSC queues for
//! telemetry, commands and events, and the atomics both sides read ([`Shared`]).
//!
//! Units: `seq` is the servo's sample number (every sample produced, sent or dropped); ticks are
//! servo ticks; queue lengths are entries (a queue of length L holds L − 1).
//!
//! Invariants: the servo is the single producer of telemetry and events and the single consumer
//! of commands ([`ServoPort`]); the main loop is the other end ([`HostPort`]). Neither end
//! blocks or allocates; a full queue refuses the item (the servo counts dropped samples in
//! [`Shared::dropped`]). A compiled haptic profile travels in a queue of its own
//! (`ProfileTable`s are kilobytes: in [`ServoCmd`] they would make every command's copy out of
//! the queue that long), announced by one [`ServoCmd::Profile`] in the command queue, so it
//! takes effect in order with the configs around it, whole, between two ticks. The channels are
//! generic over the servo's numeric back-end `N` (the table's gain forms), `Fx64` by default.
//! This module imports only the numeric back-ends and the profile table of the crate.

use core::sync::atomic::{AtomicBool, AtomicU32};
// heapless 0.8's SPSC queue: its capacity is a const generic, so enqueue/dequeue have no
// division by a runtime capacity (0.9's has one, a panic path; see the workspace Cargo.toml).
use crate::numeric::{Fx64, Numeric};
use crate::profile::ProfileTable;
use heapless::Vec;
use heapless08::spsc::{Consumer, Producer, Queue};
use stiffwall_proto::{ExciteProfile, ExperimentKind, Sample, ServoConfig, TABLE_CHUNK};

/// Telemetry queue length (capacity − 1 samples in flight).
pub const TELEMETRY_QUEUE: usize = 256;
/// Command queue length.
pub const COMMAND_QUEUE: usize = 4;
/// Event queue length.
pub const EVENT_QUEUE: usize = 8;
/// Profile queue length (one compiled profile in flight).
pub const PROFILE_QUEUE: usize = 2;

/// A telemetry sample with its sample number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TelemetryItem {
    /// Sample number (counts every sample produced, sent or dropped).
    pub seq: u32,
    /// The sample.
    pub sample: Sample,
}

/// Commands from the main loop to the servo.
///
/// `repr(C)` (a tag word, then the variant's fields at aligned offsets): the servo copies a
/// command out of the queue in the tick that takes it, and with Rust's layout (the tag in a
/// niche of a nested config) that copy was split into misaligned pieces that `memcpy` moved
/// byte by byte. Once the configs grew (protocol 3's travel window) a tick that cleared the
/// faults took 762 instructions, over its 700 budget; with `repr(C)` it takes 504
/// (`cargo xtask bench-firmware`).
#[derive(Debug, Clone, PartialEq)]
#[repr(C)]
pub enum ServoCmd {
    /// Apply a validated configuration.
    Config(ServoConfig),
    /// Telemetry every `decimation` ticks; 0 stops.
    Stream {
        /// Ticks per sample, 0 = off.
        decimation: u16,
    },
    /// Start a release test.
    Release {
        /// Deflection, effective counts from the wall.
        deflection: i32,
        /// Ticks after release.
        ticks: u32,
        /// How it ends besides its length (`HostMsg::PrepareTest`).
        end: Option<DecidedEnd>,
    },
    /// Start an impact test.
    Impact {
        /// Start, effective counts from the wall (|·| ≤ 2²⁰).
        start: i32,
        /// Launch velocity toward the wall, thousandths of a count per tick.
        velocity_milli: i32,
        /// Ticks after contact.
        ticks: u32,
        /// How it ends besides its length (`HostMsg::PrepareTest`).
        end: Option<DecidedEnd>,
    },
    /// Start an excitation.
    Excite {
        /// Profile.
        profile: ExciteProfile,
        /// Ticks.
        ticks: u32,
    },
    /// Store table values.
    TableChunk {
        /// First index.
        offset: u16,
        /// Values (codes).
        values: Vec<i16, TABLE_CHUNK>,
    },
    /// Clear latched faults.
    ClearFaults,
    /// Abort the running experiment.
    Stop,
    /// Take the next compiled profile from the profile queue and render it (an empty one
    /// renders the config's wall again). Enqueued after its table.
    Profile,
}

/// A release or impact test prepared by `HostMsg::PrepareTest`: run with `run` from its first
/// tick, ended when settled after a run of `min_run` counts (within one count with
/// `one_count`; 0: never) or decided at a decay checkpoint from `decay_base` (0: none), and
/// back to `park` (the active config) on the tick it ends, however it ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DecidedEnd {
    /// Shortest settled run, ticks (0: no settled end).
    pub min_run: u32,
    /// A toggle between neighbouring counts counts as settled.
    pub one_count: bool,
    /// Base length of the decay checkpoints, ticks (0: none).
    pub decay_base: u32,
    /// The test's config, applied on the tick it starts.
    pub run: ServoConfig,
    /// The config applied on the tick the test ends (the active one).
    pub park: ServoConfig,
}

/// Events from the servo to the main loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ServoEvent {
    /// An experiment ended.
    ExperimentDone {
        /// Which.
        kind: ExperimentKind,
        /// Ran its full length.
        completed: bool,
        /// Latched faults at the end.
        faults: u32,
        /// Sample number the next telemetry sample will get (all the experiment's samples
        /// have smaller numbers): the main loop reports the end after sending them.
        next_seq: u32,
    },
}

/// State shared between servo and main loop through atomics.
#[derive(Debug, Default)]
pub struct Shared {
    /// Latched fault bits.
    pub faults: AtomicU32,
    /// Tick of the first latched fault.
    pub first_fault_tick: AtomicU32,
    /// Samples dropped because the telemetry queue was full (cumulative).
    pub dropped: AtomicU32,
    /// Heartbeat counter, incremented by the main loop on each host heartbeat.
    pub heartbeat: AtomicU32,
    /// An experiment is running.
    pub experiment: AtomicBool,
    /// Last servo tick seen.
    pub tick: AtomicU32,
}

impl Shared {
    /// All zero.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            faults: AtomicU32::new(0),
            first_fault_tick: AtomicU32::new(0),
            dropped: AtomicU32::new(0),
            heartbeat: AtomicU32::new(0),
            experiment: AtomicBool::new(false),
            tick: AtomicU32::new(0),
        }
    }
}

/// The queues and shared state between the servo (interrupt) and the main loop. Allocate it
/// statically (e.g. `static_cell`) on a board, or on the stack in tests, then [`Channels::split`].
pub struct Channels<N: Numeric = Fx64> {
    telemetry: Queue<TelemetryItem, TELEMETRY_QUEUE>,
    commands: Queue<ServoCmd, COMMAND_QUEUE>,
    events: Queue<ServoEvent, EVENT_QUEUE>,
    profiles: Queue<ProfileTable<N>, PROFILE_QUEUE>,
    shared: Shared,
}

impl<N: Numeric> core::fmt::Debug for Channels<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Channels")
            .field("shared", &self.shared)
            .finish_non_exhaustive()
    }
}

impl Default for Channels {
    fn default() -> Self {
        Self::new()
    }
}

impl Channels {
    /// Empty queues, for the default back-end (`Fx64`).
    #[must_use]
    pub const fn new() -> Self {
        Self::for_numeric()
    }
}

impl<N: Numeric> Channels<N> {
    /// Empty queues, for a servo of back-end `N`.
    #[must_use]
    pub const fn for_numeric() -> Self {
        Self {
            telemetry: Queue::new(),
            commands: Queue::new(),
            events: Queue::new(),
            profiles: Queue::new(),
            shared: Shared::new(),
        }
    }

    /// The servo's end and the main loop's end.
    pub fn split(&mut self) -> (ServoPort<'_, N>, HostPort<'_, N>) {
        let Channels {
            telemetry,
            commands,
            events,
            profiles,
            shared,
        } = self;
        let shared: &Shared = shared;
        let (tp, tc) = telemetry.split();
        let (cp, cc) = commands.split();
        let (ep, ec) = events.split();
        let (pp, pc) = profiles.split();
        (
            ServoPort {
                telemetry: tp,
                commands: cc,
                events: ep,
                profiles: pc,
                shared,
            },
            HostPort {
                telemetry: tc,
                commands: cp,
                events: ec,
                profiles: pp,
                shared,
            },
        )
    }
}

/// The servo's end of [`Channels`].
pub struct ServoPort<'a, N: Numeric = Fx64> {
    pub(crate) telemetry: Producer<'a, TelemetryItem, TELEMETRY_QUEUE>,
    pub(crate) commands: Consumer<'a, ServoCmd, COMMAND_QUEUE>,
    pub(crate) events: Producer<'a, ServoEvent, EVENT_QUEUE>,
    pub(crate) profiles: Consumer<'a, ProfileTable<N>, PROFILE_QUEUE>,
    pub(crate) shared: &'a Shared,
}

/// The main loop's end of [`Channels`].
pub struct HostPort<'a, N: Numeric = Fx64> {
    /// Telemetry samples from the servo.
    pub telemetry: Consumer<'a, TelemetryItem, TELEMETRY_QUEUE>,
    /// Commands to the servo.
    pub commands: Producer<'a, ServoCmd, COMMAND_QUEUE>,
    /// Events from the servo.
    pub events: Consumer<'a, ServoEvent, EVENT_QUEUE>,
    /// Compiled profiles to the servo (each announced by a [`ServoCmd::Profile`]).
    pub profiles: Producer<'a, ProfileTable<N>, PROFILE_QUEUE>,
    /// Shared atomics.
    pub shared: &'a Shared,
}

impl<N: Numeric> core::fmt::Debug for ServoPort<'_, N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ServoPort")
            .field("shared", self.shared)
            .finish_non_exhaustive()
    }
}

impl<N: Numeric> core::fmt::Debug for HostPort<'_, N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("HostPort")
            .field("shared", self.shared)
            .finish_non_exhaustive()
    }
}
