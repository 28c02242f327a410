//! SysTick, the Cortex-M4 system timer: latched only, since the image keeps time with TIM7 and
//! must not start SysTick.
//!
//! Models: CSR, RVR, CVR (latched; the counter does not run) and CALIB (read-only: NOREF,
//! TENMS = 22 499). Refuses: CSR.ENABLE, a write to CALIB. Units: none
//! (the counter never counts). Invariant: SysTick never raises its exception.

use super::state::Periph;

/// SYST_CSR address (the block's base).
pub const BASE: u32 = 0xE000_E010;
/// SYST_CALIB address (the last word).
pub const LAST: u32 = 0xE000_E01C;
/// SYST_CSR.
const CSR: u32 = BASE;
/// SYST_CALIB.
const CALIB: u32 = 0xE000_E01C;
/// CALIB's value: NOREF, TENMS = 22 499.
const CALIB_VALUE: u32 = 0x4000_0000 | 22_499;
/// CSR.ENABLE.
const CSR_ENABLE: u32 = 1;

/// SysTick at reset: off.
pub(super) fn reset(p: &mut Periph) {
    p.systick = [0; 3];
}

/// A word read of a SysTick register.
pub(super) fn read(p: &mut Periph, a: u32) -> u32 {
    if a == CALIB {
        CALIB_VALUE
    } else {
        p.systick[((a - BASE) / 4) as usize]
    }
}

/// A word write of a SysTick register.
pub(super) fn write(p: &mut Periph, a: u32, v: u32, raw: u64) {
    match a {
        CSR => {
            if v & CSR_ENABLE != 0 {
                p.fail("SYST_CSR.ENABLE: the firmware starts SysTick, which this image is not expected to use (the servo clock is TIM7)".into());
            }
            p.systick[0] = v;
        }
        CALIB => p.unmodelled(a, Some(raw)),
        _ => p.systick[((a - BASE) / 4) as usize] = v,
    }
}

#[cfg(test)]
mod tests {
    use crate::periph::state::Periph;
    use crate::plant::Coupling;

    #[test]
    fn systick_latches_and_starting_it_stops_the_run() {
        let mut p = Periph::new(Coupling::new(None));
        p.write(0xE000_E014, 4, 1234);
        assert_eq!(p.read(0xE000_E014, 4), 1234);
        assert_eq!(p.read(0xE000_E01C, 4), 0x4000_0000 | 22_499);
        assert!(p.stop.is_none(), "{:?}", p.stop);
        p.write(0xE000_E010, 4, 1);
        let why = p.stop.take().expect("ENABLE stops the run");
        assert!(why.contains("SYST_CSR.ENABLE"), "{why}");
    }
}
