//! stiffwall firmware image for the ST Nucleo-F446RE (STM32F446RE, Cortex-M4F at 180 MHz).
//!
//! Clocks: HSE 8 MHz in bypass mode (the ST-LINK's MCO output, the Nucleo's default HSE source)
//! → PLL → SYSCLK = HCLK = 180 MHz (over-drive on), APB1 = 45 MHz (timers 90 MHz), APB2 = 90 MHz
//! (timers 180 MHz). Interrupts: USART2 (priority 0, serial bytes), TIM7 (priority 1, servo
//! tick); thread mode runs the protocol. Pins: see README.md and each module's header.
#![no_std]
#![no_main]

mod encoder;
mod flash_store;
mod force;
mod handoff;
mod log;
mod rig;
mod serial;
mod servo_timer;
mod watchdog;

use cortex_m_rt::{entry, exception, ExceptionFrame};
use stm32f4xx_hal::{
    gpio::{Output, PushPull, PA5},
    interrupt,
    pac::{self, Interrupt, NVIC},
    prelude::*,
    rcc::{Config, Rcc},
};

use encoder::QuadEncoder;
use flash_store::FlashSlots;
use force::ForceOut;
use handoff::Handoff;
use serial::{SerialIsr, SerialPort};
use servo_timer::ServoTimer;
use static_cell::StaticCell;
use stiffwall_firmware::{Channels, ConfigStore, Device, Servo, Shared};

/// Frequency of the ST-LINK MCO clock fed into OSC_IN.
const HSE_HZ: u32 = 8_000_000;
/// System clock.
const SYSCLK_HZ: u32 = 180_000_000;

/// NVIC priorities (upper nibble significant on the STM32F4: 16 levels, lower = more urgent).
#[cfg(not(feature = "mutant-nvic-priority"))]
const PRIO_USART2: u8 = 0x00;
// Mutation check (board emulator): USART2 below the servo tick.
#[cfg(feature = "mutant-nvic-priority")]
const PRIO_USART2: u8 = 0x20;
const PRIO_SERVO: u8 = 0x10;

/// LD2, the green user LED.
type Led = PA5<Output<PushPull>>;

/// What the servo interrupt owns.
struct ServoIsr {
    timer: ServoTimer,
    encoder: QuadEncoder,
    force: ForceOut,
    servo: Servo<'static>,
}

/// Queues and atomics between the servo (TIM7) and the protocol (thread mode).
static CHANNELS: StaticCell<Channels> = StaticCell::new();
static SERVO: Handoff<ServoIsr> = Handoff::new();
static SERIAL: Handoff<SerialIsr> = Handoff::new();

#[entry]
fn main() -> ! {
    // Both `take`s succeed: this is the only caller, and it runs once.
    let (Some(dp), Some(mut cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        halt()
    };
    let mut rcc = clocks(dp.RCC);
    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);
    // LD2 (green user LED): blinks at 1 Hz while the servo ticks (thread mode toggles it).
    let led = gpioa.pa5.into_push_pull_output();

    // Force output first, so the amplifier sees "disabled, zero force" as early as possible.
    let enable = gpiob.pb10.into_push_pull_output();
    #[cfg(not(feature = "pwm"))]
    let parts = force::Parts {
        dac: dp.DAC,
        pa4: gpioa.pa4,
    };
    #[cfg(feature = "pwm")]
    let parts = force::Parts {
        tim1: dp.TIM1,
        pa8: gpioa.pa8,
        pa9: gpioa.pa9,
    };
    let force = ForceOut::new(parts, enable, &mut rcc);
    let encoder = QuadEncoder::new(dp.TIM2, gpioa.pa0, gpioa.pa1, &mut rcc);
    let Some((port, serial_isr)) = serial::new(dp.USART2, gpioa.pa2, gpioa.pa3, &mut rcc) else {
        halt()
    };

    let (device, servo, fault_log) = firmware_core(dp.FLASH);
    let Some(timer) = ServoTimer::new(dp.TIM7, device.servo_rate_hz(), &mut rcc) else {
        halt()
    };
    SERIAL.put(serial_isr);
    SERVO.put(ServoIsr {
        timer,
        encoder,
        force,
        servo,
    });
    start_interrupts(&mut cp.NVIC);
    log_boot(&device);

    let dog = watchdog::Watchdog::start(dp.IWDG, &dp.DBGMCU, servo_timer::ticks());
    run(device, port, led, dog, fault_log)
}

/// The clock tree: HSE 8 MHz bypass → SYSCLK = HCLK = 180 MHz, APB1 45 MHz, APB2 90 MHz.
fn clocks(rcc: pac::RCC) -> Rcc {
    rcc.freeze(
        Config::hse(HSE_HZ.Hz())
            .bypass_hse_oscillator()
            .sysclk(SYSCLK_HZ.Hz())
            .hclk(SYSCLK_HZ.Hz())
            .pclk1(45.MHz())
            .pclk2(90.MHz()),
    )
}

/// The firmware core: the device loads the newest valid stored config (else the defaults);
/// the servo starts from that config. Also the fault log, which reads the latched fault bits.
fn firmware_core(flash: pac::FLASH) -> (Device<'static, FlashSlots>, Servo<'static>, FaultLog) {
    let channels: &'static mut Channels = CHANNELS.init_with(Channels::new);
    let (servo_port, host_port) = channels.split();
    let fault_log = FaultLog::new(host_port.shared);
    let board = rig::board_info();
    let device = Device::new(
        board,
        ConfigStore::new(FlashSlots::new(flash)),
        host_port,
        rig::defaults(),
    );
    let servo = Servo::new(board, device.config(), servo_port);
    (device, servo, fault_log)
}

/// Sets the interrupt priorities (serial above the servo tick) and unmasks both.
fn start_interrupts(nvic: &mut NVIC) {
    // SAFETY: no priority-based critical sections exist in this program (shared state is
    // handed off or atomic), so changing priorities and unmasking can't break a lock.
    unsafe {
        nvic.set_priority(Interrupt::USART2, PRIO_USART2);
        nvic.set_priority(Interrupt::TIM7, PRIO_SERVO);
        NVIC::unmask(Interrupt::USART2);
        NVIC::unmask(Interrupt::TIM7);
    }
}

/// The boot line of the optional log: board, force output, servo rate, stiffness.
fn log_boot(device: &Device<'static, FlashSlots>) {
    log::info!(
        "stiffwall boot on {=str} ({=str} output): servo {=u32} Hz, stiffness {=f32} N/m",
        device.board().name,
        if cfg!(feature = "pwm") { "PWM" } else { "DAC" },
        device.servo_rate_hz(),
        device.config().stiffness
    );
}

/// Thread mode, forever: the protocol, servo-rate changes, the fault log, the watchdog, the
/// LED, and sleep until the next interrupt.
fn run(
    mut device: Device<'static, FlashSlots>,
    mut port: SerialPort,
    mut led: Led,
    mut dog: watchdog::Watchdog,
    mut fault_log: FaultLog,
) -> ! {
    loop {
        device.poll(servo_timer::ticks(), &mut port);
        port.kick();
        if let Some(hz) = device.take_rate_change() {
            servo_timer::request_rate(hz);
        }
        let now = servo_timer::ticks();
        fault_log.poll();
        dog.feed_if_ticking(now);
        // Half a second of ticks per LED phase.
        led.set_state(((now / (device.servo_rate_hz() / 2).max(1)) & 1 == 1).into());
        // Sleep until the next interrupt (servo tick, serial byte in or out) unless received
        // bytes are waiting. Interrupts are masked around the check so a byte arriving between
        // the check and WFI still wakes it (WFI wakes on a pending interrupt even when masked).
        cortex_m::interrupt::free(|_| {
            if !port.rx_pending() {
                cortex_m::asm::wfi();
            }
        });
    }
}

/// The servo's latched faults, logged from thread mode when they change (with `defmt`; without
/// it this holds and does nothing).
struct FaultLog {
    #[cfg(feature = "defmt")]
    shared: &'static Shared,
    #[cfg(feature = "defmt")]
    logged: u32,
}

impl FaultLog {
    fn new(shared: &'static Shared) -> Self {
        #[cfg(not(feature = "defmt"))]
        let _ = shared;
        Self {
            #[cfg(feature = "defmt")]
            shared,
            #[cfg(feature = "defmt")]
            logged: 0,
        }
    }

    /// Logs the fault bits and the first fault's tick when the bits changed since last time.
    fn poll(&mut self) {
        #[cfg(feature = "defmt")]
        {
            use core::sync::atomic::Ordering::Relaxed;
            let faults = self.shared.faults.load(Relaxed);
            if faults != self.logged {
                let first = self.shared.first_fault_tick.load(Relaxed);
                log::warning!(
                    "servo faults {=u32:#x} (first at tick {=u32})",
                    faults,
                    first
                );
                self.logged = faults;
            }
        }
    }
}

#[interrupt]
fn TIM7() {
    static mut RES: Option<ServoIsr> = None;
    if RES.is_none() {
        *RES = SERVO.take();
    }
    let Some(res) = RES.as_mut() else {
        return;
    };
    let now = res.timer.ack();
    res.servo.tick(now, &mut res.encoder, &mut res.force);
    res.timer.apply_rate_request();
}

#[interrupt]
fn USART2() {
    static mut RES: Option<SerialIsr> = None;
    if RES.is_none() {
        *RES = SERIAL.take();
    }
    if let Some(res) = RES.as_mut() {
        res.on_interrupt();
    }
}

/// Puts the outputs in their safe state and stops (boot failures only).
fn halt() -> ! {
    force::emergency_off();
    loop {
        cortex_m::asm::wfi();
    }
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    force::emergency_off();
    log::error!("HardFault at pc {=u32:#010x}", frame.pc());
    loop {
        cortex_m::asm::nop();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    force::emergency_off();
    if let Some(at) = info.location() {
        log::error!("panic at {=str}:{=u32}", at.file(), at.line());
    }
    loop {
        cortex_m::asm::nop();
    }
}
