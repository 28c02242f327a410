//! Classification of a trajectory into the four shades of the paper's Fig. 6/7.
//!
//! Units: energies H_T (35) in K·Δ², evaluated at sample instants τ = h only.
//!
//! Rules (thresholds in [`Thresholds`], documented in `docs/model-notes-sim.md`):
//! 1. **Growing**: H_T exceeds `divergence_ratio`·max(H_T(0), 1) (the run stops early), the state
//!    diverges, or H_T at the end of the horizon exceeds H_T(0)·(1 + `growth_tol`).
//! 2. **Decaying**: the mass comes to rest for good (at rest under an unchanged force for longer
//!    than the delay line, a fixed point, see [`crate::ExactSim::at_rest`]) before the horizon.
//!    - **monotonically** if H_T(h+1) ≤ H_T(h) + `mono_tol`·max(H_T(0), 1) at every sample,
//!    - **non-monotonically** otherwise.
//! 3. **Persistent**: neither: still moving at the end, with no net energy gain.
//!
//! **Cycle detection** (`Thresholds::cycle_detection`, on by default): the sampled system is
//! deterministic, so once the solver's state at a sample instant repeats bit for bit
//! ([`ExactSim::same_state`]; Brent's algorithm: one saved state, compared at every sample,
//! re-saved at powers of two) the trajectory is periodic with the found period L, and every
//! later sample equals one already classified. The rules above only take maxima (H_T, tail
//! |ξ| and |ξ̇|), the last H_T, and per-sample tests (monotonicity of consecutive pairs,
//! divergence, rest); within the cycle every such value and pair has been seen, so whole
//! cycles are skipped: up to just before the tail window, then, once the tail has covered
//! one whole cycle, up to the last L − 1 periods before the horizon, which run as usual (they
//! give H_T at the end). The outcome is identical to the brute-force run, field by field
//! ([`Outcome::cycle`] apart); states that never repeat exactly run in full. The solver's own
//! period counter ([`ExactSim::period`]) then lags `periods_run` by the skipped periods.
//!
//! Invariant: the classifier calls `step_period` at most `periods` times and stops at rest.

use crate::exact::{storage, ExactSim};

/// The four classes, darkest first (Fig. 6/7 shading).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "std", serde(rename_all = "snake_case"))]
pub enum Class {
    /// Energy grows (dark).
    Growing,
    /// Oscillations persist (medium).
    Persistent,
    /// Motion stops, energy not monotonic at samples (light).
    NonMonotoneDecay,
    /// Motion stops, energy monotonically decreasing at samples (white).
    MonotoneDecay,
}

impl Class {
    /// Short name used in JSON and CSV.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Growing => "growing",
            Self::Persistent => "persistent",
            Self::NonMonotoneDecay => "non_monotone_decay",
            Self::MonotoneDecay => "monotone_decay",
        }
    }

    /// True for the two decaying classes.
    #[must_use]
    pub fn decays(self) -> bool {
        matches!(self, Self::NonMonotoneDecay | Self::MonotoneDecay)
    }
}

/// Classification thresholds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// Early stop as growing when H_T > ratio·max(H_T(0), 1).
    pub divergence_ratio: f64,
    /// Growing when H_T(end) > H_T(0)·(1 + growth_tol).
    pub growth_tol: f64,
    /// Relative tolerance of the monotonicity test (floating-point noise).
    pub mono_tol: f64,
    /// Fraction of the horizon at its end over which the oscillation amplitude is measured.
    pub tail_fraction: f64,
    /// Skip whole periods of an exactly repeating state (see the module header; the outcome
    /// is the same either way, only faster). Off: brute force over the whole horizon.
    pub cycle_detection: bool,
}

impl Default for Thresholds {
    fn default() -> Self {
        Self {
            divergence_ratio: 1e6,
            growth_tol: 1e-9,
            mono_tol: 1e-12,
            tail_fraction: 0.1,
            cycle_detection: true,
        }
    }
}

/// Result of a classification run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outcome {
    /// The class.
    pub class: Class,
    /// Periods simulated (less than the horizon on early stop).
    pub periods_run: u64,
    /// H_T(0).
    pub h0: f64,
    /// H_T at the last sample instant simulated.
    pub h_end: f64,
    /// Largest H_T seen at a sample instant.
    pub h_max: f64,
    /// Largest |ξ| at sample instants over the tail of the horizon (0 if stopped early).
    pub tail_amplitude: f64,
    /// Largest |ξ̇| at sample instants over the tail of the horizon.
    pub tail_speed: f64,
    /// The period L (in sampling periods) of the exactly repeating state that ended the run
    /// early by skipping whole cycles; `None` for a run that simulated every period (no
    /// repetition found before the end, or detection off). Not part of the classification.
    pub cycle: Option<u64>,
}

/// Runs `sim` for up to `periods` periods and classifies the trajectory.
pub fn classify<S: ExactSim>(sim: &mut S, periods: u64, th: &Thresholds) -> Outcome {
    let mu = sim.params().mu;
    let s0 = sim.state();
    let h0 = storage(mu, s0.x, s0.v);
    let scale = if h0 > 1.0 { h0 } else { 1.0 };
    let limit = th.divergence_ratio * scale;
    let tol = th.mono_tol * scale;
    let tail_start = periods - (periods as f64 * th.tail_fraction) as u64;
    let mut prev = h0;
    let mut h_max = h0;
    let mut mono = true;
    let mut amp: f64 = 0.0;
    let mut spd: f64 = 0.0;
    let mut h = 0;
    let mut class = None;
    // Brent: `saved` is the state at sample `h - lam`; compared with every later sample up to
    // `power` samples on, then replaced by the current one with `power` doubled.
    let mut saved = if th.cycle_detection {
        Some(sim.clone())
    } else {
        None
    };
    let mut power: u64 = 1;
    let mut lam: u64 = 0;
    // (L, c): the state at every sample k >= c equals the state at k + L.
    let mut cycle: Option<(u64, u64)> = None;
    let mut skipped = false;
    while h < periods {
        if let Some((l, c)) = cycle {
            // Skip q whole cycles (samples h+1 ..= h+q·L): each repeats a sample already
            // classified; only the tail maxima need care (see the module header).
            let q = if h + 1 < tail_start {
                (tail_start - 1 - h) / l
            } else if h + 1 >= tail_start.max(c + 1) + l {
                // The tail has covered L consecutive samples of the cycle: all its phases.
                (periods - h) / l
            } else {
                0
            };
            if q > 0 {
                h += q * l;
                skipped = true;
                if h >= periods {
                    break;
                }
            }
        }
        sim.step_period();
        h += 1;
        let s = sim.state();
        let e = storage(mu, s.x, s.v);
        if e > prev + tol {
            mono = false;
        }
        prev = e;
        if e > h_max {
            h_max = e;
        }
        if h >= tail_start {
            amp = amp.max(s.x.abs());
            spd = spd.max(s.v.abs());
        }
        if e.is_nan() || e > limit || sim.diverged() {
            class = Some(Class::Growing);
            break;
        }
        if sim.at_rest() {
            class = Some(if mono {
                Class::MonotoneDecay
            } else {
                Class::NonMonotoneDecay
            });
            break;
        }
        if cycle.is_none() {
            if let Some(t) = saved.as_mut() {
                lam += 1;
                if sim.same_state(t) {
                    cycle = Some((lam, h - lam));
                    saved = None;
                } else if lam == power {
                    t.clone_from(sim);
                    power *= 2;
                    lam = 0;
                }
            }
        }
    }
    let class = class.unwrap_or(if prev > h0 * (1.0 + th.growth_tol) {
        Class::Growing
    } else {
        Class::Persistent
    });
    Outcome {
        class,
        periods_run: h,
        h0,
        h_end: prev,
        h_max,
        tail_amplitude: amp,
        tail_speed: spd,
        cycle: if skipped { cycle.map(|(l, _)| l) } else { None },
    }
}
