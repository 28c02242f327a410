//! Two-slot, CRC-protected store of the configuration and the haptic profile.
//!
//! Record layout (bytes, little-endian), at offset 0 of a slot:
//! `magic "SWC4" (4) | generation u32 (4) | len u16 (2) | postcard(ServoConfig, Profile) (len) | CRC-32 (4)`
//! with the CRC-32/ISO-HDLC over everything before it (postcard writes the pair as the config's
//! bytes followed by the profile's: its element count, then each element).
//!
//! Versions: records are written with magic `SWC4` (protocol 5: protocol 3's [`ServoConfig`]
//! and the active [`Profile`]). Older records (same layout) are still read, with an empty
//! profile (the config's wall, all they could render): `SWC3` (protocol 3's config, ending
//! with its travel window `travel_min`, `travel_max`); `SWC2` (protocol 2's config: every field
//! but the travel window) with no travel window, the supervision it ran with; `SWC1` (protocol
//! 1's: every field before `damper`) also with `damper = DamperLaw::Difference`, the law it was
//! saved under. The next save writes `SWC4`. Generations count across all four.
//!
//! Size: the largest record (the longest config and [`MAX_PROFILE_ELEMENTS`] detent trains,
//! every varint at its longest) is [`LARGEST_RECORD`] bytes, within [`RECORD_MAX`]; a board's
//! config slot must hold it (the test `the_largest_record_fits` states the figure).
//!
//! Invariant: [`ConfigStore::save`] always writes the slot that does *not* hold the newest
//! valid record, with generation = newest + 1. A write interrupted at any byte therefore leaves
//! the newest valid record untouched, and [`ConfigStore::load`] returns it (the record with the
//! highest generation among the slots whose magic, length and CRC check).

use crate::hal::{ConfigStorage, StorageError};
use crc::{Crc, CRC_32_ISO_HDLC};
use serde::Deserialize;
use stiffwall_proto::profile::{Profile, MAX_PROFILE_ELEMENTS};
use stiffwall_proto::{DamperLaw, SafeMode, ServoConfig, WallMode};

/// Largest record, bytes (a config slot holds at least this many).
pub const RECORD_MAX: usize = 640;
/// The longest record the firmware writes: a header, the longest config (64 bytes), the
/// longest profile (1 + 16 × 27 bytes: detent trains, every varint at its longest), the CRC.
pub const LARGEST_RECORD: usize = HEADER + 64 + 1 + MAX_PROFILE_ELEMENTS * 27 + 4;
const _: () = assert!(LARGEST_RECORD <= RECORD_MAX);
/// The magic of the records written (protocol 3's config and protocol 5's profile).
const MAGIC: [u8; 4] = *b"SWC4";
/// The magic of a record of protocol 3's config alone, read with an empty profile.
const MAGIC_V3: [u8; 4] = *b"SWC3";
/// The magic of a record of protocol 2's config ([`ServoConfigV2`]), read and migrated.
const MAGIC_V2: [u8; 4] = *b"SWC2";
/// The magic of a record of protocol 1's config ([`ServoConfigV1`]), read and migrated.
const MAGIC_V1: [u8; 4] = *b"SWC1";
const HEADER: usize = 10;
const CRC32: Crc<u32> = Crc::<u32>::new(&CRC_32_ISO_HDLC);

/// The two-slot config store over a [`ConfigStorage`].
#[derive(Debug)]
pub struct ConfigStore<S: ConfigStorage> {
    storage: S,
}

/// Protocol 1's [`ServoConfig`], the payload of an `SWC1` record: today's fields before
/// `damper`, in the same order (postcard writes a struct's fields in order, without names).
/// Only read, to migrate.
#[derive(Debug, Deserialize)]
struct ServoConfigV1 {
    stiffness: f32,
    damping: f32,
    servo_rate_hz: u32,
    extra_delay_ticks: u8,
    coarsen_shift: u8,
    wall: WallMode,
    wall_position: i32,
    force_limit: f32,
    max_velocity: f32,
    energy_monitor: bool,
    energy_limit: f32,
    energy_growth_cycles: u8,
    encoder_jump_counts: u32,
    heartbeat_timeout_ms: u32,
    safe_mode: SafeMode,
    safe_damping: f32,
}

/// Protocol 2's [`ServoConfig`], the payload of an `SWC2` record: protocol 1's fields, then
/// `damper` (postcard writes a nested struct's fields in place, without framing, so this is
/// byte for byte the flat protocol-2 struct). Only read, to migrate.
#[derive(Debug, Deserialize)]
struct ServoConfigV2 {
    v1: ServoConfigV1,
    damper: DamperLaw,
}

impl From<ServoConfigV2> for ServoConfig {
    /// The same config without a travel window (protocol 2 had none).
    fn from(c: ServoConfigV2) -> Self {
        Self {
            damper: c.damper,
            ..c.v1.into()
        }
    }
}

impl From<ServoConfigV1> for ServoConfig {
    /// The same config with the damper it ran with (the plain backward difference) and no
    /// travel window.
    fn from(c: ServoConfigV1) -> Self {
        Self {
            stiffness: c.stiffness,
            damping: c.damping,
            servo_rate_hz: c.servo_rate_hz,
            extra_delay_ticks: c.extra_delay_ticks,
            coarsen_shift: c.coarsen_shift,
            wall: c.wall,
            wall_position: c.wall_position,
            force_limit: c.force_limit,
            max_velocity: c.max_velocity,
            energy_monitor: c.energy_monitor,
            energy_limit: c.energy_limit,
            energy_growth_cycles: c.energy_growth_cycles,
            encoder_jump_counts: c.encoder_jump_counts,
            heartbeat_timeout_ms: c.heartbeat_timeout_ms,
            safe_mode: c.safe_mode,
            safe_damping: c.safe_damping,
            damper: DamperLaw::Difference,
            travel_min: None,
            travel_max: None,
        }
    }
}

/// The protocol of a record's config, by its magic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Layout {
    V1,
    V2,
    V3,
    V4,
}

/// What a record holds: its generation, the config, the profile.
type Record = (u32, ServoConfig, Profile);

/// Parses one record (`SWC4`, or `SWC3` / `SWC2` / `SWC1` migrated, with an empty profile);
/// `None` if it is not a valid record.
fn parse(buf: &[u8]) -> Option<Record> {
    let magic = buf.get(..4)?;
    let layout = if magic == MAGIC {
        Layout::V4
    } else if magic == MAGIC_V3 {
        Layout::V3
    } else if magic == MAGIC_V2 {
        Layout::V2
    } else if magic == MAGIC_V1 {
        Layout::V1
    } else {
        return None;
    };
    let gen = u32::from_le_bytes(buf.get(4..8)?.try_into().ok()?);
    let len = usize::from(u16::from_le_bytes(buf.get(8..10)?.try_into().ok()?));
    let end = HEADER.checked_add(len)?;
    let crc = u32::from_le_bytes(buf.get(end..end.checked_add(4)?)?.try_into().ok()?);
    if CRC32.checksum(buf.get(..end)?) != crc {
        return None;
    }
    let body = buf.get(HEADER..end)?;
    let (cfg, profile) = match layout {
        Layout::V1 => (
            postcard::from_bytes::<ServoConfigV1>(body).ok()?.into(),
            Profile::default(),
        ),
        Layout::V2 => (
            postcard::from_bytes::<ServoConfigV2>(body).ok()?.into(),
            Profile::default(),
        ),
        Layout::V3 => (postcard::from_bytes(body).ok()?, Profile::default()),
        Layout::V4 => postcard::from_bytes(body).ok()?,
    };
    Some((gen, cfg, profile))
}

/// Builds a record for `cfg` and `profile` with `gen` into `buf`; returns its length.
fn build(
    cfg: &ServoConfig,
    profile: &Profile,
    gen: u32,
    buf: &mut [u8; RECORD_MAX],
) -> Option<usize> {
    buf[..4].copy_from_slice(&MAGIC);
    buf[4..8].copy_from_slice(&gen.to_le_bytes());
    let len = postcard::to_slice(&(cfg, profile), &mut buf[HEADER..RECORD_MAX - 4])
        .ok()?
        .len();
    buf[8..10].copy_from_slice(&u16::try_from(len).ok()?.to_le_bytes());
    let end = HEADER + len;
    let crc = CRC32.checksum(&buf[..end]);
    buf.get_mut(end..end + 4)?
        .copy_from_slice(&crc.to_le_bytes());
    Some(end + 4)
}

impl<S: ConfigStorage> ConfigStore<S> {
    /// Wraps `storage`.
    pub fn new(storage: S) -> Self {
        Self { storage }
    }

    /// The underlying storage.
    pub fn storage_mut(&mut self) -> &mut S {
        &mut self.storage
    }

    /// Consumes the store, returning the storage.
    pub fn into_inner(self) -> S {
        self.storage
    }

    fn read_slot(&mut self, slot: usize) -> Option<Record> {
        let mut buf = [0u8; RECORD_MAX];
        let n = self.storage.slot_len().min(RECORD_MAX);
        let b = buf.get_mut(..n)?;
        self.storage.read(slot, b).ok()?;
        parse(b)
    }

    /// The newest valid record: `(slot, (generation, config, profile))`.
    fn newest_record(&mut self) -> Option<(usize, Record)> {
        let a = self.read_slot(0).map(|r| (0, r));
        let b = self.read_slot(1).map(|r| (1, r));
        match (a, b) {
            (Some(a), Some(b)) => Some(if (b.1).0.wrapping_sub((a.1).0) as i32 > 0 {
                b
            } else {
                a
            }),
            (a, b) => a.or(b),
        }
    }

    /// The newest valid record: `(slot, generation, config)`.
    pub fn newest(&mut self) -> Option<(usize, u32, ServoConfig)> {
        self.newest_record().map(|(s, (g, c, _))| (s, g, c))
    }

    /// The newest valid config, if any.
    pub fn load(&mut self) -> Option<ServoConfig> {
        self.newest().map(|(_, _, c)| c)
    }

    /// The newest valid config and the profile saved with it (empty for a record older than
    /// protocol 5), if any.
    pub fn load_with_profile(&mut self) -> Option<(ServoConfig, Profile)> {
        self.newest_record().map(|(_, (_, c, p))| (c, p))
    }

    /// Saves `cfg` with an empty profile (see [`ConfigStore::save_with_profile`]).
    ///
    /// # Errors
    /// As [`ConfigStore::save_with_profile`].
    pub fn save(&mut self, cfg: &ServoConfig) -> Result<(), StorageError> {
        self.save_with_profile(cfg, &Profile::default())
    }

    /// Saves `cfg` and `profile` into the slot not holding the newest record.
    ///
    /// # Errors
    /// [`StorageError`] if the storage is too small or the write failed (the previous record
    /// stays loadable).
    pub fn save_with_profile(
        &mut self,
        cfg: &ServoConfig,
        profile: &Profile,
    ) -> Result<(), StorageError> {
        let (slot, gen) = match self.newest() {
            Some((s, g, _)) => (1 - s, g.wrapping_add(1)),
            None => (0, 1),
        };
        let mut buf = [0u8; RECORD_MAX];
        let n = build(cfg, profile, gen, &mut buf)
            .ok_or(StorageError::RecordTooLong { max: RECORD_MAX })?;
        let slot_len = self.storage.slot_len();
        if n > slot_len {
            return Err(StorageError::TooLong { len: n, slot_len });
        }
        self.storage.write(slot, &buf[..n])
    }
}

/// In-memory storage (for tests and the virtual device), with optional write interruption.
#[derive(Debug, Clone)]
pub struct MemStorage {
    /// Slot contents.
    pub slots: [[u8; RECORD_MAX]; 2],
    /// When `Some(k)`, the next write stops after `k` bytes and fails (then resets to `None`).
    pub interrupt_after: Option<usize>,
    /// Flash semantics: a write first erases the slot to 0xFF.
    pub erase_first: bool,
}

impl Default for MemStorage {
    fn default() -> Self {
        Self {
            slots: [[0xff; RECORD_MAX]; 2],
            interrupt_after: None,
            erase_first: true,
        }
    }
}

impl ConfigStorage for MemStorage {
    fn slot_len(&self) -> usize {
        RECORD_MAX
    }
    fn read(&mut self, slot: usize, buf: &mut [u8]) -> Result<(), StorageError> {
        let s = self.slots.get(slot).ok_or(StorageError::Slot { slot })?;
        let src = s.get(..buf.len()).ok_or(StorageError::TooLong {
            len: buf.len(),
            slot_len: RECORD_MAX,
        })?;
        buf.copy_from_slice(src);
        Ok(())
    }
    fn write(&mut self, slot: usize, data: &[u8]) -> Result<(), StorageError> {
        let cut = self.interrupt_after.take();
        let erase = self.erase_first;
        let s = self
            .slots
            .get_mut(slot)
            .ok_or(StorageError::Slot { slot })?;
        if data.len() > s.len() {
            return Err(StorageError::TooLong {
                len: data.len(),
                slot_len: RECORD_MAX,
            });
        }
        if erase {
            s.fill(0xff);
        }
        let n = cut.map_or(data.len(), |k| k.min(data.len()));
        s[..n].copy_from_slice(&data[..n]);
        if cut.is_some() {
            Err(StorageError::Interrupted { written: n })
        } else {
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stiffwall_proto::profile::{ProfileElement, Side, MAX_DETENTS};

    /// A record of `cfg` with no profile.
    fn build(cfg: &ServoConfig, gen: u32, buf: &mut [u8; RECORD_MAX]) -> Option<usize> {
        super::build(cfg, &Profile::default(), gen, buf)
    }

    /// A record's generation and config, its profile empty.
    fn parse(buf: &[u8]) -> Option<(u32, ServoConfig)> {
        super::parse(buf).map(|(g, c, p)| {
            assert_eq!(p, Profile::default());
            (g, c)
        })
    }

    fn cfg(k: f32) -> ServoConfig {
        ServoConfig {
            stiffness: k,
            ..ServoConfig::default()
        }
    }

    #[test]
    fn empty_store_loads_nothing_then_saves() {
        let mut s = ConfigStore::new(MemStorage::default());
        assert_eq!(s.load(), None);
        s.save(&cfg(1.0)).unwrap();
        assert_eq!(s.load(), Some(cfg(1.0)));
        s.save(&cfg(2.0)).unwrap();
        s.save(&cfg(3.0)).unwrap();
        assert_eq!(s.load(), Some(cfg(3.0)));
        assert_eq!(s.newest().unwrap().1, 3);
    }

    #[test]
    fn record_literal_header() {
        let mut buf = [0u8; RECORD_MAX];
        let n = build(&cfg(0.0), 7, &mut buf).unwrap();
        assert_eq!(&buf[..8], &[b'S', b'W', b'C', b'4', 7, 0, 0, 0]);
        assert_eq!(
            usize::from(u16::from_le_bytes([buf[8], buf[9]])) + HEADER + 4,
            n
        );
        assert_eq!(parse(&buf[..n]), Some((7, cfg(0.0))));
    }

    /// The protocol-1 default config's 37 postcard bytes (see `stiffwall_proto`'s literal
    /// bytes test) with stiffness 2.0 (`00 00 00 40`) and damping 0.5 (`00 00 00 3f`): also
    /// the start of a protocol-2 and a protocol-3 config.
    #[rustfmt::skip]
    const V1_PAYLOAD: [u8; 37] = [
        0x00, 0x00, 0x00, 0x40, // stiffness 2.0
        0x00, 0x00, 0x00, 0x3f, // damping 0.5
        0xe8, 0x07,             // servo_rate_hz 1000
        0x00, 0x00,             // extra_delay_ticks, coarsen_shift
        0x00,                   // wall: Bidirectional
        0x00,                   // wall_position 0
        0xcd, 0xcc, 0xcc, 0x3d, // force_limit 0.1
        0x00, 0x00, 0x00, 0x00, // max_velocity 0.0
        0x01,                   // energy_monitor true
        0x00, 0x00, 0x80, 0x3f, // energy_limit 1.0
        0x04,                   // energy_growth_cycles 4
        0xe8, 0x07,             // encoder_jump_counts 1000
        0xf4, 0x03,             // heartbeat_timeout_ms 500
        0x00,                   // safe_mode: ZeroForce
        0x00, 0x00, 0x00, 0x00, // safe_damping 0.0
    ];

    /// An `SWC1` record of generation 5 holding [`V1_PAYLOAD`], CRC-32 written out
    /// (Python's `zlib.crc32` of the 47 bytes before it).
    fn v1_record() -> std::vec::Vec<u8> {
        let mut r = std::vec![b'S', b'W', b'C', b'1', 5, 0, 0, 0, 37, 0];
        r.extend_from_slice(&V1_PAYLOAD);
        assert_eq!(CRC32.checksum(&r).to_le_bytes(), [0xea, 0x9e, 0x77, 0x05]);
        r.extend_from_slice(&[0xea, 0x9e, 0x77, 0x05]);
        r
    }

    /// What the `SWC1` record holds, migrated: the plain difference it ran with.
    fn v1_config() -> ServoConfig {
        ServoConfig {
            stiffness: 2.0,
            damping: 0.5,
            damper: DamperLaw::Difference,
            ..ServoConfig::default()
        }
    }

    /// An `SWC3` record (protocol 3, before profiles) of the default config, as protocol 3
    /// wrote it: still loads, with an empty profile.
    #[test]
    fn record_literal_bytes_of_the_default_config() {
        let mut want = std::vec![b'S', b'W', b'C', b'3', 7, 0, 0, 0, 41, 0];
        want.extend_from_slice(&[0x00; 4]); // stiffness 0.0
        want.extend_from_slice(&[0x00; 4]); // damping 0.0
        want.extend_from_slice(&V1_PAYLOAD[8..]); // the rest of protocol 1's defaults
        want.extend_from_slice(&[0x01, 0x01]); // damper: DeadBand (variant 1), counts 1
        want.extend_from_slice(&[0x00, 0x00]); // travel_min, travel_max: None
        want.extend_from_slice(&[0x73, 0x87, 0xac, 0x28]); // zlib.crc32 of the bytes before
        assert_eq!(parse(&want), Some((7, ServoConfig::default())));
    }

    /// A one-wall profile (the wire's literal-bytes element of `stiffwall_proto::profile`).
    fn one_wall() -> Profile {
        let mut p = Profile::default();
        p.elements
            .push(ProfileElement::Wall {
                position: -3,
                side: Side::Upper,
                stiffness: 1.0,
                damping: 0.0,
                damper: DamperLaw::DeadBand { counts: 1 },
            })
            .unwrap();
        p
    }

    /// An `SWC4` record written out: the header, the default config's 41 bytes, the profile
    /// (its element count, then the element's postcard bytes), the CRC-32 (Python's
    /// `zlib.crc32` of the 65 bytes before it).
    #[test]
    fn swc4_record_literal_bytes() {
        let mut buf = [0u8; RECORD_MAX];
        let n = super::build(&ServoConfig::default(), &one_wall(), 7, &mut buf).unwrap();
        let mut want = std::vec![b'S', b'W', b'C', b'4', 7, 0, 0, 0, 55, 0];
        want.extend_from_slice(&[0x00; 8]); // stiffness, damping 0.0
        want.extend_from_slice(&V1_PAYLOAD[8..]); // the rest of protocol 1's defaults
        want.extend_from_slice(&[0x01, 0x01, 0x00, 0x00]); // damper, travel window
        #[rustfmt::skip]
        want.extend_from_slice(&[
            0x01,                   // one element
            0x00, 0x05, 0x01,       // Wall, position −3, side Upper
            0x00, 0x00, 0x80, 0x3f, // stiffness 1.0
            0x00, 0x00, 0x00, 0x00, // damping 0.0
            0x01, 0x01,             // damper: DeadBand, counts 1
        ]);
        want.extend_from_slice(&[0xa6, 0xb0, 0xf4, 0x0f]);
        assert_eq!(&buf[..n], &want[..]);
        assert_eq!(
            super::parse(&want),
            Some((7, ServoConfig::default(), one_wall()))
        );
    }

    /// The longest record (the longest config, [`MAX_PROFILE_ELEMENTS`] detent trains with
    /// every varint at its longest) is [`LARGEST_RECORD`] = 511 bytes, within [`RECORD_MAX`]
    /// and every board's config slot (the Nucleo's 128 KiB sector; the virtual device's and
    /// the tests' [`MemStorage`] is `RECORD_MAX`; the QEMU board stores nothing).
    #[test]
    fn the_largest_record_fits() {
        let c = ServoConfig {
            servo_rate_hz: u32::MAX,
            wall_position: i32::MIN,
            encoder_jump_counts: u32::MAX,
            heartbeat_timeout_ms: u32::MAX,
            damper: DamperLaw::DeadBand { counts: u8::MAX },
            travel_min: Some(i32::MIN),
            travel_max: Some(i32::MAX),
            ..ServoConfig::default()
        };
        let mut p = Profile::default();
        for _ in 0..MAX_PROFILE_ELEMENTS {
            p.elements
                .push(ProfileElement::Detents {
                    first: i32::MIN,
                    pitch_counts: f64::MAX,
                    count: u16::MAX,
                    strength: f32::MAX,
                    damping: f32::MAX,
                    damper: DamperLaw::DeadBand { counts: u8::MAX },
                })
                .unwrap();
        }
        let mut buf = [0u8; RECORD_MAX];
        let n = super::build(&c, &p, u32::MAX, &mut buf).unwrap();
        assert_eq!(n, LARGEST_RECORD);
        assert_eq!(LARGEST_RECORD, 511);
        assert_eq!(super::parse(&buf[..n]), Some((u32::MAX, c, p)));
        let _ = MAX_DETENTS;
    }

    /// A save of a config with a profile over an `SWC3` record, interrupted at every byte,
    /// leaves the SWC3 config (and no profile) loadable; complete, both load.
    #[test]
    fn interrupted_write_with_a_profile_keeps_the_previous_record() {
        let mut m = MemStorage::default();
        let mut old = std::vec![b'S', b'W', b'C', b'3', 7, 0, 0, 0, 41, 0];
        old.extend_from_slice(&[0x00; 8]);
        old.extend_from_slice(&V1_PAYLOAD[8..]);
        old.extend_from_slice(&[0x01, 0x01, 0x00, 0x00, 0x73, 0x87, 0xac, 0x28]);
        m.slots[0][..old.len()].copy_from_slice(&old);
        let new = cfg(5.0);
        let mut full = [0u8; RECORD_MAX];
        let n = super::build(&new, &one_wall(), 8, &mut full).unwrap();
        for erase_first in [true, false] {
            for k in 0..=n {
                let mut s = ConfigStore::new(MemStorage {
                    erase_first,
                    ..m.clone()
                });
                s.storage.interrupt_after = Some(k);
                assert!(s.save_with_profile(&new, &one_wall()).is_err());
                let want = if k == n {
                    (new, one_wall())
                } else {
                    (ServoConfig::default(), Profile::default())
                };
                assert_eq!(s.load_with_profile(), Some(want), "interrupted at byte {k}");
            }
        }
        let mut s = ConfigStore::new(m);
        s.save_with_profile(&new, &one_wall()).unwrap();
        assert_eq!(s.load_with_profile(), Some((new, one_wall())));
        assert_eq!(&s.storage.slots[1][..4], b"SWC4");
    }

    /// An `SWC2` record of generation 9: [`V1_PAYLOAD`] then the damper `DeadBand`
    /// (variant 1) of 2 counts, `01 02` (protocol 2's config), CRC-32 written out (Python's
    /// `zlib.crc32` of the 49 bytes before it).
    fn v2_record() -> std::vec::Vec<u8> {
        let mut r = std::vec![b'S', b'W', b'C', b'2', 9, 0, 0, 0, 39, 0];
        r.extend_from_slice(&V1_PAYLOAD);
        r.extend_from_slice(&[0x01, 0x02]);
        assert_eq!(CRC32.checksum(&r).to_le_bytes(), [0x22, 0x93, 0xc3, 0x71]);
        r.extend_from_slice(&[0x22, 0x93, 0xc3, 0x71]);
        r
    }

    /// What the `SWC2` record holds, migrated: its damper, no travel window.
    fn v2_config() -> ServoConfig {
        ServoConfig {
            stiffness: 2.0,
            damping: 0.5,
            damper: DamperLaw::DeadBand { counts: 2 },
            travel_min: None,
            travel_max: None,
            ..ServoConfig::default()
        }
    }

    /// A protocol-2 record (before the travel window) still loads, without a travel window,
    /// and the next save writes `SWC3`; a save interrupted at any byte leaves it loadable.
    #[test]
    fn a_v2_record_loads_without_a_travel_window_and_the_next_save_is_v3() {
        let rec = v2_record();
        assert_eq!(parse(&rec), Some((9, v2_config())));
        let mut bad = rec.clone();
        bad[30] ^= 4;
        assert_eq!(parse(&bad), None);
        // The same bytes under the new magic are no record (a protocol-3 config is longer).
        let mut as_v3 = rec.clone();
        as_v3[3] = b'3';
        let end = as_v3.len() - 4;
        let crc = CRC32.checksum(&as_v3[..end]).to_le_bytes();
        as_v3[end..].copy_from_slice(&crc);
        assert_eq!(parse(&as_v3), None);
        let travel = ServoConfig {
            travel_min: Some(-4000),
            travel_max: Some(4000),
            ..v2_config()
        };
        for slot in 0..2 {
            let mut m = MemStorage::default();
            m.slots[slot][..rec.len()].copy_from_slice(&rec);
            let mut s = ConfigStore::new(m.clone());
            assert_eq!(s.newest(), Some((slot, 9, v2_config())));
            s.save(&travel).unwrap();
            assert_eq!(s.newest(), Some((1 - slot, 10, travel)));
            assert_eq!(&s.storage.slots[1 - slot][..4], b"SWC4");
            assert_eq!(&s.storage.slots[slot][..rec.len()], &rec[..]);
            // Interrupted at every byte: the SWC2 config stays loadable.
            let mut full = [0u8; RECORD_MAX];
            let n = build(&travel, 10, &mut full).unwrap();
            for k in 0..=n {
                let mut s = ConfigStore::new(m.clone());
                s.storage.interrupt_after = Some(k);
                assert!(s.save(&travel).is_err());
                let want = if k == n { travel } else { v2_config() };
                assert_eq!(s.load(), Some(want), "interrupted at byte {k}");
            }
        }
    }

    /// The largest protocol-3 config (every varint at its longest, both travel ends set) fits
    /// a record.
    #[test]
    fn the_longest_config_fits_a_record() {
        let c = ServoConfig {
            servo_rate_hz: u32::MAX,
            wall_position: i32::MIN,
            encoder_jump_counts: u32::MAX,
            heartbeat_timeout_ms: u32::MAX,
            damper: DamperLaw::DeadBand { counts: u8::MAX },
            travel_min: Some(i32::MIN),
            travel_max: Some(i32::MAX),
            ..ServoConfig::default()
        };
        let mut buf = [0u8; RECORD_MAX];
        let n = build(&c, u32::MAX, &mut buf).unwrap();
        assert!(n <= 90, "{n}");
        assert_eq!(parse(&buf[..n]), Some((u32::MAX, c)));
    }

    #[test]
    fn a_v1_record_loads_with_the_plain_difference_and_the_next_save_is_v3() {
        let rec = v1_record();
        assert_eq!(parse(&rec), Some((5, v1_config())));
        // A corrupted one is no record, as a v2 one.
        let mut bad = rec.clone();
        bad[20] ^= 1;
        assert_eq!(parse(&bad), None);
        for slot in 0..2 {
            let mut m = MemStorage::default();
            m.slots[slot][..rec.len()].copy_from_slice(&rec);
            let mut s = ConfigStore::new(m);
            assert_eq!(s.newest(), Some((slot, 5, v1_config())));
            // Saved unchanged, it is written as SWC3 (its damper now in the record).
            s.save(&v1_config()).unwrap();
            let (new_slot, gen, got) = s.newest().unwrap();
            assert_eq!((new_slot, gen, got), (1 - slot, 6, v1_config()));
            assert_eq!(&s.storage.slots[new_slot][..4], b"SWC4");
            // The v1 record is untouched until the slot is needed again.
            assert_eq!(&s.storage.slots[slot][..rec.len()], &rec[..]);
            s.save(&cfg(3.0)).unwrap();
            assert_eq!(&s.storage.slots[slot][..4], b"SWC4");
            assert_eq!(s.load(), Some(cfg(3.0)));
        }
    }

    /// A save over a store holding only an SWC1 record, interrupted at every byte, leaves the
    /// migrated SWC1 config loadable.
    #[test]
    fn interrupted_first_v3_write_keeps_the_v1_config() {
        let rec = v1_record();
        for erase_first in [true, false] {
            let mut m = MemStorage {
                erase_first,
                ..MemStorage::default()
            };
            m.slots[0][..rec.len()].copy_from_slice(&rec);
            let mut full = [0u8; RECORD_MAX];
            let n = build(&cfg(3.0), 6, &mut full).unwrap();
            for k in 0..=n {
                let mut s = ConfigStore::new(m.clone());
                s.storage.interrupt_after = Some(k);
                assert!(s.save(&cfg(3.0)).is_err());
                let want = if k == n { cfg(3.0) } else { v1_config() };
                assert_eq!(s.load(), Some(want), "interrupted at byte {k}");
            }
        }
    }

    #[test]
    fn interrupted_write_at_every_byte_keeps_previous_config() {
        for erase_first in [true, false] {
            let mut base = ConfigStore::new(MemStorage {
                erase_first,
                ..MemStorage::default()
            });
            base.save(&cfg(1.0)).unwrap();
            base.save(&cfg(2.0)).unwrap();
            let mut rec = [0u8; RECORD_MAX];
            let n = build(&cfg(3.0), 3, &mut rec).unwrap();
            for k in 0..=n {
                let mut s = ConfigStore::new(base.storage.clone());
                s.storage.interrupt_after = Some(k);
                let r = s.save(&cfg(3.0));
                assert!(r.is_err());
                let got = s.load();
                if k == n {
                    assert_eq!(got, Some(cfg(3.0)), "complete write at k={k}");
                } else {
                    assert_eq!(
                        got,
                        Some(cfg(2.0)),
                        "interrupted at byte {k} (erase_first={erase_first})"
                    );
                }
                // And the next save after the interruption works and wins.
                s.save(&cfg(4.0)).unwrap();
                assert_eq!(s.load(), Some(cfg(4.0)));
            }
        }
    }

    #[test]
    fn corrupted_newest_falls_back() {
        let mut s = ConfigStore::new(MemStorage::default());
        s.save(&cfg(1.0)).unwrap();
        s.save(&cfg(2.0)).unwrap();
        let (slot, _, _) = s.newest().unwrap();
        s.storage.slots[slot][12] ^= 0x40;
        assert_eq!(s.load(), Some(cfg(1.0)));
    }

    #[test]
    fn storage_errors_name_what_failed() {
        use crate::hal::NoStorage;
        use embedded_storage::nor_flash::{NorFlashError, NorFlashErrorKind};
        use std::string::ToString;

        let mut m = MemStorage::default();
        assert_eq!(m.read(2, &mut [0; 4]), Err(StorageError::Slot { slot: 2 }));
        assert_eq!(
            m.write(0, &[0; RECORD_MAX + 1]),
            Err(StorageError::TooLong {
                len: RECORD_MAX + 1,
                slot_len: RECORD_MAX
            })
        );
        m.interrupt_after = Some(3);
        assert_eq!(
            m.write(1, &[1; 10]),
            Err(StorageError::Interrupted { written: 3 })
        );
        assert_eq!(
            ConfigStore::new(NoStorage).save(&cfg(1.0)),
            Err(StorageError::TooLong {
                len: build(&cfg(1.0), 1, &mut [0; RECORD_MAX]).unwrap(),
                slot_len: 0
            })
        );

        // A board driver's own error keeps its kind on the way into the core.
        #[derive(Debug)]
        struct Misaligned;
        impl NorFlashError for Misaligned {
            fn kind(&self) -> NorFlashErrorKind {
                NorFlashErrorKind::NotAligned
            }
        }
        let e = StorageError::flash(Misaligned);
        assert_eq!(e, StorageError::Flash(NorFlashErrorKind::NotAligned));
        let e: &dyn core::error::Error = &e;
        assert!(e.to_string().starts_with("flash error: "));
        assert_eq!(
            StorageError::Slot { slot: 2 }.to_string(),
            "config slot 2 out of range 0..=1"
        );
    }
}
