//! USART2 to the ST-LINK virtual COM port (the Nucleo's USB serial), interrupt driven.
//!
//! Pins: TX = PA2, RX = PA3 (AF7), wired on the Nucleo to the ST-LINK/V2-1 VCP (solder bridges
//! SB13/SB14 closed, the default); nothing to wire. Line: `BAUD` = 921600 baud, 8N1, no flow
//! control. At APB1 = 45 MHz the divider is 48.8 (BRR 0x31): 918 367 baud, −0.35 %, well within
//! the ±2 % a UART tolerates against the ST-LINK's own −/+0.2 %.
//!
//! Data path: the USART2 interrupt (highest priority in the system, a few dozen cycles per byte)
//! moves each received byte into a lock-free SPSC ring (`ring.rs`; `RX_CAPACITY` bytes, ~11 ms
//! of line time at full rate) and feeds the transmitter from a second ring (`TX_CAPACITY` bytes),
//! one byte per TXE interrupt. Thread mode (`SerialPort`) only touches the other ends of the two
//! rings, so no lock is needed. One byte time at 921600 baud is 10.9 µs; because the RX
//! interrupt preempts everything else, a byte is read well within that and the hardware never
//! overruns. Invariants: a byte is lost only if the RX ring is full (counted in `rx_dropped`) or
//! on an overrun/framing/noise error (counted in `rx_errors`); writing never blocks: a byte that
//! doesn't fit is refused (`ByteLink::write` returns false) and the firmware core retries it.
//!
//! Caveat: erasing a flash sector stalls instruction fetches from flash for up to ~1 s, interrupts
//! included; bytes that arrive then are lost (`flash_store.rs`). The host waits for the reply to
//! a config save before sending more.

use crate::ring::Ring;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use stm32f4xx_hal::{
    gpio::{PA2, PA3},
    nb,
    pac::{Interrupt, USART2},
    prelude::*,
    rcc::Rcc,
    serial::{config::Config, Rx, Serial, Tx},
};

/// Line rate of the link to the host.
pub const BAUD: u32 = 921_600;
/// Receive queue size in bytes.
pub const RX_CAPACITY: usize = 1024;
/// Transmit queue size in bytes.
pub const TX_CAPACITY: usize = 2048;

static RX_RING: Ring<RX_CAPACITY> = Ring::new();
static TX_RING: Ring<TX_CAPACITY> = Ring::new();
static TAKEN: AtomicBool = AtomicBool::new(false);
static RX_DROPPED: AtomicU32 = AtomicU32::new(0);
static RX_ERRORS: AtomicU32 = AtomicU32::new(0);

/// Thread-mode end of the link: reads received bytes, queues bytes to send.
pub struct SerialPort {
    rx: &'static Ring<RX_CAPACITY>,
    tx: &'static Ring<TX_CAPACITY>,
}

/// Interrupt end of the link, owned by the `USART2` handler.
pub struct SerialIsr {
    rx: Rx<USART2>,
    tx: Tx<USART2>,
    rx_queue: &'static Ring<RX_CAPACITY>,
    tx_queue: &'static Ring<TX_CAPACITY>,
}

/// Configures USART2 on PA2/PA3 at `BAUD` and returns both ends. Returns `None` if called twice
/// (each ring must have one producer and one consumer) or if the clock tree can't make the
/// baud rate.
pub fn new(usart: USART2, pa2: PA2, pa3: PA3, rcc: &mut Rcc) -> Option<(SerialPort, SerialIsr)> {
    if TAKEN.swap(true, Ordering::AcqRel) {
        return None;
    }

    let serial: Serial<USART2> = Serial::new(
        usart,
        (pa2, pa3),
        Config::default().baudrate(BAUD.bps()).wordlength_8(),
        rcc,
    )
    .ok()?;
    let (tx, mut rx) = serial.split();
    rx.listen();
    Some((
        SerialPort {
            rx: &RX_RING,
            tx: &TX_RING,
        },
        SerialIsr {
            rx,
            tx,
            rx_queue: &RX_RING,
            tx_queue: &TX_RING,
        },
    ))
}

impl SerialIsr {
    /// The whole USART2 interrupt: drain the receiver, then feed the transmitter.
    #[inline(always)]
    pub fn on_interrupt(&mut self) {
        loop {
            match self.rx.read() {
                Ok(byte) => {
                    if !self.rx_queue.push(byte) {
                        RX_DROPPED.fetch_add(1, Ordering::Relaxed);
                    }
                }
                Err(nb::Error::WouldBlock) => break,
                // The error flag is cleared by the read sequence the HAL performs.
                Err(nb::Error::Other(_)) => {
                    RX_ERRORS.fetch_add(1, Ordering::Relaxed);
                }
            }
        }
        // TXE is set whenever the data register can take a byte; one byte per interrupt.
        if let Some(byte) = self.tx_queue.peek() {
            if self.tx.write(byte).is_ok() {
                let _ = self.tx_queue.pop();
            }
        }
        if !self.tx_queue.is_empty() {
            self.tx.listen();
        } else {
            self.tx.unlisten();
        }
    }
}

impl SerialPort {
    /// The next received byte, if any. Never blocks.
    #[inline]
    pub fn read_byte(&mut self) -> Option<u8> {
        self.rx.pop()
    }

    /// Queues one byte; `false` if the transmit queue is full. Never blocks. The byte goes out
    /// once `kick` runs (thread mode calls it after each batch of writes).
    #[inline]
    pub fn write_byte(&mut self, byte: u8) -> bool {
        self.tx.push(byte)
    }

    /// Starts the transmitter if bytes are waiting: pends the USART2 interrupt, which enables
    /// its TXE interrupt itself (so thread mode never read-modify-writes USART2's CR1).
    #[inline]
    pub fn kick(&mut self) {
        if !self.tx.is_empty() {
            cortex_m::peripheral::NVIC::pend(Interrupt::USART2);
        }
    }

    /// Whether received bytes are waiting.
    #[inline]
    pub fn rx_pending(&self) -> bool {
        !self.rx.is_empty()
    }

    /// Bytes lost because the receive queue was full.
    #[allow(dead_code)]
    pub fn rx_dropped(&self) -> u32 {
        RX_DROPPED.load(Ordering::Relaxed)
    }

    /// Bytes lost to overrun, framing, parity or noise errors.
    #[allow(dead_code)]
    pub fn rx_errors(&self) -> u32 {
        RX_ERRORS.load(Ordering::Relaxed)
    }
}

/// The firmware core's link: bytes queue up until `kick` (main loop, after each `Device::poll`).
impl stiffwall_firmware::ByteLink for SerialPort {
    #[inline]
    fn read(&mut self) -> Option<u8> {
        self.read_byte()
    }
    #[inline]
    fn write(&mut self, byte: u8) -> bool {
        self.write_byte(byte)
    }
}
