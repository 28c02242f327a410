//! Config storage in two 128 KiB flash sectors: slot 0 = sector 6 at 0x0804_0000, slot 1 =
//! sector 7 at 0x0806_0000 (the linker script keeps the image below 0x0804_0000).
//!
//! Units: byte offsets within a slot, `SLOT_LEN` bytes each. Flash reads as 0xFF after an erase;
//! programming can only clear bits, so a slot is erased as a whole before it is rewritten. This
//! driver programs 32-bit words (PSIZE = x32, valid at VDD 2.7–3.6 V, the Nucleo's 3.3 V), which
//! makes a sector erase about twice as fast as the HAL's x8 path (typ. 1 s instead of 2 s for
//! 128 KiB). Invariants: offsets and lengths are bounds-checked (an out-of-range request is an
//! error, never a write elsewhere); the flash is locked again after every operation; the data
//! cache is reset after an erase and after programming so reads never return stale bytes.
//!
//! The two-slot scheme itself (sequence numbers, CRC, which slot is newer, writing the older
//! one) belongs to the firmware core: a half-written slot (power cut during a save) fails its
//! CRC and the other slot is used.
//!
//! Timing caveat: while a sector erases or a word programs, every instruction fetch from flash
//! stalls, interrupt handlers included (they live in flash). The servo tick and the serial
//! receiver therefore stop for up to ~1–2 s during an erase. `ConfigStorage::write` holds the
//! force output at zero with the amplifier disabled for the whole save (`force::inhibit`) and
//! stretches the watchdog for the erase; the host waits for the save's reply.
//!
//! Errors: [`FlashError`] implements `embedded-storage`'s `NorFlashError`, so its kind
//! (out of bounds, not aligned, other) reaches the firmware core as `StorageError::Flash`.

use embedded_storage::nor_flash::{NorFlashError, NorFlashErrorKind};
use stm32f4xx_hal::pac::FLASH;

/// Number of slots.
pub const SLOTS: usize = 2;
/// Bytes per slot (one 128 KiB sector each).
pub const SLOT_LEN: usize = 128 * 1024;
/// Memory-mapped start address of each slot.
pub const SLOT_ADDR: [usize; SLOTS] = [0x0804_0000, 0x0806_0000];
/// Flash sector number of each slot.
const SLOT_SECTOR: [u8; SLOTS] = [6, 7];

const KEY1: u32 = 0x4567_0123;
const KEY2: u32 = 0xCDEF_89AB;

/// Programming alignment and parallelism errors (PGAERR, PGPERR) in FLASH_SR.
const SR_ALIGNMENT: u32 = 0b110_0000;

/// What can go wrong with a flash operation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FlashError {
    /// Slot index, offset or length outside the slot.
    OutOfRange,
    /// A program offset not 4-byte aligned.
    NotAligned,
    /// The flash controller reported an error (its SR error bits).
    Hardware(u32),
}

impl NorFlashError for FlashError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            FlashError::OutOfRange => NorFlashErrorKind::OutOfBounds,
            FlashError::NotAligned => NorFlashErrorKind::NotAligned,
            FlashError::Hardware(sr) if sr & SR_ALIGNMENT != 0 => NorFlashErrorKind::NotAligned,
            FlashError::Hardware(_) => NorFlashErrorKind::Other,
        }
    }
}

/// The two config slots. One instance (owns the FLASH controller).
pub struct FlashSlots {
    flash: FLASH,
}

impl FlashSlots {
    pub fn new(flash: FLASH) -> Self {
        Self { flash }
    }

    /// The whole slot as a byte slice (memory-mapped, read-only).
    pub fn slot(&self, slot: usize) -> Result<&[u8], FlashError> {
        let addr = *SLOT_ADDR.get(slot).ok_or(FlashError::OutOfRange)?;
        // SAFETY: `addr..addr + SLOT_LEN` is one whole flash sector of the STM32F446RE, always
        // mapped and readable; it is outside the image (memory.x), and it only changes through
        // `&mut self` methods, so it can't change while this shared borrow lives.
        Ok(unsafe { core::slice::from_raw_parts(addr as *const u8, SLOT_LEN) })
    }

    /// Copies `buf.len()` bytes from `offset` in `slot`.
    pub fn read(&self, slot: usize, offset: usize, buf: &mut [u8]) -> Result<(), FlashError> {
        let src = self.slot(slot)?;
        let end = offset
            .checked_add(buf.len())
            .ok_or(FlashError::OutOfRange)?;
        buf.copy_from_slice(src.get(offset..end).ok_or(FlashError::OutOfRange)?);
        Ok(())
    }

    /// Erases a whole slot (all bytes read 0xFF afterwards). Stalls the CPU for ~1–2 s.
    pub fn erase(&mut self, slot: usize) -> Result<(), FlashError> {
        let sector = *SLOT_SECTOR.get(slot).ok_or(FlashError::OutOfRange)?;
        self.unlock();
        self.wait_idle();
        self.clear_errors();
        self.flash.cr().modify(|_, w| {
            w.pg().clear_bit();
            w.psize().psize32();
            // SAFETY: SNB accepts any 4-bit value; `sector` is 6 or 7, both present on this part.
            unsafe { w.snb().bits(sector) };
            w.ser().set_bit()
        });
        self.flash.cr().modify(|_, w| w.strt().set_bit());
        self.wait_idle();
        let result = self.check();
        self.flash.cr().modify(|_, w| w.ser().clear_bit());
        self.lock();
        self.reset_data_cache();
        result
    }

    /// Programs `data` at `offset` (4-byte aligned) in an erased part of `slot`. A trailing
    /// partial word is padded with 0xFF (erased state), so it can still be read back exactly.
    pub fn program(&mut self, slot: usize, offset: usize, data: &[u8]) -> Result<(), FlashError> {
        let base = *SLOT_ADDR.get(slot).ok_or(FlashError::OutOfRange)?;
        let end = offset
            .checked_add(data.len())
            .ok_or(FlashError::OutOfRange)?;
        if !offset.is_multiple_of(4) {
            return Err(FlashError::NotAligned);
        }
        if end > SLOT_LEN {
            return Err(FlashError::OutOfRange);
        }
        self.unlock();
        self.wait_idle();
        self.clear_errors();
        self.flash.cr().modify(|_, w| {
            w.ser().clear_bit();
            w.psize().psize32();
            w.pg().set_bit()
        });
        let mut result = Ok(());
        for (i, chunk) in data.chunks(4).enumerate() {
            let mut word = [0xFF_u8; 4];
            word[..chunk.len()].copy_from_slice(chunk);
            let addr = base + offset + 4 * i;
            // SAFETY: `addr` is word aligned and inside the slot's sector (bounds checked above),
            // never inside the running image; PG is set, so this write programs one flash word.
            unsafe { core::ptr::write_volatile(addr as *mut u32, u32::from_le_bytes(word)) };
            self.wait_idle();
            result = self.check();
            if result.is_err() {
                break;
            }
        }
        self.flash.cr().modify(|_, w| w.pg().clear_bit());
        self.lock();
        // Lines of this slot read before programming (e.g. by `is_blank`) may still be cached.
        self.reset_data_cache();
        result
    }

    /// Whether every byte of `slot` reads 0xFF (erased).
    pub fn is_blank(&self, slot: usize) -> Result<bool, FlashError> {
        let bytes = self.slot(slot)?;
        // Word-sized compares: the slot is 4-byte aligned and a multiple of 4 long.
        Ok(bytes.chunks_exact(4).all(|w| w == [0xFF; 4]))
    }

    /// Erases `slot` and programs `data` from offset 0 (the core's `ConfigStorage::write`).
    pub fn rewrite(&mut self, slot: usize, data: &[u8]) -> Result<(), FlashError> {
        if data.len() > SLOT_LEN {
            return Err(FlashError::OutOfRange);
        }
        // A blank slot (first save on a fresh board) needs no erase: skip the 1–2 s stall.
        if !self.is_blank(slot)? {
            crate::watchdog::stretch_for_flash();
            let erased = self.erase(slot);
            crate::watchdog::restore();
            erased?;
        }
        self.program(slot, 0, data)
    }

    fn unlock(&mut self) {
        if self.flash.cr().read().lock().bit_is_set() {
            self.flash.keyr().write(|w| w.key().set(KEY1));
            self.flash.keyr().write(|w| w.key().set(KEY2));
        }
    }

    fn lock(&mut self) {
        self.flash.cr().modify(|_, w| w.lock().set_bit());
    }

    fn wait_idle(&self) {
        while self.flash.sr().read().bsy().bit_is_set() {}
    }

    fn clear_errors(&mut self) {
        // The status bits are write-1-to-clear.
        self.flash.sr().write(|w| {
            w.eop().clear_bit_by_one();
            w.operr().clear_bit_by_one();
            w.wrperr().clear_bit_by_one();
            w.pgaerr().clear_bit_by_one();
            w.pgperr().clear_bit_by_one();
            w.pgserr().clear_bit_by_one()
        });
    }

    fn check(&self) -> Result<(), FlashError> {
        // OPERR, WRPERR, PGAERR, PGPERR, PGSERR, RDERR (RM0390 §3.8.4).
        const ERRORS: u32 = 0b1_1111_0010;
        let sr = self.flash.sr().read().bits();
        if sr & ERRORS != 0 {
            Err(FlashError::Hardware(sr & ERRORS))
        } else {
            Ok(())
        }
    }

    fn reset_data_cache(&mut self) {
        // RM0390 §3.5.2: the data cache must be disabled before it is reset.
        let dcen = self.flash.acr().read().dcen().bit_is_set();
        self.flash.acr().modify(|_, w| w.dcen().clear_bit());
        self.flash.acr().modify(|_, w| w.dcrst().set_bit());
        self.flash.acr().modify(|_, w| w.dcrst().clear_bit());
        if dcen {
            self.flash.acr().modify(|_, w| w.dcen().set_bit());
        }
    }
}

/// The firmware core's two-slot storage (`stiffwall_firmware::ConfigStore` adds the records,
/// generations and CRC). A write holds the force output at zero with the amplifier disabled for
/// as long as the flash is busy (`force::inhibit`), because the servo can't run meanwhile.
impl stiffwall_firmware::ConfigStorage for FlashSlots {
    fn slot_len(&self) -> usize {
        SLOT_LEN
    }

    fn read(
        &mut self,
        slot: usize,
        buf: &mut [u8],
    ) -> Result<(), stiffwall_firmware::StorageError> {
        FlashSlots::read(self, slot, 0, buf).map_err(stiffwall_firmware::StorageError::flash)
    }

    fn write(&mut self, slot: usize, data: &[u8]) -> Result<(), stiffwall_firmware::StorageError> {
        crate::force::inhibit(true);
        let result = self.rewrite(slot, data);
        crate::force::inhibit(false);
        match result {
            Ok(()) => crate::log::info!("config saved: slot {}, {} bytes", slot, data.len()),
            Err(e) => crate::log::error!("config save to slot {} failed: {}", slot, e),
        }
        result.map_err(stiffwall_firmware::StorageError::flash)
    }
}
