//! `stiffwall-proto`: the wire protocol shared by the stiffwall firmware and host.
//!
//! no_std, no allocation. Two layers, kept apart (smoltcp style):
//! - [`msg`]: the messages ([`HostMsg`] host → device, [`DeviceMsg`] device → host) and the
//!   servo configuration, serialized with postcard. Physical quantities are SI (`f32`); force
//!   and position on the device side are output codes and encoder counts, named as such.
//! - [`damper`]: the virtual damper's law in the servo configuration and its text form.
//! - [`profile`]: a haptic profile (walls, springs, detents, viscous zones) and each element's
//!   force law (protocol 5).
//! - [`kinds`]: what a message is, as values (its name, the request an `Ack` echoes, which
//!   error codes are framing errors and which are transient).
//! - [`frame`]: the framing. One frame on the wire is
//!   `COBS( version:u8 ++ postcard(msg) ++ CRC-32/ISO-HDLC(version ++ postcard) as 4 LE bytes ) ++ 0x00`.
//!   [`encode`] writes one frame into a caller buffer; [`FrameDecoder`] is fed byte by byte and
//!   yields a message or one of the distinct [`FrameError`]s.
//!
//! Invariants: a frame (including its 0x00 terminator) is at most [`MAX_FRAME`] bytes; decoding
//! never panics on any byte sequence; after any error the decoder resynchronizes at the next 0x00.
#![no_std]
#![cfg_attr(not(test), warn(missing_docs))]

#[cfg(test)]
extern crate std;

pub mod damper;
pub mod frame;
pub mod kinds;
pub mod msg;
pub mod profile;

pub use damper::{DamperLaw, ParseDamperLawError, LAW_NAME_LEN, MAX_DEADBAND_COUNTS};
pub use frame::{encode, FrameDecoder, FrameError, Message, MAX_FRAME, MAX_PAYLOAD};
pub use msg::*;
pub use profile::{Profile, ProfileElement, ProfileField, Side, MAX_DETENTS, MAX_PROFILE_ELEMENTS};
