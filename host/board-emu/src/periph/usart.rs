//! USART2, the host link: PA2/PA3 to the ST-LINK's virtual COM port, 921 600 baud 8N1.
//!
//! Models: SR (RXNE, TC, TXE, ORE; RXNE, TC, LBD, CTS are rc_w0; reading DR clears RXNE, ORE
//! and the error flags), DR (receive from the host FIFO at the configured byte rate, overrun
//! when the image is late; transmit through a holding and a shift register), BRR (checked
//! against `BAUD` ± `BAUD_TOLERANCE` whenever the USART is enabled), CR1 (UE, TE, RE and the
//! RXNE/TC/TXE interrupt enables), CR2, CR3, GTPR (latched). Refuses: a baud rate off by more
//! than `BAUD_TOLERANCE`, 8× oversampling, DR written with the transmitter off or while a byte
//! waits in the holding register; offsets from 0x1C on. Units: time in 1/720 MHz units, one
//! byte = 10 bit times at the configured rate. Invariants: no received byte is lost but by an
//! overrun (counted); the interrupt line is the level of the enabled flags.

use super::state::{Periph, Usart};

/// USART2 base address.
pub const BASE: u32 = 0x4000_4400;
/// Last modelled word address (GTPR).
pub const LAST: u32 = 0x4000_441B;

/// Baud rate the host link must run at.
pub const BAUD: f64 = 921_600.0;
/// Largest baud-rate error a UART tolerates against the ST-LINK.
pub const BAUD_TOLERANCE: f64 = 0.02;

/// USART_SR (register index, offset / 4).
const SR: usize = 0;
/// USART_DR.
const DR: usize = 1;
/// USART_BRR.
const BRR: usize = 2;
/// USART_CR1.
const CR1: usize = 3;
/// SR.RXNE.
const SR_RXNE: u32 = 1 << 5;
/// SR.TC.
const SR_TC: u32 = 1 << 6;
/// SR.TXE.
const SR_TXE: u32 = 1 << 7;
/// SR.ORE.
const SR_ORE: u32 = 1 << 3;
/// SR.PE, FE, NF (cleared with ORE by a DR read).
const SR_ERRORS: u32 = 0b111;
/// SR.LBD and CTS (rc_w0).
const SR_LBD_CTS: u32 = (1 << 8) | (1 << 9);
/// CR1.RE.
const CR1_RE: u32 = 1 << 2;
/// CR1.TE.
const CR1_TE: u32 = 1 << 3;
/// CR1.RXNEIE.
const CR1_RXNEIE: u32 = 1 << 5;
/// CR1.TCIE.
const CR1_TCIE: u32 = 1 << 6;
/// CR1.TXEIE.
const CR1_TXEIE: u32 = 1 << 7;
/// CR1.UE.
const CR1_UE: u32 = 1 << 13;
/// CR1.OVER8.
const CR1_OVER8: u32 = 1 << 15;

impl Usart {
    /// The registers at reset; the bytes in flight to and from the host survive.
    pub(super) fn reset(&mut self) {
        let rx = std::mem::take(&mut self.rx_fifo);
        let tx = std::mem::take(&mut self.tx_out);
        *self = Self::default();
        self.rx_fifo = rx;
        self.tx_out = tx;
        self.r[SR] = SR_TXE | SR_TC;
    }

    /// Whether CR1.UE is set.
    fn enabled(&self) -> bool {
        self.r[CR1] & CR1_UE != 0
    }

    /// Whether the receiver runs (UE and RE).
    fn receiving(&self) -> bool {
        self.enabled() && self.r[CR1] & CR1_RE != 0
    }

    /// The interrupt line: an enabled flag is set.
    pub(super) fn line(&self) -> bool {
        let cr1 = self.r[CR1];
        let sr = self.r[SR];
        (cr1 & CR1_RXNEIE != 0 && sr & (SR_RXNE | SR_ORE) != 0)
            || (cr1 & CR1_TXEIE != 0 && sr & SR_TXE != 0)
            || (cr1 & CR1_TCIE != 0 && sr & SR_TC != 0)
    }

    /// The next time something changes by itself.
    pub(super) fn next_event(&self) -> Option<u64> {
        let rx = (!self.rx_fifo.is_empty() && self.receiving()).then_some(self.rx_next);
        match (rx, self.tx_busy_until) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

/// Brings transmit and receive up to `now`.
pub(super) fn advance(p: &mut Periph, now: u64) {
    advance_tx(p, now);
    advance_rx(p, now);
}

/// Transmit: the shift register finishes, the holding register moves in.
fn advance_tx(p: &mut Periph, now: u64) {
    while let Some(end) = p.usart.tx_busy_until {
        if end > now {
            break;
        }
        match p.usart.tx_hold.take() {
            Some(b) => {
                p.usart.tx_out.push_back(b);
                p.usart.sent += 1;
                p.usart.r[SR] |= SR_TXE;
                p.usart.tx_busy_until = Some(end + p.byte_units());
            }
            None => {
                p.usart.tx_busy_until = None;
                p.usart.r[SR] |= SR_TC;
            }
        }
    }
}

/// Receive: the next host byte shifts into DR (or overruns it) once its time has come.
fn advance_rx(p: &mut Periph, now: u64) {
    let u = &p.usart;
    if u.receiving() && !u.rx_fifo.is_empty() && u.rx_next <= now {
        let byte_units = p.byte_units();
        let u = &mut p.usart;
        let b = u.rx_fifo.pop_front().expect("non-empty");
        if u.r[SR] & SR_RXNE != 0 {
            u.r[SR] |= SR_ORE;
            u.overruns += 1;
        } else {
            u.rx_dr = b;
            u.r[SR] |= SR_RXNE;
        }
        u.rx_next = now.max(u.rx_next) + byte_units;
    }
}

/// The latched value at `a` without side effects.
pub(super) fn peek(p: &Periph, a: u32) -> u32 {
    p.usart.r[((a & 0x1F) / 4) as usize]
}

/// A word read of a USART2 register; reading DR takes the received byte.
pub(super) fn read(p: &mut Periph, a: u32) -> u32 {
    let i = ((a - BASE) / 4) as usize;
    p.advance();
    if i == DR {
        let b = p.usart.rx_dr;
        p.usart.r[SR] &= !(SR_RXNE | SR_ORE | SR_ERRORS);
        u32::from(b)
    } else {
        p.usart.r[i]
    }
}

/// A word write of a USART2 register.
pub(super) fn write(p: &mut Periph, a: u32, v: u32) {
    let i = ((a - BASE) / 4) as usize;
    p.advance();
    match i {
        SR => {
            // rc_w0 bits: RXNE, TC, LBD, CTS.
            let keep = v | !(SR_RXNE | SR_TC | SR_LBD_CTS);
            p.usart.r[SR] &= keep;
        }
        DR => transmit(p, v as u8),
        BRR => {
            p.usart.r[BRR] = v;
            if p.usart.enabled() {
                p.check_baud();
            }
        }
        CR1 => {
            p.usart.r[CR1] = v;
            if v & CR1_UE != 0 {
                p.check_baud();
            }
        }
        _ => p.usart.r[i] = v,
    }
}

/// A byte written to DR: into the shift register if idle, else into the holding register.
fn transmit(p: &mut Periph, b: u8) {
    let u = &p.usart;
    if !u.enabled() || u.r[CR1] & CR1_TE == 0 {
        p.fail("USART2_DR written with the transmitter off (CR1.UE/TE = 0)".into());
        return;
    }
    let byte_units = p.byte_units();
    let u = &mut p.usart;
    u.r[SR] &= !SR_TC;
    match u.tx_busy_until {
        None => {
            u.tx_out.push_back(b);
            u.sent += 1;
            u.tx_busy_until = Some(p.now + byte_units);
        }
        Some(_) => {
            // Writing DR while TXE = 0 overwrites the holding register on the chip.
            let lost = u.tx_hold.replace(b).is_some();
            u.r[SR] &= !SR_TXE;
            if lost {
                p.fail("USART2_DR written while TXE = 0: a byte would be lost".into());
            }
        }
    }
}

impl Periph {
    /// The USART2 byte time (10 bits at the configured rate), units.
    fn byte_units(&self) -> u64 {
        let brr = self.usart.r[BRR].max(16);
        let baud = self.clocks().pclk1 * 16.0 / f64::from(brr) / 16.0;
        Self::units(baud / 10.0)
    }

    /// Checks BRR against the host link's rate at the current PCLK1.
    fn check_baud(&mut self) {
        let brr = self.usart.r[BRR];
        let pclk1 = self.clocks().pclk1;
        let over8 = self.usart.r[CR1] & CR1_OVER8 != 0;
        if over8 {
            self.fail("USART2_CR1.OVER8: 8x oversampling is not modelled".into());
            return;
        }
        let baud = if brr == 0 {
            0.0
        } else {
            pclk1 / f64::from(brr)
        };
        let err = baud / BAUD - 1.0;
        if err.abs() > BAUD_TOLERANCE {
            let lo = (pclk1 / (BAUD * (1.0 + BAUD_TOLERANCE))).ceil();
            let hi = (pclk1 / (BAUD * (1.0 - BAUD_TOLERANCE))).floor();
            self.fail(format!(
                "USART2_BRR = {brr:#x} gives {baud:.0} baud at PCLK1 {:.1} MHz ({:+.2} %): the \
                 host link needs 921600 baud +/- 2 % (BRR {lo:.0}..={hi:.0})",
                pclk1 / 1e6,
                100.0 * err
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::periph::state::Periph;
    use crate::plant::Coupling;
    use crate::plant::UNITS_PER_S;

    #[test]
    fn transmit_holds_one_byte_and_refuses_to_lose_a_second() {
        let mut p = Periph::new(Coupling::new(None));
        p.write(0x4000_440C, 4, (1 << 13) | (1 << 3)); // UE, TE
        p.stop = None; // the reset clock gives no valid baud rate: not the point here
        p.write(0x4000_4404, 4, u64::from(b'a'));
        let sr = p.read(0x4000_4400, 4);
        assert_eq!(
            sr & ((1 << 6) | (1 << 7)),
            1 << 7,
            "TXE set, TC clear while shifting"
        );
        p.write(0x4000_4404, 4, u64::from(b'b'));
        assert_eq!(p.read(0x4000_4400, 4) & (1 << 7), 0, "TXE clear: b waits");
        assert!(p.stop.is_none(), "{:?}", p.stop);
        p.write(0x4000_4404, 4, u64::from(b'c'));
        let why = p.stop.take().expect("overwriting the holding register");
        assert!(why.contains("a byte would be lost"), "{why}");
        // Three byte times at the reset BRR (PCLK1 / 16 = 1 Mbaud, 10 µs a byte).
        p.now += 3 * UNITS_PER_S / 100_000;
        p.advance();
        assert_eq!(p.usart.tx_out.iter().copied().collect::<Vec<_>>(), b"ac");
        assert_eq!(p.usart.sent, 2);
        let sr = p.read(0x4000_4400, 4);
        assert_eq!(
            sr & ((1 << 6) | (1 << 7)),
            (1 << 6) | (1 << 7),
            "TXE and TC"
        );
    }

    #[test]
    fn a_byte_not_read_in_time_is_an_overrun() {
        let mut p = Periph::new(Coupling::new(None));
        p.write(0x4000_440C, 4, (1 << 13) | (1 << 2)); // UE, RE
        p.stop = None;
        p.usart.rx_fifo.extend(b"xy");
        p.advance();
        assert_eq!(p.read(0x4000_4400, 4) & (1 << 5), 1 << 5, "RXNE");
        p.now += UNITS_PER_S / 1000;
        p.advance();
        assert_eq!(p.usart.overruns, 1);
        assert_eq!(p.read(0x4000_4404, 4), u64::from(b'x'));
        assert_eq!(
            p.read(0x4000_4400, 4) & ((1 << 5) | (1 << 3)),
            0,
            "a DR read clears RXNE and ORE"
        );
    }
}
