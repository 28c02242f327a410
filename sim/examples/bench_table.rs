//! What accuracy costs in time: the measurement program behind `cargo xtask bench`.
//!
//! Writes a Markdown report (default `docs/BENCHMARKS-sim.md`) and the Pareto plot
//! `docs/figures/pareto-sim.png`:
//! 1. solver × step size / tolerance → wall time per simulated period, error of the state at
//!    sample instants against the exact solver, energy-balance residual (26);
//! 2. exact-solver time per period for each effect set (all, each removed, none) and for each
//!    disabled effect against the same effect enabled with a neutral parameter
//!    (`effect_costs`), and the cost of the effects only the reference integrator models
//!    (`reference_effects`);
//! 3. the paper's base scene throughput on one core and the Fig. 6 set on the paper's grid on
//!    all cores through `sim::map::run_with` (the code path of `hostctl map`), with and without
//!    cycle detection, ns per period by class (decaying, growing, persistent);
//! 4. the issue-10 plant effects (`rich_rows`): cost of each, accuracy against references.
//!
//! Units: dimensionless scenes (Table I); times in ns per simulated period.
//! Usage: `cargo run --release -p stiffwall-sim --example bench_table -- [--out FILE] [--quick]`.

#[path = "bench_table/effect_costs.rs"]
mod effect_costs;
#[path = "bench_table/reference_effects.rs"]
mod reference_effects;
#[path = "bench_table/rich_rows.rs"]
mod rich_rows;

use plotters::prelude::*;
use std::fmt::Write as _;
use std::time::Instant;
use stiffwall_sim::classify::Class;
use stiffwall_sim::exact::{dispatch, ExactSim, History, Visitor};
use stiffwall_sim::map::{run_with as map_run_with, Axis, MapSpec, RunOptions};
use stiffwall_sim::reference::{Method, RefModel, RefSim};
use stiffwall_sim::{Effects, Motion, Params};

struct Scene {
    name: &'static str,
    p: Params,
    init: Motion,
}

const HORIZON: u64 = 300;

fn scenes() -> Vec<Scene> {
    vec![
        Scene {
            name: "base (mu 100, beta 0.1, sigma 1, xidot0 5)",
            p: Params::BASE,
            init: Motion { x: 0.0, v: 5.0 },
        },
        Scene {
            name: "delayed (beta 2, sigma 1.5, tau_D 1.25)",
            p: Params {
                mu: 100.0,
                beta: 2.0,
                sigma: 1.5,
                tau_d: 1.25,
            },
            init: Motion { x: 0.0, v: 5.0 },
        },
        Scene {
            name: "light device (mu 0.5, beta 0.6, sigma 0.3, xidot0 2): fast dynamics within a period",
            p: Params {
                mu: 0.5,
                beta: 0.6,
                sigma: 0.3,
                tau_d: 0.0,
            },
            init: Motion { x: 0.0, v: 2.0 },
        },
        Scene {
            name: "limit cycle B (beta 0.8, sigma 0.3)",
            p: Params {
                mu: 100.0,
                beta: 0.8,
                sigma: 0.3,
                tau_d: 0.0,
            },
            init: Motion { x: 0.0, v: 5.0 },
        },
    ]
}

/// Trajectory (states at samples) and max |residual| per period.
struct Traj(u64);
impl Visitor for Traj {
    type Output = (Vec<Motion>, f64);
    fn visit<S: ExactSim>(self, mut s: S) -> (Vec<Motion>, f64) {
        trajectory(&mut s, self.0)
    }
}

fn trajectory<S: ExactSim>(s: &mut S, n: u64) -> (Vec<Motion>, f64) {
    let mut out = Vec::with_capacity(n as usize + 1);
    out.push(s.state());
    let mut res: f64 = 0.0;
    for _ in 0..n {
        s.step_period();
        out.push(s.state());
        res = res.max(s.audit().residual.abs());
    }
    (out, res)
}

/// Repeats `f` (which simulates `periods` periods) until at least `min_s` seconds passed;
/// returns ns per period (best of 3 batches).
fn time_per_period(periods: u64, min_s: f64, mut f: impl FnMut()) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let t = Instant::now();
        let mut reps = 0u64;
        while t.elapsed().as_secs_f64() < min_s / 3.0 || reps == 0 {
            f();
            reps += 1;
        }
        best = best.min(t.elapsed().as_secs_f64() * 1e9 / (reps * periods) as f64);
    }
    best
}

struct Row {
    scene: usize,
    solver: String,
    ns: f64,
    err_x: f64,
    err_v: f64,
    residual: f64,
}

fn exact_traj(sc: &Scene, audit: bool) -> (Vec<Motion>, f64) {
    if audit {
        dispatch::<_, true>(
            sc.p,
            Effects::ALL,
            sc.init,
            History::HoldInitial,
            Traj(HORIZON),
        )
    } else {
        dispatch::<_, false>(
            sc.p,
            Effects::ALL,
            sc.init,
            History::HoldInitial,
            Traj(HORIZON),
        )
    }
    .expect("valid scene")
}

fn accuracy_table(min_s: f64) -> Vec<Row> {
    let mut rows = Vec::new();
    let mut methods: Vec<(String, Method)> = Vec::new();
    for n in [4u32, 16, 64, 256] {
        methods.push((
            format!("RK4, {n} steps/period"),
            Method::Rk4 {
                steps_per_period: n,
            },
        ));
    }
    for tol in [1e-4, 1e-6, 1e-8, 1e-10, 1e-12] {
        methods.push((
            format!("Dormand-Prince 5(4), tol {tol:.0e}"),
            Method::Dopri {
                rtol: tol,
                atol: tol,
            },
        ));
    }
    for (i, sc) in scenes().iter().enumerate() {
        let (reference, res) = exact_traj(sc, true);
        let ns = time_per_period(HORIZON, min_s, || {
            std::hint::black_box(exact_traj(sc, false));
        });
        rows.push(Row {
            scene: i,
            solver: "exact (event-driven)".into(),
            ns,
            err_x: 0.0,
            err_v: 0.0,
            residual: res,
        });
        for (name, m) in &methods {
            let model = RefModel::paper(sc.p, Effects::ALL);
            let run = || {
                let mut s = RefSim::new(model, *m, sc.init).expect("valid");
                trajectory(&mut s, HORIZON)
            };
            let (t, res) = run();
            let (mut ex, mut ev) = (0.0f64, 0.0f64);
            for (a, b) in t.iter().zip(&reference) {
                ex = ex.max((a.x - b.x).abs());
                ev = ev.max((a.v - b.v).abs());
            }
            let ns = time_per_period(HORIZON, min_s, || {
                std::hint::black_box(run());
            });
            rows.push(Row {
                scene: i,
                solver: name.clone(),
                ns,
                err_x: ex,
                err_v: ev,
                residual: res,
            });
        }
    }
    rows
}

/// Steps `periods` periods, restarting from the initial state whenever the trajectory diverges
/// or comes to rest (so every timed period is real work).
struct Throughput {
    periods: u64,
}
impl Visitor for Throughput {
    type Output = u64;
    fn visit<S: ExactSim>(self, mut s: S) -> u64 {
        let fresh = s.clone();
        let mut restarts = 0;
        let mut k = 0;
        while k < self.periods {
            s.step_period();
            k += 1;
            if s.diverged() || s.at_rest() || s.period() >= 50_000 {
                s = fresh.clone();
                restarts += 1;
            }
        }
        restarts
    }
}

fn effect_time(p: Params, e: Effects, init: Motion, periods: u64, min_s: f64) -> f64 {
    time_per_period(periods, min_s, || {
        std::hint::black_box(
            dispatch::<_, false>(p, e, init, History::HoldInitial, Throughput { periods })
                .expect("valid"),
        );
    })
}

/// The paper's Fig. 6 grid, as `hostctl map --mu 100 --tau-d 0 --xidot0 1,5,10,20 --beta
/// 0:1.2:21 --sigma 0:2:34 --periods 50000` runs it.
const FIG6_GRID: &str =
    "beta 0-1.2 x 21, sigma 0-2 x 34, xidot0 in {1, 5, 10, 20}, mu 100, tau_D 0, 5e4 periods";

/// One timed run of the Fig. 6 set through `map::run_with` (the code path of `hostctl map`).
struct Fig6 {
    seconds: f64,
    /// Per class group (decaying, growing, persistent): points, periods, summed thread ns.
    groups: [(usize, u64, f64); 3],
    cycle_points: usize,
    exact_points: usize,
}

fn fig6(opts: RunOptions) -> Fig6 {
    let t = Instant::now();
    let mut groups = [(0usize, 0u64, 0.0f64); 3];
    let mut cycle_points = 0;
    let mut exact_points = 0;
    for v in [1.0, 5.0, 10.0, 20.0] {
        let spec = MapSpec {
            mu: 100.0,
            tau_d: 0.0,
            xidot0: v,
            beta: Axis {
                lo: 0.0,
                hi: 1.2,
                n: 21,
            },
            sigma: Axis {
                lo: 0.0,
                hi: 2.0,
                n: 34,
            },
            periods: 50_000,
            history: History::HoldInitial,
            damping: 0.0,
        };
        let idx: Vec<usize> = (0..spec.len()).collect();
        let o = std::hint::black_box(map_run_with(&spec, &idx, &|| {}, opts));
        cycle_points += o.cycle_points();
        exact_points += o.exact_cycle_points();
        for (p, ns) in o.points.iter().zip(&o.ns_per_period) {
            let g = match p.class {
                c if c.decays() => 0,
                Class::Growing => 1,
                _ => 2,
            };
            groups[g].0 += 1;
            groups[g].1 += p.periods_run;
            groups[g].2 += ns * p.periods_run.max(1) as f64;
        }
    }
    Fig6 {
        seconds: t.elapsed().as_secs_f64(),
        groups,
        cycle_points,
        exact_points,
    }
}

/// Best of two runs.
fn fig6_best(opts: RunOptions) -> Fig6 {
    let (a, b) = (fig6(opts), fig6(opts));
    if a.seconds <= b.seconds {
        a
    } else {
        b
    }
}

fn pareto(rows: &[Row], path: &str) -> Result<(), Box<dyn std::error::Error>> {
    if path.ends_with(".svg") {
        let root = SVGBackend::new(path, (800, 560)).into_drawing_area();
        pareto_draw(&root, rows)?;
        root.present()?;
    } else {
        let root = BitMapBackend::new(path, (800, 560)).into_drawing_area();
        pareto_draw(&root, rows)?;
        root.present()?;
    }
    Ok(())
}

fn pareto_draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    rows: &[Row],
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let floor = 1e-16;
    let mut chart = ChartBuilder::on(root)
        .caption(
            "Error of xi at sample instants vs time per period (300 periods per scene)",
            ("sans-serif", 18),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d((5.0f64..1e6f64).log_scale(), (floor..1e3f64).log_scale())?;
    chart
        .configure_mesh()
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .x_desc("ns per simulated period (circles RK4, triangles DP 5(4), crosses exact)")
        .y_desc("max |xi - xi_exact| [ticks] (exact plotted at 1e-16)")
        .draw()?;
    for (i, c) in [BLUE, RED, GREEN, MAGENTA].into_iter().enumerate() {
        for fam in ["RK4", "Dormand", "exact"] {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.scene == i && r.solver.starts_with(fam))
                .map(|r| (r.ns, r.err_x.max(floor)))
                .collect();
            let style = c.stroke_width(2);
            if fam != "exact" {
                chart.draw_series(LineSeries::new(pts.clone(), style))?;
            }
            let marker = fam;
            let anno = chart.draw_series(pts.iter().map(|&p| match marker {
                "RK4" => Circle::new(p, 4, c.filled()).into_dyn(),
                "Dormand" => TriangleMarker::new(p, 5, c.filled()).into_dyn(),
                _ => Cross::new(p, 7, c.stroke_width(3)).into_dyn(),
            }))?;
            if fam == "exact" {
                anno.label(format!("scene {}", i + 1))
                    .legend(move |(x, y)| Circle::new((x, y), 4, c.filled()));
            }
        }
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()?;
    Ok(())
}

/// Command-line options.
struct Args {
    /// The report (`--out FILE`).
    out: String,
    /// The Pareto plot (`--figure FILE`).
    figure: String,
    /// Shorter timing batches (`--quick`).
    quick: bool,
}

fn parse_args() -> Args {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut out = "docs/BENCHMARKS-sim.md".to_string();
    let mut figure = "docs/figures/pareto-sim.png".to_string();
    let mut quick = false;
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--out" => {
                out = args.get(i + 1).cloned().expect("--out FILE");
                i += 1;
            }
            "--figure" => {
                figure = args.get(i + 1).cloned().expect("--figure FILE");
                i += 1;
            }
            "--quick" => quick = true,
            a => panic!("unknown argument {a}; use --out FILE, --figure FILE, --quick"),
        }
        i += 1;
    }
    Args { out, figure, quick }
}

/// The report's title and the machine it ran on.
fn preamble(md: &mut String) {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let threads = rayon::current_num_threads();
    let load = std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into());
    writeln!(md, "# stiffwall-sim benchmarks\n").unwrap();
    writeln!(
        md,
        "Generated by `cargo xtask bench` (`cargo run --release -p stiffwall-sim --example bench_table`) \
         on {cpu}, {threads} rayon threads, load average at start {load} (a shared machine: \
         other jobs inflate the times). Dimensionless units (Table I); times are wall-clock \
         ns per simulated sampling period, best of 3 batches. Criterion benches with statistics: \
         `cargo bench -p stiffwall-sim --bench solvers`. Not run by `cargo xtask ci` (times move \
         with the machine and its load): the requirements below are checked by running this \
         command.\n"
    )
    .unwrap();
}

/// Section 1: the base scene's throughput and the Fig. 6 set on the paper's grid.
fn headline(md: &mut String, min_s: f64) {
    let threads = rayon::current_num_threads();
    let base_ns = effect_time(
        Params::BASE,
        Effects::ALL,
        Motion { x: 0.0, v: 5.0 },
        1_000_000,
        min_s * 3.0,
    );
    let fast = fig6_best(RunOptions::default());
    let brute = fig6_best(RunOptions {
        cycle_detection: false,
    });
    writeln!(md, "## Headline\n").unwrap();
    writeln!(md, "| measurement | result | requirement |\n|---|---|---|").unwrap();
    writeln!(
        md,
        "| exact solver, base scene (mu 100, beta 0.1, sigma 1, xidot0 5, all effects), one core | {:.1} ns/period = **{:.1} M periods/s** | >= 20 M periods/s |",
        base_ns,
        1e3 / base_ns
    )
    .unwrap();
    writeln!(
        md,
        "| Fig. 6 set on the paper's grid ({FIG6_GRID}; 4 x 714 points, classification included, `sim::map::run_with` as in `hostctl map`), {threads} threads | **{:.2} s** ({} of 2856 points ended by cycle detection, {} of them by exact repetition; brute force {:.2} s) | <= 0.5 s (idle machine) |\n",
        fast.seconds, fast.cycle_points, fast.exact_points, brute.seconds
    )
    .unwrap();
    class_table(md, &fast, &brute);
}

/// Section 1's table of the Fig. 6 set by class, with and without cycle detection.
fn class_table(md: &mut String, fast: &Fig6, brute: &Fig6) {
    writeln!(
        md,
        "Fig. 6 set by class (same runs, best of 2 each): ns of worker-thread wall time per period of \
         `periods_run` (skipped periods of a detected cycle included: the cost per period of the horizon). \
         A point ends by cycle detection when its exact solver state repeats bit for bit (whole cycles are \
         then skipped) or repeats but for the rounding drift of the position (the rest is replayed from one \
         recorded cycle, the solver's own additions); the outcome is identical to brute force \
         (`sim/tests/cycle_detection.rs`).\n"
    )
    .unwrap();
    writeln!(
        md,
        "| points | count | periods | ns/period, cycle detection | ns/period, brute force |\n|---|---:|---:|---:|---:|"
    )
    .unwrap();
    for (g, name) in ["decaying", "growing", "persistent"].iter().enumerate() {
        let (n, periods, ns) = fast.groups[g];
        let (_, bp, bns) = brute.groups[g];
        let per = |ns: f64, p: u64| if p == 0 { 0.0 } else { ns / p as f64 };
        writeln!(
            md,
            "| {name} | {n} | {periods} | {:.1} | {:.1} |",
            per(ns, periods),
            per(bns, bp)
        )
        .unwrap();
    }
    writeln!(md).unwrap();
}

/// Section 2: accuracy against time of every solver on every scene, and the Pareto plot.
fn accuracy(md: &mut String, min_s: f64, figure: &str) {
    let rows = accuracy_table(min_s);
    writeln!(md, "## Accuracy against time\n").unwrap();
    writeln!(
        md,
        "Each scene runs {HORIZON} periods from xi0 = 0 with all effects of the paper. Error: the largest \
         deviation from the exact solver at the sample instants. Residual: the largest per-period \
         residual of the energy balance (26), H_T(h+1) - H_T(h) + E_d - E_g, with E_d and the \
         actuator work integrated as extra states by the reference integrators and in closed form by \
         the exact solver. A position error of order one tick means the trajectory took a different \
         quantization branch (a wrong encoder count at some sample), after which it is a different \
         trajectory.\n"
    )
    .unwrap();
    for (i, sc) in scenes().iter().enumerate() {
        writeln!(md, "### Scene {}: {}\n", i + 1, sc.name).unwrap();
        writeln!(
            md,
            "| solver | ns/period | max abs error xi [ticks] | max abs error xidot | max abs residual (26) |\n|---|---:|---:|---:|---:|"
        )
        .unwrap();
        for r in rows.iter().filter(|r| r.scene == i) {
            writeln!(
                md,
                "| {} | {:.1} | {:.2e} | {:.2e} | {:.2e} |",
                r.solver, r.ns, r.err_x, r.err_v, r.residual
            )
            .unwrap();
        }
        writeln!(md).unwrap();
    }
    if let Err(e) = pareto(&rows, figure) {
        eprintln!("pareto plot failed: {e}");
    } else {
        writeln!(md, "Pareto front (error against time): `{figure}`.\n").unwrap();
    }
}

fn main() {
    let Args { out, figure, quick } = parse_args();
    let min_s = if quick { 0.05 } else { 0.3 };
    let mut md = String::new();
    preamble(&mut md);
    headline(&mut md, min_s);
    accuracy(&mut md, min_s, &figure);
    effect_costs::effect_costs(&mut md, min_s);
    reference_effects::reference_effects(&mut md, min_s);
    rich_rows::rich_rows(&mut md, min_s);
    std::fs::write(&out, &md).expect("write report");
    print!("{md}");
    eprintln!("wrote {out} and {figure}");
}
