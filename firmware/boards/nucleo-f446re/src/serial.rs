//! USART2 to the ST-LINK virtual COM port (the Nucleo's USB serial), interrupt driven.
//!
//! Pins: TX = PA2, RX = PA3 (AF7), wired on the Nucleo to the ST-LINK/V2-1 VCP (solder bridges
//! SB13/SB14 closed, the default); nothing to wire. Line: `BAUD` = 921600 baud, 8N1, no flow
//! control. At APB1 = 45 MHz the divider is 48.8 (BRR 0x31): 918 367 baud, −0.35 %, well within
//! the ±2 % a UART tolerates against the ST-LINK's own −/+0.2 %.
//!
//! Data path: the USART2 interrupt (highest priority in the system, a few dozen cycles per byte)
//! moves each received byte into a lock-free SPSC queue (`heapless::spsc`, the same 0.8 queue
//! the firmware core's channels use; `RX_SLOTS − 1` = 1023 bytes, ~11 ms of line time at full
//! rate) and feeds the transmitter from a second queue (`TX_SLOTS − 1` = 2047 bytes), one byte per
//! TXE interrupt. Thread mode (`SerialPort`) only holds the other ends of the two queues (the
//! `Producer`/`Consumer` split makes one producer and one consumer per queue a type-level
//! fact), so no lock is needed. The slot counts are powers of two, so heapless's index wrap
//! `(i + 1) % N` compiles to a mask: no division and no panic path in the interrupt. One byte time at 921600 baud is 10.9 µs; because the RX
//! interrupt preempts everything else, a byte is read well within that and the hardware never
//! overruns. Invariants: a byte is lost only if the RX queue is full (counted in `rx_dropped`) or
//! on an overrun/framing/noise error (counted in `rx_errors`); writing never blocks: a byte that
//! doesn't fit is refused (`ByteLink::write` returns false) and the firmware core retries it.
//!
//! Caveat: erasing a flash sector stalls instruction fetches from flash for up to ~1 s, interrupts
//! included; bytes that arrive then are lost (`flash_store.rs`). The host waits for the reply to
//! a config save before sending more.

use core::sync::atomic::{AtomicU32, Ordering};
use heapless08::spsc::{Consumer, Producer, Queue};
use static_cell::ConstStaticCell;
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
/// Receive queue slots (a power of two); the queue holds one byte less.
pub const RX_SLOTS: usize = 1024;
/// Transmit queue slots (a power of two); the queue holds one byte less.
pub const TX_SLOTS: usize = 2048;
const _: () = assert!(RX_SLOTS.is_power_of_two() && TX_SLOTS.is_power_of_two());

static RX_QUEUE: ConstStaticCell<Queue<u8, RX_SLOTS>> = ConstStaticCell::new(Queue::new());
static TX_QUEUE: ConstStaticCell<Queue<u8, TX_SLOTS>> = ConstStaticCell::new(Queue::new());
static RX_DROPPED: AtomicU32 = AtomicU32::new(0);
static RX_ERRORS: AtomicU32 = AtomicU32::new(0);

/// Thread-mode end of the link: reads received bytes, queues bytes to send.
pub struct SerialPort {
    rx: Consumer<'static, u8, RX_SLOTS>,
    tx: Producer<'static, u8, TX_SLOTS>,
}

/// Interrupt end of the link, owned by the `USART2` handler.
pub struct SerialIsr {
    rx: Rx<USART2>,
    tx: Tx<USART2>,
    rx_queue: Producer<'static, u8, RX_SLOTS>,
    tx_queue: Consumer<'static, u8, TX_SLOTS>,
}

/// Configures USART2 on PA2/PA3 at `BAUD` and returns both ends. Returns `None` if called twice
/// (the queues are handed out once) or if the clock tree can't make the baud rate.
pub fn new(usart: USART2, pa2: PA2, pa3: PA3, rcc: &mut Rcc) -> Option<(SerialPort, SerialIsr)> {
    // The interrupt produces received bytes and consumes bytes to send; thread mode the reverse.
    let (rx_queue, rx) = RX_QUEUE.try_take()?.split();
    let (tx, tx_queue) = TX_QUEUE.try_take()?.split();

    let serial: Serial<USART2> = Serial::new(
        usart,
        (pa2, pa3),
        Config::default().baudrate(BAUD.bps()).wordlength_8(),
        rcc,
    )
    .ok()?;
    // Mutation check (board emulator): the baud-rate divider doubled (460 800 baud).
    #[cfg(feature = "mutant-usart-brr")]
    // SAFETY: USART2 is owned by `serial`; one write of its divider.
    unsafe {
        (*USART2::ptr()).brr().write(|w| w.bits(2 * 0x31));
    }
    let (usart_tx, mut usart_rx) = serial.split();
    usart_rx.listen();
    Some((
        SerialPort { rx, tx },
        SerialIsr {
            rx: usart_rx,
            tx: usart_tx,
            rx_queue,
            tx_queue,
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
                    if self.rx_queue.enqueue(byte).is_err() {
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
        if let Some(&byte) = self.tx_queue.peek() {
            if self.tx.write(byte).is_ok() {
                let _ = self.tx_queue.dequeue();
            }
        }
        if self.tx_queue.ready() {
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
        self.rx.dequeue()
    }

    /// Queues one byte; `false` if the transmit queue is full. Never blocks. The byte goes out
    /// once `kick` runs (thread mode calls it after each batch of writes).
    #[inline]
    pub fn write_byte(&mut self, byte: u8) -> bool {
        self.tx.enqueue(byte).is_ok()
    }

    /// Starts the transmitter if bytes are waiting: pends the USART2 interrupt, which enables
    /// its TXE interrupt itself (so thread mode never read-modify-writes USART2's CR1).
    #[inline]
    pub fn kick(&mut self) {
        if self.tx.len() != 0 {
            cortex_m::peripheral::NVIC::pend(Interrupt::USART2);
        }
    }

    /// Whether received bytes are waiting.
    #[inline]
    pub fn rx_pending(&self) -> bool {
        self.rx.ready()
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
