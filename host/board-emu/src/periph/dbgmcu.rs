//! DBGMCU, the MCU debug component: its ID code and the freeze/low-power debug settings.
//!
//! Models: IDCODE (read-only: the STM32F446's device ID 0x421, revision 0x1000), CR, APB1_FZ,
//! APB2_FZ (latched; the emulator has no debugger, so they change nothing). Refuses: a write to
//! IDCODE. Units: none. Invariant: writes never change timing.

use super::state::Periph;

/// DBGMCU_IDCODE address (the block's base).
pub const BASE: u32 = 0xE004_2000;
/// Last word address (APB2_FZ).
pub const LAST: u32 = 0xE004_200F;
/// DBGMCU_IDCODE.
const IDCODE: u32 = BASE;
/// IDCODE's value.
const IDCODE_VALUE: u32 = 0x1000_6421;
/// DBGMCU_CR, the first latched register.
const CR: u32 = BASE + 4;

/// DBGMCU at reset.
pub(super) fn reset(p: &mut Periph) {
    p.dbgmcu = [0; 3];
}

/// A word read of a DBGMCU register.
pub(super) fn read(p: &mut Periph, a: u32) -> u32 {
    if a == IDCODE {
        IDCODE_VALUE
    } else {
        p.dbgmcu[((a - CR) / 4) as usize]
    }
}

/// A word write of a DBGMCU register.
pub(super) fn write(p: &mut Periph, a: u32, v: u32, raw: u64) {
    if a == IDCODE {
        p.unmodelled(a, Some(raw));
    } else {
        p.dbgmcu[((a - CR) / 4) as usize] = v;
    }
}

#[cfg(test)]
mod tests {
    use crate::periph::state::Periph;
    use crate::plant::Coupling;

    #[test]
    fn idcode_is_the_f446s_and_the_freeze_bits_latch() {
        let mut p = Periph::new(Coupling::new(None));
        assert_eq!(p.read(0xE004_2000, 4), 0x1000_6421);
        p.write(0xE004_2008, 4, 1 << 12);
        assert_eq!(p.read(0xE004_2008, 4), 1 << 12);
        assert!(p.stop.is_none(), "{:?}", p.stop);
        p.write(0xE004_2000, 4, 0);
        let why = p.stop.take().expect("IDCODE is read-only");
        assert!(why.contains("DBGMCU+0x000"), "{why}");
    }
}
