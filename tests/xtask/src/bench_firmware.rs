//! `cargo xtask bench-firmware [--no-write]`: instructions per servo tick on the QEMU image.
//!
//! Runs `stiffwall-qemu-an386-bench` under `qemu-system-arm -icount shift=7` (deterministic:
//! 128 virtual ns per instruction, SysTick one count per 40 ns, so a single tick is resolved to
//! a third of an instruction), parses its `BENCH <stage> <numeric> <ns ×100>` lines (mean
//! instructions per tick over 8000 fault-free ticks) and its `BENCH-TICK <phase> <numeric> <ns>
//! <tick> <ticks>` lines (the longest single tick of each phase of one run through a config
//! change, two prepared tests, a fault and its clearing), prints the tables, writes them into
//! `docs/BENCHMARKS.md` between the `firmware-icount` markers, and fails when the default
//! back-end (I32F32) exceeds the full-tick budget of 155 instructions (mean, with B = 0 or with
//! the damper on, its default dead band of one count, at two counts per tick so that the damper
//! acts on every tick), the spring stage's budget of 31, or the worst-tick budget of
//! [`WORST_BUDGET`] (see docs/BENCHMARKS.md).

use crate::firmware::{root, IMAGES};
use crate::process::update_section;
use crate::toolchain;
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use std::process::Command;

/// Budget of the spring stage, instructions per tick (29.0 measured + 10 %, rounded down).
pub const SPRING_BUDGET: f64 = 31.0;
/// Budget of the full tick, with and without the damper, mean instructions per tick (140.2
/// measured with B = 0, 151.2 with B > 0 and the damper acting on every tick, since the
/// supervisor's travel window (protocol 3: one load pair, the raw count's reload, a subtract, a
/// compare and a branch, 5 instructions, on every tick whether a window is set or not); was
/// 150 with 135.3 and 146.3 before it (147.2 before the bench image gained its worst-tick run:
/// the same servo code, inlined differently into the bench's `full`), and 157 with 142.3 and
/// 153.3 before the damper law and the tick's `halt` word).
pub const FULL_BUDGET: f64 = 155.0;
/// Budget of the longest single tick of the worst-tick run (any phase: a config change, a
/// prepared test's first and last tick, a fault, clearing it), instructions. Those ticks derive
/// the servo's gains from a config (`Gains::from_config`, f64 in software on the M4F):
/// 7039 (config change), 7594 (a prepared test's first tick: its own config), 7574 (its last:
/// the active config back) measured (7034, 7589, 7569 before the bench's worst-tick run was
/// split into functions: the same servo code, the bench's own instructions inside the timed
/// window around the call 5 more, 3 to 5 on the other back-ends). 9000 is half the 18 000 cycles of a 100 µs tick (the
/// boards' highest rate, 10 kHz) on the nucleo-f446re's 180 MHz core, at one cycle per
/// instruction.
pub const WORST_BUDGET: f64 = 9000.0;
/// Budget of the longest tick that applies no config (the phases but `config-change`,
/// `prepared-test-start` and `test-end`: a first reading, the wall, a test running, a fault,
/// clearing it), instructions: 655 measured (an impact's release after its launch; 650 before
/// the bench's worst-tick run was split into functions, see [`WORST_BUDGET`]).
pub const NO_CONFIG_BUDGET: f64 = 700.0;
/// The phases whose ticks apply a config (`Gains::from_config`).
const CONFIG_PHASES: [&str; 3] = ["config-change", "prepared-test-start", "test-end"];
/// `-icount shift`: one instruction is 2^ICOUNT_SHIFT virtual ns.
const ICOUNT_SHIFT: u32 = 7;
const DEFAULT_NUMERIC: &str = "I32F32";
/// The full tick's stage name in the bench output (B = 0).
const FULL: &str = "full(+telemetry)";
/// The full tick with the virtual damper on (B > 0, the default law: a dead band of one count)
/// and a sweep of two counts per tick, beyond the dead band; one word (the bench output is split
/// on whitespace).
const FULL_DAMPED: &str = "full+damper";

/// (stage, numeric, mean instructions per tick).
pub type Mean = (String, String, f64);

/// The longest tick of one phase of the worst-tick run.
#[derive(Debug, Clone)]
pub struct WorstTick {
    /// Phase (`wall`, `config-change`, …).
    pub phase: String,
    /// Numeric back-end.
    pub numeric: String,
    /// Instructions of the phase's longest tick.
    pub instructions: f64,
    /// Its tick number in the run.
    pub tick: u64,
    /// Ticks of the run in this phase.
    pub ticks: u64,
}

/// Builds and runs the bench image; returns (stage, numeric, mean instructions per tick) and
/// the worst-tick run's phases.
pub fn measure() -> Result<(Vec<Mean>, Vec<WorstTick>)> {
    toolchain::ensure_qemu()?;
    let cross = toolchain::ensure_cross()?;
    let image = IMAGES
        .iter()
        .find(|i| i.name == "qemu-an386")
        .expect("QEMU image listed");
    let elf = crate::firmware::build(cross, image, &[])?;
    let bench = elf.with_file_name("stiffwall-qemu-an386-bench");
    let out = Command::new("timeout")
        .args([
            "120",
            "qemu-system-arm",
            "-cpu",
            "cortex-m4",
            "-machine",
            "mps2-an386",
        ])
        .args(["-display", "none", "-monitor", "none", "-serial", "null"])
        .args([
            "-semihosting-config",
            "enable=on,target=native",
            "-icount",
            &format!("shift={ICOUNT_SHIFT}"),
        ])
        .arg("-kernel")
        .arg(&bench)
        .output()
        .context("running qemu-system-arm")?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() || stdout.contains("BENCH-ERROR") {
        bail!(
            "bench image failed ({}):\n{stdout}{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let ns_per_instruction = f64::from(1u32 << ICOUNT_SHIFT);
    let rows: Vec<Mean> = stdout
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            match f.as_slice() {
                ["BENCH", stage, numeric, v] if *stage != "baseline" => Some((
                    (*stage).into(),
                    (*numeric).into(),
                    v.parse::<f64>().ok()? / 100.0 / ns_per_instruction,
                )),
                _ => None,
            }
        })
        .collect();
    let worst: Vec<WorstTick> = stdout
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            match f.as_slice() {
                ["BENCH-TICK", phase, numeric, ns, tick, ticks] => Some(WorstTick {
                    phase: (*phase).into(),
                    numeric: (*numeric).into(),
                    instructions: ns.parse::<f64>().ok()? / ns_per_instruction,
                    tick: tick.parse().ok()?,
                    ticks: ticks.parse().ok()?,
                }),
                _ => None,
            }
        })
        .collect();
    if rows.is_empty() || worst.is_empty() {
        bail!("bench image printed no results:\n{stdout}");
    }
    Ok((rows, worst))
}

/// The worst-tick run as a Markdown table: per phase, the longest tick of each back-end
/// (instructions, rounded: a single tick is resolved to ±0.3), its tick, and the phase's ticks.
pub fn worst_table(worst: &[WorstTick]) -> String {
    let mut numerics: Vec<&str> = Vec::new();
    let mut phases: Vec<&str> = Vec::new();
    for w in worst {
        if !numerics.contains(&w.numeric.as_str()) {
            numerics.push(&w.numeric);
        }
        if !phases.contains(&w.phase.as_str()) {
            phases.push(&w.phase);
        }
    }
    let mut t = String::from("| phase of the run | ticks |");
    for n in &numerics {
        let _ = write!(t, " {n}: longest tick (at) |");
    }
    t.push_str("\n|---|---:|");
    t.push_str(&"---:|".repeat(numerics.len()));
    t.push('\n');
    for p in &phases {
        let ticks = worst.iter().find(|w| w.phase == *p).map_or(0, |w| w.ticks);
        let _ = write!(t, "| {p} | {ticks} |");
        for n in &numerics {
            match worst.iter().find(|w| w.phase == *p && w.numeric == *n) {
                Some(w) => {
                    let _ = write!(t, " {:.0} ({}) |", w.instructions, w.tick);
                }
                None => t.push_str(" – |"),
            }
        }
        t.push('\n');
    }
    t
}

/// The phases every worst-tick run must contain (a rename or a lost event fails the gate).
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

/// Renders the measurements as a Markdown table.
pub fn table(rows: &[(String, String, f64)]) -> String {
    let mut numerics: Vec<&str> = Vec::new();
    let mut stages: Vec<&str> = Vec::new();
    for (s, n, _) in rows {
        if !numerics.contains(&n.as_str()) {
            numerics.push(n);
        }
        if !stages.contains(&s.as_str()) {
            stages.push(s);
        }
    }
    let mut t = String::from("| servo stage (cumulative) |");
    for n in &numerics {
        let _ = write!(t, " {n} |");
    }
    t.push_str("\n|---|");
    t.push_str(&"---:|".repeat(numerics.len()));
    t.push('\n');
    for s in &stages {
        let _ = write!(t, "| {s} |");
        for n in &numerics {
            match rows.iter().find(|r| r.0 == *s && r.1 == *n) {
                Some(r) => {
                    let _ = write!(t, " {:.1} |", r.2);
                }
                None => t.push_str(" – |"),
            }
        }
        t.push('\n');
    }
    t
}

/// `cargo xtask bench-firmware`.
pub fn bench_firmware(args: &[String]) -> Result<()> {
    let write = !args.iter().any(|a| a == "--no-write");
    if let Some(bad) = args.iter().find(|a| *a != "--no-write") {
        bail!("unknown argument {bad:?} for `cargo xtask bench-firmware` (allowed: --no-write)");
    }
    let (rows, worst) = measure()?;
    let t = table(&rows);
    let worst_default = worst
        .iter()
        .filter(|w| w.numeric == DEFAULT_NUMERIC)
        .max_by(|a, b| a.instructions.total_cmp(&b.instructions))
        .context("the bench printed no worst tick for the default back-end")?;
    let worst_text = worst_text(worst_default, &worst_table(&worst));
    let damper = damper_text(&rows)?;
    println!(
        "Instructions per servo tick (QEMU -icount shift={ICOUNT_SHIFT}, mps2-an386, release build):\n\n{t}\n{damper}\n{worst_text}"
    );
    if write {
        write_doc(&t, &damper, &worst_text)?;
    }
    check_budgets(&rows, &worst, worst_default)
}

/// The default back-end's mean instructions per tick of `stage`.
fn default_mean(rows: &[Mean], stage: &str) -> Option<f64> {
    rows.iter()
        .find(|r| r.0 == stage && r.1 == DEFAULT_NUMERIC)
        .map(|r| r.2)
}

/// The worst-tick paragraph (the run, its budgets) and its table `wt`.
fn worst_text(worst_default: &WorstTick, wt: &str) -> String {
    format!(
        "The worst tick ({DEFAULT_NUMERIC}: {:.0} instructions, {}, budget ≤ {WORST_BUDGET}): one run of\n\
         16 000 full ticks with the damper (the `full+damper` sweep), each tick timed alone (SysTick\n\
         read around the call, the per-tick stand-ins subtracted), through a config change (tick\n\
         1000: K × 1.5, B × 0.5), a prepared release test (tick 2000, `PrepareTest`'s own config, a\n\
         decided end: the device at rest 20 counts in) and a prepared impact test (tick 4000, from\n\
         30 counts out: the hold, the launch, its time limit, the release), an encoder jump (tick\n\
         12 000: the fault latched, then safe-mode damping) and clearing it (tick 13 000); heartbeat\n\
         watchdog armed. The ticks that apply a config (a change, a prepared test's first and last\n\
         tick) derive the gains in f64, in software on the M4F (`Gains::from_config`): they are\n\
         the worst by far. The budget is half of a 100 µs tick (the boards' highest rate, 10 kHz)\n\
         on the nucleo-f446re's 180 MHz core at one cycle per instruction; a tick without a\n\
         config to apply has its own budget, ≤ {NO_CONFIG_BUDGET}.\n\n{wt}",
        worst_default.instructions, worst_default.phase
    )
}

/// The damper's sentence: what B > 0 adds to the default back-end's full tick.
fn damper_text(rows: &[Mean]) -> Result<String> {
    match (default_mean(rows, FULL_DAMPED), default_mean(rows, FULL)) {
        (Some(d), Some(f)) => Ok(format!(
            "The virtual damper (B > 0, `{FULL_DAMPED}`: the same two-sided wall, its default law (a dead\n\
             band of one count) and a sweep of two counts per tick, so that the damper term is computed\n\
             on every tick) adds {:.1} instructions to the full tick ({DEFAULT_NUMERIC}: {f:.1} with B = 0, {d:.1} with B > 0).\n",
            d - f
        )),
        _ => bail!("the bench printed no damper figure for {DEFAULT_NUMERIC}"),
    }
}

/// Writes the tables `t` and the texts into `docs/BENCHMARKS.md` (`firmware-icount` section).
fn write_doc(t: &str, damper: &str, worst_text: &str) -> Result<()> {
    let body = format!(
        "Instructions per servo tick on the QEMU image, measured by `cargo xtask bench-firmware`\n\
         (run by `cargo xtask ci`, which fails over a budget; `qemu-system-arm -icount shift=7`:\n\
         128 virtual ns per instruction, SysTick at 40 ns per count; SysTick read around\n\
         batches of 200 ticks, 8000 fault-free ticks per stage, the empty loop subtracted: the mean). Stages are\n\
         cumulative; the full tick adds the command queue and the telemetry push. Each stage is\n\
         its own function, called once per tick as the servo interrupt calls `Servo::tick`,\n\
         so its count depends on the servo's code only. The call, the return and the bench's\n\
         encoder and output stand-ins are measured the same way (`io-stand-ins`) and\n\
         subtracted; on hardware the stand-ins are one register load and one store. Budgets for the default back-end\n\
         ({DEFAULT_NUMERIC}): full tick ≤ {FULL_BUDGET} (mean, with B = 0 and with the damper), spring ≤ {SPRING_BUDGET},\n\
         worst single tick ≤ {WORST_BUDGET}, ≤ {NO_CONFIG_BUDGET} where the tick applies no config (enforced in CI).\n\n{t}\n{damper}\n{worst_text}"
    );
    update_section(&root().join("docs/BENCHMARKS.md"), "firmware-icount", &body)
}

/// The gates on the default back-end: the spring stage, every phase of the worst-tick run
/// present, the ticks without a config, the worst tick, and the full tick with and without the
/// damper.
fn check_budgets(rows: &[Mean], worst: &[WorstTick], worst_default: &WorstTick) -> Result<()> {
    match default_mean(rows, "spring") {
        Some(v) if v > SPRING_BUDGET => {
            bail!("spring stage over its instruction budget: {v:.1} > {SPRING_BUDGET}")
        }
        Some(_) => {}
        None => bail!("the bench printed no spring figure for {DEFAULT_NUMERIC}"),
    }
    for phase in WORST_PHASES {
        if !worst
            .iter()
            .any(|w| w.phase == phase && w.numeric == DEFAULT_NUMERIC && w.ticks > 0)
        {
            bail!("the worst-tick run has no {phase} tick for {DEFAULT_NUMERIC}");
        }
    }
    if let Some(w) = worst.iter().find(|w| {
        w.numeric == DEFAULT_NUMERIC
            && !CONFIG_PHASES.contains(&w.phase.as_str())
            && w.instructions > NO_CONFIG_BUDGET
    }) {
        bail!(
            "servo tick without a config over its budget: {} {:.0} > {NO_CONFIG_BUDGET} (tick {})",
            w.phase,
            w.instructions,
            w.tick
        );
    }
    if worst_default.instructions > WORST_BUDGET {
        bail!(
            "worst servo tick over its budget: {} {:.0} > {WORST_BUDGET} (tick {})",
            worst_default.phase,
            worst_default.instructions,
            worst_default.tick
        );
    }
    for stage in [FULL, FULL_DAMPED] {
        match default_mean(rows, stage) {
            Some(v) if v > FULL_BUDGET => {
                bail!("servo tick over its instruction budget: {stage} {v:.1} > {FULL_BUDGET}")
            }
            Some(_) => {}
            None => bail!("the bench printed no {stage} figure for {DEFAULT_NUMERIC}"),
        }
    }
    Ok(())
}
