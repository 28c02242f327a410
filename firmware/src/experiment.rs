//! The experiments the servo runs instead of the wall: the release test's hold → release state
//! machine (paper Fig. 8), the impact test's hold → launch → contact state machine, and the
//! excitation profiles (steps, linear chirp, uploaded table) as
//! generators of one output code per tick.
//!
//! Units: counts are effective counts n (Δ_eff = 2^shift·Δ) relative to the wall; codes are
//! output codes; times are servo ticks; `rate_hz` is the servo rate.
//!
//! Invariants: every step is bounded work without allocation or panics (table reads are
//! checked, counters saturate, divisions are by values ≥ 1 or checked). This module imports
//! nothing else of the crate (the servo calls it; it never calls back).

use stiffwall_proto::{
    ExciteProfile, ExperimentKind, DECAY_CHECKS_PER_BASE, DECAY_LAST_CHECK, DECAY_MIN_WINDOW,
};

/// What the force stage does this tick (a one-byte mirror of [`Experiment`] for the hot path).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mode {
    /// The wall (no experiment).
    Wall,
    /// The wall, in the released phase of a release test.
    Released,
    /// Holding or exciting.
    Other,
    /// The haptic profile (no experiment; a profile is active).
    Profile,
}

/// The running experiment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Experiment {
    None,
    Hold(Hold),
    Launch(Launch),
    Released {
        remaining: u32,
        kind: ExperimentKind,
    },
    Excite(Excitation),
}

impl Experiment {
    /// The force stage's mode for this experiment.
    pub(crate) fn mode(&self) -> Mode {
        match self {
            Experiment::None => Mode::Wall,
            Experiment::Released { .. } => Mode::Released,
            _ => Mode::Other,
        }
    }

    /// Which experiment this is (None for the wall).
    pub(crate) fn kind(&self) -> Option<ExperimentKind> {
        match self {
            Experiment::None => None,
            Experiment::Hold(_) => Some(ExperimentKind::Release),
            Experiment::Launch(_) => Some(ExperimentKind::Impact),
            Experiment::Released { kind, .. } => Some(*kind),
            Experiment::Excite(_) => Some(ExperimentKind::Excite),
        }
    }
}

/// The release test's holding phase: a stiff, damped spring holds the device at `target` until
/// it has been still there (within a count) for a settling time, or still anywhere for
/// [`STUCK_SETTLES`] settling times (static friction holds it where the hold spring's force fell
/// below breakaway: waiting longer changes nothing, and the host reads where it started), or
/// for at most 2 s; then it is released for `ticks`.
/// Settling times a device must stay still off its hold target before it is released there.
pub(crate) const STUCK_SETTLES: u32 = 4;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Hold {
    /// Hold position, effective counts from the wall.
    pub(crate) target: i32,
    /// Ticks to run after the release (≥ 1).
    ticks: u32,
    held: u32,
    still: u32,
    /// Consecutive ticks without motion, anywhere.
    stuck: u32,
    /// Within a count of the target counts as still even while moving (see
    /// [`Hold::toggle_settles`]).
    toggle_ok: bool,
}

impl Hold {
    /// Hold at `target`, then run `ticks` (at least 1) after the release.
    pub(crate) fn new(target: i32, ticks: u32) -> Self {
        Self {
            target,
            ticks: ticks.max(1),
            held: 0,
            still: 0,
            stuck: 0,
            toggle_ok: false,
        }
    }

    /// With `on`, a device toggling between counts within one count of the target counts as
    /// still: a wall with a virtual damper answers every count change and may never rest
    /// exactly, so without this its hold would wait the full 2 s. The release then starts
    /// within one count of the target at most one count per tick slow (the host re-aims a
    /// release off its target). Off (spring only): still means no motion.
    pub(crate) fn toggle_settles(mut self, on: bool) -> Self {
        self.toggle_ok = on;
        self
    }

    /// One tick after the output at count `n` (moved `dn` since the last tick): `Some(ticks)`
    /// when the device is to be released now, for `ticks` ticks.
    pub(crate) fn advance(&mut self, n: i32, dn: i32, rate_hz: u32) -> Option<u32> {
        let rate = rate_hz.max(1);
        self.held = self.held.saturating_add(1);
        // `abs_diff`: exact for every pair of i32 (a saturating difference's `abs` overflows at
        // i32::MIN, and in release builds the hold would then never settle).
        if (dn == 0 || self.toggle_ok) && n.abs_diff(self.target) <= 1 {
            self.still = self.still.saturating_add(1);
        } else {
            self.still = 0;
        }
        self.stuck = if dn == 0 {
            self.stuck.saturating_add(1)
        } else {
            0
        };
        let settle = (rate / 10).max(20);
        ((self.still >= settle && self.held >= settle)
            || self.stuck >= settle.saturating_mul(STUCK_SETTLES)
            || self.held >= rate.saturating_mul(2))
        .then_some(self.ticks)
    }
}

/// The impact test's launch: the release test's hold at `start` until still (or 2 s), then the
/// hold target moves toward the wall at `velocity_milli` thousandths of a count per tick; at
/// contact (count ≥ 0 moving up, < 0 moving down), or 4 s after the launch began, the device
/// is released into the wall for `ticks`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Launch {
    hold: Hold,
    /// Hold target, thousandths of an effective count from the wall.
    target_milli: i32,
    velocity_milli: i32,
    launched: bool,
    t: u32,
}

impl Launch {
    /// Launch from `start` at `velocity_milli` (its sign toward the wall), then run `ticks`
    /// (at least 1) after contact. `start` is bounded by the caller (|start| ≤ 2²⁰).
    pub(crate) fn new(start: i32, velocity_milli: i32, ticks: u32) -> Self {
        Self {
            hold: Hold::new(start, ticks),
            target_milli: start.saturating_mul(1000),
            velocity_milli,
            launched: false,
            t: 0,
        }
    }

    /// Whether the hold before the launch has ended (the target is moving).
    pub(crate) fn launched(&self) -> bool {
        self.launched
    }

    /// [`Hold::toggle_settles`] for the hold before the launch.
    pub(crate) fn toggle_settles(mut self, on: bool) -> Self {
        self.hold = self.hold.toggle_settles(on);
        self
    }

    /// The hold target this tick, effective counts (rounded toward −∞).
    pub(crate) fn target(&self) -> i32 {
        self.target_milli.div_euclid(1000)
    }

    /// One tick after the output at count `n` (moved `dn`): `Some(ticks)` at contact.
    pub(crate) fn advance(&mut self, n: i32, dn: i32, rate_hz: u32) -> Option<u32> {
        if !self.launched {
            self.launched = self.hold.advance(n, dn, rate_hz).is_some();
            return None;
        }
        self.t = self.t.saturating_add(1);
        self.target_milli = self.target_milli.saturating_add(self.velocity_milli);
        let contact = if self.velocity_milli > 0 {
            n >= 0
        } else {
            n < 0
        };
        (contact || self.t >= rate_hz.max(1).saturating_mul(4)).then_some(self.hold.ticks)
    }
}

/// The settle rule of a released phase under `HostMsg::PrepareTest`: settled at the first
/// count L of the phase at which the last max(`min_run`, ⌈L/3⌉) counts are all equal (or, with
/// `one_count`, all within one count). The exact streaming form of the host's
/// `settled_within` (stiffwall-tune's verify module): the longest runs ending at the latest
/// count with values in {n − 1, n} (`below`) and {n, n + 1} (`above`), O(1) per tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SettleWatch {
    min_run: u32,
    one_count: bool,
    prev: i32,
    len: u32,
    below: u32,
    above: u32,
}

impl SettleWatch {
    /// A watch for runs of at least `min_run` counts (within one count with `one_count`).
    pub(crate) fn new(min_run: u32, one_count: bool) -> Self {
        Self {
            min_run,
            one_count,
            prev: 0,
            len: 0,
            below: 0,
            above: 0,
        }
    }

    /// The released phase's next count `n`; true when the phase has settled with it.
    pub(crate) fn push(&mut self, n: i32) -> bool {
        let one = |a: i32, b: i32| self.one_count && a.checked_add(1) == Some(b);
        (self.below, self.above) = if self.len == 0 {
            (1, 1)
        } else if self.prev == n {
            (self.below.saturating_add(1), self.above.saturating_add(1))
        } else if one(self.prev, n) {
            (self.above.saturating_add(1), 1)
        } else if one(n, self.prev) {
            (1, self.below.saturating_add(1))
        } else {
            (1, 1)
        };
        self.prev = n;
        self.len = self.len.saturating_add(1);
        self.below.max(self.above) >= self.min_run.max(self.len.div_ceil(3))
    }
}

/// Decay checkpoints a [`DecayWatch`] follows (j = 0..=`DECAY_LAST_CHECK`).
const CHECKPOINTS: usize = DECAY_LAST_CHECK as usize + 1;

/// The decay rule of `HostMsg::PrepareTest`: at checkpoint L_j = b + j·max(⌊b/8⌋, 1) the
/// test ends unless its oscillation still shrinks (the range of the last w = max(⌊L/4⌋, 50)
/// counts below that of the w before); at the last checkpoint it ends. The streaming form of
/// the host's `judged_len` decay watch: the two windows of every checkpoint still ahead are
/// tracked as (min, max) pairs, O(checkpoints) per tick and no record kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct DecayWatch {
    base: u32,
    step: u32,
    /// The next checkpoint to decide.
    next: u32,
    len: u32,
    /// Per checkpoint: (min, max) of its earlier window, then of its later window.
    win: [[i32; 4]; CHECKPOINTS],
}

impl DecayWatch {
    /// Checkpoints from base length `base` ticks (≥ 1).
    pub(crate) fn new(base: u32) -> Self {
        let base = base.max(1);
        Self {
            base,
            step: (base / DECAY_CHECKS_PER_BASE).max(1),
            next: 0,
            len: 0,
            win: [[i32::MAX, i32::MIN, i32::MAX, i32::MIN]; CHECKPOINTS],
        }
    }

    /// Checkpoint j's length L and window w (None when 2w > L: nothing to compare).
    fn checkpoint(&self, j: u32) -> (u32, Option<u32>) {
        let l = self.base.saturating_add(j.saturating_mul(self.step));
        let w = (l / 4).max(DECAY_MIN_WINDOW);
        (l, (w.saturating_mul(2) <= l).then_some(w))
    }

    /// The released phase's next count `n`; true when a checkpoint ends the test with it.
    pub(crate) fn push(&mut self, n: i32) -> bool {
        let i = self.len;
        self.len = self.len.saturating_add(1);
        for j in self.next..=DECAY_LAST_CHECK {
            let (l, w) = self.checkpoint(j);
            let (Some(w), Some(m)) = (w, self.win.get_mut(j as usize)) else {
                continue;
            };
            let slot = if i >= l - w && i < l {
                2
            } else if i >= l - 2 * w && i < l - w {
                0
            } else {
                continue;
            };
            m[slot] = m[slot].min(n);
            m[slot + 1] = m[slot + 1].max(n);
        }
        let (l, w) = self.checkpoint(self.next);
        if self.len != l {
            return false;
        }
        let range = |lo: i32, hi: i32| i64::from(hi) - i64::from(lo);
        let decaying = match (w, self.win.get(self.next as usize)) {
            (Some(_), Some(m)) => range(m[2], m[3]) < range(m[0], m[1]),
            _ => false,
        };
        if self.next >= DECAY_LAST_CHECK || !decaying {
            return true;
        }
        self.next += 1;
        false
    }
}

/// The whole end rule of `HostMsg::PrepareTest` on a released phase: settled, or decided
/// by a decay checkpoint, whichever comes first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct EndWatch {
    settle: SettleWatch,
    decay: Option<DecayWatch>,
}

impl EndWatch {
    /// Settled after `min_run` (within one count with `one_count`; 0: never); decay
    /// checkpoints from `decay_base` ticks (0: none).
    pub(crate) fn new(min_run: u32, one_count: bool, decay_base: u32) -> Self {
        // No settled end: a run no record reaches.
        let min_run = if min_run == 0 { u32::MAX } else { min_run };
        Self {
            settle: SettleWatch::new(min_run, one_count),
            decay: (decay_base > 0).then(|| DecayWatch::new(decay_base)),
        }
    }

    /// The released phase's next count; true when the test ends with it.
    pub(crate) fn push(&mut self, n: i32) -> bool {
        let settled = self.settle.push(n);
        let decided = self.decay.as_mut().is_some_and(|d| d.push(n));
        settled || decided
    }
}

/// The length at which a test under `HostMsg::PrepareTest { min_run_ticks: min_run,
/// within_one_count: one_count, decay_base_ticks: decay_base }` with released counts `counts`
/// ends on the device (None: it has not ended within them). For hosts that check their own
/// judgement against the device's.
pub fn decided_len(
    counts: impl IntoIterator<Item = i32>,
    min_run: u32,
    one_count: bool,
    decay_base: u32,
) -> Option<usize> {
    let mut w = EndWatch::new(min_run, one_count, decay_base);
    counts.into_iter().position(|n| w.push(n)).map(|i| i + 1)
}

/// An excitation: one code per tick from its profile, for `total` ticks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Excitation {
    profile: ExciteProfile,
    total: u32,
    t: u32,
    /// Chirp phase, rad, in [0, 2π].
    phase: f32,
    /// Table position and ticks spent on it.
    idx: u32,
    cnt: u32,
}

impl Excitation {
    /// `profile` for `ticks` ticks (at least 1).
    pub(crate) fn new(profile: ExciteProfile, ticks: u32) -> Self {
        Self {
            profile,
            total: ticks.max(1),
            t: 0,
            phase: 0.0,
            idx: 0,
            cnt: 0,
        }
    }

    /// This tick's code (a generator: advances the chirp phase and the table position).
    /// `table`: the uploaded values; `rate_hz`: the servo rate.
    pub(crate) fn next_code(&mut self, table: &[i16], rate_hz: u32) -> i32 {
        match self.profile {
            ExciteProfile::Steps {
                low,
                high,
                half_period_ticks,
            } => {
                let hp = half_period_ticks.max(1);
                if self.t.checked_div(hp).unwrap_or(0) & 1 == 0 {
                    high
                } else {
                    low
                }
            }
            ExciteProfile::Chirp {
                amplitude,
                f0_hz,
                f1_hz,
            } => {
                let frac = if self.total > 0 {
                    self.t as f32 / self.total as f32
                } else {
                    0.0
                };
                let f = f0_hz + (f1_hz - f0_hz) * frac;
                let v = amplitude as f32 * libm::sinf(self.phase);
                self.phase += core::f32::consts::TAU * f / rate_hz.max(1) as f32;
                if self.phase > core::f32::consts::TAU {
                    self.phase -= core::f32::consts::TAU;
                }
                libm::roundf(v) as i32
            }
            ExciteProfile::Table { len, hold_ticks } => {
                let v = table.get(self.idx as usize).copied().unwrap_or(0);
                self.cnt = self.cnt.saturating_add(1);
                if self.cnt >= u32::from(hold_ticks.max(1)) {
                    self.cnt = 0;
                    self.idx = self.idx.saturating_add(1);
                    if self.idx >= u32::from(len) {
                        self.idx = 0;
                    }
                }
                i32::from(v)
            }
        }
    }

    /// One tick after the output; true when the excitation has run its length.
    pub(crate) fn advance(&mut self) -> bool {
        self.t = self.t.saturating_add(1);
        self.t >= self.total
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::strategy::Just;

    /// The host's rule, written as plainly as possible: the first L at which the last
    /// max(min_run, ⌈L/3⌉) counts have max − min ≤ `band`.
    fn settled_plain(counts: &[i32], min_run: u32, band: i32) -> Option<usize> {
        (1..=counts.len()).find(|&l| {
            let w = (min_run as usize).max(l.div_ceil(3));
            w <= l && {
                let tail = &counts[l - w..l];
                tail.iter().max().unwrap() - tail.iter().min().unwrap() <= band
            }
        })
    }

    /// The decay rule as the protocol states it, on the whole record.
    fn decay_plain(counts: &[i32], base: u32) -> Option<usize> {
        let base = base.max(1) as usize;
        let step = (base / 8).max(1);
        (0..=8).find_map(|j| {
            let l = base + j * step;
            if l > counts.len() {
                return None;
            }
            let w = (l / 4).max(50);
            let range = |s: &[i32]| s.iter().max().unwrap() - s.iter().min().unwrap();
            let decaying =
                2 * w <= l && range(&counts[l - w..l]) < range(&counts[l - 2 * w..l - w]);
            (j == 8 || !decaying).then_some(l)
        })
    }

    fn settled_watch(counts: &[i32], min_run: u32, one_count: bool) -> Option<usize> {
        let mut w = SettleWatch::new(min_run, one_count);
        counts.iter().position(|&n| w.push(n)).map(|i| i + 1)
    }

    #[test]
    fn settle_watch_ends_a_toggle_only_within_one_count() {
        let toggle = [9, 7, 5, 4, 5, 4, 5, 4, 5, 4, 5, 4];
        assert_eq!(settled_watch(&toggle, 6, true), Some(8));
        assert_eq!(settled_watch(&toggle, 6, false), None);
        // A shift of the band: 5,4 then 5,6: the run {5,6} starts at the last 5 before the 6.
        let shift = [4, 5, 4, 5, 6, 5, 6, 5, 6, 5];
        assert_eq!(settled_watch(&shift, 6, true), Some(9));
        assert_eq!(settled_watch(&[3, 3, 3], 3, false), Some(3));
        assert_eq!(
            settled_watch(&[i32::MAX, i32::MIN, i32::MAX], 1, true),
            Some(1)
        );
    }

    proptest::proptest! {
        #[test]
        fn settle_watch_is_the_plain_rule(
            counts in proptest::collection::vec(-3i32..=3, 0..120),
            min_run in 0u32..40,
            one_count: bool,
        ) {
            proptest::prop_assert_eq!(
                settled_watch(&counts, min_run, one_count),
                settled_plain(&counts, min_run, i32::from(one_count))
            );
        }
    }

    proptest::proptest! {
        /// A shrinking, a steady and a growing oscillation (amplitude a0·r^k, r around 1),
        /// against the protocol's rule; with the settle rule, the earlier of the two.
        #[test]
        fn decay_watch_is_the_plain_rule(
            a0 in 1.0f64..40.0,
            r in 0.995f64..1.003,
            period in 2.0f64..40.0,
            base in 1u32..400,
            len in 0usize..1000,
            min_run in 1u32..80,
        ) {
            let counts: std::vec::Vec<i32> = (0..len)
                .map(|k| {
                    let a = a0 * r.powi(k as i32);
                    (a * (core::f64::consts::TAU * k as f64 / period).cos()).floor() as i32
                })
                .collect();
            let decay = decay_plain(&counts, base);
            proptest::prop_assert_eq!(decided_len(counts.iter().copied(), u32::MAX, false, base), decay);
            let settle = settled_plain(&counts, min_run, 1);
            let first = match (settle, decay) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            };
            proptest::prop_assert_eq!(decided_len(counts.iter().copied(), min_run, true, base), first);
        }
    }

    #[test]
    fn hold_releases_after_settling_or_two_seconds() {
        // Still at the target: released after the settling time (100 ticks at 1 kHz).
        let mut h = Hold::new(5, 300);
        let first = (1..=1000).find(|_| h.advance(5, 0, 1000).is_some());
        assert_eq!(first, Some(100));
        // Stuck 9 counts past the target (static friction): released after 4 settling times.
        let mut h = Hold::new(57, 300);
        let first = (1..=1000).find(|_| h.advance(66, 0, 1000).is_some());
        assert_eq!(first, Some(100 * STUCK_SETTLES));
        // Creeping (one count every 50 ticks) off target is not stuck: 2 s.
        let mut h = Hold::new(57, 300);
        let first = (1..=5000u32).find(|i| h.advance(70, i32::from(i % 50 == 0), 1000).is_some());
        assert_eq!(first, Some(2000));
        // Never still: released after 2 s.
        let mut h = Hold::new(5, 0);
        let first = (1..=5000u32).find(|i| h.advance(5 + (*i as i32 & 7), 1, 1000).is_some());
        assert_eq!(first, Some(2000));
        assert_eq!(Hold::new(0, 0).ticks, 1);
    }

    #[test]
    fn a_toggle_at_the_target_settles_only_with_toggle_settles() {
        // Toggling between 5 and 6 (one count per tick): never still for the spring-only
        // hold (2 s), still for the damped wall's hold (100 ticks at 1 kHz).
        let toggle = |i: u32| (5 + (i & 1) as i32, if i == 1 { 0 } else { 1 });
        let mut h = Hold::new(5, 300);
        let first = (1..=5000u32).find(|&i| {
            let (n, dn) = toggle(i);
            h.advance(n, dn, 1000).is_some()
        });
        assert_eq!(first, Some(2000));
        let mut h = Hold::new(5, 300).toggle_settles(true);
        let first = (1..=5000u32).find(|&i| {
            let (n, dn) = toggle(i);
            h.advance(n, dn, 1000).is_some()
        });
        assert_eq!(first, Some(100));
        // Moving two counts off the target is not still, toggle or not.
        let mut h = Hold::new(5, 300).toggle_settles(true);
        let first = (1..=5000u32).find(|&i| h.advance(7 + (i & 1) as i32, 1, 1000).is_some());
        assert_eq!(first, Some(2000));
    }

    /// The settled check at the ends of the count range: a hold at i32::MIN (the repro
    /// `wall_position = i32::MAX`, count 0, deflection 1 gives n = i32::MIN) settles when still
    /// there, and a device 2³¹ counts or more away from its target never counts as still.
    #[test]
    fn hold_settles_at_the_ends_of_the_count_range() {
        for target in [i32::MIN, i32::MIN + 1, i32::MAX, i32::MAX - 1, 0] {
            let mut h = Hold::new(target, 10);
            let first = (1..=1000).find(|_| h.advance(target, 0, 1000).is_some());
            assert_eq!(first, Some(100), "still at {target}");
        }
        for (n, target) in [
            (i32::MIN, i32::MAX),
            (i32::MAX, i32::MIN),
            (i32::MIN, 0),
            (0, i32::MIN),
        ] {
            let mut h = Hold::new(target, 10);
            let first = (1..=5000).find(|_| h.advance(n, 0, 1000).is_some());
            assert_eq!(
                first,
                Some(100 * STUCK_SETTLES),
                "n {n} target {target}: not at the target, released only as stuck"
            );
        }
    }

    proptest::proptest! {
        /// Still at the target exactly when |n − target| ≤ 1 in exact (i64) arithmetic, for any
        /// pair; otherwise only released as stuck.
        #[test]
        fn hold_still_matches_exact_distance(
            n in proptest::prop_oneof![proptest::num::i32::ANY, Just(i32::MIN), Just(i32::MAX)],
            off in -3i64..=3,
            far in proptest::bool::ANY,
        ) {
            let target_wide = if far { i64::from(n) ^ (1 << 31) } else { i64::from(n) + off };
            let target = target_wide.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
            let exact_still = (i64::from(n) - i64::from(target)).abs() <= 1;
            let mut h = Hold::new(target, 1);
            let released_at = (1..=1000).find(|_| h.advance(n, 0, 1000).is_some());
            let expected = if exact_still { 100 } else { 100 * STUCK_SETTLES };
            proptest::prop_assert_eq!(released_at, Some(expected));
        }
    }

    #[test]
    fn launch_holds_then_moves_the_target_and_releases_at_contact() {
        // Still at the start: launched after the settling time (100 ticks at 1 kHz).
        let mut l = Launch::new(-10, 2500, 300);
        for _ in 0..100 {
            assert_eq!(l.advance(-10, 0, 1000), None);
        }
        assert_eq!(l.target(), -10);
        // The target moves 2.5 counts per tick toward the wall.
        assert_eq!(l.advance(-10, 0, 1000), None);
        assert_eq!(l.target(), -8); // −10 + 2.5 = −7.5 → −8
        assert_eq!(l.advance(-9, 1, 1000), None);
        assert_eq!(l.target(), -5);
        // Contact: the count reaches 0 from below.
        assert_eq!(l.advance(0, 2, 1000), Some(300));
        // From above: contact when the count drops below 0.
        let mut l = Launch::new(7, -1000, 5);
        for _ in 0..100 {
            l.advance(7, 0, 1000);
        }
        assert_eq!(l.advance(0, -1, 1000), None);
        assert_eq!(l.advance(-1, -1, 1000), Some(5));
        // Never reaching the wall: released 4 s after the launch.
        let mut l = Launch::new(-10, 1, 5);
        let first = (1..=10_000).find(|_| l.advance(-10, 0, 1000).is_some());
        assert_eq!(first, Some(100 + 4000));
    }

    #[test]
    fn steps_and_table_generators() {
        let mut x = Excitation::new(
            ExciteProfile::Steps {
                low: -3,
                high: 5,
                half_period_ticks: 2,
            },
            6,
        );
        let codes: [i32; 6] = core::array::from_fn(|_| {
            let c = x.next_code(&[], 1000);
            x.advance();
            c
        });
        assert_eq!(codes, [5, 5, -3, -3, 5, 5]);
        let mut x = Excitation::new(
            ExciteProfile::Table {
                len: 3,
                hold_ticks: 2,
            },
            8,
        );
        let mut done = [false; 8];
        let codes: [i32; 8] = core::array::from_fn(|i| {
            let c = x.next_code(&[1, 2, 3, 9], 1000);
            done[i] = x.advance();
            c
        });
        assert_eq!(codes, [1, 1, 2, 2, 3, 3, 1, 1]);
        assert_eq!(
            done,
            [false, false, false, false, false, false, false, true]
        );
    }
}
