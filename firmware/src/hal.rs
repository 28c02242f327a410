//! Hardware traits the firmware core is generic over.
//!
//! Units: encoder counts are raw hardware counter values (wrapping at the counter width, see
//! [`crate::config::BoardInfo::encoder_bits`]); force codes are signed output codes (one code =
//! `BoardInfo::force_per_code` N or N·m); ticks are servo ticks. Implementations must not block.

use embedded_storage::nor_flash::{NorFlashError, NorFlashErrorKind};

/// A quadrature (or simulated) encoder: the raw hardware counter.
pub trait Encoder {
    /// The raw counter value. Only the low `encoder_bits` bits are used; the firmware unwraps
    /// counter wrap itself (the count may move less than half the counter range per tick).
    fn count(&mut self) -> u32;
}

/// A force (or torque) output: DAC, PWM + direction, or a simulated amplifier.
pub trait ForceOutput {
    /// Applies `code` (already clamped to ±`BoardInfo::max_code` and the configured limit).
    fn write(&mut self, code: i32);
}

/// An encoder reading taken at the sample instant: what a simulated or replayed device's
/// counter showed when the servo sampled it (the raw counter value, as [`Encoder::count`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SampledCount(pub u32);

impl Encoder for SampledCount {
    fn count(&mut self) -> u32 {
        self.0
    }
}

/// A force output that keeps the last code written: a simulated amplifier holds it for one
/// servo period (ZOH), a replay compares it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct HeldCode(pub i32);

impl ForceOutput for HeldCode {
    fn write(&mut self, code: i32) {
        self.0 = code;
    }
}

/// A byte-oriented, non-blocking link to the host (UART, USB CDC, in-memory pipe).
pub trait ByteLink {
    /// The next received byte, if any.
    fn read(&mut self) -> Option<u8>;
    /// Queues one byte for sending; `false` if the link cannot take it now (try again later).
    fn write(&mut self, byte: u8) -> bool;
}

/// Non-volatile storage with two independent slots of `slot_len()` bytes each (flash sectors,
/// EEPROM pages, a file). A write may be interrupted at any byte: the bytes before the
/// interruption are new, the rest keep their previous (or erased) value.
pub trait ConfigStorage {
    /// Bytes per slot.
    fn slot_len(&self) -> usize;
    /// Reads `buf.len()` bytes of `slot` (0 or 1) from offset 0.
    ///
    /// # Errors
    /// [`StorageError`] on a hardware failure or an out-of-range request.
    fn read(&mut self, slot: usize, buf: &mut [u8]) -> Result<(), StorageError>;
    /// Erases `slot` (flash semantics) and writes `data` from offset 0.
    ///
    /// # Errors
    /// [`StorageError`] when the write did not complete.
    fn write(&mut self, slot: usize, data: &[u8]) -> Result<(), StorageError>;
}

/// A storage failure, with the board's flash error kind kept.
///
/// Boards speak `embedded-storage`'s vocabulary at their edge: a flash driver's error implements
/// [`NorFlashError`] and reaches the core as [`StorageError::Flash`] through
/// [`StorageError::flash`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StorageError {
    /// The slot index is outside `0..=1`.
    Slot {
        /// The slot asked for.
        slot: usize,
    },
    /// A request of `len` bytes does not fit a slot of `slot_len` bytes.
    TooLong {
        /// Bytes asked for.
        len: usize,
        /// Bytes per slot.
        slot_len: usize,
    },
    /// The config does not encode into a record of at most `max` bytes.
    RecordTooLong {
        /// Largest record, bytes.
        max: usize,
    },
    /// The board has no non-volatile storage.
    Unsupported,
    /// The write stopped after `written` bytes (a simulated power cut).
    Interrupted {
        /// Bytes written before the stop.
        written: usize,
    },
    /// The board's flash driver failed, with its error kind.
    Flash(NorFlashErrorKind),
}

impl StorageError {
    /// A board flash driver's error, keeping its kind.
    pub fn flash(e: impl NorFlashError) -> Self {
        Self::Flash(e.kind())
    }
}

impl core::fmt::Display for StorageError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Slot { slot } => write!(f, "config slot {slot} out of range 0..=1"),
            Self::TooLong { len, slot_len } => write!(
                f,
                "{len} bytes do not fit a config slot: allowed 0..={slot_len} bytes"
            ),
            Self::RecordTooLong { max } => {
                write!(f, "config record too long: allowed at most {max} bytes")
            }
            Self::Unsupported => write!(f, "this board has no config storage"),
            Self::Interrupted { written } => {
                write!(f, "config write interrupted after {written} bytes")
            }
            Self::Flash(kind) => write!(f, "flash error: {kind}"),
        }
    }
}

impl core::error::Error for StorageError {}

/// Storage for boards without non-volatile memory: every read and write fails, so the device
/// boots with its defaults and `SaveConfig` answers `StoreFailed`.
#[derive(Debug, Default, Clone, Copy)]
pub struct NoStorage;

impl ConfigStorage for NoStorage {
    fn slot_len(&self) -> usize {
        0
    }
    fn read(&mut self, _slot: usize, _buf: &mut [u8]) -> Result<(), StorageError> {
        Err(StorageError::Unsupported)
    }
    fn write(&mut self, _slot: usize, _data: &[u8]) -> Result<(), StorageError> {
        Err(StorageError::Unsupported)
    }
}
