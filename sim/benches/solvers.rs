//! Criterion benches of the solvers (statistics for the numbers in docs/BENCHMARKS-sim.md).
//!
//! Units: one iteration = a fixed number of simulated sampling periods (see each bench name).
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;
use std::time::Duration;
use stiffwall_sim::exact::{ExactSim, Full, History, NoDelay};
use stiffwall_sim::reference::{Method, RefModel, RefSim};
use stiffwall_sim::{Effects, Motion, Params};

fn exact(c: &mut Criterion) {
    let init = Motion { x: 0.0, v: 5.0 };
    let mut g = c.benchmark_group("exact");
    g.throughput(Throughput::Elements(50_000));
    g.bench_function("base scene, all effects, 5e4 periods", |b| {
        b.iter(|| {
            let mut s = Full::new(Params::BASE, init, History::HoldInitial).unwrap();
            for _ in 0..50_000 {
                s.step_period();
            }
            black_box(s.state())
        });
    });
    g.bench_function("base scene, no delay line, 5e4 periods", |b| {
        b.iter(|| {
            let mut s = NoDelay::new(Params::BASE, init, History::HoldInitial).unwrap();
            for _ in 0..50_000 {
                s.step_period();
            }
            black_box(s.state())
        });
    });
    let p = Params {
        tau_d: 1.25,
        ..Params::BASE
    };
    g.bench_function("tau_D 1.25, 5e4 periods", |b| {
        b.iter(|| {
            let mut s = Full::new(p, init, History::HoldInitial).unwrap();
            for _ in 0..50_000 {
                s.step_period();
            }
            black_box(s.state())
        });
    });
    g.finish();
}

fn reference(c: &mut Criterion) {
    let init = Motion { x: 0.0, v: 5.0 };
    let model = RefModel::paper(Params::BASE, Effects::ALL);
    let mut g = c.benchmark_group("reference");
    g.throughput(Throughput::Elements(300));
    for (name, m) in [
        (
            "RK4 16 steps",
            Method::Rk4 {
                steps_per_period: 16,
            },
        ),
        (
            "DP45 tol 1e-8",
            Method::Dopri {
                rtol: 1e-8,
                atol: 1e-8,
            },
        ),
    ] {
        g.bench_function(format!("{name}, 300 periods"), |b| {
            b.iter(|| {
                let mut s = RefSim::new(model, m, init).unwrap();
                for _ in 0..300 {
                    s.step_period();
                }
                black_box(s.state())
            });
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    targets = exact, reference
}
criterion_main!(benches);
