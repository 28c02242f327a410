//! `hostctl map --k-b`: the stability map over the (K, B) plane of one physical device.
//!
//! Units: SI. K in N/m and B (virtual damping) in N·s/m for a linear device; N·m/rad and
//! N·m·s/rad for a rotational one (a plant file with `counts_per_rev`, a rotary preset or
//! `--rotational`). The plant: m [kg or kg·m²], b, c, Δ [m or rad], T [s], T_D [s]. ξ̇₀ is in
//! counts per period (independent of K, so one value for the whole plane).
//!
//! Model: every (K, B) is mapped by Table I to μ = m/(KT²), β = b/(KT), σ = c/(KΔ),
//! τ_D = T_D/T and β_v = B/(KT), then simulated by the same exact solver, horizon and classes
//! as the (β, σ) map (quantization, Coulomb, viscous, delay, two-sided wall, ξ₀ = 0). That
//! solver knows only the paper's rigid plant: a plant file's stiction, cogging, transmission,
//! amplifier filter/dead band/saturation, hand and one-sided wall are NOT simulated (they are
//! listed under `plant.ignored` in the JSON and on standard error). The damper law is
//! simulated exactly: `--damper`, else the plant file's `controller.damper`, else the
//! firmware's default `dead-band-1` (JSON `spec.damper`), so the map classifies the wall the
//! firmware renders. The predicted boundary is
//! core's exact sampled linear K_max(B) (`criteria::k_max_exact_linear`: ZOH, backward
//! difference, b, T_D; no quantization or Coulomb).
//!
//! Layout: the flags are resolved once ([`spec_of`], the device by `kb_args`) into a
//! `Plant` and a [`KbSpec`]; the JSON document and its computation are
//! `stiffwall_analysis::kb` with its text [`render`] (re-exported here), drawn by `kb_plot`
//! (`stiffwall_figures::kb_map`); this module runs the command.
//!
//! Invariants: every flag is checked before anything is computed or written; β_v ≤ 1000 and
//! τ_D ≤ 250 at every point; the result is deterministic and independent of thread count.

use super::args::{history_of, Args};
use super::kb_args::{damper_of, resolve_plant, Plant};
use anyhow::{ensure, Context, Result};
pub use stiffwall_analysis::kb::render;
pub use stiffwall_analysis::kb::{
    boundary, compute, BoundaryPoint, KbFile, KbPoint, KbSpec, Units, BOUNDARY_POINTS, MODEL_NOTE,
};
use stiffwall_analysis::map_file as file;
use stiffwall_figures::kb_map as kb_plot;
use stiffwall_sim::exact::MAX_BETA_V;
use stiffwall_sim::map::{self as smap, Axis};

fn axis(flag: &str, s: Option<&str>, min: f64, strict: bool, unit: &str) -> Result<Axis> {
    let s = s.with_context(|| format!("--k-b needs {flag} LO:HI:N [{unit}]"))?;
    let a = Axis::parse(s).map_err(|e| anyhow::anyhow!("{flag} [{unit}]: {e}"))?;
    let ok = if strict { a.lo > min } else { a.lo >= min };
    ensure!(
        ok,
        "{flag} lo = {}: allowed range is {} {min} {unit}",
        a.lo,
        if strict { ">" } else { ">=" }
    );
    Ok(a)
}

/// Checks the flags of `--k-b` and returns the plant and sweep (nothing is computed).
///
/// # Errors
/// A flag out of range, naming it and its allowed range.
pub fn spec_of(a: &Args) -> Result<(Plant, KbSpec)> {
    let plant = resolve_plant(&a.kb)?;
    let tau_d = plant.delay_s / plant.period_s;
    ensure!(
        tau_d <= stiffwall_sim::params::MAX_TAU_D,
        "{}: delay T_D = {} s is {tau_d} periods; allowed range is T_D <= {} T",
        if a.kb.plant_file.is_some() {
            "--plant controller.extra_delay_s"
        } else {
            "--delay"
        },
        plant.delay_s,
        stiffwall_sim::params::MAX_TAU_D
    );
    let u = Units::of(plant.rotational);
    let k = axis("--k-axis", a.kb.k_axis.as_deref(), 0.0, true, u.k)?;
    let b = axis("--b-axis", a.kb.b_axis.as_deref(), 0.0, false, u.b)?;
    ensure!(
        k.n.checked_mul(b.n)
            .is_some_and(|n| n <= smap::MAX_GRID_POINTS),
        "--k-axis x --b-axis: {} x {} points, at most {}",
        k.n,
        b.n,
        smap::MAX_GRID_POINTS
    );
    let bv_max = b.hi / (k.lo * plant.period_s);
    ensure!(
        bv_max.is_finite() && bv_max <= MAX_BETA_V,
        "--b-axis hi = {} {}: beta_v = B/(K*T) = {bv_max:e} at K = {} (--k-axis lo); allowed \
         range is B <= {MAX_BETA_V}*K*T = {:e} {}",
        b.hi,
        u.b,
        k.lo,
        MAX_BETA_V * k.lo * plant.period_s,
        u.b
    );
    ensure!(
        a.xidot0.len() == 1 && a.xidot0[0].is_finite() && a.xidot0[0].abs() <= 1e12,
        "--xidot0 with --k-b: give one finite value, |v| <= 1e12 (counts per period)"
    );
    ensure!(
        (1..=smap::MAX_PERIODS).contains(&a.periods),
        "--periods {}: allowed range is [1, 1e8]",
        a.periods
    );
    let spec = KbSpec {
        k,
        b,
        xidot0: a.xidot0[0],
        velocity: a.xidot0[0] * plant.resolution / plant.period_s,
        periods: a.periods,
        history: history_of(a.history),
        damper: damper_of(&a.kb, &plant),
    };
    for kk in [k.lo, k.hi] {
        plant
            .at(kk, b.hi)
            .map_err(|e| anyhow::anyhow!("--k-axis K = {kk}: {e}"))?;
    }
    Ok((plant, spec))
}

/// Runs `hostctl map --k-b`: checks every flag, computes, then writes JSON, text and plot.
///
/// # Errors
/// A flag out of range or a file error, before anything is written.
pub fn run(a: &Args, threads: usize) -> Result<()> {
    let (plant, spec) = spec_of(a)?;
    if let Some(img) = &a.plot {
        crate::figure::prepare(img)?;
    }
    if let Some(out) = &a.out {
        crate::figure::check_writable(out).with_context(|| format!("--out {}", out.display()))?;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    let pb = if a.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        let pb = indicatif::ProgressBar::new((spec.k.n * spec.b.n) as u64);
        pb.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} points, eta {eta}")
                .expect("static template"),
        );
        pb
    };
    let m = pool.install(|| compute(&plant, &spec, &|| pb.inc(1)));
    pb.finish_and_clear();
    eprint!("{}", render(&m));
    match &a.out {
        Some(out) => file::write(out, &m)?,
        None if a.plot.is_none() => crate::output::emit_json(&m)?,
        None => {}
    }
    if let Some(img) = &a.plot {
        kb_plot::plot(&m, img)?;
    }
    Ok(())
}
