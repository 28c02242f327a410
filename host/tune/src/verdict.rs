//! The verdict on one wall trajectory: encoder counts, one per servo tick, recorded after a
//! release or from the contact of an impact. Pure (no device, no plant): `tune` judges its
//! release and impact tests with it, and a brute-force K* computed with the simulator alone
//! can judge its trajectories with the same function, so both agree on what "stable" means.
//!
//! Units and frame: counts are effective encoder ticks (Δ_eff) relative to the wall origin, the
//! encoder boundary between counts −1 and 0 (eq. (2): the force for count n is −KΔ(n + ½)), so
//! count n lies |n + ½| ticks from it (cell centre). For a one-sided wall the wall occupies
//! counts ≥ 0 (an impact from the other side is judged on the mirrored counts −n − 1).
//!
//! The criterion (the same as the brute-force true K*_quiet): *the wall comes to rest*, by the
//! project's one rule of rest (`stiffwall_core::rest`: at most two count changes over the
//! judged tail). Judged on the tail, the last quarter of the record (at least [`MIN_TAIL`]
//! samples; a test's base length is 60 natural periods, so the tail starts at 45 or later
//! only when the test was still shrinking: see `judged`), in this order:
//! 1. [`Verdict::Growing`] (fails): the supervisor tripped, or the tail reaches as far from the
//!    origin as the head (first quarter) did, or the tail's second half reaches more than one
//!    tick further than its first half (a growing oscillation at any frequency, even one that
//!    is still small);
//! 2. [`Verdict::Settles`] (passes): the count comes to rest over the tail, and the
//!    half-cycle peaks never grew; [`Verdict::LocallyStable`] (passes): the same, after a swing
//!    that exceeded the one before it;
//! 3. [`Verdict::Departs`] (passes, one-sided walls only): the whole tail is outside the wall
//!    (counts < 0), where the wall exerts no force; for an impact ([`classify_impact`]) only
//!    if the device left no faster than it came in (exit speed over the first
//!    [`EXIT_WINDOW`] ticks outside ≤ entry speed + one count per window), else it is
//!    [`Verdict::Growing`] (the wall gave it energy);
//! 4. [`Verdict::Chatter`] (fails): the count keeps changing, within two adjacent counts (an
//!    oscillation of one count, region B): the wall's force keeps swinging by KΔ (and a plain
//!    damper's pulse BΔ/T at every change) for as long as the device is touched, a buzz users
//!    hear. Under [`Criterion::AcceptChatter`] (the user's explicit choice) it becomes
//!    [`Verdict::ChatterAccepted`], which passes and is reported;
//! 5. [`Verdict::Persistent`] (fails): a *buzz*, an oscillation over more than one count that
//!    persists without growing.

/// Fewest samples in the judged tail.
pub const MIN_TAIL: usize = 50;

/// Wall geometry of a trajectory.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Wall {
    /// The spring acts on both sides of the origin.
    Bidirectional,
    /// The wall occupies counts ≥ 0; no force at counts < 0.
    OneSided,
}

/// Outcome of one test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Comes to rest with monotonically shrinking swings.
    Settles,
    /// Comes to rest, after swings that grew at times.
    LocallyStable,
    /// Leaves a one-sided wall and stays out of it.
    Departs,
    /// Keeps toggling within one count: does not come to rest (fails).
    Chatter,
    /// [`Verdict::Chatter`] under [`Criterion::AcceptChatter`]: passes, reported as chatter.
    ChatterAccepted,
    /// Keeps oscillating over more than one count without growing (a buzz).
    Persistent,
    /// Oscillation grows, or the supervisor tripped.
    Growing,
    /// An impact test whose launch did not bring the device to the wall at the requested speed
    /// (the firmware's hold could not move it at a controlled speed): says nothing about the
    /// wall. Does not pass;
    /// `tune` judges that energy by the releases instead and reports it.
    NotLaunched,
}

impl Verdict {
    /// True when the test passes: the motion comes to rest or leaves a one-sided wall (or, under
    /// [`Criterion::AcceptChatter`], chatters within one count).
    #[must_use]
    pub fn passes(self) -> bool {
        matches!(
            self,
            Self::Settles | Self::LocallyStable | Self::Departs | Self::ChatterAccepted
        )
    }

    /// The verdict under `criterion`: [`Verdict::Chatter`] becomes [`Verdict::ChatterAccepted`]
    /// under [`Criterion::AcceptChatter`]; every other verdict is unchanged.
    #[must_use]
    pub fn under(self, criterion: Criterion) -> Self {
        match (self, criterion) {
            (Self::Chatter, Criterion::AcceptChatter) => Self::ChatterAccepted,
            (v, _) => v,
        }
    }

    /// True for a run that kept toggling within one count (accepted or not).
    #[must_use]
    pub fn chatters(self) -> bool {
        matches!(self, Self::Chatter | Self::ChatterAccepted)
    }

    /// True when the wall came to rest (stricter than [`Verdict::passes`]).
    #[must_use]
    pub fn settled(self) -> bool {
        matches!(self, Self::Settles | Self::LocallyStable)
    }

    /// Human-readable name.
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            Self::Settles => "comes to rest",
            Self::LocallyStable => "comes to rest (after swings that grew at times)",
            Self::Departs => "leaves the one-sided wall",
            Self::Chatter => "chatter: keeps toggling between two counts, never comes to rest",
            Self::ChatterAccepted => {
                "chatter (accepted): keeps toggling between two counts, never comes to rest"
            }
            Self::Persistent => "buzz: persistent oscillation over more than one count",
            Self::Growing => "growing",
            Self::NotLaunched => "not launched (the hold did not bring the device to the wall at the requested speed)",
        }
    }
}

/// What a passing wall must do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Criterion {
    /// Every test comes to rest (`stiffwall_core::rest`): the default.
    #[default]
    Rest,
    /// Also pass a test that keeps toggling within one count (chatter), reported as such: the
    /// criterion of earlier versions, for a user who accepts a wall that buzzes.
    AcceptChatter,
}

/// Distance of count `n` from the wall origin, in ticks (cell centre).
fn offset(n: i64) -> f64 {
    (n as f64 + 0.5).abs()
}

fn max_offset(s: &[i64]) -> f64 {
    s.iter().map(|&n| offset(n)).fold(0.0, f64::max)
}

/// Half-cycle peaks of |offset| between sign changes of the offset.
fn half_cycle_peaks(counts: &[i64]) -> Vec<f64> {
    let mut peaks = Vec::new();
    let mut cur = 0.0f64;
    let mut side = 0i8;
    for &n in counts {
        let s = if n >= 0 { 1 } else { -1 };
        if side != 0 && s != side {
            peaks.push(cur);
            cur = 0.0;
        }
        side = s;
        cur = cur.max(offset(n));
    }
    peaks.push(cur);
    peaks
}

/// Classifies a trajectory (see the module header for the criterion).
#[must_use]
pub fn classify_trajectory(counts: &[i64], wall: Wall, supervisor_tripped: bool) -> Verdict {
    if supervisor_tripped || counts.is_empty() {
        return Verdict::Growing;
    }
    let tail_len = (counts.len() / 4).max(MIN_TAIL).min(counts.len());
    let tail = &counts[counts.len() - tail_len..];
    let head = &counts[..tail_len];
    let at_rest = stiffwall_core::rest::window_rests(tail);
    let (first, second) = tail.split_at(tail.len() / 2);
    let tail_grows = !first.is_empty() && max_offset(second) > max_offset(first) + 1.0;
    let outside = wall == Wall::OneSided && tail.iter().all(|&n| n < 0);
    if !at_rest && !outside && (max_offset(tail) >= max_offset(head) || tail_grows) {
        return Verdict::Growing;
    }
    if at_rest {
        let peaks = half_cycle_peaks(counts);
        // The final "peak" is the rest position; compare only completed swings.
        let swings = &peaks[..peaks.len().saturating_sub(1)];
        return if swings.windows(2).any(|w| w[1] > w[0]) {
            Verdict::LocallyStable
        } else {
            Verdict::Settles
        };
    }
    if outside {
        return Verdict::Departs;
    }
    if stiffwall_core::rest::window_within_one_count(tail) {
        Verdict::Chatter
    } else {
        Verdict::Persistent
    }
}

/// Ticks over which the exit speed of an impact is measured.
pub const EXIT_WINDOW: usize = 10;

/// Speed (counts per tick) at which the trajectory first leaves a one-sided wall, over
/// [`EXIT_WINDOW`] ticks (fewer if it turns or the record ends), or None if it never leaves.
#[must_use]
pub fn exit_speed(counts: &[i64]) -> Option<f64> {
    let inside = counts.iter().position(|&n| n >= 0)?;
    let out = inside + counts[inside..].iter().position(|&n| n < 0)?;
    let mut end = out;
    while end + 1 < counts.len() && end - out < EXIT_WINDOW && counts[end + 1] <= counts[end] {
        end += 1;
    }
    (end > out).then(|| (counts[out] - counts[end]) as f64 / (end - out) as f64)
}

/// Classifies an impact from contact on, with the speed at contact (counts per tick): as
/// [`classify_trajectory`], and on a one-sided wall a device that leaves faster than it came
/// (beyond one count per [`EXIT_WINDOW`]) is growing.
#[must_use]
pub fn classify_impact(
    counts: &[i64],
    wall: Wall,
    entry_speed: f64,
    supervisor_tripped: bool,
) -> Verdict {
    let v = classify_trajectory(counts, wall, supervisor_tripped);
    if v == Verdict::Departs {
        if let Some(out) = exit_speed(counts) {
            if out > entry_speed.abs() + 1.0 / EXIT_WINDOW as f64 {
                return Verdict::Growing;
            }
        }
    }
    v
}

/// Classifies a release test on a bidirectional wall from the counts after release.
#[must_use]
pub fn classify(counts: &[i64], supervisor_tripped: bool) -> Verdict {
    classify_trajectory(counts, Wall::Bidirectional, supervisor_tripped)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decaying(a0: f64, decay: f64, n: usize) -> Vec<i64> {
        (0..n)
            .map(|k| {
                let a = a0 * (-decay * k as f64).exp();
                (a * (k as f64 * 0.3).cos()).floor() as i64
            })
            .collect()
    }

    #[test]
    fn a_decaying_swing_that_stops_settles() {
        let mut c = decaying(20.0, 0.02, 400);
        c.extend(std::iter::repeat_n(0, 200));
        assert_eq!(classify(&c, false), Verdict::Settles);
    }

    #[test]
    fn a_swing_that_grows_then_stops_is_locally_stable() {
        let mut c: Vec<i64> = vec![10, 10, 5, 0, -5, -12, -12, -5, 0, 3, 3, 0, -1];
        c.extend(std::iter::repeat_n(-1, 200));
        assert_eq!(classify(&c, false), Verdict::LocallyStable);
        assert!(Verdict::LocallyStable.passes());
    }

    #[test]
    fn toggling_within_one_count_anywhere_is_chatter_and_fails_unless_accepted() {
        let mut c = decaying(10.0, 0.05, 200);
        c.extend((0..400).map(|k| if (k / 3) % 2 == 0 { 0 } else { -1 }));
        assert_eq!(classify(&c, false), Verdict::Chatter);
        let mut c = decaying(10.0, 0.05, 200);
        c.extend((0..400).map(|k| if k % 2 == 0 { 4 } else { 5 }));
        let v = classify(&c, false);
        assert_eq!(v, Verdict::Chatter);
        assert!(!v.passes() && !v.settled());
        assert_eq!(v.under(Criterion::Rest), Verdict::Chatter);
        let accepted = v.under(Criterion::AcceptChatter);
        assert_eq!(accepted, Verdict::ChatterAccepted);
        assert!(accepted.passes() && accepted.chatters() && !accepted.settled());
        assert_eq!(
            Verdict::Growing.under(Criterion::AcceptChatter),
            Verdict::Growing
        );
    }

    #[test]
    fn two_count_changes_in_the_tail_still_rest_and_three_do_not() {
        // 400 samples: the tail is the last 100; one excursion and back (2 changes) rests.
        let mut c = decaying(10.0, 0.05, 200);
        c.extend(std::iter::repeat_n(0, 200));
        let n = c.len();
        c[n - 50] = 1;
        assert!(classify(&c, false).settled());
        c[n - 30] = 1;
        assert_eq!(classify(&c, false), Verdict::Chatter);
    }

    #[test]
    fn growth_and_trips_are_growing() {
        let c: Vec<i64> = (0..800)
            .map(|k| (5.0 * (0.004 * k as f64).exp() * (k as f64 * 0.3).sin()).floor() as i64)
            .collect();
        assert_eq!(classify(&c, false), Verdict::Growing);
        assert_eq!(classify(&vec![0; 100], true), Verdict::Growing);
        assert!(!Verdict::Growing.passes());
    }

    #[test]
    fn a_fast_buzz_that_grows_within_the_tail_is_growing_even_while_small() {
        // A large release that decays, then a high-frequency (Nyquist) oscillation that grows
        // from one to nine counts: still far below the release amplitude.
        let mut c = decaying(40.0, 0.02, 600);
        c.extend((0..600).map(|k| {
            let a = 1.0 + 8.0 * f64::from(k) / 600.0;
            let s = if k % 2 == 0 { 1.0 } else { -1.0 };
            (a * s).floor() as i64
        }));
        assert_eq!(classify(&c, false), Verdict::Growing);
    }

    #[test]
    fn a_steady_three_count_buzz_fails_as_persistent() {
        let c: Vec<i64> = (0..800)
            .map(|k| ((k as f64 * 0.3).sin() * 3.0).floor() as i64)
            .collect();
        assert!(!classify(&c, false).passes());
        let c = decaying(30.0, 0.005, 800);
        assert_eq!(classify(&c, false), Verdict::Persistent);
        // A Nyquist buzz over three counts after a large decaying release.
        let mut c = decaying(40.0, 0.02, 600);
        c.extend((0..600).map(|k| if k % 2 == 0 { 1 } else { -2 }));
        assert_eq!(classify(&c, false), Verdict::Persistent);
        assert!(!Verdict::Persistent.passes());
    }

    #[test]
    fn leaving_a_one_sided_wall_passes_only_for_a_one_sided_wall() {
        // Contact, penetration to 6 counts, bounce out, coast away and keep creeping.
        let mut c: Vec<i64> = (0..20).map(|k| 6 - (k as i64 - 6).abs()).collect();
        c.extend((0..400).map(|k| -1 - k / 10));
        assert_eq!(
            classify_trajectory(&c, Wall::OneSided, false),
            Verdict::Departs
        );
        assert!(Verdict::Departs.passes());
        // The same counts on a two-sided wall: moving ever further from the origin grows.
        assert_eq!(
            classify_trajectory(&c, Wall::Bidirectional, false),
            Verdict::Growing
        );
    }

    #[test]
    fn an_impact_that_leaves_faster_than_it_came_grows() {
        // In at 1 count per tick, out at 2: the wall gave it energy.
        let mut c: Vec<i64> = (0..8).collect();
        c.extend((0..8).rev());
        c.extend((1..300).map(|k| -2 * k));
        assert_eq!(exit_speed(&c), Some(2.0));
        assert_eq!(
            classify_impact(&c, Wall::OneSided, 1.0, false),
            Verdict::Growing
        );
        assert_eq!(
            classify_impact(&c, Wall::OneSided, 2.0, false),
            Verdict::Departs
        );
        assert_eq!(exit_speed(&[0, 1, 2, 3]), None);
    }

    #[test]
    fn chatter_inside_a_one_sided_wall_is_a_buzz() {
        let mut c: Vec<i64> = (0..20).map(|k| 12 - (k as i64 - 12).abs()).collect();
        c.extend((0..600).map(|k| if (k / 2) % 2 == 0 { 3 } else { -1 }));
        assert_eq!(
            classify_trajectory(&c, Wall::OneSided, false),
            Verdict::Persistent
        );
    }
}
