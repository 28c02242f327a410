//! A profile as lowered for one device: the wire elements in file order, each with where it
//! came from in the file ([`Origin`]: its number and kind, and which wall of an `end-stops`
//! element), and [`Lowered::wire`], the profile a device is sent. Plain data; made only by
//! [`lower`](fn@super::lower::lower), whose checks it has passed.
//!
//! Units: positions in raw counts, stiffness N/m (N·m/rad), damping N·s/m (N·m·s/rad),
//! strength N (N·m), as `stiffwall_proto::ProfileElement`'s.

use super::error::Place;
use super::units::Device;
use stiffwall_proto::{Profile, ProfileElement};

/// Where a wire element came from in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Origin {
    /// The element's number in file order, from 1.
    pub index: usize,
    /// Its `kind` as the file spells it.
    pub kind: &'static str,
    /// Which wall of an `end-stops` element (`lower`, `upper`); None otherwise.
    pub part: Option<&'static str>,
}

impl Origin {
    /// The place an error names.
    #[must_use]
    pub fn place(&self) -> Place {
        Place::Element {
            index: self.index,
            kind: match self.part {
                Some(p) => format!("{}, {p} wall", self.kind),
                None => self.kind.to_owned(),
            },
        }
    }
}

/// One wire element and where it came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placed {
    /// Where in the file.
    pub origin: Origin,
    /// The element as the device renders it.
    pub element: ProfileElement,
}

/// A profile checked and lowered for one device.
#[derive(Debug, Clone, PartialEq)]
pub struct Lowered {
    /// `[profile] name`.
    pub name: String,
    /// The device it was lowered for.
    pub device: Device,
    /// The wire elements in file order (at most [`stiffwall_proto::MAX_PROFILE_ELEMENTS`]).
    pub elements: Vec<Placed>,
}

impl Lowered {
    /// The wire profile: what `SetProfile` sends to the device.
    #[must_use]
    pub fn wire(&self) -> Profile {
        let mut p = Profile::default();
        for e in &self.elements {
            // `lower` keeps at most MAX_PROFILE_ELEMENTS, the table's capacity.
            let _ = p.elements.push(e.element);
        }
        p
    }
}
