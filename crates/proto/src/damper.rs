//! The wall's virtual damper law (`ServoConfig::damper`): how the count difference
//! dn = n_h − n_(h−1), in effective counts per tick, becomes the damper's velocity, and its
//! text form (`difference`, `dead-band-N`) for flags, plant files and JSON. No allocation.

use heapless::String;
use serde::{Deserialize, Serialize};

/// Longest law name, bytes (`dead-band-255` is 13).
pub const LAW_NAME_LEN: usize = 16;

/// Largest dead band of [`DamperLaw::DeadBand`], effective counts per tick.
pub const MAX_DEADBAND_COUNTS: u8 = 8;

/// How the wall's virtual damper turns the count difference dn = n_h − n_(h−1) into a velocity.
///
/// dn is in effective counts (after the coarsening shift) per servo tick; the damper's code is
/// −g_B·v (g_B = B·Δ_eff·rate in output codes, see the firmware model notes). Text form
/// ([`core::fmt::Display`], [`core::str::FromStr`]): `difference`, `dead-band-N`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum DamperLaw {
    /// v = dn (the plain backward difference).
    Difference,
    /// v = 0 when |dn| ≤ counts, else v = dn (a dead band of `counts` effective counts per tick).
    DeadBand {
        /// The dead band, effective counts per tick, 1..=[`MAX_DEADBAND_COUNTS`].
        counts: u8,
    },
}

impl Default for DamperLaw {
    /// A dead band of one count: a wall at rest toggling between two neighbouring counts
    /// feels the spring alone, not a damper pulse B·Δ/T at every toggle.
    fn default() -> Self {
        Self::DeadBand { counts: 1 }
    }
}

impl DamperLaw {
    /// The law in a record written before the field existed (protocol 1, config store
    /// `SWC1`, a recording's JSON header without `damper`): the plain backward difference.
    #[must_use]
    pub const fn legacy() -> Self {
        Self::Difference
    }

    /// The dead band in effective counts per tick (0 for [`DamperLaw::Difference`]): the
    /// velocity is 0 when |dn| is at most this.
    #[must_use]
    pub const fn dead_band(self) -> u8 {
        match self {
            Self::Difference => 0,
            Self::DeadBand { counts } => counts,
        }
    }

    /// The law's name: `"difference"` or `"dead-band-N"` (N the counts).
    #[must_use]
    pub fn name(self) -> String<LAW_NAME_LEN> {
        use core::fmt::Write as _;
        let mut s = String::new();
        // At most 13 characters ("dead-band-255"): always fits.
        let _ = write!(s, "{self}");
        s
    }
}

impl core::fmt::Display for DamperLaw {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Difference => f.write_str("difference"),
            Self::DeadBand { counts } => write!(f, "dead-band-{counts}"),
        }
    }
}

/// A [`DamperLaw`] spelled wrong; its `Display` gives the allowed forms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParseDamperLawError {
    /// Neither `difference` nor `dead-band-N` with N a decimal number.
    Unknown,
    /// `dead-band-N` with N outside 1..=[`MAX_DEADBAND_COUNTS`] (saturated at `u32::MAX`).
    DeadBandOutOfRange {
        /// The N given.
        counts: u32,
    },
}

impl core::fmt::Display for ParseDamperLawError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Unknown => write!(
                f,
                "allowed forms are `difference` and `dead-band-N` with N in 1..={MAX_DEADBAND_COUNTS}"
            ),
            Self::DeadBandOutOfRange { counts } => write!(
                f,
                "dead band {counts} counts is outside 1..={MAX_DEADBAND_COUNTS} (use `difference` \
                 for no dead band)"
            ),
        }
    }
}

impl core::error::Error for ParseDamperLawError {}

impl core::str::FromStr for DamperLaw {
    type Err = ParseDamperLawError;

    /// Exactly `difference` or `dead-band-N`, N in decimal without sign or leading zeros,
    /// 1..=[`MAX_DEADBAND_COUNTS`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s == "difference" {
            return Ok(Self::Difference);
        }
        let digits = s
            .strip_prefix("dead-band-")
            .ok_or(ParseDamperLawError::Unknown)?;
        let canonical = !digits.is_empty()
            && digits.bytes().all(|b| b.is_ascii_digit())
            && (digits == "0" || !digits.starts_with('0'));
        if !canonical {
            return Err(ParseDamperLawError::Unknown);
        }
        let counts = digits.bytes().fold(0u32, |n, b| {
            n.saturating_mul(10).saturating_add(u32::from(b - b'0'))
        });
        match u8::try_from(counts) {
            Ok(c) if (1..=MAX_DEADBAND_COUNTS).contains(&c) => Ok(Self::DeadBand { counts: c }),
            _ => Err(ParseDamperLawError::DeadBandOutOfRange { counts }),
        }
    }
}
