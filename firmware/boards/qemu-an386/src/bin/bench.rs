//! Instruction counts of the servo tick, stage by stage and per numeric back-end.
//!
//! Run under `qemu-system-arm ... -icount shift=0` (`cargo xtask bench-firmware`): the virtual
//! clock then advances 1 ns per instruction and SysTick (25 MHz core clock) one count per 40
//! instructions, deterministically. Each stage runs `BATCHES × PER_BATCH` ticks; the SysTick
//! counter is read around every batch, and the telemetry queue is drained between batches
//! (outside the measured windows). Subtracted from every stage: the loop itself and the bench's
//! encoder and output stand-ins (a table walk and a store, measured alone in the same loop); on
//! hardware those are one counter-register load and one DAC/PWM-register store. Output lines, on
//! the semihosting console: `BENCH <stage> <numeric> <instructions per tick ×100>`.
#![no_std]
#![no_main]

use core::hint::black_box;
use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use stiffwall_firmware::{
    Channels, Encoder, ForceOutput, Fx32, Fx64, Numeric, Servo, ServoCmd, F32,
};
use stiffwall_proto::{DamperLaw, ServoConfig};

const BATCHES: u32 = 40;
const PER_BATCH: u32 = 200;
/// Instructions per SysTick count with `-icount shift=0` and a 25 MHz SysTick clock.
const INSTR_PER_COUNT: u64 = 40;

/// Counts of a triangle sweep of ±256·`step` counts around the wall, `step` counts per tick.
const SWEEP_LEN: usize = 1024;

fn sweep_table(step: i32) -> [u32; SWEEP_LEN] {
    let mut t = [0u32; SWEEP_LEN];
    for (i, v) in t.iter_mut().enumerate() {
        let p = i as i32;
        let tri = if p < 512 { p - 256 } else { 768 - p };
        *v = (tri * step) as u32 & 0xffff;
    }
    t
}

/// An encoder replaying the sweep: one load per read, like a timer's counter register, so the
/// measured instructions are the servo's and not a synthetic encoder's.
struct Sweep<'t> {
    table: &'t [u32; SWEEP_LEN],
    i: usize,
}
impl Encoder for Sweep<'_> {
    fn count(&mut self) -> u32 {
        self.i = (self.i + 1) & (SWEEP_LEN - 1);
        self.table[self.i]
    }
}

struct Sink;
impl ForceOutput for Sink {
    fn write(&mut self, code: i32) {
        black_box(code);
    }
}

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

fn elapsed(start: u32, end: u32) -> u64 {
    u64::from(start.wrapping_sub(end) & 0x00ff_ffff)
}

/// SysTick counts for `BATCHES × PER_BATCH` calls of `f`, with `between` run unmeasured.
fn measure(mut f: impl FnMut(u32), mut between: impl FnMut()) -> u64 {
    let mut total = 0;
    let mut now = 0u32;
    for _ in 0..BATCHES {
        let start = SYST::get_current();
        for _ in 0..PER_BATCH {
            f(black_box(now));
            now = now.wrapping_add(1);
        }
        total += elapsed(start, SYST::get_current());
        between();
    }
    total
}

fn report(stage: &str, numeric: &str, counts: u64, baseline: u64) {
    let ticks = u64::from(BATCHES * PER_BATCH);
    let instr_x100 = counts.saturating_sub(baseline) * INSTR_PER_COUNT * 100 / ticks;
    hprintln!("BENCH {} {} {}", stage, numeric, instr_x100);
}

// Each stage is measured as its own function, called once per tick, as the board's servo
// interrupt calls `Servo::tick`: the stage's code is then compiled on its own and its count does
// not move with the register allocation of this bench's loop (inlined into `main`, the spring
// stage measured anywhere from 35 to 42 instructions as unrelated code changed). The call, the
// return and the stand-ins are measured the same way (`io`) and subtracted.

#[inline(never)]
fn io(enc: &mut Sweep<'_>, out: &mut Sink) -> i32 {
    let c = enc.count() as i32;
    out.write(c);
    c
}

#[inline(never)]
fn spring<N: Numeric>(servo: &mut Servo<'_, N>, enc: &mut Sweep<'_>, out: &mut Sink) -> i32 {
    servo.tick_spring(enc, out)
}

#[inline(never)]
fn spring_delay<N: Numeric>(servo: &mut Servo<'_, N>, enc: &mut Sweep<'_>, out: &mut Sink) -> i32 {
    servo.tick_spring_delay(enc, out)
}

#[inline(never)]
fn supervised<N: Numeric>(
    servo: &mut Servo<'_, N>,
    now: u32,
    enc: &mut Sweep<'_>,
    out: &mut Sink,
) -> i32 {
    servo.tick_supervised(now, enc, out)
}

#[inline(never)]
fn full<N: Numeric>(
    servo: &mut Servo<'_, N>,
    now: u32,
    enc: &mut Sweep<'_>,
    out: &mut Sink,
) -> i32 {
    servo.tick(now, enc, out)
}

fn stages<N: Numeric>(baseline: u64) {
    let board = stiffwall_board_qemu_an386::plant::board_info();
    let cfg = config();
    let mut channels = Channels::new();
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
    if host
        .commands
        .enqueue(ServoCmd::Stream { decimation: 1 })
        .is_err()
    {
        hprintln!("BENCH-ERROR command queue full");
    }
    let c = measure(
        |t| {
            black_box(full(&mut servo, t, &mut enc, &mut out));
        },
        || while host.telemetry.dequeue().is_some() {},
    );
    report("full(+telemetry)", N::NAME, c, baseline);
    if servo.faults() != 0 {
        hprintln!(
            "BENCH-ERROR faults {:#x} latched during {}",
            servo.faults(),
            N::NAME
        );
    }
    // The same full tick with the virtual damper on (B > 0, the default law: a dead band of
    // one count): the sweep moves two counts per tick, beyond the dead band, so the two-sided
    // wall computes the damper term on every tick.
    let damped = ServoConfig {
        damping: DAMPING_N_S_PER_M,
        ..cfg
    };
    if damped.damper != (DamperLaw::DeadBand { counts: 1 }) {
        hprintln!("BENCH-ERROR the damped stage is not the dead band of one count");
    }
    let table2 = black_box(sweep_table(2));
    let mut enc = Sweep {
        table: &table2,
        i: 0,
    };
    let mut channels = Channels::new();
    let (servo_port, mut host) = channels.split();
    let mut servo: Servo<'_, N> = Servo::new(board, &damped, servo_port);
    if host
        .commands
        .enqueue(ServoCmd::Stream { decimation: 1 })
        .is_err()
    {
        hprintln!("BENCH-ERROR command queue full");
    }
    let c = measure(
        |t| {
            black_box(full(&mut servo, t, &mut enc, &mut out));
        },
        || while host.telemetry.dequeue().is_some() {},
    );
    report("full+damper", N::NAME, c, baseline);
    if servo.faults() != 0 {
        hprintln!(
            "BENCH-ERROR faults {:#x} latched during {} with the damper",
            servo.faults(),
            N::NAME
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
        baseline * INSTR_PER_COUNT * 100 / u64::from(BATCHES * PER_BATCH)
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
