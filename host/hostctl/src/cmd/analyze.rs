//! `hostctl analyze`: the paper's analysis of one device ([`crate::analysis`]) from a preset
//! and/or flags, as a table, JSON, and a (β, σ) figure (with `--damping`, also the (K, B)
//! frontier figure `<stem>-kb.<ext>`). Without `--stiffness` (on a preset too) it answers "how
//! stiff can my device go" ([`crate::analysis::stiffest`]): the device's limits and the
//! stiffest wall they predict, spring only and with the best damper, capped by the quiet
//! ceiling; its figures are drawn at the predicted wall (at `--damping B` when given). With
//! `--stiffness K` it is the report at K (on a preset, `--stiffness` with the preset's own K
//! gives the report at it).
//!
//! Units: command-line values are SI (kg, N·s/m, N, m, s, N/m, m/s, m/s²; with `--rotational`
//! kg·m², N·m·s/rad, N·m, rad, N·m/rad, rad/s, rad/s²).
//!
//! Invariants: every physical flag is checked against its one range of
//! `stiffwall_sim::scene::field_bounds` (the plant flags through [`PlantArgs`]), the same range
//! and message as the plant file's key, then by `stiffwall-core`; bad input is an error naming
//! the field and its allowed range, and nothing is written.

use crate::analysis::damping::{self, damping_report};
use crate::analysis::stiffest::{self, Stiffest};
use crate::analysis::{analyze, kb_plot, list_devices, plot, render_table};
use crate::output::{emit, emit_report};
use crate::plant_args::PlantArgs;
use anyhow::{anyhow, bail, Context};
use std::fmt::Write as _;
use std::path::PathBuf;
use stiffwall_core::params::resolution_from_counts_per_rev;
use stiffwall_core::{devices, ParamError, PhysicalParams};
use stiffwall_sim::scene::field_bounds::{
    FieldBounds, COULOMB, COUNTS_PER_REV, MASS, PERIOD, RESOLUTION, STIFFNESS, VELOCITY, VISCOUS,
};

/// Arguments of `hostctl analyze`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Without --stiffness: how stiff a wall the device can hold (spring only and with the best damper, capped by the quiet ceiling 2c/Δ). With --stiffness K: the report at K (on a preset, its own K is in --list-devices).\n\nExamples:\n  hostctl analyze --device phantom-1.0\n  hostctl analyze --device phantom-1.0 --stiffness 1015\n  hostctl analyze --device omega --stiffness 8000 --velocity 0.05 --json\n  hostctl analyze --device phantom-1.0 --stiffness 1015 --damping 2\n  hostctl analyze --mass 0.1 --viscous 0.01 --coulomb 0.05 --resolution 2e-5 --period 1e-3 --stiffness 2000 --plot wall.svg"
)]
pub struct Args {
    /// Plant: preset and m, b, c.
    #[command(flatten)]
    pub plant: PlantArgs,
    /// List the presets and exit.
    #[arg(long)]
    pub list_devices: bool,
    /// Encoder resolution Δ [m, or rad], > 0.
    #[arg(long, allow_hyphen_values = true, conflicts_with = "counts_per_rev")]
    pub resolution: Option<f64>,
    /// Rotary encoder counts per revolution (Δ = 2π/N rad); rotational devices only.
    #[arg(long, allow_hyphen_values = true)]
    pub counts_per_rev: Option<f64>,
    /// Sampling period T [s], > 0.
    #[arg(long, allow_hyphen_values = true)]
    pub period: Option<f64>,
    /// Virtual wall stiffness K [N/m, or N·m/rad]: the report at K. Without it (on a preset
    /// too): how stiff a wall the device can hold.
    #[arg(long, allow_hyphen_values = true)]
    pub stiffness: Option<f64>,
    /// Extra loop delay T_D (amplifier + computation, excluding the ZOH) [s], >= 0.
    #[arg(long, allow_hyphen_values = true)]
    pub delay: Option<f64>,
    /// Maximum velocity |ẋ| the user reaches [m/s, or rad/s], >= 0.
    #[arg(long, allow_hyphen_values = true)]
    pub velocity: Option<f64>,
    /// Maximum acceleration |ẍ| [m/s², or rad/s²], >= 0 (delayed criterion (19)).
    #[arg(long, allow_hyphen_values = true)]
    pub acceleration: Option<f64>,
    /// Rotational device: angles, torques and inertia instead of positions, forces and mass.
    #[arg(long)]
    pub rotational: bool,
    /// Virtual damping B of the wall [N·s/m, or N·m·s/rad], finite and >= 0: adds the spring +
    /// damper analysis (exact linear K_max(B), closed forms, frontier over B, best B).
    #[arg(long, allow_hyphen_values = true)]
    pub damping: Option<f64>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Write the (β, σ) plane with regions, operating point and K path (.svg or .png); with
    /// `--damping`, also the (K, B) frontier beside it as `<stem>-kb.<ext>`.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
}

/// Runs `hostctl analyze`.
///
/// # Errors
/// Bad or missing input (message names the field and allowed range), or a plot write error.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.list_devices {
        return Ok(emit(&list_devices())?);
    }
    let (name, p) = resolve_params(args)?;
    if let Some(path) = &args.plot {
        crate::figure::prepare(path)?;
        if args.damping.is_some() {
            crate::figure::prepare(&kb_plot::kb_path(path))?;
        }
    }
    if args.stiffness.is_none() {
        return run_stiffest(args, name, &p);
    }
    let mut report = analyze(name, &p, args.velocity, args.acceleration)?;
    if let Some(b) = args.damping {
        report.damping = Some(damping_report(&p, b)?);
    }
    let written = draw(args, &p)?;
    Ok(emit_report(args.json, &report, |r| {
        let mut s = render_table(r);
        written_lines(&mut s, args, written.as_ref());
        s
    })?)
}

/// `analyze` without `--stiffness`: the device's limits; the figures at the predicted wall.
fn run_stiffest(args: &Args, name: Option<String>, p: &PhysicalParams) -> anyhow::Result<()> {
    let r = stiffest::stiffest(name, p, args.velocity, args.damping)?;
    let drawn = match args.plot {
        Some(_) => {
            let k = plot_stiffness(&r)?;
            Some((k, draw(args, &p.with_stiffness(k))?))
        }
        None => None,
    };
    Ok(emit_report(args.json, &r, |r| {
        let mut s = stiffest::render(r);
        if let Some((k, kb)) = &drawn {
            let _ = writeln!(
                s,
                "figures drawn at the predicted wall K = {k:.4e} {}{}",
                r.units.k,
                args.damping
                    .map_or_else(String::new, |b| format!(", B = {b:.4e} {}", r.units.b))
            );
            written_lines(&mut s, args, kb.as_ref());
        }
        s
    })?)
}

/// The K the figures of the report without `--stiffness` are drawn at: the predicted wall at
/// `--damping B`, else the spring-only one.
fn plot_stiffness(r: &Stiffest) -> anyhow::Result<f64> {
    let k = r
        .at_damping
        .as_ref()
        .map(|d| d.k_predicted)
        .filter(|&k| k > 0.0)
        .unwrap_or(r.spring_only.k_predicted);
    if k > 0.0 && k.is_finite() {
        Ok(k)
    } else {
        bail!(
            "no wall is predicted to come to rest (quiet ceiling {:.4e} {}), so there is no \
             operating point to draw: give --stiffness K to plot the report at K",
            r.quiet_ceiling,
            r.units.k
        )
    }
}

/// The (β, σ) figure of `p` (with its damper, when `--damping` is given) and, with
/// `--damping`, the (K, B) frontier beside it; the frontier file when one was written.
fn draw(args: &Args, p: &PhysicalParams) -> anyhow::Result<Option<PathBuf>> {
    let Some(path) = &args.plot else {
        return Ok(None);
    };
    let mut report = analyze(
        args.plant.device.clone(),
        p,
        args.velocity,
        args.acceleration,
    )?;
    report.damping = args.damping.map(|b| damping_report(p, b)).transpose()?;
    plot::write(path, &report).with_context(|| format!("writing plot {}", path.display()))?;
    let Some(d) = &report.damping else {
        return Ok(None);
    };
    let kb_file = kb_plot::kb_path(path);
    let f = damping::figure(d, p, report.device.as_deref());
    kb_plot::write(&kb_file, &f).with_context(|| format!("writing plot {}", kb_file.display()))?;
    Ok(Some(kb_file))
}

fn written_lines(s: &mut String, args: &Args, kb: Option<&PathBuf>) {
    if let Some(path) = &args.plot {
        let _ = writeln!(s, "plot written to {}", path.display());
    }
    if let Some(path) = kb {
        let _ = writeln!(s, "(K, B) frontier plot written to {}", path.display());
    }
}

fn missing(flag: &str, allowed: &str) -> anyhow::Error {
    anyhow!(
        "missing --{flag} (must be {allowed}); give it or start from --device NAME ({})",
        devices::NAMES
    )
}

/// A refused flag, its value written as `{:?}` (`1e300`, not 301 digits).
fn readable(e: ParamError) -> anyhow::Error {
    anyhow!("{} must be {} (got {:?})", e.name(), e.allowed(), e.value())
}

/// A flag checked against its field's range ([`FieldBounds`]).
fn flag(
    name: &'static str,
    value: Option<f64>,
    bounds: &FieldBounds,
    rotational: bool,
) -> anyhow::Result<Option<f64>> {
    value
        .map(|v| bounds.check(name, v, rotational).map_err(readable))
        .transpose()
}

/// Builds the physical parameters from a preset and/or flags, and validates them: every flag
/// against its field's range, then the whole by core. The stiffness is `--stiffness`, else 1
/// (not used by the report without `--stiffness`).
///
/// # Errors
/// Unknown device, missing field, or a field out of range (named, with its allowed range).
pub fn resolve_params(args: &Args) -> anyhow::Result<(Option<String>, PhysicalParams)> {
    let preset = args.plant.preset()?;
    let (mass, viscous, coulomb) = args.plant.overrides()?;
    let rotational = args.rotational || preset.is_some_and(|d| d.params.rotational);
    let resolution = match (args.resolution, args.counts_per_rev) {
        (Some(r), _) => flag("--resolution", Some(r), &RESOLUTION, rotational)?,
        (None, Some(n)) => {
            if !rotational {
                bail!("--counts-per-rev applies to rotational devices only; add --rotational or give --resolution [m]");
            }
            let n = COUNTS_PER_REV
                .check("--counts-per-rev", n, true)
                .map_err(readable)?;
            Some(resolution_from_counts_per_rev(n)?)
        }
        (None, None) => preset.map(|d| d.params.resolution),
    };
    let pick = |flag: Option<f64>, preset_val: Option<f64>| flag.or(preset_val);
    let pp = preset.map(|d| d.params);
    let mass = pick(mass, pp.map(|p| p.mass)).ok_or_else(|| missing("mass", MASS.allowed))?;
    let viscous =
        pick(viscous, pp.map(|p| p.viscous)).ok_or_else(|| missing("viscous", VISCOUS.allowed))?;
    let coulomb =
        pick(coulomb, pp.map(|p| p.coulomb)).ok_or_else(|| missing("coulomb", COULOMB.allowed))?;
    let resolution = resolution.ok_or_else(|| missing("resolution", RESOLUTION.allowed))?;
    let period = pick(
        flag("--period", args.period, &PERIOD, rotational)?,
        pp.map(|p| p.period_s),
    )
    .ok_or_else(|| missing("period", PERIOD.allowed))?;
    let delay = args
        .delay
        .map(|d| FieldBounds::check_delay("--delay", d, Some(period)).map_err(readable))
        .transpose()?;
    let stiffness = flag("--stiffness", args.stiffness, &STIFFNESS, rotational)?;
    flag("--velocity", args.velocity, &VELOCITY, rotational)?;
    if let Some(b) = args.damping {
        FieldBounds::check_damping("--damping", b, rotational, stiffness.map(|k| k * period))
            .map_err(readable)?;
    }
    let p = PhysicalParams {
        mass,
        viscous,
        coulomb,
        resolution,
        period_s: period,
        stiffness: stiffness.unwrap_or(1.0),
        delay_s: pick(delay, pp.map(|p| p.delay_s)).unwrap_or(0.0),
        rotational,
    };
    let p = p.validate()?;
    Ok((args.plant.device.clone(), p))
}
