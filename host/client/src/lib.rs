//! `stiffwall-client`: the host side of the stiffwall protocol as a library, with no
//! command-line code. Its modules are private; what a program uses is re-exported here:
//!
//! - [`Client`], the protocol client (handshake with version check, request/answer with
//!   timeouts, telemetry with sequence-gap accounting, experiments returning a [`Record`]) over
//!   any [`Transport`] (serial port, pty, in-memory pair), with typed errors
//!   ([`ClientError`]) and device errors in words ([`describe_error`]);
//! - [`connect()`], which reaches the device a [`ConnectSpec`] names (a serial port, the
//!   built-in virtual device at a [`Pace`], QEMU, the board emulator);
//! - the virtual device itself ([`spawn_virtual_device`], [`VirtualSpec`], feature `virtual`),
//!   QEMU ([`boot_qemu`]) and the board emulator ([`start_board_emulator`], feature `qemu`);
//! - telemetry sessions ([`Plan`], [`pump`], [`record`]: the stream loop and the lossless
//!   recorder) and the CSV recording format ([`Writer`], [`read_recording`]);
//! - [`Cancel`], the cancel token every experiment and session checks.
//!
//! Units: SI at the API, device integers on the wire (as documented per module).
//! Invariants: the client never names command-line flags; refused fields are named by the
//! protocol ([`stiffwall_proto::ConfigField::name`]) and carried as data in
//! [`ClientError::Refused`], for a front end to spell as it likes. This crate installs no
//! signal handler: a client's token ([`Client::set_cancel`]) is detached unless the front end
//! gives it one made by [`Cancel::on_ctrl_c`], which its Ctrl-C handler reaches by cancelling
//! [`ctrl_c`].
//!
//! ```
//! use stiffwall_client::{connect, ClientError, ConnectSpec, Pace};
//! use stiffwall_proto::{ConfigField, ErrorDetail};
//!
//! // The virtual device running a preset, as fast as this program reads.
//! let mut client = connect(&ConnectSpec::preset("maxon-re35", Pace::Fast))?;
//! let mut cfg = client.get_config()?;
//! cfg.stiffness = 1.0e6; // far beyond what this device allows
//! match client.set_config(&cfg) {
//!     Err(ClientError::Refused {
//!         detail: ErrorDetail::Field { field, max, .. },
//!         ..
//!     }) => {
//!         assert_eq!(field, ConfigField::Stiffness);
//!         println!("{} at most {max}", field.name());
//!     }
//!     other => panic!("expected a refusal: {other:?}"),
//! }
//! # Ok::<(), ClientError>(())
//! ```

#![warn(missing_docs)]

#[cfg(feature = "qemu")]
mod board_emu;
mod cancel;
mod client;
mod connect;
mod describe;
mod error;
mod pace;
#[cfg(feature = "qemu")]
mod qemu;
mod recording;
mod session;
mod transport;
#[cfg(feature = "virtual")]
mod virtual_device;

#[cfg(feature = "qemu")]
pub use board_emu::{
    find_emulator as find_board_emulator, find_image as find_board_image,
    start as start_board_emulator, BoardEmulator, Spec as BoardEmulatorSpec,
    OUTPUTS as BOARD_EMULATOR_OUTPUTS,
};
pub use cancel::{ctrl_c, Cancel};
pub use client::{
    Backend, Client, EnoughFn, GapStats, Link, Record, ANSWER_TIMEOUT, BACKLOG_WAIT_MAX,
    HEARTBEAT_PERIOD, QUEUE_FULL_RETRY,
};
pub use connect::{connect, ConnectSpec, VirtualPlant, DEFAULT_VIRTUAL_DEVICE};
pub use describe::{describe_error, describe_error_named, readable, FieldLabel};
pub use error::ClientError;
pub use pace::Pace;
#[cfg(feature = "qemu")]
pub use qemu::{
    boot as boot_qemu, find_image as find_qemu_image, Qemu, DEFAULT_IMAGE as DEFAULT_QEMU_IMAGE,
    TIME_LIMIT as QEMU_TIME_LIMIT,
};
pub use recording::{
    parse as parse_recording, read as read_recording, Header, Recording, RecordingError, Row,
    Writer, COLUMNS as RECORDING_COLUMNS, MAGIC as RECORDING_MAGIC,
};
pub use session::{
    header_for_target, interrupted, pump, record, End, Outcome as SessionOutcome, Plan,
    SessionError, Stats,
};
pub use transport::{
    memory_pair, open_port, pty_pair, MemoryPort, Transport, DEFAULT_BAUD, READ_TIMEOUT,
};
#[cfg(feature = "virtual")]
pub use virtual_device::{
    spawn as spawn_virtual_device, ScenePlant, Spec as VirtualSpec, VirtualDevice, FAST_BACKLOG,
    MAX_CODE, RX_LIMIT,
};
