//! A release test's trace as the page gets it: decimated to at most [`TRACE_POINTS`] points,
//! keeping each bucket's minimum and maximum (in time order), so a one-tick spike stays visible
//! however long the test; the `release` message that carries it is therefore bounded
//! (under 100 kB for any `--ticks`), and so is what the server keeps for pages that open later.
//! The full trace, every sample, is in a recording started from the page (the lossless CSV of
//! `hostctl record`).
//!
//! Units: counts in effective encoder ticks (as `tune::release::released_counts`), indices in
//! servo ticks after the release.

use serde::Serialize;

/// Most points of a trace sent to the page.
pub const TRACE_POINTS: usize = 4000;

/// A trace for the page: `counts[i]` is the count `index[i]` ticks after the release; every
/// count when there are at most [`TRACE_POINTS`], else each bucket's minimum and maximum.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Trace {
    /// Released samples in the test (the length of the full trace).
    pub samples: usize,
    /// Tick after the release of each point, increasing.
    pub index: Vec<u32>,
    /// Count of each point.
    pub counts: Vec<i64>,
}

/// Decimates `counts` to at most `max_points` (≥ 2) points: the whole trace if it fits, else
/// `max_points / 2` equal buckets, each giving its minimum and maximum in time order (one point
/// when they are the same sample).
#[must_use]
pub fn decimate(counts: &[i64], max_points: usize) -> Trace {
    let n = counts.len();
    let mut t = Trace {
        samples: n,
        index: Vec::with_capacity(n.min(max_points)),
        counts: Vec::with_capacity(n.min(max_points)),
    };
    let mut push = |i: usize| {
        t.index.push(u32::try_from(i).unwrap_or(u32::MAX));
        t.counts.push(counts[i]);
    };
    if n <= max_points {
        (0..n).for_each(&mut push);
        return t;
    }
    let buckets = (max_points / 2).max(1);
    for b in 0..buckets {
        let (lo, hi) = (b * n / buckets, (b + 1) * n / buckets);
        let slice = &counts[lo..hi];
        let (mut imin, mut imax) = (0, 0);
        for (i, &x) in slice.iter().enumerate() {
            if x < slice[imin] {
                imin = i;
            }
            if x > slice[imax] {
                imax = i;
            }
        }
        let (first, second) = (imin.min(imax), imin.max(imax));
        push(lo + first);
        if second != first {
            push(lo + second);
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_traces_are_sent_whole() {
        let c: Vec<i64> = (0..100).map(|i| i % 7).collect();
        let t = decimate(&c, TRACE_POINTS);
        assert_eq!(t.counts, c);
        assert_eq!(t.index, (0..100).collect::<Vec<u32>>());
        assert_eq!(t.samples, 100);
    }

    #[test]
    fn a_million_ticks_keep_their_spikes_within_the_bound() {
        let n = 1_000_000;
        let mut c: Vec<i64> = (0..n).map(|i| [0, 1, 0, -1][i % 4]).collect();
        c[123_457] = 40;
        c[876_543] = -25;
        let t = decimate(&c, TRACE_POINTS);
        assert!(t.counts.len() <= TRACE_POINTS, "{}", t.counts.len());
        assert_eq!(t.samples, n);
        assert_eq!(t.counts.iter().max(), Some(&40));
        assert_eq!(t.counts.iter().min(), Some(&-25));
        let at = |i: u32| t.index.iter().position(|&x| x == i).map(|k| t.counts[k]);
        assert_eq!(at(123_457), Some(40));
        assert_eq!(at(876_543), Some(-25));
        assert!(t.index.windows(2).all(|w| w[0] < w[1]));
        // Every bucket keeps its range: ±1 appear throughout.
        assert!(t.counts.iter().filter(|&&x| x == 1).count() >= TRACE_POINTS / 2 - 2);
        let bytes = serde_json::to_string(&t).unwrap().len();
        assert!(bytes < 64 << 10, "{bytes} bytes");
    }
}
