//! One compiled profile element and its code: where it acts, its spring (walls and springs, in
//! the config wall's exact fixed point and saturation), its detent sine, and its damper with
//! the damper law.
//!
//! Units: the anchor and a viscous zone's bounds are raw counts; n (the element's effective
//! count, ⌊(count − anchor)/2^shift⌋, saturating) and dn (its backward difference) are
//! effective counts; codes are output codes. Invariants: [`Element::code`] is pure, saturating
//! and panic-free for every `i32` n and dn; for a `Wall`/`Spring` it is exactly the config
//! wall's law (`Servo::wall_code`): `spring_code(n) − g_B·v`, its spring clamped at the count
//! n_sat beyond which the force already exceeds the limit (its code at ±n_sat used beyond, as
//! if n were clamped), v clamped to ±[`DAMPER_V_MAX`].

use super::detent::Detent;
use crate::numeric::{AbsBound, Numeric, RangeBound, Shift, DAMPER_V_MAX};

/// What an element's own code is, besides the damper.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Law<N: Numeric> {
    /// Eq. (2): `round(−(2n+1)·k_half)` for −n_sat−1 < n < n_sat, `hi` at or above n_sat, `lo`
    /// at or below −n_sat−1 (a wall is a spring that acts on one side: its `active` range).
    Spring {
        /// `k_half` in [`Numeric::spring`]'s form.
        spring: N::Spring,
        /// The count clamp n_sat.
        n_sat: i32,
        /// The code at n_sat.
        hi: i32,
        /// The code at −n_sat−1.
        lo: i32,
    },
    /// A train of sinusoidal detents.
    Detents(Detent),
    /// No force but the damper's (a viscous zone).
    Damper,
}

/// One element of a [`super::ProfileTable`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Element<N: Numeric> {
    /// The count the effective count is measured from, raw counts.
    pub(crate) anchor: i32,
    /// The coarsening shift (the config's).
    pub(crate) shift: Shift,
    /// Where the element acts: on its effective count n, or (`on_raw`) on the raw count.
    pub(crate) active: RangeBound,
    /// `active` is tested on the raw count (a viscous zone), not on n.
    pub(crate) on_raw: bool,
    /// The element's own law.
    pub(crate) law: Law<N>,
    /// The damper gain in [`Numeric::damper`]'s form.
    pub(crate) damp: N::Spring,
    /// |dn| beyond the law's dead band (never without a damper), as `Gains::damper_band`.
    pub(crate) band: AbsBound,
}

impl<N: Numeric> Element<N> {
    /// The element's code at raw count `pos`, the previous tick's raw count being `prev`.
    #[inline]
    #[must_use]
    pub fn code_at(&self, pos: i32, prev: i32) -> i32 {
        let s = self.shift.get();
        let n = pos.saturating_sub(self.anchor) >> s;
        let before = prev.saturating_sub(self.anchor) >> s;
        self.code(n, n.saturating_sub(before), pos)
    }

    /// The element's code at effective count `n` moved by `dn` since the last tick (`pos`: the
    /// raw count, which a viscous zone's bounds are tested on).
    #[inline]
    #[must_use]
    pub fn code(&self, n: i32, dn: i32, pos: i32) -> i32 {
        let at = if self.on_raw { pos } else { n };
        if self.active.outside(at) {
            return 0;
        }
        let own = match &self.law {
            Law::Spring {
                spring,
                n_sat,
                hi,
                lo,
            } => {
                if n >= *n_sat {
                    *hi
                } else if n <= n_sat.wrapping_neg().wrapping_sub(1) {
                    *lo
                } else {
                    // |n| < n_sat ≤ 2^29: in range (as the config wall's `spring_between`).
                    N::spring(*spring, n)
                }
            }
            Law::Detents(d) => d.code(n),
            Law::Damper => 0,
        };
        own.saturating_add(self.damping(dn))
    }

    /// −g_B·v, v by the element's damper law (the config wall's `Servo::damping`).
    #[inline]
    fn damping(&self, dn: i32) -> i32 {
        if self.band.exceeded(dn) {
            N::damper(self.damp, dn.clamp(-DAMPER_V_MAX, DAMPER_V_MAX))
        } else {
            0
        }
    }
}
