//! Instruction counts of the servo tick, stage by stage and per numeric back-end.
//!
//! Run under `qemu-system-arm ... -icount shift=S` (`cargo xtask bench-firmware`, S = 7): the
//! virtual clock then advances 2^S ns per instruction and SysTick (25 MHz core clock) one count
//! per 40 ns, deterministically; with S = 7 one instruction is 3.2 counts, so a single tick is
//! resolved to a third of an instruction. Each stage runs `BATCHES × PER_BATCH` ticks; the
//! SysTick counter is read around every batch, and the telemetry queue is drained between
//! batches (outside the measured windows). Subtracted from every stage: the loop itself and the
//! bench's encoder and output stand-ins (a table walk and a store, measured alone in the same
//! loop); on hardware those are one counter-register load and one DAC/PWM-register store. Output
//! lines, on the semihosting console: `BENCH <stage> <numeric> <virtual ns per tick ×100>`
//! (instructions × 100 · 2^S).
//!
//! Then the worst tick ([`worst`]): one run of the full tick with the damper, each tick timed
//! alone, through a config change, a prepared release test and a prepared impact test
//! (`HostMsg::PrepareTest`: the test's own config applied on its first tick, the active one
//! parked back on its last), a latched fault (an encoder jump) in safe-mode damping and the
//! clearing of it: `BENCH-TICK <phase> <numeric> <virtual ns of the phase's longest tick>
//! <its tick> <ticks in the phase>`, the per-tick stand-ins subtracted.
//!
//! Then the haptic profile (`bench/profile.rs`): the full tick with the damper in profile mode,
//! the profile loaded as `HostMsg::SetProfile` loads it (validate, compile, the table queued,
//! `ServoCmd::Profile`), the mean as above for one element of each kind and for 1, 4 and 16
//! detent trains (`BENCH profile-… <numeric> …`; 16 trains is the worst case a user can load),
//! and one run per detent stage with every tick timed alone: `BENCH-PROFILE-TICK <stage>
//! <phase> <numeric> <ns> <tick> <ticks>` (the tick that takes the profile, a config change in
//! profile mode, the render ticks) and `BENCH-COMPILE <stage> <numeric> <ns>` (the main loop's
//! validate + compile + queue). The measuring kit (sweep, sink, batches, windows, the measured
//! functions) is `bench/kit.rs`.
#![no_std]
#![no_main]

use core::hint::black_box;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use stiffwall_firmware::channels::DecidedEnd;
use stiffwall_firmware::{
    BoardInfo, Channels, Encoder, ForceOutput, Fx32, Fx64, Numeric, Servo, ServoCmd, ServoEvent,
    F32,
};
use stiffwall_proto::{DamperLaw, SafeMode, ServoConfig};

// The bench's modules sit in `bench/` beside this crate root (one folder per binary).
#[path = "bench/kit.rs"]
mod kit;
#[path = "bench/profile.rs"]
mod profile;

use kit::{
    check_no_faults, full, io, measure, report, spring, spring_delay, start_stream, supervised,
    sweep_table, window, Sink, Sweep, BATCHES, NS_PER_COUNT, PER_BATCH, SWEEP_LEN,
};

/// Virtual damping of the damper-on stage, N·s/m (nonzero gain in every back-end).
const DAMPING_N_S_PER_M: f32 = 0.01;

fn config() -> ServoConfig {
    ServoConfig {
        stiffness: 2.0,
        damping: 0.0,
        extra_delay_ticks: 1,
        max_velocity: 1.0e4,
        energy_monitor: true,
        // Generous limits: the sweep must not trip the supervisor during the measurement.
        energy_limit: 1.0e5,
        encoder_jump_counts: 100_000,
        force_limit: 0.09,
        heartbeat_timeout_ms: 0,
        ..ServoConfig::default()
    }
}

fn stages<N: Numeric>(baseline: u64) {
    let board = stiffwall_board_qemu_an386::plant::board_info();
    let cfg = config();
    let mut channels = Channels::<N>::for_numeric();
    let (servo_port, mut host) = channels.split();
    let mut servo: Servo<'_, N> = Servo::new(board, &cfg, servo_port);
    let table = black_box(sweep_table(1));
    let (mut enc, mut out) = (
        Sweep {
            table: &table,
            i: 0,
        },
        Sink,
    );
    // The loop plus the encoder and output stand-ins alone: subtracted from every stage.
    let io = measure(
        |_| {
            black_box(io(&mut enc, &mut out));
        },
        || {},
    );
    if N::NAME == "I32F32" {
        report("io-stand-ins", "all", io, baseline);
    }
    let baseline = io;
    let c = measure(
        |_| {
            black_box(spring(&mut servo, &mut enc, &mut out));
        },
        || {},
    );
    report("spring", N::NAME, c, baseline);
    let c = measure(
        |_| {
            black_box(spring_delay(&mut servo, &mut enc, &mut out));
        },
        || {},
    );
    report("spring+delay", N::NAME, c, baseline);
    let c = measure(
        |t| {
            black_box(supervised(&mut servo, t, &mut enc, &mut out));
        },
        || {},
    );
    report("spring+delay+supervisor", N::NAME, c, baseline);
    start_stream(&mut host);
    let c = measure(
        |t| {
            black_box(full(&mut servo, t, &mut enc, &mut out));
        },
        || while host.telemetry.dequeue().is_some() {},
    );
    report("full(+telemetry)", N::NAME, c, baseline);
    check_no_faults(&servo, "");
    let damped = damped_config(&cfg);
    let table2 = black_box(sweep_table(2));
    let mut enc = Sweep {
        table: &table2,
        i: 0,
    };
    let mut channels = Channels::<N>::for_numeric();
    let (servo_port, mut host) = channels.split();
    let mut servo: Servo<'_, N> = Servo::new(board, &damped, servo_port);
    start_stream(&mut host);
    let c = measure(
        |t| {
            black_box(full(&mut servo, t, &mut enc, &mut out));
        },
        || while host.telemetry.dequeue().is_some() {},
    );
    report("full+damper", N::NAME, c, baseline);
    check_no_faults(&servo, " with the damper");
    worst::<N>(board, &damped, &table2);
    profile::stages::<N>(board, &damped, &table2, baseline);
}

/// The same config with the virtual damper on (B > 0, the default law: a dead band of one
/// count): the sweep moves two counts per tick, beyond the dead band, so the two-sided wall
/// computes the damper term on every tick.
fn damped_config(cfg: &ServoConfig) -> ServoConfig {
    let damped = ServoConfig {
        damping: DAMPING_N_S_PER_M,
        ..*cfg
    };
    if damped.damper != (DamperLaw::DeadBand { counts: 1 }) {
        hprintln!("BENCH-ERROR the damped stage is not the dead band of one count");
    }
    damped
}

/// The worst tick's encoder: the sweep shifted by `offset` counts (a jump), or held still at
/// `still` (a device at rest during a test's hold).
struct Script<'t> {
    table: &'t [u32; SWEEP_LEN],
    i: usize,
    offset: u32,
    still: Option<u32>,
}
impl Encoder for Script<'_> {
    fn count(&mut self) -> u32 {
        if let Some(c) = self.still {
            return c;
        }
        self.i = (self.i + 1) & (SWEEP_LEN - 1);
        self.table[self.i].wrapping_add(self.offset) & 0xffff
    }
}

#[inline(never)]
fn io_script(enc: &mut Script<'_>, out: &mut Sink) -> i32 {
    let c = enc.count() as i32;
    out.write(c);
    c
}

#[inline(never)]
fn full_script<N: Numeric>(
    servo: &mut Servo<'_, N>,
    now: u32,
    enc: &mut Script<'_>,
    out: &mut Sink,
) -> i32 {
    servo.tick(now, enc, out)
}

/// The phases of the worst-tick run, in the order of [`WORST_PHASES`].
const FIRST: usize = 0;
const WALL: usize = 1;
const CONFIG: usize = 2;
const PREPARED_START: usize = 3;
const EXPERIMENT: usize = 4;
const TEST_END: usize = 5;
const FAULT: usize = 6;
const FAULTED: usize = 7;
const CLEAR: usize = 8;
/// Phase names as printed (`BENCH-TICK <phase> …`).
const WORST_PHASES: [&str; 9] = [
    "first-reading",
    "wall",
    "config-change",
    "prepared-test-start",
    "test-running",
    "test-end",
    "fault-latch",
    "faulted",
    "clear-faults",
];
/// Ticks of the worst-tick run.
const WORST_TICKS: u32 = 16_000;
/// Ticks at which the run's events are queued (config change, prepared release, prepared
/// impact, encoder jump, clear faults).
const AT_CONFIG: u32 = 1000;
const AT_RELEASE: u32 = 2000;
const AT_IMPACT: u32 = 4000;
const AT_JUMP: u32 = 12_000;
const AT_CLEAR: u32 = 13_000;

/// The worst tick of the full tick with the damper over one run that changes the config,
/// runs a prepared release and a prepared impact test (each with its own config and a decided
/// end), latches a fault and clears it; every tick timed alone (`window`), the per-tick
/// stand-ins (the call, `io_script`) subtracted. Prints one `BENCH-TICK` line per phase.
/// (Its configs, commands and report are functions of their own since the run was written out
/// in one: the timed window around the call then holds 5 more of this bench's instructions
/// for I32F32, 3 to 5 for the others; the servo's code is the same.)
fn worst<N: Numeric>(board: BoardInfo, damped: &ServoConfig, table: &[u32; SWEEP_LEN]) {
    let (cfg, changed, end) = worst_configs(damped);
    let mut channels = Channels::<N>::for_numeric();
    let (servo_port, mut host) = channels.split();
    let mut servo: Servo<'_, N> = Servo::new(board, &cfg, servo_port);
    let mut enc = Script {
        table,
        i: 0,
        offset: 0,
        still: None,
    };
    let mut out = Sink;
    // The per-tick window around the stand-ins alone: the least of many (its true cost is fixed;
    // the least reading subtracts least, so a phase's figure errs high, never low).
    let mut io = u64::MAX;
    for _ in 0..256 {
        io = io.min(window(|| {
            black_box(io_script(&mut enc, &mut out));
        }));
    }
    start_stream(&mut host);
    let mut worst = [(0u64, 0u32); WORST_PHASES.len()];
    let mut seen = [0u32; WORST_PHASES.len()];
    let mut tests_done = 0;
    for t in 0..WORST_TICKS {
        // Unmeasured: the main loop's side (queue a command, move the device).
        let cmd = worst_command(t, &mut enc, changed, end);
        if t == AT_JUMP {
            enc.offset = 5000;
        }
        let queued = cmd.is_some();
        if let Some(c) = cmd {
            if host.commands.enqueue(c).is_err() {
                hprintln!("BENCH-ERROR command queue full");
            }
        }
        let (faults_before, running_before) = (servo.faults(), servo.experiment_running());
        let ns = window(|| {
            black_box(full_script(&mut servo, t, &mut enc, &mut out));
        });
        while host.telemetry.dequeue().is_some() {}
        let mut ended = false;
        while let Some(ServoEvent::ExperimentDone { .. }) = host.events.dequeue() {
            ended = true;
            tests_done += 1;
            // Back to the sweep once a test is over.
            enc.still = None;
        }
        let phase = match (queued, t) {
            (_, 0) => FIRST,
            (true, AT_CONFIG) => CONFIG,
            (true, AT_RELEASE | AT_IMPACT) => PREPARED_START,
            (true, AT_CLEAR) => CLEAR,
            _ if ended => TEST_END,
            _ if faults_before == 0 && servo.faults() != 0 => FAULT,
            _ if faults_before != 0 => FAULTED,
            _ if running_before => EXPERIMENT,
            _ => WALL,
        };
        seen[phase] += 1;
        let ns = ns.saturating_sub(io);
        if ns > worst[phase].0 {
            worst[phase] = (ns, t);
        }
    }
    report_worst::<N>(&worst, &seen, tests_done, servo.faults());
}

/// The worst-tick run's configs, from the damped sweep's: the active one (the supervisor on
/// every path: a jump limit the sweep stays under, safe-mode damping after a fault, the
/// heartbeat watchdog armed: it runs during tests; the run is shorter than it), the changed
/// one (K × 1.5, B × 0.5), and the prepared tests' decided end (their own config, K × 0.8).
fn worst_configs(damped: &ServoConfig) -> (ServoConfig, ServoConfig, DecidedEnd) {
    let cfg = ServoConfig {
        encoder_jump_counts: 1000,
        safe_mode: SafeMode::Damping,
        safe_damping: DAMPING_N_S_PER_M,
        heartbeat_timeout_ms: 60_000,
        ..*damped
    };
    let changed = ServoConfig {
        stiffness: 1.5 * cfg.stiffness,
        damping: 0.5 * cfg.damping,
        ..cfg
    };
    let test_cfg = ServoConfig {
        stiffness: 0.8 * cfg.stiffness,
        ..changed
    };
    let end = DecidedEnd {
        min_run: 100,
        one_count: true,
        decay_base: 200,
        run: test_cfg,
        park: changed,
    };
    (cfg, changed, end)
}

/// The command the main loop queues at tick `t` of the worst-tick run (holding the encoder
/// still for a test's hold), if any.
fn worst_command(
    t: u32,
    enc: &mut Script<'_>,
    changed: ServoConfig,
    end: DecidedEnd,
) -> Option<ServoCmd> {
    match t {
        AT_CONFIG => Some(ServoCmd::Config(changed)),
        AT_RELEASE => {
            // A device at rest 20 counts into the wall: the hold settles, the release runs
            // until the decided end (still for `min_run` ticks).
            enc.still = Some(20);
            Some(ServoCmd::Release {
                deflection: 20,
                ticks: 2000,
                end: Some(end),
            })
        }
        AT_IMPACT => {
            // At rest 30 counts out: the hold settles, the launch moves its target toward
            // the wall; the device stays, so the launch's time limit releases it.
            enc.still = Some((-30i32) as u32 & 0xffff);
            Some(ServoCmd::Impact {
                start: -30,
                velocity_milli: 2000,
                ticks: 2000,
                end: Some(end),
            })
        }
        AT_CLEAR => Some(ServoCmd::ClearFaults),
        _ => None,
    }
}

/// Checks the worst-tick run (two tests ended, no fault left at the end (`faults`), every
/// phase seen) and prints one `BENCH-TICK` line per phase: its longest tick (virtual ns, the
/// tick) and its ticks.
fn report_worst<N: Numeric>(
    worst: &[(u64, u32); WORST_PHASES.len()],
    seen: &[u32; WORST_PHASES.len()],
    tests_done: u32,
    faults: u32,
) {
    if tests_done != 2 || faults != 0 || seen.contains(&0) {
        hprintln!(
            "BENCH-ERROR worst-tick run of {}: {} tests ended (2 expected), faults {:#x} at the end, ticks per phase {:?}",
            N::NAME,
            tests_done,
            faults,
            seen
        );
    }
    // `BENCH-TICK <phase> <numeric> <ns of its longest tick> <that tick> <ticks in the phase>`.
    for (i, name) in WORST_PHASES.iter().enumerate() {
        hprintln!(
            "BENCH-TICK {} {} {} {} {}",
            name,
            N::NAME,
            worst[i].0,
            worst[i].1,
            seen[i]
        );
    }
}

#[entry]
fn main() -> ! {
    let mut cp = match cortex_m::Peripherals::take() {
        Some(p) => p,
        None => cortex_m::asm::udf(),
    };
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(0x00ff_ffff);
    cp.SYST.clear_current();
    cp.SYST.enable_counter();
    let baseline = measure(
        |t| {
            black_box(t);
        },
        || {},
    );
    hprintln!(
        "BENCH baseline loop {}",
        baseline * NS_PER_COUNT * 100 / u64::from(BATCHES * PER_BATCH)
    );
    stages::<Fx64>(baseline);
    stages::<Fx32>(baseline);
    stages::<F32>(baseline);
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    hprintln!("BENCH-ERROR panic");
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}
