//! `hostctl map atlas`: a complete map compared, panel by panel, with the paper's analytic
//! growth boundaries.
//!
//! Units: dimensionless (Table I); fractions in [0, 1]. For each panel (μ, τ_D, ξ̇₀) every grid
//! point's simulated outcome is reduced to "growing" (class `growing`) or not, and each analytic
//! line is read as a predictor of growth:
//! - `worst_case`: the regions of (12) (τ_D = 0) / (19) (τ_D > 0), growth in C or D
//!   (`stiffwall_core::regions::classify_delayed`), with ξ̇_max = |ξ̇₀| and the harmonic
//!   ξ̈_max = ξ̇_max/√μ (as `hostctl map --overlay` draws them);
//! - `df_72`: growth below the describing-function line (72), σ < (πM/4)(sin(τ_Lω) − βω) with ω
//!   from (71) and M = |ξ̇₀|/ω (so ξ̇_max = Mω), τ_L = ½ + τ_D
//!   (`stiffwall_core::describing::large_cycle_sigma`);
//! - `df_74`: the same with the low-frequency approximation (73)/(74);
//! - `linear_exact`: growth where the sampled linear loop (no quantization, no Coulomb friction)
//!   is unstable (`stiffwall_core::criteria::gil_avello_rubio_stable`); defined for
//!   τ_D ≤ 60 periods, `null` beyond.
//!
//! A line's agreement is the fraction of the panel's grid points on which its prediction
//! equals the simulation. Invariant: the atlas is computed only from a complete, validated map.
//!
//! Layout: the lines and the atlas document are plain data in `atlas_model` (re-exported
//! here); `atlas_plot` draws them; this module computes, renders Markdown and runs the
//! command, on top of both.

pub use super::atlas_model::{Agreement, Atlas, AtlasPanel, Line, Slice};
use super::atlas_plot;
use super::file::{self, Cost, MapFile};
use anyhow::{ensure, Context, Result};
use std::path::PathBuf;
use stiffwall_sim::classify::Class;

/// Arguments of `hostctl map atlas`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A complete map JSON (from `hostctl map` or `hostctl map merge`).
    pub input: PathBuf,
    /// Atlas JSON output (stdout when neither --out, --plots nor --markdown is given).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Directory for one image per panel and `atlas-summary.<ext>`.
    #[arg(long)]
    pub plots: Option<PathBuf>,
    /// Image format of --plots: png or svg.
    #[arg(long, default_value = "png")]
    pub format: String,
    /// Markdown table of the agreement fractions.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// Command line recorded in the --markdown header (how the table was generated).
    #[arg(long)]
    pub generated_by: Option<String>,
}

/// Compares every panel of a complete map with every [`Line`].
///
/// # Errors
/// A sharded map, or parameters out of the analysis' range.
pub fn compute(m: &MapFile) -> Result<Atlas> {
    ensure!(
        m.shard.is_none(),
        "the atlas needs a complete map: merge the shards first (hostctl map merge)"
    );
    ensure!(
        m.spec.damping == 0.0,
        "the atlas compares with the spring-only boundaries of the paper: the map has \
         damping beta_v = {} (recompute it with --damping 0)",
        m.spec.damping
    );
    let mut panels = Vec::with_capacity(m.panels.len());
    for (pi, p) in m.panels.iter().enumerate() {
        let cost = Cost::of(
            std::slice::from_ref(p),
            vec![m.cost.ns_per_period.get(pi).cloned().unwrap_or_default()],
        );
        let slice = Slice {
            mu: p.mu,
            tau_d: p.tau_d,
            xidot0: p.xidot0,
        };
        let growing = p
            .points
            .iter()
            .filter(|q| q.class == Class::Growing)
            .count();
        let mut agreement = Vec::with_capacity(Line::ALL.len());
        for line in Line::ALL {
            let (mut correct, mut false_growth, mut missed, mut defined) = (0, 0, 0, true);
            for q in &p.points {
                let Some(pred) = slice
                    .predicts_growth(line, q.beta, q.sigma)
                    .with_context(|| format!("mu = {}, tau_d = {}", p.mu, p.tau_d))?
                else {
                    defined = false;
                    break;
                };
                let sim = q.class == Class::Growing;
                match (pred, sim) {
                    (true, false) => false_growth += 1,
                    (false, true) => missed += 1,
                    _ => correct += 1,
                }
            }
            let n = p.points.len();
            agreement.push(Agreement {
                line: line.name(),
                correct: defined.then_some(correct),
                fraction: (defined && n > 0).then(|| correct as f64 / n as f64),
                false_growth: defined.then_some(false_growth),
                missed_growth: defined.then_some(missed),
            });
        }
        panels.push(AtlasPanel {
            mu: p.mu,
            tau_d: p.tau_d,
            xidot0: p.xidot0,
            points: p.points.len(),
            growing,
            periods_total: cost.periods_total,
            ns_per_period_mean: cost.ns_per_period_mean,
            agreement,
        });
    }
    Ok(Atlas {
        map_spec_crc64: m.spec_crc64.clone(),
        periods: m.spec.periods,
        cpu_seconds: m.cost.cpu_seconds,
        cpu_ns_per_period: m.cost.cpu_ns_per_period,
        panels,
    })
}

fn pct(f: Option<f64>) -> String {
    f.map_or_else(|| "n/a".to_owned(), |f| format!("{:.1} %", 100.0 * f))
}

/// The figures written next to a Markdown table: their directory relative to the Markdown
/// file, and their extension.
#[derive(Debug, Clone, Copy)]
pub struct FigureLinks<'a> {
    /// Directory of the figures, relative to the Markdown file, `/`-separated.
    pub dir: &'a str,
    /// `png` or `svg`.
    pub ext: &'a str,
}

/// The agreement fractions as a Markdown document (with links to the figures when given).
#[must_use]
pub fn markdown(a: &Atlas, generated_by: Option<&str>, figures: Option<FigureLinks>) -> String {
    let mut s = String::from("# Stability atlas: simulated growth vs the analytic lines\n\n");
    s.push_str(
        "Generated; do not edit by hand. Each row is one slice of the map: the fraction of its \
         grid points on which each analytic line's growth prediction equals the exact \
         simulation (growing = class `growing`). Lines: worst case = regions C/D of (12)/(19) \
         with ξ̇_max = ξ̇₀, ξ̈_max = ξ̇₀/√μ; (72), (74) = growth below the describing-function \
         line with ξ̇_max = Mω; exact linear = unstable sampled linear loop (no quantization, \
         no Coulomb friction).\n\n",
    );
    md_provenance(&mut s, a, generated_by, figures);
    md_table(&mut s, a, figures);
    md_totals(&mut s, a, figures);
    s
}

/// The command line, the map's identity and the figure legend.
fn md_provenance(
    s: &mut String,
    a: &Atlas,
    generated_by: Option<&str>,
    figures: Option<FigureLinks>,
) {
    use std::fmt::Write as _;
    if let Some(cmd) = generated_by {
        let _ = writeln!(s, "Generated by:\n\n```sh\n{cmd}\n```\n");
    }
    let _ = writeln!(
        s,
        "Map spec_crc64 `{}`, horizon {} periods.\n",
        a.map_spec_crc64, a.periods
    );
    if let Some(f) = figures {
        let _ = writeln!(
            s,
            "![agreement per slice]({}/atlas-summary.{})\n\nOne figure per slice (linked in the \
             last column): simulated classes as grey levels, growing darkest; the worst-case \
             lines in red, (72) in blue, (74) in light blue, the exact linear boundary in green.\n",
            f.dir, f.ext
        );
    }
}

/// The header and one row per panel.
fn md_table(s: &mut String, a: &Atlas, figures: Option<FigureLinks>) {
    use std::fmt::Write as _;
    s.push_str("| μ | τ_D | ξ̇₀ | points | growing |");
    for l in Line::ALL {
        let _ = write!(s, " {} |", l.label());
    }
    s.push_str(" periods run / point | ns / period |");
    if figures.is_some() {
        s.push_str(" figure |");
    }
    s.push_str("\n|---:|---:|---:|---:|---:|");
    for _ in Line::ALL {
        s.push_str("---:|");
    }
    s.push_str("---:|---:|");
    if figures.is_some() {
        s.push_str("---|");
    }
    s.push('\n');
    for p in &a.panels {
        let _ = write!(
            s,
            "| {:.4} | {} | {} | {} | {} |",
            p.mu, p.tau_d, p.xidot0, p.points, p.growing
        );
        for l in Line::ALL {
            let _ = write!(s, " {} |", pct(p.fraction(l)));
        }
        let _ = write!(
            s,
            " {:.0} | {:.1} |",
            p.periods_total as f64 / p.points.max(1) as f64,
            p.ns_per_period_mean
        );
        if let Some(f) = figures {
            let name = atlas_plot::panel_file(p.mu, p.tau_d, p.xidot0, f.ext);
            let _ = write!(s, " [{}]({}/{name}) |", f.ext, f.dir);
        }
        s.push('\n');
    }
}

/// The mean row and the cost paragraph.
fn md_totals(s: &mut String, a: &Atlas, figures: Option<FigureLinks>) {
    use std::fmt::Write as _;
    s.push_str("| **mean** | | | | |");
    for l in Line::ALL {
        let v: Vec<f64> = a.panels.iter().filter_map(|p| p.fraction(l)).collect();
        let mean = (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
        let _ = write!(s, " **{}** |", pct(mean));
    }
    let points: usize = a.panels.iter().map(|p| p.points).sum();
    let periods: u64 = a.panels.iter().map(|p| p.periods_total).sum();
    let core_ns: f64 = a
        .panels
        .iter()
        .map(|p| p.periods_total as f64 * p.ns_per_period_mean)
        .sum();
    let ns = if periods > 0 {
        core_ns / periods as f64
    } else {
        0.0
    };
    let _ = writeln!(
        s,
        " {:.0} | {ns:.1} |{}",
        periods as f64 / points.max(1) as f64,
        if figures.is_some() { " |" } else { "" }
    );
    let _ = writeln!(
        s,
        "\nCost of this map: {points} points, {periods} simulated periods ({:.1} % of the \
         horizon on average: decaying and growing points stop early), {:.1} s of worker-thread \
         wall time ({ns:.1} ns per period; the column above){}.",
        100.0 * periods as f64 / (points.max(1) as f64 * a.periods as f64),
        core_ns * 1e-9,
        match (a.cpu_seconds, a.cpu_ns_per_period) {
            (Some(c), Some(n)) => format!(
                ", {c:.1} s of CPU time as the operating system counts it ({n:.1} ns per period)"
            ),
            _ => String::new(),
        }
    );
}

/// Runs `hostctl map atlas`.
///
/// # Errors
/// An invalid or incomplete map, an unwritable output, or a drawing error.
pub fn run(a: &Args) -> Result<()> {
    let ext = match a.format.to_ascii_lowercase().as_str() {
        f @ ("png" | "svg") => f.to_owned(),
        other => anyhow::bail!("--format {other}: allowed values are png, svg"),
    };
    if let Some(d) = &a.plots {
        std::fs::create_dir_all(d).with_context(|| format!("--plots {}", d.display()))?;
    }
    for p in a.out.iter().chain(&a.markdown) {
        crate::figure::check_writable(p).with_context(|| format!("{}", p.display()))?;
    }
    let m = file::read(&a.input)?;
    let atlas = compute(&m)?;
    for p in &atlas.panels {
        eprintln!(
            "mu = {:.4}, tau_d = {}, xidot0 = {}: {} growing of {}; agreement: {}",
            p.mu,
            p.tau_d,
            p.xidot0,
            p.growing,
            p.points,
            Line::ALL
                .iter()
                .map(|&l| format!("{} {}", l.name(), pct(p.fraction(l))))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let json = serde_json::to_string_pretty(&atlas)? + "\n";
    if let Some(out) = &a.out {
        std::fs::write(out, &json).with_context(|| format!("writing {}", out.display()))?;
    }
    if let Some(md) = &a.markdown {
        // Link the figures when they sit below the Markdown file's directory.
        let parent = md
            .parent()
            .map(std::path::Path::to_path_buf)
            .unwrap_or_default();
        let rel = a.plots.as_ref().and_then(|d| {
            let rel = d.strip_prefix(&parent).ok()?;
            let parts: Option<Vec<&str>> = rel.iter().map(|c| c.to_str()).collect();
            Some(parts?.join("/"))
        });
        let links = rel.as_deref().map(|dir| FigureLinks { dir, ext: &ext });
        std::fs::write(md, markdown(&atlas, a.generated_by.as_deref(), links))
            .with_context(|| format!("writing {}", md.display()))?;
    }
    if let Some(dir) = &a.plots {
        atlas_plot::plot_all(&m, &atlas, dir, &ext)?;
    }
    if a.out.is_none() && a.plots.is_none() && a.markdown.is_none() {
        print!("{json}");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cmd::map::file::{Panel, Spec, Values};
    use stiffwall_sim::exact::History;
    use stiffwall_sim::map::{Axis, MapPoint};

    /// A 4 × 4 map (μ = 100, τ_D = 0, ξ̇₀ = 1) whose "simulated" classes are set by hand.
    fn hand_map(growing: &[(f64, f64)]) -> MapFile {
        let spec = Spec {
            mu: Values::One(100.0),
            tau_d: Values::One(0.0),
            xidot0: vec![1.0],
            beta: Axis {
                lo: 0.1,
                hi: 1.0,
                n: 4,
            },
            sigma: Axis {
                lo: 0.0,
                hi: 1.5,
                n: 4,
            },
            periods: 10,
            history: History::HoldInitial,
            damping: 0.0,
        };
        let ps = spec.panels()[0];
        let points: Vec<MapPoint> = (0..16)
            .map(|i| {
                let (beta, sigma) = ps.point(i);
                let hit = growing
                    .iter()
                    .any(|&(b, s)| (b - beta).abs() < 1e-9 && (s - sigma).abs() < 1e-9);
                MapPoint {
                    index: i,
                    beta,
                    sigma,
                    class: if hit {
                        Class::Growing
                    } else {
                        Class::MonotoneDecay
                    },
                    periods_run: 10,
                    h0: 0.0,
                    h_end: 0.0,
                    tail_amplitude: 0.0,
                }
            })
            .collect();
        let panels = vec![Panel {
            mu: 100.0,
            tau_d: 0.0,
            xidot0: 1.0,
            points,
        }];
        MapFile {
            spec_crc64: spec.crc64(),
            spec,
            shard: None,
            cost: Cost::of(&panels, vec![vec![0.0; 16]]),
            panels,
            seconds: 0.0,
        }
    }

    /// Expected counts worked out by hand on the grid β ∈ {0.1, 0.4, 0.7, 1.0},
    /// σ ∈ {0, 0.5, 1, 1.5}, μ = 100, τ_D = 0, ξ̇_max = 1:
    /// - worst case: growth in C (β < ½, σ < ½) or D (β < ½, ½ ≤ σ < ½ + (½ − β)·1 = 1 − β):
    ///   (0.1, 0), (0.1, 0.5), (0.4, 0), (0.4, 0.5);
    /// - (72)/(74): ω ≈ 1/√μ = 0.1, M = 1/ω, σ_line ≈ (π/4)(½ − β): 0.31 at β = 0.1, 0.08 at
    ///   0.4, negative beyond: growth at (0.1, 0), (0.4, 0) only;
    /// - exact linear, τ_D = 0: stable iff β ≳ ½ (Colgate's 2b/T for bT/m = β/μ ≪ 1), growth at
    ///   all 8 points with β ∈ {0.1, 0.4}.
    ///
    /// With simulated growth at (0.1, 0), (0.1, 0.5), (0.1, 1), (0.4, 0):
    /// worst case misses (0.1, 1) and falsely predicts (0.4, 0.5): 14/16; DF misses (0.1, 0.5)
    /// and (0.1, 1): 14/16; linear falsely predicts (0.4, 0.5), (0.4, 1), (0.4, 1.5),
    /// (0.1, 1.5): 12/16.
    #[test]
    fn agreement_fractions_match_a_hand_count() {
        let m = hand_map(&[(0.1, 0.0), (0.1, 0.5), (0.1, 1.0), (0.4, 0.0)]);
        let a = compute(&m).unwrap();
        let p = &a.panels[0];
        assert_eq!((p.points, p.growing), (16, 4));
        let get = |l: Line| *p.agreement.iter().find(|x| x.line == l.name()).unwrap();
        let wc = get(Line::WorstCase);
        assert_eq!(
            (wc.correct, wc.false_growth, wc.missed_growth),
            (Some(14), Some(1), Some(1))
        );
        assert_eq!(wc.fraction, Some(0.875));
        for l in [Line::Df72, Line::Df74] {
            let d = get(l);
            assert_eq!(
                (d.correct, d.false_growth, d.missed_growth),
                (Some(14), Some(0), Some(2)),
                "{l:?}"
            );
        }
        let lin = get(Line::LinearExact);
        assert_eq!(
            (lin.correct, lin.false_growth, lin.missed_growth),
            (Some(12), Some(4), Some(0))
        );
        assert_eq!(lin.fraction, Some(0.75));
        // Simulated growth exactly where the worst case predicts it: 16/16.
        let m = hand_map(&[(0.1, 0.0), (0.1, 0.5), (0.4, 0.0), (0.4, 0.5)]);
        assert_eq!(
            compute(&m).unwrap().panels[0].fraction(Line::WorstCase),
            Some(1.0)
        );
        let md = markdown(
            &compute(&m).unwrap(),
            Some("hostctl map atlas x.json"),
            None,
        );
        assert!(
            md.contains("| 100.0000 | 0 | 1 | 16 | 4 | 100.0 % |"),
            "{md}"
        );
        assert_eq!(compute(&m).unwrap().panels[0].periods_total, 160);
    }

    #[test]
    fn a_shard_is_refused() {
        let mut m = hand_map(&[]);
        m.shard = Some((0, 2));
        let e = compute(&m).unwrap_err().to_string();
        assert!(e.contains("merge the shards first"), "{e}");
    }
}
