//! `cargo xtask readme-figures`: the README's figures of how `tune` does against the truth are
//! the ones its tables state, so a regenerated table cannot leave a stale claim behind.
//!
//! Each table (`docs/TUNE.md`, `docs/TUNE-holdout.md`) ends in a summary line written by
//! `tune-table` ("Over N tuned plants: median K set / K*(0) = M …, K set / K*(B set) from A to
//! B; …"). The README must quote, for each: the range "A–B" (en dash), "median M" and the
//! number of plants, and it must give the number of plant files in `sim/plants/` where it says
//! how many there are. Units: the figures are dimensionless ratios, compared as the text the
//! tables print (3 and 2 decimals). Reads files only; runs nothing.

use anyhow::{bail, Context, Result};
use std::path::Path;

/// The figures of one table's summary line.
#[derive(Debug, PartialEq)]
struct Summary {
    plants: String,
    median: String,
    lo: String,
    hi: String,
}

fn between<'a>(s: &'a str, start: &str, end: &str) -> Option<&'a str> {
    let from = s.find(start)? + start.len();
    let len = s[from..].find(end)?;
    Some(s[from..from + len].trim())
}

fn summary(table: &str) -> Option<Summary> {
    let line = table.lines().rev().find(|l| l.starts_with("Over "))?;
    Some(Summary {
        plants: between(line, "Over ", " tuned plants")?.to_owned(),
        median: between(line, "median K set / K*(0) = ", " ")?.to_owned(),
        lo: between(line, "K set / K*(B set) from ", " to ")?.to_owned(),
        hi: between(line, " to ", ";")?.to_owned(),
    })
}

/// The claims `readme` must make about the table of `what` with summary `s`.
fn missing(readme: &str, what: &str, s: &Summary, plants_phrase: &str) -> Vec<String> {
    let flat = readme.split_whitespace().collect::<Vec<_>>().join(" ");
    [
        format!("{}–{}", s.lo, s.hi),
        format!("median {}", s.median),
        plants_phrase.replace("{n}", &s.plants),
    ]
    .into_iter()
    .filter(|claim| !flat.contains(claim.as_str()))
    .map(|claim| format!("{what}: the README does not say \"{claim}\""))
    .collect()
}

fn check(root: &Path) -> Result<Vec<String>> {
    let read =
        |p: &str| std::fs::read_to_string(root.join(p)).with_context(|| format!("reading {p}"));
    let readme = read("README.md")?;
    let mut wrong = Vec::new();
    for (doc, phrase) in [
        ("docs/TUNE.md", "On the {n} plants of `sim/plants/`"),
        (
            "docs/TUNE-holdout.md",
            "`docs/TUNE-holdout.md` is the {n} plants of `sim/plants-holdout/`",
        ),
    ] {
        let s = summary(&read(doc)?).with_context(|| format!("{doc}: no summary line"))?;
        wrong.extend(missing(&readme, doc, &s, phrase));
    }
    let files = std::fs::read_dir(root.join("sim/plants"))?
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "toml"))
        .count();
    let flat = readme.split_whitespace().collect::<Vec<_>>().join(" ");
    let said = format!("`sim/plants/` has {files} such plants");
    if !flat.contains(&said) {
        wrong.push(format!("sim/plants/: the README does not say \"{said}\""));
    }
    Ok(wrong)
}

/// Runs the check on the repository.
///
/// # Errors
/// A missing file or summary line, or every claim the README gets wrong.
pub fn readme_figures() -> Result<()> {
    let wrong = check(&crate::firmware::root())?;
    if !wrong.is_empty() {
        bail!(
            "README.md is stale against the tune tables:\n  {}",
            wrong.join("\n  ")
        );
    }
    eprintln!("xtask readme-figures: README.md quotes docs/TUNE.md and docs/TUNE-holdout.md");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const LINE: &str = "| row |\n\nOver 9 tuned plants: median K set / K*(0) = 3.15 (the damper's gain, quietly), K set / K*(B set) from 0.730 to 1.009; 0 set walls do not come to rest in every run.\n";

    #[test]
    fn the_summary_line_is_read() {
        let s = summary(LINE).unwrap();
        assert_eq!(
            s,
            Summary {
                plants: "9".into(),
                median: "3.15".into(),
                lo: "0.730".into(),
                hi: "1.009".into()
            }
        );
    }

    #[test]
    fn a_stale_or_missing_figure_is_named() {
        let s = summary(LINE).unwrap();
        let good = "the 9\n plants: K/K* 0.730–1.009, median 3.15 × K*(0)";
        assert!(missing(good, "t", &s, "the {n} plants").is_empty());
        let stale = "the 9 plants: K/K* 0.731–0.980, median 3.20 × K*(0)";
        let m = missing(stale, "t", &s, "the {n} plants");
        assert_eq!(m.len(), 2, "{m:?}");
        assert!(m[0].contains("0.730–1.009") && m[1].contains("median 3.15"));
    }
}
