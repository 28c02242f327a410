//! `cargo xtask bench-firmware [--no-write]`: instructions per servo tick on the QEMU image.
//!
//! Runs `stiffwall-qemu-an386-bench` under `qemu-system-arm -icount shift=0` (deterministic:
//! one virtual ns per instruction, SysTick one count per 40 instructions), parses its
//! `BENCH <stage> <numeric> <instructions ×100>` lines, prints a table, writes it into
//! `docs/BENCHMARKS.md` between the `firmware-icount` markers, and fails when the default
//! back-end (I32F32) exceeds the full-tick budget of 150 instructions (with B = 0 or with the
//! damper on, its default dead band of one count, at two counts per tick so that the damper
//! acts on every tick) or the spring stage's budget of 31 (see docs/BENCHMARKS.md).

use crate::firmware::{root, IMAGES};
use crate::{toolchain, update_section};
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use std::process::Command;

/// Budget of the spring stage, instructions per tick (29.0 measured + 10 %, rounded down).
pub const SPRING_BUDGET: f64 = 31.0;
/// Budget of the full tick, with and without the damper, instructions per tick (135.3
/// measured with B = 0, 147.2 with B > 0 and the damper acting on every tick; was 157 with
/// 142.3 and 153.3 before the damper law and the tick's `halt` word).
pub const FULL_BUDGET: f64 = 150.0;
const DEFAULT_NUMERIC: &str = "I32F32";
/// The full tick's stage name in the bench output (B = 0).
const FULL: &str = "full(+telemetry)";
/// The full tick with the virtual damper on (B > 0, the default law: a dead band of one count)
/// and a sweep of two counts per tick, beyond the dead band; one word (the bench output is split
/// on whitespace).
const FULL_DAMPED: &str = "full+damper";

/// Builds and runs the bench image; returns (stage, numeric, instructions per tick).
pub fn measure() -> Result<Vec<(String, String, f64)>> {
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
            "shift=0",
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
    let rows: Vec<(String, String, f64)> = stdout
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            match f.as_slice() {
                ["BENCH", stage, numeric, v] if *stage != "baseline" => Some((
                    (*stage).into(),
                    (*numeric).into(),
                    v.parse::<f64>().ok()? / 100.0,
                )),
                _ => None,
            }
        })
        .collect();
    if rows.is_empty() {
        bail!("bench image printed no results:\n{stdout}");
    }
    Ok(rows)
}

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
    let rows = measure()?;
    let t = table(&rows);
    let get = |stage: &str| {
        rows.iter()
            .find(|r| r.0 == stage && r.1 == DEFAULT_NUMERIC)
            .map(|r| r.2)
    };
    let damper = match (get(FULL_DAMPED), get(FULL)) {
        (Some(d), Some(f)) => format!(
            "The virtual damper (B > 0, `{FULL_DAMPED}`: the same two-sided wall, its default law (a dead\n\
             band of one count) and a sweep of two counts per tick, so that the damper term is computed\n\
             on every tick) adds {:.1} instructions to the full tick ({DEFAULT_NUMERIC}: {f:.1} with B = 0, {d:.1} with B > 0).\n",
            d - f
        ),
        _ => bail!("the bench printed no damper figure for {DEFAULT_NUMERIC}"),
    };
    println!(
        "Instructions per servo tick (QEMU -icount shift=0, mps2-an386, release build):\n\n{t}\n{damper}"
    );
    if write {
        let body = format!(
            "Instructions per servo tick on the QEMU image, measured by `cargo xtask bench-firmware`\n\
             (`qemu-system-arm -icount shift=0`: one instruction per virtual ns; SysTick read around\n\
             batches of 200 ticks, 8000 ticks per stage, the empty loop subtracted). Stages are\n\
             cumulative; the full tick adds the command queue and the telemetry push. Each stage is\n\
             its own function, called once per tick as the servo interrupt calls `Servo::tick`,\n\
             so its count depends on the servo's code only. The call, the return and the bench's\n\
             encoder and output stand-ins are measured the same way (`io-stand-ins`) and\n\
             subtracted; on hardware the stand-ins are one register load and one store. Budgets for the default back-end\n\
             ({DEFAULT_NUMERIC}): full tick ≤ {FULL_BUDGET} (with B = 0 and with the damper), spring ≤ {SPRING_BUDGET} (enforced in CI).\n\n{t}\n{damper}"
        );
        update_section(&root().join("docs/BENCHMARKS.md"), "firmware-icount", &body)?;
    }
    match get("spring") {
        Some(v) if v > SPRING_BUDGET => {
            bail!("spring stage over its instruction budget: {v:.1} > {SPRING_BUDGET}")
        }
        Some(_) => {}
        None => bail!("the bench printed no spring figure for {DEFAULT_NUMERIC}"),
    }
    for stage in [FULL, FULL_DAMPED] {
        match get(stage) {
            Some(v) if v > FULL_BUDGET => {
                bail!("servo tick over its instruction budget: {stage} {v:.1} > {FULL_BUDGET}")
            }
            Some(_) => {}
            None => bail!("the bench printed no {stage} figure for {DEFAULT_NUMERIC}"),
        }
    }
    Ok(())
}
