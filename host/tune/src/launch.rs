//! What an impact test's launch delivered at contact, and whether it was the impact asked for.
//!
//! The firmware launches an impact with its hold: a spring (the wall's K) and damper pulling
//! the device toward a target that moves at the requested speed; at contact (the first count
//! inside the wall) it releases the device into the wall. On a light device behind a slow
//! amplifier or extra delay the hold lags its target and then catches up, so the device can
//! reach the wall much faster than asked (a wall that holds at v_max may fail at 1.8 v_max),
//! or, behind a tight force limit, slower. This module measures what the launch delivered,
//! from the samples alone, so that a failure after a launch that was not the one asked for is
//! not taken for the wall's:
//! - the *contact speed*: the larger of the last two count steps into contact (the launch
//!   releases on the tick it reads a count in the wall, so its last count is already in
//!   contact), counts per tick;
//! - the *fastest step* of the launch's last [`EXIT_WINDOW`] ticks into contact (a hold that
//!   oscillates near the Nyquist rate moves fast but averages to no speed);
//! - the *mean speed* over those ticks (what the one-sided exit-speed rule compares with).
//!
//! A launch is *as asked* when its contact speed and fastest step are within
//! [`LAUNCH_AIM_TOLERANCE`] × the asked speed + one count per tick of it (one count: the
//! encoder's resolution of a speed measured over one tick). An impact that fails after a launch
//! that arrived too fast is re-aimed (`verify::run_test`). A failure is
//! [`Verdict::NotLaunched`] (it says nothing about the wall at the asked speed) only after a
//! launch slower than asked or more than [`LAUNCH_EXCUSE_FACTOR`] × faster: a moderately
//! faster hit that fails is kept as the wall's failure (safety first: the hit a user gives is
//! not bounded by v_max to the count). One that passes after a faster launch passes (a harder
//! test); one that passes after a slower launch passes as the impact it was, and is reported
//! (see [`Delivered::slow`]).
//!
//! Units: effective counts, servo ticks; speeds in counts per tick.

use super::verdict::{classify_impact, Verdict, Wall, EXIT_WINDOW};
use stiffwall_proto::{flags, Sample};

/// Relative tolerance of a launch's speed at contact (plus one count per tick).
pub const LAUNCH_AIM_TOLERANCE: f64 = 0.3;

/// Impact tests re-aimed at most this many times when the launch arrived too fast.
pub const LAUNCH_REAIMS: usize = 2;

/// A failure is excused as not the wall's only after a launch faster than this × the asked
/// speed (+ one count per tick), or slower than asked: between the two, a re-aimed launch that
/// still arrives too fast and fails is the wall failing at that (harder) speed, which is kept
/// (a faster hit than v may be what shows the wall's limit cycle).
pub const LAUNCH_EXCUSE_FACTOR: f64 = 2.0;

/// What one impact's launch delivered.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Delivered {
    /// The asked speed, counts per tick (magnitude).
    pub asked: f64,
    /// The speed into contact (the larger of the last two steps), counts per tick (magnitude).
    pub contact: f64,
    /// The fastest step of the launch's last ticks into contact (magnitude).
    pub fastest: f64,
    /// The mean speed over the launch's last ticks into contact (magnitude).
    pub mean: f64,
}

impl Delivered {
    /// From an impact record: its samples (launch flagged `HOLD`) and the counts in contact
    /// (`in_contact`, effective counts), with the asked speed. None without contact.
    #[must_use]
    pub fn from_record(
        samples: &[Sample],
        in_contact: &[i64],
        shift: u8,
        asked: f64,
    ) -> Option<Self> {
        let first = *in_contact.first()?;
        let launch: Vec<i64> = samples
            .iter()
            .filter(|x| x.flags & flags::HOLD != 0)
            .map(|x| i64::from(x.count) >> shift)
            .collect();
        // Contact is seen on the last launched count (the hold releases on the tick it reads
        // a count in the wall): the speed into contact is the larger of the last two steps.
        let last = *launch.last()?;
        let before = launch.len().checked_sub(2).map_or(last, |i| launch[i]);
        let w = EXIT_WINDOW.min(launch.len().saturating_sub(1));
        let mean = if w > 0 {
            ((first - launch[launch.len() - w]) as f64 / (w as f64 + 1.0)).abs()
        } else {
            0.0
        };
        let tail = &launch[launch.len().saturating_sub(EXIT_WINDOW + 1)..];
        let fastest = tail
            .iter()
            .chain(std::iter::once(&first))
            .collect::<Vec<_>>()
            .windows(2)
            .map(|p| (p[1] - p[0]).unsigned_abs() as f64)
            .fold(0.0, f64::max);
        Some(Self {
            asked: asked.abs(),
            contact: (first - last)
                .unsigned_abs()
                .max((last - before).unsigned_abs()) as f64,
            fastest,
            mean,
        })
    }

    fn slack(&self) -> f64 {
        LAUNCH_AIM_TOLERANCE * self.asked + 1.0
    }

    /// Faster than asked: the contact speed or the fastest step beyond the tolerance.
    #[must_use]
    pub fn fast(&self) -> bool {
        self.contact.max(self.fastest) > self.asked + self.slack()
    }

    /// Slower than asked: the contact speed below the tolerance.
    #[must_use]
    pub fn slow(&self) -> bool {
        self.contact < self.asked - self.slack()
    }

    /// The launch delivered the impact asked for.
    #[must_use]
    pub fn as_asked(&self) -> bool {
        !self.fast() && !self.slow()
    }

    /// So far off the asked speed that a failure says nothing about the wall at it: slower
    /// than asked, or faster than `LAUNCH_EXCUSE_FACTOR` × it + one count per tick.
    #[must_use]
    pub fn excuses_failure(&self) -> bool {
        self.slow() || self.contact.max(self.fastest) > LAUNCH_EXCUSE_FACTOR * self.asked + 1.0
    }

    /// For a launch that arrived too fast, the launch speed (thousandths of a count per tick,
    /// signed as `milli`) that should deliver the asked speed: `milli` scaled by asked over
    /// delivered (the hold's catch-up scales with its speed), at least 1.
    #[must_use]
    pub fn reaimed(&self, milli: i32) -> Option<i32> {
        if !self.fast() || self.contact <= 0.0 {
            return None;
        }
        let scale = self.asked / self.contact.max(self.fastest);
        let m = (f64::from(milli) * scale).round() as i32;
        Some(if m == 0 { milli.signum() } else { m })
    }
}

/// The verdict on an impact from contact on (see the module header): `classify_impact` with
/// the launch's mean speed, and [`Verdict::NotLaunched`] for no contact or for a failure after
/// a launch that excuses it ([`Delivered::excuses_failure`]).
#[must_use]
pub fn judge_impact(
    in_contact: &[i64],
    wall: Wall,
    delivered: Option<&Delivered>,
    tripped: bool,
) -> Verdict {
    let Some(d) = delivered else {
        return Verdict::NotLaunched;
    };
    let verdict = classify_impact(in_contact, wall, d.mean, tripped);
    // Chatter is the wall's own (it keeps toggling where it came to rest, whatever the
    // launch); only a failure in the motion itself can be the launch's.
    if !verdict.passes() && !verdict.chatters() && d.excuses_failure() {
        Verdict::NotLaunched
    } else {
        verdict
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(count: i32, fl: u16) -> Sample {
        Sample {
            tick: 0,
            count,
            force_code: 0,
            flags: fl,
            energy: 0,
        }
    }

    /// A launch at `steps` counts per tick into contact at count 0 and beyond.
    fn record(steps: &[i64]) -> (Vec<Sample>, Vec<i64>) {
        let mut n = -steps.iter().sum::<i64>();
        let mut samples = vec![sample(n as i32, flags::HOLD)];
        for &s in &steps[..steps.len() - 1] {
            n += s;
            samples.push(sample(n as i32, flags::HOLD));
        }
        let first = n + steps[steps.len() - 1];
        (samples, vec![first, first + 1, first + 1])
    }

    #[test]
    fn a_steady_launch_is_as_asked_and_a_catch_up_is_too_fast() {
        let (s, c) = record(&[5; 12]);
        let d = Delivered::from_record(&s, &c, 0, 5.0).unwrap();
        assert_eq!((d.contact, d.fastest), (5.0, 5.0));
        assert!(d.as_asked());
        assert_eq!(d.reaimed(5000), None);
        // Lagging, then catching up at 9 counts per tick into contact.
        let (s, c) = record(&[2, 2, 3, 3, 4, 5, 6, 7, 8, 9]);
        let d = Delivered::from_record(&s, &c, 0, 5.0).unwrap();
        assert_eq!(d.contact, 9.0);
        assert!(d.fast() && !d.as_asked());
        assert_eq!(d.reaimed(5000), Some(2778));
        assert_eq!(d.reaimed(-5000), Some(-2778));
        // Behind a force limit: 2 counts per tick for an asked 5.
        let (s, c) = record(&[2; 12]);
        let d = Delivered::from_record(&s, &c, 0, 5.0).unwrap();
        assert!(d.slow() && !d.fast());
        assert_eq!(d.reaimed(5000), None);
    }

    #[test]
    fn a_failure_says_nothing_about_the_wall_only_after_a_launch_not_as_asked() {
        // Growing swings in contact (the tail reaches as far as the head).
        let growing: Vec<i64> = (0..400)
            .map(|k: i64| ((k % 20) - 10) * (1 + k / 100))
            .collect();
        let (s, c) = record(&[5; 12]);
        let asked = Delivered::from_record(&s, &c, 0, 5.0).unwrap();
        assert_eq!(
            judge_impact(&growing, Wall::Bidirectional, Some(&asked), false),
            Verdict::Growing
        );
        // 9 for 5: too fast (re-aimed by the caller), but not so fast as to excuse a failure.
        let (s, c) = record(&[2, 2, 3, 3, 4, 5, 6, 7, 8, 9]);
        let faster = Delivered::from_record(&s, &c, 0, 5.0).unwrap();
        assert!(faster.fast() && !faster.excuses_failure());
        assert_eq!(
            judge_impact(&growing, Wall::Bidirectional, Some(&faster), false),
            Verdict::Growing
        );
        // 13 for 5 (more than 2 × 5 + 1): says nothing about the wall at 5.
        let (s, c) = record(&[2, 2, 3, 4, 6, 8, 10, 12, 13]);
        let fast = Delivered::from_record(&s, &c, 0, 5.0).unwrap();
        assert!(fast.excuses_failure());
        assert_eq!(
            judge_impact(&growing, Wall::Bidirectional, Some(&fast), false),
            Verdict::NotLaunched
        );
        let mut rest = vec![3, 2, 1];
        rest.extend(std::iter::repeat_n(0, 300));
        assert_eq!(
            judge_impact(&rest, Wall::Bidirectional, Some(&fast), false),
            Verdict::Settles
        );
        assert_eq!(
            judge_impact(&rest, Wall::Bidirectional, None, false),
            Verdict::NotLaunched
        );
    }
}
