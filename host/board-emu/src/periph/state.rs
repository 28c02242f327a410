//! The board's state as plain data: the register files and models' state of every peripheral
//! (`Periph`, the timers', USART2's and the watchdog's), read and written by the peripheral
//! modules beside it. A leaf of `periph`: it imports no peripheral module, so each of them can
//! name the board without an import cycle through `periph/mod.rs`.
//!
//! Units: time in 1/720 MHz units (`crate::plant::UNITS_PER_S`); registers as latched words.

use crate::plant::Coupling;
use std::collections::VecDeque;

/// Number of external interrupts on the STM32F446.
pub const IRQS: usize = 97;

/// Why the emulated board reset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResetCause {
    /// The independent watchdog ran out.
    Watchdog,
    /// SCB AIRCR.SYSRESETREQ.
    Software,
}

/// The register-level board.
#[derive(Debug)]
pub struct Periph {
    /// Latched register files of the simple peripherals, by (base, offset).
    pub rcc: [u32; 0x40],
    /// PWR CR, CSR.
    pub pwr: [u32; 2],
    /// FLASH ACR, KEYR, OPTKEYR, SR, CR, OPTCR.
    pub flash: [u32; 6],
    /// Flash unlock sequence state (0: locked, 1: KEY1 seen).
    pub(crate) flash_key: u8,
    /// GPIOA..H: MODER, OTYPER, OSPEEDR, PUPDR, IDR, ODR, BSRR, LCKR, AFRL, AFRH.
    pub gpio: [[u32; 10]; 8],
    /// TIM2 (encoder), TIM7 (servo), TIM1 (PWM).
    pub tim2: Timer,
    /// TIM7.
    pub tim7: Timer,
    /// TIM1.
    pub tim1: Timer,
    /// TIM2 count bookkeeping: plant count at the last CNT write / start.
    pub(crate) enc_base_plant: i64,
    pub(crate) enc_base_cnt: u64,
    /// DAC registers by offset / 4 (CR .. SR).
    pub dac: [u32; 14],
    /// USART2.
    pub usart: Usart,
    /// The independent watchdog.
    pub iwdg: Iwdg,
    /// DBGMCU CR, APB1_FZ, APB2_FZ.
    pub dbgmcu: [u32; 3],
    /// NVIC: enabled, soft-pending, active, priority.
    pub nvic_en: [bool; IRQS],
    /// Software-pended interrupts.
    pub nvic_pend: [bool; IRQS],
    /// Priority bytes.
    pub nvic_prio: [u8; IRQS],
    /// SCB: VTOR, AIRCR, SCR, CCR, SHPR1..3, SHCSR, CPACR, FPCCR, FPDSCR, DEMCR.
    pub scb: std::collections::BTreeMap<u32, u32>,
    /// SysTick CSR, RVR, CVR.
    pub systick: [u32; 3],
    /// Config store sectors 6 and 7.
    pub store: Vec<u8>,
    /// Why the run must stop (an unmodelled register, a bad setting).
    pub stop: Option<String>,
    /// A reset the board must perform.
    pub reset: Option<ResetCause>,
    /// Extra time the CPU is stalled (flash erase/program), to add to the clock.
    pub stall: u64,
    /// All stall time so far, units (fast pacing does not hold it against the host).
    pub stalled_total: u64,
    /// Time now.
    pub now: u64,
    /// Time units per CPU cycle.
    pub cpu_units: u64,
    /// The plant behind the encoder and the force output.
    pub plant: Coupling,
    /// Flash operations performed (erases, words programmed).
    pub erases: u64,
    /// Words programmed.
    pub programs: u64,
}

/// A basic or general-purpose up-counter as a time-based model (TIM7, and TIM2/TIM1 when they
/// count the internal clock).
#[derive(Debug, Clone, Default)]
pub struct Timer {
    /// Latched registers by offset / 4 (CR1, CR2, SMCR, DIER, SR, EGR, CCMR1, CCMR2, CCER, CNT,
    /// PSC, ARR, RCR, CCR1..4, BDTR, DCR, DMAR, OR).
    pub r: [u32; 21],
    /// CNT at `t0`.
    pub(crate) cnt0: u64,
    /// Time of `cnt0`.
    pub(crate) t0: u64,
    /// Active (shadow) prescaler and reload.
    pub(crate) psc: u32,
    pub(crate) arr: u32,
    /// Update events so far.
    pub updates: u64,
    /// Time of the first and last update events.
    pub first_update: Option<u64>,
    /// Time of the last update event.
    pub last_update: u64,
}

/// USART2 model.
#[derive(Debug, Clone, Default)]
pub struct Usart {
    /// SR, DR, BRR, CR1, CR2, CR3, GTPR.
    pub r: [u32; 7],
    /// Received byte in DR.
    pub(crate) rx_dr: u8,
    /// Bytes from the host, not yet shifted in.
    pub rx_fifo: VecDeque<u8>,
    /// Earliest time of the next received byte.
    pub(crate) rx_next: u64,
    /// Byte in the transmit holding register.
    pub(crate) tx_hold: Option<u8>,
    /// End of the byte in the shift register.
    pub(crate) tx_busy_until: Option<u64>,
    /// Bytes sent to the host, not yet written to the pty.
    pub tx_out: VecDeque<u8>,
    /// Bytes lost to overrun (the firmware did not read DR in time).
    pub overruns: u64,
    /// Bytes sent in total.
    pub sent: u64,
}

/// The independent watchdog's state.
#[derive(Debug, Clone, Default)]
pub struct Iwdg {
    /// KR, PR, RLR, SR.
    pub r: [u32; 4],
    /// Whether the watchdog runs.
    pub on: bool,
    /// Time of the last reload, units.
    pub(crate) reload_at: u64,
    /// Time from the last reload to the reset: RLR and PR as they were at that reload (a new
    /// RLR or PR only counts from the next reload, as on the chip), units.
    pub(crate) period: u64,
    /// Whether PR and RLR are writable (`KEY_ACCESS` seen, no other key since).
    pub(crate) unlocked: bool,
    /// Feeds so far.
    pub feeds: u64,
}
