//! The host-side checks of a servo-configuration change (`hostctl config set`, `stream`,
//! `record` and the `config` command of `hostctl ui`), before anything is sent: a real field
//! finite and > 0 or >= 0, an integer field within its range, a damper law within the
//! firmware's, a travel window whose ends are in order.
//!
//! Units: those of the field (SI: N/m or N·m/rad, N·s/m or N·m·s/rad, N or N·m, m/s or rad/s,
//! J; Hz, ticks, counts, shifts and milliseconds as integers). Invariants: a refusal names the
//! field by its flag (without dashes in [`FlagError`]'s fields), its allowed range and the
//! value; the device validates the rest and a refused config changes nothing.

use stiffwall_proto::{DamperLaw, ParseDamperLawError};

/// A configuration flag outside its allowed range (checked on the host, before sending).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlagError {
    /// A real-valued field.
    #[error("--{flag} must be a finite number {range} (got {value})")]
    Real {
        /// The flag, without dashes.
        flag: &'static str,
        /// The value given.
        value: f32,
        /// The allowed range, `> 0` or `>= 0`.
        range: &'static str,
    },
    /// A damper law outside the firmware's (a dead band out of range).
    #[error("--damper {value}: {reason}")]
    Damper {
        /// The law given.
        value: DamperLaw,
        /// What is wrong with it.
        reason: ParseDamperLawError,
    },
    /// A travel window whose upper end is not above its lower end (both in raw counts).
    #[error(
        "--travel-max must be above --travel-min (got the window [{min}, {max}] raw counts; \
         give `off` for no end on that side)"
    )]
    Travel {
        /// The lower end given (or kept).
        min: i32,
        /// The upper end given (or kept).
        max: i32,
    },
    /// An integer field.
    #[error("--{flag} must be within [{lo}, {hi}] (got {value})")]
    Int {
        /// The flag, without dashes.
        flag: &'static str,
        /// The value given.
        value: i64,
        /// Smallest allowed value.
        lo: i64,
        /// Largest allowed value.
        hi: i64,
    },
}

/// `value` of the real-valued field `flag`: finite and > 0 (`positive`) or >= 0.
///
/// # Errors
/// [`FlagError::Real`], naming the flag, its range and the value.
pub fn real(flag: &'static str, value: f32, positive: bool) -> Result<f32, FlagError> {
    let ok = value.is_finite() && if positive { value > 0.0 } else { value >= 0.0 };
    if ok {
        Ok(value)
    } else {
        Err(FlagError::Real {
            flag,
            value,
            range: if positive { "> 0" } else { ">= 0" },
        })
    }
}

/// `value` of the integer field `flag`, within [`lo`, `hi`] and representable as `T`.
///
/// # Errors
/// [`FlagError::Int`], naming the flag, its range and the value.
pub fn int<T: TryFrom<i64>>(
    flag: &'static str,
    value: i64,
    lo: i64,
    hi: i64,
) -> Result<T, FlagError> {
    let err = FlagError::Int {
        flag,
        value,
        lo,
        hi,
    };
    if value < lo || value > hi {
        return Err(err);
    }
    T::try_from(value).map_err(|_| err)
}

/// The travel window `[min, max]` (raw counts; `None`: no end on that side): with both ends,
/// `max` must be above `min`, as the firmware requires.
///
/// # Errors
/// [`FlagError::Travel`] with both ends.
pub fn travel(min: Option<i32>, max: Option<i32>) -> Result<(), FlagError> {
    match (min, max) {
        (Some(min), Some(max)) if max <= min => Err(FlagError::Travel { min, max }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_named_with_the_value() {
        assert_eq!(real("stiffness", 0.0, false), Ok(0.0));
        assert_eq!(
            real("force-limit", 0.0, true).unwrap_err().to_string(),
            "--force-limit must be a finite number > 0 (got 0)"
        );
        assert!(real("damping", f32::NAN, false).is_err());
        assert_eq!(int::<u8>("energy-growth-cycles", 64, 1, 64), Ok(64));
        assert_eq!(
            int::<u8>("energy-growth-cycles", 65, 1, 64)
                .unwrap_err()
                .to_string(),
            "--energy-growth-cycles must be within [1, 64] (got 65)"
        );
        // In range but not representable: refused, not wrapped.
        assert!(int::<u8>("x", 300, 0, 1000).is_err());
    }

    #[test]
    fn travel_window_ends_in_order() {
        for ok in [
            (None, None),
            (Some(5), None),
            (None, Some(-5)),
            (Some(-5), Some(-4)),
        ] {
            assert_eq!(travel(ok.0, ok.1), Ok(()), "{ok:?}");
        }
        assert_eq!(
            travel(Some(10), Some(10)).unwrap_err().to_string(),
            "--travel-max must be above --travel-min (got the window [10, 10] raw counts; give \
             `off` for no end on that side)"
        );
        assert!(travel(Some(10), Some(-10)).is_err());
    }
}
