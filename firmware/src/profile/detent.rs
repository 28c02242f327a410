//! A detent train's force in fixed point: F = −A·sin(2π·d/pitch), d = (n + ½)·Δ_eff counts
//! from the first minimum, for the effective counts n inside the train (the element's
//! `active` range; 0 outside).
//!
//! Units: the phase is a `u32` in which 2^32 is one pitch; the phase step per half effective
//! count, `step`, is a `u64` in units of 2^-64 pitch (step = 2^64·Δ_eff/(2·pitch) ≤ 2^62, the
//! pitch being at least 2 effective counts); the strength A is in output codes with 8
//! fractional bits (`strength_q8` ≤ 2^32: A ≤ 2^24 codes); the sine is `idsp::cossin`'s Q31.
//!
//! Invariants: the phase of count n is ((2n+1)·step mod 2^64)/2^32. That product is taken
//! modulo 2^64 on purpose, and only it: the sine is periodic in the pitch, so dropping whole
//! pitches (the wrap) is the periodic function itself, and the wrapped phase is exact. Every
//! other operation is exact or saturating: |A·sin| < 2^63 before the rounding shift, and the
//! code is at most A in magnitude (A ≤ 2^24 codes), never wrapped. `idsp::cossin` (a 128-entry
//! table interpolated to 9·10⁻⁶ of full scale) makes the code within 9·10⁻⁶·A + ½ codes of
//! the exact −A·sin (within 1 code for A up to 5·10⁴ codes).

/// One detent train's fixed-point form (see the module header).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Detent {
    /// Phase per half effective count, 2^-64 pitch.
    pub(crate) step: u64,
    /// A, output codes × 2^8.
    pub(crate) strength_q8: i64,
}

impl Detent {
    /// The phase of effective count `n` relative to the first minimum, 2^-32 pitch.
    #[inline]
    #[must_use]
    pub(crate) fn phase(&self, n: i32) -> u32 {
        // 2n+1 is exact in i64; its product with the step wraps modulo 2^64 = one pitch (the
        // period of the sine: see the header).
        let m = (i64::from(n) * 2 + 1) as u64;
        (m.wrapping_mul(self.step) >> 32) as u32
    }

    /// The detent's code at effective count `n` (inside the train): ⌊−A·sin(phase) + ½⌋.
    #[inline]
    #[must_use]
    pub(crate) fn code(&self, n: i32) -> i32 {
        let (_, sin) = idsp::cossin(self.phase(n) as i32);
        // |A_q8| ≤ 2^32, |sin| ≤ 2^31: |product| ≤ 2^63 − 2^32 (A_q8 < 2^32), exact; the
        // quotient by 2^39 is at most A ≤ 2^24 codes.
        let p = self.strength_q8.saturating_mul(i64::from(sin));
        (p.saturating_neg().saturating_add(1 << 38) >> 39) as i32
    }
}
