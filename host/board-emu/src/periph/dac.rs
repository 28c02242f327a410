//! DAC1 channel 1, the analog force output (`dac` builds): PA4 through the op-amp stage to the
//! amplifier (see `plant` for the output stage).
//!
//! Models: CR (EN1; TEN1 must stay 0), the channel-1 data holding registers DHR12R1, DHR12L1,
//! DHR8R1 and DHR12RD (each moves to DOR1 at once, untriggered, by its alignment), DOR1, and
//! the rest of the block up to SR latched. Refuses: a triggered channel (CR.TEN1); offsets
//! from 0x38 on. Units: DAC codes (12 bits, 0..=4095). Invariant: every write goes through
//! `output_changed`, so the plant sees the new code at the time of the write.

use super::state::Periph;

/// DAC base address.
pub const BASE: u32 = 0x4000_7400;
/// Last modelled word address (SR).
pub const LAST: u32 = 0x4000_7437;

/// DAC_CR (register index, offset / 4).
pub(super) const CR: usize = 0;
/// DAC_DOR1 (register index).
pub(super) const DOR1: usize = 0x2C / 4;
/// DAC_CR offset.
const CR_OFF: u32 = 0x00;
/// DAC_DHR12R1 offset: 12 bits right-aligned.
const DHR12R1_OFF: u32 = 0x08;
/// DAC_DHR12L1 offset: 12 bits left-aligned.
const DHR12L1_OFF: u32 = 0x0C;
/// DAC_DHR8R1 offset: 8 bits right-aligned.
const DHR8R1_OFF: u32 = 0x10;
/// DAC_DHR12RD offset: dual 12 bits right-aligned (channel 1 in the low half).
const DHR12RD_OFF: u32 = 0x20;
/// DAC_CR.EN1.
pub(super) const CR_EN1: u32 = 1;
/// DAC_CR.TEN1.
const CR_TEN1: u32 = 1 << 2;
/// A 12-bit code.
pub(super) const CODE: u32 = 0xFFF;

/// The DAC at reset: off, code 0.
pub(super) fn reset(p: &mut Periph) {
    p.dac = [0; 14];
}

/// A word read of a DAC register (the latched value).
pub(super) fn read(p: &mut Periph, a: u32) -> u32 {
    p.dac[((a - BASE) / 4) as usize]
}

/// A word write of a DAC register; a data holding register moves to DOR1 at once.
pub(super) fn write(p: &mut Periph, a: u32, v: u32) {
    let before = p.force_output();
    let off = a - BASE;
    p.dac[(off / 4) as usize] = v;
    // DHR → DOR at once (no trigger: TEN1 = 0), by alignment.
    if p.dac[CR] & CR_TEN1 == 0 {
        match off {
            DHR12R1_OFF => p.dac[DOR1] = v & CODE,
            DHR12L1_OFF => p.dac[DOR1] = (v >> 4) & CODE,
            DHR8R1_OFF => p.dac[DOR1] = (v & 0xFF) << 4,
            DHR12RD_OFF => p.dac[DOR1] = v & CODE,
            _ => {}
        }
    } else if off == CR_OFF {
        p.fail("DAC_CR.TEN1: a triggered DAC is not modelled (the firmware writes DHR12R1 untriggered)".into());
    }
    p.output_changed(before);
}

#[cfg(test)]
mod tests {
    use crate::periph::state::Periph;
    use crate::plant::Coupling;

    #[test]
    fn data_holding_registers_move_to_dor1_by_alignment_and_a_trigger_is_refused() {
        let mut p = Periph::new(Coupling::new(None));
        for (off, v, code) in [
            (0x08, 0x1ABC, 0xABC),
            (0x0C, 0xABC0, 0xABC),
            (0x10, 0x1AB, 0xAB0),
            (0x20, 0x0FFF_0123, 0x123),
        ] {
            p.write(0x4000_7400 + off, 4, v);
            assert_eq!(p.read(0x4000_742C, 4), code, "offset {off:#x}");
        }
        assert!(p.stop.is_none(), "{:?}", p.stop);
        p.write(0x4000_7400, 4, 1 | (1 << 2));
        let why = p.stop.take().expect("TEN1 stops the run");
        assert!(why.contains("DAC_CR.TEN1"), "{why}");
    }
}
