//! K*(B) lowered where the plant keeps a small swing: a damped wall whose damper has a dead band
//! (`dead-band-1`, the default) is the spring alone while the count changes by at most one per
//! tick, and can keep a swing of about ±1.5 counts from a small, slow state near its origin that
//! none of the criterion's trials ([`crate::kstar`]) starts from. `hostctl tune` screens its
//! wall for them on its identified model (`stiffwall_tune::small_swing`); here the same states
//! run on the plant itself, so the truth a tune is held to is the largest K at which neither a
//! trial nor a small state keeps moving (docs/TUNE.md, "Small swings").
//!
//! Units: counts from the wall's origin (signed, fractional) and counts per servo tick for the
//! states; SI (or rotary) K. Deterministic; parallel over the states (rayon).

use crate::kstar::{run_trial, KStar, Rig, SampledPlant, Trial, TrialKind};

/// Ratio between the stiffnesses [`lowered_where_swinging`] tries (K*'s confirmation step).
pub const SMALL_SWING_STEP: f64 = 1.05;

/// The states `starts` (position from the wall's origin, counts; velocity, counts per servo
/// tick) as trials at every wall offset of `rig` (tune's small-swing states:
/// `stiffwall_tune::small_swing::small_starts`).
#[must_use]
pub fn moving_trials(rig: &Rig, starts: &[(f64, f64)]) -> Vec<Trial> {
    let per_tick = rig.resolution_m / rig.period_s;
    rig.wall_offsets
        .iter()
        .flat_map(|&wall| {
            starts.iter().map(move |&(x, v)| Trial {
                wall,
                side: 1,
                kind: TrialKind::Moving {
                    position_counts: x,
                    velocity_m_per_s: v * per_tick,
                },
            })
        })
        .collect()
}

/// `k`, a damped wall's K*(B) by the criterion's trials, lowered where the plant keeps a small
/// swing: `trials` run on the plant at K from K*/1.05³ upwards in steps of
/// [`SMALL_SWING_STEP`]; the first K at which one does not come to rest is the failure, and K*
/// the first K below it, by the same steps, that keeps none (down to K*/10).
#[must_use]
pub fn lowered_where_swinging<P: SampledPlant + Clone + Sync>(
    proto: &P,
    rig: &Rig,
    k: KStar,
    trials: &[Trial],
) -> KStar {
    use rayon::prelude::*;
    let swing = |at: f64| {
        trials
            .par_iter()
            .find_first(|t| !run_trial(proto, rig, at, **t).rests())
            .copied()
    };
    let mut evaluations = k.evaluations;
    let mut at = k.k_star / (SMALL_SWING_STEP * SMALL_SWING_STEP * SMALL_SWING_STEP);
    loop {
        let top = at >= k.k_star;
        let kk = at.min(k.k_star);
        evaluations += 1;
        if let Some(failing) = swing(kk) {
            let mut below = kk / SMALL_SWING_STEP;
            while below > k.k_star / 10.0 && swing(below).is_some() {
                evaluations += 1;
                below /= SMALL_SWING_STEP;
            }
            return KStar {
                k_star: below,
                k_fail: kk,
                failing,
                evaluations,
            };
        }
        if top {
            return KStar { evaluations, ..k };
        }
        at *= SMALL_SWING_STEP;
    }
}
