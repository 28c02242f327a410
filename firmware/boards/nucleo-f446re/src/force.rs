//! Force output: DAC channel 1 (feature `dac`) or TIM1 PWM + direction pin (feature `pwm`), plus
//! the amplifier / bridge enable line shared by both.
//!
//! Units: the input is the firmware core's signed force code (`ForceOutput::write`), in native
//! hardware steps so that one code is one DAC LSB or one PWM timer count: −`MAX_CODE` …
//! +`MAX_CODE`, 0 = zero force; anything beyond saturates. The force per code (N or N·m per
//! code) depends on the amplifier and is the board's `force_per_code` setting (README).
//!
//! - `dac`: PA4 (DAC_OUT1, Arduino A2 / CN8-3), 12-bit, output buffer on. Mid-scale code
//!   `DAC_ZERO` = 2048 (1.65 V) is zero force; full scale is ±`MAX_CODE` = ±1800 LSB
//!   (0.20 V … 3.10 V), inside the output buffer's linear range (VSS + 0.2 V … VDDA − 0.2 V).
//!   An external op-amp stage (README) maps 1.65 V ± 1.45 V to ±10 V for a Copley-style analog
//!   current amplifier in current (torque) mode.
//! - `pwm`: TIM1_CH1 on PA8 (AF1, Arduino D7 / CN9-8) at `PWM_HZ` = 20 kHz, edge aligned, with
//!   the magnitude as duty cycle in timer counts (period `PWM_PERIOD` = 9000 counts at the
//!   180 MHz timer clock; `MAX_CODE` = 8820 = 98 %, so bootstrapped gate drivers get off time),
//!   and the sign on DIR = PA9 (Arduino D8 / CN5-1, high = negative force). Sign-magnitude.
//!   The duty register is preloaded, so a new duty takes effect at the next PWM period (≤ 50 µs).
//! - Enable: PB10 (Arduino D6 / CN9-7), push-pull, high = amplifier / bridge enabled. It is
//!   driven low at init and only raised by `enable(true)` after the output is at zero. Until the
//!   firmware runs, the pin floats: the amplifier's enable input needs a pull-down (README).
//!
//! Invariants: `ForceOutput::write` is O(1), never blocks, never panics (saturating arithmetic
//! only), and runs in the servo interrupt. `new` leaves the output at zero force and disabled.

#[cfg(all(feature = "dac", feature = "pwm"))]
compile_error!("features `dac` and `pwm` are mutually exclusive: pick the one your amplifier uses");
#[cfg(not(any(feature = "dac", feature = "pwm")))]
compile_error!("select the force output: `--features dac` (DAC on PA4) or `--features pwm` (PWM on PA8 + DIR on PA9)");

// The `dac` code is compiled when `pwm` is off and the `pwm` code when it is on, so a wrong
// feature set stops at exactly one of the two errors above.

use core::sync::atomic::{AtomicBool, Ordering};
use stm32f4xx_hal::gpio::{Output, PushPull, PB10};

/// Set while thread mode needs the power stage off (flash writes stall the servo).
static INHIBIT: AtomicBool = AtomicBool::new(false);

/// Turns the power stage off (zero force, enable low) until `inhibit(false)`, at once and in
/// every servo tick meanwhile. Thread mode only. Clearing it lets the next servo tick re-enable
/// the amplifier (after writing zero first) and apply the servo's code.
pub fn inhibit(on: bool) {
    INHIBIT.store(on, Ordering::SeqCst);
    if on {
        // Any servo tick after the store sees the flag, so the tick can't undo this.
        emergency_off();
    }
}

pub use imp::MAX_CODE;

/// Amplifier / H-bridge enable pin type.
pub type EnablePin = PB10<Output<PushPull>>;

#[cfg(not(feature = "pwm"))]
mod imp {
    use stm32f4xx_hal::{
        dac::{DacExt, DacOut, DacPin, C1},
        gpio::PA4,
        pac::DAC,
        rcc::Rcc,
    };

    /// DAC code for zero force (mid-scale).
    pub const DAC_ZERO: u16 = 2048;
    /// DAC codes from zero to full-scale force, each way (the buffer's linear range).
    pub const MAX_CODE: i32 = 1800;

    /// The DAC driver: channel 1 on PA4.
    pub struct Driver {
        ch: C1,
    }

    impl Driver {
        pub fn new(dac: DAC, pa4: PA4, rcc: &mut Rcc) -> Self {
            let mut ch = dac.constrain(pa4.into_analog(), rcc);
            // Load mid-scale before the channel is enabled so the first output is zero force.
            ch.set_value(DAC_ZERO);
            ch.enable();
            ch.set_value(DAC_ZERO);
            Self { ch }
        }

        /// Maps a force code to a 12-bit DAC code: mid-scale + code, saturated to ±`MAX_CODE`.
        #[inline(always)]
        pub fn code_for(cmd: i32) -> u16 {
            // In 248..=3848 after the clamp: always a valid 12-bit code.
            (i32::from(DAC_ZERO) + cmd.clamp(-MAX_CODE, MAX_CODE)) as u16
        }

        #[inline(always)]
        pub fn set(&mut self, cmd: i32) {
            let code = Self::code_for(cmd);
            #[cfg(not(feature = "mutant-dac-alignment"))]
            self.ch.set_value(code);
            // Mutation check (board emulator): the right-aligned code in the left-aligned
            // holding register.
            #[cfg(feature = "mutant-dac-alignment")]
            {
                // The driver still owns the channel; only this write bypasses it.
                let _ = &self.ch;
                // SAFETY: one write of the DAC's holding register, which this driver owns.
                unsafe {
                    (*stm32f4xx_hal::pac::DAC::ptr())
                        .dhr12l1()
                        .write(|w| w.bits(u32::from(code)));
                }
            }
        }
    }

    /// Peripherals the DAC output needs.
    pub struct Parts {
        pub dac: DAC,
        pub pa4: PA4,
    }

    impl Parts {
        pub fn build(self, rcc: &mut Rcc) -> Driver {
            Driver::new(self.dac, self.pa4, rcc)
        }
    }
}

#[cfg(feature = "pwm")]
mod imp {
    use stm32f4xx_hal::{
        gpio::{Output, PushPull, PA8, PA9},
        pac::TIM1,
        prelude::*,
        rcc::Rcc,
        timer::{PwmChannel, PwmHzManager},
    };

    /// PWM carrier frequency (above hearing, well below the bridge's switching limit).
    pub const PWM_HZ: u32 = 20_000;
    /// TIM1 clock (APB2 timer clock at the 180 MHz system clock, `main.rs`).
    pub const TIMCLK_HZ: u32 = 180_000_000;
    /// Timer counts per PWM period.
    pub const PWM_PERIOD: u32 = TIMCLK_HZ / PWM_HZ;
    /// Largest duty cycle, percent (bootstrapped high-side drivers need some off time).
    pub const DUTY_LIMIT_PERCENT: u32 = 98;
    /// Largest force code = largest duty in timer counts.
    pub const MAX_CODE: i32 = (PWM_PERIOD * DUTY_LIMIT_PERCENT / 100) as i32;

    /// The PWM + DIR driver.
    pub struct Driver {
        _timer: PwmHzManager<TIM1>,
        ch: PwmChannel<TIM1, 0>,
        dir: PA9<Output<PushPull>>,
        /// Largest duty in timer counts: `MAX_CODE`, or less if the timer's period came out shorter.
        max_duty: i32,
    }

    impl Driver {
        pub fn new(tim: TIM1, pa8: PA8, pa9: PA9, rcc: &mut Rcc) -> Self {
            let dir = pa9.into_push_pull_output_in_state(stm32f4xx_hal::gpio::PinState::Low);
            let (timer, (ch1, ..)) = tim.pwm_hz(PWM_HZ.Hz(), rcc);
            let mut ch = ch1.with(pa8);
            ch.set_duty(0);
            ch.enable();
            let period = u32::from(ch.get_max_duty());
            let max_duty = MAX_CODE.min((period * DUTY_LIMIT_PERCENT / 100) as i32);
            Self {
                _timer: timer,
                ch,
                dir,
                max_duty,
            }
        }

        #[inline(always)]
        pub fn set(&mut self, cmd: i32) {
            let cmd = cmd.max(-self.max_duty).min(self.max_duty);
            // 0 ≤ |cmd| ≤ max_duty ≤ 8820: fits u16.
            let duty = cmd.unsigned_abs() as u16;
            if cmd < 0 {
                self.dir.set_high();
            } else {
                self.dir.set_low();
            }
            self.ch.set_duty(duty);
        }
    }

    /// Peripherals the PWM output needs.
    pub struct Parts {
        pub tim1: TIM1,
        pub pa8: PA8,
        pub pa9: PA9,
    }

    impl Parts {
        pub fn build(self, rcc: &mut Rcc) -> Driver {
            Driver::new(self.tim1, self.pa8, self.pa9, rcc)
        }
    }
}

pub use imp::Parts;

/// Drives the outputs to their safe state without owning them: amplifier enable low, zero
/// force. For the panic and fault handlers and boot failures, where the drivers may be owned by
/// an interrupt handler that will never run again. Only single-register writes (no
/// read-modify-write), so it is correct whatever state the interrupted code left.
pub fn emergency_off() {
    // SAFETY: BSRR is write-only and set/reset atomic; resetting PB10 can't disturb other pins.
    // If GPIOB's clock is still off the write is ignored, and the pin is still floating (the
    // amplifier's pull-down keeps it disabled).
    unsafe {
        (*stm32f4xx_hal::pac::GPIOB::ptr())
            .bsrr()
            .write(|w| w.br10().set_bit());
    }
    #[cfg(not(feature = "pwm"))]
    // SAFETY: a write of the mid-scale code to the 12-bit right-aligned holding register; the
    // DAC driver only ever writes this register too, so the last write (this one) wins.
    unsafe {
        (*stm32f4xx_hal::pac::DAC::ptr())
            .dhr12r1()
            .write(|w| w.daccdhr().set(imp::DAC_ZERO));
    }
    #[cfg(feature = "pwm")]
    // SAFETY: writes of duty 0 to CCR1, then an update event (EGR.UG) that loads the preloaded
    // duty at once instead of at the end of the period; DIR (PA9) low through the atomic BSRR.
    unsafe {
        let tim = &*stm32f4xx_hal::pac::TIM1::ptr();
        tim.ccr1().write(|w| w.ccr().set(0));
        tim.egr().write(|w| w.ug().set_bit());
        (*stm32f4xx_hal::pac::GPIOA::ptr())
            .bsrr()
            .write(|w| w.br9().set_bit());
    }
}

/// The force output and its enable line. One instance, owned by the servo interrupt.
pub struct ForceOut {
    driver: imp::Driver,
    enable: EnablePin,
    enabled: bool,
}

impl ForceOut {
    /// Sets up the selected output at zero force with the amplifier disabled.
    pub fn new(parts: Parts, enable: EnablePin, rcc: &mut stm32f4xx_hal::rcc::Rcc) -> Self {
        let mut enable = enable;
        enable.set_low();
        let mut driver = parts.build(rcc);
        driver.set(0);
        Self {
            driver,
            enable,
            enabled: false,
        }
    }

    /// Enables or disables the amplifier. Enabling first forces the output to zero.
    #[inline(always)]
    pub fn enable(&mut self, on: bool) {
        if on {
            if !self.enabled {
                self.driver.set(0);
            }
            self.enable.set_high();
        } else {
            self.driver.set(0);
            self.enable.set_low();
        }
        self.enabled = on;
    }

    /// Whether the amplifier enable line is high.
    #[allow(dead_code)] // diagnostics
    pub fn is_enabled(&self) -> bool {
        self.enabled
    }
}

/// The firmware core's force output: the servo's code, in native steps (±`MAX_CODE`). The
/// amplifier is enabled on the first write (after the output is at zero) and stays enabled,
/// including while the servo is in safe mode (its safe damping needs the amplifier), unless
/// `inhibit` is on.
impl stiffwall_firmware::ForceOutput for ForceOut {
    #[inline(always)]
    fn write(&mut self, code: i32) {
        if INHIBIT.load(Ordering::Relaxed) {
            self.enable(false);
        } else {
            if !self.enabled {
                self.enable(true);
            }
            self.driver.set(code);
        }
    }
}
