//! When a wall **comes to rest**: the one rule that `tune`'s verification, the brute-force
//! K*_quiet of the tests, the (K, B) map and the live view all use, for spring-only and damped
//! walls alike.
//!
//! Units: encoder counts (one sample per servo tick), forces in N (N·m), times in s.
//!
//! **The rule.** A run comes to rest when, over its judged window, the encoder count changes at
//! most [`REST_MAX_CHANGES`] times. The window is the last quarter of the run, and never starts
//! later than [`REST_WINDOW_NATURAL_PERIODS`] natural periods 2π√(m/K) after the start
//! ([`window_start`]): so for any run of at least [`REST_RUN_NATURAL_PERIODS`] natural periods
//! it is at least as strict as "at most 2 count changes over the last quarter of a run of 60
//! natural periods". A device whose count still toggles there never stops: with the wall's
//! force F = −KΔ(n + ½) (eq. (2)) it rests only at a count where friction holds the force, and
//! a count that keeps changing is the *buzz* users hear, even within one count.
//!
//! A run that does not rest and stays within two neighbouring counts is **chatter**
//! ([`Chatter`]: toggles per second and the rendered force's peak to peak, in N and in units of
//! the Coulomb friction c). Runs that wander over more counts are a buzz or growth and are
//! classified by their callers.
//!
//! **The quiet ceiling.** With F = −KΔ(n + ½) the smallest wall force at any count is KΔ/2, so
//! once KΔ/2 exceeds the friction that can hold the device (Coulomb c, or static friction F_s
//! when larger) no count exists where it can stay: the count must toggle for ever. Eq. (18)'s
//! σ = c/(KΔ) ≥ ½ is this condition. [`quiet_ceiling`] gives 2·max(c, F_s)/Δ.

/// Most count changes a run may show in its judged window and still count as at rest.
pub const REST_MAX_CHANGES: usize = 2;

/// Natural periods a run must last for its rest to be judged (the trial length of the K*
/// criterion and of `tune`'s tests).
pub const REST_RUN_NATURAL_PERIODS: f64 = 60.0;

/// The judged window starts no later than this many natural periods into the run (the last
/// quarter of a run of [`REST_RUN_NATURAL_PERIODS`]).
pub const REST_WINDOW_NATURAL_PERIODS: f64 = 45.0;

/// Number of times consecutive counts differ.
#[must_use]
pub fn count_changes(counts: &[i64]) -> usize {
    counts.windows(2).filter(|w| w[0] != w[1]).count()
}

/// First index of the judged window of a run of `len` samples whose natural period is
/// `natural_ticks` samples: the last quarter, or from [`REST_WINDOW_NATURAL_PERIODS`] natural
/// periods on when that is earlier (a run longer than 60 natural periods is judged over more
/// than its last quarter, never less). A `natural_ticks` that is not finite and positive
/// judges the last quarter.
#[must_use]
pub fn window_start(len: usize, natural_ticks: f64) -> usize {
    let quarter = len - len / 4;
    if natural_ticks.is_finite() && natural_ticks > 0.0 {
        let by_periods = REST_WINDOW_NATURAL_PERIODS * natural_ticks;
        if by_periods < quarter as f64 {
            return by_periods as usize;
        }
    }
    quarter
}

/// True when the window `counts` shows at most [`REST_MAX_CHANGES`] count changes.
#[must_use]
pub fn window_rests(counts: &[i64]) -> bool {
    count_changes(counts) <= REST_MAX_CHANGES
}

/// True when the window `counts` stays within one count (at most two neighbouring counts): a
/// run that does not rest but keeps to this chatters, one that does not swings over more.
#[must_use]
pub fn window_within_one_count(counts: &[i64]) -> bool {
    let lo = counts.iter().copied().min().unwrap_or(0);
    let hi = counts.iter().copied().max().unwrap_or(0);
    hi - lo <= 1
}

/// True when the run `counts` comes to rest by the rule of the module header.
#[must_use]
pub fn comes_to_rest(counts: &[i64], natural_ticks: f64) -> bool {
    window_rests(&counts[window_start(counts.len(), natural_ticks)..])
}

/// The quiet ceiling 2·max(c, F_s)/Δ, N/m (N·m/rad): above it no count can hold the wall's
/// force KΔ/2 and the count toggles for ever. `coulomb_n` c and `static_n` F_s in N (N·m;
/// a static friction below c counts as c), `resolution_m` Δ in m (rad). 0 without friction;
/// +∞ for Δ = 0.
#[must_use]
pub fn quiet_ceiling(coulomb_n: f64, static_n: f64, resolution_m: f64) -> f64 {
    let hold = if static_n > coulomb_n {
        static_n
    } else {
        coulomb_n
    };
    if hold <= 0.0 {
        return 0.0;
    }
    2.0 * hold / resolution_m
}

/// A run that keeps toggling in its judged window: how fast and how hard.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chatter {
    /// Count changes per second over the window.
    pub toggles_per_s: f64,
    /// Peak-to-peak rendered force over the window, N (N·m).
    pub force_pp_n: f64,
    /// The same in units of the Coulomb friction c (+∞ without friction, 0 when the force
    /// does not swing).
    pub force_pp_c: f64,
    /// Distinct counts visited in the window (2: within one count).
    pub span_counts: i64,
}

impl Chatter {
    /// The chatter of a window: `counts` and the rendered `forces_n` of the same samples (the
    /// shorter length is used), one per `period_s`, with Coulomb friction `coulomb_n`.
    #[must_use]
    pub fn of_window(counts: &[i64], forces_n: &[f64], period_s: f64, coulomb_n: f64) -> Self {
        let len = counts.len().min(forces_n.len()).max(1);
        let duration = len as f64 * period_s;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &f in &forces_n[..forces_n.len().min(len)] {
            lo = lo.min(f);
            hi = hi.max(f);
        }
        let force_pp_n = if hi >= lo { hi - lo } else { 0.0 };
        let force_pp_c = if force_pp_n == 0.0 {
            0.0
        } else if coulomb_n > 0.0 {
            force_pp_n / coulomb_n
        } else {
            f64::INFINITY
        };
        let c = &counts[..counts.len().min(len)];
        let n_lo = c.iter().copied().min().unwrap_or(0);
        let n_hi = c.iter().copied().max().unwrap_or(0);
        Self {
            toggles_per_s: count_changes(c) as f64 / duration,
            force_pp_n,
            force_pp_c,
            span_counts: n_hi - n_lo + 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn within_one_count_takes_a_toggle_and_not_a_wider_swing() {
        assert!(window_within_one_count(&[3, 4, 3, 4, 4]));
        assert!(window_within_one_count(&[-1, -1]));
        assert!(!window_within_one_count(&[-1, 0, 1, 0]));
    }

    #[test]
    fn changes_are_counted_between_neighbours() {
        assert_eq!(count_changes(&[]), 0);
        assert_eq!(count_changes(&[3]), 0);
        assert_eq!(count_changes(&[3, 3, 4, 4, 3, 5]), 3);
    }

    #[test]
    fn two_changes_in_the_window_rest_three_do_not() {
        // 400 samples, natural period 10: window from 300 (quarter) vs 450 (periods): 300.
        let mut c = [0i64; 400];
        c[350] = 1;
        assert_eq!(window_start(400, 10.0), 300);
        assert!(comes_to_rest(&c, 10.0), "one excursion = 2 changes");
        c[360] = 1;
        assert!(!comes_to_rest(&c, 10.0), "two excursions = 4 changes");
        // A toggle before the window does not count.
        let mut c = [0i64; 400];
        for (i, n) in c.iter_mut().enumerate().take(299) {
            *n = (i % 2) as i64;
        }
        assert!(comes_to_rest(&c, 10.0));
    }

    #[test]
    fn a_long_run_is_judged_from_45_natural_periods() {
        // 60 natural periods of 10 ticks = 600; a run of 2000 is judged from 450, not 1500.
        assert_eq!(window_start(2000, 10.0), 450);
        let mut c = [0i64; 2000];
        for (i, n) in c.iter_mut().enumerate().take(1000).skip(450) {
            *n = (i % 2) as i64;
        }
        assert!(!comes_to_rest(&c, 10.0), "toggles from period 45 to 100");
        assert_eq!(window_start(2000, f64::NAN), 1500);
        assert_eq!(window_start(2000, 0.0), 1500);
    }

    #[test]
    fn the_quiet_ceiling_is_twice_the_holding_friction_over_the_resolution() {
        // Phantom 1.0 (Table II): c = 0.038 N, Δ = 29.1 µm → 2612 N/m.
        let k = quiet_ceiling(0.038, 0.0, 29.1e-6);
        assert!((k - 2611.7).abs() < 0.1, "{k}");
        assert_eq!(quiet_ceiling(0.04, 0.06, 1e-3), 120.0);
        assert_eq!(quiet_ceiling(0.0, 0.0, 1e-3), 0.0);
    }

    #[test]
    fn chatter_reports_rate_and_force_swing() {
        // Toggling every tick between 0 and −1 at 1 kHz, force ±KΔ/2 = ±0.5 N, c = 0.1 N.
        let counts: [i64; 100] = core::array::from_fn(|i| -((i % 2) as i64));
        let forces: [f64; 100] = core::array::from_fn(|i| if i % 2 == 0 { -0.5 } else { 0.5 });
        let ch = Chatter::of_window(&counts, &forces, 1e-3, 0.1);
        assert!((ch.toggles_per_s - 990.0).abs() < 1e-9);
        assert!((ch.force_pp_n - 1.0).abs() < 1e-12);
        assert!((ch.force_pp_c - 10.0).abs() < 1e-9);
        assert_eq!(ch.span_counts, 2);
        assert_eq!(
            Chatter::of_window(&counts, &forces, 1e-3, 0.0).force_pp_c,
            f64::INFINITY
        );
    }
}
