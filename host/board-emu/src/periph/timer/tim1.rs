//! TIM1, the PWM force output (`pwm` builds): an advanced-control timer counting the APB2
//! timer clock, CH1 on PA8 (AF1) driving the amplifier's PWM input.
//!
//! Models: every TIM1 register through the shared `Timer` (CR1, SR, EGR, CNT, PSC, ARR
//! counting; CCMR1, CCER, CCR1, BDTR and the rest latched); the duty the force output sees is
//! computed from CCR1 / (ARR + 1) by `force`. Refuses: offsets from 0x50 on. Units: time in
//! 1/720 MHz units, the counter clock from `Periph::apb2_timer_units`. Invariant: every write
//! goes through `output_changed`, so the plant sees a new duty at the time of the write.

use super::Periph;

/// TIM1 base address.
pub const BASE: u32 = 0x4001_0000;
/// Last modelled word address (DMAR/OR).
pub const LAST: u32 = 0x4001_004F;
/// ARR at reset.
const ARR_RESET: u32 = 0xFFFF;

/// TIM1 at reset.
pub(in crate::periph) fn reset(p: &mut Periph) {
    p.tim1.reset(ARR_RESET);
}

/// A word read of a TIM1 register (the latched value).
pub(in crate::periph) fn read(p: &mut Periph, a: u32) -> u32 {
    let i = ((a - BASE) / 4) as usize;
    p.tim1.r[i]
}

/// A word write of a TIM1 register; the force output follows.
pub(in crate::periph) fn write(p: &mut Periph, a: u32, v: u32) {
    let before = p.force_output();
    let i = ((a - BASE) / 4) as usize;
    let u = p.apb2_timer_units();
    p.tim1.write(i, v, p.now, u);
    p.output_changed(before);
}
