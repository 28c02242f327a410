//! Where a test's record ends and what of it is judged: computed from the counts alone, so
//! the host's judgement does not depend on when it sees them, and the device ends a test on
//! the same tick (`HostMsg::PrepareTest` states this rule; the firmware streams it and a test
//! below checks the two agree).
//!
//! - *Settled* ([`settled_within`]): the first length L at which the last
//!   max(`min_run`, ⌈L/3⌉) counts are all equal, or within one count under
//!   `Criterion::AcceptChatter`.
//! - *Decided by decay* ([`judged_len`]): from the base length on, at checkpoints every
//!   base/8 ticks up to [`DECAY_EXTENSION`] × the base, the first at which the oscillation no
//!   longer shrinks ([`decaying`]).
//!
//! Units: effective counts, one per servo tick; lengths in ticks.

use super::verdict::MIN_TAIL;

/// The length at which a record counts as settled: the first L at which the last
/// max(`min_run`, ⌈L/3⌉) counts of `counts[..L]` are all equal (so the tail judged by the
/// verdict, a quarter of L, is at rest). None while that has not happened.
/// (The tests' shorthand.)
#[cfg(test)]
#[must_use]
pub fn settled_at(counts: &[i64], min_run: usize) -> Option<usize> {
    settled_within(counts, min_run, false)
}

/// [`settled_at`], or with `one_count` the first L at which that tail lies within one count
/// (max − min ≤ 1: at rest or toggling between two neighbouring counts, the chatter that
/// passes only under `Criterion::AcceptChatter`, where a test ends there).
#[must_use]
pub fn settled_within(counts: &[i64], min_run: usize, one_count: bool) -> Option<usize> {
    // Longest suffixes ending here with values in {n − 1, n} (`below`) and {n, n + 1} (`above`).
    let (mut below, mut above) = (0usize, 0usize);
    for (i, &n) in counts.iter().enumerate() {
        let prev = if i > 0 { Some(counts[i - 1]) } else { None };
        (below, above) = match prev {
            Some(p) if p == n => (below + 1, above + 1),
            Some(p) if one_count && p == n - 1 => (above + 1, 1),
            Some(p) if one_count && p == n + 1 => (1, below + 1),
            _ => (1, 1),
        };
        let run = below.max(above);
        let len = i + 1;
        if run >= min_run.max(len.div_ceil(3)) {
            return Some(len);
        }
    }
    None
}

/// Most a test runs, as a multiple of its base length, while its oscillation keeps shrinking.
pub const DECAY_EXTENSION: usize = 2;
/// Checkpoints per base length at which a test past its base length is judged still decaying.
const DECAY_CHECKS: usize = 8;

/// Whether the oscillation at the end of `counts` is still shrinking: the range (max − min) of
/// the last quarter (at least [`MIN_TAIL`] counts) is smaller than that of the quarter before.
#[must_use]
pub fn decaying(counts: &[i64]) -> bool {
    let w = (counts.len() / 4).max(MIN_TAIL);
    if 2 * w > counts.len() {
        return false;
    }
    let range = |s: &[i64]| s.iter().max().unwrap_or(&0) - s.iter().min().unwrap_or(&0);
    let l = counts.len();
    range(&counts[l - w..]) < range(&counts[l - 2 * w..l - w])
}

/// Longest record of a test of base length `ticks` (the budget the firmware is given).
#[must_use]
pub fn max_test_len(ticks: usize) -> usize {
    let w = DecayWatch::new(ticks);
    w.ticks + w.step * DecayWatch::LAST
}

/// The length of a test's record that the verdict judges, once the counts decide it (None while
/// they do not): where it settled ([`settled_at`]), or else the first checkpoint at or after
/// the base length `ticks` — every `ticks`/8 up to [`max_test_len`] — at which the oscillation
/// is no longer [`decaying`]. A slowly decaying mode the encoder sees (a heavy hand ringing on a
/// soft transmission, say) is thus watched up to [`DECAY_EXTENSION`] × longer instead of being
/// judged a buzz while it still shrinks; a persistent buzz ends at the base length. Computed
/// from the counts alone, so it does not depend on when the host sees them.
/// (The tests' shorthand.)
#[cfg(test)]
#[must_use]
pub fn judged_len(counts: &[i64], ticks: usize, min_run: usize) -> Option<usize> {
    judged_len_within(counts, ticks, min_run, false)
}

/// [`judged_len`] with [`settled_within`]'s `one_count`.
#[must_use]
pub fn judged_len_within(
    counts: &[i64],
    ticks: usize,
    min_run: usize,
    one_count: bool,
) -> Option<usize> {
    let stop = DecayWatch::new(ticks).stop(counts);
    match (settled_within(counts, min_run, one_count), stop) {
        (Some(s), Some(l)) => Some(s.min(l)),
        (s, None) => s,
        (None, l) => l,
    }
}

/// The checkpoints of [`judged_len`] past the base length, examined once each as a record
/// grows (a prefix never changes, so a checkpoint found still decaying stays so): the running
/// test asks on every telemetry batch without re-reading the checkpoints already passed.
struct DecayWatch {
    ticks: usize,
    step: usize,
    next: usize,
}

impl DecayWatch {
    const LAST: usize = DECAY_CHECKS * (DECAY_EXTENSION - 1);
    // The device's rule (`HostMsg::PrepareTest`) is this one.
    const _SAME_AS_DEVICE: () = assert!(
        Self::LAST == stiffwall_proto::DECAY_LAST_CHECK as usize
            && DECAY_CHECKS == stiffwall_proto::DECAY_CHECKS_PER_BASE as usize
            && MIN_TAIL == stiffwall_proto::DECAY_MIN_WINDOW as usize
    );

    fn new(ticks: usize) -> Self {
        let ticks = ticks.max(1);
        Self {
            ticks,
            step: (ticks / DECAY_CHECKS).max(1),
            next: 0,
        }
    }

    /// The first checkpoint reached by `counts` at which the oscillation no longer decays (or
    /// the last one), if any.
    fn stop(&mut self, counts: &[i64]) -> Option<usize> {
        while self.next <= Self::LAST {
            let l = self.ticks + self.next * self.step;
            if l > counts.len() {
                return None;
            }
            if self.next == Self::LAST || !decaying(&counts[..l]) {
                return Some(l);
            }
            self.next += 1;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::verdict::classify;

    /// A square-ish oscillation of amplitude `amp(i)` counts, period 40 ticks.
    fn ringing(len: usize, amp: impl Fn(usize) -> f64) -> Vec<i64> {
        (0..len)
            .map(|i| (amp(i) * (std::f64::consts::TAU * i as f64 / 40.0).sin()).round() as i64)
            .collect()
    }

    #[test]
    fn a_shrinking_oscillation_is_decaying_and_a_steady_one_is_not() {
        let shrinking = ringing(2000, |i| 12.0 * (-(i as f64) / 600.0).exp());
        assert!(decaying(&shrinking));
        let steady = ringing(2000, |_| 6.0);
        assert!(!decaying(&steady));
        assert!(!decaying(&shrinking[..60]), "too short to tell");
    }

    #[test]
    fn a_decaying_test_runs_past_its_base_length_and_a_buzz_does_not() {
        let ticks = 1000;
        // A buzz: judged at the base length.
        let buzz = ringing(max_test_len(ticks) + 500, |_| 6.0);
        assert_eq!(judged_len(&buzz, ticks, 100), Some(ticks));
        assert_eq!(
            judged_len(&buzz[..ticks - 1], ticks, 100),
            None,
            "not decided yet"
        );
        // Ringing that decays to rest by about 2300 ticks: watched on past the base length and
        // ended where it settled, within the extension.
        let slow = ringing(4000, |i| 12.0 * (-(i as f64) / 400.0).exp());
        let settled = settled_at(&slow, 100).unwrap();
        assert!(
            settled > ticks && settled <= max_test_len(ticks),
            "{settled}"
        );
        assert_eq!(judged_len(&slow, ticks, 100), Some(settled));
        assert_eq!(
            judged_len(&slow[..ticks + 10], ticks, 100),
            None,
            "still shrinking"
        );
        // Never past the extension, however long it keeps shrinking.
        let very_slow = ringing(5000, |i| 40.0 * (-(i as f64) / 3000.0).exp());
        assert_eq!(
            judged_len(&very_slow, ticks, 100),
            Some(max_test_len(ticks))
        );
        assert_eq!(max_test_len(ticks), DECAY_EXTENSION * ticks);
        // A record that settles before its base length ends there, as before.
        let quick = ringing(3000, |i| 12.0 * (-(i as f64) / 40.0).exp());
        assert_eq!(judged_len(&quick, ticks, 100), settled_at(&quick, 100));
        assert!(settled_at(&quick, 100).unwrap() < ticks);
    }

    #[test]
    fn settled_at_cuts_where_a_third_of_the_record_is_constant() {
        let mut c: Vec<i64> = (0..300).map(|k| (10 - k / 30) as i64).collect();
        c.extend(std::iter::repeat_n(0, 400));
        let len = settled_at(&c, 100).unwrap();
        // Constant from index 300 (the last value of the ramp is 1, then zeros).
        assert_eq!(len, 450);
        assert!(classify(&c[..len], false).settled());
        // Adding samples after the cut does not move it.
        assert_eq!(settled_at(&c[..len + 37], 100), Some(len));
        assert_eq!(settled_at(&c[..400], 100), None);
        let toggling: Vec<i64> = (0..2000).map(|k| k % 2).collect();
        assert_eq!(settled_at(&toggling, 100), None);
    }

    proptest::proptest! {
        /// The device ends a test where the host judges it: `judged_len_within` and the
        /// firmware's `PrepareTest` rule agree on every record.
        #[test]
        fn the_device_ends_a_test_where_the_host_judges_it(
            a0 in 1.0f64..40.0,
            r in 0.995f64..1.003,
            period in 2.0f64..40.0,
            ticks in 1usize..400,
            len in 0usize..1000,
            min_run in 1usize..80,
            one_count: bool,
        ) {
            let counts: Vec<i64> = (0..len)
                .map(|k| {
                    let a = a0 * r.powi(k as i32);
                    (a * (std::f64::consts::TAU * k as f64 / period).cos()).floor() as i64
                })
                .collect();
            let device = stiffwall_firmware::experiment::decided_len(
                counts.iter().map(|&n| n as i32),
                min_run as u32,
                one_count,
                ticks as u32,
            );
            proptest::prop_assert_eq!(device, judged_len_within(&counts, ticks, min_run, one_count));
        }
    }

    #[test]
    fn settled_within_one_count_takes_a_toggle_and_not_a_wider_swing() {
        // Ten samples of a swing ending at 3, then a toggle between 3 and 4: the run within
        // one count starts at that last 3 (index 9) and is 20 long (the minimum run, more
        // than a third of the record) at L = 29.
        let mut c: Vec<i64> = vec![9, 1, 8, 2, 7, 3, 6, 2, 5, 3];
        c.extend((0..200).map(|k| 3 + (k / 3) % 2));
        assert_eq!(settled_within(&c, 20, true), Some(29));
        assert_eq!(settled_within(&c, 20, false), None);
        // Three counts wide (2, 3, 4) never settles within one count.
        let wide: Vec<i64> = (0..600).map(|k| [2, 3, 4, 3][k % 4]).collect();
        assert_eq!(settled_within(&wide, 20, true), None);
        // Either neighbour: a toggle between 3 and 2 also settles; a step from the pair
        // {3, 4} to {4, 5} keeps the 4s of the old pair in the new run.
        let low: Vec<i64> = (0..100).map(|k| 3 - (k % 2)).collect();
        assert_eq!(settled_within(&low, 20, true), Some(20));
        let shift: [i64; 7] = [3, 4, 4, 5, 4, 5, 4];
        assert_eq!(settled_within(&shift, 5, true), Some(6));
        assert_eq!(settled_within(&shift, 7, true), None);
        // Without one_count it is settled_at.
        assert_eq!(
            settled_within(&[1, 1, 1, 1], 3, false),
            settled_at(&[1, 1, 1, 1], 3)
        );
    }
}
