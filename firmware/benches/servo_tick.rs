//! Host micro-benchmark of the servo tick, per stage and numeric back-end.
//!
//! The encoder replays a 1024-entry sine of ±50 counts (so branches are not constant); the
//! output stores the code. Host (x86-64) timings only: the target's instruction counts come
//! from `cargo xtask bench-firmware` under QEMU.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use stiffwall_firmware::{
    BoardInfo, Channels, Encoder, ForceOutput, Fx32, Fx64, Numeric, Servo, F32,
};
use stiffwall_proto::ServoConfig;

struct TableEnc {
    t: Vec<u32>,
    i: usize,
}

impl Encoder for TableEnc {
    #[inline]
    fn count(&mut self) -> u32 {
        self.i = (self.i + 1) & 1023;
        self.t[self.i]
    }
}

struct Sink(i32);

impl ForceOutput for Sink {
    #[inline]
    fn write(&mut self, code: i32) {
        self.0 = black_box(code);
    }
}

fn enc() -> TableEnc {
    TableEnc {
        t: (0..1024)
            .map(|i| (50.0 * (i as f64 * 0.0613).sin()).round() as i32 as u32)
            .collect(),
        i: 0,
    }
}

fn cfg() -> ServoConfig {
    ServoConfig {
        stiffness: 2000.0,
        damping: 0.01,
        extra_delay_ticks: 2,
        force_limit: 0.3,
        max_velocity: 10.0,
        energy_monitor: true,
        energy_limit: 1000.0,
        heartbeat_timeout_ms: 0,
        encoder_jump_counts: 100_000,
        ..ServoConfig::default()
    }
}

fn stages<N: Numeric>(c: &mut Criterion) {
    let board = BoardInfo::default();
    let name = N::NAME;
    let mut g = c.benchmark_group(format!("servo_tick/{name}"));
    {
        let mut ch = Channels::<N>::for_numeric();
        let (sp, _hp) = ch.split();
        let mut s: Servo<'_, N> = Servo::new(board, &cfg(), sp);
        let (mut e, mut o) = (enc(), Sink(0));
        g.bench_function("spring", |b| b.iter(|| s.tick_spring(&mut e, &mut o)));
        g.bench_function("spring+delay", |b| {
            b.iter(|| s.tick_spring_delay(&mut e, &mut o))
        });
        let mut now = 0u32;
        g.bench_function("+supervisor", |b| {
            b.iter(|| {
                now = now.wrapping_add(1);
                s.tick_supervised(now, &mut e, &mut o)
            })
        });
        // The measured path must be the normal one, not safe mode.
        assert_eq!(s.faults(), 0, "supervisor tripped during the benchmark");
    }
    {
        // Full tick with telemetry every tick; the consumer drains so the push succeeds.
        let mut ch = Channels::<N>::for_numeric();
        let (sp, mut hp) = ch.split();
        let mut s: Servo<'_, N> = Servo::new(board, &cfg(), sp);
        s.command(0, stiffwall_firmware::ServoCmd::Stream { decimation: 1 });
        let (mut e, mut o) = (enc(), Sink(0));
        let mut now = 0u32;
        g.bench_function("full+telemetry", |b| {
            b.iter(|| {
                now = now.wrapping_add(1);
                let c = s.tick(now, &mut e, &mut o);
                black_box(hp.telemetry.dequeue());
                c
            })
        });
        assert_eq!(s.faults(), 0, "supervisor tripped during the benchmark");
    }
    g.finish();
}

fn benches(c: &mut Criterion) {
    stages::<Fx64>(c);
    stages::<Fx32>(c);
    stages::<F32>(c);
}

criterion_group!(servo, benches);
criterion_main!(servo);
