//! TIM1, the PWM force output (`pwm` builds): an advanced-control timer counting the APB2
//! timer clock, CH1 on PA8 (AF1) driving the amplifier's PWM input.
//!
//! Models: every TIM1 register through the shared `Timer` (CR1, SR, EGR, CNT, PSC, ARR
//! counting; CCMR1, CCER, CCR1, BDTR and the rest latched); the duty the force output sees is
//! computed from CCR1 / (ARR + 1) by `force`. Refuses: offsets from 0x50 on. Units: time in
//! 1/720 MHz units, the counter clock from `Periph::apb2_timer_units`. Invariant: every write
//! goes through `output_changed`, so the plant sees a new duty at the time of the write.

use crate::periph::state::Periph;

/// TIM1 base address.
pub const BASE: u32 = 0x4001_0000;
/// Last modelled word address (DMAR/OR).
pub const LAST: u32 = 0x4001_004F;
/// ARR at reset.
const ARR_RESET: u32 = 0xFFFF;

/// TIM1 at reset.
pub(crate) fn reset(p: &mut Periph) {
    p.tim1.reset(ARR_RESET);
}

/// A word read of a TIM1 register (the latched value).
pub(crate) fn read(p: &mut Periph, a: u32) -> u32 {
    let i = ((a - BASE) / 4) as usize;
    p.tim1.r[i]
}

/// A word write of a TIM1 register; the force output follows.
pub(crate) fn write(p: &mut Periph, a: u32, v: u32) {
    let before = p.force_output();
    let i = ((a - BASE) / 4) as usize;
    let u = p.apb2_timer_units();
    p.tim1.write(i, v, p.now, u);
    p.output_changed(before);
}

#[cfg(test)]
mod tests {
    use crate::periph::state::Periph;
    use crate::plant::Coupling;

    #[test]
    fn the_pwm_duty_is_ccr1_over_arr_plus_one_and_cc1p_inverts_it() {
        let mut p = Periph::new(Coupling::new(None));
        p.write(0x4002_3830, 4, 0b11); // GPIOA, GPIOB clocks
        p.write(0x4002_0000, 4, 0xA800_0000 | (2 << 16) | (1 << 18)); // PA8 AF, PA9 output
        p.write(0x4002_0024, 4, 1); // AFRH: PA8 AF1
        p.write(0x4002_0400, 4, 0x0000_0280 | (1 << 20)); // PB10 output
        p.write(0x4002_0418, 4, 1 << 10); // PB10 high: enabled
        p.write(0x4001_002C, 4, 999); // ARR
        p.write(0x4001_0034, 4, 250); // CCR1
        p.write(0x4001_0018, 4, 6 << 4); // CCMR1.OC1M: PWM mode 1
        p.write(0x4001_0020, 4, 1); // CCER.CC1E
        p.write(0x4001_0044, 4, 1 << 15); // BDTR.MOE
        assert_eq!(p.force_output().duty, None, "TIM1 not running");
        p.write(0x4001_0000, 4, 1); // CEN
        let f = p.force_output();
        assert_eq!((f.enabled, f.duty, f.dac_code), (true, Some(0.25), None));
        assert!(!f.dir_high);
        p.write(0x4002_0018, 4, 1 << 9); // DIR (PA9) high
        assert!(p.force_output().dir_high);
        p.write(0x4001_0020, 4, 0b11); // CC1P: active low
        assert_eq!(p.force_output().duty, Some(0.75));
        assert_eq!(
            p.plant.state,
            Some(p.force_output()),
            "the plant sees each change"
        );
        assert!(p.stop.is_none(), "{:?}", p.stop);
    }
}
