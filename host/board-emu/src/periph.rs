//! Register-level models of the STM32F446 peripherals the Nucleo image touches: RCC, PWR, FLASH
//! (ACR and the NOR config store on sectors 6–7), GPIOA–H, TIM2 (encoder), TIM7 (servo tick),
//! TIM1 (PWM), DAC1, USART2, IWDG, DBGMCU and the Cortex-M4 system space (NVIC, SCB, SysTick,
//! FPU control).
//!
//! Units: time in "units" of 1/720 MHz (`UNITS_PER_S`), which divides evenly into every clock of
//! the 180 MHz tree (HSI 16 MHz = 45 units, SYSCLK 180 MHz = 4, APB1 timers 90 MHz = 8, LSI
//! 32 kHz = 22 500). Invariants: a register the model does not know stops the run with its name
//! and address (`Board::stop`), never silently ignored; status bits follow the bits that request
//! them (RCC ready bits, PWR over-drive, SWS = SW); flash sectors 6–7 obey NOR semantics (erase
//! sets 0xFF, programming only clears bits, a write needs FLASH_CR.PG and an unlocked controller);
//! interrupt lines are levels computed from flag & enable bits, plus NVIC software pends.

use crate::plant::Coupling;
pub use crate::plant::{ForceState, UNITS_PER_S};
use std::collections::VecDeque;

/// Interrupt numbers (RM0390 Table 38).
pub const IRQ_TIM2: usize = 28;
/// USART2 global interrupt.
pub const IRQ_USART2: usize = 38;
/// TIM7 global interrupt.
pub const IRQ_TIM7: usize = 55;
/// Number of external interrupts on the STM32F446.
pub const IRQS: usize = 97;
/// Baud rate the host link must run at.
pub const BAUD: f64 = 921_600.0;
/// Largest baud-rate error a UART tolerates against the ST-LINK.
pub const BAUD_TOLERANCE: f64 = 0.02;
/// Flash config-store sectors: (number, start, length).
pub const STORE_SECTORS: [(u32, u32, u32); 2] =
    [(6, 0x0804_0000, 0x2_0000), (7, 0x0806_0000, 0x2_0000)];
/// Sector erase time at x32 parallelism (RM0390/datasheet typical 128 KiB), seconds.
pub const ERASE_S: f64 = 1.0;
/// Word program time, seconds (datasheet typical x32).
pub const PROGRAM_S: f64 = 16e-6;

/// Why the emulated board reset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResetCause {
    /// The independent watchdog ran out.
    Watchdog,
    /// SCB AIRCR.SYSRESETREQ.
    Software,
}

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

/// A basic or general-purpose up-counter as a time-based model (TIM7, and TIM2/TIM1 when they
/// count the internal clock).
#[derive(Debug, Clone, Default)]
pub struct Timer {
    /// Latched registers by offset / 4 (CR1, CR2, SMCR, DIER, SR, EGR, CCMR1, CCMR2, CCER, CNT,
    /// PSC, ARR, RCR, CCR1..4, BDTR, DCR, DMAR, OR).
    pub r: [u32; 21],
    /// CNT at `t0`.
    cnt0: u64,
    /// Time of `cnt0`.
    t0: u64,
    /// Active (shadow) prescaler and reload.
    psc: u32,
    arr: u32,
    /// Update events so far.
    pub updates: u64,
    /// Time of the first and last update events.
    pub first_update: Option<u64>,
    /// Time of the last update event.
    pub last_update: u64,
}

const CR1: usize = 0;
const SMCR: usize = 2;
const DIER: usize = 3;
const SR: usize = 4;
const EGR: usize = 5;
const CCMR1: usize = 6;
const CCER: usize = 8;
const CNT: usize = 9;
const PSC: usize = 10;
const ARR: usize = 11;
const CCR1: usize = 13;
const BDTR: usize = 17;

impl Timer {
    fn reset(&mut self, arr_reset: u32) {
        *self = Self::default();
        self.r[ARR] = arr_reset;
        self.arr = arr_reset;
    }

    fn running(&self) -> bool {
        self.r[CR1] & 1 != 0
    }

    /// Units per counter step at timer clock `units_per_clk`.
    fn step(&self, units_per_clk: u64) -> u64 {
        units_per_clk * (u64::from(self.psc) + 1)
    }

    /// Counter value at `now`.
    fn count(&self, now: u64, units_per_clk: u64) -> u64 {
        if !self.running() {
            return self.cnt0;
        }
        let steps = now.saturating_sub(self.t0) / self.step(units_per_clk);
        (self.cnt0 + steps) % (u64::from(self.arr) + 1)
    }

    /// Time of the next update event (counter overflow), if counting.
    pub fn next_update(&self, units_per_clk: u64) -> Option<u64> {
        if !self.running() {
            return None;
        }
        let remaining = (u64::from(self.arr) + 1).saturating_sub(self.cnt0);
        Some(self.t0 + remaining * self.step(units_per_clk))
    }

    /// Processes the update events up to `now`.
    fn advance(&mut self, now: u64, units_per_clk: u64) {
        while let Some(at) = self.next_update(units_per_clk) {
            if at > now {
                break;
            }
            self.update_event(at);
        }
    }

    fn update_event(&mut self, at: u64) {
        self.cnt0 = 0;
        self.t0 = at;
        self.psc = self.r[PSC];
        self.arr = self.r[ARR];
        self.r[SR] |= 1;
        self.updates += 1;
        self.first_update.get_or_insert(at);
        self.last_update = at;
    }

    fn write(&mut self, idx: usize, v: u32, now: u64, units_per_clk: u64) {
        self.advance(now, units_per_clk);
        match idx {
            CR1 => {
                let cnt = self.count(now, units_per_clk);
                self.cnt0 = cnt;
                self.t0 = now;
                self.r[CR1] = v;
                // ARPE off: a new ARR takes effect at once.
            }
            SR => self.r[SR] &= v, // rc_w0
            EGR => {
                if v & 1 != 0 {
                    self.cnt0 = 0;
                    self.t0 = now;
                    self.psc = self.r[PSC];
                    self.arr = self.r[ARR];
                    if self.r[CR1] & 0b100 == 0 {
                        self.r[SR] |= 1;
                    }
                }
            }
            CNT => {
                self.cnt0 = u64::from(v);
                self.t0 = now;
            }
            ARR => {
                self.r[ARR] = v;
                if self.r[CR1] & 0x80 == 0 {
                    self.arr = v;
                }
            }
            _ => self.r[idx] = v,
        }
    }

    /// The update interrupt line (UIF & UIE) and the capture/compare flags it enables.
    fn line(&self) -> bool {
        self.r[SR] & self.r[DIER] & 0x5F != 0
    }
}

/// USART2 model.
#[derive(Debug, Clone, Default)]
pub struct Usart {
    /// SR, DR, BRR, CR1, CR2, CR3, GTPR.
    pub r: [u32; 7],
    /// Received byte in DR.
    rx_dr: u8,
    /// Bytes from the host, not yet shifted in.
    pub rx_fifo: VecDeque<u8>,
    /// Earliest time of the next received byte.
    rx_next: u64,
    /// Byte in the transmit holding register.
    tx_hold: Option<u8>,
    /// End of the byte in the shift register.
    tx_busy_until: Option<u64>,
    /// Bytes sent to the host, not yet written to the pty.
    pub tx_out: VecDeque<u8>,
    /// Bytes lost to overrun (the firmware did not read DR in time).
    pub overruns: u64,
    /// Bytes sent in total.
    pub sent: u64,
}

const U_SR: usize = 0;
const U_DR: usize = 1;
const U_BRR: usize = 2;
const U_CR1: usize = 3;
const SR_RXNE: u32 = 1 << 5;
const SR_TC: u32 = 1 << 6;
const SR_TXE: u32 = 1 << 7;
const SR_ORE: u32 = 1 << 3;

impl Usart {
    fn reset(&mut self) {
        let rx = std::mem::take(&mut self.rx_fifo);
        let tx = std::mem::take(&mut self.tx_out);
        *self = Self::default();
        self.rx_fifo = rx;
        self.tx_out = tx;
        self.r[U_SR] = SR_TXE | SR_TC;
    }

    fn enabled(&self) -> bool {
        self.r[U_CR1] & (1 << 13) != 0
    }

    fn line(&self) -> bool {
        let cr1 = self.r[U_CR1];
        let sr = self.r[U_SR];
        (cr1 & (1 << 5) != 0 && sr & (SR_RXNE | SR_ORE) != 0)
            || (cr1 & (1 << 7) != 0 && sr & SR_TXE != 0)
            || (cr1 & (1 << 6) != 0 && sr & SR_TC != 0)
    }

    /// The next time something changes by itself.
    fn next_event(&self) -> Option<u64> {
        let rx = (!self.rx_fifo.is_empty() && self.enabled() && self.r[U_CR1] & 0b100 != 0)
            .then_some(self.rx_next);
        match (rx, self.tx_busy_until) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
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
    flash_key: u8,
    /// GPIOA..H: MODER, OTYPER, OSPEEDR, PUPDR, IDR, ODR, BSRR, LCKR, AFRL, AFRH.
    pub gpio: [[u32; 10]; 8],
    /// TIM2 (encoder), TIM7 (servo), TIM1 (PWM).
    pub tim2: Timer,
    /// TIM7.
    pub tim7: Timer,
    /// TIM1.
    pub tim1: Timer,
    /// TIM2 count bookkeeping: plant count at the last CNT write / start.
    enc_base_plant: i64,
    enc_base_cnt: u64,
    /// DAC registers by offset / 4 (CR .. SR).
    pub dac: [u32; 14],
    /// USART2.
    pub usart: Usart,
    /// IWDG: KR, PR, RLR, SR; running; time of the last reload.
    pub iwdg: [u32; 4],
    /// Whether the IWDG runs.
    pub iwdg_on: bool,
    iwdg_reload_at: u64,
    /// Time from the last reload to the reset: RLR and PR as they were at that reload (a new
    /// RLR or PR only counts from the next reload, as on the chip).
    iwdg_period: u64,
    iwdg_unlocked: bool,
    /// Feeds so far.
    pub iwdg_feeds: u64,
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

/// Register names for messages: (address, name).
const NAMES: &[(u32, &str)] = &[
    (0x4002_3800, "RCC_CR"),
    (0x4002_3804, "RCC_PLLCFGR"),
    (0x4002_3808, "RCC_CFGR"),
    (0x4002_3884, "RCC_PLLI2SCFGR"),
    (0x4002_3888, "RCC_PLLSAICFGR"),
    (0x4002_388C, "RCC_DCKCFGR"),
    (0x4002_3894, "RCC_DCKCFGR2"),
    (0x4002_3870, "RCC_BDCR"),
    (0x4002_3874, "RCC_CSR"),
    (0x4000_7000, "PWR_CR"),
    (0x4000_7004, "PWR_CSR"),
    (0x4002_3C00, "FLASH_ACR"),
    (0x4002_3C10, "FLASH_CR"),
    (0x4002_3C14, "FLASH_OPTCR"),
    (0xE000_E010, "SYST_CSR"),
    (0xE000_ED04, "SCB_ICSR"),
    (0xE000_ED0C, "SCB_AIRCR"),
    (0xE000_ED88, "SCB_CPACR"),
    (0xE000_EF34, "FPU_FPCCR"),
    (0xE000_1000, "DWT_CTRL"),
    (0xE000_1004, "DWT_CYCCNT"),
    (0xE000_EDFC, "DCB_DEMCR"),
];

/// Peripheral names by base address (for unknown registers).
const BLOCKS: &[(u32, u32, &str)] = &[
    (0x4000_0000, 0x400, "TIM2"),
    (0x4000_0400, 0x400, "TIM3"),
    (0x4000_0800, 0x400, "TIM4"),
    (0x4000_0C00, 0x400, "TIM5"),
    (0x4000_1000, 0x400, "TIM6"),
    (0x4000_1400, 0x400, "TIM7"),
    (0x4000_2800, 0x400, "RTC"),
    (0x4000_2C00, 0x400, "WWDG"),
    (0x4000_3000, 0x400, "IWDG"),
    (0x4000_3800, 0x400, "SPI2"),
    (0x4000_4400, 0x400, "USART2"),
    (0x4000_4800, 0x400, "USART3"),
    (0x4000_5400, 0x400, "I2C1"),
    (0x4000_7000, 0x400, "PWR"),
    (0x4000_7400, 0x400, "DAC"),
    (0x4001_0000, 0x400, "TIM1"),
    (0x4001_1000, 0x400, "USART1"),
    (0x4001_2000, 0x400, "ADC"),
    (0x4001_3800, 0x400, "SYSCFG"),
    (0x4001_3C00, 0x400, "EXTI"),
    (0x4002_0000, 0x2000, "GPIO"),
    (0x4002_3000, 0x400, "CRC"),
    (0x4002_3800, 0x400, "RCC"),
    (0x4002_3C00, 0x400, "FLASH"),
    (0x4002_6000, 0x800, "DMA"),
    (0xE000_0000, 0x1000, "ITM"),
    (0xE000_1000, 0x1000, "DWT"),
    (0xE000_E000, 0x1000, "SCS"),
    (0xE004_2000, 0x1000, "DBGMCU"),
];

/// The register's name for messages, e.g. "RCC_PLLI2SCFGR (0x40023884)" or "TIM3+0x00
/// (0x40000400)".
pub fn reg_name(addr: u32) -> String {
    if let Some((_, n)) = NAMES.iter().find(|(a, _)| *a == addr) {
        return format!("{n} ({addr:#010x})");
    }
    match BLOCKS.iter().find(|(b, l, _)| (*b..b + l).contains(&addr)) {
        Some((b, _, n)) => format!("{n}+{:#05x} ({addr:#010x})", addr - b),
        None => format!("unmapped register {addr:#010x}"),
    }
}

fn merge(old: u32, addr: u32, size: usize, v: u64) -> u32 {
    if size >= 4 {
        return v as u32;
    }
    let shift = (addr & 3) * 8;
    let mask = (((1u64 << (8 * size)) - 1) as u32) << shift;
    (old & !mask) | (((v as u32) << shift) & mask)
}

impl Periph {
    /// A board at power-on reset.
    pub fn new(plant: Coupling) -> Self {
        let mut p = Self {
            rcc: [0; 0x40],
            pwr: [0; 2],
            flash: [0; 6],
            flash_key: 0,
            gpio: [[0; 10]; 8],
            tim2: Timer::default(),
            tim7: Timer::default(),
            tim1: Timer::default(),
            enc_base_plant: 0,
            enc_base_cnt: 0,
            dac: [0; 14],
            usart: Usart::default(),
            iwdg: [0; 4],
            iwdg_on: false,
            iwdg_reload_at: 0,
            iwdg_period: 0,
            iwdg_unlocked: false,
            iwdg_feeds: 0,
            dbgmcu: [0; 3],
            nvic_en: [false; IRQS],
            nvic_pend: [false; IRQS],
            nvic_prio: [0; IRQS],
            scb: Default::default(),
            systick: [0; 3],
            store: vec![0xFF; 0x4_0000],
            stop: None,
            reset: None,
            stall: 0,
            stalled_total: 0,
            now: 0,
            cpu_units: UNITS_PER_S / 16_000_000,
            plant,
            erases: 0,
            programs: 0,
        };
        p.reset_registers();
        p
    }

    /// Every register to its reset value; the config store, the plant and time survive.
    pub fn reset_registers(&mut self) {
        self.rcc = [0; 0x40];
        self.rcc[0] = 0x0000_0083;
        self.rcc[1] = 0x2400_3010;
        self.rcc[0x84 / 4] = 0x2400_3000;
        self.rcc[0x88 / 4] = 0x2400_3000;
        self.rcc[0x74 / 4] = 0x0E00_0000;
        self.pwr = [0x0000_C000, 0];
        self.flash = [0, 0, 0, 0, 0x8000_0000, 0x0FFF_AAED];
        self.flash_key = 0;
        self.gpio = [[0; 10]; 8];
        self.gpio[0][0] = 0xA800_0000;
        self.gpio[0][3] = 0x6400_0000;
        self.gpio[0][2] = 0x0C00_0000;
        self.gpio[1][0] = 0x0000_0280;
        self.gpio[1][3] = 0x0000_0100;
        self.gpio[1][2] = 0x0000_00C0;
        self.tim2.reset(u32::MAX);
        self.tim7.reset(0xFFFF);
        self.tim1.reset(0xFFFF);
        self.enc_base_plant = self.plant.count();
        self.enc_base_cnt = 0;
        self.dac = [0; 14];
        self.usart.reset();
        self.iwdg = [0, 0, 0xFFF, 0];
        self.iwdg_on = false;
        self.iwdg_unlocked = false;
        self.dbgmcu = [0; 3];
        self.nvic_en = [false; IRQS];
        self.nvic_pend = [false; IRQS];
        self.nvic_prio = [0; IRQS];
        self.scb.clear();
        self.scb.insert(0xE000_EF34, 0xC000_0000);
        self.systick = [0; 3];
        self.stop = None;
        self.reset = None;
        self.cpu_units = UNITS_PER_S / 16_000_000;
    }

    fn fail(&mut self, why: String) {
        if self.stop.is_none() {
            self.stop = Some(why);
        }
    }

    fn unmodelled(&mut self, addr: u32, write: Option<u64>) {
        let what = match write {
            Some(v) => format!("write of {v:#x} to"),
            None => "read of".into(),
        };
        self.fail(format!(
            "the firmware touched a register the emulator does not model: {what} {}",
            reg_name(addr)
        ));
    }

    /// The clock tree from RCC.
    pub fn clocks(&self) -> Clocks {
        let cfgr = self.rcc[2];
        let pll = self.rcc[1];
        let sws = (cfgr >> 2) & 3;
        let src_in = if pll & (1 << 22) != 0 { 8e6 } else { 16e6 };
        let m = f64::from((pll & 0x3F).max(1));
        let n = f64::from((pll >> 6) & 0x1FF);
        let p = f64::from(2 * (((pll >> 16) & 3) + 1));
        let sysclk = match sws {
            0 => 16e6,
            1 => 8e6,
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

    fn units(hz: f64) -> u64 {
        (UNITS_PER_S as f64 / hz).round().max(1.0) as u64
    }

    /// Units per APB1 timer clock.
    pub fn apb1_timer_units(&self) -> u64 {
        Self::units(self.clocks().tim1clk_apb1)
    }

    fn apb2_timer_units(&self) -> u64 {
        Self::units(self.clocks().timclk_apb2)
    }

    /// The USART2 byte time (10 bits at the configured rate), units.
    fn byte_units(&self) -> u64 {
        let brr = self.usart.r[U_BRR].max(16);
        let baud = self.clocks().pclk1 * 16.0 / f64::from(brr) / 16.0;
        Self::units(baud / 10.0)
    }

    /// The LSI period times the IWDG prescaler, units.
    fn iwdg_step(&self) -> u64 {
        (UNITS_PER_S / 32_000) * (4u64 << self.iwdg[1].min(6))
    }

    /// When the watchdog runs out, if it runs.
    pub fn iwdg_deadline(&self) -> Option<u64> {
        self.iwdg_on.then(|| self.iwdg_reload_at + self.iwdg_period)
    }

    /// The next time something happens by itself (timer update, UART byte, watchdog).
    pub fn next_event(&self) -> Option<u64> {
        [
            self.tim7.next_update(self.apb1_timer_units()),
            self.usart.next_event(),
            self.iwdg_deadline(),
        ]
        .into_iter()
        .flatten()
        .min()
    }

    /// Brings every time-driven model up to `self.now`.
    pub fn advance(&mut self) {
        let now = self.now;
        let u1 = self.apb1_timer_units();
        self.tim7.advance(now, u1);
        // USART transmit: the shift register finishes, the holding register moves in.
        while let Some(end) = self.usart.tx_busy_until {
            if end > now {
                break;
            }
            match self.usart.tx_hold.take() {
                Some(b) => {
                    self.usart.tx_out.push_back(b);
                    self.usart.sent += 1;
                    self.usart.r[U_SR] |= SR_TXE;
                    self.usart.tx_busy_until = Some(end + self.byte_units());
                }
                None => {
                    self.usart.tx_busy_until = None;
                    self.usart.r[U_SR] |= SR_TC;
                }
            }
        }
        // USART receive.
        let u = &self.usart;
        if u.enabled() && u.r[U_CR1] & 0b100 != 0 && !u.rx_fifo.is_empty() && u.rx_next <= now {
            let byte_units = self.byte_units();
            let u = &mut self.usart;
            let b = u.rx_fifo.pop_front().expect("non-empty");
            if u.r[U_SR] & SR_RXNE != 0 {
                u.r[U_SR] |= SR_ORE;
                u.overruns += 1;
            } else {
                u.rx_dr = b;
                u.r[U_SR] |= SR_RXNE;
            }
            u.rx_next = now.max(u.rx_next) + byte_units;
        }
        if let Some(d) = self.iwdg_deadline() {
            if d <= now {
                self.reset = Some(ResetCause::Watchdog);
            }
        }
    }

    /// Whether interrupt `irq`'s line is high or it is pended by software.
    pub fn irq_pending(&self, irq: usize) -> bool {
        self.nvic_pend[irq]
            || match irq {
                IRQ_TIM7 => self.tim7.line(),
                IRQ_USART2 => self.usart.line(),
                IRQ_TIM2 => self.tim2.line(),
                24..=27 => self.tim1.line(),
                _ => false,
            }
    }

    /// The encoder count TIM2 shows now.
    fn tim2_count(&mut self) -> u64 {
        let t = &self.tim2;
        let sms = t.r[SMCR] & 7;
        if !t.running() {
            return self.enc_base_cnt;
        }
        let ccmr1 = t.r[CCMR1];
        let encoder = matches!(sms, 1..=3) && ccmr1 & 3 == 1 && (ccmr1 >> 8) & 3 == 1;
        if !encoder {
            self.fail(format!(
                "TIM2 runs but is not an encoder interface: TIM2_SMCR.SMS = {sms} (allowed 1-3), \
                 TIM2_CCMR1.CC1S = {} and CC2S = {} (allowed 1: TI1/TI2 inputs)",
                ccmr1 & 3,
                (ccmr1 >> 8) & 3
            ));
            return self.enc_base_cnt;
        }
        let ccer = t.r[CCER];
        let inverted = ((ccer >> 1) & 1) ^ ((ccer >> 5) & 1) == 1;
        let now_count = self.plant.count_at(self.now);
        let mut delta = now_count - self.enc_base_plant;
        if sms != 3 {
            // Modes 1 and 2 count the edges of one channel only: half the ×4 count.
            delta = delta.div_euclid(2);
        }
        if inverted {
            delta = -delta;
        }
        let modulo = i128::from(self.tim2.arr) + 1;
        let cnt = (i128::from(self.enc_base_cnt) + i128::from(delta)).rem_euclid(modulo) as u64;
        // The DIR bit of CR1 follows the last movement.
        if delta < 0 {
            self.tim2.r[CR1] |= 0x10;
        } else if delta > 0 {
            self.tim2.r[CR1] &= !0x10;
        }
        cnt
    }

    fn tim2_rebase(&mut self, cnt: u64) {
        self.enc_base_cnt = cnt;
        self.enc_base_plant = self.plant.count_at(self.now);
    }

    /// The force the board drives now, in the rig's force units (N·m): from the DAC through the
    /// op-amp stage and the amplifier, or from the PWM duty and DIR; zero while the enable pin
    /// (PB10) is low or not an output.
    pub fn force_output(&self) -> ForceState {
        let pb = &self.gpio[1];
        let enable_out = (pb[0] >> 20) & 3 == 1;
        let enabled = enable_out && pb[5] & (1 << 10) != 0;
        // DAC: PA4 analog, DAC EN1.
        let pa = &self.gpio[0];
        let dac_code =
            (self.dac[0] & 1 != 0 && (pa[0] >> 8) & 3 == 3).then_some(self.dac[0x2C / 4] & 0xFFF);
        // PWM: TIM1 running, CH1 enabled, main output enabled, PA8 AF1, mode PWM1/2.
        let t = &self.tim1;
        let oc1m = (t.r[CCMR1] >> 4) & 7;
        let pwm_on = t.running()
            && t.r[CCER] & 1 != 0
            // MOE, or AOE (bit 14): MOE is set by the next update event of the running timer.
            && t.r[BDTR] & (3 << 14) != 0
            && (pa[0] >> 16) & 3 == 2
            && pa[9] & 0xF == 1
            && (oc1m == 6 || oc1m == 7);
        let duty = pwm_on.then(|| {
            let period = f64::from(t.r[ARR]) + 1.0;
            let mut d = (f64::from(t.r[CCR1]) / period).min(1.0);
            if (oc1m == 7) ^ (t.r[CCER] & 2 != 0) {
                d = 1.0 - d;
            }
            d
        });
        let dir_out = (pa[0] >> 18) & 3 == 1;
        let dir_high = dir_out && pa[5] & (1 << 9) != 0;
        ForceState {
            enabled,
            dac_code,
            duty,
            dir_high,
        }
    }

    /// Reads `size` bytes at `addr` (a peripheral or system register).
    pub fn read(&mut self, addr: u32, size: usize) -> u64 {
        let word = addr & !3;
        let v = self.read_word(word);
        let shift = (addr & 3) * 8;
        let mask = if size >= 4 {
            u64::from(u32::MAX)
        } else {
            (1u64 << (8 * size)) - 1
        };
        (u64::from(v) >> shift) & mask
    }

    /// Writes `size` bytes of `v` at `addr`.
    pub fn write(&mut self, addr: u32, size: usize, v: u64) {
        let word = addr & !3;
        // Byte writes to the NVIC priority registers are the common sub-word case.
        if (0xE000_E400..0xE000_E400 + IRQS as u32).contains(&addr) && size < 4 {
            for i in 0..size {
                let irq = (addr - 0xE000_E400) as usize + i;
                if irq < IRQS {
                    self.nvic_prio[irq] = (v >> (8 * i)) as u8 & 0xF0;
                }
            }
            return;
        }
        let merged = if size < 4 {
            let old = self.peek_word(word);
            merge(old, addr, size, v)
        } else {
            v as u32
        };
        self.write_word(word, merged, v);
    }

    /// The latched value of a register without side effects (for sub-word merges).
    fn peek_word(&self, a: u32) -> u32 {
        match a {
            0x4002_0000..=0x4002_1FFF => {
                let port = ((a - 0x4002_0000) / 0x400) as usize;
                let off = ((a & 0x3FF) / 4) as usize;
                self.gpio[port].get(off).copied().unwrap_or(0)
            }
            0x4000_4400..=0x4000_441B => self.usart.r[((a & 0x1F) / 4) as usize],
            _ => 0,
        }
    }

    fn read_word(&mut self, a: u32) -> u32 {
        match a {
            0x4002_3800..=0x4002_38FF => {
                let i = ((a - 0x4002_3800) / 4) as usize;
                match i {
                    0..=4 | 8..=0x11 | 0x14..=0x15 | 0x1C..=0x1D | 0x21 | 0x22 | 0x23 | 0x25 => {
                        self.rcc[i]
                    }
                    _ => {
                        self.unmodelled(a, None);
                        0
                    }
                }
            }
            0x4000_7000 => self.pwr[0],
            0x4000_7004 => self.pwr[1],
            0x4002_3C00..=0x4002_3C17 => self.flash[((a - 0x4002_3C00) / 4) as usize],
            0x4002_0000..=0x4002_1FFF if (a & 0x3FF) < 0x28 => {
                let port = ((a - 0x4002_0000) / 0x400) as usize;
                let off = ((a & 0x3FF) / 4) as usize;
                let g = &self.gpio[port];
                match off {
                    4 => {
                        // IDR: outputs read back their latch; pull-ups read high otherwise.
                        let mut idr = 0;
                        for pin in 0..16 {
                            let mode = (g[0] >> (2 * pin)) & 3;
                            let pupd = (g[3] >> (2 * pin)) & 3;
                            let bit = match mode {
                                1 => (g[5] >> pin) & 1,
                                _ => u32::from(pupd == 1),
                            };
                            idr |= bit << pin;
                        }
                        idr
                    }
                    6 => 0,
                    _ => g[off],
                }
            }
            0x4000_0000..=0x4000_0053 => {
                let i = ((a - 0x4000_0000) / 4) as usize;
                if i == CNT {
                    self.tim2_count() as u32
                } else {
                    self.tim2.r[i]
                }
            }
            0x4000_1400..=0x4000_142F => {
                let i = ((a - 0x4000_1400) / 4) as usize;
                let u = self.apb1_timer_units();
                self.tim7.advance(self.now, u);
                if i == CNT {
                    self.tim7.count(self.now, u) as u32
                } else {
                    self.tim7.r[i]
                }
            }
            0x4001_0000..=0x4001_004F => {
                let i = ((a - 0x4001_0000) / 4) as usize;
                self.tim1.r[i]
            }
            0x4000_7400..=0x4000_7437 => self.dac[((a - 0x4000_7400) / 4) as usize],
            0x4000_4400..=0x4000_441B => {
                let i = ((a - 0x4000_4400) / 4) as usize;
                self.advance();
                if i == U_DR {
                    let b = self.usart.rx_dr;
                    self.usart.r[U_SR] &= !(SR_RXNE | SR_ORE | 0b111);
                    u32::from(b)
                } else {
                    self.usart.r[i]
                }
            }
            0x4000_3000..=0x4000_300F => self.iwdg[((a - 0x4000_3000) / 4) as usize],
            0xE004_2000 => 0x1000_6421,
            0xE004_2004..=0xE004_200C => self.dbgmcu[((a - 0xE004_2004) / 4) as usize],
            0xE000_E100..=0xE000_E11F | 0xE000_E180..=0xE000_E19F => {
                let base = ((a & 0x1F) / 4) as usize * 32;
                bits(|i| self.nvic_en.get(base + i).copied().unwrap_or(false))
            }
            0xE000_E200..=0xE000_E21F | 0xE000_E280..=0xE000_E29F => {
                let base = ((a & 0x1F) / 4) as usize * 32;
                let pend: Vec<bool> = (0..32)
                    .map(|i| base + i < IRQS && self.irq_pending(base + i))
                    .collect();
                bits(|i| pend[i])
            }
            0xE000_E400..=0xE000_E45F => {
                let base = (a - 0xE000_E400) as usize;
                (0..4).fold(0, |acc, i| {
                    acc | u32::from(self.nvic_prio.get(base + i).copied().unwrap_or(0)) << (8 * i)
                })
            }
            0xE000_E010..=0xE000_E018 => self.systick[((a - 0xE000_E010) / 4) as usize],
            0xE000_E01C => 0x4000_0000 | 22_499,
            0xE000_ED00 => 0x410F_C241,
            0xE000_ED04 => 0,
            0xE000_ED08 | 0xE000_ED0C | 0xE000_ED10 | 0xE000_ED14 | 0xE000_ED18 | 0xE000_ED1C
            | 0xE000_ED20 | 0xE000_ED24 | 0xE000_ED88 | 0xE000_EF34 | 0xE000_EF38 | 0xE000_EF3C
            | 0xE000_EDFC => {
                self.scb
                    .get(&a)
                    .copied()
                    .unwrap_or(if a == 0xE000_ED0C { 0xFA05_0000 } else { 0 })
            }
            _ => {
                self.unmodelled(a, None);
                0
            }
        }
    }

    fn write_word(&mut self, a: u32, v: u32, raw: u64) {
        let now = self.now;
        match a {
            0x4002_3800..=0x4002_38FF => {
                let i = ((a - 0x4002_3800) / 4) as usize;
                match i {
                    0 => {
                        // Ready bits follow their enables (HSI 0/1, HSE 16/17, PLL 24/25,
                        // PLLI2S 26/27, PLLSAI 28/29).
                        let mut r = v & !((1 << 1) | (1 << 17) | (1 << 25) | (1 << 27) | (1 << 29));
                        for en in [0, 16, 24, 26, 28] {
                            if v & (1 << en) != 0 {
                                r |= 1 << (en + 1);
                            }
                        }
                        if v & (1 << 16) != 0 && v & (1 << 18) == 0 {
                            self.fail(
                                "RCC_CR: HSE enabled without HSEBYP (bit 18): the Nucleo's HSE \
                                 is the ST-LINK's 8 MHz MCO, which needs bypass mode"
                                    .into(),
                            );
                        }
                        self.rcc[0] = r;
                    }
                    1 => self.rcc[1] = v,
                    2 => {
                        // SWS (bits 3:2) follows SW (bits 1:0).
                        self.rcc[2] = (v & !0xC) | ((v & 3) << 2);
                        self.clock_changed();
                    }
                    3
                    | 4
                    | 5
                    | 8
                    | 9
                    | 0xC..=0x11
                    | 0x14
                    | 0x15
                    | 0x1C
                    | 0x1D
                    | 0x21
                    | 0x22
                    | 0x23
                    | 0x25 => {
                        let old = self.rcc[i];
                        self.rcc[i] = v;
                        // A peripheral reset pulse restores that peripheral's registers.
                        if i == 8 && v & !old & (1 << 17) != 0 {
                            self.usart.reset();
                        }
                        if i == 0x1D {
                            // CSR: LSIRDY follows LSION; RMVF clears the reset flags.
                            self.rcc[i] = (v & !2) | ((v & 1) << 1);
                        }
                    }
                    _ => self.unmodelled(a, Some(raw)),
                }
            }
            0x4000_7000 => {
                self.pwr[0] = v;
                // ODRDY (16) follows ODEN (16), ODSWRDY (17) follows ODSWEN (17); VOSRDY (14).
                self.pwr[1] = (1 << 14) | (v & (3 << 16));
            }
            0x4000_7004 => self.pwr[1] = (self.pwr[1] & !(1 << 8)) | (v & (1 << 8)),
            0x4002_3C00 => {
                self.flash[0] = v & !(1 << 11 | 1 << 12);
            }
            0x4002_3C04 => {
                self.flash_key = match (self.flash_key, v) {
                    (0, 0x4567_0123) => 1,
                    (1, 0xCDEF_89AB) => {
                        self.flash[4] &= !(1 << 31);
                        0
                    }
                    _ => {
                        self.fail(format!(
                            "FLASH_KEYR: wrong unlock sequence (wrote {v:#010x}; allowed \
                             0x45670123 then 0xCDEF89AB): the flash would lock until reset"
                        ));
                        0
                    }
                };
            }
            0x4002_3C0C => self.flash[3] &= !(v & 0x1F3),
            0x4002_3C10 => self.flash_cr(v),
            0x4002_3C08 | 0x4002_3C14 => self.unmodelled(a, Some(raw)),
            0x4002_0000..=0x4002_1FFF if (a & 0x3FF) < 0x28 => {
                let port = ((a - 0x4002_0000) / 0x400) as usize;
                let off = ((a & 0x3FF) / 4) as usize;
                if self.rcc[0x30 / 4] & (1 << port) == 0 {
                    // Clock off: the write is ignored, as on the chip.
                    return;
                }
                let before = self.force_output();
                let g = &mut self.gpio[port];
                match off {
                    6 => {
                        g[5] |= v & 0xFFFF;
                        g[5] &= !(v >> 16);
                    }
                    4 => {}
                    _ => g[off] = v,
                }
                self.output_changed(before);
            }
            0x4000_0000..=0x4000_0053 => {
                let i = ((a - 0x4000_0000) / 4) as usize;
                match i {
                    CNT => self.tim2_rebase(u64::from(v)),
                    CR1 => {
                        let cnt = self.tim2_count();
                        self.tim2.r[CR1] = v;
                        self.tim2_rebase(cnt);
                    }
                    SR => self.tim2.r[SR] &= v,
                    EGR => {
                        if v & 1 != 0 {
                            self.tim2.arr = self.tim2.r[ARR];
                            self.tim2.psc = self.tim2.r[PSC];
                            self.tim2_rebase(0);
                        }
                    }
                    ARR => {
                        self.tim2.r[ARR] = v;
                        self.tim2.arr = v;
                    }
                    _ => self.tim2.r[i] = v,
                }
            }
            0x4000_1400..=0x4000_142F => {
                let i = ((a - 0x4000_1400) / 4) as usize;
                let u = self.apb1_timer_units();
                self.tim7.write(i, v, now, u);
            }
            0x4001_0000..=0x4001_004F => {
                let before = self.force_output();
                let i = ((a - 0x4001_0000) / 4) as usize;
                let u = self.apb2_timer_units();
                self.tim1.write(i, v, now, u);
                self.output_changed(before);
            }
            0x4000_7400..=0x4000_7437 => {
                let before = self.force_output();
                let i = ((a - 0x4000_7400) / 4) as usize;
                self.dac[i] = v;
                // DHR → DOR at once (no trigger: TEN1 = 0), by alignment.
                if self.dac[0] & (1 << 2) == 0 {
                    match a - 0x4000_7400 {
                        0x08 => self.dac[0x2C / 4] = v & 0xFFF,
                        0x0C => self.dac[0x2C / 4] = (v >> 4) & 0xFFF,
                        0x10 => self.dac[0x2C / 4] = (v & 0xFF) << 4,
                        0x20 => self.dac[0x2C / 4] = v & 0xFFF,
                        _ => {}
                    }
                } else if a == 0x4000_7400 {
                    self.fail("DAC_CR.TEN1: a triggered DAC is not modelled (the firmware writes DHR12R1 untriggered)".into());
                }
                self.output_changed(before);
            }
            0x4000_4400..=0x4000_441B => {
                let i = ((a - 0x4000_4400) / 4) as usize;
                self.advance();
                match i {
                    U_SR => {
                        // rc_w0 bits: RXNE, TC, LBD, CTS.
                        let keep = v | !(SR_RXNE | SR_TC | (1 << 8) | (1 << 9));
                        self.usart.r[U_SR] &= keep;
                    }
                    U_DR => self.usart_tx(v as u8),
                    U_BRR => {
                        self.usart.r[U_BRR] = v;
                        if self.usart.enabled() {
                            self.check_baud();
                        }
                    }
                    U_CR1 => {
                        self.usart.r[U_CR1] = v;
                        if v & (1 << 13) != 0 {
                            self.check_baud();
                        }
                    }
                    _ => self.usart.r[i] = v,
                }
            }
            0x4000_3000 => match v & 0xFFFF {
                0xCCCC => {
                    self.iwdg_on = true;
                    self.iwdg_reload_at = now;
                    self.iwdg_period = (u64::from(self.iwdg[2] & 0xFFF) + 1) * self.iwdg_step();
                }
                0xAAAA => {
                    self.iwdg_reload_at = now;
                    self.iwdg_period = (u64::from(self.iwdg[2] & 0xFFF) + 1) * self.iwdg_step();
                    self.iwdg_feeds += 1;
                    self.iwdg_unlocked = false;
                }
                0x5555 => self.iwdg_unlocked = true,
                _ => self.iwdg_unlocked = false,
            },
            0x4000_3004 | 0x4000_3008 => {
                if !self.iwdg_unlocked {
                    self.fail(format!(
                        "{}: written without the 0x5555 access key first (the write is ignored \
                         by the chip)",
                        if a == 0x4000_3004 {
                            "IWDG_PR"
                        } else {
                            "IWDG_RLR"
                        }
                    ));
                }
                self.iwdg[((a - 0x4000_3000) / 4) as usize] = v;
                if std::env::var_os("STIFFWALL_EMU_TRACE").is_some() {
                    eprintln!(
                        "iwdg: {} = {v} at {:.6} s",
                        if a == 0x4000_3004 { "PR" } else { "RLR" },
                        self.now as f64 / UNITS_PER_S as f64
                    );
                }
            }
            0xE004_2004..=0xE004_200C => self.dbgmcu[((a - 0xE004_2004) / 4) as usize] = v,
            0xE000_E100..=0xE000_E11F => set_bits(&mut self.nvic_en, a, v, true),
            0xE000_E180..=0xE000_E19F => set_bits(&mut self.nvic_en, a, v, false),
            0xE000_E200..=0xE000_E21F => set_bits(&mut self.nvic_pend, a, v, true),
            0xE000_E280..=0xE000_E29F => set_bits(&mut self.nvic_pend, a, v, false),
            0xE000_E400..=0xE000_E45F => {
                let base = (a - 0xE000_E400) as usize;
                for i in 0..4 {
                    if base + i < IRQS {
                        self.nvic_prio[base + i] = (v >> (8 * i)) as u8 & 0xF0;
                    }
                }
            }
            0xE000_E010 => {
                if v & 1 != 0 {
                    self.fail("SYST_CSR.ENABLE: the firmware starts SysTick, which this image is not expected to use (the servo clock is TIM7)".into());
                }
                self.systick[0] = v;
            }
            0xE000_E014 | 0xE000_E018 => self.systick[((a - 0xE000_E010) / 4) as usize] = v,
            0xE000_ED0C => {
                if v >> 16 != 0x05FA {
                    self.fail(format!(
                        "SCB_AIRCR: written without VECTKEY 0x05FA ({v:#010x})"
                    ));
                } else if v & 4 != 0 {
                    self.reset = Some(ResetCause::Software);
                } else {
                    self.scb.insert(a, 0xFA05_0000 | (v & 0x700));
                }
            }
            0xE000_ED08 | 0xE000_ED10 | 0xE000_ED14 | 0xE000_ED18 | 0xE000_ED1C | 0xE000_ED20
            | 0xE000_ED24 | 0xE000_ED88 | 0xE000_EF34 | 0xE000_EF38 | 0xE000_EF3C | 0xE000_EDFC => {
                self.scb.insert(a, v);
            }
            _ => self.unmodelled(a, Some(raw)),
        }
    }

    /// Called when RCC_CFGR changes: the CPU clock and the flash wait states it needs.
    fn clock_changed(&mut self) {
        let c = self.clocks();
        self.cpu_units = Self::units(c.hclk);
        // RM0390 Table 5 (2.7–3.6 V): one wait state per 30 MHz of HCLK.
        let needed = ((c.hclk / 30e6).ceil() as u32).saturating_sub(1);
        let latency = self.flash[0] & 0xF;
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
                self.rcc[1]
            ));
        }
        if c.hclk > 168e6 && self.pwr[1] & (1 << 17) == 0 {
            self.fail(format!(
                "RCC: HCLK {:.1} MHz above 168 MHz needs over-drive (PWR_CR.ODEN/ODSWEN)",
                c.hclk / 1e6
            ));
        }
    }

    fn check_baud(&mut self) {
        let brr = self.usart.r[U_BRR];
        let pclk1 = self.clocks().pclk1;
        let over8 = self.usart.r[U_CR1] & (1 << 15) != 0;
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

    fn usart_tx(&mut self, b: u8) {
        let u = &self.usart;
        if !u.enabled() || u.r[U_CR1] & 0b1000 == 0 {
            self.fail("USART2_DR written with the transmitter off (CR1.UE/TE = 0)".into());
            return;
        }
        let byte_units = self.byte_units();
        let u = &mut self.usart;
        u.r[U_SR] &= !SR_TC;
        match u.tx_busy_until {
            None => {
                u.tx_out.push_back(b);
                u.sent += 1;
                u.tx_busy_until = Some(self.now + byte_units);
            }
            Some(_) => {
                // Writing DR while TXE = 0 overwrites the holding register on the chip.
                let lost = u.tx_hold.replace(b).is_some();
                u.r[U_SR] &= !SR_TXE;
                if lost {
                    self.fail("USART2_DR written while TXE = 0: a byte would be lost".into());
                }
            }
        }
    }

    fn flash_cr(&mut self, v: u32) {
        let locked = self.flash[4] & (1 << 31) != 0;
        if locked && v & (1 << 31) == 0 {
            self.fail(format!(
                "FLASH_CR written while locked ({v:#010x}); unlock with FLASH_KEYR first"
            ));
            return;
        }
        self.flash[4] = v & !(1 << 16);
        if v & (1 << 16) != 0 {
            // STRT: a sector erase (SER) or mass erase (MER).
            if v & (1 << 2) != 0 {
                self.fail("FLASH_CR.MER: a mass erase would destroy the image".into());
                return;
            }
            if v & 2 != 0 {
                let snb = (v >> 3) & 0xF;
                match STORE_SECTORS.iter().find(|s| s.0 == snb) {
                    Some(&(_, start, len)) => {
                        let at = (start - STORE_SECTORS[0].1) as usize;
                        self.store[at..at + len as usize].fill(0xFF);
                        self.erases += 1;
                        if std::env::var_os("STIFFWALL_EMU_TRACE").is_some() {
                            eprintln!(
                                "flash: erase sector {snb} at {:.6} s",
                                self.now as f64 / UNITS_PER_S as f64
                            );
                        }
                        self.stall += (ERASE_S * UNITS_PER_S as f64) as u64;
                        self.stalled_total += (ERASE_S * UNITS_PER_S as f64) as u64;
                        self.flash[3] |= 1; // EOP
                    }
                    None => self.fail(format!(
                        "FLASH_CR.SNB = {snb}: erasing that sector would destroy the image \
                         (allowed: 6, 7, the config store)"
                    )),
                }
            }
        }
    }

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
        let cr = self.flash[4];
        if cr & (1 << 31) != 0 || cr & 1 == 0 {
            self.fail(format!(
                "write of {v:#x} to flash {addr:#010x} without FLASH_CR.PG set on an unlocked \
                 controller (FLASH_CR = {cr:#010x})"
            ));
            return;
        }
        let psize = 1usize << ((cr >> 8) & 3);
        if size != psize {
            // PGPERR on the chip.
            self.flash[3] |= 1 << 6;
            return;
        }
        if !(offset as usize).is_multiple_of(size) {
            self.flash[3] |= 1 << 5;
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

    /// Notes a change of the force output: the plant is brought up to now under the old force
    /// before the new one applies.
    fn output_changed(&mut self, before: ForceState) {
        let after = self.force_output();
        if std::env::var_os("STIFFWALL_EMU_TRACE").is_some() && after != before {
            eprintln!(
                "output {after:?} tim1 {:x?} gpioa {:x?}",
                self.tim1.r, self.gpio[0]
            );
        }
        if after != before {
            self.plant.set_force(self.now, after);
        }
    }
}

fn bits(f: impl Fn(usize) -> bool) -> u32 {
    (0..32).fold(0, |acc, i| acc | (u32::from(f(i)) << i))
}

fn set_bits(arr: &mut [bool; IRQS], a: u32, v: u32, to: bool) {
    let base = ((a & 0x1F) / 4) as usize * 32;
    for i in 0..32 {
        if v & (1 << i) != 0 && base + i < IRQS {
            arr[base + i] = to;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unmodelled_register_stops_the_run_with_its_name_and_address() {
        let mut p = Periph::new(Coupling::new(None));
        let _ = p.read(0x4000_0400, 4);
        let why = p.stop.take().expect("a stop");
        assert!(why.contains("TIM3+0x000 (0x40000400)"), "{why}");
        p.write(0x4000_0800, 4, 1);
        let why = p.stop.take().expect("a stop");
        assert!(
            why.contains("write of 0x1 to TIM4+0x000 (0x40000800)"),
            "{why}"
        );
    }

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

    #[test]
    fn tim2_follows_the_encoder_with_direction_polarity_and_wrap() {
        use stiffwall_sim::rich::{PlantModel, RichPlant};
        let delta = std::f64::consts::TAU / 8192.0;
        let model = PlantModel::rigid(1e-5, 1e-5, 1e-3, delta).unwrap();
        let mut plant = RichPlant::new(&model).unwrap();
        plant.set_state(0.0, 0.0);
        let mut p = Periph::new(Coupling::new(Some(plant)));
        p.write(0x4000_0008, 4, 3); // SMCR.SMS = 3: encoder mode 3
        p.write(0x4000_0018, 4, 0x0101); // CC1S = CC2S = 1
        p.write(0x4000_0024, 4, 0); // CNT = 0
        p.write(0x4000_0000, 4, 1); // CEN
                                    // The plant moves backwards 5.5 counts: floor gives -6, the 32-bit counter wraps.
        p.plant = {
            let mut pl = RichPlant::new(&model).unwrap();
            pl.set_state(-5.5 * delta, 0.0);
            Coupling::new(Some(pl))
        };
        assert_eq!(p.read(0x4000_0024, 4), u64::from(u32::MAX - 5));
        assert_eq!(
            p.read(0x4000_0000, 4) & 0x10,
            0x10,
            "CR1.DIR: counting down"
        );
        p.write(0x4000_0020, 4, 0b10); // CC1P: channel 1 inverted, the count runs the other way
        assert_eq!(p.read(0x4000_0024, 4), 6);
        assert!(p.stop.is_none(), "{:?}", p.stop);
    }

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
