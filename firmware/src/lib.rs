//! `stiffwall-firmware`: the hardware-neutral firmware core (no_std, no allocation, no
//! `unsafe`), host-testable.
//!
//! # Using it on a board (stable API)
//! ```text
//! // Once, at boot (no `unsafe`: e.g. `static_cell::StaticCell<Channels>` or
//! // `cortex_m::singleton!`; the servo needs 32-bit atomics, present on thumbv7em):
//! let ch: &'static mut Channels = CHANNELS.init(Channels::new());
//! let (servo_port, host_port) = ch.split();
//! let store = ConfigStore::new(my_flash_slots);        // impl ConfigStorage (or NoStorage)
//! let mut device: Device<'static, _> = Device::new(BOARD, store, host_port, ServoConfig::default());
//! let mut servo: Servo<'static> = Servo::new(BOARD, device.config(), servo_port);
//! // program the tick timer at device.servo_rate_hz(), move `servo` into the interrupt.
//!
//! // Servo interrupt, once per period T:
//! servo.tick(now_tick, &mut encoder, &mut force_output);   // -> i32 code written
//!
//! // Main loop, as often as possible:
//! device.poll(now_tick, &mut uart);                         // impl ByteLink
//! if let Some(hz) = device.take_rate_change() { /* reprogram the tick timer */ }
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
//!   [`ForceOutput`]`::write(&mut self, code: i32)`, [`TickSource`]`::now(&self) -> u32`,
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
pub mod servo;
pub mod store;

pub use channels::{
    Channels, HostPort, ServoCmd, ServoEvent, ServoPort, Shared, TelemetryItem, COMMAND_QUEUE,
    EVENT_QUEUE, TELEMETRY_QUEUE,
};
pub use config::{validate, BoardInfo, ConfigError, Gains};
pub use device::Device;
pub use hal::{
    ByteLink, ConfigStorage, Encoder, ForceOutput, HeldCode, NoStorage, SampledCount, StorageError,
    TickSource,
};
pub use numeric::{Fx32, Fx64, Numeric, F32};
pub use servo::Servo;
/// The energy monitor (the dissipation check, eq. (35)), from `stiffwall-core`.
pub use stiffwall_core::monitor;
pub use stiffwall_core::monitor::EnergyMonitor;
pub use store::{ConfigStore, MemStorage};
