//! The values of a slice axis of `hostctl map` (μ or τ_D): one value, a list, or a linearly or
//! logarithmically spaced range.
//!
//! Units: those of the quantity (μ dimensionless, τ_D in sampling periods). Invariants: after
//! [`Values::validate`] there are 1..=[`MAX_VALUES`] finite values; a log range has lo > 0; the
//! first and last values of a range are exactly `lo` and `hi`. A single value serialises as a
//! plain JSON number, so the spec (and its hash) of a two-axis map is what it was before slice
//! axes existed.

use serde::{Deserialize, Serialize};

/// Largest number of values on one slice axis.
pub const MAX_VALUES: usize = 1000;

/// Values of a slice axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Values {
    /// One value (`100`).
    One(f64),
    /// Explicit values (`0,0.5,1`), in the given order.
    List(Vec<f64>),
    /// `lo:hi:n` (linear) or `lo:hi:n:log` (logarithmic spacing).
    Range {
        /// First value.
        lo: f64,
        /// Last value.
        hi: f64,
        /// Number of values.
        n: usize,
        /// Logarithmic spacing (lo > 0).
        #[serde(default)]
        log: bool,
    },
}

impl Values {
    /// Parses `v`, `v1,v2,…`, `lo:hi:n` or `lo:hi:n:log`.
    ///
    /// # Errors
    /// A message giving the accepted forms.
    pub fn parse(s: &str) -> Result<Self, String> {
        let bad = || {
            format!(
                "{s:?}: expected a number, a list v1,v2,… or a range lo:hi:n[:log] \
                 (finite lo <= hi, 1 <= n <= {MAX_VALUES}; lo > 0 for :log)"
            )
        };
        let num = |t: &str| t.trim().parse::<f64>().map_err(|_| bad());
        let v = if s.contains(':') {
            let parts: Vec<&str> = s.split(':').collect();
            let log = match parts.get(3).map(|t| t.trim()) {
                None => false,
                Some("log") => true,
                Some(_) => return Err(bad()),
            };
            if !(3..=4).contains(&parts.len()) {
                return Err(bad());
            }
            Self::Range {
                lo: num(parts[0])?,
                hi: num(parts[1])?,
                n: parts[2].trim().parse().map_err(|_| bad())?,
                log,
            }
        } else if s.contains(',') {
            Self::List(s.split(',').map(num).collect::<Result<_, _>>()?)
        } else {
            Self::One(num(s)?)
        };
        v.validate().map_err(|e| format!("{}: {e}", bad()))?;
        Ok(v)
    }

    /// Checks the shape: 1..=[`MAX_VALUES`] values, finite bounds with lo <= hi, lo > 0 for a
    /// log range. (The range of the quantity itself is checked by its user.)
    ///
    /// # Errors
    /// A message naming the violated bound.
    pub fn validate(&self) -> Result<(), String> {
        match self {
            Self::One(_) => Ok(()),
            Self::List(v) if (1..=MAX_VALUES).contains(&v.len()) => Ok(()),
            Self::List(v) => Err(format!("{} values: allowed 1 to {MAX_VALUES}", v.len())),
            Self::Range { lo, hi, n, log } => {
                if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                    Err(format!("lo = {lo}, hi = {hi}: need finite lo <= hi"))
                } else if !(1..=MAX_VALUES).contains(n) {
                    Err(format!("n = {n}: allowed range is [1, {MAX_VALUES}]"))
                } else if *log && *lo <= 0.0 {
                    Err(format!("lo = {lo}: a log range needs lo > 0"))
                } else {
                    Ok(())
                }
            }
        }
    }

    /// Number of values (call after [`Self::validate`]).
    #[must_use]
    pub fn len(&self) -> usize {
        match self {
            Self::One(_) => 1,
            Self::List(v) => v.len(),
            Self::Range { n, .. } => *n,
        }
    }

    /// True when there are no values (never, after validation).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The i-th value (i < [`Self::len`]).
    #[must_use]
    pub fn at(&self, i: usize) -> f64 {
        match self {
            Self::One(v) => *v,
            Self::List(v) => v[i],
            Self::Range { lo, hi, n, log } => {
                if *n == 1 || i == 0 {
                    *lo
                } else if i + 1 == *n {
                    *hi
                } else {
                    let t = i as f64 / (*n - 1) as f64;
                    if *log {
                        lo * (hi / lo).powf(t)
                    } else {
                        lo + (hi - lo) * t
                    }
                }
            }
        }
    }

    /// All values, in order.
    #[must_use]
    pub fn values(&self) -> Vec<f64> {
        (0..self.len()).map(|i| self.at(i)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forms_parse_and_log_ranges_hit_decades() {
        assert_eq!(Values::parse("100").unwrap().values(), vec![100.0]);
        assert_eq!(
            Values::parse("0, 0.5,1.25").unwrap().values(),
            vec![0.0, 0.5, 1.25]
        );
        assert_eq!(
            Values::parse("0:2:5").unwrap().values(),
            vec![0.0, 0.5, 1.0, 1.5, 2.0]
        );
        let v = Values::parse("1:1000:7:log").unwrap().values();
        // Independent: 10^(i/2).
        for (i, x) in v.iter().enumerate() {
            let want = 10f64.powf(i as f64 / 2.0);
            assert!((x - want).abs() <= 1e-12 * want, "{i}: {x} vs {want}");
        }
        assert_eq!(v[6], 1000.0);
        for bad in [
            "",
            "1:2",
            "0:10:3:log",
            "2:1:3",
            "1:2:0",
            "1:2:3:lin",
            "a,b",
        ] {
            assert!(Values::parse(bad).is_err(), "{bad:?}");
        }
    }

    #[test]
    fn a_single_value_serialises_as_a_number() {
        assert_eq!(serde_json::to_string(&Values::One(100.0)).unwrap(), "100.0");
        let back: Values = serde_json::from_str("100.0").unwrap();
        assert_eq!(back, Values::One(100.0));
        let r = Values::parse("1:1000:4:log").unwrap();
        let back: Values = serde_json::from_str(&serde_json::to_string(&r).unwrap()).unwrap();
        assert_eq!(back, r);
    }
}
