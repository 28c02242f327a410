//! `cargo xtask`: orchestration that plain cargo can't do.
//!
//! - `ci`: everything CI runs (the README's test command): fmt, clippy, unused dependencies,
//!   module cycles, size limits, no_std checks for the Cortex-M target, firmware cross-builds
//!   with the size report, host tests, the fuzz campaign (10⁷ frames), the 10 s link flood,
//!   the tune tables against a fresh run, the every-plant supervisor, the real-browser test of `hostctl ui`,
//!   QEMU scenarios, the emulated Nucleo board's tests and mutation checks, the instruction
//!   budgets (mean and worst tick) and the Slurm cluster test.
//!   Every step that runs `#[ignore]`d tests fails when fewer ran than it has.
//! - `unused-deps`: every declared dependency of the root workspace is used (also in `ci`).
//! - `firmware [--update-size-report]`: builds every board image.
//! - `qemu [--bless]`: runs the QEMU scenarios against their expected transcripts.
//! - `board-emu [--build] [--bench]`: the Nucleo-F446RE images on the board emulator
//!   (host/board-emu): builds images, mutants and emulator, then runs the emulated-board tests
//!   (also in `ci`); `--build` only builds (for `hostctl --board-emulator`), `--bench` prints
//!   cycles per servo tick and CPU load for docs/BENCHMARKS.md.
//! - `flash BOARD --features dac|pwm[,defmt]`: builds a real board's image and flashes it with
//!   probe-rs (the board's runner; docs/toolchain.md).
//! - `bench-firmware [--no-write | --check]`: instructions per servo tick under QEMU `-icount`
//!   (`--check`, in `ci`: docs/BENCHMARKS.md's section must be the fresh run's).
//! - `fuzz [--frames N] [--seed S]`: the fuzz campaign with a chosen budget (CI runs 10⁷
//!   frames, seed 1, docs/RELIABILITY.md's figures).
//! - `bench [--quick] [--no-criterion]`: the simulator's accuracy-vs-time tables
//!   (docs/BENCHMARKS-sim.md, docs/figures/pareto-sim.png).
//! - `tune-table [--quick] [--only NAME]`: K* vs the K `hostctl tune` sets on the plants of
//!   `sim/plants/`, and the supervisor at 1.5 K* (docs/TUNE.md).
//! - `ui-screenshots`: the real-browser test of `hostctl ui`, writing `docs/figures/ui-*.png`
//!   (installs Debian's chromium and chromium-driver if missing, as `ci` does).
//! - `cluster-test`: a Fig. 6 panel as a Slurm job array on a throw-away single-node cluster
//!   (installs slurm-wlm and munge; also in `ci`, about 2.5 min; docs/cluster.md).
//! - `module-cycles [--edges]`: no import cycle between the files of any crate's `src` (the
//!   graph of `crate::`/`super::`/child paths; `--edges` prints it).
//! - `arch [--print]`: docs/ARCHITECTURE.md's crate diagram, crate table (layer, folder,
//!   dependencies, modules) and folder order against the code; every arrow runs down (also in
//!   `ci`; `--print` prints the sections as built).
//! - `sizes`: no production file over 700 lines before its tests, no production function over
//!   80 lines, no `#[allow(clippy::too_many_arguments)]` (also in `ci`).
//! - `readme-figures`: README.md quotes the summary figures of docs/TUNE.md and
//!   docs/TUNE-holdout.md and the number of plant files (also in `ci`).
//! - `atlas`: the stability atlas of docs/ATLAS.md and docs/figures/atlas/ (`hostctl map` over
//!   μ × τ_D, then `hostctl map atlas`).
//! - `figures [--check]`: the figure gallery docs/FIGURES.md and docs/figures/gallery/ (every
//!   kind of `hostctl` figure on a preset and a plant file, with its words as text); `--check`
//!   compares those words with a fresh run and that every PNG is there (also in `ci`).
use anyhow::{bail, Context, Result};
use process::{cargo, run, run_counting, run_ignored, update_section};

mod arch;
mod atlas;
mod bench;
mod bench_firmware;
mod board_emu;
mod cluster;
mod figures;
mod firmware;
mod flash;
mod fuzz;
mod module_cycles;
mod process;
mod qemu;
mod readme_figures;
mod sizes;
mod toolchain;
mod tune_table;
mod ui;
mod unused_deps;

/// no_std crates that must build for the Cortex-M target.
const NO_STD_CRATES: &[(&str, &[&str])] = &[
    ("stiffwall-core", &[]),
    ("stiffwall-proto", &[]),
    ("stiffwall-firmware", &[]),
    ("stiffwall-sim", &["--no-default-features"]),
];

/// Copies the simulator's tables (docs/BENCHMARKS-sim.md, written by `bench`) into their
/// section of docs/BENCHMARKS.md, one level down in the heading hierarchy.
fn sync_sim_benchmarks() -> Result<()> {
    let docs = firmware::root().join("docs");
    let sim = std::fs::read_to_string(docs.join("BENCHMARKS-sim.md"))
        .context("reading docs/BENCHMARKS-sim.md")?;
    let body: String = sim
        .lines()
        .map(|l| {
            if l.starts_with('#') {
                format!("#{l}\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    update_section(&docs.join("BENCHMARKS.md"), "sim", body.trim_end())
}

/// The examples of the library crates `ci` builds and runs (each a few seconds on the fast
/// virtual device).
const LIBRARY_EXAMPLES: [(&str, &str); 3] = [
    ("stiffwall-tune", "tune_virtual"),
    ("stiffwall-tune", "release_test"),
    ("stiffwall-client", "record"),
];

/// Everything CI runs, in order: the static checks, then builds and tests, then the long
/// campaigns, then the emulated targets and the cluster.
fn ci() -> Result<()> {
    let started = std::time::Instant::now();
    let step = |name: &str| {
        eprintln!(
            "xtask ci: {name} ({:.0} s in)",
            started.elapsed().as_secs_f64()
        )
    };
    let cross = toolchain::ensure_cross()?;
    ci_static_checks(&step)?;
    ci_builds_and_tests(&step, cross)?;
    ci_campaigns(&step)?;
    ci_emulated_targets(&step)?;
    step("done");
    Ok(())
}

/// `ci`'s checks that read the code without running it: format, clippy (with and without the
/// live view), unused dependencies, module cycles, the architecture page and size limits.
fn ci_static_checks(step: &dyn Fn(&str)) -> Result<()> {
    step("format");
    run(cargo().args(["fmt", "--all", "--check"]))?;
    step("clippy");
    run(cargo().args([
        "clippy",
        "--workspace",
        "--all-targets",
        "--",
        "-D",
        "warnings",
    ]))?;
    step("hostctl without the live view (--no-default-features: no axum, tokio, hyper)");
    run(cargo().args([
        "clippy",
        "-p",
        "stiffwall-host",
        "--all-targets",
        "--no-default-features",
        "--",
        "-D",
        "warnings",
    ]))?;
    step("every declared dependency is used");
    unused_deps::unused_deps()?;
    step("no import cycle between the files of any crate");
    module_cycles::module_cycles(&[])?;
    step("docs/ARCHITECTURE.md's crate diagram, layers and module lists against the code");
    arch::arch(&[])?;
    step("no production file over 700 lines before its tests, no function over 80 lines, no too_many_arguments allow");
    sizes::sizes(&[])?;
    step("README.md's figures of tune against the truth are the ones docs/TUNE.md and docs/TUNE-holdout.md state");
    readme_figures::readme_figures()?;
    Ok(())
}

/// `ci`'s builds and tests: the no_std crates, the firmware images, the host tests and the
/// library examples.
fn ci_builds_and_tests(step: &dyn Fn(&str), cross: toolchain::Cross) -> Result<()> {
    if cross == toolchain::Cross::Rustup {
        step("no_std crates for the Cortex-M target");
        for (krate, extra) in NO_STD_CRATES {
            run(cargo()
                .args(["check", "-p", krate, "--target", toolchain::TARGET])
                .args(*extra))?;
        }
    } else {
        eprintln!("xtask: no_std crates are checked through the board builds (build-std fallback)");
    }
    step("firmware images, size report, no-panic proof");
    firmware::firmware(&[])?;
    step("host tests (unit, SIL, end to end against the virtual device)");
    run(cargo().args(["test", "--workspace"]))?;
    step("the library examples (tune the virtual device, one release test, record 10 s)");
    for (krate, example) in LIBRARY_EXAMPLES {
        run(cargo().args(["run", "-p", krate, "--example", example]))?;
    }
    Ok(())
}

/// `ci`'s long runs: the fuzz campaign, the link flood, the tune tables and the supervisor on
/// every plant.
fn ci_campaigns(step: &dyn Fn(&str)) -> Result<()> {
    step("the fuzz campaign of docs/RELIABILITY.md: 1e7 frames, 1e6 chunks, 1e5 power cuts, 1e6 pty frames (seed 1)");
    fuzz::fuzz(&["--frames".to_string(), "10000000".to_string()])?;
    step("the 10 s flood of bad frames, real time and fast (the issue's acceptance run; debug build of the step above)");
    run_counting(
        cargo().args([
            "test",
            "-p",
            "stiffwall-host",
            "--test",
            "link_flood",
            "--",
            "--ignored",
        ]),
        1,
    )?;
    step("docs/TUNE.md and docs/TUNE-holdout.md against a fresh run: every set wall rests, K ≥ 0.7 K*(B), supervisor rows stop, median ≥ 2, K* columns not stale");
    tune_table::ci_checks()?;
    step("docs/FIGURES.md against a fresh run (every figure's title, axes, legend and values; every PNG it names present)");
    figures::figures(&["--check".to_string()])?;
    step("tune on the random launch plants (quiet walls)");
    run_ignored("stiffwall-tests", "tune_plants", &["random_launch"], 1)?;
    step("the supervisor on every plant: 1.5 K*(0), and 1.5 K*(B) at the B and law tune sets (docs/TUNE.md's supervisor column)");
    run_ignored("stiffwall-tests", "supervisor_plants", &[], 2)?;
    Ok(())
}

/// `ci`'s runs on other machines: the real browser, QEMU, the board emulator, the instruction
/// budget and the Slurm cluster.
fn ci_emulated_targets(step: &dyn Fn(&str)) -> Result<()> {
    step("hostctl ui in a real browser (chromium + chromedriver)");
    ui::browser_test(None)?;
    step("QEMU scenarios");
    qemu::qemu(&[])?;
    step("the Nucleo images on the board emulator (unicorn): boot, pty, tune vs the virtual device, flash store, watchdog, mutation checks");
    board_emu::board_emu(&[])?;
    step("servo instruction budgets under QEMU -icount (the wall, the haptic profile), and docs/BENCHMARKS.md's figures against the run");
    bench_firmware::bench_firmware(&["--no-write".to_string()])?;
    step("a Fig. 6 panel as a Slurm job array on a throw-away cluster (Debian's slurm-wlm and munge; root), with pre-emption");
    cluster::cluster_test(&[])?;
    Ok(())
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("ci") => ci(),
        Some("firmware") => firmware::firmware(&args[1..]),
        Some("bench") => {
            bench::bench(&args[1..])?;
            sync_sim_benchmarks()
        }
        Some("qemu") => qemu::qemu(&args[1..]),
        Some("board-emu") => board_emu::board_emu(&args[1..]),
        Some("flash") => flash::flash(&args[1..]),
        Some("unused-deps") => unused_deps::unused_deps(),
        Some("bench-firmware") => bench_firmware::bench_firmware(&args[1..]),
        Some("fuzz") => fuzz::fuzz(&args[1..]),
        Some("tune-table") => tune_table::tune_table(&args[1..]),
        Some("ui-screenshots") => ui::screenshots(),
        Some("cluster-test") => cluster::cluster_test(&args[1..]),
        Some("atlas") => atlas::atlas(&args[1..]),
        Some("figures") => figures::figures(&args[1..]),
        Some("module-cycles") => module_cycles::module_cycles(&args[1..]),
        Some("arch") => arch::arch(&args[1..]),
        Some("sizes") => sizes::sizes(&args[1..]),
        Some("readme-figures") => readme_figures::readme_figures(),
        other => bail!("unknown xtask {other:?}; available: ci, unused-deps, firmware [--update-size-report], qemu [--bless], board-emu [--build] [--bench], flash BOARD --features dac|pwm[,defmt], bench-firmware [--no-write | --check], bench [--quick], tune-table [--quick] [--only NAME], ui-screenshots, fuzz [--frames N] [--seed S], cluster-test, atlas, figures [--check], module-cycles [--edges], arch [--print], sizes, readme-figures"),
    }
}
