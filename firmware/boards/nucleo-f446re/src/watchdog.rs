//! Independent watchdog (IWDG, 32 kHz LSI): resets the MCU if the servo tick stops.
//!
//! Units: milliseconds (LSI nominal 32 kHz; the real LSI is 17–47 kHz, so a timeout is only
//! good to about −45 %/+90 %). Invariants: thread mode feeds it only when the servo tick counter
//! has advanced since the last feed, so a servo interrupt that hangs (thread mode starves) and a
//! servo timer that stops (ticks don't advance) both end in a reset within `TIMEOUT_MS`; after a
//! reset every output pin floats and the amplifier enable's pull-down turns the power stage off.
//! A flash sector erase stalls the CPU for up to 2 s, so `stretch_for_flash` lengthens the timeout
//! to `FLASH_TIMEOUT_MS` for the erase and `restore` shortens it again. Once started the IWDG
//! can't be stopped; it is frozen while a debugger halts the core (DBGMCU).

use stm32f4xx_hal::pac::{DBGMCU, IWDG};

/// Normal timeout: 100 servo periods at 1 kHz.
pub const TIMEOUT_MS: u32 = 100;
/// Timeout while a flash sector is being erased (max erase time 2 s at x32, plus margin).
pub const FLASH_TIMEOUT_MS: u32 = 4_000;

const LSI_HZ: u32 = 32_000;

/// The watchdog, owned by thread mode.
pub struct Watchdog {
    _iwdg: IWDG,
    last_tick: u32,
}

fn regs() -> &'static stm32f4xx_hal::pac::iwdg::RegisterBlock {
    // SAFETY: IWDG's registers are always mapped; every access below is a single write of a key
    // or of PR/RLR after the access key, from thread mode only (never from an interrupt), so no
    // two writers interleave.
    unsafe { &*IWDG::ptr() }
}

/// Programs prescaler and reload for `ms` (waits for a previous update to finish first).
fn configure(ms: u32) {
    // Prescaler /64 (PR = 4): 2 ms per count at 32 kHz, reload up to 4095 → up to 8.19 s.
    const PR: u8 = 4;
    const DIV: u32 = 64;
    let reload = (ms * (LSI_HZ / 1000) / DIV).clamp(1, 0xFFF) as u16;
    let iwdg = regs();
    while iwdg.sr().read().bits() & 0b11 != 0 {}
    iwdg.kr().write(|w| w.key().unlock());
    // SAFETY: PR = 4 is a valid prescaler code (0..=6).
    iwdg.pr().write(|w| unsafe { w.pr().bits(PR) });
    iwdg.rlr().write(|w| w.rl().set(reload));
    iwdg.kr().write(|w| w.key().feed());
}

impl Watchdog {
    /// Starts the watchdog with `TIMEOUT_MS`. It is frozen while a debugger halts the core.
    pub fn start(iwdg: IWDG, dbgmcu: &DBGMCU, servo_ticks: u32) -> Self {
        dbgmcu.apb1_fz().modify(|_, w| w.dbg_iwdg_stop().set_bit());
        // Start first: starting turns the LSI on, which the PR/RLR update needs to complete.
        regs().kr().write(|w| w.key().start());
        configure(TIMEOUT_MS);
        Self {
            _iwdg: iwdg,
            last_tick: servo_ticks,
        }
    }

    /// Feeds the watchdog if the servo has ticked since the last feed.
    #[inline]
    pub fn feed_if_ticking(&mut self, servo_ticks: u32) {
        if servo_ticks != self.last_tick {
            self.last_tick = servo_ticks;
            regs().kr().write(|w| w.key().feed());
        }
    }
}

/// Lengthens the timeout for a flash erase and feeds it (thread mode only).
pub fn stretch_for_flash() {
    configure(FLASH_TIMEOUT_MS);
}

/// Restores the normal timeout and feeds it (thread mode only).
pub fn restore() {
    configure(TIMEOUT_MS);
}
