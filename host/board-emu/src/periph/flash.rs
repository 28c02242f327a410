//! The embedded flash interface (FLASH_ACR, KEYR, SR, CR) and the config store it programs:
//! sectors 6–7 (0x0804_0000..0x0808_0000, 2 × 128 KiB), the image's settings across resets.
//!
//! Models: ACR (latency and the cache enables; the cache-reset bits read 0), the KEYR unlock
//! sequence (`KEY1` then `KEY2`), SR (rc_w1 flags EOP, OPERR, WRPERR, PGAERR, PGPERR, PGSERR, RDERR),
//! CR (LOCK, PG, PSIZE, SER/SNB with STRT), and the store with NOR semantics: erase sets 0xFF
//! and stalls the core `ERASE_S`, programming only clears bits, needs PG on an unlocked
//! controller, an access of PSIZE and an aligned address, and stalls the core `PROGRAM_S` per
//! word. Refuses: OPTKEYR and OPTCR, a wrong key sequence, CR written while locked, a mass
//! erase, erasing any sector but 6 and 7, programming without PG. Units: stall time in
//! 1/720 MHz units; store offsets in bytes from the start of sector 6.

use super::state::Periph;
use crate::plant::UNITS_PER_S;
use crate::trace;

/// FLASH interface base address.
pub const BASE: u32 = 0x4002_3C00;
/// Last word address of the modelled registers (OPTCR).
pub const LAST: u32 = 0x4002_3C17;

/// FLASH_ACR (register index, offset / 4).
const ACR: usize = 0;
/// FLASH_SR.
const SR: usize = 3;
/// FLASH_CR.
const CR: usize = 4;
/// Offsets of the registers.
const ACR_OFF: u32 = 0x00;
const KEYR_OFF: u32 = 0x04;
const SR_OFF: u32 = 0x0C;
const CR_OFF: u32 = 0x10;

/// First key of the FLASH_KEYR unlock sequence.
pub const KEY1: u32 = 0x4567_0123;
/// Second key of the FLASH_KEYR unlock sequence.
pub const KEY2: u32 = 0xCDEF_89AB;

/// FLASH_ACR.LATENCY (wait states).
const ACR_LATENCY: u32 = 0xF;
/// FLASH_ACR.ICRST and DCRST (write-only, read 0).
const ACR_CACHE_RESETS: u32 = (1 << 11) | (1 << 12);
/// FLASH_SR: the rc_w1 flags.
const SR_FLAGS: u32 = 0x1F3;
/// FLASH_SR.EOP.
const SR_EOP: u32 = 1;
/// FLASH_SR.PGAERR.
const SR_PGAERR: u32 = 1 << 5;
/// FLASH_SR.PGPERR.
const SR_PGPERR: u32 = 1 << 6;
/// FLASH_CR.PG.
const CR_PG: u32 = 1;
/// FLASH_CR.SER.
const CR_SER: u32 = 1 << 1;
/// FLASH_CR.MER.
const CR_MER: u32 = 1 << 2;
/// FLASH_CR.STRT.
const CR_STRT: u32 = 1 << 16;
/// FLASH_CR.LOCK.
const CR_LOCK: u32 = 1 << 31;

/// Flash config-store sectors: (number, start, length).
pub const STORE_SECTORS: [(u32, u32, u32); 2] =
    [(6, 0x0804_0000, 0x2_0000), (7, 0x0806_0000, 0x2_0000)];
/// Bytes in the config store (sectors 6 and 7).
pub const STORE_LEN: usize = 0x4_0000;
/// Sector erase time at x32 parallelism (RM0390/datasheet typical 128 KiB), seconds.
pub const ERASE_S: f64 = 1.0;
/// Word program time, seconds (datasheet typical x32).
pub const PROGRAM_S: f64 = 16e-6;

/// The flash interface at reset: locked, PSIZE x8, no operation pending.
pub(super) fn reset(p: &mut Periph) {
    p.flash = [0, 0, 0, 0, 0x8000_0000, 0x0FFF_AAED];
    p.flash_key = 0;
}

/// FLASH_ACR.LATENCY: the wait states configured.
pub(super) fn latency(p: &Periph) -> u32 {
    p.flash[ACR] & ACR_LATENCY
}

/// A word read of a flash interface register.
pub(super) fn read(p: &mut Periph, a: u32) -> u32 {
    p.flash[((a - BASE) / 4) as usize]
}

/// A word write of a flash interface register.
pub(super) fn write(p: &mut Periph, a: u32, v: u32, raw: u64) {
    match a - BASE {
        ACR_OFF => p.flash[ACR] = v & !ACR_CACHE_RESETS,
        KEYR_OFF => write_key(p, v),
        SR_OFF => p.flash[SR] &= !(v & SR_FLAGS),
        CR_OFF => write_cr(p, v),
        // OPTKEYR, OPTCR: the option bytes are not modelled.
        _ => p.unmodelled(a, Some(raw)),
    }
}

/// FLASH_KEYR: `KEY1` then `KEY2` unlocks FLASH_CR; anything else would lock it until reset.
fn write_key(p: &mut Periph, v: u32) {
    p.flash_key = match (p.flash_key, v) {
        (0, KEY1) => 1,
        (1, KEY2) => {
            p.flash[CR] &= !CR_LOCK;
            0
        }
        _ => {
            p.fail(format!(
                "FLASH_KEYR: wrong unlock sequence (wrote {v:#010x}; allowed \
                 0x45670123 then 0xCDEF89AB): the flash would lock until reset"
            ));
            0
        }
    };
}

/// FLASH_CR: needs an unlocked controller (or sets LOCK); STRT starts a sector erase.
fn write_cr(p: &mut Periph, v: u32) {
    let locked = p.flash[CR] & CR_LOCK != 0;
    if locked && v & CR_LOCK == 0 {
        p.fail(format!(
            "FLASH_CR written while locked ({v:#010x}); unlock with FLASH_KEYR first"
        ));
        return;
    }
    p.flash[CR] = v & !CR_STRT;
    if v & CR_STRT != 0 {
        // STRT: a sector erase (SER) or mass erase (MER).
        if v & CR_MER != 0 {
            p.fail("FLASH_CR.MER: a mass erase would destroy the image".into());
            return;
        }
        if v & CR_SER != 0 {
            erase_sector(p, (v >> 3) & 0xF);
        }
    }
}

/// Erases sector `snb` if it is one of the config store's; stalls the core for the erase.
fn erase_sector(p: &mut Periph, snb: u32) {
    match STORE_SECTORS.iter().find(|s| s.0 == snb) {
        Some(&(_, start, len)) => {
            let at = (start - STORE_SECTORS[0].1) as usize;
            p.store[at..at + len as usize].fill(0xFF);
            p.erases += 1;
            if trace::enabled() {
                eprintln!(
                    "flash: erase sector {snb} at {:.6} s",
                    p.now as f64 / UNITS_PER_S as f64
                );
            }
            p.stall += (ERASE_S * UNITS_PER_S as f64) as u64;
            p.stalled_total += (ERASE_S * UNITS_PER_S as f64) as u64;
            p.flash[SR] |= SR_EOP;
        }
        None => p.fail(format!(
            "FLASH_CR.SNB = {snb}: erasing that sector would destroy the image \
             (allowed: 6, 7, the config store)"
        )),
    }
}

impl Periph {
    /// Reads the config store (sectors 6–7) at `offset`.
    pub fn store_read(&self, offset: u32, size: usize) -> u64 {
        let at = offset as usize;
        let mut buf = [0u8; 8];
        buf[..size].copy_from_slice(&self.store[at..at + size]);
        u64::from_le_bytes(buf)
    }

    /// A program access to the config store: needs PG and an unlocked controller; programming
    /// only clears bits (NOR); the word size must match PSIZE.
    pub fn store_write(&mut self, offset: u32, size: usize, v: u64) {
        let addr = STORE_SECTORS[0].1 + offset;
        let cr = self.flash[CR];
        if cr & CR_LOCK != 0 || cr & CR_PG == 0 {
            self.fail(format!(
                "write of {v:#x} to flash {addr:#010x} without FLASH_CR.PG set on an unlocked \
                 controller (FLASH_CR = {cr:#010x})"
            ));
            return;
        }
        let psize = 1usize << ((cr >> 8) & 3);
        if size != psize {
            // PGPERR on the chip.
            self.flash[SR] |= SR_PGPERR;
            return;
        }
        if !(offset as usize).is_multiple_of(size) {
            self.flash[SR] |= SR_PGAERR;
            return;
        }
        for i in 0..size {
            let b = &mut self.store[offset as usize + i];
            *b &= (v >> (8 * i)) as u8;
        }
        self.programs += 1;
        self.stall += (PROGRAM_S * UNITS_PER_S as f64) as u64;
        self.stalled_total += (PROGRAM_S * UNITS_PER_S as f64) as u64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::Coupling;

    #[test]
    fn flash_store_is_nor_and_needs_pg() {
        let mut p = Periph::new(Coupling::new(None));
        p.store_write(0, 4, 0);
        assert!(
            p.stop.take().is_some(),
            "programming without PG on a locked controller"
        );
        p.write(0x4002_3C04, 4, 0x4567_0123);
        p.write(0x4002_3C04, 4, 0xCDEF_89AB);
        p.write(0x4002_3C10, 4, (2 << 8) | 1);
        p.store_write(0, 4, 0xFFFF_00F0);
        p.store_write(0, 4, 0x0F0F_FFFF);
        assert_eq!(
            p.store_read(0, 4),
            0x0F0F_00F0,
            "programming only clears bits"
        );
        p.write(0x4002_3C10, 4, (2 << 8) | (6 << 3) | 2 | (1 << 16));
        assert_eq!(p.store_read(0, 4), 0xFFFF_FFFF, "erase sets 0xFF");
        p.write(0x4002_3C10, 4, (2 << 8) | (3 << 3) | 2 | (1 << 16));
        let why = p
            .stop
            .take()
            .expect("erasing an image sector stops the run");
        assert!(why.contains("FLASH_CR.SNB = 3"), "{why}");
    }
}
