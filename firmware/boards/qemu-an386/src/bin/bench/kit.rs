//! The bench's measuring kit: the sweep encoder and the output sink (the stand-ins for a
//! timer's counter register and a DAC register), the batch measurement of a stage's mean and
//! the single tick's window (SysTick read around them), the measured functions (each stage its
//! own function, as the servo interrupt calls `Servo::tick`), and the stream command and fault
//! check every stage uses. Units: SysTick counts (40 virtual ns each) and virtual ns.

use core::hint::black_box;
use cortex_m::peripheral::SYST;
use cortex_m_semihosting::hprintln;
use stiffwall_firmware::{Encoder, ForceOutput, HostPort, Numeric, Servo, ServoCmd};

pub const BATCHES: u32 = 40;
pub const PER_BATCH: u32 = 200;
/// Virtual ns per SysTick count (a 25 MHz SysTick clock); one instruction is 2^S ns under
/// `-icount shift=S`.
pub const NS_PER_COUNT: u64 = 40;

/// Counts of a triangle sweep of ±256·`step` counts around the wall, `step` counts per tick.
pub const SWEEP_LEN: usize = 1024;

pub fn sweep_table(step: i32) -> [u32; SWEEP_LEN] {
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
pub struct Sweep<'t> {
    pub table: &'t [u32; SWEEP_LEN],
    pub i: usize,
}
impl Encoder for Sweep<'_> {
    fn count(&mut self) -> u32 {
        self.i = (self.i + 1) & (SWEEP_LEN - 1);
        self.table[self.i]
    }
}

pub struct Sink;
impl ForceOutput for Sink {
    fn write(&mut self, code: i32) {
        black_box(code);
    }
}

pub fn elapsed(start: u32, end: u32) -> u64 {
    u64::from(start.wrapping_sub(end) & 0x00ff_ffff)
}

/// SysTick counts for `BATCHES × PER_BATCH` calls of `f`, with `between` run unmeasured.
pub fn measure(mut f: impl FnMut(u32), mut between: impl FnMut()) -> u64 {
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

pub fn report(stage: &str, numeric: &str, counts: u64, baseline: u64) {
    let ticks = u64::from(BATCHES * PER_BATCH);
    let ns_x100 = counts.saturating_sub(baseline) * NS_PER_COUNT * 100 / ticks;
    hprintln!("BENCH {} {} {}", stage, numeric, ns_x100);
}

// Each stage is measured as its own function, called once per tick, as the board's servo
// interrupt calls `Servo::tick`: the stage's code is then compiled on its own and its count does
// not move with the register allocation of this bench's loop (inlined into `main`, the spring
// stage measured anywhere from 35 to 42 instructions as unrelated code changed). The call, the
// return and the stand-ins are measured the same way (`io`) and subtracted.

#[inline(never)]
pub fn io(enc: &mut Sweep<'_>, out: &mut Sink) -> i32 {
    let c = enc.count() as i32;
    out.write(c);
    c
}

#[inline(never)]
pub fn spring<N: Numeric>(servo: &mut Servo<'_, N>, enc: &mut Sweep<'_>, out: &mut Sink) -> i32 {
    servo.tick_spring(enc, out)
}

#[inline(never)]
pub fn spring_delay<N: Numeric>(
    servo: &mut Servo<'_, N>,
    enc: &mut Sweep<'_>,
    out: &mut Sink,
) -> i32 {
    servo.tick_spring_delay(enc, out)
}

#[inline(never)]
pub fn supervised<N: Numeric>(
    servo: &mut Servo<'_, N>,
    now: u32,
    enc: &mut Sweep<'_>,
    out: &mut Sink,
) -> i32 {
    servo.tick_supervised(now, enc, out)
}

#[inline(never)]
pub fn full<N: Numeric>(
    servo: &mut Servo<'_, N>,
    now: u32,
    enc: &mut Sweep<'_>,
    out: &mut Sink,
) -> i32 {
    servo.tick(now, enc, out)
}

/// Queues telemetry at every tick (the full tick's push).
pub fn start_stream<N: Numeric>(host: &mut HostPort<'_, N>) {
    if host
        .commands
        .enqueue(ServoCmd::Stream { decimation: 1 })
        .is_err()
    {
        hprintln!("BENCH-ERROR command queue full");
    }
}

/// A measured stage must latch no fault (the sweep stays within every limit); `what` ends the
/// error line.
pub fn check_no_faults<N: Numeric>(servo: &Servo<'_, N>, what: &str) {
    if servo.faults() != 0 {
        hprintln!(
            "BENCH-ERROR faults {:#x} latched during {}{}",
            servo.faults(),
            N::NAME,
            what
        );
    }
}

/// Virtual ns of one call of `f`, the SysTick counter read around it.
#[inline(always)]
pub fn window(f: impl FnOnce()) -> u64 {
    let start = SYST::get_current();
    f();
    elapsed(start, SYST::get_current()) * NS_PER_COUNT
}
