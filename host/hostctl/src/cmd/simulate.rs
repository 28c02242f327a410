//! `hostctl simulate`: simulate one scene file and write the trajectory as CSV.
//!
//! Units: dimensionless (Table I) in the CSV: `period` (τ = h), `xi` (ticks), `xidot` (ticks per
//! period), `phi_a` (K·Δ, force applied from that instant), `h_t` (H_T of eq. (35), K·Δ²), and
//! the energy audit of the period ending at that instant: `e_d` (28), `e_g` (29), `residual` of
//! the balance (26). Physical scenes are converted to these units when loaded. Standard error
//! gets the one-screen summary (`stiffwall_analysis::scene_summary`): the verdict by the rest
//! rule and the energy audit, in K·Δ² (and J for a physical scene).

use crate::figure;
use anyhow::{Context, Result};
use std::io::Write;
use std::path::{Path, PathBuf};
use stiffwall_analysis::scene_summary::SceneSummary;
use stiffwall_figures::trajectory;
use stiffwall_sim::scene::{Row, Scene};

/// Arguments of `hostctl simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene file (TOML, see sim/scenes/).
    pub scene: PathBuf,
    /// CSV output file (default: standard output).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Also draw ξ(τ), H_T(τ) and the energy audit (E_d, E_g, residual) to this figure file
    /// (.svg or .png).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Write every n-th sample only (the audit columns still cover the last period only).
    #[arg(long, default_value_t = 1)]
    pub every: u64,
}

/// Loads a scene file, with the file name in the error.
pub fn load(path: &Path) -> Result<Scene> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Scene::from_toml(&text).with_context(|| format!("scene {}", path.display()))
}

fn write_row(w: &mut dyn Write, r: &Row) -> std::io::Result<()> {
    writeln!(
        w,
        "{},{},{},{},{},{},{},{}",
        r.period, r.xi, r.xidot, r.phi_a, r.h_t, r.e_d, r.e_g, r.residual
    )
}

/// Runs `hostctl simulate`.
///
/// # Errors
/// A bad flag or scene, an unwritable `--out`/`--plot` (before the run), a write error, or a
/// diverged trajectory (reported after the rows up to the divergence are written).
pub fn run(args: &Args) -> Result<()> {
    anyhow::ensure!(
        args.every >= 1,
        "--every {}: allowed range is >= 1",
        args.every
    );
    if let Some(p) = &args.plot {
        figure::prepare(p)?;
    }
    let scene = load(&args.scene)?;
    let mut w: Box<dyn Write> = match &args.out {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("creating {}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
    };
    writeln!(w, "period,xi,xidot,phi_a,h_t,e_d,e_g,residual")?;
    let mut rows: Vec<Row> = Vec::new();
    let keep = args.plot.is_some();
    let mut io_err = None;
    let mut last: Option<(Row, bool)> = None;
    let mut summary = SceneSummary::new(&scene);
    scene.simulate(&mut |r: &Row| {
        summary.add(r);
        let written = r.period.is_multiple_of(args.every);
        last = Some((*r, written));
        if !written || io_err.is_some() {
            return;
        }
        if let Err(e) = write_row(&mut *w, r) {
            io_err = Some(e);
        }
        if keep {
            rows.push(*r);
        }
    })?;
    if let Some(e) = io_err {
        return Err(e.into());
    }
    // The last row is always written, whatever --every.
    if let Some((r, false)) = last {
        write_row(&mut *w, &r)?;
        if keep {
            rows.push(r);
        }
    }
    w.flush()?;
    if let Some(p) = &args.plot {
        let name = args.scene.display().to_string();
        let fig = trajectory::Trajectory {
            rows: &rows,
            name: &name,
        };
        figure::write(p, trajectory::SIZE_PX, &fig)?;
    }
    let joules = scene
        .rich
        .map(|r| r.controller.stiffness_n_per_m * r.model.resolution_m.powi(2));
    eprint!("{}", summary.render(joules));
    if let Some((r, _)) = last {
        anyhow::ensure!(
            r.period >= scene.periods,
            "the trajectory diverged at period {} of {} (xi = {:.3e}, xidot = {:.3e}); the rows \
             up to there are written",
            r.period,
            scene.periods,
            r.xi,
            r.xidot
        );
    }
    Ok(())
}
