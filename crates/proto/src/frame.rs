//! Framing: `COBS(version ++ postcard(msg) ++ CRC-32 LE) ++ 0x00`.
//!
//! Wire format only; no I/O. Sizes are bytes. The CRC is CRC-32/ISO-HDLC (the zlib/Ethernet
//! CRC-32) over `version ++ postcard(msg)`, appended little-endian. A frame including its 0x00
//! terminator is at most [`MAX_FRAME`] bytes, so the decoded payload is at most [`MAX_PAYLOAD`].
//!
//! Decoding checks, in order: length (→ [`FrameError::Oversize`]), COBS and minimum length
//! (→ [`FrameError::Cobs`]), CRC (→ [`FrameError::Crc`]), version byte
//! (→ [`FrameError::VersionMismatch`]), message tag (→ [`FrameError::UnknownTag`]), body
//! (→ [`FrameError::Deserialize`], also for trailing bytes). It never panics.
//!
//! Strictness: every message has exactly one encoding. Varints must be canonical (no
//! over-long forms such as `84 00` for 4) and fit their type (a fifth tag byte above `0x0f`
//! overflows a u32): the tag is checked by [`FrameError::UnknownTag`]'s varint reader and the
//! whole body by re-encoding the decoded message and comparing it byte for byte, so anything
//! non-canonical is [`FrameError::Deserialize`]. A frame ends at its first 0x00: the streaming
//! [`FrameDecoder`] starts the next frame with the byte after it, and [`decode_frame`] (which
//! takes exactly one frame) refuses a 0x00 anywhere but at the end ([`FrameError::Cobs`]).

use crate::msg::{DeviceMsg, ErrorCode, ErrorDetail, HostMsg, PROTOCOL_VERSION};
use crc::{Crc, CRC_32_ISO_HDLC};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// Largest frame on the wire, bytes, including the 0x00 terminator.
pub const MAX_FRAME: usize = 1024;
/// Largest decoded payload (version + postcard + CRC), bytes.
pub const MAX_PAYLOAD: usize = 1016;
const _: () = assert!(cobs::max_encoding_length(MAX_PAYLOAD) < MAX_FRAME);

/// Bytes of framing overhead inside the payload: version byte + 4 CRC bytes.
const OVERHEAD: usize = 5;

const CRC32: Crc<u32> = Crc::<u32>::new(&CRC_32_ISO_HDLC);

/// A message type of this protocol.
pub trait Message: Serialize + DeserializeOwned {
    /// Number of enum variants (tags ≥ this are [`FrameError::UnknownTag`]).
    const VARIANTS: u32;
}

impl Message for HostMsg {
    const VARIANTS: u32 = 19;
}

impl Message for DeviceMsg {
    const VARIANTS: u32 = 8;
}

/// Framing errors. Each maps to a distinct [`ErrorCode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameError {
    /// More than [`MAX_FRAME`] bytes before the 0x00 terminator.
    Oversize,
    /// Invalid COBS, or a payload shorter than version + CRC.
    Cobs,
    /// CRC mismatch.
    Crc,
    /// The version byte is not [`PROTOCOL_VERSION`].
    VersionMismatch {
        /// Version byte received.
        got: u8,
    },
    /// Message tag out of range.
    UnknownTag(u32),
    /// The body does not deserialize (or has trailing bytes).
    Deserialize,
    /// Encoding: the message does not fit the output buffer or [`MAX_PAYLOAD`].
    BufferTooSmall,
}

impl FrameError {
    /// The protocol error code for this error.
    #[must_use]
    pub fn code(self) -> ErrorCode {
        match self {
            FrameError::Oversize | FrameError::BufferTooSmall => ErrorCode::Oversize,
            FrameError::Cobs => ErrorCode::Cobs,
            FrameError::Crc => ErrorCode::Crc,
            FrameError::VersionMismatch { .. } => ErrorCode::VersionMismatch,
            FrameError::UnknownTag(_) => ErrorCode::UnknownTag,
            FrameError::Deserialize => ErrorCode::Deserialize,
        }
    }

    /// The error detail for this error.
    #[must_use]
    pub fn detail(self) -> ErrorDetail {
        match self {
            FrameError::VersionMismatch { got } => ErrorDetail::Version {
                got,
                expected: PROTOCOL_VERSION,
            },
            FrameError::UnknownTag(t) => ErrorDetail::Tag(t),
            _ => ErrorDetail::None,
        }
    }
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FrameError::Oversize => write!(f, "frame longer than {MAX_FRAME} bytes"),
            FrameError::Cobs => write!(f, "invalid COBS encoding or short frame"),
            FrameError::Crc => write!(f, "CRC mismatch"),
            FrameError::VersionMismatch { got } => {
                write!(f, "protocol version {got}, expected {PROTOCOL_VERSION}")
            }
            FrameError::UnknownTag(t) => write!(f, "unknown message tag {t}"),
            FrameError::Deserialize => write!(f, "message body does not deserialize"),
            FrameError::BufferTooSmall => write!(f, "message too large for the frame buffer"),
        }
    }
}

impl core::error::Error for FrameError {}

/// Encodes `msg` as one frame (terminator included) into `out`; returns the frame.
///
/// # Errors
/// [`FrameError::BufferTooSmall`] when the message exceeds [`MAX_PAYLOAD`] or `out`.
pub fn encode<'a, M: Serialize>(msg: &M, out: &'a mut [u8]) -> Result<&'a [u8], FrameError> {
    let mut payload = [0u8; MAX_PAYLOAD];
    let body_len = {
        let (head, rest) = payload.split_at_mut(1);
        head[0] = PROTOCOL_VERSION;
        let room = rest.len() - 4;
        let body =
            postcard::to_slice(msg, &mut rest[..room]).map_err(|_| FrameError::BufferTooSmall)?;
        body.len()
    };
    let crc_end = 1 + body_len;
    let crc = CRC32.checksum(&payload[..crc_end]);
    payload[crc_end..crc_end + 4].copy_from_slice(&crc.to_le_bytes());
    let total = crc_end + 4;
    let n = cobs::try_encode(&payload[..total], out).map_err(|_| FrameError::BufferTooSmall)?;
    let term = out.get_mut(n).ok_or(FrameError::BufferTooSmall)?;
    *term = 0;
    Ok(&out[..=n])
}

/// Reads a canonical postcard varint u32 from the start of `b`: `None` when it is cut short,
/// longer than 5 bytes, over-long (a final byte of 0 after the first), or overflows u32 (a
/// fifth byte above `0x0f`).
fn peek_varint(b: &[u8]) -> Option<u32> {
    let mut v: u32 = 0;
    for (i, &byte) in b.iter().take(5).enumerate() {
        if i == 4 && byte > 0x0f {
            return None;
        }
        v |= u32::from(byte & 0x7f).checked_shl(7 * i as u32)?;
        if byte & 0x80 == 0 {
            return (i == 0 || byte != 0).then_some(v);
        }
    }
    None
}

/// Decodes one COBS-decoded payload (version ++ postcard ++ CRC).
///
/// # Errors
/// The distinct [`FrameError`]s listed in the module header.
pub fn decode_payload<M: Message>(payload: &[u8]) -> Result<M, FrameError> {
    if payload.len() < OVERHEAD {
        return Err(FrameError::Cobs);
    }
    let (data, crc_bytes) = payload.split_at(payload.len() - 4);
    let mut crc = [0u8; 4];
    crc.copy_from_slice(crc_bytes);
    if CRC32.checksum(data) != u32::from_le_bytes(crc) {
        return Err(FrameError::Crc);
    }
    let (version, body) = data.split_at(1);
    if version[0] != PROTOCOL_VERSION {
        return Err(FrameError::VersionMismatch { got: version[0] });
    }
    let tag = peek_varint(body).ok_or(FrameError::Deserialize)?;
    if tag >= M::VARIANTS {
        return Err(FrameError::UnknownTag(tag));
    }
    let m = match postcard::take_from_bytes::<M>(body) {
        Ok((m, [])) => m,
        _ => return Err(FrameError::Deserialize),
    };
    // Canonical encoding only: the message must encode back to exactly these bytes.
    let mut again = [0u8; MAX_PAYLOAD];
    match postcard::to_slice(&m, &mut again) {
        Ok(b) if *b == *body => Ok(m),
        _ => Err(FrameError::Deserialize),
    }
}

/// Decodes one whole frame (with or without its 0x00 terminator), in place.
///
/// # Errors
/// As [`decode_payload`], plus [`FrameError::Oversize`] and [`FrameError::Cobs`].
pub fn decode_frame<M: Message>(frame: &mut [u8]) -> Result<M, FrameError> {
    let frame = match frame.split_last() {
        Some((0, _)) => {
            let l = frame.len() - 1;
            &mut frame[..l]
        }
        _ => frame,
    };
    if frame.len() >= MAX_FRAME {
        return Err(FrameError::Oversize);
    }
    if frame.contains(&0) {
        // Bytes after a delimiter: this is more than one frame.
        return Err(FrameError::Cobs);
    }
    let n = cobs::decode_in_place(frame).map_err(|_| FrameError::Cobs)?;
    let payload = frame.get(..n).ok_or(FrameError::Cobs)?;
    decode_payload(payload)
}

/// Streaming frame decoder, fed one byte at a time.
///
/// Holds at most [`MAX_FRAME`] − 1 encoded bytes. Empty frames (consecutive 0x00) are ignored.
/// After an oversize frame, bytes are discarded up to the next 0x00, which then yields
/// [`FrameError::Oversize`] once.
#[derive(Debug)]
pub struct FrameDecoder {
    buf: [u8; MAX_FRAME],
    len: usize,
    overflow: bool,
}

impl Default for FrameDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl FrameDecoder {
    /// An empty decoder.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            buf: [0; MAX_FRAME],
            len: 0,
            overflow: false,
        }
    }

    /// Drops any partial frame.
    pub fn reset(&mut self) {
        self.len = 0;
        self.overflow = false;
    }

    /// Bytes of the partial frame held.
    #[must_use]
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Feeds one byte; returns a result when `byte` completes a frame.
    pub fn feed<M: Message>(&mut self, byte: u8) -> Option<Result<M, FrameError>> {
        if byte == 0 {
            let len = self.len;
            let overflow = self.overflow;
            self.reset();
            if overflow {
                return Some(Err(FrameError::Oversize));
            }
            if len == 0 {
                return None;
            }
            let frame = self.buf.get_mut(..len)?;
            return Some(decode_frame(frame));
        }
        if self.overflow {
            return None;
        }
        match self.buf.get_mut(self.len) {
            Some(slot) if self.len < MAX_FRAME - 1 => {
                *slot = byte;
                self.len += 1;
            }
            _ => {
                self.len = 0;
                self.overflow = true;
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::damper::DamperLaw;
    use crate::msg::*;

    #[test]
    fn frame_error_is_a_core_error_naming_its_limit() {
        use std::string::ToString;
        // A no_std caller can hold it as `&dyn core::error::Error` (no `std` feature needed).
        let e: &dyn core::error::Error = &FrameError::Oversize;
        assert!(e.to_string().contains(&MAX_FRAME.to_string()));
        let v = FrameError::VersionMismatch { got: 9 }.to_string();
        assert!(
            v.contains('9') && v.contains(&PROTOCOL_VERSION.to_string()),
            "{v}"
        );
    }

    fn roundtrip<M: Message + PartialEq + core::fmt::Debug>(m: &M) -> usize {
        let mut out = [0u8; MAX_FRAME];
        let f = encode(m, &mut out).unwrap();
        let n = f.len();
        assert_eq!(
            f.iter().filter(|&&b| b == 0).count(),
            1,
            "only the terminator is 0"
        );
        let mut d = FrameDecoder::new();
        let mut got = None;
        for &b in f {
            if let Some(r) = d.feed::<M>(b) {
                got = Some(r.unwrap());
            }
        }
        assert_eq!(got.as_ref(), Some(m));
        n
    }

    fn decode_bytes(bytes: &[u8]) -> Result<HostMsg, FrameError> {
        let mut v = bytes.to_vec();
        let whole = decode_frame::<HostMsg>(&mut v);
        // The streaming decoder agrees on a single frame.
        let mut d = FrameDecoder::new();
        let mut streamed = None;
        for &b in bytes {
            streamed = d.feed::<HostMsg>(b).or(streamed);
        }
        assert_eq!(streamed, Some(whole.clone()), "{bytes:02x?}");
        whole
    }

    /// Issue 11, item 6: an over-long varint tag (`84 00` for 4) is not LoadDefaults.
    #[test]
    fn overlong_varint_tag_is_refused() {
        // Version 5, the tag `84 00`, the CRC; COBS: `03` (two bytes, then the 0x00), `05`
        // (the four CRC bytes).
        let frame = [0x03, 0x05, 0x84, 0x05, 0xb6, 0x46, 0x65, 0xa6, 0x00];
        // The CRC is right (zlib.crc32(b'\x05\x84\x00')): only the encoding is wrong.
        assert_eq!(
            CRC32.checksum(&[0x05, 0x84, 0x00]).to_le_bytes(),
            [0xb6, 0x46, 0x65, 0xa6]
        );
        assert_eq!(decode_bytes(&frame), Err(FrameError::Deserialize));
        // The canonical form of the same message decodes.
        let mut out = [0u8; 32];
        let good = encode(&HostMsg::LoadDefaults, &mut out).unwrap().to_vec();
        assert_eq!(decode_bytes(&good), Ok(HostMsg::LoadDefaults));
    }

    /// Issue 11, item 6: a fifth varint byte above 0x0f overflows u32 and is a decode error,
    /// not `UnknownTag(4294967295)`.
    #[test]
    fn varint_overflow_in_fifth_byte_is_a_decode_error() {
        // Version 5, the five varint bytes, zlib.crc32(b'\x05\xff\xff\xff\xff\x7f') LE.
        let frame = [
            0x0b, 0x05, 0xff, 0xff, 0xff, 0xff, 0x7f, 0x5f, 0x54, 0x68, 0x18, 0x00,
        ];
        assert_eq!(decode_bytes(&frame), Err(FrameError::Deserialize));
        // The largest u32 (fifth byte 0x0f) is a valid varint, hence an unknown tag.
        let mut out = [0u8; 32];
        let f = encode(&u32::MAX, &mut out).unwrap().to_vec();
        assert_eq!(decode_bytes(&f), Err(FrameError::UnknownTag(u32::MAX)));
    }

    /// Over-long varints inside a body (not only in the tag) are refused too.
    #[test]
    fn overlong_varint_in_a_field_is_refused() {
        // StreamStart (tag 5) with decimation 1 written as `81 00`.
        let payload_body = [0x05u8, 0x05, 0x81, 0x00];
        let mut payload = payload_body.to_vec();
        payload.extend(CRC32.checksum(&payload_body).to_le_bytes());
        assert_eq!(
            decode_payload::<HostMsg>(&payload),
            Err(FrameError::Deserialize)
        );
        let canonical_body = [0x05u8, 0x05, 0x01];
        let mut payload = canonical_body.to_vec();
        payload.extend(CRC32.checksum(&canonical_body).to_le_bytes());
        assert_eq!(
            decode_payload::<HostMsg>(&payload),
            Ok(HostMsg::StreamStart { decimation: 1 })
        );
    }

    /// Bytes after a frame's delimiter: `decode_frame` (exactly one frame) refuses them; the
    /// streaming decoder starts the next frame with them.
    #[test]
    fn bytes_after_a_delimiter_start_the_next_frame() {
        let mut out = [0u8; 32];
        let hb = encode(&HostMsg::Heartbeat, &mut out).unwrap().to_vec();
        let mut two = hb.clone();
        two.extend_from_slice(&[0x05, 0x01, 0x02]); // a trailing partial frame
        assert_eq!(
            decode_frame::<HostMsg>(&mut two.clone()),
            Err(FrameError::Cobs)
        );
        let mut with_junk = hb[..hb.len() - 1].to_vec();
        with_junk.extend_from_slice(&[0x00, 0x03, 0x01]);
        assert_eq!(
            decode_frame::<HostMsg>(&mut with_junk),
            Err(FrameError::Cobs)
        );
        let mut d = FrameDecoder::new();
        let mut got = std::vec::Vec::new();
        for &b in hb.iter().chain(&hb) {
            if let Some(r) = d.feed::<HostMsg>(b) {
                got.push(r);
            }
        }
        assert_eq!(got, [Ok(HostMsg::Heartbeat), Ok(HostMsg::Heartbeat)]);
    }

    #[test]
    fn heartbeat_literal_bytes() {
        // payload = [version 5, tag 10 (Heartbeat)] ++ CRC-32 LE.
        let mut out = [0u8; 32];
        let f = encode(&HostMsg::Heartbeat, &mut out).unwrap();
        let crc = CRC32.checksum(&[5, 10]).to_le_bytes();
        assert_eq!(crc, [0xa4, 0x0f, 0x7b, 0xdc]); // zlib.crc32(b'\x05\x0a')
        assert_eq!(f, &[0x07, 0x05, 0x0a, 0xa4, 0x0f, 0x7b, 0xdc, 0x00]);
        let mut d = FrameDecoder::new();
        let mut r = None;
        for &b in f {
            r = d.feed::<HostMsg>(b).or(r);
        }
        assert_eq!(r, Some(Ok(HostMsg::Heartbeat)));
    }

    #[test]
    fn stream_start_literal_bytes() {
        // StreamStart is tag 5, decimation 300 = varint [0xac, 0x02]; version 5;
        // zlib.crc32(b'\x05\x05\xac\x02') LE.
        let mut out = [0u8; 32];
        let f = encode(&HostMsg::StreamStart { decimation: 300 }, &mut out).unwrap();
        assert_eq!(
            f,
            &[0x09, 0x05, 0x05, 0xac, 0x02, 0x0c, 0x7f, 0xed, 0xfc, 0x00]
        );
    }

    #[test]
    fn prepare_test_tag_and_rule_bytes() {
        // PrepareTest is tag 16 (appended after Impact, 15); its ServoConfig, then
        // min_run_ticks 300 = varint [0xac, 0x02], within_one_count true = 0x01,
        // decay_base_ticks 2000 = [0xd0, 0x0f].
        let config = ServoConfig::default();
        let mut cfg_bytes = [0u8; 128];
        let cfg_len = postcard::to_slice(&config, &mut cfg_bytes).unwrap().len();
        let mut buf = [0u8; 160];
        let body = postcard::to_slice(
            &HostMsg::PrepareTest {
                config,
                min_run_ticks: 300,
                within_one_count: true,
                decay_base_ticks: 2000,
            },
            &mut buf,
        )
        .unwrap();
        assert_eq!(body[0], 0x10);
        assert_eq!(&body[1..=cfg_len], &cfg_bytes[..cfg_len]);
        assert_eq!(&body[cfg_len + 1..], &[0xac, 0x02, 0x01, 0xd0, 0x0f]);
    }

    #[test]
    fn errors_are_distinct() {
        let mut d = FrameDecoder::new();
        // Bad CRC.
        let bad_crc = [0x07, 0x05, 0x0a, 0xa4, 0x0f, 0x7b, 0xdd, 0x00];
        let r: std::vec::Vec<_> = bad_crc
            .iter()
            .filter_map(|&b| d.feed::<HostMsg>(b))
            .collect();
        assert_eq!(r, [Err(FrameError::Crc)]);
        // Versions 1 and 2 (a host or device of protocol 1 or 2).
        let mut enc = [0u8; 16];
        for old in [1u8, 2, 3, 4] {
            let crc = CRC32.checksum(&[old, 10]).to_le_bytes();
            let mut p = std::vec![old, 10];
            p.extend_from_slice(&crc);
            let n = cobs::encode(&p, &mut enc);
            let r: std::vec::Vec<_> = enc[..n]
                .iter()
                .chain(&[0])
                .filter_map(|&b| d.feed::<HostMsg>(b))
                .collect();
            assert_eq!(r, [Err(FrameError::VersionMismatch { got: old })]);
        }
        // Unknown tag 99.
        let crc = CRC32.checksum(&[5, 99]).to_le_bytes();
        let mut p = std::vec![5u8, 99];
        p.extend_from_slice(&crc);
        let n = cobs::encode(&p, &mut enc);
        let r: std::vec::Vec<_> = enc[..n]
            .iter()
            .chain(&[0])
            .filter_map(|&b| d.feed::<HostMsg>(b))
            .collect();
        assert_eq!(r, [Err(FrameError::UnknownTag(99))]);
        // Truncated body: StreamStart without decimation.
        let crc = CRC32.checksum(&[5, 5]).to_le_bytes();
        let mut p = std::vec![5u8, 5];
        p.extend_from_slice(&crc);
        let n = cobs::encode(&p, &mut enc);
        let r: std::vec::Vec<_> = enc[..n]
            .iter()
            .chain(&[0])
            .filter_map(|&b| d.feed::<HostMsg>(b))
            .collect();
        assert_eq!(r, [Err(FrameError::Deserialize)]);
        // Short frame, invalid COBS.
        let r: std::vec::Vec<_> = [0x02, 0x02, 0x00, 0x05, 0x02, 0x00]
            .iter()
            .filter_map(|&b| d.feed::<HostMsg>(b))
            .collect();
        assert_eq!(r, [Err(FrameError::Cobs), Err(FrameError::Cobs)]);
        // Oversize, then recovery.
        let mut r = std::vec::Vec::new();
        for _ in 0..MAX_FRAME + 10 {
            r.extend(d.feed::<HostMsg>(0x55));
        }
        r.extend(d.feed::<HostMsg>(0));
        for &b in &[0x07, 0x05, 0x0a, 0xa4, 0x0f, 0x7b, 0xdc, 0x00] {
            r.extend(d.feed::<HostMsg>(b));
        }
        assert_eq!(r, [Err(FrameError::Oversize), Ok(HostMsg::Heartbeat)]);
    }

    pub(crate) fn all_host_msgs() -> std::vec::Vec<HostMsg> {
        let cfg = ServoConfig {
            stiffness: 1500.0,
            damping: 0.5,
            servo_rate_hz: 1000,
            extra_delay_ticks: 2,
            coarsen_shift: 3,
            wall: WallMode::OneSided,
            wall_position: -1234,
            force_limit: 2.5,
            max_velocity: 0.3,
            energy_monitor: true,
            energy_limit: 0.01,
            energy_growth_cycles: 4,
            encoder_jump_counts: 500,
            heartbeat_timeout_ms: 250,
            safe_mode: SafeMode::Damping,
            safe_damping: 1.0,
            damper: DamperLaw::DeadBand { counts: 3 },
            travel_min: Some(-70_000),
            travel_max: Some(i32::MAX),
        };
        std::vec![
            HostMsg::Hello {
                protocol_version: PROTOCOL_VERSION
            },
            HostMsg::GetConfig,
            HostMsg::SetConfig(cfg),
            HostMsg::SaveConfig,
            HostMsg::LoadDefaults,
            HostMsg::StreamStart { decimation: 7 },
            HostMsg::StreamStop,
            HostMsg::Release {
                deflection_ticks: -5,
                ticks: 3000
            },
            HostMsg::Excite {
                profile: ExciteProfile::Chirp {
                    amplitude: 100,
                    f0_hz: 1.0,
                    f1_hz: 50.0
                },
                ticks: 5000,
            },
            HostMsg::Excite {
                profile: ExciteProfile::Steps {
                    low: -10,
                    high: 10,
                    half_period_ticks: 100
                },
                ticks: 5000,
            },
            HostMsg::Excite {
                profile: ExciteProfile::Table {
                    len: 64,
                    hold_ticks: 2
                },
                ticks: 1
            },
            HostMsg::TableChunk {
                offset: 32,
                values: (0..TABLE_CHUNK as i16).map(|v| v * -1000).collect(),
            },
            HostMsg::Heartbeat,
            HostMsg::GetFaults,
            HostMsg::ClearFaults,
            HostMsg::Stop,
            HostMsg::Shutdown { exit_code: 3 },
            HostMsg::Impact {
                start_ticks: -40,
                velocity_milliticks: 5000,
                ticks: 3000,
            },
            HostMsg::PrepareTest {
                config: ServoConfig {
                    stiffness: 1500.0,
                    damping: 2.5,
                    damper: DamperLaw::Difference,
                    ..ServoConfig::default()
                },
                min_run_ticks: 300,
                within_one_count: true,
                decay_base_ticks: 1200,
            },
        ]
    }

    pub(crate) fn all_device_msgs() -> std::vec::Vec<DeviceMsg> {
        let info = DeviceInfo {
            protocol_version: PROTOCOL_VERSION,
            firmware_name: "stiffwall".try_into().unwrap(),
            firmware_version: "0.1.0".try_into().unwrap(),
            board: "qemu-an386".try_into().unwrap(),
            servo_rate_hz: 1000,
            counts_per_rev: 8192,
            resolution: 7.67e-4,
            encoder_bits: 16,
            force_per_code: 1e-5,
            max_code: 32767,
            limits: Limits {
                min_rate_hz: 100,
                max_rate_hz: 20000,
                max_stiffness: 1e3,
                max_force: 0.3,
                max_delay_ticks: 31,
                max_coarsen_shift: 16,
                telemetry_batch: TELEMETRY_BATCH as u16,
                max_table: MAX_TABLE as u16,
            },
        };
        let full = TelemetryBatch {
            seq: u32::MAX - 3,
            dropped: 17,
            samples: (0..TELEMETRY_BATCH)
                .map(|i| Sample {
                    tick: u32::MAX - i as u32,
                    count: i32::MIN + i as i32,
                    force_code: i32::MAX - i as i32,
                    flags: u16::MAX,
                    energy: u32::MAX,
                })
                .collect(),
        };
        let mut v = std::vec![
            DeviceMsg::HelloReply(info),
            DeviceMsg::Ack(Request::Heartbeat),
            DeviceMsg::Telemetry(full),
            DeviceMsg::Faults(FaultReport {
                latched: 5,
                first_tick: 99,
                safe_mode: true
            }),
            DeviceMsg::ExperimentDone {
                kind: ExperimentKind::Release,
                completed: false,
                faults: 1
            },
            DeviceMsg::Error {
                code: ErrorCode::InvalidConfig,
                detail: ErrorDetail::Field {
                    field: ConfigField::Stiffness,
                    min: 0.0,
                    max: 1e3
                },
            },
            DeviceMsg::Error {
                code: ErrorCode::Busy,
                detail: ErrorDetail::Text("running".try_into().unwrap())
            },
        ];
        if let HostMsg::SetConfig(c) = all_host_msgs()[2] {
            v.push(DeviceMsg::Config(c));
        }
        v
    }

    #[test]
    fn every_message_round_trips() {
        for m in all_host_msgs() {
            roundtrip(&m);
        }
        let mut largest = 0;
        for m in all_device_msgs() {
            largest = largest.max(roundtrip(&m));
        }
        // The worst-case telemetry batch must fit.
        assert!(largest <= MAX_FRAME, "largest frame {largest}");
    }

    #[test]
    fn tag_counts_match_enums() {
        // The last variant's tag is VARIANTS - 1 (protocol 5's profile messages are last).
        let mut buf = [0u8; 128];
        assert_eq!(
            postcard::to_slice(&HostMsg::GetProfile, &mut buf).unwrap()[0] as u32,
            HostMsg::VARIANTS - 1
        );
        let m = DeviceMsg::Profile(crate::profile::Profile::default());
        assert_eq!(
            postcard::to_slice(&m, &mut buf).unwrap()[0] as u32,
            DeviceMsg::VARIANTS - 1
        );
    }
}

#[cfg(test)]
mod proptests {
    use super::tests::{all_device_msgs, all_host_msgs};
    use super::*;
    use proptest::prelude::*;

    fn feed_all(d: &mut FrameDecoder, bytes: &[u8]) -> std::vec::Vec<Result<HostMsg, FrameError>> {
        bytes.iter().filter_map(|&b| d.feed::<HostMsg>(b)).collect()
    }

    fn frame_of(i: usize) -> std::vec::Vec<u8> {
        let msgs = all_host_msgs();
        let mut out = [0u8; MAX_FRAME];
        encode(&msgs[i % msgs.len()], &mut out).unwrap().to_vec()
    }

    proptest! {
        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..3000)) {
            let mut d = FrameDecoder::new();
            let _ = feed_all(&mut d, &bytes);
            // Resynchronizes: a valid frame after a delimiter decodes.
            let f = frame_of(0);
            let mut tail = std::vec![0u8];
            tail.extend_from_slice(&f);
            let r = feed_all(&mut d, &tail);
            prop_assert_eq!(r.last().cloned(), Some(Ok(HostMsg::Hello { protocol_version: PROTOCOL_VERSION })));
        }

        #[test]
        fn truncated_frames_error(i in 0usize..16, cut in 1usize..200) {
            let f = frame_of(i);
            let cut = cut.min(f.len() - 1);
            let mut t = f[..f.len() - 1 - cut.min(f.len() - 1)].to_vec();
            t.push(0);
            let mut d = FrameDecoder::new();
            let r = feed_all(&mut d, &t);
            prop_assert!(r.len() <= 1);
            if let Some(r) = r.first() {
                prop_assert!(r.is_err(), "truncated frame decoded: {:?}", r);
            }
        }

        #[test]
        fn flipped_bit_is_detected(i in 0usize..16, pos in any::<prop::sample::Index>(), bit in 0u8..8) {
            let mut f = frame_of(i);
            let body = f.len() - 1;
            let p = pos.index(body);
            f[p] ^= 1 << bit;
            let mut d = FrameDecoder::new();
            let r = feed_all(&mut d, &f);
            // A flip may create a 0x00 and split the frame; every piece must be an error.
            for x in &r {
                prop_assert!(x.is_err(), "flipped frame decoded: {:?}", x);
            }
        }

        #[test]
        fn oversize_is_oversize(extra in 0usize..500, fill in 1u8..=255) {
            let bytes: std::vec::Vec<u8> = core::iter::repeat_n(fill, MAX_FRAME + extra).chain([0]).collect();
            let mut d = FrameDecoder::new();
            prop_assert_eq!(feed_all(&mut d, &bytes), std::vec![Err(FrameError::Oversize)]);
        }

        #[test]
        fn device_msgs_round_trip_through_decode_frame(i in 0usize..8) {
            let msgs = all_device_msgs();
            let m = &msgs[i % msgs.len()];
            let mut out = [0u8; MAX_FRAME];
            let n = encode(m, &mut out).unwrap().len();
            prop_assert_eq!(&decode_frame::<DeviceMsg>(&mut out[..n]).unwrap(), m);
        }
    }

    /// The largest profile (16 detent trains, the widest element) fits one frame's payload
    /// with the message tag around it.
    #[test]
    fn the_largest_profile_fits_a_frame() {
        use crate::profile::{Profile, ProfileElement, MAX_DETENTS, MAX_PROFILE_ELEMENTS};
        let mut p = Profile::default();
        for _ in 0..MAX_PROFILE_ELEMENTS {
            p.elements
                .push(ProfileElement::Detents {
                    first: i32::MIN,
                    pitch_counts: f64::MAX,
                    count: MAX_DETENTS,
                    strength: f32::MAX,
                    damping: f32::MAX,
                    damper: crate::damper::DamperLaw::DeadBand { counts: 8 },
                })
                .unwrap();
        }
        let mut buf = [0u8; MAX_PAYLOAD];
        let n = postcard::to_slice(&p, &mut buf).unwrap().len();
        assert!(n + 8 < MAX_PAYLOAD, "{n} bytes");
    }
}
