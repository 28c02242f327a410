//! Numeric back-ends for the servo's gains.
//!
//! A gain is "output codes per count" (e.g. K·Δ_eff/2 in codes). [`Numeric::mul`] computes
//! `round(gain · m)` for an integer `m`, saturating to `i32` instead of wrapping, rounding to
//! nearest with ties away from zero. [`Numeric::mul_bounded`] is the fast path (damping):
//! `⌊gain · m + ½⌋` for products the caller keeps below 2^30 codes; [`Numeric::spring`] is the
//! same for m = −(2n+1) with the gain precomputed ([`Numeric::spring_gain`]) for the spring.
//!
//! - [`Fx64`] (default): `I32F32` gain (resolution 2^-32 code, range ±2^31 codes), 64-bit
//!   multiply with saturation. Exact integer arithmetic on the gain's bits.
//! - [`Fx32`]: `I16F16` gain (resolution 2^-16 code, range ±2^15 codes), 32-bit multiply, `m`
//!   saturated to `i32` first. Cheaper on a 32-bit core; coarser gain.
//! - [`F32`]: `f32` gain and product (single-precision FPU on the M4F); `m` beyond 2^24 loses
//!   precision. For the instruction-count comparison.
//!
//! Beside them the servo's integer helpers: [`Shift`] (a shift amount 0..=31 the compiler
//! knows the range of), [`AbsBound`] (`|x| > t`) and [`RangeBound`] (x outside [lo, hi]),
//! each one unsigned compare in the tick, exact for every `i32`.

use fixed::types::{I16F16, I32F32};
use stiffwall_proto::ServoConfig;

/// Velocity clamp of the damping terms, effective counts per tick: the damper's code is
/// `−g·clamp(dn, ±DAMPER_V_MAX)`, which keeps gain × velocity below 2^30 codes (g ≤ 2^16).
/// The wall law is exact for |dn| ≤ this (2^14 counts per tick; faster than any encoder jump
/// limit a device would set).
pub const DAMPER_V_MAX: i32 = 1 << 14;

/// A numeric back-end for servo gains.
pub trait Numeric: Copy + core::fmt::Debug + 'static {
    /// The gain representation.
    type Gain: Copy + core::fmt::Debug + PartialEq;
    /// Short name for reports.
    const NAME: &'static str;
    /// The zero gain.
    const ZERO: Self::Gain;
    /// Converts `x` (codes per count) to a gain, saturating; non-finite → 0.
    fn gain(x: f64) -> Self::Gain;
    /// The gain as `f64` (exact for the fixed-point back-ends).
    fn to_f64(g: Self::Gain) -> f64;
    /// `round(g · m)`, saturated to `i32`.
    fn mul(g: Self::Gain, m: i64) -> i32;
    /// `⌊g · m + ½⌋` (round to nearest, ties toward +∞) for a caller that guarantees
    /// `|g · m| < 2^30` codes (the servo clamps the count first). Differs from
    /// [`Numeric::mul`] only at exact ties (negative x.5); cheaper on the target.
    #[inline]
    fn mul_bounded(g: Self::Gain, m: i32) -> i32 {
        Self::mul(g, i64::from(m))
    }
    /// The spring gain `k_half` in the form [`Numeric::spring`] uses (precomputed at config
    /// time).
    type Spring: Copy + core::fmt::Debug + PartialEq;
    /// Precomputes [`Numeric::Spring`] from `k_half`.
    fn spring_gain(k_half: Self::Gain) -> Self::Spring;
    /// The spring of eq. (2) at effective count `n`: `⌊−(2n+1)·k_half + ½⌋`, exactly
    /// `mul_bounded(k_half, −(2n+1))`, for a caller that keeps `|(2n+1)·k_half| < 2^30` codes.
    fn spring(s: Self::Spring, n: i32) -> i32;
    /// The damping gain g in the form [`Numeric::damper`] uses (precomputed at config time).
    fn damper_gain(g: Self::Gain) -> Self::Spring;
    /// The damper at velocity `v`: `⌊−g·v + ½⌋`, exactly `mul_bounded(g, −v)`, for a caller that
    /// keeps `|g·v| < 2^30` codes and |v| ≤ 2^14.
    fn damper(s: Self::Spring, v: i32) -> i32;
}

/// [`Fx64`]'s precomputed spring gain: with g the `I32F32` bits of `k_half`,
/// `−(2n+1)·g + 2^31 = n·h + c` where h = −2g = `hi`·2^32 + `lo` (`lo` signed) and
/// c = 2^31 − g. So `⌊(n·h + c) / 2^32⌋ = n·hi + ⌊(n·lo + c) / 2^32⌋`: one 32×32→64
/// multiply-accumulate (`smlal`) and one 32-bit multiply-add (`mla`), no 64×32 product.
/// The damper's form is the same with h = −g and c = 2^31 (`−g·v + 2^31 = v·h + c`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fx64Spring {
    /// 2^31 − g.
    c: i64,
    /// Low word of −2g, signed.
    lo: i32,
    /// (−2g − lo) / 2^32.
    hi: i32,
}

/// `I32F32` gains, 64-bit arithmetic (default).
#[derive(Debug, Clone, Copy)]
pub struct Fx64;

/// `I16F16` gains, 32-bit arithmetic.
#[derive(Debug, Clone, Copy)]
pub struct Fx32;

/// `f32` gains and arithmetic.
#[derive(Debug, Clone, Copy)]
pub struct F32;

impl Numeric for Fx64 {
    type Gain = I32F32;
    const NAME: &'static str = "I32F32";
    const ZERO: I32F32 = I32F32::ZERO;
    fn gain(x: f64) -> I32F32 {
        // Scaled float-to-integer `as` casts saturate and map NaN to 0, so this conversion has
        // no panic path (`saturating_from_num` keeps one for NaN, which the link-time no-panic
        // proof of the servo rejects). Scaling by 2^32 is exact.
        if x.is_finite() {
            I32F32::from_bits(libm::round(x * 4_294_967_296.0) as i64)
        } else {
            I32F32::ZERO
        }
    }
    fn to_f64(g: I32F32) -> f64 {
        g.to_num::<f64>()
    }
    #[inline]
    fn mul(g: I32F32, m: i64) -> i32 {
        g.saturating_mul_int(m)
            .saturating_round()
            .saturating_to_num::<i32>()
    }
    #[inline]
    fn mul_bounded(g: I32F32, m: i32) -> i32 {
        // In range by contract: a plain 32×64-bit multiply and ⌊x + ½⌋ (add, then drop the
        // fraction: `to_num` rounds toward −∞), no overflow checks needed.
        g.wrapping_mul_int(i64::from(m))
            .wrapping_add(I32F32::from_bits(1 << 31))
            .wrapping_to_num::<i32>()
    }
    type Spring = Fx64Spring;
    fn spring_gain(k_half: I32F32) -> Fx64Spring {
        let g = k_half.to_bits();
        let h = g.wrapping_mul(-2);
        let lo = h as i32;
        Fx64Spring {
            c: (1i64 << 31).wrapping_sub(g),
            lo,
            hi: (h.wrapping_sub(i64::from(lo)) >> 32) as i32,
        }
    }
    #[inline]
    fn spring(s: Fx64Spring, n: i32) -> i32 {
        // |n·lo| ≤ 2^62 and |c| < 2^47: no overflow. The sum is exact modulo 2^32 and in range
        // by contract.
        let low = ((i64::from(n) * i64::from(s.lo)).wrapping_add(s.c) >> 32) as i32;
        n.wrapping_mul(s.hi).wrapping_add(low)
    }
    fn damper_gain(g: I32F32) -> Fx64Spring {
        let h = g.to_bits().wrapping_neg();
        let lo = h as i32;
        Fx64Spring {
            c: 1i64 << 31,
            lo,
            hi: (h.wrapping_sub(i64::from(lo)) >> 32) as i32,
        }
    }
    #[inline]
    fn damper(s: Fx64Spring, v: i32) -> i32 {
        // The spring's evaluation of n·h + c (|v·lo| ≤ 2^45, c = 2^31: no overflow).
        Self::spring(s, v)
    }
}

impl Numeric for Fx32 {
    type Gain = I16F16;
    const NAME: &'static str = "I16F16";
    const ZERO: I16F16 = I16F16::ZERO;
    fn gain(x: f64) -> I16F16 {
        // See `Fx64::gain`: a saturating, panic-free cast of the value scaled by 2^16.
        if x.is_finite() {
            I16F16::from_bits(libm::round(x * 65_536.0) as i32)
        } else {
            I16F16::ZERO
        }
    }
    fn to_f64(g: I16F16) -> f64 {
        g.to_num::<f64>()
    }
    #[inline]
    fn mul(g: I16F16, m: i64) -> i32 {
        let m = m.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
        g.saturating_mul_int(m)
            .saturating_round()
            .saturating_to_num::<i32>()
    }
    type Spring = I16F16;
    fn spring_gain(k_half: I16F16) -> I16F16 {
        k_half
    }
    fn damper_gain(g: I16F16) -> I16F16 {
        g
    }
    #[inline]
    fn damper(g: I16F16, v: i32) -> i32 {
        Self::mul_bounded(g, v.wrapping_neg())
    }
    #[inline]
    fn spring(g: I16F16, n: i32) -> i32 {
        Self::mul_bounded(g, n.wrapping_mul(2).wrapping_add(1).wrapping_neg())
    }
}

impl Numeric for F32 {
    type Gain = f32;
    const NAME: &'static str = "f32";
    const ZERO: f32 = 0.0;
    fn gain(x: f64) -> f32 {
        if x.is_finite() {
            x as f32
        } else {
            0.0
        }
    }
    fn to_f64(g: f32) -> f64 {
        f64::from(g)
    }
    #[inline]
    fn mul(g: f32, m: i64) -> i32 {
        // `as` from float saturates (NaN → 0): no panic, no wrap.
        libm::roundf(g * m as f32) as i32
    }
    #[inline]
    fn mul_bounded(g: f32, m: i32) -> i32 {
        // ⌊y⌋ without a libm call (the M4F has no VRINTM): truncate, then step down for
        // negative non-integers. |y| < 2^30 by contract, so the casts are exact.
        let y = g * m as f32 + 0.5;
        let t = y as i32;
        if (t as f32) > y {
            t - 1
        } else {
            t
        }
    }
    type Spring = f32;
    fn spring_gain(k_half: f32) -> f32 {
        k_half
    }
    fn damper_gain(g: f32) -> f32 {
        g
    }
    #[inline]
    fn damper(g: f32, v: i32) -> i32 {
        Self::mul_bounded(g, v.wrapping_neg())
    }
    #[inline]
    fn spring(g: f32, n: i32) -> i32 {
        Self::mul_bounded(g, n.wrapping_mul(2).wrapping_add(1).wrapping_neg())
    }
}

/// A shift amount 0..=31. Its type tells the compiler the range, so shifting by it needs no
/// `& 31` mask (`wrapping_shl`/`wrapping_shr` by a plain `u32` do).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u8)]
#[allow(missing_docs)]
pub enum Shift {
    #[default]
    S0,
    S1,
    S2,
    S3,
    S4,
    S5,
    S6,
    S7,
    S8,
    S9,
    S10,
    S11,
    S12,
    S13,
    S14,
    S15,
    S16,
    S17,
    S18,
    S19,
    S20,
    S21,
    S22,
    S23,
    S24,
    S25,
    S26,
    S27,
    S28,
    S29,
    S30,
    S31,
}

impl Shift {
    const ALL: [Shift; 32] = [
        Shift::S0,
        Shift::S1,
        Shift::S2,
        Shift::S3,
        Shift::S4,
        Shift::S5,
        Shift::S6,
        Shift::S7,
        Shift::S8,
        Shift::S9,
        Shift::S10,
        Shift::S11,
        Shift::S12,
        Shift::S13,
        Shift::S14,
        Shift::S15,
        Shift::S16,
        Shift::S17,
        Shift::S18,
        Shift::S19,
        Shift::S20,
        Shift::S21,
        Shift::S22,
        Shift::S23,
        Shift::S24,
        Shift::S25,
        Shift::S26,
        Shift::S27,
        Shift::S28,
        Shift::S29,
        Shift::S30,
        Shift::S31,
    ];

    /// The shift `s`, saturated to 31.
    #[must_use]
    pub fn new(s: u32) -> Self {
        *Self::ALL.get(s.min(31) as usize).unwrap_or(&Shift::S31)
    }

    /// The amount.
    #[inline]
    #[must_use]
    pub fn get(self) -> u32 {
        self as u32
    }
}

/// The test `|x| > t` for every `i32` x as one unsigned compare,
/// `(x as u32).wrapping_add(bias) > span`: for t < 2^31, bias = t and span = 2t (x + t lands in
/// 0..=2t exactly when −t ≤ x ≤ t, and wraps above 2t when x < −t); for t ≥ 2^31 no |x|
/// exceeds t, and span = `u32::MAX` is never exceeded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AbsBound {
    bias: u32,
    span: u32,
}

impl AbsBound {
    /// The bound for threshold `t`.
    #[must_use]
    pub const fn new(t: u32) -> Self {
        if t < 1 << 31 {
            Self {
                bias: t,
                span: 2 * t,
            }
        } else {
            Self {
                bias: 0,
                span: u32::MAX,
            }
        }
    }

    /// `|x| > t`.
    #[inline(always)]
    #[must_use]
    pub fn exceeded(self, x: i32) -> bool {
        (x as u32).wrapping_add(self.bias) > self.span
    }
}

/// The test "x outside [lo, hi]" for every `i32` x as one unsigned compare,
/// `(x as u32).wrapping_sub(lo as u32) > span` with span = hi − lo (as `u32`): x − lo, taken
/// modulo 2^32, lies in 0..=span exactly when lo ≤ x ≤ hi, and wraps above span when x < lo.
/// The full `i32` range (lo = `i32::MIN`, span = `u32::MAX`) is never left: a window that is
/// off costs the same one compare.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RangeBound {
    lo: i32,
    span: u32,
}

impl RangeBound {
    /// The window [`lo`, `hi`] (lo ≤ hi; a reversed pair gives the empty-but-for-`lo` window
    /// [lo, lo], never a wrapped one).
    #[must_use]
    pub const fn new(lo: i32, hi: i32) -> Self {
        let hi = if hi < lo { lo } else { hi };
        Self {
            lo,
            span: (hi as u32).wrapping_sub(lo as u32),
        }
    }

    /// The travel window of a config: `travel_min` (`i32::MIN` when `None`) to `travel_max`
    /// (`i32::MAX` when `None`).
    #[must_use]
    pub fn travel(cfg: &ServoConfig) -> Self {
        Self::new(
            cfg.travel_min.unwrap_or(i32::MIN),
            cfg.travel_max.unwrap_or(i32::MAX),
        )
    }

    /// `x` < lo or `x` > hi.
    #[inline(always)]
    #[must_use]
    pub fn outside(self, x: i32) -> bool {
        (x as u32).wrapping_sub(self.lo as u32) > self.span
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn rounding_and_saturation() {
        let g = Fx64::gain(0.25);
        assert_eq!(Fx64::mul(g, 1), 0);
        assert_eq!(Fx64::mul(g, 2), 1); // 0.5 rounds away from zero
        assert_eq!(Fx64::mul(g, -2), -1);
        assert_eq!(Fx64::mul(g, i64::MAX), i32::MAX);
        assert_eq!(Fx64::mul(g, i64::MIN), i32::MIN);
        let g = Fx32::gain(3.0);
        assert_eq!(Fx32::mul(g, 5), 15);
        assert_eq!(Fx32::mul(g, i64::MIN), i16::MIN as i32);
        assert_eq!(F32::mul(3.0, -5), -15);
        assert_eq!(F32::mul(1e30, 1 << 40), i32::MAX);
        assert_eq!(Fx64::gain(f64::NAN), I32F32::ZERO);
        for m in -1000..1000 {
            let g = Fx64::gain(0.3757);
            assert_eq!(Fx64::mul(g, i64::from(m)), Fx64::mul_bounded(g, m));
            let want = (0.3757f32 * m as f32 + 0.5).floor() as i32;
            assert_eq!(F32::mul_bounded(0.3757, m), want);
        }
        for k in [0.0, 0.3757, 1.0, 2.5, 0.5 + 1e-9, 16383.99, 1e-7] {
            let g = Fx64::gain(k);
            let s = Fx64::spring_gain(g);
            for n in (-70_000..70_000).chain([-(1 << 29) - 1, 1 << 29, 12_345_678]) {
                let m = n * 2 + 1;
                if k * f64::from(m).abs() < f64::from(1 << 30) {
                    assert_eq!(Fx64::spring(s, n), Fx64::mul_bounded(g, -m), "k {k} n {n}");
                }
            }
        }
    }

    fn check_damper<N: Numeric>(b: f64) {
        let g = N::gain(b);
        let s = N::damper_gain(g);
        let vmax = DAMPER_V_MAX;
        for v in (-vmax..=vmax).step_by(7).chain([-vmax, -1, 0, 1, vmax]) {
            if b * f64::from(v).abs() < f64::from(1 << 30) {
                assert_eq!(N::damper(s, v), N::mul_bounded(g, -v), "b {b} v {v}");
            }
        }
    }

    #[test]
    fn damper_is_mul_bounded_of_minus_v() {
        for b in [
            0.0,
            1e-7,
            0.3757,
            0.5,
            1.0,
            2.5,
            0.5 + 1e-9,
            1234.567,
            16383.99,
            65536.0,
        ] {
            for b in [b, -b] {
                check_damper::<Fx64>(b);
                check_damper::<Fx32>(b);
                check_damper::<F32>(b);
            }
        }
    }

    fn check_abs_bound(x: i32, t: u32) -> Result<(), TestCaseError> {
        prop_assert_eq!(
            AbsBound::new(t).exceeded(x),
            x.unsigned_abs() > t,
            "x = {}, t = {}",
            x,
            t
        );
        Ok(())
    }

    #[test]
    fn abs_bound_at_the_edges() {
        let edges = [
            0u32,
            1,
            2,
            (1 << 30) - 1,
            1 << 30,
            (1 << 31) - 1,
            1 << 31,
            u32::MAX,
        ];
        for &t in &edges {
            for x in [i32::MIN, i32::MIN + 1, -1, 0, 1, i32::MAX - 1, i32::MAX] {
                check_abs_bound(x, t).unwrap();
            }
            for dx in [-1i64, 0, 1] {
                for x in [i64::from(t) + dx, -i64::from(t) + dx] {
                    if let Ok(x) = i32::try_from(x) {
                        check_abs_bound(x, t).unwrap();
                    }
                }
            }
        }
    }

    proptest! {
        #[test]
        fn abs_bound_is_the_abs_test(x in any::<i32>(), t in any::<u32>(), small in 0u32..1000, near in -1000i32..1000) {
            for t in [t, small] {
                for x in [x, near] {
                    check_abs_bound(x, t)?;
                }
            }
        }
    }

    fn check_range_bound(x: i32, lo: i32, hi: i32) -> Result<(), TestCaseError> {
        let (lo, hi) = (lo.min(hi), lo.max(hi));
        prop_assert_eq!(
            RangeBound::new(lo, hi).outside(x),
            x < lo || x > hi,
            "x = {}, [{}, {}]",
            x,
            lo,
            hi
        );
        Ok(())
    }

    #[test]
    fn range_bound_at_the_edges() {
        let edges = [i32::MIN, i32::MIN + 1, -1, 0, 1, i32::MAX - 1, i32::MAX];
        for &lo in &edges {
            for &hi in &edges {
                for &x in &edges {
                    check_range_bound(x, lo, hi).unwrap();
                }
            }
        }
        // The full range is never left.
        assert!(edges
            .iter()
            .all(|&x| !RangeBound::new(i32::MIN, i32::MAX).outside(x)));
        // A reversed pair is [lo, lo], never a wrapped window.
        assert!(!RangeBound::new(5, 4).outside(5) && RangeBound::new(5, 4).outside(4));
    }

    proptest! {
        #[test]
        fn range_bound_is_the_interval_test(x in any::<i32>(), lo in any::<i32>(), hi in any::<i32>(), near in -1000i32..1000, small in -1000i32..1000) {
            for x in [x, near, lo, hi, lo.wrapping_sub(1), hi.wrapping_add(1)] {
                check_range_bound(x, lo, hi)?;
                check_range_bound(x, small, small.saturating_add(near.abs()))?;
            }
        }
    }
}
