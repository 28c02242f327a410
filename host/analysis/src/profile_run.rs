//! A haptic profile on a simulated device, software in the loop (issue 43, the proof): the
//! firmware's own `Device` and `Servo` (the fixed-point code the boards run) render a profile
//! loaded through the protocol (`HostMsg::SetProfile`, framed and decoded as on a wire)
//! against the virtual device's plant (a preset's rigid plant or a plant file's rich one), from
//! the starts a user meets: a release from rest and an impact at each element.
//!
//! Units: SI at the plant (m or rad, m/s or rad/s), raw encoder counts at the firmware (count
//! = ⌊x/Δ⌋, the virtual device's frame), servo ticks. A run's verdict is the project's one
//! rest rule (`stiffwall_core::rest`): it comes to rest when its count changes at most twice
//! over the judged window.
//!
//! Invariants: deterministic (no clock, no thread); the plant is held at the start until the
//! profile is active (four ticks), then released there with the start's velocity; the run stops only at
//! its length, or at the first fault (which ends it: the supervisor's safe mode is not the
//! profile).

use stiffwall_client::VirtualSpec as Spec;
use stiffwall_core::rest;
use stiffwall_firmware::{
    ByteLink, Channels, ConfigStore, Device, HeldCode, MemStorage, SampledCount, Servo,
};
use stiffwall_proto::{
    encode, DeviceMsg, FrameDecoder, HostMsg, Profile, ProfileElement, Side, MAX_FRAME,
};
use stiffwall_sim::rich::RichPlant;

/// Why a run could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ProfileRunError {
    /// The plant of the spec does not build.
    #[error("the device's plant: {0}")]
    Plant(String),
    /// The device refused the profile (its words).
    #[error("the device refused the profile: {0}")]
    Refused(String),
    /// The profile does not fit a frame.
    #[error("the profile does not fit a frame: {0}")]
    Frame(String),
}

/// Where a run starts: the plant's position and velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct Start {
    /// What the start is, in words ("release 0.25 pitch above detent 3 of element 1").
    pub label: String,
    /// The element it tests (index in the profile).
    pub element: usize,
    /// Position, m (rad).
    pub position: f64,
    /// Velocity, m/s (rad/s).
    pub velocity: f64,
}

/// One run.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Raw counts, one per tick.
    pub counts: Vec<i64>,
    /// Fault bits latched (0: none; the run ended at the first).
    pub faults: u32,
    /// It comes to rest by the rest rule.
    pub rests: bool,
}

impl Run {
    /// The last count.
    #[must_use]
    pub fn final_count(&self) -> i64 {
        self.counts.last().copied().unwrap_or(0)
    }

    /// The counts spanned over the judged window of `natural_ticks` (0 at rest).
    #[must_use]
    pub fn final_span(&self, natural_ticks: f64) -> i64 {
        let w = &self.counts[rest::window_start(self.counts.len(), natural_ticks)..];
        w.iter().max().unwrap_or(&0) - w.iter().min().unwrap_or(&0)
    }
}

/// A byte link in memory: the host's frames in, the device's bytes out.
#[derive(Debug, Default)]
struct Link {
    rx: std::collections::VecDeque<u8>,
    tx: Vec<u8>,
}

impl ByteLink for Link {
    fn read(&mut self) -> Option<u8> {
        self.rx.pop_front()
    }
    fn write(&mut self, byte: u8) -> bool {
        self.tx.push(byte);
        true
    }
}

/// The device's replies in `bytes`.
fn replies(bytes: &[u8]) -> Vec<DeviceMsg> {
    let mut d = FrameDecoder::new();
    bytes
        .iter()
        .filter_map(|&b| d.feed::<DeviceMsg>(b))
        .filter_map(Result::ok)
        .collect()
}

/// Runs `profile` on the device of `spec` from `start` for `ticks` servo ticks; the rest rule
/// judges the run with the natural period `natural_ticks` (servo ticks; not finite or ≤ 0:
/// the last quarter is judged).
///
/// # Errors
/// The spec's plant does not build; the device refuses the profile (its reason).
pub fn run(
    spec: &Spec,
    profile: &Profile,
    start: &Start,
    ticks: usize,
    natural_ticks: f64,
) -> Result<Run, ProfileRunError> {
    run_traced(spec, profile, start, ticks, natural_ticks, &mut |_| {})
}

/// The plant at one servo tick of a run: its state at the sample instant (when the count of
/// the same tick is read) and the force the servo commands from there for one period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Position, m (rad).
    pub position: f64,
    /// Velocity, m/s (rad/s).
    pub velocity: f64,
    /// Commanded force, N (N·m), held for the tick.
    pub force: f64,
}

/// [`run`], calling `on_tick` with each tick's [`Sample`] (in tick order, one per count of the
/// returned run; the run and its verdict are [`run`]'s).
///
/// # Errors
/// As [`run`].
pub fn run_traced(
    spec: &Spec,
    profile: &Profile,
    start: &Start,
    ticks: usize,
    natural_ticks: f64,
    on_tick: &mut dyn FnMut(&Sample),
) -> Result<Run, ProfileRunError> {
    let model = spec
        .plant_model()
        .map_err(|e| ProfileRunError::Plant(e.to_string()))?;
    let mut plant = RichPlant::new(&model).map_err(|e| ProfileRunError::Plant(e.to_string()))?;
    // At the start from the first tick: the servo's first reading and its count difference are
    // of the start, so the damper sees no jump there (a device does not teleport).
    plant.set_state(start.position, 0.0);
    let board = spec.board();
    let mut channels = Box::new(Channels::new());
    let (servo_port, host_port) = channels.split();
    let store = ConfigStore::new(MemStorage::default());
    let mut device = Device::new(board, store, host_port, spec.defaults());
    let mut servo: Servo<'_> = Servo::new(board, device.config(), servo_port);
    let period_s = 1.0 / f64::from(device.servo_rate_hz().max(1));
    let fpc = f64::from(board.force_per_code);
    let mut link = Link::default();
    let mut frame = [0u8; MAX_FRAME];
    let bytes = encode(&HostMsg::SetProfile(profile.clone()), &mut frame)
        .map_err(|e| ProfileRunError::Frame(e.to_string()))?;
    link.rx.extend(bytes.iter().copied());
    let mut tick = 0u32;
    let step = |servo: &mut Servo<'_>, plant: &RichPlant, tick: &mut u32| {
        *tick = tick.wrapping_add(1);
        let mut out = HeldCode(0);
        servo.tick(
            *tick,
            &mut SampledCount(plant.encoder_count() as u32),
            &mut out,
        );
        f64::from(out.0) * fpc
    };
    // The request, its reply, and the servo taking the profile (one command per tick), with
    // the plant held at the start.
    for _ in 0..4 {
        device.poll(tick, &mut link);
        step(&mut servo, &plant, &mut tick);
    }
    device.poll(tick, &mut link);
    for reply in replies(&link.tx) {
        if let DeviceMsg::Error { code, detail } = reply {
            return Err(ProfileRunError::Refused(stiffwall_client::describe_error(
                code, &detail,
            )));
        }
    }
    plant.set_state(start.position, start.velocity);
    let mut counts = Vec::with_capacity(ticks);
    let mut faults = 0;
    for _ in 0..ticks {
        counts.push(plant.encoder_count());
        let force = step(&mut servo, &plant, &mut tick);
        on_tick(&Sample {
            position: plant.position_m(),
            velocity: plant.velocity_m_per_s(),
            force,
        });
        plant.advance(force, period_s);
        link.tx.clear();
        device.poll(tick, &mut link);
        faults = servo.faults();
        if faults != 0 {
            break;
        }
    }
    let rests = faults == 0 && rest::comes_to_rest(&counts, natural_ticks);
    Ok(Run {
        counts,
        faults,
        rests,
    })
}

/// The minima of a detent train, raw counts (fractional).
#[must_use]
pub fn detent_minima(e: &ProfileElement) -> Vec<f64> {
    match *e {
        ProfileElement::Detents {
            first,
            pitch_counts,
            count,
            ..
        } => (0..count)
            .map(|j| f64::from(first) + f64::from(j) * pitch_counts)
            .collect(),
        _ => Vec::new(),
    }
}

/// True when the count `n` lies within one count of the minimum `m` (raw counts, fractional):
/// it is the count holding the minimum, ⌊m⌋, or one beside it. A detent whose force one and a
/// half counts from its minimum exceeds static friction, A·sin(3π·Δ/pitch) > F_s (the check's
/// centring rule), can rest in no other count: every other count's centre is at least 1.5
/// counts from the minimum.
#[must_use]
pub fn within_one_count(n: i64, m: f64) -> bool {
    (n - m.floor() as i64).abs() <= 1
}

/// The starts a user meets at each element, for a device of resolution `resolution` (m or rad
/// per count) and an impact speed `velocity` (m/s or rad/s): a release from rest and an impact
/// at each wall (from `approach` counts outside, moving in; from `approach` counts inside, at
/// rest), a spring's release from ±`approach` counts and an impact through its centre, a
/// release a quarter pitch above and below every detent's minimum and an impact across the
/// train from each end, and a viscous zone entered at speed from each side.
#[must_use]
pub fn starts(profile: &Profile, resolution: f64, velocity: f64, approach: i32) -> Vec<Start> {
    let mut out = Vec::new();
    let at = |c: f64| c * resolution;
    let a = f64::from(approach);
    for (i, e) in profile.elements.iter().enumerate() {
        let mut push = |label: String, c: f64, v: f64| {
            out.push(Start {
                label: format!("element {} ({}): {label}", i + 1, e.kind_name()),
                element: i,
                position: at(c),
                velocity: v,
            });
        };
        match *e {
            ProfileElement::Wall { position, side, .. } => {
                let p = f64::from(position);
                let (outside, inside, into) = match side {
                    Side::Upper => (p - a, p + a, velocity),
                    Side::Lower => (p + a, p - a, -velocity),
                };
                push(
                    format!("impact from {approach} counts out"),
                    outside + 0.5,
                    into,
                );
                push(
                    format!("release from {approach} counts in"),
                    inside + 0.5,
                    0.0,
                );
            }
            ProfileElement::Spring { center, .. } => {
                let c = f64::from(center);
                push(format!("release from +{approach} counts"), c + a + 0.5, 0.0);
                push(format!("release from −{approach} counts"), c - a + 0.5, 0.0);
                push("impact through the centre".into(), c - a + 0.5, velocity);
            }
            ProfileElement::Detents { pitch_counts, .. } => {
                let minima = detent_minima(e);
                for (j, m) in minima.iter().enumerate() {
                    push(
                        format!("release ¼ pitch above detent {j}"),
                        m + pitch_counts / 4.0,
                        0.0,
                    );
                    push(
                        format!("release ¼ pitch below detent {j}"),
                        m - pitch_counts / 4.0,
                        0.0,
                    );
                }
                let lo = minima.first().copied().unwrap_or(0.0) - pitch_counts / 2.0;
                let hi = minima.last().copied().unwrap_or(0.0) + pitch_counts / 2.0;
                push("impact across the train upward".into(), lo + 0.5, velocity);
                push(
                    "impact across the train downward".into(),
                    hi - 0.5,
                    -velocity,
                );
            }
            ProfileElement::Viscous { from, to, .. } => {
                push("entered upward".into(), f64::from(from) - 0.5, velocity);
                push("entered downward".into(), f64::from(to) + 0.5, -velocity);
            }
        }
    }
    out
}

/// An element's stiffest local slope, N/m (N·m/rad): its K, or a detent train's 2π·A/pitch
/// (at a minimum); 0 for a viscous zone.
#[must_use]
pub fn local_k(e: &ProfileElement, resolution: f64) -> f64 {
    match *e {
        ProfileElement::Wall { stiffness, .. } | ProfileElement::Spring { stiffness, .. } => {
            f64::from(stiffness)
        }
        ProfileElement::Detents {
            strength,
            pitch_counts,
            ..
        } => core::f64::consts::TAU * f64::from(strength) / (pitch_counts * resolution),
        ProfileElement::Viscous { .. } => 0.0,
    }
}

/// Runs `start` for at least 60 natural periods 2π√(m/K) of its element's local stiffness
/// (the rest rule's run) and 20 000 ticks (a viscous zone, which has none: 20 000); returns
/// the run and the natural period in ticks.
///
/// # Errors
/// As [`run`].
pub fn run_start(
    spec: &Spec,
    profile: &Profile,
    start: &Start,
) -> Result<(Run, f64), ProfileRunError> {
    let p = &spec.plant;
    let k = profile
        .elements
        .get(start.element)
        .map_or(0.0, |e| local_k(e, p.resolution));
    let natural = core::f64::consts::TAU * (p.mass / k).sqrt() / p.period_s;
    let ticks = if natural.is_finite() {
        ((rest::REST_RUN_NATURAL_PERIODS * natural).ceil() as usize).max(20_000)
    } else {
        20_000
    };
    Ok((run(spec, profile, start, ticks, natural)?, natural))
}

/// Where a run came to rest, by the profile's elements.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RestPlace {
    /// Within one count of minimum `minimum` of detent train `element`.
    Detent {
        /// The train's index in the profile.
        element: usize,
        /// The minimum's index in the train.
        minimum: usize,
    },
    /// Within one count of the surface of wall `element` (its first count in contact, or the
    /// free count beside it).
    Wall {
        /// The wall's index.
        element: usize,
    },
    /// Inside a detent train's span but at no minimum and against no wall: not where the
    /// profile holds the device.
    OffDetent {
        /// The train's index.
        element: usize,
    },
    /// Elsewhere (free space, a spring, a viscous zone).
    Elsewhere,
}

/// Where raw count `n` lies by `profile`'s elements (see [`RestPlace`]).
#[must_use]
pub fn rest_place(profile: &Profile, n: i64) -> RestPlace {
    let walls = profile
        .elements
        .iter()
        .enumerate()
        .find_map(|(i, e)| match *e {
            ProfileElement::Wall { position, .. } => {
                let p = i64::from(position);
                (p - 1..=p)
                    .contains(&n)
                    .then_some(RestPlace::Wall { element: i })
            }
            _ => None,
        });
    for (i, e) in profile.elements.iter().enumerate() {
        let ProfileElement::Detents { pitch_counts, .. } = *e else {
            continue;
        };
        let minima = detent_minima(e);
        if let Some(j) = minima.iter().position(|&m| within_one_count(n, m)) {
            return RestPlace::Detent {
                element: i,
                minimum: j,
            };
        }
        let lo = minima.first().copied().unwrap_or(0.0) - pitch_counts / 2.0;
        let hi = minima.last().copied().unwrap_or(0.0) + pitch_counts / 2.0;
        let centre = n as f64 + 0.5;
        if (lo..hi).contains(&centre) && walls.is_none() {
            return RestPlace::OffDetent { element: i };
        }
    }
    walls.unwrap_or(RestPlace::Elsewhere)
}
