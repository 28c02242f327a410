//! `hostctl analyze`: the paper's analysis of one device ([`crate::analysis`]) from a preset
//! and/or flags, as a table, JSON, and a (β, σ) figure (with `--damping`, also the (K, B)
//! frontier figure `<stem>-kb.<ext>`).
//!
//! Units: command-line values are SI (kg, N·s/m, N, m, s, N/m, m/s, m/s²; with `--rotational`
//! kg·m², N·m·s/rad, N·m, rad, N·m/rad, rad/s, rad/s²).
//!
//! Invariants: every number from the command line is validated by `stiffwall-core` (the plant
//! flags through [`PlantArgs`]); bad input is an error naming the field and its allowed range,
//! and nothing is written.

use crate::analysis::damping::{self, damping_report};
use crate::analysis::{analyze, kb_plot, list_devices, plot, render_table};
use crate::output::{emit, emit_report};
use crate::plant_args::PlantArgs;
use anyhow::{anyhow, bail, Context};
use std::fmt::Write as _;
use std::path::PathBuf;
use stiffwall_core::params::resolution_from_counts_per_rev;
use stiffwall_core::{devices, PhysicalParams};

/// Arguments of `hostctl analyze`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  hostctl analyze --device phantom-1.0\n  hostctl analyze --device omega --stiffness 8000 --velocity 0.05 --json\n  hostctl analyze --device phantom-1.0 --damping 2\n  hostctl analyze --mass 0.1 --viscous 0.01 --coulomb 0.05 --resolution 2e-5 --period 1e-3 --stiffness 2000 --plot wall.svg"
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
    /// Virtual wall stiffness K [N/m, or N·m/rad], > 0.
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
    if let Some(b) = args.damping {
        let unit = if args.rotational {
            "N·m·s/rad"
        } else {
            "N·s/m"
        };
        stiffwall_core::criteria::check_damping(b)
            .map_err(|e| anyhow!("--damping [{unit}]: {e}"))?;
    }
    if let Some(path) = &args.plot {
        crate::figure::prepare(path)?;
        if args.damping.is_some() {
            crate::figure::prepare(&kb_plot::kb_path(path))?;
        }
    }
    let (name, p) = resolve_params(args)?;
    let mut report = analyze(name, &p, args.velocity, args.acceleration)?;
    if let Some(b) = args.damping {
        report.damping = Some(damping_report(&p, b)?);
    }
    let mut kb = None;
    if let Some(path) = &args.plot {
        plot::write(path, &report).with_context(|| format!("writing plot {}", path.display()))?;
        if let Some(d) = &report.damping {
            let kb_file = kb_plot::kb_path(path);
            let f = damping::figure(d, &p, report.device.as_deref());
            kb_plot::write(&kb_file, &f)
                .with_context(|| format!("writing plot {}", kb_file.display()))?;
            kb = Some(kb_file);
        }
    }
    Ok(emit_report(args.json, &report, |r| {
        let mut s = render_table(r);
        if let Some(path) = &args.plot {
            let _ = writeln!(s, "plot written to {}", path.display());
        }
        if let Some(path) = &kb {
            let _ = writeln!(s, "(K, B) frontier plot written to {}", path.display());
        }
        s
    })?)
}

fn missing(flag: &str, unit: &str, range: &str) -> anyhow::Error {
    anyhow!(
        "missing --{flag} [{unit}] (must be {range}); give it or start from --device NAME ({})",
        devices::NAMES
    )
}

/// Builds the physical parameters from a preset and/or flags, and validates them.
///
/// # Errors
/// Unknown device, missing field, or a field out of range (named, with its allowed range).
pub fn resolve_params(args: &Args) -> anyhow::Result<(Option<String>, PhysicalParams)> {
    let preset = args.plant.preset()?;
    let (mass, viscous, coulomb) = args.plant.overrides()?;
    let rotational = args.rotational || preset.is_some_and(|d| d.params.rotational);
    let resolution = match (args.resolution, args.counts_per_rev) {
        (Some(r), _) => Some(r),
        (None, Some(n)) => {
            if !rotational {
                bail!("--counts-per-rev applies to rotational devices only; add --rotational or give --resolution [m]");
            }
            Some(resolution_from_counts_per_rev(n)?)
        }
        (None, None) => preset.map(|d| d.params.resolution),
    };
    let pick = |flag: Option<f64>, preset_val: Option<f64>| flag.or(preset_val);
    let pp = preset.map(|d| d.params);
    let unit = |l: &'static str, r: &'static str| if rotational { r } else { l };
    let p = PhysicalParams {
        mass: pick(mass, pp.map(|p| p.mass))
            .ok_or_else(|| missing("mass", unit("kg", "kg·m²"), "finite and > 0"))?,
        viscous: pick(viscous, pp.map(|p| p.viscous))
            .ok_or_else(|| missing("viscous", unit("N·s/m", "N·m·s/rad"), "finite and >= 0"))?,
        coulomb: pick(coulomb, pp.map(|p| p.coulomb))
            .ok_or_else(|| missing("coulomb", unit("N", "N·m"), "finite and >= 0"))?,
        resolution: resolution
            .ok_or_else(|| missing("resolution", unit("m", "rad"), "finite and > 0"))?,
        period_s: pick(args.period, pp.map(|p| p.period_s))
            .ok_or_else(|| missing("period", "s", "finite and > 0"))?,
        stiffness: pick(args.stiffness, pp.map(|p| p.stiffness))
            .ok_or_else(|| missing("stiffness", unit("N/m", "N·m/rad"), "finite and > 0"))?,
        delay_s: pick(args.delay, pp.map(|p| p.delay_s)).unwrap_or(0.0),
        rotational,
    };
    let p = p.validate()?;
    Ok((args.plant.device.clone(), p))
}
