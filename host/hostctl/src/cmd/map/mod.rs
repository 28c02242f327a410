//! `hostctl map`: stability map over a (beta, sigma) grid (the paper's Fig. 6/7).
//!
//! Units: dimensionless (Table I): μ, τ_D in periods, ξ̇₀ in ticks per period, ξ₀ = 0.
//! Each grid point runs the exact solver (all effects) for `--periods` periods and is classified
//! as growing / persistent / non-monotonically / monotonically decaying. Several `--xidot0`
//! values give several panels; `--mu` and `--tau-d` also take lists or ranges (`lo:hi:n`,
//! `lo:hi:n:log`), a third axis: one panel per (μ, τ_D, ξ̇₀), μ outer. `--shard k/n` computes
//! every n-th point (starting at k) of every panel so a batch scheduler can split a sweep;
//! `hostctl map merge` joins the shard files; `hostctl map atlas` compares a map with the
//! analytic boundaries ([`atlas`]). `--beta-v BETA_V` (dimensionless β_v = B/(K·T) in
//! [0, 1000]) adds the wall's virtual damper at every point (`spec.damping`, written only when
//! nonzero: with 0 every file, hash and figure is unchanged). `--k-b` maps the (K, B) plane of
//! one physical device instead ([`kb`]; SI units).
//!
//! JSON output: `{ "spec": {...}, "spec_crc64", "shard": [k, n] | null, "panels": [{ "mu",
//! "tau_d", "xidot0", "points": [{ index, beta, sigma, class, periods_run, h0, h_end,
//! tail_amplitude }] }], "cost": { periods_total, core_seconds, ns_per_period_mean,
//! cpu_seconds, cpu_ns_per_period, ns_per_period: [[per point] per panel], cycle_points },
//! "seconds" }` (`cycle_points`: how many points ended by cycle detection, their state having
//! repeated exactly or up to the position's rounding drift; `--no-cycle-detection` simulates
//! every period, with the same points), written atomically ([`file::write`]). A run whose `--out` already holds the
//! complete, valid result of the same sweep and shard does nothing (resume after a pre-empted
//! batch job); `--force` recomputes. Bounds: `--threads` in [1, [`THREADS_PER_CORE`] × cores].

pub mod args;
pub mod atlas;
pub use stiffwall_analysis::map_file as file;
pub use stiffwall_figures::atlas as atlas_plot;
pub mod kb;
pub mod kb_args;
pub use stiffwall_analysis::values;
pub use stiffwall_figures::kb_map as kb_plot;
pub use stiffwall_figures::map as plot;

use crate::figure;
use crate::output::emit_json;
use anyhow::{bail, ensure, Context, Result};
pub use args::{history_of, Args, HistoryArg, Sub};
use file::{MapFile, Panel, Spec, Values};
use indicatif::{ProgressBar, ProgressStyle};
use plot::damping_label;
use std::path::PathBuf;
use stiffwall_sim::classify::Class;
use stiffwall_sim::exact::MAX_BETA_V;
use stiffwall_sim::map::{self, Axis};

/// Largest `--threads` per available core.
pub const THREADS_PER_CORE: usize = 4;

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
    ensure!(
        (1..=file::MAX_SHARDS).contains(&n) && k < n,
        "--shard {s:?}: need 0 <= k < n and 1 <= n <= {}",
        file::MAX_SHARDS
    );
    Ok((k, n))
}

fn spec_of(a: &Args) -> Result<Spec> {
    let mu = Values::parse(&a.mu).map_err(|e| anyhow::anyhow!("--mu {e}"))?;
    let tau_d = Values::parse(&a.tau_d).map_err(|e| anyhow::anyhow!("--tau-d {e}"))?;
    for v in mu.values() {
        ensure!(v.is_finite() && v > 0.0, "--mu {v}: allowed range is > 0");
    }
    for v in tau_d.values() {
        ensure!(
            v.is_finite() && (0.0..=250.0).contains(&v),
            "--tau-d {v}: allowed range is [0, 250]"
        );
    }
    ensure!(
        (1..=file::MAX_PANELS).contains(&a.xidot0.len()),
        "--xidot0: give 1 to {} values",
        file::MAX_PANELS
    );
    for &v in &a.xidot0 {
        ensure!(
            v.is_finite() && v.abs() <= 1e12,
            "--xidot0 {v}: allowed range is finite, |v| <= 1e12"
        );
    }
    ensure!(
        (1..=map::MAX_PERIODS).contains(&a.periods),
        "--periods {}: allowed range is [1, 1e8]",
        a.periods
    );
    let beta = Axis::parse(&a.beta).map_err(|e| anyhow::anyhow!("--beta: {e}"))?;
    let sigma = Axis::parse(&a.sigma).map_err(|e| anyhow::anyhow!("--sigma: {e}"))?;
    ensure!(beta.lo >= 0.0, "--beta: allowed range is >= 0");
    ensure!(sigma.lo >= 0.0, "--sigma: allowed range is >= 0");
    ensure!(
        a.beta_v.is_finite() && (0.0..=MAX_BETA_V).contains(&a.beta_v),
        "--beta-v {}: allowed range is [0, {MAX_BETA_V}] (dimensionless beta_v = B/(K*T))",
        a.beta_v
    );
    let spec = Spec {
        mu,
        tau_d,
        xidot0: a.xidot0.clone(),
        beta,
        sigma,
        periods: a.periods,
        history: history_of(a.history),
        damping: a.beta_v,
    };
    spec.validate()
        .context("--mu x --tau-d x --xidot0 x --beta x --sigma x --beta-v")?;
    Ok(spec)
}

/// Largest `--threads`: [`THREADS_PER_CORE`] × the available cores.
#[must_use]
pub fn max_threads() -> usize {
    THREADS_PER_CORE * std::thread::available_parallelism().map_or(1, std::num::NonZero::get)
}

fn threads_of(a: &Args) -> Result<usize> {
    let Some(t) = a.threads else { return Ok(0) };
    let max = max_threads();
    ensure!(
        (1..=max).contains(&t),
        "--threads {t}: allowed range is [1, {max}] ({THREADS_PER_CORE} per core)"
    );
    Ok(t)
}

/// Computes a map (or one shard of it) with a progress bar.
///
/// # Errors
/// None today (the signature leaves room for a failing solver).
pub fn compute(spec: &Spec, shard: Option<(usize, usize)>, quiet: bool) -> Result<MapFile> {
    compute_with(spec, shard, quiet, map::RunOptions::default())
}

/// [`compute`] with explicit [`map::RunOptions`] (cycle detection on or off: same points).
///
/// # Errors
/// None today (the signature leaves room for a failing solver).
pub fn compute_with(
    spec: &Spec,
    shard: Option<(usize, usize)>,
    quiet: bool,
    opts: map::RunOptions,
) -> Result<MapFile> {
    let (k, n) = shard.unwrap_or((0, 1));
    let total: usize = spec
        .panels()
        .iter()
        .map(|ps| map::shard(ps, k, n).len())
        .sum();
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
    let m = file::compute(spec, shard, &|| pb.inc(1), opts);
    pb.finish_and_clear();
    Ok(m)
}

/// The complete result already in `out` for this sweep and shard, if any (resume).
fn already_done(
    out: &std::path::Path,
    spec: &Spec,
    shard: Option<(usize, usize)>,
) -> Option<MapFile> {
    if !out.exists() {
        return None;
    }
    match file::read(out) {
        Ok(f) if f.spec == *spec && f.shard == shard => Some(f),
        Ok(_) => {
            eprintln!(
                "{}: holds another sweep or shard; recomputing",
                out.display()
            );
            None
        }
        Err(e) => {
            eprintln!("{e:#}; recomputing");
            None
        }
    }
}

fn run_merge(
    inputs: &[PathBuf],
    out: &std::path::Path,
    img: Option<&PathBuf>,
    overlay: bool,
) -> Result<()> {
    if let Some(img) = img {
        figure::prepare(img)?;
    }
    figure::check_writable(out).with_context(|| format!("--out {}", out.display()))?;
    let files = inputs
        .iter()
        .map(|p| Ok((p.clone(), file::read(p)?)))
        .collect::<Result<Vec<_>>>()?;
    let merged = file::merge(&files)?;
    if img.is_some() {
        check_overlay(&merged.spec, overlay)?;
    }
    file::write(out, &merged)?;
    if let Some(img) = img {
        plot::plot(&merged, img, overlay)?;
    }
    Ok(())
}

/// `--overlay` draws the paper's spring-only boundaries: refused on a damped map.
fn check_overlay(spec: &Spec, overlay: bool) -> Result<()> {
    ensure!(
        !overlay || spec.damping == 0.0,
        "--overlay draws the spring-only boundaries of Fig. 3/5: not valid with --beta-v {} \
         (allowed with --overlay: 0)",
        spec.damping
    );
    Ok(())
}

/// The per-panel class counts and the cost of a computed map, on standard error.
fn report(m: &MapFile) {
    let counts = |p: &Panel, c: Class| p.points.iter().filter(|q| q.class == c).count();
    for p in &m.panels {
        eprintln!(
            "mu = {}, tau_d = {}, xidot0 = {}{}: {} points: growing {}, persistent {}, non-monotone decay {}, monotone decay {}",
            p.mu,
            p.tau_d,
            p.xidot0,
            damping_label(m.spec.damping),
            p.points.len(),
            counts(p, Class::Growing),
            counts(p, Class::Persistent),
            counts(p, Class::NonMonotoneDecay),
            counts(p, Class::MonotoneDecay)
        );
    }
    eprintln!(
        "computed in {:.2} s: {} periods ({} points ended by cycle detection), {:.1} ns/period (thread wall time), {} CPU",
        m.seconds,
        m.cost.periods_total,
        m.cost.cycle_points,
        m.cost.ns_per_period_mean,
        m.cost.cpu_seconds.map_or_else(
            || "unknown".to_owned(),
            |c| format!(
                "{c:.2} s = {:.1} ns/period",
                m.cost.cpu_ns_per_period.unwrap_or(f64::NAN)
            )
        )
    );
}

/// Runs `hostctl map`.
///
/// # Errors
/// A flag out of range, an invalid or incomplete set of shard files, or a file error.
pub fn run(args: &Args) -> Result<()> {
    if args.damping_renamed.is_some() {
        bail!(
            "`hostctl map --damping` was renamed: use `--beta-v` (the dimensionless virtual \
             damping B/(K*T))"
        );
    }
    if let Some(Sub::Merge {
        inputs,
        out,
        plot: img,
        overlay,
    }) = &args.cmd
    {
        return run_merge(inputs, out, img.as_ref(), *overlay);
    }
    if let Some(Sub::Atlas(a)) = &args.cmd {
        return atlas::run(a);
    }
    if args.kb.k_b {
        return kb::run(args, threads_of(args)?);
    }
    let spec = spec_of(args)?;
    check_overlay(&spec, args.overlay)?;
    let threads = threads_of(args)?;
    let shard = args.shard.as_deref().map(parse_shard).transpose()?;
    if shard.is_some() && args.plot.is_some() {
        bail!("--plot needs the complete map: plot after `hostctl map merge`");
    }
    if let Some(img) = &args.plot {
        figure::prepare(img)?;
    }
    if let Some(out) = &args.out {
        figure::check_writable(out).with_context(|| format!("--out {}", out.display()))?;
    }
    let done = match &args.out {
        Some(out) if !args.force => already_done(out, &spec, shard),
        _ => None,
    };
    let m = if let Some(m) = done {
        eprintln!(
            "{}: already holds this sweep's complete result; nothing to do (--force recomputes)",
            args.out
                .as_deref()
                .map(std::path::Path::display)
                .map(|d| d.to_string())
                .unwrap_or_default()
        );
        m
    } else {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        let opts = map::RunOptions {
            cycle_detection: !args.no_cycle_detection,
        };
        let m = pool.install(|| compute_with(&spec, shard, args.quiet, opts))?;
        report(&m);
        match &args.out {
            Some(out) => file::write(out, &m)?,
            None if args.plot.is_none() => emit_json(&m)?,
            None => {}
        }
        m
    };
    if let Some(img) = &args.plot {
        plot::plot(&m, img, args.overlay)?;
    }
    Ok(())
}
