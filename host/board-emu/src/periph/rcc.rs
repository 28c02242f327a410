//! RCC and PWR: the clock tree (HSI 16 MHz, HSE bypass 8 MHz from the ST-LINK, the main PLL,
//! the AHB/APB prescalers), the peripheral clock enables and resets, and PWR's over-drive.
//!
//! Models: RCC_CR (ready bits follow their enables), PLLCFGR, CFGR (SWS follows SW), the reset,
//! enable and low-power enable registers (latched; a USART2RST pulse resets USART2), BDCR, CSR
//! (LSIRDY follows LSION), PLLI2SCFGR, PLLSAICFGR, DCKCFGR, DCKCFGR2; PWR_CR (VOSRDY, ODRDY and
//! ODSWRDY follow at once) and PWR_CSR.EWUP. Refuses: any other RCC register, HSE without
//! bypass, an HCLK above 180 MHz or above 168 MHz without over-drive, fewer flash wait states
//! than RM0390 Table 5 asks for at the new HCLK. Units: clocks in Hz; time in 1/720 MHz units.
//! Invariant: the CPU's cycle time (`Periph::cpu_units`) follows HCLK whenever CFGR changes.

use super::flash;
use super::state::Periph;
use crate::plant::UNITS_PER_S;

/// RCC base address.
pub const BASE: u32 = 0x4002_3800;
/// Last word address of the RCC block.
pub const LAST: u32 = 0x4002_38FF;
/// PWR_CR address.
pub const PWR_CR: u32 = 0x4000_7000;
/// PWR_CSR address.
pub const PWR_CSR: u32 = 0x4000_7004;

/// RCC_CR (register index, offset / 4; offset 0x00).
const CR: usize = 0;
/// RCC_PLLCFGR (offset 0x04).
const PLLCFGR: usize = 1;
/// RCC_CFGR.
const CFGR: usize = 0x08 / 4;
/// RCC_APB1RSTR.
const APB1RSTR: usize = 0x20 / 4;
/// RCC_AHB1ENR (GPIO port clocks, bit n = port n).
pub(super) const AHB1ENR: usize = 0x30 / 4;
/// RCC_CSR.
const CSR: usize = 0x74 / 4;
/// RCC_PLLI2SCFGR.
const PLLI2SCFGR: usize = 0x84 / 4;
/// RCC_PLLSAICFGR.
const PLLSAICFGR: usize = 0x88 / 4;
/// APB1RSTR.USART2RST.
const USART2RST: u32 = 1 << 17;
/// RCC_CR.HSEON.
const CR_HSEON: u32 = 1 << 16;
/// RCC_CR.HSEBYP.
const CR_HSEBYP: u32 = 1 << 18;
/// RCC_CR ready bits (HSIRDY, HSERDY, PLLRDY, PLLI2SRDY, PLLSAIRDY), each one above its enable.
const CR_READY: u32 = (1 << 1) | (1 << 17) | (1 << 25) | (1 << 27) | (1 << 29);
/// RCC_CR enable bits (HSION, HSEON, PLLON, PLLI2SON, PLLSAION).
const CR_ENABLES: [u32; 5] = [0, 16, 24, 26, 28];

/// PWR_CR index.
const PWR_CR_I: usize = 0;
/// PWR_CSR index.
const PWR_CSR_I: usize = 1;
/// PWR_CSR.VOSRDY.
const PWR_VOSRDY: u32 = 1 << 14;
/// PWR_CR.ODEN and ODSWEN (bits 16, 17) = PWR_CSR.ODRDY and ODSWRDY.
const PWR_OD: u32 = 3 << 16;
/// PWR_CSR.ODSWRDY.
const PWR_ODSWRDY: u32 = 1 << 17;
/// PWR_CSR.EWUP.
const PWR_EWUP: u32 = 1 << 8;

/// HSI frequency, Hz.
const HSI_HZ: f64 = 16e6;
/// HSE frequency (the ST-LINK's MCO), Hz.
const HSE_HZ: f64 = 8e6;
/// Time units per CPU cycle at reset (HSI).
pub(super) const RESET_CPU_UNITS: u64 = UNITS_PER_S / 16_000_000;

/// The clock tree as configured, Hz.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clocks {
    /// SYSCLK = HCLK (AHB prescaler 1 is checked).
    pub sysclk: f64,
    /// HCLK.
    pub hclk: f64,
    /// APB1 clock.
    pub pclk1: f64,
    /// APB2 clock.
    pub pclk2: f64,
    /// APB1 timer clock.
    pub tim1clk_apb1: f64,
    /// APB2 timer clock.
    pub timclk_apb2: f64,
}

/// RCC and PWR at reset.
pub(super) fn reset(p: &mut Periph) {
    p.rcc = [0; 0x40];
    p.rcc[CR] = 0x0000_0083;
    p.rcc[PLLCFGR] = 0x2400_3010;
    p.rcc[PLLI2SCFGR] = 0x2400_3000;
    p.rcc[PLLSAICFGR] = 0x2400_3000;
    p.rcc[CSR] = 0x0E00_0000;
    p.pwr = [0x0000_C000, 0];
}

/// Whether RCC register `i` can be read.
fn readable(i: usize) -> bool {
    matches!(i, 0..=4 | 8..=0x11 | 0x14..=0x15 | 0x1C..=0x1D | 0x21 | 0x22 | 0x23 | 0x25)
}

/// Whether RCC register `i` is a plain latch on writes (resets, enables, BDCR, CSR, PLLs).
fn latched(i: usize) -> bool {
    matches!(
        i,
        3 | 4 | 5 | 8 | 9 | 0xC..=0x11 | 0x14 | 0x15 | 0x1C | 0x1D | 0x21 | 0x22 | 0x23 | 0x25
    )
}

/// A word read in the RCC block.
pub(super) fn read(p: &mut Periph, a: u32) -> u32 {
    let i = ((a - BASE) / 4) as usize;
    if readable(i) {
        p.rcc[i]
    } else {
        p.unmodelled(a, None);
        0
    }
}

/// A word write in the RCC block.
pub(super) fn write(p: &mut Periph, a: u32, v: u32, raw: u64) {
    let i = ((a - BASE) / 4) as usize;
    match i {
        CR => write_cr(p, v),
        PLLCFGR => p.rcc[PLLCFGR] = v,
        CFGR => {
            // SWS (bits 3:2) follows SW (bits 1:0).
            p.rcc[CFGR] = (v & !0xC) | ((v & 3) << 2);
            p.clock_changed();
        }
        _ if latched(i) => write_latched(p, i, v),
        _ => p.unmodelled(a, Some(raw)),
    }
}

/// RCC_CR: ready bits follow their enables (HSI 0/1, HSE 16/17, PLL 24/25, PLLI2S 26/27,
/// PLLSAI 28/29); HSE needs bypass.
fn write_cr(p: &mut Periph, v: u32) {
    let mut r = v & !CR_READY;
    for en in CR_ENABLES {
        if v & (1 << en) != 0 {
            r |= 1 << (en + 1);
        }
    }
    if v & CR_HSEON != 0 && v & CR_HSEBYP == 0 {
        p.fail(
            "RCC_CR: HSE enabled without HSEBYP (bit 18): the Nucleo's HSE \
             is the ST-LINK's 8 MHz MCO, which needs bypass mode"
                .into(),
        );
    }
    p.rcc[CR] = r;
}

/// A latched RCC register: a peripheral reset pulse restores that peripheral's registers.
fn write_latched(p: &mut Periph, i: usize, v: u32) {
    let old = p.rcc[i];
    p.rcc[i] = v;
    if i == APB1RSTR && v & !old & USART2RST != 0 {
        p.usart.reset();
    }
    if i == CSR {
        // CSR: LSIRDY follows LSION; RMVF clears the reset flags.
        p.rcc[i] = (v & !2) | ((v & 1) << 1);
    }
}

/// A word read of PWR_CR or PWR_CSR.
pub(super) fn pwr_read(p: &mut Periph, a: u32) -> u32 {
    if a == PWR_CR {
        p.pwr[PWR_CR_I]
    } else {
        p.pwr[PWR_CSR_I]
    }
}

/// A word write of PWR_CR or PWR_CSR.
pub(super) fn pwr_write(p: &mut Periph, a: u32, v: u32) {
    if a == PWR_CR {
        p.pwr[PWR_CR_I] = v;
        // ODRDY (16) follows ODEN (16), ODSWRDY (17) follows ODSWEN (17); VOSRDY (14).
        p.pwr[PWR_CSR_I] = PWR_VOSRDY | (v & PWR_OD);
    } else {
        p.pwr[PWR_CSR_I] = (p.pwr[PWR_CSR_I] & !PWR_EWUP) | (v & PWR_EWUP);
    }
}

impl Periph {
    /// The clock tree from RCC.
    pub fn clocks(&self) -> Clocks {
        let cfgr = self.rcc[CFGR];
        let pll = self.rcc[PLLCFGR];
        let sws = (cfgr >> 2) & 3;
        let src_in = if pll & (1 << 22) != 0 { HSE_HZ } else { HSI_HZ };
        let m = f64::from((pll & 0x3F).max(1));
        let n = f64::from((pll >> 6) & 0x1FF);
        let p = f64::from(2 * (((pll >> 16) & 3) + 1));
        let sysclk = match sws {
            0 => HSI_HZ,
            1 => HSE_HZ,
            _ => src_in / m * n / p,
        };
        let hpre = (cfgr >> 4) & 0xF;
        let hclk = if hpre < 8 {
            sysclk
        } else {
            sysclk / f64::from([2, 4, 8, 16, 64, 128, 256, 512][(hpre - 8) as usize])
        };
        let apb = |bits: u32| {
            if bits < 4 {
                1.0
            } else {
                f64::from(1 << (bits - 3))
            }
        };
        let d1 = apb((cfgr >> 10) & 7);
        let d2 = apb((cfgr >> 13) & 7);
        Clocks {
            sysclk,
            hclk,
            pclk1: hclk / d1,
            pclk2: hclk / d2,
            tim1clk_apb1: if d1 == 1.0 { hclk } else { 2.0 * hclk / d1 },
            timclk_apb2: if d2 == 1.0 { hclk } else { 2.0 * hclk / d2 },
        }
    }

    /// Time units per period of a clock at `hz` (at least 1).
    pub(super) fn units(hz: f64) -> u64 {
        (UNITS_PER_S as f64 / hz).round().max(1.0) as u64
    }

    /// Units per APB1 timer clock.
    pub fn apb1_timer_units(&self) -> u64 {
        Self::units(self.clocks().tim1clk_apb1)
    }

    /// Units per APB2 timer clock.
    pub(super) fn apb2_timer_units(&self) -> u64 {
        Self::units(self.clocks().timclk_apb2)
    }

    /// Called when RCC_CFGR changes: the CPU clock and the flash wait states it needs.
    fn clock_changed(&mut self) {
        let c = self.clocks();
        self.cpu_units = Self::units(c.hclk);
        // RM0390 Table 5 (2.7–3.6 V): one wait state per 30 MHz of HCLK.
        let needed = ((c.hclk / 30e6).ceil() as u32).saturating_sub(1);
        let latency = flash::latency(self);
        if latency < needed {
            self.fail(format!(
                "FLASH_ACR.LATENCY = {latency} wait states at HCLK {:.1} MHz: needs at least \
                 {needed} (RM0390 Table 5, 2.7-3.6 V)",
                c.hclk / 1e6
            ));
        }
        if c.hclk > 180e6 * 1.0001 {
            self.fail(format!(
                "RCC: HCLK {:.1} MHz exceeds the STM32F446's 180 MHz (RCC_PLLCFGR {:#010x})",
                c.hclk / 1e6,
                self.rcc[PLLCFGR]
            ));
        }
        if c.hclk > 168e6 && self.pwr[PWR_CSR_I] & PWR_ODSWRDY == 0 {
            self.fail(format!(
                "RCC: HCLK {:.1} MHz above 168 MHz needs over-drive (PWR_CR.ODEN/ODSWEN)",
                c.hclk / 1e6
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::Coupling;

    #[test]
    fn ready_bits_follow_enables_and_the_baud_rate_is_checked() {
        let mut p = Periph::new(Coupling::new(None));
        p.write(0x4002_3800, 4, (1 << 16) | (1 << 18) | (1 << 24));
        let cr = p.read(0x4002_3800, 4) as u32;
        assert!(cr & (1 << 17) != 0 && cr & (1 << 25) != 0, "{cr:#x}");
        p.write(0x4002_3808, 4, 2);
        assert_eq!((p.read(0x4002_3808, 4) >> 2) & 3, 2, "SWS follows SW");
        p.stop = None; // SYSCLK from the reset PLL config: not the point here
        p.write(0x4000_4408, 4, 0x11);
        p.write(0x4000_440C, 4, 1 << 13);
        let why = p.stop.take().expect("a bad BRR stops the run");
        assert!(why.contains("USART2_BRR = 0x11"), "{why}");
    }
}
