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
//! amplifier filter/dead band/saturation, hand, one-sided wall and a damper law with a dead
//! band (`controller.damper`; B damps the plain difference here) are NOT simulated (they are
//! listed under `plant.ignored` in the JSON and on standard error). The predicted boundary is
//! core's exact sampled linear K_max(B) (`criteria::k_max_exact_linear`: ZOH, backward
//! difference, b, T_D; no quantization or Coulomb).
//!
//! Layout: the flags are resolved once by `kb_args` into a device and a sweep; the JSON
//! document and its computation are `stiffwall_analysis::kb` (re-exported here), drawn by
//! `kb_plot`; this module renders the text and runs the command.
//!
//! Invariants: every flag is checked before anything is computed or written; β_v ≤ 1000 and
//! τ_D ≤ 250 at every point; the result is deterministic and independent of thread count.

use super::args::Args;
use super::file;
pub use super::kb_args::spec_of;
use super::kb_plot;
use anyhow::{Context, Result};
use std::fmt::Write as _;
pub use stiffwall_analysis::kb::{
    boundary, compute, BoundaryPoint, KbFile, KbPoint, KbSpec, Units, BOUNDARY_POINTS, MODEL_NOTE,
};
use stiffwall_sim::classify::Class;

fn class_char(c: Class, chatter: bool) -> char {
    match c {
        Class::Persistent if chatter => 'c',
        Class::Growing => '#',
        Class::Persistent => 'o',
        Class::NonMonotoneDecay => '~',
        Class::MonotoneDecay => '.',
    }
}

/// The text report: class counts, the class grid (K rows from the top, B columns) and K_max(B).
#[must_use]
pub fn render(m: &KbFile) -> String {
    let (s, u) = (&m.spec, m.units);
    let mut out = String::new();
    let _ = writeln!(out, "(K, B) map of {}: {}", m.plant.source, MODEL_NOTE);
    if !m.plant.ignored.is_empty() {
        let _ = writeln!(out, "not simulated: {}", m.plant.ignored.join(", "));
    }
    let count = |c: Class| m.points.iter().filter(|p| p.class == c).count();
    let chatter = m.points.iter().filter(|p| p.chatter).count();
    let _ = writeln!(
        out,
        "{} points: growing {} (#), persistent {} (o), chatter within one count {chatter} (c), non-monotone decay {} (~), monotone decay {} (.); linear-stable {}",
        m.points.len(),
        count(Class::Growing),
        count(Class::Persistent) - chatter,
        count(Class::NonMonotoneDecay),
        count(Class::MonotoneDecay),
        m.points.iter().filter(|p| p.linear_stable).count()
    );
    let _ = writeln!(
        out,
        "rows K [{}] from {:e} (top) down, columns B [{}] {:e}..{:e}:",
        u.k, s.k.hi, u.b, s.b.lo, s.b.hi
    );
    for row in m.points.chunks(s.b.n).rev() {
        let cells: String = row.iter().map(|p| class_char(p.class, p.chatter)).collect();
        let _ = writeln!(out, "{:>12.4e} {cells}", row[0].k);
    }
    let _ = writeln!(out, "predicted exact linear K_max(B):");
    let step = (m.boundary.len() / 10).max(1);
    for bp in m.boundary.iter().step_by(step) {
        let _ = writeln!(
            out,
            "  B = {:>11.4e} {}: K_max = {:.4e} {}",
            bp.b, u.b, bp.k_max, u.k
        );
    }
    out
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
