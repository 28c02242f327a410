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

/// Every trial of the K* criterion at the set wall, by the simulator alone.
pub(super) struct AtSet {
    pub(super) trials: usize,
    /// Trials that come to rest.
    pub(super) rest: usize,
    /// Trials that chatter within one count (do not rest, do not grow): the worst one's
    /// toggles per second and force swing in units of c.
    pub(super) chatter: Vec<(Trial, stiffwall_core::rest::Chatter)>,
    /// Trials that buzz over more counts or grow.
    pub(super) unstable: Vec<Trial>,
}

impl AtSet {
    pub(super) fn of(case: &PlantCase, k: f64) -> Self {
        let runs = kstar::run_all(&case.proto, &case.rig, k);
        let c = case.model.coulomb_n;
        let mut at = Self {
            trials: runs.len(),
            rest: 0,
            chatter: Vec::new(),
            unstable: Vec::new(),
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

    pub(super) fn all_rest(&self) -> bool {
        self.rest == self.trials
    }

    pub(super) fn cell(&self) -> String {
        if self.all_rest() {
            return format!("yes ({} of {})", self.rest, self.trials);
        }
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
    }
}
