//! The compiled profile the servo renders ([`ProfileTable`]): its elements and the per-tick
//! sum of their codes.
//!
//! Units: raw counts in, output codes out (before the delay line and the output clamp).
//! Invariant: at most [`MAX_PROFILE_ELEMENTS`] elements; the sum saturates; no allocation or
//! panic.

use super::element::Element;
use crate::numeric::{Fx64, Numeric};
use stiffwall_proto::profile::MAX_PROFILE_ELEMENTS;

/// A compiled profile: the elements' gains, in the servo's back-end `N`. Empty: the config's
/// wall renders.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileTable<N: Numeric = Fx64> {
    pub(super) elements: heapless::Vec<Element<N>, MAX_PROFILE_ELEMENTS>,
}

impl<N: Numeric> Default for ProfileTable<N> {
    fn default() -> Self {
        Self::empty()
    }
}

impl<N: Numeric> ProfileTable<N> {
    /// The empty table (the config's wall).
    #[must_use]
    pub const fn empty() -> Self {
        Self {
            elements: heapless::Vec::new(),
        }
    }

    /// Makes this table `other`'s, copying only `other`'s elements (a table is up to 16
    /// elements long; the servo takes a profile in one tick).
    pub fn copy_from(&mut self, other: &Self) {
        self.elements.clear();
        // Cannot fail: both hold at most `MAX_PROFILE_ELEMENTS`.
        let _ = self.elements.extend_from_slice(&other.elements);
    }

    /// No element: the servo renders the config's wall.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.elements.is_empty()
    }

    /// The compiled elements, in the profile's order.
    #[must_use]
    pub fn elements(&self) -> &[Element<N>] {
        &self.elements
    }

    /// The profile's code at raw count `pos`, the previous tick's raw count being `prev`
    /// (before the delay line and the output clamp): the saturating sum of the elements'
    /// codes.
    #[inline]
    #[must_use]
    pub fn code(&self, pos: i32, prev: i32) -> i32 {
        let mut sum = 0i32;
        for e in &self.elements {
            sum = sum.saturating_add(e.code_at(pos, prev));
        }
        sum
    }
}
