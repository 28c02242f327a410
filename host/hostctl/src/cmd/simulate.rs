//! `hostctl simulate`: simulate one scene file and write the trajectory as CSV.
//!
//! Units: dimensionless (Table I) in the CSV: `period` (τ = h), `xi` (ticks), `xidot` (ticks per
//! period), `phi_a` (K·Δ, force applied from that instant), `h_t` (H_T of eq. (35), K·Δ²), and
//! the energy audit of the period ending at that instant: `e_d` (28), `e_g` (29), `residual` of
//! the balance (26). Physical scenes are converted to these units when loaded. Standard error
//! gets the one-screen summary (`stiffwall_analysis::scene_summary`): the verdict by the rest
//! rule and the energy audit, in K·Δ² (and J for a physical scene).
//!
//! With `--profile FILE` (a haptic profile, `profiles/README.md`) the scene's plant renders the
//! profile instead of the scene's single wall: the scene file is the virtual device's plant file
//! (as `hostctl profile simulate --plant` reads one: `[device]`, `[effects]`, `[controller]`'s
//! period and delay), the profile is lowered for that device, and the firmware's own servo runs
//! it against the plant (`stiffwall_analysis::profile_run`) from the scene's `[initial]`
//! (`position_m`, `velocity_m_per_s`; a plant file without `[initial]` or `[controller]`: at rest
//! at its start position) for `[run] periods` servo ticks (a file without `[run]`: 60 natural
//! periods of the profile's stiffest element, at least 20 000 ticks). The CSV is then in SI
//! units, one row per servo tick: `tick`, `t_s` (s), `count` (raw encoder count), `position` (m
//! or rad), `velocity` (m/s or rad/s) and `force` (the force the servo commands from that
//! instant for one tick, N or N·m). Standard error gets the start, where the run came to rest
//! (the project's rest rule over the run, with the natural period of the stiffest element; where
//! by `profile_run::rest_place`) and the faults. Invariants: a dimensionless scene is refused (a
//! profile's positions and gains are physical), as is a profile of the other axis or a bad
//! profile file (the library's message: element, key, range), before any row is written; a run
//! that does not come to rest where the profile holds the device (a fault, no rest, or inside a
//! detent train at no minimum) is an error (exit code 2) after all its rows are written;
//! `--plot` is refused with `--profile`.

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
    /// Render this haptic profile file (profiles/README.md) on the scene's plant with the
    /// firmware's servo, in place of the scene's wall (physical scenes only; SI columns).
    #[arg(long, value_name = "FILE.toml")]
    pub profile: Option<PathBuf>,
}

/// Loads a scene file, with the file name in the error.
pub fn load(path: &Path) -> Result<Scene> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Scene::from_toml(&text).with_context(|| format!("scene {}", path.display()))
}

/// The CSV's destination: `out`, or standard output.
fn writer(out: Option<&Path>) -> Result<Box<dyn Write>> {
    Ok(match out {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("creating {}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
    })
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
    if let Some(profile) = &args.profile {
        return run_profile(args, profile);
    }
    if let Some(p) = &args.plot {
        figure::prepare(p)?;
    }
    let scene = load(&args.scene)?;
    let mut w = writer(args.out.as_deref())?;
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

/// Where a profile's run on a scene's plant starts and how long it lasts.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ProfileStart {
    /// Position, m (rad).
    position: f64,
    /// Velocity, m/s (rad/s).
    velocity: f64,
    /// `[run] periods` (servo ticks), when the file has a `[run]`.
    periods: Option<u64>,
}

/// The start of a profile's run on the scene at `path` (text `text`): a physical scene's
/// `[initial]` and `[run] periods`, or a plant file's start position at rest (no `[run]`).
///
/// # Errors
/// A dimensionless scene (why, and what to give instead), or neither a scene nor a plant file
/// (the scene's error).
fn profile_start(path: &Path, text: &str) -> Result<ProfileStart> {
    let scene = match Scene::from_toml(text) {
        Ok(s) => s,
        Err(scene_error) => {
            // A plant file (`[controller]`, `[initial]` or `[run]` omitted) starts at rest.
            let (_, _, position) =
                stiffwall_sim::rich::PlantModel::from_scene_toml_with_start(text)
                    .map_err(|_| scene_error)
                    .with_context(|| format!("scene {}", path.display()))?;
            return Ok(ProfileStart {
                position,
                velocity: 0.0,
                periods: None,
            });
        }
    };
    let Some(rich) = scene.rich else {
        anyhow::bail!(
            "--profile: scene {} is dimensionless (mu, beta, sigma): a profile's positions, \
             stiffnesses and damping are physical (m or rad, N/m, N·s/m) and need the device's \
             mass, friction and resolution; give a physical scene (mass_kg, resolution_m, … as \
             sim/scenes/phantom-physical.toml) or a plant file (sim/plants/*.toml)",
            path.display()
        );
    };
    let delta = rich.model.resolution_m;
    Ok(ProfileStart {
        position: scene.init.x * delta,
        velocity: scene.init.v * delta / rich.controller.period_s,
        periods: Some(scene.periods),
    })
}

/// The natural period 2π√(m/K) of the profile's stiffest element on `spec`'s plant, servo
/// ticks (+∞ when no element has a stiffness: a viscous zone alone).
fn stiffest_natural_ticks(
    spec: &stiffwall_client::VirtualSpec,
    wire: &stiffwall_proto::Profile,
) -> f64 {
    let p = &spec.plant;
    let k = wire
        .elements
        .iter()
        .map(|e| stiffwall_analysis::profile_run::local_k(e, p.resolution))
        .fold(0.0, f64::max);
    core::f64::consts::TAU * (p.mass / k).sqrt() / p.period_s
}

/// A profile run's length, servo ticks: the scene's `[run] periods`, or 60 natural periods
/// (`natural`, ticks) and at least 20 000 ticks (a plant file without `[run]`).
fn profile_ticks(periods: Option<u64>, natural: f64) -> Result<usize> {
    Ok(match periods {
        Some(n) => usize::try_from(n)?,
        None if natural.is_finite() => {
            ((stiffwall_core::rest::REST_RUN_NATURAL_PERIODS * natural).ceil() as usize).max(20_000)
        }
        None => 20_000,
    })
}

/// One CSV row of a profile's run (module header).
fn write_profile_row(
    w: &mut dyn Write,
    tick: usize,
    period_s: f64,
    count: i64,
    s: &stiffwall_analysis::profile_run::Sample,
) -> std::io::Result<()> {
    writeln!(
        w,
        "{tick},{:e},{count},{:e},{:e},{:e}",
        tick as f64 * period_s,
        s.position,
        s.velocity,
        s.force
    )
}

/// `hostctl simulate SCENE --profile FILE` (module header).
///
/// # Errors
/// `--plot` given, a dimensionless scene, a bad scene or profile file, a profile of the other
/// axis, the device refusing the profile, a write error; after the rows, a run that does not
/// come to rest where the profile holds the device.
fn run_profile(args: &Args, profile_path: &Path) -> Result<()> {
    use stiffwall_analysis::profile_run::{run_traced, Sample, Start};
    anyhow::ensure!(
        args.plot.is_none(),
        "--plot draws the dimensionless trajectory of the scene's wall; with --profile the CSV \
         is in SI units (tick,t_s,count,position,velocity,force): write it with --out and plot \
         it from there"
    );
    anyhow::ensure!(
        args.every >= 1,
        "--every {}: allowed range is >= 1",
        args.every
    );
    let text = std::fs::read_to_string(&args.scene)
        .with_context(|| format!("reading {}", args.scene.display()))?;
    let start = profile_start(&args.scene, &text)?;
    let file = super::profile::read_file(profile_path)?;
    let spec = stiffwall_client::ConnectSpec::plant_file(&args.scene, stiffwall_client::Pace::Fast)
        .virtual_spec()?
        .context("the scene's virtual device")?;
    let (wire, device) = super::profile::lower_for_spec(&file, profile_path, &spec)?;
    let natural = stiffest_natural_ticks(&spec, &wire);
    let ticks = profile_ticks(start.periods, natural)?;
    let period_s = 1.0 / f64::from(spec.defaults().servo_rate_hz.max(1));
    let mut samples: Vec<Sample> = Vec::with_capacity(ticks);
    let st = Start {
        label: format!("the start of {}", args.scene.display()),
        element: 0,
        position: start.position,
        velocity: start.velocity,
    };
    let r = run_traced(&spec, &wire, &st, ticks, natural, &mut |s| samples.push(*s))?;
    let mut w = writer(args.out.as_deref())?;
    writeln!(w, "tick,t_s,count,position,velocity,force")?;
    let last = samples.len().saturating_sub(1);
    for (i, (s, &c)) in samples.iter().zip(&r.counts).enumerate() {
        if i.is_multiple_of(args.every as usize) || i == last {
            write_profile_row(&mut *w, i, period_s, c, s)?;
        }
    }
    w.flush()?;
    let (verdict, holds) = super::profile::rest_verdict(&wire, &r, natural, &device);
    let u = device.units();
    let sig = stiffwall_tune::profile::units::sig;
    eprintln!(
        "{} on the plant of {}: {} wire element(s), the firmware's servo at {} Hz\n\
         start: x = {} {pos}, v = {} {pos}/s; {} of {ticks} ticks run\n{verdict}\nfaults: {}",
        profile_path.display(),
        args.scene.display(),
        wire.elements.len(),
        sig(1.0 / period_s),
        sig(start.position),
        sig(start.velocity),
        r.counts.len(),
        match r.faults {
            0 => "none".to_string(),
            f => format!("{f:#x} (the run ended there)"),
        },
        pos = u.position,
    );
    anyhow::ensure!(
        holds,
        "the run ends where the profile does not hold the device: {verdict}; the rows are \
         written"
    );
    Ok(())
}
