//! `cargo xtask figures [--check]`: the figure gallery docs/FIGURES.md — every kind of figure
//! the `hostctl` commands write (analyze's (β, σ) plane and (K, B) frontier, tune's plane and
//! frontier, map with one panel and many, `map --k-b`, `map atlas`, simulate, replay and
//! experiment release), each on a preset and, where the command takes one, on a plant file of
//! `sim/plants/`, drawn by the release `hostctl` into docs/figures/gallery/.
//!
//! PNG bytes depend on the machine's fonts, so the checked record is font-independent: with
//! `STIFFWALL_FIGURE_TEXT` set, every figure also writes `<file>.txt`, its words as drawn
//! (title, axes, legend entries, key values: `stiffwall_figures::describe`), and the gallery
//! lists them under each image. `--check` draws the gallery into a scratch directory and fails
//! when docs/FIGURES.md differs from the fresh text (for a figure of a run on the fast virtual
//! device, whose values can move in their last digits between machines, every word but the
//! numbers) or names a PNG that docs/figures/gallery/ lacks; it writes nothing in docs/.
//!
//! Units: those of each figure. Invariants: every run is short (small grids, short
//! horizons, the fast virtual device, tune as a dry run); the runs of the simulators are
//! deterministic, so their text is the same on every machine; the `.txt` files never stay in
//! docs/.

use crate::firmware;
use crate::process::run;
use anyhow::{bail, ensure, Context, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Where the gallery's PNGs live, relative to the root (also as written in the markdown).
const GALLERY: &str = "docs/figures/gallery";
/// Scratch files (map JSON, recordings, CSV) as named in the markdown.
const SCRATCH: &str = "target/figures";

/// One section of the gallery: the `hostctl` runs (`{G}`: the gallery directory, `{T}`: the
/// scratch directory) and the figures they write, relative to the gallery directory.
struct Entry {
    heading: &'static str,
    runs: &'static [&'static str],
    figures: &'static [&'static str],
}

const ENTRIES: &[Entry] = &[
    Entry {
        heading: "analyze: the (β, σ) plane and the (K, B) frontier of a rotary preset with a damper",
        runs: &["analyze --device maxon-re35 --stiffness 2 --damping 0.0005 --plot {G}/analyze-maxon-re35.png"],
        figures: &["analyze-maxon-re35.png", "analyze-maxon-re35-kb.png"],
    },
    Entry {
        heading: "analyze: the (β, σ) plane of a linear preset at a given velocity",
        runs: &["analyze --device phantom-1.0 --stiffness 1015 --velocity 0.05 --plot {G}/analyze-phantom-1.0.png"],
        figures: &["analyze-phantom-1.0.png"],
    },
    Entry {
        heading: "tune: the plane and the frontier of a tune of the virtual device (preset)",
        runs: &["tune --device maxon-re35 --fast --dry-run --plot {G}/tune-maxon-re35.png"],
        figures: &["tune-maxon-re35.png", "tune-maxon-re35-kb.png"],
    },
    Entry {
        heading: "tune: the plane and the frontier of a tune of the virtual device (plant file)",
        runs: &["tune --plant sim/plants/phantom-stiction.toml --fast --dry-run --plot {G}/tune-phantom-stiction.png"],
        figures: &["tune-phantom-stiction.png", "tune-phantom-stiction-kb.png"],
    },
    Entry {
        heading: "simulate: the paper's base scene",
        runs: &["simulate sim/scenes/base.toml --out {T}/base.csv --plot {G}/simulate-base.png"],
        figures: &["simulate-base.png"],
    },
    Entry {
        heading: "simulate: a plant file",
        runs: &["simulate sim/plants/phantom-realistic.toml --out {T}/phantom-realistic.csv --plot {G}/simulate-phantom-realistic.png"],
        figures: &["simulate-phantom-realistic.png"],
    },
    Entry {
        heading: "map: one panel",
        runs: &["map --beta 0:1:11 --sigma 0:2:11 --periods 2000 --quiet --plot {G}/map-one-panel.png"],
        figures: &["map-one-panel.png"],
    },
    Entry {
        heading: "map: many panels with the analytic boundaries",
        runs: &["map --tau-d 0,1 --xidot0 1,5,20 --beta 0:1:11 --sigma 0:2:11 --periods 2000 --overlay --quiet --plot {G}/map-panels.png"],
        figures: &["map-panels.png"],
    },
    Entry {
        heading: "map --k-b: the (K, B) plane of a preset",
        runs: &["map --k-b --device maxon-re35 --k-axis 0.5:8:9 --b-axis 0:0.002:9 --periods 3000 --quiet --plot {G}/map-kb-maxon-re35.png"],
        figures: &["map-kb-maxon-re35.png"],
    },
    Entry {
        heading: "map --k-b: the (K, B) plane of a plant file",
        runs: &["map --k-b --plant sim/plants/phantom-stiction.toml --k-axis 200:4000:9 --b-axis 0:5:9 --periods 3000 --quiet --plot {G}/map-kb-phantom-stiction.png"],
        figures: &["map-kb-phantom-stiction.png"],
    },
    Entry {
        heading: "map atlas: a panel per slice and the summary",
        runs: &[
            "map --mu 10,100 --xidot0 5 --beta 0:1:11 --sigma 0:2:11 --periods 2000 --quiet --force --out {T}/atlas-map.json",
            "map atlas {T}/atlas-map.json --plots {G}/atlas",
        ],
        figures: &[
            "atlas/atlas-mu10.0000-tau0-xidot5.png",
            "atlas/atlas-mu100.0000-tau0-xidot5.png",
            "atlas/atlas-summary.png",
        ],
    },
    Entry {
        heading: "experiment release: a preset",
        runs: &["experiment release --device maxon-re35 --fast --deflection 40 --stiffness 2 --plot {G}/release-maxon-re35.png"],
        figures: &["release-maxon-re35.png"],
    },
    Entry {
        heading: "experiment release: a plant file",
        runs: &["experiment release --plant sim/plants/phantom-stiction.toml --fast --deflection 20 --stiffness 800 --plot {G}/release-phantom-stiction.png"],
        figures: &["release-phantom-stiction.png"],
    },
    Entry {
        heading: "replay: a recording of a preset through its plant",
        runs: &[
            "record --device maxon-re35 --fast --seconds 1 --release 40 --stiffness 2 {T}/rec-maxon-re35.csv",
            "replay {T}/rec-maxon-re35.csv --device maxon-re35 --plot {G}/replay-maxon-re35.png",
        ],
        figures: &["replay-maxon-re35.png"],
    },
    Entry {
        heading: "replay: a recording of a plant file through the recording's plant",
        runs: &[
            "record --plant sim/plants/phantom-stiction.toml --fast --seconds 1 --release 20 --stiffness 800 {T}/rec-phantom-stiction.csv",
            "replay {T}/rec-phantom-stiction.csv --plot {G}/replay-phantom-stiction.png",
        ],
        figures: &["replay-phantom-stiction.png"],
    },
];

/// Runs `cargo xtask figures [--check]`.
///
/// # Errors
/// A bad option, a failed build or run, a figure without its text, or (with `--check`) a
/// stale docs/FIGURES.md or a missing PNG.
pub fn figures(args: &[String]) -> Result<()> {
    let check = match args {
        [] => false,
        [a] if a == "--check" => true,
        _ => bail!("figures takes no arguments but --check (got {args:?})"),
    };
    let hostctl = crate::process::build_hostctl()?;
    let root = firmware::root();
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), PathBuf::from);
    let scratch = target.join("figures");
    let _ = std::fs::remove_dir_all(&scratch);
    let gallery = if check {
        scratch.join("gallery")
    } else {
        root.join(GALLERY)
    };
    // Figures no longer in the gallery must not linger.
    let _ = std::fs::remove_dir_all(&gallery);
    std::fs::create_dir_all(gallery.join("atlas"))?;
    let markdown = draw_all(&hostctl, &root, &gallery, &scratch)?;
    let path = root.join("docs/FIGURES.md");
    if check {
        return compare(&path, &markdown, &root.join(GALLERY));
    }
    std::fs::write(&path, markdown).with_context(|| format!("writing {}", path.display()))?;
    eprintln!("xtask figures: wrote docs/FIGURES.md and {GALLERY}/");
    Ok(())
}

/// Runs every entry into `gallery` and returns the markdown of the gallery.
fn draw_all(hostctl: &Path, root: &Path, gallery: &Path, scratch: &Path) -> Result<String> {
    let mut md = String::from(HEADER);
    for e in ENTRIES {
        let _ = writeln!(md, "\n## {}\n\n```sh", e.heading);
        for r in e.runs {
            let shown = r.replace("{G}", GALLERY).replace("{T}", SCRATCH);
            let _ = writeln!(md, "hostctl {shown}");
            let actual = r
                .replace("{G}", &gallery.to_string_lossy())
                .replace("{T}", &scratch.to_string_lossy());
            std::fs::create_dir_all(scratch)?;
            run(Command::new(hostctl)
                .args(actual.split_whitespace())
                .env("STIFFWALL_FIGURE_TEXT", "1")
                .stdout(Stdio::null())
                .current_dir(root))?;
        }
        md.push_str("```\n");
        for f in e.figures {
            let text_path = gallery.join(format!("{f}.txt"));
            let text = std::fs::read_to_string(&text_path).with_context(|| {
                format!("{}: the figure's text was not written", text_path.display())
            })?;
            std::fs::remove_file(&text_path)?;
            let _ = write!(md, "\n![{f}](figures/gallery/{f})\n\n{text}");
        }
    }
    md.push_str(LIVE_VIEW);
    Ok(md)
}

/// The live view's panels are drawn by the browser, not by `hostctl`: the page shows the
/// screenshots that `cargo xtask ui-screenshots` takes (its browser test runs in `ci`).
const LIVE_VIEW: &str = "\n## hostctl ui: the live view's panels\n\n\
Drawn by the page in the browser, so not by this xtask: `cargo xtask ui-screenshots` takes \
these through the browser test that `cargo xtask ci` runs. Traces of position [counts], force \
[N or N·m] and storage energy H_T/(KΔ²) with the fault bits over time [s]; the (β, σ) plane of \
the spring wall of the connected device (regions A–E of the spring alone, critical line, the \
path of the point as K grows, the stiffness limits and the configured K with its unit, a \
legend under it); the (B, K) frontier of the spring + damper wall (K_max(B), the quiet \
ceiling 2c/Δ, the chatter band, the best B and the configured (B, K) with units, a legend \
under it); the map viewer's panels (β = b/(KT), σ = c/(KΔ), ξ̇0 in ticks/period).\n\n\
![ui-overview.png](figures/ui-overview.png)\n\n\
![ui-map.png](figures/ui-map.png)\n";

const HEADER: &str = "# Figure gallery\n\n\
Every kind of figure the `hostctl` commands write, drawn on a preset and, where the command \
takes one, on a plant file of `sim/plants/`. Generated by `cargo xtask figures`; \
`cargo xtask figures --check` (in `cargo xtask ci`) draws it again and fails when this page \
is stale. The PNGs depend on the fonts of the machine that drew them; the words under each \
image do not: they are the figure's title, axis labels, legend entries and key values as \
drawn (`stiffwall_figures::describe`), and are what the check compares.\n";

/// A section's text with every number replaced by `#`: the figures of runs on the fast
/// virtual device (tune, release tests, recordings) are compared this way, since host and
/// device threads race there and a figure's values can move in their last digits from one
/// machine to another; everything else (titles, axes, legend entries, units) must match.
fn without_numbers(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut in_number = false;
    for ch in s.chars() {
        let digit = ch.is_ascii_digit() || (in_number && matches!(ch, '.' | 'e' | '-' | '+'));
        if digit {
            if !in_number {
                out.push('#');
            }
        } else {
            out.push(ch);
        }
        in_number = digit;
    }
    out
}

/// The sections of a gallery page by heading (the text before the first heading first).
fn sections(md: &str) -> Vec<&str> {
    md.split("\n## ").collect()
}

/// Whether the section whose text is `section` runs on the fast virtual device.
fn on_the_device(section: &str) -> bool {
    section
        .lines()
        .any(|l| l.starts_with("hostctl ") && l.contains(" --fast"))
}

/// `--check`: the fresh markdown against docs/FIGURES.md (exactly, but for the numbers of
/// figures drawn from runs on the fast virtual device), and every PNG it names present.
fn compare(path: &Path, fresh: &str, gallery: &Path) -> Result<()> {
    let old =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let (a, b) = (sections(&old), sections(fresh));
    let same = a.len() == b.len()
        && a.iter()
            .zip(&b)
            .all(|(x, y)| x == y || (on_the_device(y) && without_numbers(x) == without_numbers(y)));
    if !same {
        let first = old
            .lines()
            .zip(fresh.lines())
            .position(|(a, b)| a != b)
            .unwrap_or_else(|| old.lines().count().min(fresh.lines().count()));
        let line = |s: &str| s.lines().nth(first).unwrap_or("(end of file)").to_owned();
        bail!(
            "docs/FIGURES.md is stale (first difference at line {}):\n  docs: {}\n  fresh: {}\nrun `cargo xtask figures`",
            first + 1,
            line(&old),
            line(fresh)
        );
    }
    let missing: Vec<&str> = ENTRIES
        .iter()
        .flat_map(|e| e.figures.iter().copied())
        .filter(|f| !gallery.join(f).is_file())
        .collect();
    ensure!(
        missing.is_empty(),
        "{GALLERY}/ lacks {missing:?}, named by docs/FIGURES.md; run `cargo xtask figures`"
    );
    eprintln!("xtask figures: docs/FIGURES.md matches a fresh run; every PNG it names is present");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_numbers_of_device_runs_may_move() {
        assert_eq!(
            without_numbers("K = 3.347 N·m/rad, B = 5.462e-3, 12 tests"),
            "K = # N·m/rad, B = #, # tests"
        );
        let device = "tune\n\n```sh\nhostctl tune --fast --dry-run\n```\n- K = 3.347 N·m/rad\n";
        assert!(on_the_device(device));
        assert!(!on_the_device(
            "map\n\n```sh\nhostctl map --quiet\n```\n- K = 3\n"
        ));
        assert_eq!(
            without_numbers(device),
            without_numbers(&device.replace("3.347", "3.351"))
        );
        assert_ne!(
            without_numbers(device),
            without_numbers(&device.replace("N·m/rad", "N/m"))
        );
    }
}
