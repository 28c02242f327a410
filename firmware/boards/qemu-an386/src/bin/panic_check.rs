//! Link-time proof that the servo tick has no panic path.
//!
//! This image calls only the full servo tick (and the stage functions) on the simulated bench.
//! Its panic handler calls a symbol that is defined nowhere, so the image links only if the
//! optimiser removed every path to a panic in that code (`cargo xtask firmware` builds it; a
//! link error naming `servo_path_must_not_panic` means a panic path crept into the servo).
#![no_std]
#![no_main]

use core::hint::black_box;
use cortex_m_rt::entry;
use stiffwall_board_qemu_an386::plant::{board_info, Bench};
use stiffwall_firmware::{Channels, Fx32, Fx64, Numeric, Servo, F32};
use stiffwall_proto::ServoConfig;

fn run<N: Numeric>() {
    let mut channels = Channels::<N>::for_numeric();
    let (port, _host) = channels.split();
    let cfg: ServoConfig = black_box(ServoConfig::default());
    let mut servo: Servo<'_, N> = Servo::new(board_info(), &cfg, port);
    let mut bench = Bench::new();
    let mut now = 0u32;
    for _ in 0..black_box(10u32) {
        now = now.wrapping_add(1);
        let enc = black_box(&mut bench);
        let code = servo.tick(now, enc, &mut black_box(Sink));
        black_box(code);
        black_box(servo.tick_spring(enc, &mut Sink));
        black_box(servo.tick_spring_delay(enc, &mut Sink));
        black_box(servo.tick_supervised(now, enc, &mut Sink));
    }
}

struct Sink;
impl stiffwall_firmware::ForceOutput for Sink {
    fn write(&mut self, code: i32) {
        black_box(code);
    }
}

#[entry]
fn main() -> ! {
    run::<Fx64>();
    run::<Fx32>();
    run::<F32>();
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    extern "C" {
        fn servo_path_must_not_panic() -> !;
    }
    // SAFETY: never called in a correct image: the symbol does not exist, so any reachable
    // panic makes the link fail, which is the point of this binary.
    unsafe { servo_path_must_not_panic() }
}
