//! A frontier K as a repeatable measurement (issue 42): the largest resting K a search found
//! is run again from a new start before it counts.
//!
//! A quantized wall near its limit has narrow, start-dependent failing bands: whether a release
//! or an impact rests turns on where within a count the device starts and what the last test
//! left behind. A bisection that ran each K once can end on a K that rested by chance, and two
//! tunes of the same device then set walls a band apart. Here the search's K is re-run (the
//! device starts wherever the tests before left it, so the repeat is a new start); a K counts
//! only when every run of it rested. When the repeat fails, K steps down by the search's
//! tolerance, each new K run once, at most [`REPEAT_STEPS`] times.
//!
//! The *spread* is the bracket this measurement leaves: the smallest K that failed (in the
//! search or the repeat) over the largest that rested in every run, minus 1 (0 when the search
//! stopped at its cap, the quiet ceiling, resting). It is what this run's tests saw: a narrow
//! failing band that none of its starts fell in is not in it, and another tune of the same
//! device can land elsewhere (the emulated maxon-re35 board: frontiers 4.28 to 5.19 at one B).
//! The margin it implies ([`margin_for_spread`]) keeps the wall set below the frontier by
//! twice the spread at least.
//!
//! Units: K in N/m (N·m/rad); spreads and margins are ratios. Nothing here talks to a device:
//! the caller supplies the search step as a closure.

use super::error::Result;
use super::release::Verdict;

/// Steps down a K whose repeat failed may take before the frontier there is given up.
pub const REPEAT_STEPS: usize = 4;

/// What re-running a search's largest resting K showed.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Repeat {
    /// The search's largest resting K (one run), N/m (N·m/rad).
    pub k_searched: f64,
    /// The largest K whose every run rested, N/m (N·m/rad); None when no K within
    /// [`REPEAT_STEPS`] steps below rested.
    pub k_repeated: Option<f64>,
    /// The smallest K above it that failed, in the search or its repeat, N/m (N·m/rad); None
    /// when none did (the search stopped at its cap).
    pub k_failed: Option<f64>,
    /// Runs made after the search (the repeat and the steps down).
    pub runs: u32,
}

impl Repeat {
    /// The frontier's spread: k_failed / k_repeated − 1, the bracket within which this
    /// measurement puts the frontier (0 at the cap); when no K rested, k_searched over the last
    /// K tried.
    #[must_use]
    pub fn spread(&self) -> f64 {
        match (self.k_repeated, self.k_failed) {
            (Some(k), Some(f)) => (f / k - 1.0).max(0.0),
            (Some(_), None) => 0.0,
            (None, f) => f.map_or(0.0, |f| self.k_searched / f - 1.0),
        }
    }
}

/// Re-runs `k_searched` with `step` (a new start), stepping down by `1 + rel_step` while a run
/// fails, at most [`REPEAT_STEPS`] times below; `k_fail` is the search's smallest failing K.
pub fn repeated(
    k_searched: f64,
    k_fail: Option<f64>,
    rel_step: f64,
    mut step: impl FnMut(f64) -> Result<Verdict>,
) -> Result<Repeat> {
    let mut k = k_searched;
    let mut k_failed = k_fail;
    let mut runs = 0;
    for _ in 0..=REPEAT_STEPS {
        runs += 1;
        if step(k)?.passes() {
            return Ok(Repeat {
                k_searched,
                k_repeated: Some(k),
                k_failed,
                runs,
            });
        }
        k_failed = Some(k);
        k /= 1.0 + rel_step;
    }
    Ok(Repeat {
        k_searched,
        k_repeated: None,
        k_failed,
        runs,
    })
}

/// The margin a measured `spread` leaves: `margin`, or 1/(1 + 2·spread) when that is smaller.
#[must_use]
pub fn margin_for_spread(margin: f64, spread: f64) -> f64 {
    margin.min(1.0 / (1.0 + 2.0 * spread.max(0.0)))
}

/// The spread a `margin` leaves room for (the inverse of [`margin_for_spread`]'s bound).
#[must_use]
pub fn spread_room(margin: f64) -> f64 {
    ((1.0 / margin) - 1.0) / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::tests::threshold;

    #[test]
    fn a_repeat_that_rests_keeps_the_k_and_the_searchs_bracket() {
        let r = repeated(100.0, Some(102.5), 0.025, threshold(100.0)).unwrap();
        assert_eq!(r.k_repeated, Some(100.0));
        assert_eq!(r.runs, 1);
        assert!((r.spread() - 0.025).abs() < 1e-12);
        // At the search's cap nothing above failed.
        let capped = repeated(100.0, None, 0.025, threshold(100.0)).unwrap();
        assert_eq!(capped.spread(), 0.0);
    }

    #[test]
    fn a_repeat_that_fails_steps_down_to_a_k_that_rests() {
        // The search's K rested once by chance; the truth is 5 % lower.
        let r = repeated(100.0, Some(102.5), 0.025, threshold(95.0)).unwrap();
        let k = r.k_repeated.unwrap();
        assert!(k <= 95.0 && k > 95.0 / 1.025, "{r:?}");
        // 100, 97.6 and 95.2 fail, 92.9 rests.
        assert_eq!(r.runs, 4);
        // The bracket is now the last K that failed over the one that rested: one step.
        assert_eq!(r.k_failed, Some(100.0 / 1.025 / 1.025));
        assert!((r.spread() - 0.025).abs() < 1e-12);
    }

    #[test]
    fn no_k_within_the_steps_gives_up_and_reports_the_spread_tried() {
        let r = repeated(100.0, None, 0.025, threshold(50.0)).unwrap();
        assert_eq!(r.k_repeated, None);
        assert_eq!(r.runs as usize, REPEAT_STEPS + 1);
        assert!((r.spread() - (1.025f64.powi(4) - 1.0)).abs() < 1e-12);
    }

    #[test]
    fn the_margin_shrinks_only_for_a_spread_it_has_no_room_for() {
        assert_eq!(margin_for_spread(0.8, 0.0), 0.8);
        assert_eq!(margin_for_spread(0.8, 0.1), 0.8);
        // 0.8 leaves room for a spread of 12.5 %; 20 % needs 1/1.4.
        assert!((spread_room(0.8) - 0.125).abs() < 1e-12);
        assert!((margin_for_spread(0.8, 0.2) - 1.0 / 1.4).abs() < 1e-12);
    }
}
