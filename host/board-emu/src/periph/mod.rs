//! Register-level models of the STM32F446 peripherals the Nucleo image touches, one module per
//! peripheral (laid out as embassy-stm32 lays out its drivers): `rcc` (RCC, PWR and the clock
//! tree), `flash` (ACR, the key sequence and the NOR config store on sectors 6–7), `gpio`
//! (GPIOA–H), `timer` (the shared up-counter, TIM2 encoder, TIM7 servo tick, TIM1 PWM), `dac`
//! (DAC1), `usart` (USART2), `iwdg`, `dbgmcu` and the Cortex-M4 system space (`nvic`, `scb` with
//! the FPU control registers, `systick`); `force` derives the force output from the pins, and
//! `names` names registers for messages; `state` holds the register files and every model's
//! state as plain data (a leaf, so no peripheral module imports this one). This module is the
//! bus: it dispatches each word access by base address, merges sub-word writes and runs the
//! time-driven models.
//!
//! Units: time in "units" of 1/720 MHz (`UNITS_PER_S`), which divides evenly into every clock of
//! the 180 MHz tree (HSI 16 MHz = 45 units, SYSCLK 180 MHz = 4, APB1 timers 90 MHz = 8, LSI
//! 32 kHz = 22 500). Invariants: a register the model does not know stops the run with its name
//! and address (`Periph::stop`), never silently ignored; status bits follow the bits that request
//! them (RCC ready bits, PWR over-drive, SWS = SW); flash sectors 6–7 obey NOR semantics (erase
//! sets 0xFF, programming only clears bits, a write needs FLASH_CR.PG and an unlocked controller);
//! interrupt lines are levels computed from flag & enable bits, plus NVIC software pends.

mod dac;
mod dbgmcu;
mod flash;
mod force;
mod gpio;
mod iwdg;
mod names;
mod nvic;
mod rcc;
mod scb;
mod state;
mod systick;
mod timer;
mod usart;

use crate::plant::Coupling;
pub use crate::plant::UNITS_PER_S;
pub use names::reg_name;
pub use nvic::{IRQ_TIM2, IRQ_TIM7, IRQ_USART2};
pub use state::{Iwdg, Periph, ResetCause, Timer, Usart, IRQS};

/// Merges a `size`-byte write of `v` at `addr` into the word `old`.
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
            iwdg: Iwdg::default(),
            dbgmcu: [0; 3],
            nvic_en: [false; IRQS],
            nvic_pend: [false; IRQS],
            nvic_prio: [0; IRQS],
            scb: Default::default(),
            systick: [0; 3],
            store: vec![0xFF; flash::STORE_LEN],
            stop: None,
            reset: None,
            stall: 0,
            stalled_total: 0,
            now: 0,
            cpu_units: rcc::RESET_CPU_UNITS,
            plant,
            erases: 0,
            programs: 0,
        };
        p.reset_registers();
        p
    }

    /// Every register to its reset value; the config store, the plant and time survive.
    pub fn reset_registers(&mut self) {
        rcc::reset(self);
        flash::reset(self);
        gpio::reset(self);
        timer::reset(self);
        dac::reset(self);
        self.usart.reset();
        self.iwdg.reset();
        dbgmcu::reset(self);
        nvic::reset(self);
        scb::reset(self);
        systick::reset(self);
        self.stop = None;
        self.reset = None;
        self.cpu_units = rcc::RESET_CPU_UNITS;
    }

    /// Stops the run with `why`, unless it is already stopping (the first reason is kept).
    fn fail(&mut self, why: String) {
        if self.stop.is_none() {
            self.stop = Some(why);
        }
    }

    /// Stops the run for an access to a register the emulator does not model.
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
        usart::advance(self, now);
        if let Some(d) = self.iwdg_deadline() {
            if d <= now {
                self.reset = Some(ResetCause::Watchdog);
            }
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
        if nvic::is_priority_byte(addr) && size < 4 {
            nvic::write_priority_bytes(self, addr, size, v);
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
            gpio::BASE..=gpio::LAST => gpio::peek(self, a),
            usart::BASE..=usart::LAST => usart::peek(self, a),
            _ => 0,
        }
    }

    /// A word read at word address `a`, dispatched by base address.
    fn read_word(&mut self, a: u32) -> u32 {
        match a {
            rcc::BASE..=rcc::LAST => rcc::read(self, a),
            rcc::PWR_CR | rcc::PWR_CSR => rcc::pwr_read(self, a),
            flash::BASE..=flash::LAST => flash::read(self, a),
            gpio::BASE..=gpio::LAST if gpio::modelled(a) => gpio::read(self, a),
            timer::tim2::BASE..=timer::tim2::LAST => timer::tim2::read(self, a),
            timer::tim7::BASE..=timer::tim7::LAST => timer::tim7::read(self, a),
            timer::tim1::BASE..=timer::tim1::LAST => timer::tim1::read(self, a),
            dac::BASE..=dac::LAST => dac::read(self, a),
            usart::BASE..=usart::LAST => usart::read(self, a),
            iwdg::BASE..=iwdg::LAST => iwdg::read(self, a),
            dbgmcu::BASE..=dbgmcu::LAST => dbgmcu::read(self, a),
            nvic::BASE..=nvic::LAST => nvic::read(self, a),
            systick::BASE..=systick::LAST => systick::read(self, a),
            scb::BASE..=scb::LAST => scb::read(self, a),
            _ => {
                self.unmodelled(a, None);
                0
            }
        }
    }

    /// A word write of `v` at word address `a` (`raw`: the value as the core wrote it, for
    /// messages), dispatched by base address.
    fn write_word(&mut self, a: u32, v: u32, raw: u64) {
        match a {
            rcc::BASE..=rcc::LAST => rcc::write(self, a, v, raw),
            rcc::PWR_CR | rcc::PWR_CSR => rcc::pwr_write(self, a, v),
            flash::BASE..=flash::LAST => flash::write(self, a, v, raw),
            gpio::BASE..=gpio::LAST if gpio::modelled(a) => gpio::write(self, a, v),
            timer::tim2::BASE..=timer::tim2::LAST => timer::tim2::write(self, a, v),
            timer::tim7::BASE..=timer::tim7::LAST => timer::tim7::write(self, a, v),
            timer::tim1::BASE..=timer::tim1::LAST => timer::tim1::write(self, a, v),
            dac::BASE..=dac::LAST => dac::write(self, a, v),
            usart::BASE..=usart::LAST => usart::write(self, a, v),
            iwdg::BASE..=iwdg::LAST => iwdg::write(self, a, v, raw),
            dbgmcu::BASE..=dbgmcu::LAST => dbgmcu::write(self, a, v, raw),
            nvic::BASE..=nvic::LAST => nvic::write(self, a, v, raw),
            systick::BASE..=systick::LAST => systick::write(self, a, v, raw),
            scb::BASE..=scb::LAST => scb::write(self, a, v, raw),
            _ => self.unmodelled(a, Some(raw)),
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
}
