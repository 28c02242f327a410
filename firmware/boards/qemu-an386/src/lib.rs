//! Shared pieces of the QEMU mps2-an386 images: the UART driver and the simulated bench.
//!
//! Binaries: `stiffwall-qemu-an386` (the device: protocol on UART0, servo in SysTick),
//! `stiffwall-qemu-an386-bench` (instruction counts per servo stage and the worst single tick
//! under `-icount shift=7`),
//! `stiffwall-qemu-an386-panic-check` (links only if the servo tick has no panic path).
#![no_std]

pub mod plant;
pub mod uart;

/// SysTick clock of the mps2-an386 model, Hz (docs/toolchain.md).
pub const CORE_CLOCK_HZ: u32 = 25_000_000;
