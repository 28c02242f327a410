//! A haptic profile on the wire: up to [`MAX_PROFILE_ELEMENTS`] elements on the device's axis
//! (walls, springs, detent trains, viscous zones) whose forces add, rendered by the servo in
//! place of the config's single wall (`HostMsg::SetProfile`, protocol 5).
//!
//! Units: positions are raw encoder counts (the frame of `ServoConfig::wall_position`); the
//! servo evaluates every element on the *effective* count (Δ_eff = 2^`coarsen_shift` counts),
//! so an element's force is a function of ⌊(count − anchor)/2^shift⌋ like eq. (2)'s. Stiffness
//! N/m (N·m/rad), damping N·s/m (N·m·s/rad), detent strength N (N·m), as `ServoConfig`'s.
//!
//! The force of each element, n its effective count relative to its anchor, Δ = Δ_eff, dn the
//! backward difference of the effective count, T the servo period, v = law(dn)/T:
//! - [`ProfileElement::Wall`], side `Upper` (the wall occupies counts ≥ `position`): for n ≥ 0,
//!   F = −K·Δ·(n + ½) − B·Δ·v (eq. (2) and the wall's damper, as the config's one-sided wall);
//!   0 for n < 0. Side `Lower` (the wall occupies counts < `position`): for n ≤ −1,
//!   F = −K·Δ·(n + ½) − B·Δ·v (pushing up); 0 for n ≥ 0.
//! - [`ProfileElement::Spring`]: F = −K·Δ·(n + ½) − B·Δ·v for every n (eq. (2), two-sided).
//! - [`ProfileElement::Detents`]: `count` minima at `first + j·pitch_counts` (j = 0..count);
//!   with d = (n + ½)·Δ_eff counts from `first` (the centre of the effective count), inside
//!   d ∈ [−pitch/2, (count − ½)·pitch): F = −A·sin(2π·d/pitch) − B·Δ·v; 0 outside (the force is
//!   0 at both ends, so the train joins free space without a step). Its steepest slope, at a
//!   minimum, is the local stiffness K = 2π·A/(pitch·Δ).
//! - [`ProfileElement::Viscous`]: for `from` ≤ count < `to`: F = −B·Δ·v; 0 outside.
//!
//! The servo sums the elements' codes saturating, then delays and clamps the sum to the force
//! limit as the wall's. Invariant: a profile that passed the firmware's validation (count ≤
//! [`MAX_PROFILE_ELEMENTS`], every number finite and in its field's range) renders without
//! overflow, allocation or panic.

use heapless::Vec;
use serde::{Deserialize, Serialize};

use crate::damper::DamperLaw;

/// Most elements in a profile (the servo's table size).
pub const MAX_PROFILE_ELEMENTS: usize = 16;

/// Most minima in one detent train.
pub const MAX_DETENTS: u16 = 4096;

/// Which side of its position a one-sided wall occupies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Side {
    /// The wall occupies counts below `position` and pushes toward higher counts.
    Lower,
    /// The wall occupies counts at or above `position` and pushes toward lower counts.
    Upper,
}

/// One element of a [`Profile`] (see the module header for each force law).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum ProfileElement {
    /// A one-sided wall of eq. (2).
    Wall {
        /// The wall's surface, raw counts.
        position: i32,
        /// Which side it occupies.
        side: Side,
        /// K, N/m (N·m/rad), ≥ 0.
        stiffness: f32,
        /// B, N·s/m (N·m·s/rad), ≥ 0.
        damping: f32,
        /// The damper's law.
        damper: DamperLaw,
    },
    /// A two-sided spring of eq. (2) (a centring spring).
    Spring {
        /// The spring's origin, raw counts.
        center: i32,
        /// K, N/m (N·m/rad), ≥ 0.
        stiffness: f32,
        /// B, N·s/m (N·m·s/rad), ≥ 0.
        damping: f32,
        /// The damper's law.
        damper: DamperLaw,
    },
    /// A train of `count` sinusoidal detents.
    Detents {
        /// The first minimum, raw counts.
        first: i32,
        /// Minimum to minimum, raw counts (not necessarily whole), > 0.
        pitch_counts: f64,
        /// How many minima, 1..=[`MAX_DETENTS`].
        count: u16,
        /// Peak force A, N (N·m), ≥ 0.
        strength: f32,
        /// B inside the train, N·s/m (N·m·s/rad), ≥ 0.
        damping: f32,
        /// The damper's law.
        damper: DamperLaw,
    },
    /// A viscous zone.
    Viscous {
        /// First count inside, raw counts.
        from: i32,
        /// First count past the zone, raw counts (> `from`).
        to: i32,
        /// B, N·s/m (N·m·s/rad), ≥ 0.
        damping: f32,
        /// The damper's law.
        damper: DamperLaw,
    },
}

impl ProfileElement {
    /// The element's kind, as the profile file spells it.
    #[must_use]
    pub fn kind_name(&self) -> &'static str {
        match self {
            Self::Wall { .. } => "wall",
            Self::Spring { .. } => "spring",
            Self::Detents { .. } => "detents",
            Self::Viscous { .. } => "viscous",
        }
    }
}

/// A profile: the elements the servo renders, summed. An empty profile renders the config's
/// own wall (`ServoConfig::stiffness` …), as before protocol 5.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Profile {
    /// The elements, at most [`MAX_PROFILE_ELEMENTS`].
    pub elements: Vec<ProfileElement, MAX_PROFILE_ELEMENTS>,
}

/// Fields of a [`ProfileElement`] (for error details).
#[allow(missing_docs)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ProfileField {
    Position,
    Stiffness,
    Damping,
    Damper,
    Center,
    First,
    PitchCounts,
    Count,
    Strength,
    From,
    To,
}

impl ProfileField {
    /// The field's name in [`ProfileElement`].
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Position => "position",
            Self::Stiffness => "stiffness",
            Self::Damping => "damping",
            Self::Damper => "damper",
            Self::Center => "center",
            Self::First => "first",
            Self::PitchCounts => "pitch_counts",
            Self::Count => "count",
            Self::Strength => "strength",
            Self::From => "from",
            Self::To => "to",
        }
    }
}

impl core::fmt::Display for ProfileField {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wall element's postcard bytes, written out by hand (enum: variant index varint;
    /// i32: zigzag varint; f32: 4 bytes LE).
    #[test]
    fn wall_element_literal_bytes() {
        let e = ProfileElement::Wall {
            position: -3,
            side: Side::Upper,
            stiffness: 1.0,
            damping: 0.0,
            damper: DamperLaw::DeadBand { counts: 1 },
        };
        #[rustfmt::skip]
        let want = [
            0x00,                   // Wall (variant 0)
            0x05,                   // position −3: zigzag 5
            0x01,                   // side: Upper (variant 1)
            0x00, 0x00, 0x80, 0x3f, // stiffness 1.0
            0x00, 0x00, 0x00, 0x00, // damping 0.0
            0x01, 0x01,             // damper: DeadBand, counts 1
        ];
        let mut buf = [0u8; 32];
        assert_eq!(postcard::to_slice(&e, &mut buf).unwrap(), &want[..]);
    }
}
