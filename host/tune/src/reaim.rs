//! Re-aiming a release whose hold stopped off its target: pure arithmetic on tick counts
//! (`verify::run_test` runs the attempts).
//!
//! Units: effective ticks.

/// Release tests re-aimed at most this many times when the hold stopped off its target.
pub const HOLD_REAIMS: usize = 3;

/// A release asked from `requested` ticks, aimed at `target`, started at `start` (the first
/// released count) with a verdict that `passes` or not: the target of the next attempt when
/// this one says nothing about the energy asked for, else `None`.
///
/// Static friction stops the hold where its spring's force falls below breakaway, up to
/// F_s/(KΔ) ticks off target (past it after the pull from rest, or short of it). A failure
/// from farther than asked or a pass from nearer, by more than ⌊|requested|/16⌋ ticks (at
/// least 1; about 12 % in energy), was a test at another energy: a wall can be stable up to
/// v_max and unstable just above it, as Coulomb friction damps less at larger amplitude. It is
/// re-aimed in proportion, target × requested / start, since the overshoot or shortfall grows
/// with the hold's travel. The tolerance is the same both ways, so that re-aiming does not
/// favour passes. A failure from nearer or a pass from farther is kept (the wall failed at a
/// lower energy, or held a higher one).
#[must_use]
pub fn reaim(requested: i32, target: i32, start: i64, passes: bool) -> Option<i32> {
    let want = i64::from(requested).abs();
    let got = start.abs();
    let tol = (want / 16).max(1);
    let off = if passes {
        got < want - tol
    } else {
        got > want + tol
    };
    if !off || got == 0 || start.signum() != i64::from(requested).signum() {
        return None;
    }
    let next = (i64::from(target) * want / got).clamp(-(1 << 20), 1 << 20);
    let next = i32::try_from(next).ok()?;
    (next != target && next != 0).then_some(next)
}

/// A release asked from `requested` ticks that started at `start` began short of it by more
/// than [`reaim`]'s tolerance (nearer the wall, at it, or on the other side).
#[must_use]
pub fn short_of(requested: i32, start: i64) -> bool {
    let want = i64::from(requested).abs();
    let tol = (want / 16).max(1);
    start.signum() != i64::from(requested).signum() || start.abs() < want - tol
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_release_off_its_target_is_reaimed_only_when_it_says_nothing() {
        // Asked 57, stuck at 66 and failed: aim at 57·57/66 = 49.
        assert_eq!(reaim(57, 57, 66, false), Some(49));
        // A second attempt (aimed at 49) that stuck at 68 again: 49·57/68 = 41.
        assert_eq!(reaim(57, 49, 68, false), Some(41));
        // Failed from 60 (within 57 + 3): the energy asked for, kept; from 61, re-aimed.
        assert_eq!(reaim(57, 57, 60, false), None);
        assert_eq!(reaim(57, 57, 61, false), Some(53));
        // Passed from 54 (within 57 − 3): kept; from 53, re-aimed.
        assert_eq!(reaim(57, 57, 54, true), None);
        assert_eq!(reaim(57, 57, 53, true), Some(61));
        // Passed from farther, or failed from nearer: kept.
        assert_eq!(reaim(57, 57, 66, true), None);
        assert_eq!(reaim(57, 57, 40, false), None);
        // Passed from well short: aim farther, on the negative side too.
        assert_eq!(reaim(-40, -40, -30, true), Some(-53));
        // Small deflections: one tick of tolerance.
        assert_eq!(reaim(2, 2, 2, true), None);
        assert_eq!(reaim(4, 4, 2, true), Some(8));
        // Started on the other side, or at the wall: nothing to scale.
        assert_eq!(reaim(57, 57, -66, false), None);
        assert_eq!(reaim(57, 57, 0, true), None);
    }

    #[test]
    fn a_start_short_of_the_deflection_asked_is_told_beyond_the_tolerance() {
        // Asked 9 (tolerance 1): from 8 is the energy asked, from 7 short, and so are the
        // wall itself and the other side.
        assert!(!short_of(9, 9) && !short_of(9, 8) && !short_of(9, 12));
        assert!(short_of(9, 7) && short_of(9, 0) && short_of(9, -9));
        // Asked −57 (tolerance 3): −54 is within it, −53 short, +57 the wrong side.
        assert!(!short_of(-57, -54) && short_of(-57, -53) && short_of(-57, 57));
    }
}
