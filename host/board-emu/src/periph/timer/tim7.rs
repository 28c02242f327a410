//! TIM7, the servo tick: a basic timer counting the APB1 timer clock, its update interrupt
//! (IRQ 55) running the servo loop.
//!
//! Models: every TIM7 register through the shared `Timer` (CR1, DIER, SR, EGR, CNT, PSC, ARR;
//! the rest latched); CNT reads the count at the time of the read. Refuses: nothing in its
//! block up to ARR (0x2C); offsets from 0x30 on are unmodelled. Units: time in 1/720 MHz
//! units, the counter clock from `Periph::apb1_timer_units`. Invariant: update events are
//! processed up to now before any access.

use super::regs::CNT;
use crate::periph::state::Periph;

/// TIM7 base address.
pub const BASE: u32 = 0x4000_1400;
/// Last modelled word address (ARR).
pub const LAST: u32 = 0x4000_142F;
/// ARR at reset.
const ARR_RESET: u32 = 0xFFFF;

/// TIM7 at reset.
pub(crate) fn reset(p: &mut Periph) {
    p.tim7.reset(ARR_RESET);
}

/// A word read of a TIM7 register.
pub(crate) fn read(p: &mut Periph, a: u32) -> u32 {
    let i = ((a - BASE) / 4) as usize;
    let u = p.apb1_timer_units();
    p.tim7.advance(p.now, u);
    if i == CNT {
        p.tim7.count(p.now, u) as u32
    } else {
        p.tim7.r[i]
    }
}

/// A word write of a TIM7 register.
pub(crate) fn write(p: &mut Periph, a: u32, v: u32) {
    let i = ((a - BASE) / 4) as usize;
    let u = p.apb1_timer_units();
    p.tim7.write(i, v, p.now, u);
}

#[cfg(test)]
mod tests {
    use crate::periph::state::Periph;
    use crate::plant::Coupling;

    #[test]
    fn cnt_reads_the_count_at_the_time_of_the_read() {
        let mut p = Periph::new(Coupling::new(None));
        p.write(0x4000_1428, 4, 15); // PSC: 16 clocks a step
        p.write(0x4000_142C, 4, 999); // ARR
        p.write(0x4000_1414, 4, 1); // EGR.UG
        p.write(0x4000_1400, 4, 1); // CEN
        let step = 16 * p.apb1_timer_units();
        p.now = 10 * step;
        assert_eq!(p.read(0x4000_1424, 4), 10);
        assert_eq!(p.tim7.next_update(p.apb1_timer_units()), Some(1000 * step));
        assert!(p.stop.is_none(), "{:?}", p.stop);
    }
}
