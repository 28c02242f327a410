//! Profile validation: [`validate`] range-checks every element of a wire [`Profile`] against
//! the active config (its coarsening shift and rate) and the board, so that [`super::compile`]
//! derives gains that fit their fixed-point formats and no product overflows.
//!
//! Units: as the profile's (raw counts, N/m, N·s/m, N; see `stiffwall_proto::profile`).
//! Invariant: a refused profile reports the first offending element (0-based) and field, in
//! the order of the element's fields, with its allowed inclusive `[min, max]`; nothing is
//! changed. The ranges of K and B are the config's (`crate::validate`) at the same shift and
//! rate; a detent train's pitch is at least 2 effective counts (so the sine's phase step is at
//! most a quarter turn per half count) and its extent, from half a pitch before `first` to
//! half a pitch after its last minimum, lies within the `i32` counts, its length below 2^31
//! counts; a viscous zone is not empty.

use crate::config::limits::{
    MAX_DEADBAND_COUNTS, MAX_LIMIT_CODES, MIN_DAMPING, MIN_DEADBAND_COUNTS, MIN_STIFFNESS,
};
use crate::config::BoardInfo;
use stiffwall_proto::profile::{Profile, ProfileElement, ProfileField, MAX_DETENTS};
use stiffwall_proto::{DamperLaw, ServoConfig};

/// A refused profile: the element, its field and the field's allowed range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileError {
    /// The element's index in the profile (0-based).
    pub element: u8,
    /// The offending field.
    pub field: ProfileField,
    /// Smallest allowed value.
    pub min: f64,
    /// Largest allowed value.
    pub max: f64,
}

impl core::fmt::Display for ProfileError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "element {}: {} must be within [{}, {}]",
            self.element, self.field, self.min, self.max
        )
    }
}

impl core::error::Error for ProfileError {}

/// An element's index as the `u8` of `stiffwall_proto::ErrorDetail::ProfileField` (at most
/// `MAX_PROFILE_ELEMENTS`).
fn element_index(i: usize) -> u8 {
    u8::try_from(i).unwrap_or(u8::MAX)
}

/// A field out of range: `(field, min, max)`.
type Refusal = (ProfileField, f64, f64);

fn check_f(field: ProfileField, v: f64, min: f64, max: f64) -> Result<(), Refusal> {
    if v.is_finite() && v >= min && v <= max {
        Ok(())
    } else {
        Err((field, min, max))
    }
}

/// The largest detent strength: the board's largest code (within [`MAX_LIMIT_CODES`]), N.
fn max_strength(board: &BoardInfo) -> f64 {
    f64::from(board.max_code.clamp(0, MAX_LIMIT_CODES)) * f64::from(board.force_per_code)
}

/// Range-checks every element of `p` for the config `cfg` on `board`, in order.
///
/// # Errors
/// The first element and field out of range, with its range.
pub fn validate(p: &Profile, cfg: &ServoConfig, board: &BoardInfo) -> Result<(), ProfileError> {
    for (i, e) in p.elements.iter().enumerate() {
        check_element(e, cfg, board).map_err(|(field, min, max)| ProfileError {
            element: element_index(i),
            field,
            min,
            max,
        })?;
    }
    Ok(())
}

/// One element's fields, in declaration order.
fn check_element(e: &ProfileElement, cfg: &ServoConfig, board: &BoardInfo) -> Result<(), Refusal> {
    let s = cfg.coarsen_shift;
    let kmax = f64::from(board.max_stiffness(s));
    let bmax = f64::from(board.max_damping(s, cfg.servo_rate_hz));
    let (kmin, bmin) = (f64::from(MIN_STIFFNESS), f64::from(MIN_DAMPING));
    match *e {
        ProfileElement::Wall {
            stiffness,
            damping,
            damper,
            ..
        }
        | ProfileElement::Spring {
            stiffness,
            damping,
            damper,
            ..
        } => {
            check_f(ProfileField::Stiffness, stiffness.into(), kmin, kmax)?;
            check_f(ProfileField::Damping, damping.into(), bmin, bmax)?;
            check_law(damper)
        }
        ProfileElement::Detents {
            first,
            pitch_counts,
            count,
            strength,
            damping,
            damper,
        } => {
            check_train(first, pitch_counts, count, cfg.coarsen_shift)?;
            check_f(
                ProfileField::Strength,
                strength.into(),
                0.0,
                max_strength(board),
            )?;
            check_f(ProfileField::Damping, damping.into(), bmin, bmax)?;
            check_law(damper)
        }
        ProfileElement::Viscous {
            from,
            to,
            damping,
            damper,
        } => {
            if to <= from {
                return Err((ProfileField::To, f64::from(from) + 1.0, f64::from(i32::MAX)));
            }
            check_f(ProfileField::Damping, damping.into(), bmin, bmax)?;
            check_law(damper)
        }
    }
}

/// A detent train's pitch and count: the pitch at least 2 effective counts and at most what
/// keeps the train's extent [first − pitch/2, first + (count − ½)·pitch] within the `i32`
/// counts and its length below 2^31 counts; the count 1..=[`MAX_DETENTS`] (checked first: the
/// pitch's range depends on it).
fn check_train(first: i32, pitch: f64, count: u16, shift: u8) -> Result<(), Refusal> {
    if count == 0 || count > MAX_DETENTS {
        return Err((ProfileField::Count, 1.0, f64::from(MAX_DETENTS)));
    }
    let (lo, hi) = pitch_range(first, count, shift);
    check_f(ProfileField::PitchCounts, pitch, lo, hi)
}

/// The allowed pitch of a train of `count` detents from `first` at coarsening `shift`, counts.
pub(crate) fn pitch_range(first: i32, count: u16, shift: u8) -> (f64, f64) {
    let de = f64::from(1u32 << u32::from(shift.min(31)));
    let min = 2.0 * de;
    let first = f64::from(first);
    // Half a pitch below `first`, (count − ½) pitches above it, the whole below 2^31 counts
    // (one effective count of margin each way for the rounding of the count bounds).
    let span = f64::from(count) - 0.5;
    let below = 2.0 * (first - f64::from(i32::MIN) - de);
    let above = (f64::from(i32::MAX) - first - de) / span;
    let length = (f64::from(i32::MAX) - 2.0 * de) / f64::from(count);
    let max = below.min(above).min(length);
    (min, max)
}

/// The dead band of a dead-band damper law (the plain difference has none to check).
fn check_law(law: DamperLaw) -> Result<(), Refusal> {
    if let DamperLaw::DeadBand { counts } = law {
        if !(MIN_DEADBAND_COUNTS..=MAX_DEADBAND_COUNTS).contains(&counts) {
            return Err((
                ProfileField::Damper,
                f64::from(MIN_DEADBAND_COUNTS),
                f64::from(MAX_DEADBAND_COUNTS),
            ));
        }
    }
    Ok(())
}
