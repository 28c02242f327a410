//! The firmware image: the Nucleo-F446RE ELF that `cargo xtask firmware` builds, loaded and
//! checked before anything runs.
//!
//! Units: byte addresses of the STM32F446RE memory map. Invariants: every loadable segment lies
//! in the image flash (0x0800_0000..0x0804_0000, sectors 0–5; sectors 6–7 are the config store),
//! the vector table's initial SP lies in SRAM (0x2000_0000..=0x2002_0000) and its reset vector in
//! the image flash with the Thumb bit set, the ELF is 32-bit little-endian ARM, and it names a
//! nucleo-f446re output variant (`dac` or `pwm`). A file that fails any check is refused with the
//! reason; nothing is run. The SHA-256 is of the ELF file's bytes (the file `cargo xtask flash`
//! hands to probe-rs).

use anyhow::{bail, Context, Result};
use object::{Object, ObjectSegment};
use sha2::{Digest, Sha256};
use std::path::Path;

/// Start of the flash (and of the image).
pub const FLASH_BASE: u32 = 0x0800_0000;
/// End of the image part of flash (sectors 0–5).
pub const IMAGE_END: u32 = 0x0804_0000;
/// SRAM start and length.
pub const RAM_BASE: u32 = 0x2000_0000;
/// SRAM length (128 KiB).
pub const RAM_LEN: u32 = 128 * 1024;

/// The force output the image was built for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Output {
    /// DAC channel 1 on PA4 through the op-amp stage.
    Dac,
    /// TIM1 CH1 PWM on PA8 with DIR on PA9.
    Pwm,
}

/// A loaded, checked image.
#[derive(Debug, Clone)]
pub struct Image {
    /// Flash contents of sectors 0–5 (0xFF where nothing is loaded).
    pub flash: Vec<u8>,
    /// Initial main stack pointer (vector table word 0).
    pub initial_sp: u32,
    /// Reset handler address (Thumb bit set).
    pub reset: u32,
    /// The output variant named in the image.
    pub output: Output,
    /// SHA-256 of the ELF file, lower-case hex.
    pub sha256: String,
    /// Addresses of every `WFI` (0xBF30) and `WFE` (0xBF20) halfword in executable sections.
    pub sleep_insns: Vec<u32>,
}

/// Loads `path`, checks it as described in the module header.
pub fn load(path: &Path) -> Result<Image> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    parse(&bytes).with_context(|| format!("refusing {}", path.display()))
}

/// Checks and loads an ELF from memory.
pub fn parse(bytes: &[u8]) -> Result<Image> {
    let sha256 = Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<String>();
    let file =
        object::File::parse(bytes).context("not a readable ELF file (truncated or corrupt)")?;
    if file.architecture() != object::Architecture::Arm || file.is_64() || !file.is_little_endian()
    {
        bail!(
            "ELF architecture is {:?} ({}-bit): the STM32F446 needs 32-bit little-endian ARM",
            file.architecture(),
            if file.is_64() { 64 } else { 32 }
        );
    }
    let mut flash = vec![0xFF_u8; (IMAGE_END - FLASH_BASE) as usize];
    let mut loaded = 0usize;
    for seg in file.segments() {
        let data = seg
            .data()
            .context("a loadable segment extends past the end of the file (truncated ELF)")?;
        if data.is_empty() {
            continue;
        }
        // The load address: the physical address of the segment (.data's LMA is in flash).
        let (offset, _) = seg.file_range();
        let lma = physical_address(bytes, offset).unwrap_or(seg.address());
        let end = lma + data.len() as u64;
        if lma < u64::from(FLASH_BASE) || end > u64::from(IMAGE_END) {
            bail!(
                "segment at {lma:#010x}..{end:#010x} is outside the image flash \
                 {FLASH_BASE:#010x}..{IMAGE_END:#010x} (sectors 0-5): not a nucleo-f446re image"
            );
        }
        let at = (lma - u64::from(FLASH_BASE)) as usize;
        flash[at..at + data.len()].copy_from_slice(data);
        loaded += data.len();
    }
    if loaded < 8 {
        bail!("the ELF loads nothing into flash (no vector table)");
    }
    let word = |i: usize| u32::from_le_bytes(flash[4 * i..4 * i + 4].try_into().expect("4 bytes"));
    let initial_sp = word(0);
    let reset = word(1);
    if !(RAM_BASE..=RAM_BASE + RAM_LEN).contains(&initial_sp) {
        bail!(
            "vector table: initial SP {initial_sp:#010x} is outside the SRAM \
             {RAM_BASE:#010x}..={:#010x}",
            RAM_BASE + RAM_LEN
        );
    }
    if reset & 1 == 0 || !(FLASH_BASE..IMAGE_END).contains(&(reset & !1)) {
        bail!(
            "vector table: reset vector {reset:#010x} is not a Thumb address in the image flash \
             {FLASH_BASE:#010x}..{IMAGE_END:#010x}"
        );
    }
    let output = if contains(&flash, b"nucleo-f446re-pwm") {
        Output::Pwm
    } else if contains(&flash, b"nucleo-f446re-dac") {
        Output::Dac
    } else {
        bail!(
            "the image names no nucleo-f446re board (neither \"nucleo-f446re-dac\" nor \
             \"nucleo-f446re-pwm\" is in its flash): built for another board"
        );
    };
    let mut sleep_insns = Vec::new();
    for section in file.sections() {
        use object::ObjectSection;
        if section.kind() != object::SectionKind::Text {
            continue;
        }
        let Ok(data) = section.data() else { continue };
        let base = section.address() as u32;
        for (i, h) in data.chunks_exact(2).enumerate() {
            let h = u16::from_le_bytes([h[0], h[1]]);
            if h == 0xBF30 || h == 0xBF20 {
                sleep_insns.push(base + 2 * i as u32);
            }
        }
    }
    Ok(Image {
        flash,
        initial_sp,
        reset,
        output,
        sha256,
        sleep_insns,
    })
}

fn contains(hay: &[u8], needle: &[u8]) -> bool {
    hay.windows(needle.len()).any(|w| w == needle)
}

/// The `p_paddr` of the program header whose file offset is `offset` (ELF32 little-endian).
fn physical_address(bytes: &[u8], offset: u64) -> Option<u64> {
    let u32_at = |at: usize| -> Option<u32> {
        Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?))
    };
    let u16_at = |at: usize| -> Option<u16> {
        Some(u16::from_le_bytes(bytes.get(at..at + 2)?.try_into().ok()?))
    };
    let phoff = u32_at(28)? as usize;
    let phentsize = u16_at(42)? as usize;
    let phnum = u16_at(44)? as usize;
    (0..phnum).find_map(|i| {
        let ph = phoff + i * phentsize;
        (u32_at(ph)? == 1 && u64::from(u32_at(ph + 4)?) == offset)
            .then(|| u32_at(ph + 12).map(u64::from))
            .flatten()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn garbage_and_truncation_are_refused() {
        let e = parse(b"not an elf").unwrap_err();
        assert!(e.to_string().contains("truncated or corrupt"), "{e}");
    }
}
