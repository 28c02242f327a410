//! The STM32F446 timers the image uses, on one shared register model (`Timer`): `tim2` (the
//! quadrature encoder), `tim7` (the servo tick) and `tim1` (the PWM force output).
//!
//! `Timer` is a basic or general-purpose up-counter as a time-based model: CNT is not stored
//! but computed from the time it was last set (`cnt0` at `t0`) and the active prescaler; update
//! events (overflow at the active ARR) are found in closed form, so time may jump. Models: CR1
//! (CEN, URS, ARPE; ARR takes effect at once while ARPE is 0), SR (rc_w0), EGR.UG (reloads PSC
//! and ARR, restarts the count, sets UIF unless URS), CNT, PSC (takes effect at the next
//! update), ARR, and the other registers latched. Units: time in 1/720 MHz units; `units_per_clk`
//! is the timer's input clock period in those units. Invariant: the interrupt line is the level
//! SR & DIER over UIF and CC1IF–CC4IF, TIF.

mod regs;
pub mod tim1;
pub mod tim2;
pub mod tim7;

use super::state::{Periph, Timer};
pub(crate) use regs::{ARR, BDTR, CCER, CCMR1, CCR1, CNT, CR1, EGR, PSC, SR};
use regs::{CR1_ARPE, CR1_CEN, CR1_URS, DIER, LINE_FLAGS, UPDATE};

/// The three timers at reset.
pub(super) fn reset(p: &mut Periph) {
    tim2::reset(p);
    tim7::reset(p);
    tim1::reset(p);
}

impl Timer {
    /// The timer at reset, with ARR's reset value `arr_reset` (0xFFFF, or 2^32 − 1 for TIM2).
    fn reset(&mut self, arr_reset: u32) {
        *self = Self::default();
        self.r[ARR] = arr_reset;
        self.arr = arr_reset;
    }

    /// Whether CR1.CEN is set.
    pub(super) fn running(&self) -> bool {
        self.r[CR1] & CR1_CEN != 0
    }

    /// Units per counter step at timer clock `units_per_clk`.
    fn step(&self, units_per_clk: u64) -> u64 {
        units_per_clk * (u64::from(self.psc) + 1)
    }

    /// Counter value at `now`.
    fn count(&self, now: u64, units_per_clk: u64) -> u64 {
        if !self.running() {
            return self.cnt0;
        }
        let steps = now.saturating_sub(self.t0) / self.step(units_per_clk);
        (self.cnt0 + steps) % (u64::from(self.arr) + 1)
    }

    /// Time of the next update event (counter overflow), if counting.
    pub fn next_update(&self, units_per_clk: u64) -> Option<u64> {
        if !self.running() {
            return None;
        }
        let remaining = (u64::from(self.arr) + 1).saturating_sub(self.cnt0);
        Some(self.t0 + remaining * self.step(units_per_clk))
    }

    /// Processes the update events up to `now`.
    pub(super) fn advance(&mut self, now: u64, units_per_clk: u64) {
        while let Some(at) = self.next_update(units_per_clk) {
            if at > now {
                break;
            }
            self.update_event(at);
        }
    }

    /// An overflow at `at`: the shadow registers load, UIF sets.
    fn update_event(&mut self, at: u64) {
        self.cnt0 = 0;
        self.t0 = at;
        self.psc = self.r[PSC];
        self.arr = self.r[ARR];
        self.r[SR] |= UPDATE;
        self.updates += 1;
        self.first_update.get_or_insert(at);
        self.last_update = at;
    }

    /// A write of `v` to register `idx` at `now` (the counter counting the internal clock).
    fn write(&mut self, idx: usize, v: u32, now: u64, units_per_clk: u64) {
        self.advance(now, units_per_clk);
        match idx {
            CR1 => {
                let cnt = self.count(now, units_per_clk);
                self.cnt0 = cnt;
                self.t0 = now;
                self.r[CR1] = v;
                // ARPE off: a new ARR takes effect at once.
            }
            SR => self.r[SR] &= v, // rc_w0
            EGR => {
                if v & UPDATE != 0 {
                    self.cnt0 = 0;
                    self.t0 = now;
                    self.psc = self.r[PSC];
                    self.arr = self.r[ARR];
                    if self.r[CR1] & CR1_URS == 0 {
                        self.r[SR] |= UPDATE;
                    }
                }
            }
            CNT => {
                self.cnt0 = u64::from(v);
                self.t0 = now;
            }
            ARR => {
                self.r[ARR] = v;
                if self.r[CR1] & CR1_ARPE == 0 {
                    self.arr = v;
                }
            }
            _ => self.r[idx] = v,
        }
    }

    /// The update interrupt line (UIF & UIE) and the capture/compare flags it enables.
    pub(super) fn line(&self) -> bool {
        self.r[SR] & self.r[DIER] & LINE_FLAGS != 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn update_events_come_every_psc_plus_one_times_arr_plus_one_clocks() {
        let mut t = Timer::default();
        t.reset(0xFFFF);
        t.write(PSC, 8, 0, 8); // 9 clocks a step
        t.write(ARR, 99, 0, 8); // ARPE off: at once
        t.write(EGR, 1, 0, 8); // UG: PSC loads, UIF sets
        assert_eq!(t.r[SR] & 1, 1, "UG sets UIF (URS = 0)");
        t.write(SR, 0, 0, 8);
        t.write(CR1, 1, 0, 8);
        let period = 9 * 100 * 8;
        assert_eq!(t.next_update(8), Some(period));
        t.advance(3 * period + 1, 8);
        assert_eq!(t.updates, 3);
        assert_eq!((t.first_update, t.last_update), (Some(period), 3 * period));
        assert_eq!(t.count(3 * period + 5 * 9 * 8, 8), 5);
        assert!(!t.line(), "UIE off");
        t.write(DIER, 1, 3 * period + 1, 8);
        assert!(t.line());
    }
}
