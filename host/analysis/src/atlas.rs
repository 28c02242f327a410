//! The analytic growth predictors of `hostctl map atlas` ([`Line`], evaluated on a [`Slice`])
//! and the atlas document ([`Atlas`], [`AtlasPanel`], [`Agreement`]) as plain data, shared by
//! the atlas computation and its figures.
//!
//! [`compute`] compares every panel of a complete map with every line (the line's agreement is
//! the fraction of the panel's grid points on which its prediction equals the simulation).
//!
//! Units: dimensionless (Table I): μ, τ_D in periods, ξ̇₀ in ticks per period, β, σ; fractions
//! in [0, 1]. Invariant: the atlas is computed only from a complete, spring-only map. Invariant: a line that is not defined at a point (`linear_exact` beyond τ_D = 60,
//! a describing-function line without a solution) answers `None`, never a guess.

use crate::map_file::{Cost, MapFile};
use serde::Serialize;
use stiffwall_core::params::Dimensionless;
use stiffwall_core::{criteria, describing, regions, ParamError};
use stiffwall_sim::classify::Class;

/// `Result` of this module.
pub type Result<T, E = ParamError> = std::result::Result<T, E>;

/// Why no atlas is computed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AtlasError {
    /// A shard of a map.
    #[error("the atlas needs a complete map: merge the shards first (hostctl map merge)")]
    Sharded,
    /// A map with virtual damping.
    #[error(
        "the atlas compares with the spring-only boundaries of the paper: the map has \
         damping beta_v = {beta_v} (recompute it with --beta-v 0)"
    )]
    Damped {
        /// The map's β_v = B/(K·T).
        beta_v: f64,
    },
    /// A panel outside the analysis' range.
    #[error("mu = {mu}, tau_d = {tau_d}")]
    Param {
        /// The panel's μ.
        mu: f64,
        /// The panel's τ_D.
        tau_d: f64,
        /// The parameter error (names the quantity and its range).
        #[source]
        source: ParamError,
    },
}

/// An analytic growth predictor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Line {
    /// Regions C, D of (12)/(19).
    WorstCase,
    /// Below (72).
    Df72,
    /// Below (74).
    Df74,
    /// Unstable sampled linear loop.
    LinearExact,
}

impl Line {
    /// Every line, in report order.
    pub const ALL: [Self; 4] = [Self::WorstCase, Self::Df72, Self::Df74, Self::LinearExact];

    /// JSON / table name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::WorstCase => "worst_case",
            Self::Df72 => "df_72",
            Self::Df74 => "df_74",
            Self::LinearExact => "linear_exact",
        }
    }

    /// Label for figures.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Self::WorstCase => "worst case (12)/(19)",
            Self::Df72 => "describing function (72)",
            Self::Df74 => "describing function (74)",
            Self::LinearExact => "exact linear",
        }
    }
}

/// The slice a prediction is made in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slice {
    /// μ.
    pub mu: f64,
    /// τ_D in periods.
    pub tau_d: f64,
    /// ξ̇₀ (its magnitude is ξ̇_max).
    pub xidot0: f64,
}

impl Slice {
    fn tau_l(&self) -> f64 {
        0.5 + self.tau_d
    }

    /// σ on line (72) (`Df72`) or (74) (`Df74`) at β; `None` for other lines.
    ///
    /// # Errors
    /// Parameters out of the analysis' range.
    pub fn df_sigma(&self, line: Line, beta: f64) -> Result<Option<f64>> {
        let v = self.xidot0.abs();
        if v == 0.0 {
            return Ok(Some(0.0));
        }
        let tl = self.tau_l();
        Ok(match line {
            Line::Df72 => {
                let w = describing::large_cycle_omega(self.mu, tl)?;
                Some(describing::large_cycle_sigma(self.mu, beta, tl, v / w)?)
            }
            Line::Df74 => {
                let w = describing::large_cycle_omega_approx(self.mu, tl)?;
                Some(describing::large_cycle_sigma_approx(
                    self.mu,
                    beta,
                    tl,
                    v / w,
                )?)
            }
            Line::WorstCase | Line::LinearExact => None,
        })
    }

    /// Whether the sampled linear loop is stable at β (`None` beyond its delay range).
    ///
    /// # Errors
    /// Parameters out of range.
    pub fn linear_stable(&self, beta: f64) -> Result<Option<bool>> {
        if self.tau_d > criteria::MAX_DELAY_PERIODS as f64 {
            return Ok(None);
        }
        let p = Dimensionless {
            mu: self.mu,
            beta,
            sigma: 0.0,
            tau_d: self.tau_d,
        }
        .to_physical(1.0, 1.0, 1.0, false)?;
        Ok(Some(criteria::gil_avello_rubio_stable(&p)?))
    }

    /// β values where the linear loop's stability flips inside [b0, b1] (scan + bisection).
    ///
    /// # Errors
    /// Parameters out of range.
    pub fn linear_flips(&self, b0: f64, b1: f64) -> Result<Vec<f64>> {
        const SCAN: usize = 400;
        let stable = |b: f64| self.linear_stable(b.max(0.0));
        let mut flips = Vec::new();
        let mut prev_b = b0.max(0.0);
        let Some(mut prev) = stable(prev_b)? else {
            return Ok(flips);
        };
        for i in 1..=SCAN {
            let b = b0.max(0.0) + (b1 - b0.max(0.0)) * i as f64 / SCAN as f64;
            let s = stable(b)?.unwrap_or(prev);
            if s != prev {
                let (mut lo, mut hi) = (prev_b, b);
                for _ in 0..50 {
                    let mid = 0.5 * (lo + hi);
                    if stable(mid)?.unwrap_or(prev) == prev {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                flips.push(0.5 * (lo + hi));
            }
            prev = s;
            prev_b = b;
        }
        Ok(flips)
    }

    /// Whether `line` predicts growth at (β, σ); `None` when the line is not defined here.
    ///
    /// # Errors
    /// Parameters out of range.
    pub fn predicts_growth(&self, line: Line, beta: f64, sigma: f64) -> Result<Option<bool>> {
        let v = self.xidot0.abs();
        Ok(match line {
            Line::WorstCase => Some(
                !regions::classify_delayed(
                    beta,
                    sigma,
                    self.tau_d,
                    Some(v),
                    Some(v / self.mu.sqrt()),
                )?
                .is_stable(),
            ),
            Line::Df72 | Line::Df74 => self.df_sigma(line, beta)?.map(|s| sigma < s),
            Line::LinearExact => self.linear_stable(beta)?.map(|stable| !stable),
        })
    }
}

/// Agreement of one line on one panel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Agreement {
    /// Line name ([`Line::name`]).
    pub line: &'static str,
    /// Grid points where prediction and simulation agree (`None`: line not defined).
    pub correct: Option<usize>,
    /// `correct / points`.
    pub fraction: Option<f64>,
    /// Points the line calls growing that do not grow.
    pub false_growth: Option<usize>,
    /// Growing points the line calls not growing.
    pub missed_growth: Option<usize>,
}

/// One panel of the atlas.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AtlasPanel {
    /// μ.
    pub mu: f64,
    /// τ_D.
    pub tau_d: f64,
    /// ξ̇₀.
    pub xidot0: f64,
    /// Grid points.
    pub points: usize,
    /// Simulated growing points.
    pub growing: usize,
    /// Periods simulated, summed over the points (growing points stop early).
    pub periods_total: u64,
    /// Measured wall time per simulated period, over the panel (ns).
    pub ns_per_period_mean: f64,
    /// One entry per [`Line::ALL`].
    pub agreement: Vec<Agreement>,
}

impl AtlasPanel {
    /// The agreement fraction of `line`.
    #[must_use]
    pub fn fraction(&self, line: Line) -> Option<f64> {
        self.agreement
            .iter()
            .find(|a| a.line == line.name())
            .and_then(|a| a.fraction)
    }
}

/// The atlas document.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Atlas {
    /// `spec_crc64` of the map it was computed from.
    pub map_spec_crc64: String,
    /// Horizon of the map in periods.
    pub periods: u64,
    /// CPU time of the map's computation in seconds (summed over its shards), if measured.
    pub cpu_seconds: Option<f64>,
    /// `cpu_seconds` per simulated period, in nanoseconds.
    pub cpu_ns_per_period: Option<f64>,
    /// Panels, in the map's order.
    pub panels: Vec<AtlasPanel>,
}

/// Compares every panel of a complete map with every [`Line`].
///
/// # Errors
/// A sharded map, or parameters out of the analysis' range.
pub fn compute(m: &MapFile) -> Result<Atlas, AtlasError> {
    if m.shard.is_some() {
        return Err(AtlasError::Sharded);
    }
    if m.spec.damping != 0.0 {
        return Err(AtlasError::Damped {
            beta_v: m.spec.damping,
        });
    }
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
                let Some(pred) =
                    slice
                        .predicts_growth(line, q.beta, q.sigma)
                        .map_err(|source| AtlasError::Param {
                            mu: p.mu,
                            tau_d: p.tau_d,
                            source,
                        })?
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

/// File name of a panel's image.
#[must_use]
pub fn panel_file(mu: f64, tau_d: f64, xidot0: f64, ext: &str) -> String {
    format!("atlas-mu{mu:.4}-tau{tau_d}-xidot{xidot0}.{ext}")
}

// The atlas as Markdown (`hostctl map atlas --markdown`).

/// A fraction in [0, 1] as a percentage with one decimal (`42.0 %`), or `n/a`.
#[must_use]
pub fn pct(f: Option<f64>) -> String {
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
            let name = panel_file(p.mu, p.tau_d, p.xidot0, f.ext);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_file::{Panel, Spec, Values};
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
