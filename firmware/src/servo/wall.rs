//! The wall's force: the spring of eq. (2) in fixed point, the virtual damper and its law, the
//! clamp to the amplifier's codes, and the safe-mode damper.
//!
//! Units: effective counts n, count differences dn (counts per tick), output codes. Invariants:
//! every function here is pure on the servo's gains (no state changes), saturating (a count far
//! outside the wall gives the clamped force, never a wrapped one), and panic-free.

use super::Servo;
use crate::config::DAMPER_V_MAX;
use crate::numeric::Numeric;
use stiffwall_proto::flags;

impl<N: Numeric> Servo<'_, N> {
    /// The spring of eq. (2) for effective count `n` before the output clamp:
    /// `round(−(2n+1)·k_half)` for |n| ≤ `n_sat`; beyond, the code at ±`n_sat` (precomputed),
    /// where the force already exceeds the limit, so the clamped output is exact for every n.
    /// 0 outside a one-sided wall (folded into the lower bound: n ≤ −1 gives 0).
    #[inline]
    #[must_use]
    pub fn spring_code(&self, n: i32) -> i32 {
        // `spring_between(n, wall_n_lo, wall_lo)` with its two bound tests as one: `wall_n_lo`
        // < n < `n_sat` exactly when n − `wall_in` (as u32, wrapping) < `wall_span` (the
        // difference is below 2^31 + 2^29 in magnitude: a negative one wraps above 2^31 and
        // `wall_span` ≤ 2^30).
        if (n as u32).wrapping_sub(self.g.wall_in as u32) < self.g.wall_span {
            N::spring(self.g.spring, n)
        } else if n >= self.g.n_sat {
            self.g.spring_hi
        } else {
            self.g.wall_lo
        }
    }

    /// The two-sided spring (release-test hold).
    #[inline]
    pub(super) fn spring_raw(&self, n: i32) -> i32 {
        self.spring_between(
            n,
            self.g.n_sat.wrapping_neg().wrapping_sub(1),
            self.g.spring_lo,
        )
    }

    /// `code(n)` for `n_lo` < n < `n_sat`; `spring_hi` at or above `n_sat`, `lo` at or below
    /// `n_lo` (same as clamping n to [`n_lo`, `n_sat`] first).
    #[inline(always)]
    pub(super) fn spring_between(&self, n: i32, n_lo: i32, lo: i32) -> i32 {
        if n >= self.g.n_sat {
            self.g.spring_hi
        } else if n <= n_lo {
            lo
        } else {
            // |n| < n_sat ≤ 2^29: |(2n+1)·k_half| ≤ limit + damper max + 3·k_half < 2^29
            // codes (limit ≤ 2^24, damper ≤ 2^28, k_half ≤ 2^14).
            N::spring(self.g.spring, n)
        }
    }

    /// The output clamp to ±`limit`, with the [`flags::CLAMPED`] flag when it acts.
    #[inline]
    pub(super) fn clamp(&self, code: i32) -> (i32, u16) {
        let mut fl = 0;
        let c = self.clamp_into(code, &mut fl);
        (c, fl)
    }

    /// The output clamp to ±`limit`, or-ing the [`flags::CLAMPED`] flag into `fl` when it acts
    /// (so that a tick's flags gather in one place on the path that sets them).
    #[inline(always)]
    pub(super) fn clamp_into(&self, code: i32, fl: &mut u16) -> i32 {
        let l = self.g.limit;
        // 0 ≤ limit ≤ 2^24: |code| > limit as one unsigned compare (as `AbsBound`).
        if (code as u32).wrapping_add(l as u32) > (2 * l) as u32 {
            *fl |= flags::CLAMPED;
            Self::clamped(code, l)
        } else {
            code
        }
    }

    /// `code` beyond ±`l`: the bound it passed.
    #[cold]
    #[inline(never)]
    pub(super) fn clamped(code: i32, l: i32) -> i32 {
        if code > l {
            l
        } else {
            -l
        }
    }

    /// [`Mode::Wall`]'s code and flags.
    #[inline(always)]
    pub(super) fn wall_force(&self, n: i32, dn: i32, free: bool) -> (i32, u16) {
        let mut fl = 0;
        let c = self.wall_force_into(n, dn, free, &mut fl);
        (c, fl)
    }

    /// [`Mode::Wall`]'s code, its flags or-ed into `fl`.
    #[inline(always)]
    pub(super) fn wall_force_into(&self, n: i32, dn: i32, free: bool, fl: &mut u16) -> i32 {
        // Inside the spring's linear range (`spring_code`'s first test), which lies in contact
        // (`wall_in` ≥ `contact_n`), one test gives the law; the rest (outside a one-sided
        // wall, or the spring saturated) out of line.
        if (n as u32).wrapping_sub(self.g.wall_in as u32) < self.g.wall_span {
            N::spring(self.g.spring, n).saturating_add(self.damping(dn))
        } else {
            let (c, f) = self.wall_force_beyond(n, dn, free);
            *fl |= f;
            c
        }
    }

    /// [`Self::wall_force`] outside the spring's linear range: no force and the wall-off flag
    /// outside a one-sided wall (`free`: n < `contact_n`; one test serves both), else the law
    /// with the spring at its bound.
    #[cold]
    #[inline(never)]
    pub(super) fn wall_force_beyond(&self, n: i32, dn: i32, free: bool) -> (i32, u16) {
        if free {
            (0, flags::WALL_OFF)
        } else {
            (self.contact_code(n, dn), 0)
        }
    }

    /// The wall law before the delay line and the output clamp:
    /// `code = spring_code(n) − g_B·v` (saturating), with g_B = B·Δ_eff·rate/fs
    /// ([`Gains::damp`]) and v the velocity the config's [`stiffwall_proto::DamperLaw`] makes
    /// of dn = n_h − n_(h−1), the backward difference of the effective count: v = dn
    /// (`Difference`), or v = 0 when |dn| ≤ c and v = dn otherwise (`DeadBand { counts: c }`).
    /// On a one-sided wall the whole law, damper included, acts only in contact (n ≥ 0): in
    /// free space (n < 0) the code is 0, so moving the device around outside the wall feels no
    /// drag.
    #[inline(always)]
    pub(crate) fn wall_code(&self, n: i32, dn: i32) -> i32 {
        if n < self.g.contact_n {
            0
        } else {
            self.contact_code(n, dn)
        }
    }

    /// Spring + damper in contact (no one-sided test): `spring_code(n) − g_B·v`, saturating.
    #[inline(always)]
    pub(super) fn contact_code(&self, n: i32, dn: i32) -> i32 {
        self.spring_code(n).saturating_add(self.damping(dn))
    }

    /// The virtual damping term −g_B·v of the wall law, v by the config's damper law.
    #[inline(always)]
    pub(super) fn damping(&self, dn: i32) -> i32 {
        // One test for "a damper is on and |dn| is beyond its dead band" (`Gains::damper_band`;
        // elsewhere v = 0 or g_B = 0, and the term is exactly 0).
        if self.g.damper_band.exceeded(dn) {
            // `damper(damp, dn)` with the gain's precomputed form; the velocity clamp, which
            // acts only beyond any encoder-jump limit a device would set, out of line.
            let v = if self.g.damper_v.exceeded(dn) {
                Self::clamp_velocity(dn)
            } else {
                dn
            };
            N::damper(self.g.damp_s, v)
        } else {
            0
        }
    }

    /// `v` clamped to ±[`DAMPER_V_MAX`].
    #[cold]
    #[inline(never)]
    pub(super) fn clamp_velocity(v: i32) -> i32 {
        v.clamp(-DAMPER_V_MAX, DAMPER_V_MAX)
    }

    /// `−g·v` for a damping gain g ≤ 2^16 codes per count per tick, with v clamped to
    /// ±2^14 counts per tick so the product stays below 2^30 codes (bounded multiply).
    #[inline]
    pub(super) fn damper(&self, g: N::Gain, v: i32) -> i32 {
        N::mul_bounded(g, v.clamp(-DAMPER_V_MAX, DAMPER_V_MAX).wrapping_neg())
    }

    /// Safe-mode output: zero or the safe damping on the raw count delta.
    #[inline]
    pub(super) fn safe_code(&self, d: i32) -> i32 {
        if self.g.safe_damping {
            self.damper(self.g.safe_damp, d)
        } else {
            0
        }
    }
}
