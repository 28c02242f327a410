//! The haptic profiles of the bench's profile stages (protocol 5, `HostMsg::SetProfile`'s
//! `Profile`), all of them acting on every count of the damped stage's sweep (±512 counts
//! around 0, two counts per tick) so that every element computes on every tick.
//!
//! The worst case a user can load is [`detents`]`(16)`: sixteen detent trains, every one of
//! them spanning the whole sweep, each with a damper (B > 0, the default law: a dead band of one
//! count, exceeded by the sweep's two counts per tick). A detent train is the costliest element:
//! its phase is a 64-bit product and its force a sine (`idsp::cossin`) and a 64-bit product,
//! where a wall or a spring is one multiply, and a viscous zone only the damper; the one-element
//! stages of each kind ([`one`]) measure that. The sixteen trains' forces add up beyond the
//! bench's force limit (0.09 N, 600 codes) on part of the sweep (35 of its 1025 counts), so the
//! output clamp's clamped path runs too.
//! Units: raw counts, N/m, N·s/m, N, as the wire profile's.

use super::kit::{
    check_no_faults, full, io, measure, report, start_stream, window, Sink, Sweep, SWEEP_LEN,
};
use core::hint::black_box;
use cortex_m_semihosting::hprintln;
use stiffwall_firmware::profile::{compile, validate};
use stiffwall_firmware::{BoardInfo, Channels, HostPort, Numeric, Servo, ServoCmd};
use stiffwall_proto::profile::{Profile, ProfileElement, Side};
use stiffwall_proto::{DamperLaw, ServoConfig};

/// Damping of every element, N·s/m (the damped stage's B, `DAMPING_N_S_PER_M`).
const B: f32 = 0.01;
/// The damper law of every element: the default, a dead band of one count.
const LAW: DamperLaw = DamperLaw::DeadBand { counts: 1 };
/// The sweep's reach, counts either side of 0, with margin: every element covers it.
const REACH: i32 = 600;
/// Each detent train's peak force, N (about 167 codes: the sixteen trains' sum passes the
/// 600-code limit on part of the sweep, up to 740 codes).
const DETENT_STRENGTH: f32 = 0.025;

/// Train `i` of [`detents`]: a pitch of 40 + 3i counts (not all alike: the phases differ), from
/// below the sweep's lower end to beyond its upper end.
fn train(i: usize) -> ProfileElement {
    let pitch = 40.0 + 3.0 * i as f64;
    ProfileElement::Detents {
        first: -REACH - i as i32,
        pitch_counts: pitch,
        count: (2.0 * f64::from(REACH) / pitch) as u16 + 2,
        strength: DETENT_STRENGTH,
        damping: B,
        damper: LAW,
    }
}

/// `n` detent trains (at most 16), each over the whole sweep, each with its damper acting.
pub fn detents(n: usize) -> Profile {
    let mut p = Profile::default();
    for i in 0..n {
        let _ = p.elements.push(train(i));
    }
    p
}

/// The detent stages: (trains, stage name). 16 is the gated worst case; 1 and 4 show the cost
/// per element.
pub const TRAINS: [(usize, &str); 3] = [
    (1, "profile-detents-1"),
    (4, "profile-detents-4"),
    (16, "profile-detents-16"),
];

/// The one-element stages of the other kinds, by stage name (see [`one`]).
pub const ONE: [&str; 3] = ["profile-wall-1", "profile-spring-1", "profile-viscous-1"];

/// The element of stage `stage` (of [`ONE`]) acting on the whole sweep, its damper acting: a
/// wall (`Upper`, its surface below the sweep: always in contact), a centring spring, a viscous
/// zone (a detent train otherwise).
pub fn one(stage: &str) -> Profile {
    let e = match stage {
        "profile-wall-1" => ProfileElement::Wall {
            position: -REACH,
            side: Side::Upper,
            stiffness: 2.0,
            damping: B,
            damper: LAW,
        },
        "profile-spring-1" => ProfileElement::Spring {
            center: 0,
            stiffness: 2.0,
            damping: B,
            damper: LAW,
        },
        "profile-viscous-1" => ProfileElement::Viscous {
            from: -REACH,
            to: REACH,
            damping: B,
            damper: LAW,
        },
        _ => train(0),
    };
    let mut p = Profile::default();
    let _ = p.elements.push(e);
    p
}

/// The profile stages: the full tick with the damper (`full+damper`'s config and sweep) in
/// profile mode, one stage per profile of this module (the mean, as the other stages), then
/// for each detent stage one run with every tick timed alone ([`profile_ticks`]).
pub fn stages<N: Numeric>(
    board: BoardInfo,
    damped: &ServoConfig,
    table: &[u32; SWEEP_LEN],
    baseline: u64,
) {
    for stage in ONE {
        profile_mean::<N>(stage, &one(stage), board, damped, table, baseline);
    }
    for (n, stage) in TRAINS {
        profile_mean::<N>(stage, &detents(n), board, damped, table, baseline);
    }
    for (n, stage) in TRAINS {
        profile_ticks::<N>(stage, &detents(n), board, damped, table);
    }
}

/// The main loop's side of `HostMsg::SetProfile` (as `Device::set_profile`): validates `p`
/// against `cfg` and the board, compiles it for the servo's back-end, and queues the table and
/// its `ServoCmd::Profile`.
fn load<N: Numeric>(host: &mut HostPort<'_, N>, p: &Profile, cfg: &ServoConfig, board: &BoardInfo) {
    if validate(p, cfg, board).is_err() {
        hprintln!("BENCH-ERROR the bench's profile is refused for {}", N::NAME);
        return;
    }
    let table = compile::<N>(p, cfg, board);
    if host.profiles.enqueue(table).is_err() || host.commands.enqueue(ServoCmd::Profile).is_err() {
        hprintln!("BENCH-ERROR profile or command queue full");
    }
}

/// A servo on `cfg` streaming at every tick, `p` loaded and taken (its first ticks, unmeasured):
/// it renders `p` from the next tick on.
fn profile_servo<'c, N: Numeric>(
    channels: &'c mut Channels<N>,
    p: &Profile,
    board: BoardInfo,
    cfg: &ServoConfig,
    enc: &mut Sweep<'_>,
) -> (Servo<'c, N>, HostPort<'c, N>) {
    let (servo_port, mut host) = channels.split();
    let mut servo: Servo<'_, N> = Servo::new(board, cfg, servo_port);
    start_stream(&mut host);
    load(&mut host, p, cfg, &board);
    for t in 0..2 {
        black_box(full(&mut servo, t, enc, &mut Sink));
    }
    if servo.profile().elements().len() != p.elements.len() {
        hprintln!("BENCH-ERROR the servo renders no profile for {}", N::NAME);
    }
    (servo, host)
}

/// The mean of the full tick rendering `p` (as the bench's other stages).
fn profile_mean<N: Numeric>(
    stage: &str,
    p: &Profile,
    board: BoardInfo,
    cfg: &ServoConfig,
    table: &[u32; SWEEP_LEN],
    baseline: u64,
) {
    let mut enc = Sweep { table, i: 0 };
    let mut out = Sink;
    let mut channels = Channels::<N>::for_numeric();
    let (mut servo, mut host) = profile_servo(&mut channels, p, board, cfg, &mut enc);
    let c = measure(
        |t| {
            black_box(full(&mut servo, t, &mut enc, &mut out));
        },
        || while host.telemetry.dequeue().is_some() {},
    );
    report(stage, N::NAME, c, baseline);
    check_no_faults(&servo, " with a profile");
}

/// Ticks of a profile's timed run; the tick at which the profile is loaded, and the tick at
/// which a config change arrives (its table recompiled and queued behind it, as the device's
/// `SetConfig` does with an active profile: the config on that tick, the table on the next).
const PROFILE_TICKS: u32 = 2100;
const AT_LOAD: u32 = 2;
const AT_PROFILE_CONFIG: u32 = 1000;
const AT_PROFILE_RETAKE: u32 = AT_PROFILE_CONFIG + 1;
/// Phases of a profile's timed run, as printed (`BENCH-PROFILE-TICK <stage> <phase> …`): the
/// ticks that take a profile (`ServoCmd::Profile`: the table out of its queue), the tick that
/// applies a config in profile mode, and the ticks rendering the profile.
const PROFILE_PHASES: [&str; 3] = ["profile-take", "config-change", "profile-tick"];

/// One run of the full tick rendering `p`, every tick timed alone (the per-tick stand-ins
/// subtracted, as in the bench's worst-tick run): the main loop loads `p` at tick [`AT_LOAD`] (validate and
/// compile timed: `BENCH-COMPILE <stage> <numeric> <ns>`), changes the config at
/// [`AT_PROFILE_CONFIG`] (K × 1.5, B × 0.5, the profile compiled again for it). Prints
/// `BENCH-PROFILE-TICK <stage> <phase> <numeric> <ns of the longest tick> <its tick> <ticks>`.
fn profile_ticks<N: Numeric>(
    stage: &str,
    p: &Profile,
    board: BoardInfo,
    cfg: &ServoConfig,
    table: &[u32; SWEEP_LEN],
) {
    let mut enc = Sweep { table, i: 0 };
    let mut out = Sink;
    let mut io_ns = u64::MAX;
    for _ in 0..256 {
        io_ns = io_ns.min(window(|| {
            black_box(io(&mut enc, &mut out));
        }));
    }
    let changed = ServoConfig {
        stiffness: 1.5 * cfg.stiffness,
        damping: 0.5 * cfg.damping,
        ..*cfg
    };
    let mut channels = Channels::<N>::for_numeric();
    let (servo_port, mut host) = channels.split();
    let mut servo: Servo<'_, N> = Servo::new(board, cfg, servo_port);
    start_stream(&mut host);
    let mut worst = [(0u64, 0u32); PROFILE_PHASES.len()];
    let mut seen = [0u32; PROFILE_PHASES.len()];
    for t in 0..PROFILE_TICKS {
        // Unmeasured but for the compile: the main loop's side.
        if t == AT_LOAD {
            let ns = window(|| load(&mut host, p, cfg, &board));
            hprintln!("BENCH-COMPILE {} {} {}", stage, N::NAME, ns);
        }
        if t == AT_PROFILE_CONFIG {
            if host.commands.enqueue(ServoCmd::Config(changed)).is_err() {
                hprintln!("BENCH-ERROR command queue full");
            }
            load(&mut host, p, &changed, &board);
        }
        let ns = window(|| {
            black_box(full(&mut servo, t, &mut enc, &mut out));
        });
        while host.telemetry.dequeue().is_some() {}
        let phase = match t {
            AT_LOAD | AT_PROFILE_RETAKE => 0,
            AT_PROFILE_CONFIG => 1,
            _ if t > AT_LOAD => 2,
            _ => continue,
        };
        seen[phase] += 1;
        let ns = ns.saturating_sub(io_ns);
        if ns > worst[phase].0 {
            worst[phase] = (ns, t);
        }
    }
    check_no_faults(&servo, " with a profile");
    if servo.profile().elements().len() != p.elements.len() {
        hprintln!("BENCH-ERROR the servo renders no profile for {}", N::NAME);
    }
    for (i, phase) in PROFILE_PHASES.iter().enumerate() {
        hprintln!(
            "BENCH-PROFILE-TICK {} {} {} {} {} {}",
            stage,
            phase,
            N::NAME,
            worst[i].0,
            worst[i].1,
            seen[i]
        );
    }
}
