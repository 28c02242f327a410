//! The brute-force **true largest stable stiffness K*** of a plant: the sampled spring of
//! eq. (2) stepping a simulated plant, no firmware, no identification (issue 10, item 4).
//!
//! Units: SI (m, m/s, N, s; rotary devices rad, rad/s, N·m, s), encoder counts n = ⌊x/Δ⌋.
//!
//! The controller is eq. (2) exactly: at each sample instant h·T the count n is read and
//! F = −K·Δ·(n + ½) (0 for n < 0 on a one-sided wall) is clamped to ±`force_limit_n` and
//! applied after `delay_ticks` whole periods (the firmware's delay line: zeros before the first
//! sample), held over the period (ZOH). The plant's amplifier, if any, filters and limits the
//! command inside [`SampledPlant::advance`].
//!
//! **Criterion** (also in docs/TUNE.md). v_max = [`DEFAULT_XIDOT`] counts per period (5Δ/T,
//! the default maximum velocity of `hostctl tune`) unless the plant states another. K is
//! *quiet* (the wall it renders is good) when every one of these trials **comes to rest**
//! (`stiffwall_core::rest`, the rule every check of the project uses):
//! - impacts: the plant starts at the wall surface (x = 0, or just below it for the negative
//!   side) moving into the wall at ten speeds v ∈ v_max·{0.1, 0.2, …, 1}, from both sides (one
//!   side for a one-sided wall);
//! - releases from rest at deflection d ∈ d_max·{1, 0.6, 0.3} and d = 1 count (the middle of
//!   count d), both sides, where ½K(d_max·Δ)² = ½ m v_max², m the whole moving mass
//!   (motor side + link + hand);
//! - with cogging, every trial is repeated with the wall a quarter cogging period further on.
//!
//! On a one-sided wall that nothing brings the plant back to (no hand spring), the plant may
//! leave the wall (count < −1, moving away): the trial ends there and settles when the plant
//! leaves no faster than a passive wall could send it back (the impact speed; for a release from
//! count d, the speed of kinetic energy ½K((d + 1)Δ)²). With a hand spring the plant comes back
//! and the trial is judged like any other.
//!
//! A trial runs for 60 natural periods 2π√(m/K) (at least 2000, at most 40000 ticks) and
//! **comes to rest** when the count changes at most twice over its judged window (the last
//! quarter, starting no later than 45 natural periods in: [`stiffwall_core::rest`]). So a
//! persistent oscillation at any frequency fails: growth (also stopped early when |n| exceeds
//! 10·(d_max + 2) + 100 counts; on a one-sided wall only the penetration counts), a buzz over
//! several counts, and **chatter**, a count that toggles between two neighbouring counts for
//! ever (the wall's force then swings by KΔ, plus a damper's pulse at every change, as long as
//! the device is touched). [`TrialRun::within_one_count`] keeps the older, weaker criterion
//! (the count stays within one count over the window) to tell chatter from growth in reports.
//! The search below finds K*_quiet(B); "K*" in this crate means it.
//!
//! K* is found by scanning K upwards by ×1.25 from a settling K until a trial fails, then
//! bisecting (geometric) to a relative width of 0.5 %, then confirming the span K*/1.5625..K*
//! at ×1.05 (a failure there is bisected instead): K* is the top of the stable interval that
//! contains the start, the largest K below the first failure, resolved to 5 % over the span
//! where a tune's answer lies and to 25 % below it.
//!
//! Invariant: deterministic (no randomness, no threads); the verdict of a trial depends only on
//! the plant prototype, the rig and K.

/// Default maximum velocity, counts per servo period (`hostctl tune`'s `DEFAULT_XIDOT`).
pub const DEFAULT_XIDOT: f64 = 5.0;
/// Impact speeds, fractions of v_max.
pub const IMPACT_FRACTIONS: [f64; 10] = [1.0, 0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1];
/// Release deflections, fractions of d_max (plus a release from 1 count).
pub const RELEASE_FRACTIONS: [f64; 3] = [1.0, 0.6, 0.3];
/// Natural periods per trial.
pub const TRIAL_NATURAL_PERIODS: f64 = stiffwall_core::rest::REST_RUN_NATURAL_PERIODS;
/// Fewest / most ticks per trial.
pub const TRIAL_TICKS: (f64, f64) = (2000.0, 40_000.0);
/// Scan factor and final relative width of the bisection.
pub const SCAN_FACTOR: f64 = 1.25;
/// Relative width at which the bisection stops.
pub const REL_TOL: f64 = 0.005;
/// Step of the confirmation scan: after the bisection, K from K*/[`CONFIRM_SPAN`] up to K* is
/// tried again at this ratio, so a failing band that the ×1.25 scan stepped over (seen with a
/// damper behind an amplifier: maxon-re35-amp-3khz fails near 4.74 while 4.26 and 5.32 settle)
/// is found where a tune's answer (≥ 0.7 K*) lies.
pub const CONFIRM_FACTOR: f64 = 1.05;
/// Span below K* that the confirmation scan covers (two steps of the coarse scan).
pub const CONFIRM_SPAN: f64 = SCAN_FACTOR * SCAN_FACTOR;

/// A plant stepped by a sampled controller (SI units, encoder on the controlled side).
pub trait SampledPlant {
    /// Sets the whole plant at `position_m` moving at `velocity_m_per_s` (internal states at
    /// rest relative to it, amplifier idle).
    fn set_state(&mut self, position_m: f64, velocity_m_per_s: f64);
    /// Held at rest with the encoder side at `position_m`, in static equilibrium (a hold just
    /// before its release); [`SampledPlant::set_state`] at rest where no internal state differs.
    fn set_held(&mut self, position_m: f64) {
        self.set_state(position_m, 0.0);
    }
    /// Holds the command `force_n` for `dt_s`.
    fn advance(&mut self, force_n: f64, dt_s: f64);
    /// ⌊x/Δ⌋ of the encoder side.
    fn encoder_count(&self) -> i64;
    /// Velocity of the encoder side, m/s (rad/s).
    fn velocity_m_per_s(&self) -> f64;
}

impl SampledPlant for stiffwall_sim::PhysicalPlant {
    fn set_state(&mut self, position_m: f64, velocity_m_per_s: f64) {
        stiffwall_sim::PhysicalPlant::set_state(self, position_m, velocity_m_per_s);
    }
    fn advance(&mut self, force_n: f64, dt_s: f64) {
        stiffwall_sim::PhysicalPlant::advance(self, force_n, dt_s);
    }
    fn encoder_count(&self) -> i64 {
        stiffwall_sim::PhysicalPlant::encoder_count(self)
    }
    fn velocity_m_per_s(&self) -> f64 {
        stiffwall_sim::PhysicalPlant::velocity_m_per_s(self)
    }
}

/// The rigid plant and the K* rig of a preset (`hostctl --device NAME`): the virtual device's
/// plant (m, b, c, Δ, T of the preset, its published peak force as the amplifier's range), the
/// spring alone on a two-sided wall at v_max = [`DEFAULT_XIDOT`] counts per period. None for an
/// unknown name.
#[must_use]
pub fn preset(name: &str) -> Option<(stiffwall_sim::PhysicalPlant, Rig)> {
    let d = stiffwall_core::devices::find(name)?;
    let p = d.params;
    let plant =
        stiffwall_sim::PhysicalPlant::new(p.mass, p.viscous, p.coulomb, p.resolution).ok()?;
    let rig = Rig {
        period_s: p.period_s,
        resolution_m: p.resolution,
        delay_ticks: 0,
        one_sided: false,
        free_exit: false,
        force_limit_n: d.force_limit,
        damping: 0.0,
        deadband_counts: 0,
        v_max: DEFAULT_XIDOT * p.resolution / p.period_s,
        moving_mass_kg: p.mass,
        wall_offsets: vec![0],
    };
    Some((plant, rig))
}

/// The controller side of a plant and the trial envelope.
#[derive(Debug, Clone, PartialEq)]
pub struct Rig {
    /// Servo period T, s.
    pub period_s: f64,
    /// Encoder resolution Δ, m (rad).
    pub resolution_m: f64,
    /// Extra delay of the force, whole periods.
    pub delay_ticks: u32,
    /// One-sided wall (occupies n ≥ 0).
    pub one_sided: bool,
    /// One-sided wall and nothing brings the plant back once it left (no hand spring): a
    /// trial ends when the plant leaves the wall, judged by its speed.
    pub free_exit: bool,
    /// Clamp of the commanded force, N (N·m).
    pub force_limit_n: f64,
    /// Virtual damping B of the wall, N·s/m (N·m·s/rad), ≥ 0, on the backward difference of the
    /// counts (0: the pure spring of eq. (2)).
    pub damping: f64,
    /// The damper's dead band, counts per tick: a count difference |n − n_prev| at most this
    /// is no motion to the damper (the firmware's `DamperLaw::DeadBand`; 0: the plain
    /// backward difference, `DamperLaw::Difference`).
    pub deadband_counts: i64,
    /// Maximum impact velocity v_max, m/s (rad/s).
    pub v_max: f64,
    /// Whole moving mass (motor side + link + hand), kg (kg·m²).
    pub moving_mass_kg: f64,
    /// Wall offsets to try, counts (several cogging phases; `[0]` otherwise).
    pub wall_offsets: Vec<i64>,
}

impl Rig {
    /// Deflection whose spring energy equals the kinetic energy at v_max, counts.
    #[must_use]
    pub fn d_max(&self, k: f64) -> f64 {
        self.v_max * (self.moving_mass_kg / k).sqrt() / self.resolution_m
    }

    /// One natural period 2π√(m/K) at stiffness `k`, ticks.
    #[must_use]
    pub fn natural_ticks(&self, k: f64) -> f64 {
        std::f64::consts::TAU * (self.moving_mass_kg / k).sqrt() / self.period_s
    }

    /// Ticks of one trial at stiffness `k`.
    #[must_use]
    pub fn trial_ticks(&self, k: f64) -> usize {
        (TRIAL_NATURAL_PERIODS * self.natural_ticks(k)).clamp(TRIAL_TICKS.0, TRIAL_TICKS.1) as usize
    }

    /// The spring of eq. (2) at count `n` relative to the wall, clamped, N.
    #[must_use]
    pub fn spring_n(&self, k: f64, n: i64) -> f64 {
        self.wall_force_n(k, n, n)
    }

    /// The firmware's wall law at count `n` after count `n_prev` (the previous sample), clamped,
    /// N: F = −K·Δ·(n + ½) − B·Δ·v/T with v = n − n_prev, or v = 0 when |n − n_prev| ≤
    /// [`Rig::deadband_counts`]; 0 for n < 0 on a one-sided wall (the damper acts only in
    /// contact). With B = 0 this is [`Rig::spring_n`] bit for bit.
    #[must_use]
    pub fn wall_force_n(&self, k: f64, n: i64, n_prev: i64) -> f64 {
        if self.one_sided && n < 0 {
            return 0.0;
        }
        let spring = -k * self.resolution_m * (n as f64 + 0.5);
        let dn = n - n_prev;
        let f = if self.damping == 0.0 || dn.abs() <= self.deadband_counts {
            spring
        } else {
            spring - self.damping * self.resolution_m * dn as f64 / self.period_s
        };
        f.clamp(-self.force_limit_n, self.force_limit_n)
    }

    /// Every trial of the criterion at stiffness `k`.
    #[must_use]
    pub fn trials(&self, k: f64) -> Vec<Trial> {
        let sides: &[i8] = if self.one_sided { &[1] } else { &[1, -1] };
        let d_max = self.d_max(k);
        let mut releases: Vec<i64> = RELEASE_FRACTIONS
            .iter()
            .map(|f| (f * d_max).round().max(1.0) as i64)
            .chain([1])
            .collect();
        releases.sort_unstable();
        releases.dedup();
        let mut out = Vec::new();
        for &wall in &self.wall_offsets {
            for &side in sides {
                for f in IMPACT_FRACTIONS {
                    out.push(Trial {
                        wall,
                        side,
                        kind: TrialKind::Impact {
                            velocity_m_per_s: f * self.v_max,
                        },
                    });
                }
                for &d in &releases {
                    out.push(Trial {
                        wall,
                        side,
                        kind: TrialKind::Release { counts: d },
                    });
                }
            }
        }
        out
    }
}

/// What a trial does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TrialKind {
    /// Arrives at the wall surface at this speed (into the wall).
    Impact {
        /// Speed, m/s (rad/s), > 0.
        velocity_m_per_s: f64,
    },
    /// Released from rest in the middle of this count (deflection ≥ 1).
    Release {
        /// Deflection, counts.
        counts: i64,
    },
    /// Starts moving from a state near the wall's origin (not one of the criterion's trials:
    /// tune's small-swing screen states, `stiffwall_tune::small_swing`, run at a set wall by
    /// `cargo xtask tune-table`). The side is ignored: the position is signed.
    Moving {
        /// Position from the wall's origin, counts (signed, fractional).
        position_counts: f64,
        /// Velocity, m/s (rad/s), signed.
        velocity_m_per_s: f64,
    },
}

/// One trial: which side of the wall (+1: n ≥ 0), where the wall is, what happens.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trial {
    /// Wall position, counts.
    pub wall: i64,
    /// +1 or −1.
    pub side: i8,
    /// Impact or release.
    pub kind: TrialKind,
}

impl Trial {
    /// Puts `plant` in the trial's initial state ([`Trial::initial_state`]); a release starts
    /// held there ([`SampledPlant::set_held`]: a hand behind a transmission deflects it).
    pub fn start<P: SampledPlant>(&self, plant: &mut P, resolution_m: f64) {
        let (x0, v0) = self.initial_state(resolution_m);
        match self.kind {
            TrialKind::Impact { .. } | TrialKind::Moving { .. } => plant.set_state(x0, v0),
            TrialKind::Release { .. } => plant.set_held(x0),
        }
    }

    /// The count (relative to the wall) one period before the trial starts, the damper's first
    /// previous sample: a release starts from a hold at rest (its own count); an impact arrives
    /// moving, as the firmware's launch brings it (the count at x₀ − v₀·T).
    #[must_use]
    pub fn previous_count(&self, resolution_m: f64, period_s: f64) -> i64 {
        let (x0, v0) = self.initial_state(resolution_m);
        ((x0 - v0 * period_s) / resolution_m).floor() as i64 - self.wall
    }

    /// Initial position and velocity for resolution Δ = `resolution_m`: an impact starts at the
    /// wall surface (just below it for the negative side), a release at rest in the middle of
    /// its count.
    #[must_use]
    pub fn initial_state(&self, resolution_m: f64) -> (f64, f64) {
        let d = resolution_m;
        let wall_x = self.wall as f64 * d;
        let s = f64::from(self.side);
        match self.kind {
            TrialKind::Impact { velocity_m_per_s } => {
                let x = if self.side > 0 {
                    wall_x
                } else {
                    wall_x - 1e-9 * d
                };
                (x, s * velocity_m_per_s)
            }
            TrialKind::Release { counts } => (wall_x + s * (counts as f64 + 0.5) * d, 0.0),
            TrialKind::Moving {
                position_counts,
                velocity_m_per_s,
            } => (wall_x + position_counts * d, velocity_m_per_s),
        }
    }
}

/// The recorded counts (relative to the wall) of one trial and its verdict.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TrialRun {
    /// Counts relative to the wall, one per tick (shorter when stopped early).
    pub counts: Vec<i64>,
    /// The wall's commanded force at each of those ticks, N (N·m), before the delay line.
    pub forces_n: Vec<f64>,
    /// One natural period at the trial's K, ticks (where the rest window starts; 0: the last
    /// quarter).
    pub natural_ticks: f64,
    /// Stopped early: |n| exceeded the runaway bound.
    pub ran_away: bool,
    /// One-sided wall: the plant left the wall (the run stops there) at this speed, with the
    /// largest speed a passive wall could give it back (m/s, rad/s).
    pub exit: Option<(f64, f64)>,
}

impl TrialRun {
    /// The judged window of the counts ([`stiffwall_core::rest::window_start`]).
    fn window(&self) -> &[i64] {
        let start = stiffwall_core::rest::window_start(self.counts.len(), self.natural_ticks);
        &self.counts[start..]
    }

    /// Comes to rest: not run away; on a one-sided wall that was left, left no faster than it
    /// could passively; otherwise the count changes at most twice over the judged window
    /// ([`stiffwall_core::rest::comes_to_rest`]).
    #[must_use]
    pub fn rests(&self) -> bool {
        if self.ran_away || self.counts.is_empty() {
            return false;
        }
        if let Some((v, passive)) = self.exit {
            return v <= passive;
        }
        stiffwall_core::rest::window_rests(self.window())
    }

    /// The weaker criterion of earlier rounds: [`TrialRun::rests`], or over the judged window
    /// the count stays within one count (chatter passes). False means a buzz or growth.
    #[must_use]
    pub fn within_one_count(&self) -> bool {
        if self.rests() {
            return true;
        }
        if self.ran_away || self.counts.is_empty() || self.exit.is_some() {
            return false;
        }
        stiffwall_core::rest::window_within_one_count(self.window())
    }

    /// A run that does not rest but stays within one count: how fast it toggles and how much
    /// the wall's force swings (Coulomb friction `coulomb_n`, servo period `period_s`).
    #[must_use]
    pub fn chatter(&self, period_s: f64, coulomb_n: f64) -> Option<stiffwall_core::rest::Chatter> {
        if self.rests() || !self.within_one_count() {
            return None;
        }
        let start = stiffwall_core::rest::window_start(self.counts.len(), self.natural_ticks);
        Some(stiffwall_core::rest::Chatter::of_window(
            &self.counts[start..],
            self.forces_n.get(start..).unwrap_or(&[]),
            period_s,
            coulomb_n,
        ))
    }

    /// Largest |n + ½| over the run, counts.
    #[must_use]
    pub fn peak(&self) -> f64 {
        self.counts
            .iter()
            .fold(0.0f64, |a, &n| a.max((n as f64 + 0.5).abs()))
    }
}

/// Runs one trial on a fresh copy of `proto` at stiffness `k`.
pub fn run_trial<P: SampledPlant + Clone>(proto: &P, rig: &Rig, k: f64, trial: Trial) -> TrialRun {
    let d = rig.resolution_m;
    let mut plant = proto.clone();
    trial.start(&mut plant, d);
    // One-sided wall: the speed a passive wall could return — the impact speed, or the speed
    // whose kinetic energy is the spring energy ½K((d + 1)Δ)² of a release from count d.
    let passive = match trial.kind {
        TrialKind::Impact { velocity_m_per_s } => velocity_m_per_s,
        TrialKind::Release { counts } => {
            (k / rig.moving_mass_kg).sqrt() * (counts as f64 + 1.0) * d
        }
        // Its own speed, or what the spring at its count could give it passively.
        TrialKind::Moving {
            position_counts,
            velocity_m_per_s,
        } => velocity_m_per_s
            .abs()
            .max((k / rig.moving_mass_kg).sqrt() * (position_counts.abs() + 1.0) * d),
    };
    let mut touched = false;
    let ticks = rig.trial_ticks(k);
    let bound = (10.0 * (rig.d_max(k) + 2.0) + 100.0) as i64;
    let delay = rig.delay_ticks as usize;
    let mut line = std::collections::VecDeque::with_capacity(delay + 1);
    let mut counts = Vec::with_capacity(ticks);
    let mut forces_n = Vec::with_capacity(ticks);
    let natural_ticks = rig.natural_ticks(k);
    let mut n_prev = trial.previous_count(d, rig.period_s);
    for _ in 0..ticks {
        let n = plant.encoder_count() - trial.wall;
        counts.push(n);
        // Outside a one-sided wall no force acts: only the penetration can run away.
        let excursion = if rig.one_sided { n } else { n.abs() };
        if excursion > bound {
            return TrialRun {
                counts,
                forces_n,
                natural_ticks,
                ran_away: true,
                exit: None,
            };
        }
        if rig.free_exit {
            touched |= n >= 0;
            if touched && n < -1 && plant.velocity_m_per_s() < 0.0 {
                // Left the wall, moving away with no force on it: judged by its speed.
                return TrialRun {
                    counts,
                    forces_n,
                    natural_ticks,
                    ran_away: false,
                    exit: Some((-plant.velocity_m_per_s(), passive)),
                };
            }
        }
        // Delay line of `delay` whole periods (zeros first), as the firmware's ring.
        let wall = rig.wall_force_n(k, n, n_prev);
        forces_n.push(wall);
        line.push_back(wall);
        n_prev = n;
        let f = if line.len() > delay {
            line.pop_front().unwrap_or(0.0)
        } else {
            0.0
        };
        plant.advance(f, rig.period_s);
    }
    TrialRun {
        counts,
        forces_n,
        natural_ticks,
        ran_away: false,
        exit: None,
    }
}

/// The first trial at `k` that does not come to rest, if any.
pub fn first_failure<P: SampledPlant + Clone>(
    proto: &P,
    rig: &Rig,
    k: f64,
) -> Option<(Trial, TrialRun)> {
    rig.trials(k).into_iter().find_map(|t| {
        let r = run_trial(proto, rig, k, t);
        (!r.rests()).then_some((t, r))
    })
}

/// Every trial at `k`, run: what a report needs to say whether a wall rests in every run and,
/// where it does not, whether it chatters, buzzes or grows.
pub fn run_all<P: SampledPlant + Clone>(proto: &P, rig: &Rig, k: f64) -> Vec<(Trial, TrialRun)> {
    rig.trials(k)
        .into_iter()
        .map(|t| (t, run_trial(proto, rig, k, t)))
        .collect()
}

/// Result of the K* search.
#[derive(Debug, Clone, PartialEq)]
pub struct KStar {
    /// Largest K found quiet (every trial comes to rest), N/m (N·m/rad).
    pub k_star: f64,
    /// Smallest K found unstable above it.
    pub k_fail: f64,
    /// The trial that failed at `k_fail`.
    pub failing: Trial,
    /// Stiffnesses evaluated.
    pub evaluations: usize,
}

/// Errors of the search.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KStarError {
    /// Even the smallest K tried fails.
    #[error("no stable stiffness found down to {0} N/m")]
    NoneStable(f64),
    /// Nothing failed up to the cap.
    #[error("every stiffness up to {0} N/m is stable (raise the cap)")]
    NoFailure(f64),
}

/// Scans up from `k_start` (or down until stable) by [`SCAN_FACTOR`], then bisects to
/// [`REL_TOL`]. `k_cap` bounds the scan.
pub fn k_star<P: SampledPlant + Clone>(
    proto: &P,
    rig: &Rig,
    k_start: f64,
    k_cap: f64,
) -> Result<KStar, KStarError> {
    let mut evaluations = 0;
    let mut eval = |k: f64| {
        evaluations += 1;
        first_failure(proto, rig, k)
    };
    let mut lo = k_start;
    let mut fail = eval(lo);
    let mut steps = 0;
    while fail.is_some() {
        steps += 1;
        if steps > 20 {
            return Err(KStarError::NoneStable(lo));
        }
        lo /= SCAN_FACTOR * SCAN_FACTOR;
        fail = eval(lo);
    }
    let start_stable = lo;
    let (mut hi, mut failing) = loop {
        let k = lo * SCAN_FACTOR;
        if k > k_cap {
            return Err(KStarError::NoFailure(k_cap));
        }
        match eval(k) {
            Some((t, _)) => break (k, t),
            None => lo = k,
        }
    };
    bisect(&mut eval, &mut lo, &mut hi, &mut failing);
    // Confirmation: the ×1.25 scan can step over a narrow failing band; the span below K*
    // where a tune's answer lies is re-scanned at ×CONFIRM_FACTOR, and a failure there becomes
    // the new upper end.
    let floor = (lo / CONFIRM_SPAN).max(start_stable);
    // The last stable point below: a point of the coarse scan (every trial of them came to rest).
    let mut stable = start_stable;
    while stable * SCAN_FACTOR <= floor {
        stable *= SCAN_FACTOR;
    }
    let mut k = floor;
    while k < lo {
        if let Some((t, _)) = eval(k) {
            hi = k;
            failing = t;
            lo = stable;
            bisect(&mut eval, &mut lo, &mut hi, &mut failing);
            break;
        }
        stable = k;
        k *= CONFIRM_FACTOR;
    }
    Ok(KStar {
        k_star: lo,
        k_fail: hi,
        failing,
        evaluations,
    })
}

/// Geometric bisection of [lo (stable), hi (failing)] to [`REL_TOL`].
fn bisect(
    eval: &mut impl FnMut(f64) -> Option<(Trial, TrialRun)>,
    lo: &mut f64,
    hi: &mut f64,
    failing: &mut Trial,
) {
    while *hi / *lo > 1.0 + REL_TOL {
        let mid = (*lo * *hi).sqrt();
        match eval(mid) {
            Some((t, _)) => {
                *hi = mid;
                *failing = t;
            }
            None => *lo = mid,
        }
    }
}

/// Default grid of the damper for [`frontier`], as β = B/(K*(0)·T): the evidence puts
/// the best walls at B ≈ 2–4 × K*(0)·T; 0.5 and 1 show the rise, 6 the fall beyond.
pub const FRONTIER_BETA: [f64; 7] = [0.0, 0.5, 1.0, 2.0, 3.0, 4.0, 6.0];

/// One point of the frontier: K* at damping `b`.
#[derive(Debug, Clone, PartialEq)]
pub struct FrontierPoint {
    /// Virtual damping B, N·s/m (N·m·s/rad).
    pub b: f64,
    /// K*(B), or why the search found none.
    pub k_star: Result<KStar, KStarError>,
}

/// K*(B) for every B of `b_grid` (N·s/m): [`k_star`] on the rig with that damping, each scan
/// started from `k_start` (a stiffness stable at every B of the grid is not known in advance:
/// the scan goes down from an unstable start until it settles, so K*(B) is the top of the
/// stable interval found first from `k_start` downwards or upwards). The frontier need not be
/// monotone in B.
pub fn frontier<P: SampledPlant + Clone>(
    proto: &P,
    rig: &Rig,
    b_grid: &[f64],
    k_start: f64,
    k_cap: f64,
) -> Vec<FrontierPoint> {
    b_grid
        .iter()
        .map(|&b| {
            let damped = Rig {
                damping: b,
                ..rig.clone()
            };
            FrontierPoint {
                b,
                k_star: k_star(proto, &damped, k_start, k_cap),
            }
        })
        .collect()
}
