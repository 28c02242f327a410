//! The map file's contents: the sweep ([`Spec`], its limits and its own validation), the
//! panels ([`Panel`]), the document ([`MapFile`]) and its measured cost ([`Cost`]).
use serde::{Deserialize, Serialize};
use stiffwall_sim::exact::History;
use stiffwall_sim::map::{Axis, MapPoint, MapSpec};

use super::error::{ensure, MapFileError, Result};
use crate::values::Values;

/// Largest number of ξ̇₀ values of one map.
pub const MAX_PANELS: usize = 64;

/// Largest number of panels (μ values × τ_D values × ξ̇₀ values) of one map.
pub const MAX_ALL_PANELS: usize = 4096;

/// Largest number of points of one map (all panels).
pub const MAX_ALL_POINTS: usize = 40_000_000;

/// Largest number of shards of one sweep.
pub const MAX_SHARDS: usize = 100_000;

/// The sweep description stored in the JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Spec {
    /// μ: one value or a slice axis.
    pub mu: Values,
    /// τ_D: one value or a slice axis.
    pub tau_d: Values,
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
    /// Virtual damping β_v = B/(K·T) of every point, dimensionless, in [0, 1000]; omitted from
    /// the JSON (and so from `spec_crc64`) when 0, so spring-only files are unchanged.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub damping: f64,
}

#[allow(clippy::trivially_copy_pass_by_ref)] // serde's skip_serializing_if passes a reference
fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl Spec {
    /// (μ, τ_D) of every slice, μ outer.
    #[must_use]
    pub fn slices(&self) -> Vec<(f64, f64)> {
        let taus = self.tau_d.values();
        self.mu
            .values()
            .into_iter()
            .flat_map(|mu| taus.iter().map(move |&t| (mu, t)))
            .collect()
    }

    /// The single-panel spec of every panel, in file order (slice outer, ξ̇₀ inner).
    #[must_use]
    pub fn panels(&self) -> Vec<MapSpec> {
        self.slices()
            .into_iter()
            .flat_map(|(mu, tau_d)| {
                self.xidot0
                    .iter()
                    .map(move |&v| self.panel_at(mu, tau_d, v))
            })
            .collect()
    }

    /// The single-panel spec of (μ, τ_D, ξ̇₀).
    #[must_use]
    pub fn panel_at(&self, mu: f64, tau_d: f64, xidot0: f64) -> MapSpec {
        MapSpec {
            mu,
            tau_d,
            xidot0,
            beta: self.beta,
            sigma: self.sigma,
            periods: self.periods,
            history: self.history,
            damping: self.damping,
        }
    }

    /// Checks every field (see [`MapSpec::validate`]), 1..=[`MAX_PANELS`] ξ̇₀ values, at most
    /// [`MAX_ALL_PANELS`] panels and [`MAX_ALL_POINTS`] points, before anything is allocated.
    ///
    /// # Errors
    /// A message naming the field and its allowed range.
    pub fn validate(&self) -> Result<()> {
        ensure!(
            Spec,
            (1..=MAX_PANELS).contains(&self.xidot0.len()),
            "xidot0: {} values, allowed 1 to {MAX_PANELS}",
            self.xidot0.len()
        );
        self.mu
            .validate()
            .map_err(|e| MapFileError::Spec(format!("mu: {e}")))?;
        self.tau_d
            .validate()
            .map_err(|e| MapFileError::Spec(format!("tau_d: {e}")))?;
        let panels = self.mu.len() * self.tau_d.len() * self.xidot0.len();
        ensure!(
            Spec,
            panels <= MAX_ALL_PANELS,
            "{} mu x {} tau_d x {} xidot0 = {panels} panels: at most {MAX_ALL_PANELS}",
            self.mu.len(),
            self.tau_d.len(),
            self.xidot0.len()
        );
        self.panel_at(self.mu.at(0), self.tau_d.at(0), self.xidot0[0])
            .validate()
            .map_err(MapFileError::Spec)?;
        ensure!(
            Spec,
            panels.saturating_mul(self.len()) <= MAX_ALL_POINTS,
            "{panels} panels x {} points: at most {MAX_ALL_POINTS} points",
            self.len()
        );
        for p in self.panels() {
            p.validate().map_err(MapFileError::Spec)?;
        }
        Ok(())
    }

    /// Number of panels (call after [`Self::validate`]).
    #[must_use]
    pub fn panel_count(&self) -> usize {
        self.mu.len() * self.tau_d.len() * self.xidot0.len()
    }

    /// Number of (β, σ) points per panel (call after [`Self::validate`]).
    #[must_use]
    pub fn len(&self) -> usize {
        self.beta.n * self.sigma.n
    }

    /// True for an empty grid (never, after validation).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// CRC-64/XZ of the spec's compact JSON, as 16 hex digits.
    #[must_use]
    pub fn crc64(&self) -> String {
        let json = serde_json::to_string(self).unwrap_or_default();
        let crc = crc::Crc::<u64>::new(&crc::CRC_64_XZ).checksum(json.as_bytes());
        format!("{crc:016x}")
    }

    /// The first field in which `other` differs, for error messages.
    pub(super) fn first_difference(&self, other: &Self) -> &'static str {
        if self.mu != other.mu {
            "mu"
        } else if self.tau_d != other.tau_d {
            "tau_d"
        } else if self.xidot0 != other.xidot0 {
            "xidot0"
        } else if self.beta != other.beta {
            "beta"
        } else if self.sigma != other.sigma {
            "sigma"
        } else if self.periods != other.periods {
            "periods"
        } else if self.history != other.history {
            "history"
        } else {
            "damping"
        }
    }
}

/// One panel (one μ, τ_D, ξ̇₀).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Panel {
    /// μ.
    pub mu: f64,
    /// τ_D.
    pub tau_d: f64,
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
    /// [`Spec::crc64`] of `spec` (absent in files of older versions: refused by [`validate`]).
    #[serde(default)]
    pub spec_crc64: String,
    /// Shard (k, n), or None when complete.
    pub shard: Option<(usize, usize)>,
    /// Panels.
    pub panels: Vec<Panel>,
    /// Measured cost, per panel and point (not part of the result: it differs run to run).
    pub cost: Cost,
    /// Wall time of the computation in seconds (sum over shards after a merge).
    pub seconds: f64,
}

/// Measured cost of a map: per point, wall time per simulated period; for the whole run, the
/// CPU time the operating system charged (which, unlike wall time, does not grow when the
/// machine is oversubscribed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cost {
    /// Sum of `periods_run` over all points.
    pub periods_total: u64,
    /// Sum over points of `periods_run × ns_per_period`, in seconds of worker-thread wall time
    /// (each point runs on one thread; this is core time when every thread has a core).
    pub core_seconds: f64,
    /// `core_seconds / periods_total` in nanoseconds (0 for no periods).
    pub ns_per_period_mean: f64,
    /// User + system CPU time of the process during the computation, in seconds (Linux
    /// `/proc/self/stat`, 10 ms resolution; summed over shards by a merge); `None` where it
    /// could not be read.
    #[serde(default)]
    pub cpu_seconds: Option<f64>,
    /// `cpu_seconds / periods_total` in nanoseconds: the figure for sizing a sweep.
    #[serde(default)]
    pub cpu_ns_per_period: Option<f64>,
    /// Per panel (in panel order), the ns per period of each point (in point order).
    pub ns_per_period: Vec<Vec<f64>>,
    /// Number of points that ended by cycle detection (`stiffwall_sim::classify`): their
    /// solver state repeated bit for bit (whole cycles skipped) or up to the position's
    /// rounding drift (the rest replayed from one recorded cycle), with a result identical to
    /// simulating every period. Their `periods_run` still counts every period of the horizon.
    /// 0 in files from before the key.
    #[serde(default)]
    pub cycle_points: u64,
}

impl Cost {
    /// The cost of `panels` with per-point `ns_per_period` (same shape), without CPU time.
    #[must_use]
    pub fn of(panels: &[Panel], ns_per_period: Vec<Vec<f64>>) -> Self {
        let mut periods_total = 0u64;
        let mut core_ns = 0.0;
        for (p, ns) in panels.iter().zip(&ns_per_period) {
            for (pt, &c) in p.points.iter().zip(ns) {
                periods_total += pt.periods_run;
                core_ns += pt.periods_run as f64 * c;
            }
        }
        Self {
            periods_total,
            core_seconds: core_ns * 1e-9,
            ns_per_period_mean: if periods_total == 0 {
                0.0
            } else {
                core_ns / periods_total as f64
            },
            cpu_seconds: None,
            cpu_ns_per_period: None,
            ns_per_period,
            cycle_points: 0,
        }
    }

    /// Sets the number of points that ended by cycle detection.
    #[must_use]
    pub fn with_cycle_points(mut self, cycle_points: u64) -> Self {
        self.cycle_points = cycle_points;
        self
    }

    /// Sets the measured CPU time (and the CPU ns per period derived from it).
    #[must_use]
    pub fn with_cpu_seconds(mut self, cpu_seconds: Option<f64>) -> Self {
        self.cpu_seconds = cpu_seconds;
        self.cpu_ns_per_period = cpu_seconds
            .filter(|_| self.periods_total > 0)
            .map(|s| s * 1e9 / self.periods_total as f64);
        self
    }
}

/// CPU time (user + system) of this process so far in seconds, from Linux `/proc/self/stat`
/// (clock ticks of 1/100 s, the fixed `USER_HZ` of Linux's user interface); `None` elsewhere.
#[must_use]
pub fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which may hold spaces) start at field 3 (state).
    let rest = &stat[stat.rfind(')')? + 1..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: u64 = f.get(11)?.parse().ok()?;
    let stime: u64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) as f64 / 100.0)
}

impl MapFile {
    /// (k, n) of this file, (0, 1) for a complete map.
    #[must_use]
    pub fn shard_or_whole(&self) -> (usize, usize) {
        self.shard.unwrap_or((0, 1))
    }
}
