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
//! position and velocity first as the cheap filter, re-saved at powers of two) the trajectory
//! is periodic with the found period L, and every later sample equals one already classified.
//! The rules above only take maxima (H_T, tail |ξ| and |ξ̇|), the last H_T, and per-sample
//! tests (monotonicity of consecutive pairs, divergence, rest); within the cycle every such
//! value and pair has been seen, so whole cycles are skipped: up to just before the tail
//! window, then, once the tail has covered one whole cycle, up to the last L − 1 periods before
//! the horizon, which run as usual (they give H_T at the end).
//!
//! Most limit cycles of the quantized loop repeat everything but the last bits of ξ: the
//! velocity, the forces and the counts ⌊ξ⌋ are periodic while ξ drifts by rounding errors of
//! ξ ← ξ + Δ (the dynamics do not depend on ξ within a count). Those
//! ([`ExactSim::same_but_position`], cycles of at most [`MAX_REPLAY`] periods) are recorded
//! for one cycle (the count at each sample, the increments Δ in the solver's order, ξ̇) and
//! replayed: ξ ← ξ + Δ with the recorded Δ (the solver's own arithmetic, so ξ is bit for bit
//! the simulated one) while every sample's count equals the recorded one; a different count
//! resumes the solver at that sample, and a replayed cycle that returns ξ bit for bit turns
//! into the skipping above. Either way the outcome is identical to the brute-force run, field
//! by field ([`Outcome::cycle`] apart); states that never repeat run in full. The solver's own
//! state and period counter ([`ExactSim::period`]) are then not those of the horizon.
//!
//! Invariant: the classifier calls `step_period` at most `periods` times and stops at rest.

use crate::exact::{storage, ExactSim};
use crate::plant::Increments;

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
    /// The cycle that ended the run early (whole cycles skipped, or periods replayed from a
    /// recorded cycle); `None` for a run that simulated every period (no repetition found
    /// before the end, or detection off). Not part of the classification.
    pub cycle: Option<Cycle>,
}

/// A repeating state found by cycle detection.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cycle {
    /// The period L in sampling periods.
    pub period: u64,
    /// True: the state repeated bit for bit and whole cycles were skipped. False: it repeated
    /// up to the position's last bits (a drift of rounding errors) and periods were replayed
    /// from one recorded cycle, a few operations per period.
    pub exact: bool,
}

/// Per-sample bookkeeping of the rules (shared by the simulated and the replayed samples).
struct Acc {
    mu: f64,
    limit: f64,
    tol: f64,
    tail_start: u64,
    prev: f64,
    h_max: f64,
    mono: bool,
    amp: f64,
    spd: f64,
}

impl Acc {
    /// Records sample `h` at (x, v); true if it makes the point growing (H_T NaN or over the
    /// limit; divergence of the state is the solver's to report).
    #[inline(always)]
    fn sample(&mut self, h: u64, x: f64, v: f64) -> bool {
        let e = storage(self.mu, x, v);
        if e > self.prev + self.tol {
            self.mono = false;
        }
        self.prev = e;
        if e > self.h_max {
            self.h_max = e;
        }
        if h >= self.tail_start {
            self.amp = self.amp.max(x.abs());
            self.spd = self.spd.max(v.abs());
        }
        e.is_nan() || e > self.limit
    }
}

/// Longest cycle recorded for replay (no allocation: the phases live on the stack).
pub const MAX_REPLAY: usize = 128;

/// One period of a cycle recorded for replay: the count the law reads at its start sample,
/// the position increments, and ξ̇ at its end sample.
#[derive(Clone, Copy, Default)]
struct Phase {
    count: u64,
    dx: Increments,
    v_end: f64,
}

/// Runs `sim` for up to `periods` periods and classifies the trajectory.
pub fn classify<S: ExactSim>(sim: &mut S, periods: u64, th: &Thresholds) -> Outcome {
    let mu = sim.params().mu;
    let s0 = sim.state();
    let h0 = storage(mu, s0.x, s0.v);
    let mut acc = Acc::new(mu, h0, periods, th);
    let mut search = Search::new(sim, th.cycle_detection);
    let mut h = 0;
    let mut class = None;
    while h < periods {
        if search.skip_cycles(&mut h, periods, acc.tail_start) {
            break;
        }
        search.step(sim);
        h += 1;
        class = settled(sim, &mut acc, h);
        if class.is_some() {
            break;
        }
        if search.recording.is_some() {
            match search.after_recording(sim, &mut acc, &mut h, periods) {
                Flow::Next => continue,
                Flow::Stop(c) => {
                    class = c;
                    break;
                }
            }
        }
        search.look_for_cycle(sim, h);
    }
    let class = class.unwrap_or(if acc.prev > h0 * (1.0 + th.growth_tol) {
        Class::Growing
    } else {
        Class::Persistent
    });
    Outcome {
        class,
        periods_run: h,
        h0,
        h_end: acc.prev,
        h_max: acc.h_max,
        tail_amplitude: acc.amp,
        tail_speed: acc.spd,
        cycle: search.ended,
    }
}

impl Acc {
    /// The bookkeeping before the first sample: H_T(0) = `h0`, limits scaled by max(h0, 1).
    fn new(mu: f64, h0: f64, periods: u64, th: &Thresholds) -> Self {
        let scale = if h0 > 1.0 { h0 } else { 1.0 };
        Self {
            mu,
            limit: th.divergence_ratio * scale,
            tol: th.mono_tol * scale,
            tail_start: periods - (periods as f64 * th.tail_fraction) as u64,
            prev: h0,
            h_max: h0,
            mono: true,
            amp: 0.0,
            spd: 0.0,
        }
    }
}

/// The class sample `h` (just simulated) settles, if any: growing (H_T over the limit or NaN,
/// or a diverged state) or decaying (at rest).
#[inline(always)]
fn settled<S: ExactSim>(sim: &S, acc: &mut Acc, h: u64) -> Option<Class> {
    let s = sim.state();
    if acc.sample(h, s.x, s.v) || sim.diverged() {
        return Some(Class::Growing);
    }
    if sim.at_rest() {
        return Some(if acc.mono {
            Class::MonotoneDecay
        } else {
            Class::NonMonotoneDecay
        });
    }
    None
}

/// What the main loop does after a recording step.
enum Flow {
    /// On to the next sample.
    Next,
    /// The run ends here, with this class (`None`: by the rules at the end of the horizon).
    Stop(Option<Class>),
}

/// Cycle detection's state across samples (see the module header).
struct Search<S> {
    /// Brent: the state at sample `h - lam`; compared with every later sample up to `power`
    /// samples on, then replaced by the current one with `power` doubled.
    saved: Option<S>,
    power: u64,
    lam: u64,
    /// (L, c): the state at every sample k >= c equals the state at k + L.
    cycle: Option<(u64, u64)>,
    /// The cycle that ended the run early, for [`Outcome::cycle`].
    ended: Option<Cycle>,
    /// A cycle up to the position's bits being recorded for replay: the solver at its first
    /// sample, and the phases so far.
    recording: Option<S>,
    phases: [Phase; MAX_REPLAY],
    recorded: usize,
    tr: Increments,
}

impl<S: ExactSim> Search<S> {
    fn new(sim: &S, cycle_detection: bool) -> Self {
        Self {
            saved: if cycle_detection {
                Some(sim.clone())
            } else {
                None
            },
            power: 1,
            lam: 0,
            cycle: None,
            ended: None,
            recording: None,
            phases: [Phase::default(); MAX_REPLAY],
            recorded: 0,
            tr: Increments::default(),
        }
    }

    /// Once a cycle is known, skips q whole cycles (samples h+1 ..= h+q·L): each repeats a
    /// sample already classified; only the tail maxima need care (see the module header).
    /// True when that reaches the horizon.
    #[inline(always)]
    fn skip_cycles(&mut self, h: &mut u64, periods: u64, tail_start: u64) -> bool {
        let Some((l, c)) = self.cycle else {
            return false;
        };
        let q = if *h + 1 < tail_start {
            (tail_start - 1 - *h) / l
        } else if *h + 1 >= tail_start.max(c + 1) + l {
            // The tail has covered L consecutive samples of the cycle: all its phases.
            (periods - *h) / l
        } else {
            0
        };
        if q > 0 {
            *h += q * l;
            self.ended = Some(Cycle {
                period: l,
                exact: true,
            });
            if *h >= periods {
                return true;
            }
        }
        false
    }

    /// Simulates one period, recording it when a cycle is being recorded.
    #[inline(always)]
    fn step(&mut self, sim: &mut S) {
        if self.recording.is_some() {
            let count = sim.count_at(sim.state().x).to_bits();
            sim.step_period_traced(&mut self.tr);
            self.phases[self.recorded] = Phase {
                count,
                dx: self.tr,
                v_end: sim.state().v,
            };
            self.recorded += 1;
        } else {
            sim.step_period();
        }
    }

    /// After a recorded period: once one period of the candidate is recorded, replays it if it
    /// is replayable, else (or once the replay left the cycle) starts the search afresh.
    fn after_recording(&mut self, sim: &mut S, acc: &mut Acc, h: &mut u64, periods: u64) -> Flow {
        let Some(first) = self.recording.as_ref() else {
            return Flow::Next;
        };
        if (self.recorded as u64) < self.lam {
            return Flow::Next;
        }
        // One period of the candidate recorded: replayable if it returned to the same state
        // up to the position's bits and never rested (the rest test compares positions).
        let ph = &self.phases[..self.recorded];
        let ok = sim.same_but_position(first)
            && !ph
                .iter()
                .zip(core::iter::once(first.state().v).chain(ph.iter().map(|p| p.v_end)))
                .any(|(p, v0)| v0 == 0.0 && p.v_end == 0.0);
        self.recording = None;
        self.recorded = 0;
        if ok {
            let lam = self.lam;
            let base = sim.clone();
            let replayed = Cycle {
                period: lam,
                exact: false,
            };
            match replay(&base, ph, acc, h, periods) {
                Replay::Horizon => {
                    self.ended = Some(replayed);
                    return Flow::Stop(None);
                }
                Replay::Growing => return Flow::Stop(Some(Class::Growing)),
                Replay::Left(resumed) => {
                    *sim = resumed;
                    self.ended = Some(replayed);
                }
                Replay::Exact(resumed) => {
                    *sim = resumed;
                    self.cycle = Some((lam, *h - lam));
                    self.ended = Some(replayed);
                    return Flow::Next;
                }
            }
        }
        // Not replayable (or left): start the search afresh from here.
        self.saved = Some(sim.clone());
        self.power = 1;
        self.lam = 0;
        Flow::Next
    }

    /// Brent's step at sample `h`: a bit-for-bit repeat is a cycle to skip, a repeat up to the
    /// position's bits starts a recording, else the saved state moves on at powers of two.
    #[inline(always)]
    fn look_for_cycle(&mut self, sim: &S, h: u64) {
        if self.cycle.is_some() {
            return;
        }
        if let Some(t) = self.saved.as_mut() {
            self.lam += 1;
            if sim.same_state(t) {
                self.cycle = Some((self.lam, h - self.lam));
                self.saved = None;
            } else if self.lam as usize <= MAX_REPLAY && sim.same_but_position(t) {
                // Same state but for the position's last bits: record one period exactly
                // (with the increments) and replay it.
                self.recording = Some(sim.clone());
            } else if self.lam == self.power {
                t.clone_from(sim);
                self.power *= 2;
                self.lam = 0;
            }
        }
    }
}

/// How a replay ended.
enum Replay<S> {
    /// At the horizon.
    Horizon,
    /// A replayed sample made the point growing.
    Growing,
    /// A count differed from the recorded one: the solver resumed at the current sample.
    Left(S),
    /// The position repeated bit for bit after one period: the solver at the current sample,
    /// whose state equals the state one period of the cycle earlier.
    Exact(S),
}

/// Replays the recorded `phases` from `base` (the solver one cycle after their first sample,
/// in the same state up to the position's bits) while every sample's count matches the
/// recorded one: ξ ← ξ + Δ with the recorded increments, ξ̇ as recorded, and the per-sample
/// rules of [`Acc`]. This is exactly the solver's own arithmetic (its future depends on ξ only
/// through the counts and these increments: [`ExactSim::same_but_position`]).
fn replay<S: ExactSim>(
    base: &S,
    phases: &[Phase],
    acc: &mut Acc,
    h: &mut u64,
    periods: u64,
) -> Replay<S> {
    let mut x = base.state().x;
    let mut x_cycle = x;
    let l = phases.len();
    let mut j = 0;
    while *h < periods {
        let p = &phases[j];
        if base.count_at(x).to_bits() != p.count {
            // Resume the solver at this sample: the base stepped j periods (the samples in
            // between matched, so it passes through the same states up to the position) with
            // the replayed position.
            let mut s = base.clone();
            for _ in 0..j {
                s.step_period();
            }
            s.set_position(x);
            return Replay::Left(s);
        }
        for &d in p.dx.as_slice() {
            x += d;
        }
        *h += 1;
        if acc.sample(*h, x, p.v_end) || !(x.abs() <= 1e150 && p.v_end.abs() <= 1e150) {
            return Replay::Growing;
        }
        j += 1;
        if j == l {
            j = 0;
            if x.to_bits() == x_cycle.to_bits() {
                let mut s = base.clone();
                s.set_position(x);
                return Replay::Exact(s);
            }
            x_cycle = x;
        }
    }
    Replay::Horizon
}
