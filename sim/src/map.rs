//! Parallel (β, σ) stability maps (the paper's Fig. 6/7). std only.
//!
//! Units: dimensionless (Table I). Every grid point starts at ξ₀ = 0 with ξ̇₀ (Sec. IV), runs
//! the exact solver with all effects of the paper (quantization, Coulomb, viscous, delay) for up
//! to `periods` periods and is classified by [`crate::classify`]. Grid points are numbered
//! row-major (σ outer, β inner) so shards (`index % n == k`) can be merged by index.
//!
//! Invariant: results are deterministic and independent of thread count and sharding (the
//! measured cost of [`run_with_cost`], ns of wall time per period, is not a result and varies). A spec
//! from outside (a file) is checked with [`MapSpec::validate`] before any use: axes of
//! 1..=[`MAX_AXIS_POINTS`] points, at most [`MAX_GRID_POINTS`] grid points, ≥ 1 period.
//! [`MapSpec::damping`] is the dimensionless virtual damping β_v = B/(K·T) of the wall law
//! (the exact solver's [`crate::exact::Exact::with_beta_v`]); 0 (the default) is the paper's
//! spring-only wall, bit for bit, and is not serialised.

use crate::classify::{classify, Class, Cycle, Outcome, Thresholds};
use crate::exact::{Full, History, NoDelay, MAX_BETA_V};
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

/// Largest number of points on one axis.
pub const MAX_AXIS_POINTS: usize = 100_000;

/// Largest number of (β, σ) points of one map panel.
pub const MAX_GRID_POINTS: usize = 4_000_000;

/// Largest horizon in periods.
pub const MAX_PERIODS: u64 = 100_000_000;

impl Axis {
    /// Parses `a:b:n`.
    pub fn parse(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(':').collect();
        let bad = || {
            format!(
                "axis {s:?}: expected lo:hi:n with finite lo <= hi and 1 <= n <= {MAX_AXIS_POINTS}"
            )
        };
        if parts.len() != 3 {
            return Err(bad());
        }
        let lo: f64 = parts[0].trim().parse().map_err(|_| bad())?;
        let hi: f64 = parts[1].trim().parse().map_err(|_| bad())?;
        let n: usize = parts[2].trim().parse().map_err(|_| bad())?;
        let axis = Self { lo, hi, n };
        axis.validate().map_err(|_| bad())?;
        Ok(axis)
    }

    /// Checks finite `lo <= hi` and `1 <= n <=` [`MAX_AXIS_POINTS`].
    ///
    /// # Errors
    /// A message naming the violated bound.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.lo.is_finite() && self.hi.is_finite() && self.lo <= self.hi) {
            return Err(format!(
                "lo = {}, hi = {}: need finite lo <= hi",
                self.lo, self.hi
            ));
        }
        if !(1..=MAX_AXIS_POINTS).contains(&self.n) {
            return Err(format!(
                "n = {}: allowed range is [1, {MAX_AXIS_POINTS}]",
                self.n
            ));
        }
        Ok(())
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
    /// Virtual damping β_v = B/(K·T), in [0, [`MAX_BETA_V`]] (0: spring only; omitted from the
    /// JSON when 0, so spring-only specs serialise as before).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub damping: f64,
}

#[allow(clippy::trivially_copy_pass_by_ref)] // serde's skip_serializing_if passes a reference
fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl MapSpec {
    /// Checks every field: μ > 0, τ_D in [0, 250], finite ξ̇₀, both axes
    /// ([`Axis::validate`], lo ≥ 0), at most [`MAX_GRID_POINTS`] points and
    /// 1..=[`MAX_PERIODS`] periods, damping β_v in [0, [`MAX_BETA_V`]]. After this, [`Self::len`] cannot overflow.
    ///
    /// # Errors
    /// A message naming the field and its allowed range.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.mu.is_finite() && self.mu > 0.0) {
            return Err(format!("mu = {}: allowed range is > 0", self.mu));
        }
        if !(self.tau_d.is_finite() && (0.0..=250.0).contains(&self.tau_d)) {
            return Err(format!("tau_d = {}: allowed range is [0, 250]", self.tau_d));
        }
        if !(self.xidot0.is_finite() && self.xidot0.abs() <= 1e12) {
            return Err(format!(
                "xidot0 = {}: allowed range is finite, |xidot0| <= 1e12",
                self.xidot0
            ));
        }
        for (name, axis) in [("beta", &self.beta), ("sigma", &self.sigma)] {
            axis.validate().map_err(|e| format!("{name} axis: {e}"))?;
            if axis.lo < 0.0 {
                return Err(format!(
                    "{name} axis: lo = {}: allowed range is >= 0",
                    axis.lo
                ));
            }
        }
        match self.beta.n.checked_mul(self.sigma.n) {
            Some(len) if len <= MAX_GRID_POINTS => {}
            _ => {
                return Err(format!(
                    "{} x {} grid points: at most {MAX_GRID_POINTS}",
                    self.beta.n, self.sigma.n
                ))
            }
        }
        if !(1..=MAX_PERIODS).contains(&self.periods) {
            return Err(format!(
                "periods = {}: allowed range is [1, {MAX_PERIODS}]",
                self.periods
            ));
        }
        if !(self.damping.is_finite() && (0.0..=MAX_BETA_V).contains(&self.damping)) {
            return Err(format!(
                "damping = {}: allowed range is [0, {MAX_BETA_V}] (beta_v = B/(K*T))",
                self.damping
            ));
        }
        Ok(())
    }

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
    simulate_point_th(p, xidot0, periods, history, &Thresholds::default())
}

/// [`simulate_point_with`] with explicit classification thresholds and options (e.g.
/// [`Thresholds::cycle_detection`] off); the model's (μ, β, σ, τ_D) in `p`.
#[must_use]
pub fn simulate_point_th(
    p: Params,
    xidot0: f64,
    periods: u64,
    history: History,
    th: &Thresholds,
) -> Outcome {
    simulate_point_damped_th(p, xidot0, periods, history, 0.0, th)
}

/// Simulates and classifies one point of the paper's model `p` (all effects, two-sided wall,
/// ξ₀ = 0, ξ̇₀ = `xidot0`) with the virtual damper β_v = `beta_v` (0: exactly
/// [`simulate_point_with`]). Invalid parameters (β_v outside [0, [`MAX_BETA_V`]] included)
/// give a `Growing` outcome of 0 periods with NaN energies.
#[must_use]
pub fn simulate_point_damped(
    p: Params,
    xidot0: f64,
    periods: u64,
    history: History,
    beta_v: f64,
) -> Outcome {
    simulate_point_damped_th(p, xidot0, periods, history, beta_v, &Thresholds::default())
}

/// [`simulate_point_damped`] with explicit classification thresholds and options (e.g.
/// [`Thresholds::cycle_detection`] off).
#[must_use]
pub fn simulate_point_damped_th(
    p: Params,
    xidot0: f64,
    periods: u64,
    history: History,
    beta_v: f64,
    th: &Thresholds,
) -> Outcome {
    simulate_point_law_th(p, xidot0, periods, history, (beta_v, 0), th)
}

/// [`simulate_point_damped`] with the firmware's damper law: `damper` = (β_v, dead band N in
/// counts per period), N = 0 the plain difference, N ≥ 1 `dead-band-N` (the difference is 0
/// while |n_h − n_(h−1)| ≤ N; [`Exact::with_dead_band`](crate::exact::Exact::with_dead_band)).
/// A dead band above [`crate::exact::MAX_DEAD_BAND`] gives the invalid outcome.
#[must_use]
pub fn simulate_point_law(
    p: Params,
    xidot0: f64,
    periods: u64,
    history: History,
    damper: (f64, u8),
) -> Outcome {
    simulate_point_law_th(p, xidot0, periods, history, damper, &Thresholds::default())
}

/// [`simulate_point_law`] with explicit classification thresholds and options.
#[must_use]
pub fn simulate_point_law_th(
    p: Params,
    xidot0: f64,
    periods: u64,
    history: History,
    (beta_v, dead_band): (f64, u8),
    th: &Thresholds,
) -> Outcome {
    let init = Motion { x: 0.0, v: xidot0 };
    if p.tau_d == 0.0 {
        match NoDelay::new(p, init, history)
            .and_then(|s| s.with_beta_v(beta_v))
            .and_then(|s| s.with_dead_band(dead_band))
        {
            Ok(mut s) => classify(&mut s, periods, th),
            Err(_) => invalid(),
        }
    } else {
        match Full::new(p, init, history)
            .and_then(|s| s.with_beta_v(beta_v))
            .and_then(|s| s.with_dead_band(dead_band))
        {
            Ok(mut s) => classify(&mut s, periods, th),
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
        cycle: None,
    }
}

/// How [`run_with`] computes. Not part of the result: every choice gives the same points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunOptions {
    /// Finish a point from its exactly repeating state ([`Thresholds::cycle_detection`], the
    /// default); off: brute force over the whole horizon.
    pub cycle_detection: bool,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            cycle_detection: true,
        }
    }
}

/// What [`run_with`] returns, in the order of the points.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOutput {
    /// The classified points.
    pub points: Vec<MapPoint>,
    /// Each point's measured cost: ns of wall time on its worker thread per period of its
    /// `periods_run` (skipped cycles included), at least one period.
    pub ns_per_period: Vec<f64>,
    /// Each point's [`Outcome::cycle`]: the repeating state that ended it early.
    pub cycle: Vec<Option<Cycle>>,
}

impl RunOutput {
    /// Number of points that ended by cycle detection (whole cycles skipped or the rest of
    /// the horizon replayed).
    #[must_use]
    pub fn cycle_points(&self) -> usize {
        self.cycle.iter().filter(|c| c.is_some()).count()
    }

    /// Of [`Self::cycle_points`], those whose state repeated bit for bit (cycles skipped).
    #[must_use]
    pub fn exact_cycle_points(&self) -> usize {
        self.cycle
            .iter()
            .filter(|c| c.is_some_and(|c| c.exact))
            .count()
    }
}

/// Runs the grid points `indices` in parallel (rayon), calling `progress` once per point.
pub fn run(spec: &MapSpec, indices: &[usize], progress: &(dyn Fn() + Sync)) -> Vec<MapPoint> {
    run_with_cost(spec, indices, progress).0
}

/// [`run`], also returning each point's measured cost in nanoseconds of wall time per simulated
/// period (the point's solve time on its worker thread over its `periods_run`, at least one),
/// in the order of the points.
pub fn run_with_cost(
    spec: &MapSpec,
    indices: &[usize],
    progress: &(dyn Fn() + Sync),
) -> (Vec<MapPoint>, Vec<f64>) {
    let o = run_with(spec, indices, progress, RunOptions::default());
    (o.points, o.ns_per_period)
}

/// [`run_with_cost`] with explicit [`RunOptions`], also reporting which points ended by cycle
/// detection.
pub fn run_with(
    spec: &MapSpec,
    indices: &[usize],
    progress: &(dyn Fn() + Sync),
    opts: RunOptions,
) -> RunOutput {
    let th = Thresholds {
        cycle_detection: opts.cycle_detection,
        ..Thresholds::default()
    };
    let mut out: Vec<(MapPoint, f64, Option<Cycle>)> = indices
        .par_iter()
        .with_max_len(1)
        .map(|&i| {
            let (beta, sigma) = spec.point(i);
            let t0 = std::time::Instant::now();
            let p = Params {
                mu: spec.mu,
                beta,
                sigma,
                tau_d: spec.tau_d,
            };
            let o = simulate_point_damped_th(
                p,
                spec.xidot0,
                spec.periods,
                spec.history,
                spec.damping,
                &th,
            );
            let ns = t0.elapsed().as_secs_f64() * 1e9;
            progress();
            let point = MapPoint {
                index: i,
                beta,
                sigma,
                class: o.class,
                periods_run: o.periods_run,
                h0: o.h0,
                h_end: o.h_end,
                tail_amplitude: o.tail_amplitude,
            };
            (point, ns / o.periods_run.max(1) as f64, o.cycle)
        })
        .collect();
    out.sort_by_key(|(p, _, _)| p.index);
    let mut r = RunOutput {
        points: Vec::with_capacity(out.len()),
        ns_per_period: Vec::with_capacity(out.len()),
        cycle: Vec::with_capacity(out.len()),
    };
    for (p, ns, c) in out {
        r.points.push(p);
        r.ns_per_period.push(ns);
        r.cycle.push(c);
    }
    r
}

/// Indices of shard `k` of `n` (k in 0..n): every n-th point starting at k (empty for n = 0).
#[must_use]
pub fn shard(spec: &MapSpec, k: usize, n: usize) -> Vec<usize> {
    if n == 0 {
        return Vec::new();
    }
    (k..spec.len()).step_by(n).collect()
}

/// Number of points of shard `k` of `n` in a grid of `len` points (0 for n = 0).
#[must_use]
pub fn shard_len(len: usize, k: usize, n: usize) -> usize {
    if n == 0 || k >= len {
        0
    } else {
        (len - k).div_ceil(n)
    }
}

/// Analytic region of Fig. 3 (τ_D = 0) for a given ξ̇_max: 'A'..'E' (boundaries belong to the
/// more stable side): `stiffwall_core::regions::classify` as a letter ('?' for invalid input).
#[must_use]
pub fn region_no_delay(beta: f64, sigma: f64, xidot_max: f64) -> char {
    stiffwall_core::regions::classify(beta, sigma, Some(xidot_max))
        .map_or('?', |r| r.label().chars().next().unwrap_or('?'))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(bn: usize, sn: usize) -> MapSpec {
        MapSpec {
            mu: 100.0,
            tau_d: 0.0,
            xidot0: 5.0,
            beta: Axis {
                lo: 0.0,
                hi: 1.0,
                n: bn,
            },
            sigma: Axis {
                lo: 0.0,
                hi: 2.0,
                n: sn,
            },
            periods: 100,
            history: History::HoldInitial,
            damping: 0.0,
        }
    }

    #[test]
    fn huge_or_empty_grids_are_refused_before_len() {
        let e = spec(1_000_000_000, 1_000_000_000).validate().unwrap_err();
        assert!(e.contains("beta axis") && e.contains("100000"), "{e}");
        let e = spec(100_000, 100_000).validate().unwrap_err();
        assert!(e.contains("at most 4000000"), "{e}");
        assert!(spec(0, 3).validate().unwrap_err().contains("[1, 100000]"));
        let mut s = spec(3, 3);
        s.periods = 0;
        assert!(s.validate().unwrap_err().contains("periods = 0"));
        assert!(spec(34, 21).validate().is_ok());
    }

    #[test]
    fn shard_len_counts_shard_indices() {
        let s = spec(7, 3);
        for n in 0..25 {
            for k in 0..n + 2 {
                assert_eq!(shard(&s, k, n).len(), shard_len(s.len(), k, n), "{k}/{n}");
            }
        }
        let all: usize = (0..4).map(|k| shard(&s, k, 4).len()).sum();
        assert_eq!(all, 21);
    }

    #[test]
    fn damping_is_validated_and_zero_is_not_serialised() {
        let mut s = spec(3, 3);
        let plain = toml::to_string(&s).unwrap();
        assert!(!plain.contains("damping"), "{plain}");
        let back: MapSpec = toml::from_str(&plain).unwrap();
        assert_eq!(back, s);
        for bad in [-1e-9, f64::NAN, f64::INFINITY, MAX_BETA_V * 1.001] {
            s.damping = bad;
            let e = s.validate().unwrap_err();
            assert!(e.contains("damping") && e.contains("[0, 1000]"), "{e}");
        }
        s.damping = 2.0;
        assert!(s.validate().is_ok());
        assert!(toml::to_string(&s).unwrap().contains("damping = 2.0"));
    }

    #[test]
    fn a_damper_makes_the_undamped_zoh_spring_decay() {
        // μ = 100, β = 0: the sampled spring alone gains energy every cycle (K_max = 0 by
        // Gil-Avello-Rubio at b = 0); β_v = 2, i.e. B = 2KT, is inside the exact linear boundary
        // (small-B estimate K_max ≈ B/(T/2) = 4K). With σ = 0 nothing can hold the mass at rest
        // against the quantized spring's ±½ at counts 0 and −1, so the damped wall cannot decay
        // to rest: it stays in a limit cycle inside one count. Coulomb σ = ½ can hold it there.
        let mut s = spec(1, 1);
        s.periods = 20_000;
        let undamped = run(&s, &[0], &|| {})[0];
        s.damping = 2.0;
        let damped = run(&s, &[0], &|| {})[0];
        assert_eq!(undamped.class, Class::Growing, "{undamped:?}");
        assert_eq!(damped.class, Class::Persistent, "{damped:?}");
        assert!(damped.h_end < 1e-4 * damped.h0 && damped.tail_amplitude < 1.0);
        s.sigma = Axis {
            lo: 0.5,
            hi: 0.5,
            n: 1,
        };
        let damped = run(&s, &[0], &|| {})[0];
        assert_eq!(damped.class, Class::NonMonotoneDecay, "{damped:?}");
        s.damping = 0.0;
        assert_eq!(run(&s, &[0], &|| {})[0].class, Class::Growing);
        let phys = stiffwall_core::PhysicalParams {
            mass: 100.0,
            viscous: 0.0,
            coulomb: 0.0,
            resolution: 1.0,
            period_s: 1.0,
            stiffness: 1.0,
            delay_s: 0.0,
            rotational: false,
        };
        let c = stiffwall_core::criteria::exact_linear_stable;
        assert!(!c(&phys, 0.0).unwrap() && c(&phys, 2.0).unwrap());
    }
}
