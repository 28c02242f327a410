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

/// The image's rig (`RigRecord` of firmware/boards/nucleo-f446re/src/rig.rs, found in flash by
/// its tag): what the firmware tells the host about the device, and so what the emulator
/// couples its plant through.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rig {
    /// Encoder counts per revolution after ×4 decoding; 0 for a linear device.
    pub counts_per_rev: u32,
    /// Encoder resolution Δ: rad per count (m for a linear device).
    pub resolution: f64,
    /// Torque (N·m) or force (N) at full-scale output.
    pub full_scale: f64,
}

impl Rig {
    /// The rig of the image's default build (the paper's Sec. V motor): rotary, 8192 counts/rev,
    /// ±0.1 N·m.
    pub const SEC_V: Rig = Rig {
        counts_per_rev: 8192,
        resolution: std::f64::consts::TAU / 8192.0,
        full_scale: 0.1,
    };

    /// Whether the device is rotary.
    pub fn rotary(&self) -> bool {
        self.counts_per_rev > 0
    }

    /// In words, for messages.
    pub fn describe(&self) -> String {
        if self.rotary() {
            format!(
                "rotary with {} counts/rev, {} N·m full scale",
                self.counts_per_rev, self.full_scale
            )
        } else {
            format!(
                "linear with {:.4e} m per count, {} N full scale",
                self.resolution, self.full_scale
            )
        }
    }
}

/// Tag and layout version of the rig record (rig.rs `RIG_MAGIC`).
pub const RIG_MAGIC: &[u8; 8] = b"SWRIG\x00\x00\x01";

/// Finds and checks the rig record in `flash`.
fn rig_record(flash: &[u8]) -> Result<Rig> {
    let Some(at) = flash.windows(RIG_MAGIC.len()).position(|w| w == RIG_MAGIC) else {
        bail!(
            "the image has no rig record (the SWRIG tag of src/rig.rs): built from a source \
             older than the emulator, or for another board"
        );
    };
    let field = |i: usize| -> [u8; 4] {
        let o = at + RIG_MAGIC.len() + 4 * i;
        flash
            .get(o..o + 4)
            .and_then(|b| b.try_into().ok())
            .unwrap_or([0xFF; 4])
    };
    let counts_per_rev = u32::from_le_bytes(field(0));
    let resolution = f64::from(f32::from_le_bytes(field(1)));
    let full_scale = f64::from(f32::from_le_bytes(field(2)));
    if !(resolution.is_finite() && resolution > 0.0 && full_scale.is_finite() && full_scale > 0.0)
        || counts_per_rev > 1 << 24
    {
        bail!(
            "the image's rig record is invalid: counts/rev {counts_per_rev} (allowed 0..=2^24), \
             resolution {resolution} and full scale {full_scale} (allowed finite and > 0)"
        );
    }
    let resolution = if counts_per_rev > 0 {
        let exact = std::f64::consts::TAU / f64::from(counts_per_rev);
        if (resolution / exact - 1.0).abs() > 1e-6 {
            bail!(
                "the image's rig record is inconsistent: {counts_per_rev} counts/rev but \
                 resolution {resolution} rad (allowed 2π/{counts_per_rev} = {exact})"
            );
        }
        exact
    } else {
        resolution
    };
    Ok(Rig {
        counts_per_rev,
        resolution,
        full_scale,
    })
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
    /// The rig the image describes.
    pub rig: Rig,
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
    check_architecture(&file)?;
    let flash = load_flash(bytes, &file)?;
    let (initial_sp, reset) = vector_table(&flash)?;
    let output = output_variant(&flash)?;
    let rig = rig_record(&flash)?;
    let sleep_insns = sleep_instructions(&file);
    Ok(Image {
        flash,
        initial_sp,
        reset,
        output,
        rig,
        sha256,
        sleep_insns,
    })
}

/// The ELF must be 32-bit little-endian ARM.
fn check_architecture(file: &object::File<'_>) -> Result<()> {
    if file.architecture() != object::Architecture::Arm || file.is_64() || !file.is_little_endian()
    {
        bail!(
            "ELF architecture is {:?} ({}-bit): the STM32F446 needs 32-bit little-endian ARM",
            file.architecture(),
            if file.is_64() { 64 } else { 32 }
        );
    }
    Ok(())
}

/// The image flash (sectors 0–5, erased bytes 0xFF) with every loadable segment at its load
/// address; a segment outside it is refused.
fn load_flash(bytes: &[u8], file: &object::File<'_>) -> Result<Vec<u8>> {
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
    Ok(flash)
}

/// The vector table's (initial SP, reset vector), checked: the SP in SRAM, the reset vector a
/// Thumb address in the image flash.
fn vector_table(flash: &[u8]) -> Result<(u32, u32)> {
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
    Ok((initial_sp, reset))
}

/// The nucleo-f446re output variant the image names in its flash.
fn output_variant(flash: &[u8]) -> Result<Output> {
    if contains(flash, b"nucleo-f446re-pwm") {
        Ok(Output::Pwm)
    } else if contains(flash, b"nucleo-f446re-dac") {
        Ok(Output::Dac)
    } else {
        bail!(
            "the image names no nucleo-f446re board (neither \"nucleo-f446re-dac\" nor \
             \"nucleo-f446re-pwm\" is in its flash): built for another board"
        );
    }
}

/// Addresses of every `WFI` (0xBF30) and `WFE` (0xBF20) halfword in executable sections.
fn sleep_instructions(file: &object::File<'_>) -> Vec<u32> {
    use object::ObjectSection;
    let mut sleep_insns = Vec::new();
    for section in file.sections() {
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
    sleep_insns
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

    fn record(counts: u32, resolution: f32, full_scale: f32) -> Vec<u8> {
        let mut flash = vec![0xFF_u8; 64];
        flash.extend_from_slice(RIG_MAGIC);
        flash.extend_from_slice(&counts.to_le_bytes());
        flash.extend_from_slice(&resolution.to_le_bytes());
        flash.extend_from_slice(&full_scale.to_le_bytes());
        flash
    }

    #[test]
    fn the_rig_record_is_read_and_checked() {
        let r = rig_record(&record(8192, std::f32::consts::TAU / 8192.0, 0.1)).unwrap();
        assert_eq!(r.counts_per_rev, 8192);
        assert_eq!(r.resolution, std::f64::consts::TAU / 8192.0);
        assert!((r.full_scale - 0.1).abs() < 1e-8);
        let r = rig_record(&record(0, 29.1e-6, 8.5)).unwrap();
        assert!(!r.rotary() && (r.resolution / 29.1e-6 - 1.0).abs() < 1e-7);
        for (bad, why) in [
            (record(8192, 1e-3, 0.1), "inconsistent"),
            (record(0, 0.0, 8.5), "invalid"),
            (record(0, 1e-5, f32::NAN), "invalid"),
            (vec![0xFF; 64], "no rig record"),
        ] {
            let e = rig_record(&bad).unwrap_err().to_string();
            assert!(e.contains(why), "{e}");
        }
    }

    #[test]
    fn garbage_and_truncation_are_refused() {
        let e = parse(b"not an elf").unwrap_err();
        assert!(e.to_string().contains("truncated or corrupt"), "{e}");
    }
}
