//! stiffwall firmware image for QEMU mps2-an386 (Cortex-M4F, 25 MHz SysTick clock).
//!
//! Boot skeleton: UART0 banner, SysTick servo interrupt at the configured rate, semihosting exit.
#![no_std]
#![no_main]

use stiffwall_board_qemu_an386::uart;

use core::fmt::Write as _;
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::debug;

/// SysTick clock of the mps2-an386 model (TOOLCHAIN.md).
const CORE_CLOCK_HZ: u32 = 25_000_000;
/// Servo rate in Hz.
const SERVO_RATE_HZ: u32 = 1_000;

static TICKS: AtomicU32 = AtomicU32::new(0);

#[entry]
fn main() -> ! {
    let mut cp = cortex_m::Peripherals::take().expect("peripherals taken once");
    let mut uart = uart::Uart0::new(16);
    let _ = writeln!(uart, "stiffwall qemu-an386 boot");
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(CORE_CLOCK_HZ / SERVO_RATE_HZ - 1);
    cp.SYST.clear_current();
    cp.SYST.enable_counter();
    cp.SYST.enable_interrupt();
    while TICKS.load(Ordering::Relaxed) < 100 {
        cortex_m::asm::wfi();
    }
    let _ = writeln!(uart, "ticks {}", TICKS.load(Ordering::Relaxed));
    debug::exit(debug::EXIT_SUCCESS);
    loop {}
}

#[exception]
fn SysTick() {
    TICKS.fetch_add(1, Ordering::Relaxed);
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    debug::exit(debug::EXIT_FAILURE);
    loop {}
}
