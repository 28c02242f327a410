//! Parallel (β, σ) stability maps (the paper's Fig. 6/7). std only.
//!
//! Units: dimensionless (Table I). Every grid point starts at ξ₀ = 0 with ξ̇₀ (Sec. IV), runs
//! the exact solver with all effects of the paper (quantization, Coulomb, viscous, delay) for up
//! to `periods` periods and is classified by [`crate::classify`]. Grid points are numbered
//! row-major (σ outer, β inner) so shards (`index % n == k`) can be merged by index.
//!
//! Invariant: results are deterministic and independent of thread count and sharding.

use crate::classify::{classify, Class, Outcome, Thresholds};
use crate::exact::{Full, History, NoDelay};
use crate::params::Params;
use crate::plant::Motion;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// An inclusive linearly spaced axis `lo:hi:n`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    /// First value.
    pub lo: f64,
    /// Last value.
    pub hi: f64,
    /// Number of points (≥ 1).
    pub n: usize,
}

impl Axis {
    /// Parses `a:b:n`.
    pub fn parse(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(':').collect();
        let bad =
            || format!("axis {s:?}: expected lo:hi:n with finite lo <= hi and 1 <= n <= 100000");
        if parts.len() != 3 {
            return Err(bad());
        }
        let lo: f64 = parts[0].trim().parse().map_err(|_| bad())?;
        let hi: f64 = parts[1].trim().parse().map_err(|_| bad())?;
        let n: usize = parts[2].trim().parse().map_err(|_| bad())?;
        if !(lo.is_finite() && hi.is_finite() && lo <= hi && (1..=100_000).contains(&n)) {
            return Err(bad());
        }
        Ok(Self { lo, hi, n })
    }

    /// The i-th value.
    #[must_use]
    pub fn at(&self, i: usize) -> f64 {
        if self.n == 1 {
            self.lo
        } else {
            self.lo + (self.hi - self.lo) * i as f64 / (self.n - 1) as f64
        }
    }
}

/// A map request.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MapSpec {
    /// μ.
    pub mu: f64,
    /// τ_D.
    pub tau_d: f64,
    /// ξ̇₀ (with ξ₀ = 0).
    pub xidot0: f64,
    /// β axis.
    pub beta: Axis,
    /// σ axis.
    pub sigma: Axis,
    /// Horizon in periods.
    pub periods: u64,
    /// Delay-line history before τ = 0.
    #[serde(default)]
    pub history: History,
}

impl MapSpec {
    /// Number of grid points.
    #[must_use]
    pub fn len(&self) -> usize {
        self.beta.n * self.sigma.n
    }

    /// True for an empty grid (never, after parsing).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// (β, σ) of grid point `index`.
    #[must_use]
    pub fn point(&self, index: usize) -> (f64, f64) {
        (
            self.beta.at(index % self.beta.n),
            self.sigma.at(index / self.beta.n),
        )
    }
}

/// One classified grid point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MapPoint {
    /// Grid index.
    pub index: usize,
    /// β.
    pub beta: f64,
    /// σ.
    pub sigma: f64,
    /// Class.
    pub class: Class,
    /// Periods simulated.
    pub periods_run: u64,
    /// H_T(0).
    pub h0: f64,
    /// H_T at the end.
    pub h_end: f64,
    /// Largest |ξ| over the tail of the horizon.
    pub tail_amplitude: f64,
}

/// Simulates and classifies one (β, σ) point (delay-line history: [`History::HoldInitial`]).
#[must_use]
pub fn simulate_point(
    mu: f64,
    beta: f64,
    sigma: f64,
    tau_d: f64,
    xidot0: f64,
    periods: u64,
) -> Outcome {
    simulate_point_with(
        mu,
        beta,
        sigma,
        tau_d,
        xidot0,
        periods,
        History::HoldInitial,
    )
}

/// Simulates and classifies one (β, σ) point with the given delay-line history.
#[must_use]
pub fn simulate_point_with(
    mu: f64,
    beta: f64,
    sigma: f64,
    tau_d: f64,
    xidot0: f64,
    periods: u64,
    history: History,
) -> Outcome {
    let p = Params {
        mu,
        beta,
        sigma,
        tau_d,
    };
    let init = Motion { x: 0.0, v: xidot0 };
    let th = Thresholds::default();
    if tau_d == 0.0 {
        match NoDelay::new(p, init, history) {
            Ok(mut s) => classify(&mut s, periods, &th),
            Err(_) => invalid(),
        }
    } else {
        match Full::new(p, init, history) {
            Ok(mut s) => classify(&mut s, periods, &th),
            Err(_) => invalid(),
        }
    }
}

fn invalid() -> Outcome {
    Outcome {
        class: Class::Growing,
        periods_run: 0,
        h0: f64::NAN,
        h_end: f64::NAN,
        h_max: f64::NAN,
        tail_amplitude: f64::NAN,
        tail_speed: f64::NAN,
    }
}

/// Runs the grid points `indices` in parallel (rayon), calling `progress` once per point.
pub fn run(spec: &MapSpec, indices: &[usize], progress: &(dyn Fn() + Sync)) -> Vec<MapPoint> {
    let mut out: Vec<MapPoint> = indices
        .par_iter()
        .with_max_len(1)
        .map(|&i| {
            let (beta, sigma) = spec.point(i);
            let o = simulate_point_with(
                spec.mu,
                beta,
                sigma,
                spec.tau_d,
                spec.xidot0,
                spec.periods,
                spec.history,
            );
            progress();
            MapPoint {
                index: i,
                beta,
                sigma,
                class: o.class,
                periods_run: o.periods_run,
                h0: o.h0,
                h_end: o.h_end,
                tail_amplitude: o.tail_amplitude,
            }
        })
        .collect();
    out.sort_by_key(|p| p.index);
    out
}

/// Indices of shard `k` of `n` (k in 0..n): every n-th point starting at k.
#[must_use]
pub fn shard(spec: &MapSpec, k: usize, n: usize) -> Vec<usize> {
    (0..spec.len()).filter(|i| i % n == k).collect()
}

/// Analytic region of Fig. 3 (τ_D = 0) for a given ξ̇_max: 'A'..'E' (boundaries belong to the
/// more stable side): `stiffwall_core::regions::classify` as a letter ('?' for invalid input).
#[must_use]
pub fn region_no_delay(beta: f64, sigma: f64, xidot_max: f64) -> char {
    stiffwall_core::regions::classify(beta, sigma, Some(xidot_max))
        .map_or('?', |r| r.label().chars().next().unwrap_or('?'))
}
