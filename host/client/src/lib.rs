//! `stiffwall-client`: the host side of the stiffwall protocol as a library, with no
//! command-line code. [`client`] is the protocol client (handshake with version check,
//! request/answer with timeouts, telemetry with sequence-gap accounting, experiments) over any
//! [`transport::Transport`] (serial port, pty, in-memory pair); [`error`] its typed errors
//! ([`ClientError`]) and [`describe`] device errors in words; [`connect()`] reaches the device a [`ConnectSpec`] names;
//! [`virtual_device`] runs the firmware core against a simulated plant in-process (feature
//! `virtual`); [`qemu`] boots the board image (feature `qemu`); [`session`] is the telemetry
//! pump and lossless recorder; [`recording`] the CSV recording format.
//!
//! Units: SI at the API, device integers on the wire (as documented per module).
//! Invariants: the client never names command-line flags; refused fields are named by the
//! protocol ([`stiffwall_proto::ConfigField::name`]) and carried as data in
//! [`ClientError::Refused`], for a front end to spell as it likes. This crate installs no
//! signal handler: a front end cancels [`cancel::ctrl_c`] (every client's experiments and
//! every session check a child of it), and any [`Cancel`] given to [`Client::set_cancel`]
//! aborts that client's experiments.
//!
//! ```
//! use stiffwall_client::{connect, ClientError, ConnectSpec};
//! use stiffwall_proto::{ConfigField, ErrorDetail};
//!
//! // The virtual device running a preset, as fast as this program reads.
//! let mut client = connect(&ConnectSpec::preset("maxon-re35", true))?;
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

#[cfg(feature = "qemu")]
pub mod board_emu;
pub mod cancel;
pub mod client;
pub mod connect;
pub mod describe;
pub mod error;
#[cfg(feature = "qemu")]
pub mod qemu;
pub mod recording;
pub mod session;
pub mod transport;
#[cfg(feature = "virtual")]
pub mod virtual_device;

pub use cancel::Cancel;
pub use client::Client;
pub use connect::{connect, ConnectSpec, VirtualPlant};
pub use error::ClientError;
