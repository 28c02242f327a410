//! Verdict of a release test (the paper's Fig. 8 experiment): the device is held at a deflection
//! with zero velocity, released, and its encoder counts are recorded.
//!
//! Positions are in encoder ticks; the wall's origin is the encoder boundary between counts −1
//! and 0 (eq. (2): the force for count n is −KΔ(n + ½)), so count n lies |n + ½| ± ½ ticks from
//! it. Verdicts, judged on the last quarter of the record (at least [`MIN_TAIL`] samples):
//! - [`Verdict::Settles`]: the count stops changing, and the half-cycle peaks never grew;
//! - [`Verdict::LocallyStable`]: the count stops changing, but some half-cycle peak exceeded the
//!   one before it (energy was generated on the way, as in regions D/E or F2);
//! - [`Verdict::LimitCycle`]: the count keeps toggling between −1 and 0 only (an oscillation of
//!   less than one tick about the origin, region B);
//! - [`Verdict::Persistent`]: it keeps moving over more than those two counts without growing;
//! - [`Verdict::Growing`]: the motion in the tail is at least as large as at the start, or the
//!   firmware's supervisor tripped.
//!
//! Only `Settles` and `LocallyStable` count as a wall that renders without oscillation.

/// The counts recorded after the release (samples flagged `RELEASED`), in effective ticks
/// (raw counts shifted right by the coarsening shift).
#[must_use]
pub fn released_counts(samples: &[stiffwall_proto::Sample], coarsen_shift: u8) -> Vec<i64> {
    samples
        .iter()
        .filter(|s| s.flags & stiffwall_proto::flags::RELEASED != 0)
        .map(|s| i64::from(s.count) >> coarsen_shift)
        .collect()
}

/// Fewest samples in the judged tail.
pub const MIN_TAIL: usize = 50;

/// Outcome of one release test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Comes to rest with monotonically shrinking swings.
    Settles,
    /// Comes to rest, after swings that grew at times.
    LocallyStable,
    /// Keeps oscillating within one tick of the origin.
    LimitCycle,
    /// Keeps oscillating over more than one tick, not growing.
    Persistent,
    /// Oscillation grows, or the supervisor tripped.
    Growing,
}

impl Verdict {
    /// True when the wall came to rest (the test passes).
    #[must_use]
    pub fn settled(self) -> bool {
        matches!(self, Self::Settles | Self::LocallyStable)
    }

    /// Human-readable name.
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            Self::Settles => "settles",
            Self::LocallyStable => "locally stable (settles after non-monotonic decay)",
            Self::LimitCycle => "limit cycle below one tick",
            Self::Persistent => "persistent oscillation above one tick",
            Self::Growing => "growing",
        }
    }
}

/// Distance of count `n` from the wall origin, in ticks (cell centre).
fn offset(n: i64) -> f64 {
    (n as f64 + 0.5).abs()
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

/// Classifies a release test from the counts recorded after release.
#[must_use]
pub fn classify(counts: &[i64], supervisor_tripped: bool) -> Verdict {
    if supervisor_tripped || counts.is_empty() {
        return Verdict::Growing;
    }
    let tail_len = (counts.len() / 4).max(MIN_TAIL).min(counts.len());
    let tail = &counts[counts.len() - tail_len..];
    let head = &counts[..tail_len];
    let max_off = |s: &[i64]| s.iter().map(|&n| offset(n)).fold(0.0, f64::max);
    let at_rest = tail.iter().all(|&n| n == tail[0]);
    if at_rest {
        let peaks = half_cycle_peaks(counts);
        // The final "peak" is the rest position; compare only completed swings.
        let swings = &peaks[..peaks.len().saturating_sub(1)];
        let grew = swings.windows(2).any(|w| w[1] > w[0]);
        return if grew {
            Verdict::LocallyStable
        } else {
            Verdict::Settles
        };
    }
    if tail.iter().all(|&n| n == -1 || n == 0) {
        return Verdict::LimitCycle;
    }
    if max_off(tail) >= max_off(head) {
        Verdict::Growing
    } else {
        Verdict::Persistent
    }
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
    }

    #[test]
    fn toggling_between_minus_one_and_zero_is_a_limit_cycle() {
        let mut c = decaying(10.0, 0.05, 200);
        c.extend((0..400).map(|k| if (k / 3) % 2 == 0 { 0 } else { -1 }));
        assert_eq!(classify(&c, false), Verdict::LimitCycle);
    }

    #[test]
    fn growth_and_trips_are_growing() {
        let c: Vec<i64> = (0..800)
            .map(|k| (5.0 * (0.004 * k as f64).exp() * (k as f64 * 0.3).sin()).floor() as i64)
            .collect();
        assert_eq!(classify(&c, false), Verdict::Growing);
        assert_eq!(classify(&vec![0; 100], true), Verdict::Growing);
    }

    #[test]
    fn a_steady_three_tick_cycle_is_persistent_or_growing_never_settled() {
        let c: Vec<i64> = (0..800)
            .map(|k| ((k as f64 * 0.3).sin() * 3.0).floor() as i64)
            .collect();
        assert!(!classify(&c, false).settled());
        let c = decaying(30.0, 0.005, 800);
        assert_eq!(classify(&c, false), Verdict::Persistent);
    }
}
