//! `cargo xtask bench-firmware [--no-write | --check]`: instructions per servo tick on the QEMU
//! image.
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
//! [`WORST_BUDGET`] (see docs/BENCHMARKS.md). The haptic profile's stages (`BENCH profile-…`,
//! `BENCH-PROFILE-TICK`, `BENCH-COMPILE`: the full tick in profile mode with 1 to 16 elements,
//! its longest ticks, the main loop's compile) have their own table and budgets:
//! [`PROFILE_BUDGET`] for the mean and the longest render tick of the worst profile (16 detent
//! trains), [`PROFILE_TAKE_BUDGET`] for the tick that takes it, [`WORST_BUDGET`] for a config
//! applied in profile mode (so the section's claim of how many elements fit at 10 and 20 kHz
//! holds whenever the budgets do). `--check` also fails when the section in docs/BENCHMARKS.md
//! is not this run's; `ci` runs `--no-write`, the budgets alone: the counts are deterministic for
//! one image, but the image is the toolchain's, and a fresh machine's may inline differently.

use crate::firmware::{root, IMAGES};
use crate::process::update_section;
use crate::toolchain;
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use std::process::Command;

/// Budget of the spring stage, instructions per tick (29.0 measured + 10 %, rounded down).
pub const SPRING_BUDGET: f64 = 31.0;
/// Budget of the full tick, with and without the damper, mean instructions per tick (142.2
/// measured with B = 0 since the haptic profile's firmware (7b6efe3; 140.2 before it, the same
/// bench), 151.2 with B > 0 and the damper acting on every tick (unchanged by it); since the
/// supervisor's travel window (protocol 3: one load pair, the raw count's reload, a subtract, a
/// compare and a branch, 5 instructions, on every tick whether a window is set or not); was
/// 150 with 135.3 and 146.3 before it (147.2 before the bench image gained its worst-tick run:
/// the same servo code, inlined differently into the bench's `full`), and 157 with 142.3 and
/// 153.3 before the damper law and the tick's `halt` word).
pub const FULL_BUDGET: f64 = 155.0;
/// Budget of the longest single tick of the worst-tick run (any phase: a config change, a
/// prepared test's first and last tick, a fault, clearing it), instructions. Those ticks derive
/// the servo's gains from a config (`Gains::from_config`, f64 in software on the M4F):
/// 7046 (config change), 7606 (a prepared test's first tick: its own config), 7592 (its last:
/// the active config back) measured since the bench image renders profiles (7040, 7600, 7586
/// with the profile's firmware before its bench stages, which link the profile's compile into
/// the image: the same servo code, inlined differently; 7039, 7594, 7574 before the profile's
/// firmware, 7034, 7589, 7569 before the bench's worst-tick run was
/// split into functions: the same servo code, the bench's own instructions inside the timed
/// window around the call 5 more, 3 to 5 on the other back-ends). 9000 is half the 18 000 cycles of a 100 µs tick (the
/// boards' highest rate, 10 kHz) on the nucleo-f446re's 180 MHz core, at one cycle per
/// instruction.
pub const WORST_BUDGET: f64 = 9000.0;
/// Budget of the longest tick that applies no config (the phases but `config-change`,
/// `prepared-test-start` and `test-end`: a first reading, the wall, a test running, a fault,
/// clearing it), instructions: 659 measured (an impact's release after its launch; 655 before
/// the haptic profile's firmware, 650 before the bench's worst-tick run was split into
/// functions, see [`WORST_BUDGET`]).
pub const NO_CONFIG_BUDGET: f64 = 700.0;
/// The phases whose ticks apply a config (`Gains::from_config`).
const CONFIG_PHASES: [&str; 3] = ["config-change", "prepared-test-start", "test-end"];
/// The gated profile stage: the worst profile a user can load, sixteen detent trains each
/// spanning the whole sweep with its damper acting (the bench image's `bench/profile.rs` says
/// why: a train is the costliest element, its phase a 64-bit product and its force a sine).
const PROFILE_16: &str = "profile-detents-16";
/// The one-train stage (with [`PROFILE_16`]: the cost per train).
const PROFILE_1: &str = "profile-detents-1";
/// Budget of the full tick rendering [`PROFILE_16`] (the `full+damper` config and sweep in
/// profile mode), instructions: the mean over the stage and the longest tick of its timed run
/// that applies nothing (2074.5 and 2084 measured, + 10 % of the mean, rounded; the longest is
/// a tick whose sum the output clamp cuts). It is 119 instructions per train on a
/// 170-instruction tick; on the nucleo-f446re's 180 MHz core at one cycle per instruction
/// it is 23 % of a 20 kHz tick (9000 cycles), half of one with the TIM7 handler around it
/// (4500), and 12.7 % of a 10 kHz tick (18 000 cycles, the boards' highest rate).
pub const PROFILE_BUDGET: f64 = 2280.0;
/// Budget of the tick that takes [`PROFILE_16`] (`ServoCmd::Profile`: the compiled table out of
/// its queue, then the first render), instructions: 3276 measured + 10 %. Taking a table
/// copies its elements out of the queue's slot (1 train: 711 in all, 425 over its render tick;
/// 16: 1192 over it); until the servo copied the elements only, the whole 16-slot table was
/// copied, 4397 for 16 trains. Under half of a 20 kHz tick's 9000 cycles. A config applied in profile mode (the
/// gains derived, and the profile's render on the same tick) is a config-applying tick, under
/// [`WORST_BUDGET`].
pub const PROFILE_TAKE_BUDGET: f64 = 3600.0;
/// Cycles of the nucleo-f446re's TIM7 handler around `Servo::tick` (exception entry and
/// return, the acknowledge, the rate check, the encoder read and the output): the board
/// emulator's wall tick less QEMU's full tick, 49 for the dac image and 62 for the pwm image
/// (191 and 204 cycles at 10 kHz against 142.2), rounded up (docs/BENCHMARKS.md, "The Nucleo
/// image on the board emulator").
const NUCLEO_HANDLER_CYCLES: f64 = 65.0;
/// The nucleo-f446re's core clock, Hz.
const NUCLEO_HZ: f64 = 180.0e6;
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

/// The longest tick of one phase of a profile's timed run (`BENCH-PROFILE-TICK`).
#[derive(Debug, Clone)]
pub struct ProfileTick {
    /// The profile's stage (`profile-detents-16`, …).
    pub stage: String,
    /// The tick's phase in the run (`profile-take`, `config-change`, `profile-tick`).
    pub tick: WorstTick,
}

/// What the bench image printed.
#[derive(Debug, Clone, Default)]
pub struct Bench {
    /// (stage, numeric, mean instructions per tick), the profile stages included.
    pub means: Vec<Mean>,
    /// The worst-tick run's phases.
    pub worst: Vec<WorstTick>,
    /// The profile runs' phases.
    pub profile_ticks: Vec<ProfileTick>,
    /// (stage, numeric, instructions of the main loop's validate + compile + queue).
    pub compiles: Vec<Mean>,
}

/// Builds and runs the bench image and parses its lines.
pub fn measure() -> Result<Bench> {
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
    let b = parse(&stdout);
    if b.means.is_empty() || b.worst.is_empty() || b.profile_ticks.is_empty() {
        bail!("bench image printed no results:\n{stdout}");
    }
    Ok(b)
}

/// Parses the bench image's `BENCH`, `BENCH-TICK`, `BENCH-PROFILE-TICK` and `BENCH-COMPILE`
/// lines (virtual ns, 2^[`ICOUNT_SHIFT`] per instruction).
pub fn parse(stdout: &str) -> Bench {
    let ns_per_instruction = f64::from(1u32 << ICOUNT_SHIFT);
    let tick = |phase: &str, numeric: &str, ns: &str, tick: &str, ticks: &str| {
        Some(WorstTick {
            phase: phase.into(),
            numeric: numeric.into(),
            instructions: ns.parse::<f64>().ok()? / ns_per_instruction,
            tick: tick.parse().ok()?,
            ticks: ticks.parse().ok()?,
        })
    };
    let mut b = Bench::default();
    for l in stdout.lines() {
        let f: Vec<&str> = l.split_whitespace().collect();
        match f.as_slice() {
            ["BENCH", stage, numeric, v] if *stage != "baseline" => {
                if let Ok(v) = v.parse::<f64>() {
                    let mean = v / 100.0 / ns_per_instruction;
                    b.means.push(((*stage).into(), (*numeric).into(), mean));
                }
            }
            ["BENCH-TICK", phase, numeric, ns, t, ticks] => {
                b.worst.extend(tick(phase, numeric, ns, t, ticks));
            }
            ["BENCH-PROFILE-TICK", stage, phase, numeric, ns, t, ticks] => {
                if let Some(tick) = tick(phase, numeric, ns, t, ticks) {
                    b.profile_ticks.push(ProfileTick {
                        stage: (*stage).into(),
                        tick,
                    });
                }
            }
            ["BENCH-COMPILE", stage, numeric, ns] => {
                if let Ok(ns) = ns.parse::<f64>() {
                    let n = ns / ns_per_instruction;
                    b.compiles.push(((*stage).into(), (*numeric).into(), n));
                }
            }
            _ => {}
        }
    }
    b
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
    table_titled(rows, "servo stage (cumulative)")
}

/// The measurements as a Markdown table whose first column is titled `title`.
fn table_titled(rows: &[(String, String, f64)], title: &str) -> String {
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
    let mut t = format!("| {title} |");
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

/// `cargo xtask bench-firmware [--no-write | --check]`: `--no-write` (what `ci` runs) writes
/// nothing and fails on a broken budget; `--check` also fails when docs/BENCHMARKS.md's section
/// differs from this run's (the figures under `-icount` are deterministic for one image).
pub fn bench_firmware(args: &[String]) -> Result<()> {
    let check = args.iter().any(|a| a == "--check");
    let write = !check && !args.iter().any(|a| a == "--no-write");
    if let Some(bad) = args.iter().find(|a| *a != "--no-write" && *a != "--check") {
        bail!("unknown argument {bad:?} for `cargo xtask bench-firmware` (allowed: --no-write, --check)");
    }
    let b = measure()?;
    let (rows, profile_rows): (Vec<Mean>, Vec<Mean>) = b
        .means
        .iter()
        .cloned()
        .partition(|r| !r.0.starts_with("profile-"));
    let t = table(&rows);
    let worst_default = b
        .worst
        .iter()
        .filter(|w| w.numeric == DEFAULT_NUMERIC)
        .max_by(|a, b| a.instructions.total_cmp(&b.instructions))
        .context("the bench printed no worst tick for the default back-end")?;
    let worst_text = worst_text(worst_default, &worst_table(&b.worst));
    let damper = damper_text(&rows)?;
    let profile = profile_text(&b.means, &b.profile_ticks, &b.compiles)?;
    let body = doc_body(&t, &damper, &worst_text, &profile);
    println!("{body}");
    let doc = root().join("docs/BENCHMARKS.md");
    if write {
        update_section(&doc, "firmware-icount", &body)?;
    }
    check_budgets(&rows, &b.worst, worst_default)?;
    check_profile_budgets(&profile_rows, &b.profile_ticks)?;
    if check {
        check_doc(&doc, &body)?;
    }
    Ok(())
}

/// Fails unless `doc`'s `firmware-icount` section is `body`.
fn check_doc(doc: &std::path::Path, body: &str) -> Result<()> {
    let text =
        std::fs::read_to_string(doc).with_context(|| format!("reading {}", doc.display()))?;
    let start = "<!-- firmware-icount:start -->\n";
    let section = text
        .split_once(start)
        .and_then(|(_, rest)| rest.split_once("\n<!-- firmware-icount:end -->"))
        .map(|(s, _)| s)
        .context("docs/BENCHMARKS.md has no firmware-icount section")?;
    if section != body {
        let diff = section
            .lines()
            .zip(body.lines())
            .find(|(a, b)| a != b)
            .map_or_else(String::new, |(a, b)| {
                format!("\n  docs:  {a}\n  fresh: {b}")
            });
        bail!(
            "docs/BENCHMARKS.md's firmware-icount section is not this run's (run `cargo xtask \
             bench-firmware` and commit it); first difference:{diff}"
        );
    }
    Ok(())
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

/// The `firmware-icount` section of `docs/BENCHMARKS.md`: the tables `t` and the texts.
fn doc_body(t: &str, damper: &str, worst_text: &str, profile: &str) -> String {
    format!(
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
         worst single tick ≤ {WORST_BUDGET}, ≤ {NO_CONFIG_BUDGET} where the tick applies no config (enforced in CI);\n\
         the haptic profile's below.\n\n{t}\n{damper}\n{worst_text}\n{profile}"
    )
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

/// The profile's gates on the default back-end: [`PROFILE_16`]'s mean and its longest render
/// tick under [`PROFILE_BUDGET`], its take under [`PROFILE_TAKE_BUDGET`], a config applied in
/// profile mode under [`WORST_BUDGET`]; every phase present.
fn check_profile_budgets(rows: &[Mean], ticks: &[ProfileTick]) -> Result<()> {
    match default_mean(rows, PROFILE_16) {
        Some(v) if v > PROFILE_BUDGET => {
            bail!("{PROFILE_16} over its instruction budget: mean {v:.1} > {PROFILE_BUDGET}")
        }
        Some(_) => {}
        None => bail!("the bench printed no {PROFILE_16} figure for {DEFAULT_NUMERIC}"),
    }
    for (phase, budget) in [
        ("profile-tick", PROFILE_BUDGET),
        ("profile-take", PROFILE_TAKE_BUDGET),
        ("config-change", WORST_BUDGET),
    ] {
        let t = ticks
            .iter()
            .find(|p| {
                p.stage == PROFILE_16
                    && p.tick.phase == phase
                    && p.tick.numeric == DEFAULT_NUMERIC
                    && p.tick.ticks > 0
            })
            .with_context(|| {
                format!("the profile run has no {phase} tick for {DEFAULT_NUMERIC}")
            })?;
        if t.tick.instructions > budget {
            bail!(
                "{PROFILE_16} {phase}: longest tick {:.0} > {budget} (tick {})",
                t.tick.instructions,
                t.tick.tick
            );
        }
    }
    Ok(())
}

/// The default back-end's longest tick of `phase` in `stage`'s timed run.
fn profile_longest(ticks: &[ProfileTick], stage: &str, phase: &str) -> Option<f64> {
    ticks
        .iter()
        .find(|p| p.stage == stage && p.tick.phase == phase && p.tick.numeric == DEFAULT_NUMERIC)
        .map(|p| p.tick.instructions)
}

/// How many elements of the worst kind (detent trains) the nucleo-f446re's core has room for
/// at `rate` Hz: the mean tick (`base` + n·`per` instructions, the handler around it) within
/// half the period, and a config applied in profile mode (`config0` + n·`per`) within the whole
/// period. Returns (n by the mean, n by the config tick); a profile holds at most 16.
fn elements_that_fit(rate: f64, base: f64, per: f64, config0: f64) -> (u32, u32) {
    let period = NUCLEO_HZ / rate;
    let fit = |room: f64| (room / per).floor().max(0.0) as u32;
    (
        fit(period / 2.0 - NUCLEO_HANDLER_CYCLES - base),
        fit(period - NUCLEO_HANDLER_CYCLES - config0),
    )
}

/// The profile's paragraphs and tables: the stages' means (of `means`, all the stages), the
/// cost per element, the timed runs' longest ticks, the main loop's compile, the budgets, and
/// how many elements fit.
fn profile_text(means: &[Mean], ticks: &[ProfileTick], compiles: &[Mean]) -> Result<String> {
    let rows: Vec<Mean> = means
        .iter()
        .filter(|r| r.0.starts_with("profile-"))
        .cloned()
        .collect();
    let rows = rows.as_slice();
    let mean = |stage| default_mean(rows, stage).with_context(|| format!("no {stage} mean"));
    let (m1, m16) = (mean(PROFILE_1)?, mean(PROFILE_16)?);
    let per = (m16 - m1) / 15.0;
    let per4 = (mean("profile-detents-4")? - m1) / 3.0;
    let base = m1 - per;
    let full = default_mean(means, FULL_DAMPED).context("no full+damper mean")?;
    let take = profile_longest(ticks, PROFILE_16, "profile-take").context("no take")?;
    let copy = take - profile_longest(ticks, PROFILE_16, "profile-tick").context("no tick")?;
    let config16 = profile_longest(ticks, PROFILE_16, "config-change").context("no config")?;
    let config0 = config16 - 16.0 * per;
    let kinds: Vec<String> = ["wall", "spring", "viscous"]
        .iter()
        .filter_map(|k| {
            let m = default_mean(rows, &format!("profile-{k}-1"))?;
            Some(format!("a {k} {:.0}", m - base))
        })
        .collect();
    let longest: Vec<WorstTick> = ticks
        .iter()
        .map(|p| WorstTick {
            phase: format!("{}: {}", p.stage, p.tick.phase),
            ..p.tick.clone()
        })
        .collect();
    Ok(format!(
        "The haptic profile (protocol 5, `Mode::Profile`): the full tick with the damper (the\n\
         `full+damper` config and sweep: ±512 counts, two per tick, beyond the damper's dead band)\n\
         rendering a profile, loaded as `HostMsg::SetProfile` loads it (the main loop's validate\n\
         and compile, the table queued, `ServoCmd::Profile`). Every element spans the whole sweep, so\n\
         every element computes on every tick, its damper acting. `profile-detents-16` is the worst\n\
         profile a user can load (16 elements, the protocol's maximum, all detent trains: the\n\
         costliest element, a 64-bit phase and a sine; their sum passes the force limit on part of\n\
         the sweep, so the clamp's slow path runs too); the one-element stages measure each kind.\n\n\
         {}\n\
         {DEFAULT_NUMERIC}: each detent train adds {per:.1} instructions (from 1 to 16 trains; {per4:.1}\n\
         from 1 to 4), on a tick of {base:.1} without elements ({full:.1} for the config's wall with\n\
         the damper); one element of the other kinds adds {}. Budgets ({DEFAULT_NUMERIC},\n\
         enforced in CI): `{PROFILE_16}` ≤ {PROFILE_BUDGET} (its mean and its longest render\n\
         tick), the tick that takes it ≤ {PROFILE_TAKE_BUDGET}, a config applied in profile mode\n\
         ≤ {WORST_BUDGET} (the worst tick's budget).\n\n\
         Longest single ticks of one run per detent stage, each tick timed alone (the stand-ins\n\
         subtracted): the main loop loads the profile at tick 2 (`profile-take`: that tick takes\n\
         the table, {take:.0} for 16 trains, {copy:.0} more than its longest render tick:\n\
         the table's elements copied out of its queue's slot), changes the config at tick 1000 (K × 1.5, B × 0.5; `config-change`:\n\
         the gains derived in f64 and the profile rendered on the same tick, {config16:.0}) with the\n\
         profile compiled again for it and taken at tick 1001 (as the device's `SetConfig` does),\n\
         and renders it on the other 2095 ticks (`profile-tick`).\n\n{}\n\
         The main loop's validate + compile + queue (`BENCH-COMPILE`: timed around the bench's\n\
         `load`, as the device's `SetProfile` after decoding; f64 in software, preempted by the\n\
         servo), instructions:\n\n{}\n\
         {}",
        table_titled(rows, "profile (full tick + damper, profile mode)"),
        kinds.join(", "),
        worst_table(&longest),
        table_titled(compiles, "profile loaded (main loop)"),
        fit_text(base, per, config0),
    ))
}

/// The paragraph of how many detent trains fit on the nucleo-f446re at 10 and 20 kHz (see
/// [`elements_that_fit`]).
fn fit_text(base: f64, per: f64, config0: f64) -> String {
    let (fit10, cfg10) = elements_that_fit(10_000.0, base, per, config0);
    let (fit20, cfg20) = elements_that_fit(20_000.0, base, per, config0);
    let all = |n: u32| {
        if n >= 16 {
            "all 16 fit"
        } else {
            "not all 16 fit"
        }
    };
    let (all10, all20) = (all(fit10.min(cfg10)), all(fit20.min(cfg20)));
    format!(
        "Elements that fit on the nucleo-f446re (180 MHz, one cycle per instruction, plus\n\
         {NUCLEO_HANDLER_CYCLES} cycles of its TIM7 handler around the tick), keeping the mean\n\
         tick within half the period (the other half for the telemetry stream and the main loop)\n\
         and a config applied in profile mode within the whole period (at {per:.1} cycles per train,\n\
         {config0:.0} for the config tick without elements): at 10 kHz (18 000 cycles per tick) {all10}\n\
         (room for {fit10} by the mean, {cfg10} by the config tick); at 20 kHz (9000 cycles) {all20}\n\
         (room for {fit20} and {cfg20}: the config tick is the bound). A profile holds at most 16.\n\
         The nucleo-f446re's images stop at 10 kHz (`max_rate_hz`, firmware/boards/nucleo-f446re/\n\
         src/rig.rs: the 921 600-baud link cannot stream every sample above it); its 20 kHz figures\n\
         are the board emulator's, on the measurement images of feature `bench-20khz` (below).\n",
    )
}
