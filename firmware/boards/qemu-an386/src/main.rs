//! stiffwall device image for QEMU mps2-an386 (Cortex-M4F, 25 MHz SysTick clock).
//!
//! The servo tick runs in the SysTick interrupt at the configured rate against the simulated
//! Impulse Engine of Table II ([`plant`]); the main loop runs the protocol on UART0 (`-serial pty` or
//! `-serial stdio`). A `Shutdown` request ends QEMU through semihosting exit.
#![no_std]
#![no_main]

use core::cell::RefCell;
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::interrupt::Mutex;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::debug;
use static_cell::StaticCell;
use stiffwall_board_qemu_an386::plant::{self, Bench};
use stiffwall_board_qemu_an386::{uart::Uart0, CORE_CLOCK_HZ};
use stiffwall_firmware::{
    ByteLink, Channels, ConfigStore, Device, HeldCode, NoStorage, SampledCount, Servo,
};
use stiffwall_proto::ServoConfig;

/// The servo and the simulated bench, owned by the SysTick handler.
struct ServoState {
    servo: Servo<'static>,
    bench: Bench,
    period_s: f64,
}

static CHANNELS: StaticCell<Channels> = StaticCell::new();
static SERVO: Mutex<RefCell<Option<ServoState>>> = Mutex::new(RefCell::new(None));
static TICK: AtomicU32 = AtomicU32::new(0);

/// UART0 as the firmware's byte link.
struct Link(Uart0);

impl ByteLink for Link {
    fn read(&mut self) -> Option<u8> {
        self.0.read()
    }
    fn write(&mut self, byte: u8) -> bool {
        self.0.try_write(byte)
    }
}

/// Boot configuration: wall off (K = 0) until the host sets one, force limit = the output's
/// full scale, energy monitor on.
fn defaults() -> ServoConfig {
    let board = plant::board_info();
    ServoConfig {
        force_limit: board.force_per_code * board.max_code as f32,
        energy_limit: 0.05,
        ..ServoConfig::default()
    }
}

fn program_systick(syst: &mut cortex_m::peripheral::SYST, rate_hz: u32) {
    syst.disable_counter();
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload((CORE_CLOCK_HZ / rate_hz.max(1)).clamp(2, 0x00ff_ffff) - 1);
    syst.clear_current();
    syst.enable_counter();
    syst.enable_interrupt();
}

#[entry]
fn main() -> ! {
    let Some(mut cp) = cortex_m::Peripherals::take() else {
        cortex_m::asm::udf()
    };
    let mut link = Link(Uart0::new(16));
    let channels: &'static mut Channels = CHANNELS.init_with(Channels::new);
    let (servo_port, host_port) = channels.split();
    let board = plant::board_info();
    let mut device = Device::new(board, ConfigStore::new(NoStorage), host_port, defaults());
    let rate = device.servo_rate_hz();
    let servo = Servo::new(board, device.config(), servo_port);
    cortex_m::interrupt::free(|cs| {
        SERVO.borrow(cs).replace(Some(ServoState {
            servo,
            bench: Bench::new(),
            period_s: 1.0 / f64::from(rate),
        }));
    });
    program_systick(&mut cp.SYST, rate);
    loop {
        device.poll(TICK.load(Ordering::Relaxed), &mut link);
        if let Some(hz) = device.take_rate_change() {
            cortex_m::interrupt::free(|cs| {
                if let Some(s) = SERVO.borrow(cs).borrow_mut().as_mut() {
                    s.period_s = 1.0 / f64::from(hz.max(1));
                }
            });
            program_systick(&mut cp.SYST, hz);
        }
        if let Some(code) = device.take_shutdown() {
            // The Ack has been written to the UART (take_shutdown waits for that).
            debug::exit(if code == 0 {
                debug::EXIT_SUCCESS
            } else {
                debug::EXIT_FAILURE
            });
        }
    }
}

#[exception]
fn SysTick() {
    let now = TICK.fetch_add(1, Ordering::Relaxed).wrapping_add(1);
    cortex_m::interrupt::free(|cs| {
        if let Some(s) = SERVO.borrow(cs).borrow_mut().as_mut() {
            // Sample the encoder at the instant, compute, then hold the code for one period.
            let mut enc = SampledCount(s.bench.raw_count());
            let mut out = HeldCode(0);
            s.servo.tick(now, &mut enc, &mut out);
            s.bench.set_code(out.0);
            s.bench.advance(s.period_s);
        }
    });
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}
