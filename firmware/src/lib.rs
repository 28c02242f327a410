//! `stiffwall-firmware`: the hardware-neutral firmware core (no_std, no allocation, no
//! `unsafe`), host-testable.
//!
//! # Using it on a board
//! ```text
//! static CHANNELS: StaticCell<Channels> = ...;          // queues + shared atomics
//! let (servo_port, host_port) = CHANNELS.init(Channels::new()).split();
//! let mut device = Device::new(board, ConfigStore::new(storage), host_port, ServoConfig::default());
//! let mut servo: Servo = Servo::new(board, device.config(), servo_port);
//! // servo interrupt, every 1/device.servo_rate_hz() s:
//! servo.tick(now_tick, &mut encoder, &mut force_output);
//! // main loop:
//! loop { device.poll(now_tick, &mut uart); if let Some(hz) = device.take_rate_change() { reprogram timer } }
//! ```
//! - Traits ([`hal`]): [`Encoder`] (raw counter, 16/32-bit wrap unwrapped here),
//!   [`ForceOutput`], [`TickSource`], [`ByteLink`], [`ConfigStorage`] (two slots).
//! - [`Servo::tick`] is the full servo tick. The reduced stages for instruction counting are
//!   [`Servo::tick_spring`] (spring alone), [`Servo::tick_spring_delay`] (spring and delay
//!   line) and [`Servo::tick_supervised`] (spring, damping, delay, supervisor, experiments);
//!   the full tick adds the command queue and the telemetry push. `Servo<'_, Fx64>` (default,
//!   `I32F32` gains), `Servo<'_, Fx32>` (`I16F16`) and `Servo<'_, F32>` are the numeric choices.
//! - [`Device::poll`] is the command handler: bytes in, replies and telemetry batches out.
//!
//! Servo and device talk only through [`Channels`] (lock-free SPSC queues + atomics), so the
//! servo can run in an interrupt while the device runs in the main loop.
//!
//! Module headers state units and invariants; `docs/model-notes-firmware.md` explains the
//! choices (energy monitor, fixed-point formats, config ranges).
#![no_std]
#![cfg_attr(not(test), warn(missing_docs))]

#[cfg(any(feature = "std", test))]
extern crate std;

pub mod config;
pub mod device;
pub mod hal;
pub mod numeric;
pub mod servo;
pub mod store;

pub use config::{validate, BoardInfo, ConfigError, Gains};
pub use device::Device;
pub use hal::{ByteLink, ConfigStorage, Encoder, ForceOutput, NoStorage, StorageError, TickSource};
pub use numeric::{Fx32, Fx64, Numeric, F32};
pub use servo::{
    Channels, EnergyMonitor, HostPort, Servo, ServoCmd, ServoEvent, ServoPort, Shared,
    TelemetryItem,
};
pub use store::{ConfigStore, MemStorage};
