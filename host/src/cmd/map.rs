//! `hostctl map`: stability map over a (beta, sigma) grid (the paper's Fig. 6/7).
//!
//! Units: dimensionless (Table I): μ, τ_D in periods, ξ̇₀ in ticks per period, ξ₀ = 0.
//! Each grid point runs the exact solver (all effects) for `--periods` periods and is classified
//! as growing / persistent / non-monotonically / monotonically decaying. Several `--xidot0`
//! values give several panels. `--shard k/n` computes every n-th point (starting at k) so a
//! batch scheduler can split a sweep; `hostctl map merge` joins the shard files.
//!
//! JSON output: `{ "spec": {...}, "shard": [k, n] | null, "panels": [{ "xidot0", "points":
//! [{ index, beta, sigma, class, periods_run, h0, h_end, tail_amplitude }] }] }`.

use crate::figure::{self, Figure, FigureError};
use crate::output::emit_json;
use anyhow::{bail, ensure, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use stiffwall_core::regions;
use stiffwall_sim::classify::Class;
use stiffwall_sim::exact::History;
use stiffwall_sim::map::{self, Axis, MapPoint, MapSpec};

/// Arguments of `hostctl map`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Sub-commands (`merge`).
    #[command(subcommand)]
    pub cmd: Option<Sub>,
    /// Dimensionless mass μ.
    #[arg(long, default_value_t = 100.0)]
    pub mu: f64,
    /// Delay τ_D in sampling periods.
    #[arg(long, default_value_t = 0.0)]
    pub tau_d: f64,
    /// Initial velocities ξ̇₀ (comma separated, one panel each).
    #[arg(long, value_delimiter = ',', default_value = "5")]
    pub xidot0: Vec<f64>,
    /// β axis lo:hi:n.
    #[arg(long, default_value = "0:1:34")]
    pub beta: String,
    /// σ axis lo:hi:n.
    #[arg(long, default_value = "0:2:21")]
    pub sigma: String,
    /// Horizon in sampling periods.
    #[arg(long, default_value_t = 50_000)]
    pub periods: u64,
    /// JSON output file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Image of the map (.svg or .png).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Draw the analytic region boundaries of Fig. 3/5 over the map.
    #[arg(long)]
    pub overlay: bool,
    /// Compute only shard k of n (k/n, 0-based).
    #[arg(long)]
    pub shard: Option<String>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Delay-line history before tau = 0: the spring force of the initial position, or zero.
    #[arg(long, value_enum, default_value = "hold-initial")]
    pub history: HistoryArg,
}

/// `--history` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum HistoryArg {
    /// phi_A = phi_C(xi0) before the first delayed sample.
    HoldInitial,
    /// phi_A = 0 before the first delayed sample.
    Zero,
}

/// `hostctl map merge`.
#[derive(Debug, clap::Subcommand)]
pub enum Sub {
    /// Merge shard JSON files of one sweep into one complete map.
    Merge {
        /// Shard files.
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
        /// Merged JSON output.
        #[arg(long)]
        out: PathBuf,
        /// Image of the merged map (.svg or .png).
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Draw the analytic region boundaries.
        #[arg(long)]
        overlay: bool,
    },
}

/// The sweep description stored in the JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Spec {
    /// μ.
    pub mu: f64,
    /// τ_D.
    pub tau_d: f64,
    /// Panels' ξ̇₀.
    pub xidot0: Vec<f64>,
    /// β axis.
    pub beta: Axis,
    /// σ axis.
    pub sigma: Axis,
    /// Horizon.
    pub periods: u64,
    /// Delay-line history before tau = 0.
    #[serde(default)]
    pub history: History,
}

/// One panel (one ξ̇₀).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Panel {
    /// ξ̇₀.
    pub xidot0: f64,
    /// Classified points, sorted by index.
    pub points: Vec<MapPoint>,
}

/// The JSON document.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapFile {
    /// Sweep.
    pub spec: Spec,
    /// Shard (k, n), or None when complete.
    pub shard: Option<(usize, usize)>,
    /// Panels.
    pub panels: Vec<Panel>,
    /// Wall time of the computation in seconds (sum over shards after a merge).
    pub seconds: f64,
}

fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let (k, n) = s
        .split_once('/')
        .with_context(|| format!("--shard {s:?}: expected k/n"))?;
    let k: usize = k
        .trim()
        .parse()
        .with_context(|| format!("--shard {s:?}: k"))?;
    let n: usize = n
        .trim()
        .parse()
        .with_context(|| format!("--shard {s:?}: n"))?;
    ensure!(n >= 1 && k < n, "--shard {s:?}: need 0 <= k < n");
    Ok((k, n))
}

fn spec_of(a: &Args) -> Result<Spec> {
    ensure!(
        a.mu.is_finite() && a.mu > 0.0,
        "--mu {}: allowed range is > 0",
        a.mu
    );
    ensure!(
        a.tau_d.is_finite() && (0.0..=250.0).contains(&a.tau_d),
        "--tau-d {}: allowed range is [0, 250]",
        a.tau_d
    );
    ensure!(!a.xidot0.is_empty(), "--xidot0: give at least one value");
    for &v in &a.xidot0 {
        ensure!(
            v.is_finite() && v.abs() <= 1e12,
            "--xidot0 {v}: allowed range is finite, |v| <= 1e12"
        );
    }
    ensure!(
        (1..=100_000_000).contains(&a.periods),
        "--periods {}: allowed range is [1, 1e8]",
        a.periods
    );
    let beta = Axis::parse(&a.beta).map_err(|e| anyhow::anyhow!("--beta: {e}"))?;
    let sigma = Axis::parse(&a.sigma).map_err(|e| anyhow::anyhow!("--sigma: {e}"))?;
    ensure!(beta.lo >= 0.0, "--beta: allowed range is >= 0");
    ensure!(sigma.lo >= 0.0, "--sigma: allowed range is >= 0");
    Ok(Spec {
        mu: a.mu,
        tau_d: a.tau_d,
        xidot0: a.xidot0.clone(),
        beta,
        sigma,
        periods: a.periods,
        history: match a.history {
            HistoryArg::HoldInitial => History::HoldInitial,
            HistoryArg::Zero => History::Zero,
        },
    })
}

fn panel_spec(s: &Spec, xidot0: f64) -> MapSpec {
    MapSpec {
        mu: s.mu,
        tau_d: s.tau_d,
        xidot0,
        beta: s.beta,
        sigma: s.sigma,
        periods: s.periods,
        history: s.history,
    }
}

/// Computes a map (or one shard of it) with a progress bar.
pub fn compute(spec: &Spec, shard: Option<(usize, usize)>, quiet: bool) -> Result<MapFile> {
    let (k, n) = shard.unwrap_or((0, 1));
    let t0 = std::time::Instant::now();
    let per_panel: Vec<Vec<usize>> = spec
        .xidot0
        .iter()
        .map(|&v| map::shard(&panel_spec(spec, v), k, n))
        .collect();
    let total: usize = per_panel.iter().map(Vec::len).sum();
    let pb = if quiet {
        ProgressBar::hidden()
    } else {
        let pb = ProgressBar::new(total as u64);
        pb.set_style(
            ProgressStyle::with_template(
                "{bar:40} {pos}/{len} points, {elapsed} elapsed, eta {eta}",
            )
            .expect("static template"),
        );
        pb
    };
    let tick = || pb.inc(1);
    let panels = spec
        .xidot0
        .iter()
        .zip(&per_panel)
        .map(|(&v, idx)| Panel {
            xidot0: v,
            points: map::run(&panel_spec(spec, v), idx, &tick),
        })
        .collect();
    pb.finish_and_clear();
    Ok(MapFile {
        spec: spec.clone(),
        shard,
        panels,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Merges shard files of one sweep; fails on mismatched sweeps, duplicates or missing points.
pub fn merge(files: &[MapFile]) -> Result<MapFile> {
    let first = files.first().context("no input files")?;
    let spec = first.spec.clone();
    let len = spec.beta.n * spec.sigma.n;
    let mut panels: Vec<Vec<Option<MapPoint>>> = vec![vec![None; len]; spec.xidot0.len()];
    let mut seconds = 0.0;
    for f in files {
        ensure!(f.spec == spec, "shard files belong to different sweeps");
        seconds += f.seconds;
        for (pi, p) in f.panels.iter().enumerate() {
            for pt in &p.points {
                ensure!(pt.index < len, "point index {} out of range", pt.index);
                ensure!(
                    panels[pi][pt.index].is_none(),
                    "point {} of panel {pi} appears twice",
                    pt.index
                );
                panels[pi][pt.index] = Some(*pt);
            }
        }
    }
    let mut out = Vec::new();
    for (pi, pts) in panels.into_iter().enumerate() {
        let missing = pts.iter().filter(|p| p.is_none()).count();
        ensure!(
            missing == 0,
            "panel {pi} (xidot0 = {}): {missing} points missing",
            spec.xidot0[pi]
        );
        out.push(Panel {
            xidot0: spec.xidot0[pi],
            points: pts.into_iter().flatten().collect(),
        });
    }
    Ok(MapFile {
        spec,
        shard: None,
        panels: out,
        seconds,
    })
}

fn write_json(path: &Path, m: &MapFile) -> Result<()> {
    let s = serde_json::to_string_pretty(m)?;
    std::fs::write(path, s).with_context(|| format!("writing {}", path.display()))
}

fn read_json(path: &Path) -> Result<MapFile> {
    let s = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&s).with_context(|| format!("parsing {}", path.display()))
}

fn class_color(c: Class) -> RGBColor {
    match c {
        Class::Growing => RGBColor(40, 40, 40),
        Class::Persistent => RGBColor(120, 120, 120),
        Class::NonMonotoneDecay => RGBColor(200, 200, 200),
        Class::MonotoneDecay => RGBColor(255, 255, 255),
    }
}

/// The map (one panel per ξ̇₀) as a [`Figure`].
struct MapFigure<'a> {
    map: &'a MapFile,
    cols: usize,
    rows: usize,
    overlay: bool,
}

impl Figure for MapFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        draw(root, self.map, self.cols, self.rows, self.overlay)
    }
}

/// Draws the map (one panel per ξ̇₀) to `path` (.svg or .png, any case).
///
/// # Errors
/// An unsupported extension, or a drawing or file error.
pub fn plot(m: &MapFile, path: &Path, overlay: bool) -> Result<(), FigureError> {
    let n = m.panels.len();
    let cols = if n >= 4 { 2 } else { n.max(1) };
    let rows = n.div_ceil(cols);
    let size = (cols as u32 * 480, rows as u32 * 440 + 30);
    let fig = MapFigure {
        map: m,
        cols,
        rows,
        overlay,
    };
    figure::write(path, size, &fig)
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    m: &MapFile,
    cols: usize,
    rows: usize,
    overlay: bool,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let s = &m.spec;
    let (top, body) = root.split_vertically(30);
    top.titled(
        &format!(
            "mu = {}, tau_D = {}, {} periods; dark: growing, medium: persistent, light: non-monotone decay, white: monotone decay",
            s.mu, s.tau_d, s.periods
        ),
        ("sans-serif", 14),
    )?;
    let areas = body.split_evenly((rows, cols));
    let db = if s.beta.n > 1 {
        (s.beta.hi - s.beta.lo) / (s.beta.n - 1) as f64
    } else {
        0.1
    };
    let ds = if s.sigma.n > 1 {
        (s.sigma.hi - s.sigma.lo) / (s.sigma.n - 1) as f64
    } else {
        0.1
    };
    let (bx0, bx1) = (s.beta.lo - db / 2.0, s.beta.hi + db / 2.0);
    let (sy0, sy1) = (s.sigma.lo - ds / 2.0, s.sigma.hi + ds / 2.0);
    for (panel, area) in m.panels.iter().zip(areas.iter()) {
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!("xidot0 = xidot_max = {}", panel.xidot0),
                ("sans-serif", 16),
            )
            .margin(8)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(bx0..bx1, sy0..sy1)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("beta")
            .y_desc("sigma")
            .draw()?;
        chart.draw_series(panel.points.iter().map(|p| {
            Rectangle::new(
                [
                    (p.beta - db / 2.0, p.sigma - ds / 2.0),
                    (p.beta + db / 2.0, p.sigma + ds / 2.0),
                ],
                class_color(p.class).filled(),
            )
        }))?;
        if overlay {
            // The boundaries of Fig. 3 (tau_D = 0) or Fig. 5 / (19), with the panel's xidot0 as
            // the velocity bound and xiddot_max ~ xidot_max / sqrt(mu) (harmonic motion).
            let red = RED.stroke_width(2);
            let v = panel.xidot0.abs();
            let window = regions::Window {
                beta_min: bx0,
                beta_max: bx1,
                sigma_min: sy0,
                sigma_max: sy1,
            };
            let lines = regions::boundaries(s.tau_d, Some(v), Some(v / s.mu.sqrt()), &window)?;
            for seg in lines.as_slice() {
                chart.draw_series(LineSeries::new(vec![seg.from, seg.to], red))?;
            }
        }
    }
    Ok(())
}

/// Runs `hostctl map`.
pub fn run(args: &Args) -> Result<()> {
    if let Some(Sub::Merge {
        inputs,
        out,
        plot: img,
        overlay,
    }) = &args.cmd
    {
        if let Some(img) = img {
            figure::format_of(img)?;
        }
        let files = inputs
            .iter()
            .map(|p| read_json(p))
            .collect::<Result<Vec<_>>>()?;
        let merged = merge(&files)?;
        write_json(out, &merged)?;
        if let Some(img) = img {
            plot(&merged, img, *overlay)?;
        }
        return Ok(());
    }
    let spec = spec_of(args)?;
    if let Some(img) = &args.plot {
        figure::format_of(img)?;
    }
    let shard = args.shard.as_deref().map(parse_shard).transpose()?;
    if shard.is_some() && args.plot.is_some() {
        bail!("--plot needs the complete map: plot after `hostctl map merge`");
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()?;
    let m = pool.install(|| compute(&spec, shard, args.quiet))?;
    let counts = |p: &Panel, c: Class| p.points.iter().filter(|q| q.class == c).count();
    for p in &m.panels {
        eprintln!(
            "xidot0 = {}: {} points: growing {}, persistent {}, non-monotone decay {}, monotone decay {}",
            p.xidot0,
            p.points.len(),
            counts(p, Class::Growing),
            counts(p, Class::Persistent),
            counts(p, Class::NonMonotoneDecay),
            counts(p, Class::MonotoneDecay)
        );
    }
    eprintln!("computed in {:.2} s", m.seconds);
    match &args.out {
        Some(out) => write_json(out, &m)?,
        None if args.plot.is_none() => emit_json(&m)?,
        None => {}
    }
    if let Some(img) = &args.plot {
        plot(&m, img, args.overlay)?;
    }
    Ok(())
}
