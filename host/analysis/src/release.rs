//! The checks of a release test (`hostctl experiment release` and the release command of
//! `hostctl ui`): its arguments, and the configuration it runs with.
//!
//! Units: deflection in raw encoder counts from the wall, duration in servo ticks, stiffness K
//! in N/m (N·m/rad for a rotational device). Invariants: a deflection is non-zero and within
//! ±2²⁰ counts, a duration within [100, 10⁷] ticks, a given K finite and > 0; a test never runs
//! with the wall off (K = 0 or NaN). Errors name the flag and its allowed range.

/// Default of `experiment release --ticks` (and of the page's release test), servo ticks.
pub const DEFAULT_RELEASE_TICKS: u32 = 3000;

use stiffwall_client::readable;
use stiffwall_proto::ServoConfig;

/// Largest |deflection| of a release test, counts.
pub const MAX_DEFLECTION: u32 = 1 << 20;

/// Why a release test cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ReleaseError {
    /// `--deflection` zero or too large.
    #[error("--deflection must be non-zero and within [-1048576, 1048576] (got {got})")]
    Deflection {
        /// The value given.
        got: i32,
    },
    /// `--ticks` out of range.
    #[error("--ticks must be within [100, 10000000] (got {got})")]
    Ticks {
        /// The value given.
        got: u32,
    },
    /// `--stiffness` not finite or not positive.
    #[error("--stiffness must be finite and > 0 (got {got})")]
    Stiffness {
        /// The value given.
        got: f64,
    },
    /// The device's wall is off and no stiffness was given.
    #[error(
        "the device's wall is off (K = {k}): give the test's stiffness with --stiffness K \
         (N/m or N·m/rad, > 0 and ≤ {max} for this device at coarsening shift 0); a board \
         keeps one set with `hostctl config set --stiffness K` and `hostctl config save`",
        max = readable(f64::from(*max_stiffness))
    )]
    WallOff {
        /// The device's K.
        k: f32,
        /// The device's largest K at coarsening shift 0.
        max_stiffness: f32,
    },
}

/// Checks a release test's deflection, duration and optional stiffness.
///
/// # Errors
/// The first value out of range, named with its range.
pub fn check_values(
    deflection: i32,
    ticks: u32,
    stiffness: Option<f64>,
) -> Result<(), ReleaseError> {
    if deflection == 0 || deflection.unsigned_abs() > MAX_DEFLECTION {
        return Err(ReleaseError::Deflection { got: deflection });
    }
    if !(100..=10_000_000).contains(&ticks) {
        return Err(ReleaseError::Ticks { got: ticks });
    }
    if let Some(k) = stiffness {
        if !(k.is_finite() && k > 0.0) {
            return Err(ReleaseError::Stiffness { got: k });
        }
    }
    Ok(())
}

/// The configuration a release test runs with: `original` with the test's stiffness, refused
/// when the wall would be off.
///
/// # Errors
/// K is 0 (or NaN) and no stiffness was given.
pub fn config(
    original: &ServoConfig,
    stiffness: Option<f64>,
    max_stiffness: f32,
) -> Result<ServoConfig, ReleaseError> {
    let mut cfg = *original;
    if let Some(k) = stiffness {
        cfg.stiffness = k as f32;
    }
    if cfg.stiffness.is_nan() || cfg.stiffness <= 0.0 {
        return Err(ReleaseError::WallOff {
            k: cfg.stiffness,
            max_stiffness,
        });
    }
    Ok(cfg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_named_and_the_wall_must_be_on() {
        assert!(check_values(100, 3000, None).is_ok());
        assert_eq!(
            check_values(0, 3000, None).unwrap_err().to_string(),
            "--deflection must be non-zero and within [-1048576, 1048576] (got 0)"
        );
        assert!(check_values(-(1 << 20), 100, Some(1.0)).is_ok());
        assert!(check_values(100, 99, None).is_err());
        assert!(check_values(100, 3000, Some(f64::NAN)).is_err());
        let off = ServoConfig {
            stiffness: 0.0,
            ..ServoConfig::default()
        };
        let e = config(&off, None, 5000.0).unwrap_err().to_string();
        assert!(e.starts_with("the device's wall is off (K = 0)"), "{e}");
        assert_eq!(config(&off, Some(200.0), 5000.0).unwrap().stiffness, 200.0);
    }
}
