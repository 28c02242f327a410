//! The analytic growth predictors of `hostctl map atlas` ([`Line`], evaluated on a [`Slice`])
//! and the atlas document ([`Atlas`], [`AtlasPanel`], [`Agreement`]) as plain data, shared by
//! the atlas computation and its figures.
//!
//! Units: dimensionless (Table I): μ, τ_D in periods, ξ̇₀ in ticks per period, β, σ; fractions
//! in [0, 1]. Invariant: a line that is not defined at a point (`linear_exact` beyond τ_D = 60,
//! a describing-function line without a solution) answers `None`, never a guess.

use anyhow::Result;
use serde::Serialize;
use stiffwall_core::params::Dimensionless;
use stiffwall_core::{criteria, describing, regions};

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
