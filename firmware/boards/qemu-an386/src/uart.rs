//! CMSDK APB UART0 of the mps2-an386 (QEMU), polled.
//!
//! Registers (docs/toolchain.md): DATA +0x00, STATE +0x04 (bit0 TX full, bit1 RX full),
//! CTRL +0x08 (bit0 TX enable, bit1 RX enable), BAUDDIV +0x10. QEMU's model has a one-byte
//! receive holding register, so the main loop must poll often enough: at the rates used here
//! (bytes arrive from a host through a pty, flow-controlled by QEMU's chardev, which only
//! offers a byte when the RX register is empty) no byte is lost.

use core::ptr::{read_volatile, write_volatile};

const BASE: usize = 0x4000_4000;
const DATA: *mut u32 = BASE as *mut u32;
const STATE: *mut u32 = (BASE + 0x04) as *mut u32;
const CTRL: *mut u32 = (BASE + 0x08) as *mut u32;
const BAUDDIV: *mut u32 = (BASE + 0x10) as *mut u32;

const STATE_TX_FULL: u32 = 1 << 0;
#[allow(dead_code)] // used once the protocol loop lands
const STATE_RX_FULL: u32 = 1 << 1;

/// The one UART0 of the board. Only one instance may exist (created once in `main`).
#[derive(Debug)]
pub struct Uart0 {
    _private: (),
}

impl Uart0 {
    /// Enables TX and RX. `bauddiv` is the clock divider (QEMU ignores the rate).
    pub fn new(bauddiv: u32) -> Self {
        // SAFETY: fixed MMIO addresses of the CMSDK UART0 on this machine; single owner.
        unsafe {
            write_volatile(BAUDDIV, bauddiv.max(16));
            write_volatile(CTRL, 0b11);
        }
        Self { _private: () }
    }

    /// Returns a received byte if one is waiting. Never blocks.
    pub fn read(&mut self) -> Option<u8> {
        // SAFETY: MMIO read of the UART's status and data registers.
        unsafe {
            if read_volatile(STATE) & STATE_RX_FULL != 0 {
                Some(read_volatile(DATA) as u8)
            } else {
                None
            }
        }
    }

    /// Queues a byte if the transmitter has room; returns false (byte not sent) when full.
    pub fn try_write(&mut self, byte: u8) -> bool {
        // SAFETY: MMIO access to the UART's status and data registers.
        unsafe {
            if read_volatile(STATE) & STATE_TX_FULL != 0 {
                false
            } else {
                write_volatile(DATA, u32::from(byte));
                true
            }
        }
    }

    /// Writes all bytes, waiting for room (main loop only, never from the servo interrupt).
    pub fn write_all(&mut self, bytes: &[u8]) {
        for &b in bytes {
            while !self.try_write(b) {}
        }
    }
}

impl core::fmt::Write for Uart0 {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.write_all(s.as_bytes());
        Ok(())
    }
}
