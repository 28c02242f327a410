//! `hostctl replay`: check a recording against the models it came from.
//!
//! (a) **Plant replay.** The recorded force codes are applied, each held for one servo period
//! T = 1/`config.servo_rate_hz` (ZOH), to the exact simulated plant
//! (`stiffwall_sim::rich::RichPlant`: a `--plant` scene file's plant, or m, b, c from
//! `--mass/--viscous/--coulomb`, a `--device`
//! preset, or the recording's virtual-device preset; Δ from the recorded `DeviceInfo`). Each
//! run of consecutive samples starts inside its first recorded count n₀ (raw counts), at
//! x₀ = (n₀ + f)·Δ with f the best of [`START_GRID`] positions in [0, 1) and v₀ the better of
//! the estimate from the first ≤ 10 samples and 0, judged on the first [`FIT_WINDOW`] samples
//! (the recording cannot say where inside a count the device was). The model's count
//! ⌊x/Δ⌋ after each period is compared with the next recorded count; the error is reported in
//! encoder ticks (raw counts), RMS and max. Needs decimation 1 (every tick's force).
//!
//! (b) **Servo replay.** The recorded encoder counts are fed, tick by tick, to the firmware's
//! own servo core (`stiffwall_firmware::Servo`, same fixed-point backend as the boards) built
//! from the recorded `DeviceInfo` (as `BoardInfo`) and the recorded `ServoConfig`, and its
//! force codes are compared bit for bit with the recorded ones. The supervisor is switched off
//! on the host (energy monitor, velocity, jump and heartbeat faults): whether the device was in
//! safe mode is read from the recorded flags instead. Comparable samples: decimation 1; not in
//! safe mode and not in an experiment's hold or excitation phase (those forces do not come from
//! the wall law); and at least `extra_delay_ticks + 1` samples after the start of each run of
//! consecutive samples and after any such excluded sample (the host servo's delay line and
//! velocity history must hold the same values as the device's). The configuration must not
//! have changed during the recording (`hostctl record` never changes it).
//!
//! (c) **Energy monitor.** The firmware's dissipation check (`stiffwall_core::monitor`) runs
//! over the recorded counts as the device ran it and reports each growth or limit event: tick,
//! count, the peak's energy, and whether the device latched there
//! ([`crate::monitor_report`]). Needs decimation 1.
//!
//! The engines and the report's text are `stiffwall_analysis::replay` (re-exported here), the
//! plant replay's figure `stiffwall_figures::plant_replay`; this module resolves the plant
//! flags and runs the command.
//!
//! Invariants: a corrupted file is an error naming the line and the column
//! (`stiffwall_client`'s recording format); nothing panics on bad input; a mismatch in (b) exits non-zero.

use crate::figure;
use crate::output::emit_report;
use crate::plant_args::{PlantArgs, PlantSpecError};
use anyhow::{anyhow, bail, Context, Result};
use std::path::PathBuf;
pub use stiffwall_analysis::replay::{
    board_of, render, replay_model, replay_plant, replay_servo, trailing_gap, Mismatch,
    PlantReplay, Report, ServoReplay, FIT_WINDOW, START_GRID,
};
use stiffwall_client::{read_recording, Recording};
use stiffwall_figures::plant_replay;
use stiffwall_sim::rich::PlantModel;

/// Arguments of `hostctl replay`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  hostctl replay wall.csv\n  hostctl replay wall.csv --device maxon-re35 --plot replay.svg\n  hostctl replay run.csv --mass 2.1e-5 --viscous 1e-5 --coulomb 2e-3 --json"
)]
pub struct Args {
    /// Recording made by `hostctl record`.
    pub file: PathBuf,
    /// Plant for (a): a preset (default: the recording's virtual-device preset, if any) and
    /// m, b, c overriding its fields.
    #[command(flatten)]
    pub plant: PlantArgs,
    /// Plant for (a) from a scene file (as `--plant` of the device commands: stiction,
    /// cogging, transmission, amplifier limit...), with --mass/--viscous/--coulomb overriding
    /// its fields; default: the recording's `--plant` file, if any.
    #[arg(long = "plant", value_name = "FILE.toml", conflicts_with = "device")]
    pub plant_file: Option<PathBuf>,
    /// Plot of recorded vs model position and the error (.svg or .png).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Plant for (a): a plant file (given, or the recording's when no plant flag is given) with the
/// flags' m, b, c overriding its fields, or else a preset (given or recorded) and the flags
/// (checked by core through [`PlantArgs`]). The resolution is the recording's.
fn plant_model(args: &Args, rec: &Recording) -> Result<(PlantModel, String)> {
    let delta = f64::from(rec.header.device.resolution);
    let recorded = rec.header.virtual_plant.as_deref();
    let recorded_file = recorded.and_then(|p| p.strip_prefix("plant:"));
    let file = args.plant_file.clone().map(|f| (f, false)).or_else(|| {
        (!args.plant.any())
            .then(|| recorded_file.map(|f| (PathBuf::from(f), true)))
            .flatten()
    });
    let Some((path, from_recording)) = file else {
        let preset = if recorded_file.is_some() {
            None
        } else {
            recorded
        };
        let f = args.plant.friction(preset).map_err(|e| match e {
            PlantSpecError::Incomplete => anyhow!("plant replay needs m, b and c: give --device NAME, --plant FILE or all of --mass, --viscous and --coulomb"),
            e => e.into(),
        })?;
        let model = PlantModel::rigid(f.mass, f.viscous, f.coulomb, delta)
            .map_err(|e| anyhow!("plant replay: {e}"))?;
        return Ok((model, f.source));
    };
    let text =
        std::fs::read_to_string(&path).map_err(|e| anyhow!("--plant {}: {e}", path.display()))?;
    let (mut model, _) = PlantModel::from_scene_toml(&text)
        .map_err(|e| anyhow!("--plant {}: {e}", path.display()))?;
    let mut src = vec![format!(
        "plant file {}{}",
        path.display(),
        if from_recording {
            " (from the recording)"
        } else {
            ""
        }
    )];
    let (m, b, c) = args.plant.overrides()?;
    for (flag, v, field) in [
        ("--mass", m, &mut model.mass_kg),
        ("--viscous", b, &mut model.viscous_ns_per_m),
        ("--coulomb", c, &mut model.coulomb_n),
    ] {
        if let Some(v) = v {
            *field = v;
            src.push(flag.to_string());
        }
    }
    model.resolution_m = delta;
    model.validate().map_err(|e| anyhow!("plant replay: {e}"))?;
    Ok((model, src.join(" + ")))
}

/// All three replays of a parsed recording, the plant of (a) from `args` (an error there is
/// the command's only when a plant flag was given).
///
/// # Errors
/// A plant flag out of range, or a plant file that cannot be read.
pub fn replay(args: &Args, rec: &Recording) -> Result<Report> {
    let plant = match plant_model(args, rec) {
        Err(e) if args.plant.any() || args.plant_file.is_some() => return Err(e),
        Err(e) => Err(format!("{e:#}")),
        Ok(p) => Ok(p),
    };
    Ok(stiffwall_analysis::replay::replay(rec, plant))
}

/// Runs `hostctl replay`.
pub fn run(args: &Args) -> Result<()> {
    if let Some(path) = &args.plot {
        figure::format_of(path)?;
    }
    let rec = read_recording(&args.file)?;
    if rec.rows.is_empty() {
        bail!("{}: the recording holds no samples", args.file.display());
    }
    let mut report = replay(args, &rec)?;
    // Samples lost at the end of a recording have no row after them: only their gap note.
    let text = std::fs::read_to_string(&args.file)
        .with_context(|| format!("reading {}", args.file.display()))?;
    report.missing += trailing_gap(&text);
    if let (Some(path), Some(p)) = (&args.plot, &report.plant) {
        figure::write(path, plant_replay::SIZE_PX, &plant_replay::PlantFigure(p))?;
    } else if args.plot.is_some() {
        bail!(
            "--plot needs the plant replay, which did not run: {}",
            report.plant_skipped.as_deref().unwrap_or("unknown reason")
        );
    }
    emit_report(args.json, &report, |r| render(&args.file, r))?;
    if let Some(v) = &report.servo {
        if v.mismatch_count > 0 {
            bail!(
                "servo replay: {} of {} comparable force codes differ from the recording (first at seq {})",
                v.mismatch_count,
                v.compared,
                v.mismatches.first().map_or(0, |m| m.seq)
            );
        }
    }
    Ok(())
}
