//! The NVIC: the interrupt controller's enable, pend and priority registers for the
//! STM32F446's 97 external interrupts, and the interrupt lines of the modelled peripherals.
//!
//! Models: ISER/ICER (set/clear enable), ISPR/ICPR (set/clear software pend; reading them shows
//! software pends and the peripherals' lines), IPR (one priority byte per interrupt, only the
//! upper 4 bits implemented; byte writes are the common case). Refuses: IABR (active bits) and
//! STIR, and every other word in the block. Units: interrupt numbers 0..`IRQS` (exception
//! number − 16); priorities 0–255, lower is more urgent. Invariant: a line is pending while
//! its peripheral's flag & enable level is high or it is pended by software.

use super::state::{Periph, IRQS};

/// Interrupt numbers (RM0390 Table 38).
pub const IRQ_TIM2: usize = 28;
/// USART2 global interrupt.
pub const IRQ_USART2: usize = 38;
/// TIM7 global interrupt.
pub const IRQ_TIM7: usize = 55;
/// TIM1 interrupts (break/TIM9, update/TIM10, trigger and commutation/TIM11, capture compare).
const IRQ_TIM1: std::ops::RangeInclusive<usize> = 24..=27;
/// First NVIC register (ISER0).
pub const BASE: u32 = 0xE000_E100;
/// Last modelled word address (IPR23).
pub const LAST: u32 = 0xE000_E45F;
/// ISER0..7: set-enable.
const ISER: u32 = 0xE000_E100;
/// ICER0..7: clear-enable.
const ICER: u32 = 0xE000_E180;
/// ISPR0..7: set-pending.
const ISPR: u32 = 0xE000_E200;
/// ICPR0..7: clear-pending.
const ICPR: u32 = 0xE000_E280;
/// IPR0..23: priority bytes.
const IPR: u32 = 0xE000_E400;
/// Bytes in each of the ISER/ICER/ISPR/ICPR banks (8 words).
const BANK: u32 = 0x20;
/// Bytes of IPR the model keeps (0x60: 96 priorities, IRQ 96's is byte-written only).
const IPR_LEN: u32 = 0x60;
/// Implemented priority bits.
const PRIO_MASK: u8 = 0xF0;

/// The NVIC at reset: nothing enabled or pended, every priority 0.
pub(super) fn reset(p: &mut Periph) {
    p.nvic_en = [false; IRQS];
    p.nvic_pend = [false; IRQS];
    p.nvic_prio = [0; IRQS];
}

/// Whether `a` lies in `start`'s bank of eight words.
fn in_bank(a: u32, start: u32, len: u32) -> bool {
    (start..start + len).contains(&a)
}

/// A word read in the NVIC block.
pub(super) fn read(p: &mut Periph, a: u32) -> u32 {
    if in_bank(a, ISER, BANK) || in_bank(a, ICER, BANK) {
        let base = ((a & 0x1F) / 4) as usize * 32;
        bits(|i| p.nvic_en.get(base + i).copied().unwrap_or(false))
    } else if in_bank(a, ISPR, BANK) || in_bank(a, ICPR, BANK) {
        let base = ((a & 0x1F) / 4) as usize * 32;
        let pend: Vec<bool> = (0..32)
            .map(|i| base + i < IRQS && p.irq_pending(base + i))
            .collect();
        bits(|i| pend[i])
    } else if in_bank(a, IPR, IPR_LEN) {
        let base = (a - IPR) as usize;
        (0..4).fold(0, |acc, i| {
            acc | u32::from(p.nvic_prio.get(base + i).copied().unwrap_or(0)) << (8 * i)
        })
    } else {
        p.unmodelled(a, None);
        0
    }
}

/// A word write in the NVIC block.
pub(super) fn write(p: &mut Periph, a: u32, v: u32, raw: u64) {
    if in_bank(a, ISER, BANK) {
        set_bits(&mut p.nvic_en, a, v, true);
    } else if in_bank(a, ICER, BANK) {
        set_bits(&mut p.nvic_en, a, v, false);
    } else if in_bank(a, ISPR, BANK) {
        set_bits(&mut p.nvic_pend, a, v, true);
    } else if in_bank(a, ICPR, BANK) {
        set_bits(&mut p.nvic_pend, a, v, false);
    } else if in_bank(a, IPR, IPR_LEN) {
        let base = (a - IPR) as usize;
        for i in 0..4 {
            if base + i < IRQS {
                p.nvic_prio[base + i] = (v >> (8 * i)) as u8 & PRIO_MASK;
            }
        }
    } else {
        p.unmodelled(a, Some(raw));
    }
}

/// Whether byte address `addr` is one of the IRQs' priority bytes.
pub(super) fn is_priority_byte(addr: u32) -> bool {
    (IPR..IPR + IRQS as u32).contains(&addr)
}

/// A sub-word write of `size` priority bytes at `addr`.
pub(super) fn write_priority_bytes(p: &mut Periph, addr: u32, size: usize, v: u64) {
    for i in 0..size {
        let irq = (addr - IPR) as usize + i;
        if irq < IRQS {
            p.nvic_prio[irq] = (v >> (8 * i)) as u8 & PRIO_MASK;
        }
    }
}

impl Periph {
    /// Whether interrupt `irq`'s line is high or it is pended by software.
    pub fn irq_pending(&self, irq: usize) -> bool {
        self.nvic_pend[irq]
            || match irq {
                IRQ_TIM7 => self.tim7.line(),
                IRQ_USART2 => self.usart.line(),
                IRQ_TIM2 => self.tim2.line(),
                _ if IRQ_TIM1.contains(&irq) => self.tim1.line(),
                _ => false,
            }
    }
}

/// A word of 32 bits from `f(bit)`.
fn bits(f: impl Fn(usize) -> bool) -> u32 {
    (0..32).fold(0, |acc, i| acc | (u32::from(f(i)) << i))
}

/// Sets the flags of `arr` to `to` where `v` has a 1, in the bank word at `a`.
fn set_bits(arr: &mut [bool; IRQS], a: u32, v: u32, to: bool) {
    let base = ((a & 0x1F) / 4) as usize * 32;
    for i in 0..32 {
        if v & (1 << i) != 0 && base + i < IRQS {
            arr[base + i] = to;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{IRQ_TIM7, IRQ_USART2};
    use crate::periph::state::Periph;
    use crate::plant::Coupling;

    #[test]
    fn enables_pends_and_priority_bytes() {
        let mut p = Periph::new(Coupling::new(None));
        let usart_bit = 1u64 << (IRQ_USART2 % 32);
        p.write(0xE000_E104, 4, usart_bit); // ISER1
        assert!(p.nvic_en[IRQ_USART2]);
        assert_eq!(p.read(0xE000_E184, 4), usart_bit, "ICER1 reads the enables");
        p.write(0xE000_E184, 4, usart_bit);
        assert!(!p.nvic_en[IRQ_USART2]);
        let tim7_bit = 1u64 << (IRQ_TIM7 % 32);
        p.write(0xE000_E204, 4, tim7_bit); // ISPR1
        assert!(p.irq_pending(IRQ_TIM7));
        assert_eq!(p.read(0xE000_E284, 4), tim7_bit, "ICPR1 reads the pends");
        p.write(0xE000_E284, 4, tim7_bit);
        assert!(!p.irq_pending(IRQ_TIM7));
        p.write(0xE000_E400 + IRQ_TIM7 as u32, 1, 0x5A); // a byte: the upper 4 bits stay
        assert_eq!(p.nvic_prio[IRQ_TIM7], 0x50);
        p.write(0xE000_E41C, 4, 0x1122_3344); // IPR7: IRQs 28-31
        assert_eq!(p.read(0xE000_E41C, 4), 0x1020_3040);
        let _ = p.read(0xE000_E300, 4); // IABR0
        let why = p.stop.take().expect("active bits are not modelled");
        assert!(why.contains("SCS+0x300"), "{why}");
    }
}
