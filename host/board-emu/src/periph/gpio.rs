//! GPIOA–GPIOH: the pins' mode, type, speed, pull, output latch and alternate function.
//!
//! Models: MODER, OTYPER, OSPEEDR, PUPDR, ODR, LCKR, AFRL, AFRH (latched), BSRR (sets and
//! clears ODR bits; reads 0) and IDR (read-only: an output pin reads back its latch, any other
//! pin reads high with a pull-up and low otherwise; nothing drives the pins from outside). A
//! write to a port whose RCC_AHB1ENR clock is off is ignored, as on the chip. Refuses: any
//! offset from 0x28 on. Invariant: every write that can change the force output (the enable
//! pin PB10, DIR on PA9, PA4/PA8's modes) goes through `output_changed`, so the plant sees the
//! new output at the time of the write. Reset values are the debug pins' (PA13–PA15, PB3, PB4).

use super::rcc;
use super::state::Periph;

/// GPIOA base address.
pub const BASE: u32 = 0x4002_0000;
/// Last address of GPIOH.
pub const LAST: u32 = 0x4002_1FFF;
/// Address distance of consecutive ports.
const PORT_STRIDE: u32 = 0x400;
/// First offset past the modelled registers.
const END_OFF: u32 = 0x28;

/// Port A (index into `Periph::gpio`).
pub(super) const PA: usize = 0;
/// Port B.
pub(super) const PB: usize = 1;

/// GPIOx_MODER (register index, offset / 4): 2 bits per pin, 0 input, 1 output, 2 AF, 3 analog.
pub(super) const MODER: usize = 0;
/// GPIOx_OSPEEDR.
const OSPEEDR: usize = 2;
/// GPIOx_PUPDR: 2 bits per pin, 1 pull-up.
const PUPDR: usize = 3;
/// GPIOx_IDR.
const IDR: usize = 4;
/// GPIOx_ODR.
pub(super) const ODR: usize = 5;
/// GPIOx_BSRR.
const BSRR: usize = 6;
/// GPIOx_AFRH (AF of pins 8–15, 4 bits each).
pub(super) const AFRH: usize = 9;

/// MODER value of an output pin.
pub(super) const MODE_OUTPUT: u32 = 1;
/// MODER value of an alternate-function pin.
pub(super) const MODE_AF: u32 = 2;
/// MODER value of an analog pin.
pub(super) const MODE_ANALOG: u32 = 3;

/// Pin `pin`'s 2-bit field of a MODER/PUPDR-style register value.
pub(super) fn field2(reg: u32, pin: u32) -> u32 {
    (reg >> (2 * pin)) & 3
}

/// Whether word address `a` (in `BASE..=LAST`) is a modelled register.
pub(super) fn modelled(a: u32) -> bool {
    (a & 0x3FF) < END_OFF
}

/// (port, register index) of address `a`.
fn locate(a: u32) -> (usize, usize) {
    let port = ((a - BASE) / PORT_STRIDE) as usize;
    let off = ((a & 0x3FF) / 4) as usize;
    (port, off)
}

/// Every port at reset; PA13/PA14 (SWDIO, SWCLK) and PB3/PB4 (SWO, NJTRST) in their debug modes.
pub(super) fn reset(p: &mut Periph) {
    p.gpio = [[0; 10]; 8];
    p.gpio[PA][MODER] = 0xA800_0000;
    p.gpio[PA][PUPDR] = 0x6400_0000;
    p.gpio[PA][OSPEEDR] = 0x0C00_0000;
    p.gpio[PB][MODER] = 0x0000_0280;
    p.gpio[PB][PUPDR] = 0x0000_0100;
    p.gpio[PB][OSPEEDR] = 0x0000_00C0;
}

/// The latched value at `a` without side effects (0 past the register file).
pub(super) fn peek(p: &Periph, a: u32) -> u32 {
    let (port, off) = locate(a);
    p.gpio[port].get(off).copied().unwrap_or(0)
}

/// A word read of a modelled GPIO register.
pub(super) fn read(p: &mut Periph, a: u32) -> u32 {
    let (port, off) = locate(a);
    let g = &p.gpio[port];
    match off {
        IDR => idr(g),
        BSRR => 0,
        _ => g[off],
    }
}

/// IDR: outputs read back their latch; pull-ups read high otherwise.
fn idr(g: &[u32; 10]) -> u32 {
    let mut idr = 0;
    for pin in 0..16 {
        let mode = field2(g[MODER], pin);
        let pupd = field2(g[PUPDR], pin);
        let bit = match mode {
            MODE_OUTPUT => (g[ODR] >> pin) & 1,
            _ => u32::from(pupd == 1),
        };
        idr |= bit << pin;
    }
    idr
}

/// A word write of a modelled GPIO register (ignored while the port's clock is off).
pub(super) fn write(p: &mut Periph, a: u32, v: u32) {
    let (port, off) = locate(a);
    if p.rcc[rcc::AHB1ENR] & (1 << port) == 0 {
        // Clock off: the write is ignored, as on the chip.
        return;
    }
    let before = p.force_output();
    let g = &mut p.gpio[port];
    match off {
        BSRR => {
            g[ODR] |= v & 0xFFFF;
            g[ODR] &= !(v >> 16);
        }
        IDR => {}
        _ => g[off] = v,
    }
    p.output_changed(before);
}

#[cfg(test)]
mod tests {
    use crate::periph::state::Periph;
    use crate::plant::Coupling;

    #[test]
    fn bsrr_sets_and_clears_odr_idr_reads_outputs_and_pull_ups_and_a_clockless_port_ignores_writes()
    {
        let mut p = Periph::new(Coupling::new(None));
        p.write(0x4002_0014, 4, 0xFFFF); // ODR with GPIOA's clock off: ignored
        assert_eq!(p.read(0x4002_0014, 4), 0);
        p.write(0x4002_3830, 4, 1); // RCC_AHB1ENR.GPIOAEN
        p.write(0x4002_0000, 4, 0xA800_0000 | 1); // PA0 output, the SWD pins as at reset
        p.write(0x4002_0018, 4, 1 | (1 << 17)); // BSRR: set PA0, reset PA1
        assert_eq!(p.read(0x4002_0014, 4), 1);
        assert_eq!(p.read(0x4002_0018, 4), 0, "BSRR reads 0");
        // IDR: PA0 drives high; PA13 and PA15 have pull-ups at reset, PA14 a pull-down.
        assert_eq!(p.read(0x4002_0010, 4), 1 | (1 << 13) | (1 << 15));
        p.write(0x4002_0018, 4, 1 << 16);
        assert_eq!(p.read(0x4002_0010, 4), (1 << 13) | (1 << 15));
        let _ = p.read(0x4002_0028, 4);
        let why = p.stop.take().expect("past AFRH");
        assert!(why.contains("GPIO+0x028 (0x40020028)"), "{why}");
    }
}
