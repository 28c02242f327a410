//! `stiffwall-firmware`: the hardware-neutral firmware core (no_std, no allocation, no
//! `unsafe`), host-testable.
//!
//! # Using it on a board (stable API)
//! Compiled and run as a doctest: the board's statics are on the stack here, the hardware is
//! [`SampledCount`]/[`HeldCode`] and a byte loop that never receives anything.
//! ```
//! use stiffwall_firmware::{
//!     BoardInfo, ByteLink, Channels, ConfigStore, Device, HeldCode, MemStorage, SampledCount,
//!     Servo,
//! };
//! use stiffwall_proto::ServoConfig;
//!
//! /// The board's UART (here: nothing arrives, everything sent is accepted).
//! struct Uart;
//! impl ByteLink for Uart {
//!     fn read(&mut self) -> Option<u8> {
//!         None
//!     }
//!     fn write(&mut self, _byte: u8) -> bool {
//!         true
//!     }
//! }
//!
//! const BOARD: BoardInfo = BoardInfo {
//!     name: "example",
//!     resolution: 1.0e-5,
//!     counts_per_rev: 0,
//!     encoder_bits: 32,
//!     force_per_code: 1.0e-3,
//!     max_code: 2047,
//!     min_rate_hz: 100,
//!     max_rate_hz: 20_000,
//! };
//!
//! // Once, at boot (on a board without `unsafe`: e.g. `static_cell::StaticCell<Channels>` or
//! // `cortex_m::singleton!`, so the ports are `'static`; the servo needs 32-bit atomics,
//! // present on thumbv7em):
//! let mut ch = Channels::new();
//! let (servo_port, host_port) = ch.split();
//! let store = ConfigStore::new(MemStorage::default()); // impl ConfigStorage (or NoStorage)
//! let defaults = ServoConfig { stiffness: 1000.0, ..ServoConfig::default() }; // N/m
//! let mut device: Device<'_, _> = Device::new(BOARD, store, host_port, defaults);
//! let mut servo: Servo<'_> = Servo::new(BOARD, device.config(), servo_port);
//! // Program the tick timer at device.servo_rate_hz(), move `servo` into the interrupt.
//! assert_eq!(device.servo_rate_hz(), 1000);
//!
//! let (mut encoder, mut force_output, mut uart) = (SampledCount(0), HeldCode(0), Uart);
//! for now_tick in 0..10u32 {
//!     // Servo interrupt, once per period T (the encoder reads 100 counts into the wall):
//!     encoder.0 = 100;
//!     let code = servo.tick(now_tick, &mut encoder, &mut force_output); // the code written
//!     assert_eq!(code, force_output.0);
//!     // Main loop, as often as possible:
//!     device.poll(now_tick, &mut uart);
//!     if let Some(_hz) = device.take_rate_change() { /* reprogram the tick timer */ }
//! }
//! assert!(force_output.0 < 0, "the wall pushes back");
//! ```
//! Signatures:
//! - `Channels::new() -> Channels` (const), `Channels::split(&mut self) -> (ServoPort, HostPort)`.
//! - `Servo::<N = Fx64>::new(board: BoardInfo, cfg: &ServoConfig, port: ServoPort) -> Servo`;
//!   `tick(&mut self, now: u32, enc: &mut impl Encoder, out: &mut impl ForceOutput) -> i32`;
//!   stages `tick_spring(enc, out)`, `tick_spring_delay(enc, out)`,
//!   `tick_supervised(now, enc, out)`; `command(&mut self, now, ServoCmd)` to apply a command
//!   directly (tests, boot); `faults()`, `position()`, `spring_code(n)`, `gains()`.
//! - `Device::new(board, ConfigStore<S>, HostPort, defaults: ServoConfig) -> Device`: loads the
//!   newest valid stored config, else `defaults`; `poll(&mut self, now: u32, link: &mut impl
//!   ByteLink)`; `handle(&mut self, HostMsg) -> DeviceMsg` (one request, no I/O);
//!   `config()`, `servo_rate_hz()`, `take_rate_change()`, `dropped()`, `stats()`,
//!   `store_mut()`.
//! - Traits ([`hal`]): [`Encoder`]`::count(&mut self) -> u32` (raw hardware counter; only
//!   `BoardInfo::encoder_bits` bits used, 16/32-bit wrap unwrapped here),
//!   [`ForceOutput`]`::write(&mut self, code: i32)` (the board's timer calls the tick; no
//!   tick-source trait is needed),
//!   [`ByteLink`]`::{read(&mut self) -> Option<u8>, write(&mut self, u8) -> bool}`,
//!   [`ConfigStorage`]`::{slot_len, read(slot, buf), write(slot, data)}` (two slots; the
//!   two-slot CRC record logic is [`ConfigStore`]; [`MemStorage`] is an in-memory one).
//! - [`BoardInfo`]: resolution Δ (m or rad per count), counts per rev, counter bits, force
//!   per code, max code, rate range. [`validate`] checks a [`stiffwall_proto::ServoConfig`].
//!
//! Stages and numeric back-ends for instruction counting: [`Servo::tick_spring`] (spring
//! alone), [`Servo::tick_spring_delay`] (spring and delay line), [`Servo::tick_supervised`]
//! (spring, damping, delay, supervisor, experiments), [`Servo::tick`] (adds the command queue
//! and the telemetry push). `Servo<'_, Fx64>` (default, `I32F32` gains, 32×64-bit multiply),
//! `Servo<'_, Fx32>` (`I16F16`, 32-bit) and `Servo<'_, F32>` (single-precision FPU).
//!
//! Servo and device talk only through [`Channels`] (lock-free SPSC queues + atomics), so the
//! servo can run in an interrupt while the device runs in the main loop; neither blocks. The
//! host (hostctl's virtual device, the SIL tests) runs both in one thread.
//!
//! Module headers state units and invariants; `docs/model-notes-firmware.md` explains the
//! choices (energy monitor, fixed-point formats, config ranges).
#![no_std]
#![cfg_attr(not(test), warn(missing_docs))]

#[cfg(any(feature = "std", test))]
extern crate std;

pub mod channels;
pub mod config;
pub mod device;
pub mod experiment;
pub mod hal;
pub mod numeric;
pub mod profile;
pub mod servo;
pub mod store;

pub use channels::{
    Channels, HostPort, ServoCmd, ServoEvent, ServoPort, Shared, TelemetryItem, COMMAND_QUEUE,
    EVENT_QUEUE, TELEMETRY_QUEUE,
};
pub use config::{validate, AbsBound, BoardInfo, ConfigError, Gains};
pub use device::Device;
pub use hal::{
    ByteLink, ConfigStorage, Encoder, ForceOutput, HeldCode, NoStorage, SampledCount, StorageError,
};
pub use numeric::{Fx32, Fx64, Numeric, F32};
pub use profile::{ProfileError, ProfileTable};
pub use servo::Servo;
/// The energy monitor (the dissipation check, eq. (35)), from `stiffwall-core`.
pub use stiffwall_core::monitor;
pub use stiffwall_core::monitor::EnergyMonitor;
pub use store::{ConfigStore, MemStorage};
