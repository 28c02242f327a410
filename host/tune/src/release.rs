//! Verdict of a release test (the paper's Fig. 8 experiment): the device is held at a deflection
//! with zero velocity, released, and its encoder counts are recorded.
//!
//! Positions are in effective encoder ticks relative to the wall's origin (the encoder
//! boundary between counts −1 and 0). The verdict (settles / locally stable / chatter within
//! one count / buzz / growing) lives in [`super::verdict`] and is re-exported here: a wall
//! passes when it comes to rest; chatter within one count, a buzz over more counts and growth
//! fail.

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

pub use super::verdict::{classify, Verdict};
