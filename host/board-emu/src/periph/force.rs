//! The force output: what the board drives at the amplifier, derived from the pins and the
//! peripherals behind them, and handed to the plant whenever it changes.
//!
//! Models: the enable pin PB10 (push-pull output, high = enabled); the `dac` build's DAC1
//! channel 1 on PA4 (analog mode, CR.EN1), its code from DOR1; the `pwm` build's TIM1 CH1 on
//! PA8 (AF1; TIM1 running, CC1E, MOE or AOE, OC1M PWM mode 1 or 2; CC1P and mode 2 invert the
//! duty) with DIR on PA9 (push-pull output). Refuses: nothing (an output that is not driven
//! is simply absent). Units: DAC codes, duty 0..=1; the plant (`plant::Coupling`) turns them
//! into N·m or N. Invariant: the plant is brought up to now under the old force before a new
//! one applies (zero-order hold).

use super::dac;
use super::gpio::{self, AFRH, MODER, MODE_AF, MODE_ANALOG, MODE_OUTPUT, ODR, PA, PB};
use super::state::Periph;
use super::timer::{ARR, BDTR, CCER, CCMR1, CCR1};
use crate::plant::ForceState;
use crate::trace;

/// PB10: the amplifier / bridge enable.
const ENABLE_PIN: u32 = 10;
/// PA4: DAC channel 1.
const DAC_PIN: u32 = 4;
/// PA8: TIM1 CH1.
const PWM_PIN: u32 = 8;
/// PA9: the PWM build's direction.
const DIR_PIN: u32 = 9;
/// AF1 (TIM1/TIM2) for PA8, in AFRH's low nibble.
const AF_TIM1: u32 = 1;
/// CCER.CC1E.
const CC1E: u32 = 1;
/// CCER.CC1P.
const CC1P: u32 = 1 << 1;
/// BDTR.MOE and AOE (bits 15, 14).
const MOE_AOE: u32 = 3 << 14;
/// OC1M PWM mode 1.
const PWM_MODE_1: u32 = 6;
/// OC1M PWM mode 2.
const PWM_MODE_2: u32 = 7;

impl Periph {
    /// The force the board drives now, in the rig's force units (N·m): from the DAC through the
    /// op-amp stage and the amplifier, or from the PWM duty and DIR; zero while the enable pin
    /// (PB10) is low or not an output.
    pub fn force_output(&self) -> ForceState {
        let pb = &self.gpio[PB];
        let enable_out = gpio::field2(pb[MODER], ENABLE_PIN) == MODE_OUTPUT;
        let enabled = enable_out && pb[ODR] & (1 << ENABLE_PIN) != 0;
        let pa = &self.gpio[PA];
        let dir_out = gpio::field2(pa[MODER], DIR_PIN) == MODE_OUTPUT;
        let dir_high = dir_out && pa[ODR] & (1 << DIR_PIN) != 0;
        ForceState {
            enabled,
            dac_code: self.dac_code(),
            duty: self.pwm_duty(),
            dir_high,
        }
    }

    /// DAC: PA4 analog, DAC EN1 — the code in DOR1.
    fn dac_code(&self) -> Option<u32> {
        let pa = &self.gpio[PA];
        (self.dac[dac::CR] & dac::CR_EN1 != 0 && gpio::field2(pa[MODER], DAC_PIN) == MODE_ANALOG)
            .then_some(self.dac[dac::DOR1] & dac::CODE)
    }

    /// PWM: TIM1 running, CH1 enabled, main output enabled, PA8 AF1, mode PWM1/2 — the duty.
    fn pwm_duty(&self) -> Option<f64> {
        let pa = &self.gpio[PA];
        let t = &self.tim1;
        let oc1m = (t.r[CCMR1] >> 4) & 7;
        let pwm_on = t.running()
            && t.r[CCER] & CC1E != 0
            // MOE, or AOE (bit 14): MOE is set by the next update event of the running timer.
            && t.r[BDTR] & MOE_AOE != 0
            && gpio::field2(pa[MODER], PWM_PIN) == MODE_AF
            && pa[AFRH] & 0xF == AF_TIM1
            && (oc1m == PWM_MODE_1 || oc1m == PWM_MODE_2);
        pwm_on.then(|| {
            let period = f64::from(t.r[ARR]) + 1.0;
            let mut d = (f64::from(t.r[CCR1]) / period).min(1.0);
            if (oc1m == PWM_MODE_2) ^ (t.r[CCER] & CC1P != 0) {
                d = 1.0 - d;
            }
            d
        })
    }

    /// Notes a change of the force output: the plant is brought up to now under the old force
    /// before the new one applies.
    pub(super) fn output_changed(&mut self, before: ForceState) {
        let after = self.force_output();
        if trace::enabled() && after != before {
            eprintln!(
                "output {after:?} tim1 {:x?} gpioa {:x?}",
                self.tim1.r, self.gpio[PA]
            );
        }
        if after != before {
            self.plant.set_force(self.now, after);
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::periph::state::Periph;
    use crate::plant::Coupling;

    #[test]
    fn the_dac_output_needs_pa4_analog_and_en1_and_the_enable_pin_an_output() {
        let mut p = Periph::new(Coupling::new(None));
        p.write(0x4002_3830, 4, 0b11); // GPIOA, GPIOB clocks
        p.write(0x4000_7408, 4, 2048); // DHR12R1
        assert_eq!(p.force_output().dac_code, None, "DAC off, PA4 input");
        p.write(0x4000_7400, 4, 1); // EN1
        assert_eq!(p.force_output().dac_code, None, "PA4 still an input");
        p.write(0x4002_0000, 4, 0xA800_0000 | (3 << 8)); // PA4 analog
        assert_eq!(p.force_output().dac_code, Some(2048));
        p.write(0x4002_0418, 4, 1 << 10); // PB10 high, but an input
        assert!(!p.force_output().enabled);
        p.write(0x4002_0400, 4, 0x0000_0280 | (1 << 20)); // PB10 output
        assert!(p.force_output().enabled);
        assert_eq!(
            p.plant.state,
            Some(p.force_output()),
            "the plant sees each change"
        );
    }
}
