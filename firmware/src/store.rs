//! Two-slot, CRC-protected configuration store.
//!
//! Record layout (bytes, little-endian), at offset 0 of a slot:
//! `magic "SWC1" (4) | generation u32 (4) | len u16 (2) | postcard(ServoConfig) (len) | CRC-32 (4)`
//! with the CRC-32/ISO-HDLC over everything before it.
//!
//! Invariant: [`ConfigStore::save`] always writes the slot that does *not* hold the newest
//! valid record, with generation = newest + 1. A write interrupted at any byte therefore leaves
//! the newest valid record untouched, and [`ConfigStore::load`] returns it (the record with the
//! highest generation among the slots whose magic, length and CRC check).

use crate::hal::{ConfigStorage, StorageError};
use crc::{Crc, CRC_32_ISO_HDLC};
use stiffwall_proto::ServoConfig;

/// Largest record, bytes.
pub const RECORD_MAX: usize = 128;
const MAGIC: [u8; 4] = *b"SWC1";
const HEADER: usize = 10;
const CRC32: Crc<u32> = Crc::<u32>::new(&CRC_32_ISO_HDLC);

/// The two-slot config store over a [`ConfigStorage`].
#[derive(Debug)]
pub struct ConfigStore<S: ConfigStorage> {
    storage: S,
}

/// Parses one record; `None` if it is not a valid record.
fn parse(buf: &[u8]) -> Option<(u32, ServoConfig)> {
    if buf.get(..4)? != MAGIC {
        return None;
    }
    let gen = u32::from_le_bytes(buf.get(4..8)?.try_into().ok()?);
    let len = usize::from(u16::from_le_bytes(buf.get(8..10)?.try_into().ok()?));
    let end = HEADER.checked_add(len)?;
    let crc = u32::from_le_bytes(buf.get(end..end.checked_add(4)?)?.try_into().ok()?);
    if CRC32.checksum(buf.get(..end)?) != crc {
        return None;
    }
    let cfg = postcard::from_bytes(buf.get(HEADER..end)?).ok()?;
    Some((gen, cfg))
}

/// Builds a record for `cfg` with `gen` into `buf`; returns its length.
fn build(cfg: &ServoConfig, gen: u32, buf: &mut [u8; RECORD_MAX]) -> Option<usize> {
    buf[..4].copy_from_slice(&MAGIC);
    buf[4..8].copy_from_slice(&gen.to_le_bytes());
    let len = postcard::to_slice(cfg, &mut buf[HEADER..RECORD_MAX - 4])
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

    fn read_slot(&mut self, slot: usize) -> Option<(u32, ServoConfig)> {
        let mut buf = [0u8; RECORD_MAX];
        let n = self.storage.slot_len().min(RECORD_MAX);
        let b = buf.get_mut(..n)?;
        self.storage.read(slot, b).ok()?;
        parse(b)
    }

    /// The newest valid record: `(slot, generation, config)`.
    pub fn newest(&mut self) -> Option<(usize, u32, ServoConfig)> {
        let a = self.read_slot(0).map(|(g, c)| (0, g, c));
        let b = self.read_slot(1).map(|(g, c)| (1, g, c));
        match (a, b) {
            (Some(a), Some(b)) => Some(if b.1.wrapping_sub(a.1) as i32 > 0 {
                b
            } else {
                a
            }),
            (a, b) => a.or(b),
        }
    }

    /// The newest valid config, if any.
    pub fn load(&mut self) -> Option<ServoConfig> {
        self.newest().map(|(_, _, c)| c)
    }

    /// Saves `cfg` into the slot not holding the newest record.
    ///
    /// # Errors
    /// [`StorageError`] if the storage is too small or the write failed (the previous config
    /// stays loadable).
    pub fn save(&mut self, cfg: &ServoConfig) -> Result<(), StorageError> {
        let (slot, gen) = match self.newest() {
            Some((s, g, _)) => (1 - s, g.wrapping_add(1)),
            None => (0, 1),
        };
        let mut buf = [0u8; RECORD_MAX];
        let n = build(cfg, gen, &mut buf).ok_or(StorageError::RecordTooLong { max: RECORD_MAX })?;
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
        assert_eq!(&buf[..8], &[b'S', b'W', b'C', b'1', 7, 0, 0, 0]);
        assert_eq!(
            usize::from(u16::from_le_bytes([buf[8], buf[9]])) + HEADER + 4,
            n
        );
        assert_eq!(parse(&buf[..n]), Some((7, cfg(0.0))));
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
