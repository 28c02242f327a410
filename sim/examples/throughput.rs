//! Quick throughput check of the exact solver on the paper's base scene (restarted every
//! 5×10⁴ periods, as in the maps, so the growing trajectory stays in range).
use stiffwall_sim::exact::{ExactSim, Full, History, NoDelay};
use stiffwall_sim::{Motion, Params};

fn run<S: ExactSim>(mk: impl Fn() -> S, label: &str) {
    let runs = 2000u64;
    let t = std::time::Instant::now();
    let mut acc = 0.0;
    for _ in 0..runs {
        let mut s = mk();
        for _ in 0..50_000 {
            s.step_period();
        }
        acc += s.state().x;
    }
    let dt = t.elapsed().as_secs_f64();
    println!(
        "{label}: {:.1} M periods/s ({acc:e})",
        (runs * 50_000) as f64 / dt / 1e6
    );
}

fn main() {
    let init = Motion { x: 0.0, v: 5.0 };
    run(
        || NoDelay::new(Params::BASE, init, History::HoldInitial).unwrap(),
        "no delay",
    );
    run(
        || Full::new(Params::BASE, init, History::HoldInitial).unwrap(),
        "delay line, tau_d 0",
    );
    let p = Params {
        tau_d: 1.25,
        ..Params::BASE
    };
    run(
        || Full::new(p, init, History::HoldInitial).unwrap(),
        "tau_d 1.25",
    );
}
