//! The table's data: one plant's row ([`Row`]), what a dry-run tune set ([`Tuned`]) and every
//! trial of the K* criterion at the set wall ([`AtSet`]), and how a trial is named.
use std::fmt::Write as _;
use stiffwall_tests::family::{PlantCase, SupervisorReport};
use stiffwall_tests::kstar::{self, KStar, Trial, TrialKind};

pub(super) struct Tuned {
    pub(super) k_set: f64,
    pub(super) b_set: f64,
    /// The damper law's dead band, counts (0: the plain difference), from `tune.damper`.
    pub(super) deadband_counts: i64,
    /// The law's name as tune reports it.
    pub(super) damper: String,
    /// What tune claims: every test of its verification set came to rest.
    pub(super) rests: bool,
    /// Tune's quiet ceiling 2·max(c, F_s)/Δ of the identified device.
    pub(super) quiet_ceiling: f64,
    pub(super) mass: f64,
    pub(super) viscous: f64,
    pub(super) coulomb: f64,
    pub(super) mismatch: Option<Vec<String>>,
    pub(super) seconds: f64,
    /// The plant's positions over the whole tune (least, largest), m (rad), and whether it
    /// touched an end stop on any tick, by its trace.
    pub(super) travel_used: ([f64; 2], bool),
    /// The maximum velocity tune tested with, counts per period.
    pub(super) xidot: f64,
    /// The travel tune kept to (m or rad) and where it came from.
    pub(super) window: Option<(f64, f64, stiffwall_tune::TravelSource)>,
}

pub(super) struct Row {
    pub(super) case: PlantCase,
    /// K*(0), the spring alone.
    pub(super) k_star: KStar,
    /// The stiffest point of the frontier grid: (B, K*(B)).
    pub(super) best: Option<(f64, f64)>,
    /// K*(B_set) at the damping tune set (K*(0) when it set none).
    pub(super) k_star_set: Option<Result<KStar, String>>,
    /// Every trial of the criterion at (K set, B set), when tune ran.
    pub(super) at_set: Option<AtSet>,
    pub(super) k_star_seconds: f64,
    pub(super) tune: Option<Result<Tuned, String>>,
    /// At 1.5 K*(B_set) with B_set (B = 0 without a tune).
    pub(super) supervisor: SupervisorReport,
}

/// Every trial of the K* criterion at the set wall, by the simulator alone, and with a damper
/// tune's small-swing states ([`small_state_trials`]).
pub(super) struct AtSet {
    pub(super) trials: usize,
    /// Trials that come to rest.
    pub(super) rest: usize,
    /// Trials that chatter within one count (do not rest, do not grow): the worst one's
    /// toggles per second and force swing in units of c.
    pub(super) chatter: Vec<(Trial, stiffwall_core::rest::Chatter)>,
    /// Trials that buzz over more counts or grow.
    pub(super) unstable: Vec<Trial>,
    /// Small-swing states run (0 without a damper).
    pub(super) small: usize,
    /// Small-swing states that do not come to rest.
    pub(super) small_swings: Vec<Trial>,
}

/// Share of the small-swing states that may keep swinging at a set wall: below K*(B) a damped
/// wall's swings are speckle, a few isolated states at isolated K (phantom-stiction at
/// B = 4.05: 2 of 480 at K = 2196, none at 2185 or 2229, 2 to 4 at 2461, 2510, 2827, 2883,
/// none between), above it a region that grows with K (maxon-re35 by the rigid model: 2 of
/// 480 at 3.9, 6 at 4.0, 16 at 4.15). A set wall passes with at most this share, 1 %.
pub(super) const SMALL_SWING_SHARE: f64 = 0.01;

impl AtSet {
    pub(super) fn of(case: &PlantCase, k: f64) -> Self {
        let runs = kstar::run_all(&case.proto, &case.rig, k);
        let small = if case.rig.damping > 0.0 {
            small_state_trials(&case.rig)
        } else {
            Vec::new()
        };
        let small_swings: Vec<Trial> = {
            use rayon::prelude::*;
            small
                .par_iter()
                .filter(|t| !kstar::run_trial(&case.proto, &case.rig, k, **t).rests())
                .copied()
                .collect()
        };
        let c = case.model.coulomb_n;
        let mut at = Self {
            trials: runs.len(),
            rest: 0,
            chatter: Vec::new(),
            unstable: Vec::new(),
            small: small.len(),
            small_swings,
        };
        for (t, r) in runs {
            if r.rests() {
                at.rest += 1;
            } else if let Some(ch) = r.chatter(case.rig.period_s, c) {
                at.chatter.push((t, ch));
            } else {
                at.unstable.push(t);
            }
        }
        at
    }

    /// Every trial of the criterion rests, and at most [`SMALL_SWING_SHARE`] of the small states
    /// swing.
    pub(super) fn all_rest(&self) -> bool {
        self.rest == self.trials
            && self.small_swings.len() as f64 <= SMALL_SWING_SHARE * self.small as f64
    }

    pub(super) fn cell(&self) -> String {
        let mut s = if self.rest == self.trials {
            format!("yes ({} of {})", self.rest, self.trials)
        } else {
            self.failures()
        };
        if self.small > 0 {
            let _ = write!(
                s,
                "; small states: {} of {} rest",
                self.small - self.small_swings.len(),
                self.small
            );
            if let Some(t) = self.small_swings.first() {
                let _ = write!(s, " (first swing: {})", describe(t));
            }
        }
        s
    }

    fn failures(&self) -> String {
        let mut s = format!("NO: {} of {} rest", self.rest, self.trials);
        if let Some((t, ch)) = self
            .chatter
            .iter()
            .max_by(|a, b| a.1.force_pp_c.total_cmp(&b.1.force_pp_c))
        {
            let _ = write!(
                s,
                "; {} chatter (worst {}: {:.0} toggles/s, {:.1} c)",
                self.chatter.len(),
                describe(t),
                ch.toggles_per_s,
                ch.force_pp_c
            );
        }
        if let Some(t) = self.unstable.first() {
            let _ = write!(
                s,
                "; {} UNSTABLE (first {})",
                self.unstable.len(),
                describe(t)
            );
        }
        s
    }
}

pub(super) fn describe_trial(k: &KStar) -> String {
    describe(&k.failing)
}

fn describe(t: &Trial) -> String {
    let side = if t.side > 0 { "+" } else { "−" };
    let wall = if t.wall == 0 {
        String::new()
    } else {
        format!(", wall +{} counts", t.wall)
    };
    match t.kind {
        TrialKind::Impact { velocity_m_per_s } => {
            format!("impact {side}{velocity_m_per_s:.3}{wall}")
        }
        TrialKind::Release { counts } => format!("release {side}{counts}{wall}"),
        TrialKind::Moving {
            position_counts,
            velocity_m_per_s,
        } => format!(
            "small swing from {position_counts:+.3} counts at {velocity_m_per_s:+.3e}{wall}"
        ),
    }
}

/// Tune's small-swing screen states (`stiffwall_tune::small_swing::small_starts`) as trials at
/// every wall offset of `rig`: run on the true plant at a set wall with a damper, where the
/// damper's dead band leaves a swing of under a count per tick undamped (the screen runs them
/// on tune's identified rigid model; this runs them on the plant with all its effects).
pub(super) fn small_state_trials(rig: &kstar::Rig) -> Vec<Trial> {
    let starts: Vec<(f64, f64)> = stiffwall_tune::small_swing::small_starts()
        .map(|st| (st.x_counts, st.v_counts_per_tick))
        .collect();
    stiffwall_tests::swings::moving_trials(rig, &starts)
}
