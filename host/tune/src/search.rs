//! Search for the largest stiffness whose release tests settle.
//!
//! Raising K moves the operating point towards the origin of the (β, σ) plane (Fig. 4), so
//! release tests pass below some K* and fail above it. The search brackets K* starting from a
//! predicted value (geometric steps of [`Search::step`] up from a pass or down from a fail),
//! then bisects geometrically until the bracket is within [`Search::rel_tol`]. It never tests
//! above `k_cap` (the firmware's force and energy limits) and gives up after `max_tests` tests.
//! Nothing here talks to a device: the caller supplies the release test as a closure.

use super::error::{bail, Result};
use super::release::Verdict;

/// Search settings.
#[derive(Debug, Clone, Copy)]
pub struct Search {
    /// Largest K that may be tested, in N/m (or N·m/rad).
    pub k_cap: f64,
    /// Factor between bracketing steps (> 1).
    pub step: f64,
    /// Stop when k_fail / k_pass − 1 is below this.
    pub rel_tol: f64,
    /// Most release tests the search may run.
    pub max_tests: usize,
    /// The search going down gives up below this K (besides 10⁻⁶ of its start): 0 for none.
    pub k_floor: f64,
}

impl Default for Search {
    fn default() -> Self {
        Self {
            k_cap: f64::INFINITY,
            step: 1.6,
            rel_tol: 0.02,
            max_tests: 40,
            k_floor: 0.0,
        }
    }
}

/// One release test the search ran.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Trial {
    /// Stiffness tested.
    pub k: f64,
    /// Its verdict.
    pub verdict: Verdict,
}

/// Result of a search.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Found {
    /// Largest stiffness whose test settled.
    pub k_pass: f64,
    /// Smallest stiffness whose test did not settle (None: the cap was reached settling).
    pub k_fail: Option<f64>,
    /// Every test, in order.
    pub trials: Vec<Trial>,
}

/// Brackets and bisects the largest resting K, starting at `k_start` (> 0).
pub fn largest_settling_k(
    k_start: f64,
    s: &Search,
    mut test: impl FnMut(f64) -> Result<Verdict>,
) -> Result<Found> {
    if !(k_start.is_finite() && k_start > 0.0) {
        bail!("start stiffness must be finite and > 0 (got {k_start})");
    }
    if !(s.step.is_finite() && s.step > 1.0 && s.rel_tol.is_finite() && s.rel_tol > 0.0) {
        bail!("search step must be > 1 and tolerance > 0");
    }
    let mut trials = Vec::new();
    let mut run = |k: f64, trials: &mut Vec<Trial>| -> Result<bool> {
        if trials.len() >= s.max_tests {
            bail!("no answer within {} release tests", s.max_tests);
        }
        let verdict = test(k)?;
        trials.push(Trial { k, verdict });
        Ok(verdict.passes())
    };
    let mut k = k_start.min(s.k_cap);
    let (mut lo, mut hi);
    if run(k, &mut trials)? {
        lo = k;
        loop {
            if lo >= s.k_cap {
                return Ok(Found {
                    k_pass: lo,
                    k_fail: None,
                    trials,
                });
            }
            k = (lo * s.step).min(s.k_cap);
            if run(k, &mut trials)? {
                lo = k;
            } else {
                hi = k;
                break;
            }
        }
    } else {
        hi = k;
        loop {
            k = hi / s.step;
            if k < k_start * 1e-6 || k < s.k_floor {
                return Err(super::error::NoWallPassed(format!(
                    "no stiffness down to {k:.3e} settles; the device may be unstable on its own"
                ))
                .into());
            }
            if run(k, &mut trials)? {
                lo = k;
                break;
            }
            hi = k;
        }
    }
    while hi / lo - 1.0 > s.rel_tol {
        let mid = (lo * hi).sqrt();
        if run(mid, &mut trials)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(Found {
        k_pass: lo,
        k_fail: Some(hi),
        trials,
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A device whose verdict is a clean threshold at `k_star` (shared with `repeat`'s tests).
    pub(crate) fn threshold(k_star: f64) -> impl FnMut(f64) -> Result<Verdict> {
        move |k| {
            Ok(if k <= k_star {
                Verdict::Settles
            } else {
                Verdict::Growing
            })
        }
    }

    #[test]
    fn finds_the_threshold_from_below_and_above() {
        for start in [10.0, 900.0, 1234.0, 1e5] {
            let f = largest_settling_k(start, &Search::default(), threshold(1234.0)).unwrap();
            assert!(
                f.k_pass <= 1234.0 && f.k_pass >= 1234.0 / 1.02,
                "{start}: {f:?}"
            );
            assert!(f.k_fail.unwrap() > 1234.0);
        }
    }

    #[test]
    fn never_tests_above_the_cap() {
        let s = Search {
            k_cap: 500.0,
            ..Search::default()
        };
        let f = largest_settling_k(100.0, &s, threshold(1e9)).unwrap();
        assert_eq!(f.k_pass, 500.0);
        assert!(f.trials.iter().all(|t| t.k <= 500.0));
        assert_eq!(f.k_fail, None);
    }

    #[test]
    fn gives_up_and_rejects_bad_input() {
        let s = Search {
            max_tests: 5,
            ..Search::default()
        };
        assert!(largest_settling_k(1.0, &s, threshold(1e12)).is_err());
        assert!(largest_settling_k(f64::NAN, &Search::default(), threshold(1.0)).is_err());
        assert!(largest_settling_k(0.0, &Search::default(), threshold(1.0)).is_err());
        let always_fails = |_k: f64| Ok(Verdict::Growing);
        assert!(largest_settling_k(1.0, &Search::default(), always_fails).is_err());
    }
}
