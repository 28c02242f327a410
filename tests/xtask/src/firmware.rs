//! `cargo xtask firmware`: builds every board image (release) and checks the tracked size report.
//!
//! The report (`firmware/size-report.txt`) lists text/data/bss bytes per image. CI fails when an
//! image grows more than 5 % over the committed figure; `--update-size-report` rewrites the file
//! (commit it together with the change that made the image grow).

use crate::toolchain::{self, Cross, TARGET};
use anyhow::{bail, Context, Result};
use object::{Object, ObjectSection};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One firmware image: a board crate built with a feature set.
#[derive(Debug, Clone, Copy)]
pub struct Image {
    /// Name in the size report.
    pub name: &'static str,
    /// Board crate directory, relative to the repository root.
    pub dir: &'static str,
    /// Binary name.
    pub bin: &'static str,
    /// Cargo features.
    pub features: &'static [&'static str],
}

/// Every image CI builds.
pub const IMAGES: &[Image] = &[
    Image {
        name: "qemu-an386",
        dir: "firmware/boards/qemu-an386",
        bin: "stiffwall-qemu-an386",
        features: &[],
    },
    Image {
        name: "nucleo-f446re-dac",
        dir: "firmware/boards/nucleo-f446re",
        bin: "stiffwall-nucleo-f446re",
        features: &["dac"],
    },
    Image {
        name: "nucleo-f446re-pwm",
        dir: "firmware/boards/nucleo-f446re",
        bin: "stiffwall-nucleo-f446re",
        features: &["pwm"],
    },
];

/// Size of one image in bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Size {
    /// Code and read-only data in flash (vector table, .text, .rodata).
    pub text: u64,
    /// Initialised RAM data (also stored in flash).
    pub data: u64,
    /// Zero-initialised RAM.
    pub bss: u64,
}

const REPORT: &str = "firmware/size-report.txt";

/// Repository root (kept here for the tasks that name it `firmware::root`).
pub use crate::process::root;

/// Builds one image and returns the path of its ELF file.
pub fn build(cross: Cross, image: &Image, extra_features: &[&str]) -> Result<PathBuf> {
    let dir = root().join(image.dir);
    let mut features: Vec<&str> = image.features.to_vec();
    features.extend_from_slice(extra_features);
    let mut cmd = toolchain::board_build(cross, &dir, &features)?;
    crate::process::run(&mut cmd)?;
    let elf = dir
        .join("target")
        .join(TARGET)
        .join("release")
        .join(image.bin);
    if !elf.exists() {
        bail!("build succeeded but {} is missing", elf.display());
    }
    Ok(elf)
}

/// Links the QEMU no-panic proof image: it links only when the servo tick has no panic path.
pub fn panic_check(cross: Cross) -> Result<()> {
    let dir = root().join("firmware/boards/qemu-an386");
    let mut cmd = toolchain::board_build(cross, &dir, &["panic-check"])?;
    cmd.args(["--bin", "stiffwall-qemu-an386-panic-check"]);
    crate::process::run(&mut cmd).map_err(|e| {
        e.context(
            "the servo tick has a panic path: the no-panic proof image did not link \
             (look for `servo_path_must_not_panic` above)",
        )
    })
}

/// Reads text/data/bss of an ELF image.
pub fn size_of(elf: &Path) -> Result<Size> {
    let bytes = std::fs::read(elf).with_context(|| format!("reading {}", elf.display()))?;
    let file =
        object::File::parse(&*bytes).with_context(|| format!("parsing {}", elf.display()))?;
    let mut size = Size {
        text: 0,
        data: 0,
        bss: 0,
    };
    for section in file.sections() {
        let name = section.name().unwrap_or("");
        let n = section.size();
        match name {
            ".vector_table" | ".text" | ".rodata" => size.text += n,
            ".data" => size.data += n,
            ".bss" | ".uninit" => size.bss += n,
            _ => {}
        }
    }
    Ok(size)
}

fn parse_report(text: &str) -> Vec<(String, Size)> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            match f.as_slice() {
                [name, t, d, b] => Some((
                    (*name).to_string(),
                    Size {
                        text: t.parse().ok()?,
                        data: d.parse().ok()?,
                        bss: b.parse().ok()?,
                    },
                )),
                _ => None,
            }
        })
        .collect()
}

fn render_report(sizes: &[(String, Size)]) -> String {
    let mut s = String::from(
        "# Firmware image sizes in bytes (cargo xtask firmware --update-size-report).\n\
         # CI fails when text+data or bss of an image grows by more than 5 % over this file.\n\
         # image                 text     data      bss\n",
    );
    for (name, z) in sizes {
        let _ = writeln!(s, "{name:<20} {:>8} {:>8} {:>8}", z.text, z.data, z.bss);
    }
    s
}

/// Builds all images, prints the size table, and checks or updates the tracked report.
pub fn firmware(args: &[String]) -> Result<()> {
    let update = args.iter().any(|a| a == "--update-size-report");
    if let Some(bad) = args.iter().find(|a| *a != "--update-size-report") {
        bail!(
            "unknown argument {bad:?} for `cargo xtask firmware` (allowed: --update-size-report)"
        );
    }
    let cross = toolchain::ensure_cross()?;
    let mut sizes = Vec::new();
    for image in IMAGES {
        let elf = build(cross, image, &[])?;
        sizes.push((image.name.to_string(), size_of(&elf)?));
    }
    panic_check(cross)?;
    let report_path = root().join(REPORT);
    let rendered = render_report(&sizes);
    print!("{rendered}");
    if update {
        std::fs::write(&report_path, &rendered)?;
        eprintln!("xtask: wrote {}", report_path.display());
        return Ok(());
    }
    let old = std::fs::read_to_string(&report_path).unwrap_or_default();
    let old = parse_report(&old);
    let mut failures = Vec::new();
    for (name, new) in &sizes {
        match old.iter().find(|(n, _)| n == name) {
            None => failures.push(format!("{name}: not in {REPORT}")),
            Some((_, was)) => {
                let grew = |a: u64, b: u64| b as f64 > a as f64 * 1.05;
                if grew(was.text + was.data, new.text + new.data) || grew(was.bss, new.bss) {
                    failures.push(format!(
                        "{name}: grew more than 5 % (flash {} -> {}, bss {} -> {})",
                        was.text + was.data,
                        new.text + new.data,
                        was.bss,
                        new.bss
                    ));
                }
            }
        }
    }
    if !failures.is_empty() {
        bail!(
            "size report check failed:\n  {}\nrun `cargo xtask firmware --update-size-report` and commit {REPORT} if the growth is intended",
            failures.join("\n  ")
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_round_trips() {
        let sizes = vec![(
            "a".to_string(),
            Size {
                text: 10,
                data: 2,
                bss: 3,
            },
        )];
        assert_eq!(parse_report(&render_report(&sizes)), sizes);
    }
}
