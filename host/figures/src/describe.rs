//! The words of a figure as text: its title, axis labels, legend entries and key labelled values
//! ([`Description`]), independent of the fonts the image is drawn with. Every figure builds its
//! description first and draws its text from it; the figure gallery (`cargo xtask figures`)
//! lists it under each image and `--check` compares it.
//!
//! Units: none of its own; the strings carry the figure's units (N·m/rad and N·m·s/rad on a
//! rotary device, N/m and N·s/m on a linear one, never both; [`unit_words`]).
//!
//! Invariants ([`Description::problems`]): a title; every axis label names a unit in square
//! brackets or defines a dimensionless quantity ("dimensionless", "(periods)", "[fraction]");
//! every series drawn has a legend entry: drawing code labels a series only through
//! [`Description::entry`], which refuses a label the description does not list.

use std::fmt::Write as _;

/// The environment variable that makes [`crate::figure::write`] also write `<file>.txt`, the
/// figure's [`Description::render`] (used by `cargo xtask figures`).
pub const TEXT_ENV: &str = "STIFFWALL_FIGURE_TEXT";

/// The words of one figure.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Description {
    /// Title (the device or plant and what is drawn).
    pub title: String,
    /// Axis labels with units, x before y, panel by panel (repeated labels listed once).
    pub axes: Vec<String>,
    /// Legend entries, one per colour, line or marker drawn.
    pub legend: Vec<String>,
    /// Key labelled values (with units) and notes drawn on the figure outside the legend.
    pub values: Vec<String>,
}

/// The unit words of stiffness and damping on a rotary (`N·m/rad`, `N·m·s/rad`) or linear
/// (`N/m`, `N·s/m`) device.
#[must_use]
pub fn unit_words(rotational: bool) -> (&'static str, &'static str) {
    if rotational {
        ("N·m/rad", "N·m·s/rad")
    } else {
        ("N/m", "N·s/m")
    }
}

pub use stiffwall_analysis::frontier::sig;

/// The unit words of the other kind of device than `rotational` (what must not appear).
fn foreign_units(rotational: bool) -> &'static [&'static str] {
    if rotational {
        &["N/m", "N·s/m"]
    } else {
        &["N·m/rad", "N·m·s/rad", "/rad"]
    }
}

/// Whether an axis label names its unit or defines a dimensionless quantity.
#[must_use]
pub fn axis_has_unit(label: &str) -> bool {
    let bracket = label
        .find('[')
        .is_some_and(|i| label[i..].find(']').is_some_and(|j| j > 1));
    bracket || label.contains("dimensionless") || label.contains("(periods)")
}

impl Description {
    /// A description with a title.
    #[must_use]
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            ..Self::default()
        }
    }

    /// Adds an axis label (once).
    pub fn axis(&mut self, label: impl Into<String>) -> &mut Self {
        let l = label.into();
        if !self.axes.contains(&l) {
            self.axes.push(l);
        }
        self
    }

    /// Adds a legend entry (once).
    pub fn legend(&mut self, label: impl Into<String>) -> &mut Self {
        let l = label.into();
        if !self.legend.contains(&l) {
            self.legend.push(l);
        }
        self
    }

    /// Adds a labelled value or note.
    pub fn value(&mut self, text: impl Into<String>) -> &mut Self {
        self.values.push(text.into());
        self
    }

    /// The legend entry `label` for a series about to be drawn.
    ///
    /// # Errors
    /// `label` is not among the legend entries: the figure would draw a series its
    /// description does not name.
    pub fn entry(&self, label: &str) -> Result<String, Box<dyn std::error::Error + Send + Sync>> {
        if self.legend.iter().any(|l| l == label) {
            Ok(label.to_owned())
        } else {
            Err(format!(
                "figure '{}': series '{label}' has no legend entry",
                self.title
            )
            .into())
        }
    }

    /// What is wrong with the description: no title, an axis without a unit, no legend; with
    /// `rotational` given, unit words of the other kind of device.
    #[must_use]
    pub fn problems(&self, rotational: Option<bool>) -> Vec<String> {
        let mut out = Vec::new();
        if self.title.trim().is_empty() {
            out.push("no title".to_owned());
        }
        if self.axes.is_empty() {
            out.push("no axis labels".to_owned());
        }
        for a in self.axes.iter().filter(|a| !axis_has_unit(a)) {
            out.push(format!("axis '{a}' names no unit"));
        }
        if self.legend.is_empty() {
            out.push("no legend".to_owned());
        }
        if let Some(rot) = rotational {
            let text = self.render();
            for w in foreign_units(rot) {
                if text.contains(w) {
                    let kind = if rot { "rotary" } else { "linear" };
                    out.push(format!("a {kind} device's figure says '{w}'"));
                }
            }
        }
        out
    }

    /// The description as markdown lines (title, axes, legend, values), one item a line.
    #[must_use]
    pub fn render(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "- title: {}", self.title);
        let _ = writeln!(s, "- axes: {}", self.axes.join("; "));
        for l in &self.legend {
            let _ = writeln!(s, "- legend: {l}");
        }
        for v in &self.values {
            let _ = writeln!(s, "- value: {v}");
        }
        s
    }
}

/// The text of an SVG drawn by plotters: every `<text>` element's content, unescaped, in
/// document order, joined by spaces (wrapped lines join back at their spaces).
#[must_use]
pub fn svg_text(svg: &str) -> String {
    let mut out = Vec::new();
    let mut rest = svg;
    while let Some(i) = rest.find("<text") {
        rest = &rest[i..];
        let Some(open_end) = rest.find('>') else {
            break;
        };
        let Some(close) = rest.find("</text>") else {
            break;
        };
        out.push(
            rest[open_end + 1..close]
                .trim()
                .replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&quot;", "\"")
                .replace("&apos;", "'")
                .replace("&#39;", "'")
                .replace("&amp;", "&"),
        );
        rest = &rest[close..];
    }
    out.join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_units_are_brackets_or_a_dimensionless_definition() {
        assert!(axis_has_unit("t [s]"));
        assert!(axis_has_unit("τ = t/T (periods)"));
        assert!(axis_has_unit("β = b/(KT) (dimensionless viscous friction)"));
        assert!(!axis_has_unit("tau"));
        assert!(!axis_has_unit("H_T"));
        assert!(!axis_has_unit("x []"));
    }

    #[test]
    fn problems_name_a_missing_title_unit_legend_and_foreign_units() {
        let mut d = Description::new("");
        d.axis("tau");
        let p = d.problems(None);
        assert!(p.contains(&"no title".to_owned()), "{p:?}");
        assert!(p.contains(&"axis 'tau' names no unit".to_owned()), "{p:?}");
        assert!(p.contains(&"no legend".to_owned()), "{p:?}");
        let mut d = Description::new("maxon-re35: wall");
        d.axis("K [N·m/rad]").legend("set wall K = 1 N·m/rad");
        assert!(d.problems(Some(true)).is_empty());
        assert!(d.problems(Some(false))[0].contains("linear device's figure says 'N·m/rad'"));
        d.value("quiet ceiling 3 N/m");
        assert!(d.problems(Some(true))[0].contains("'N/m'"));
    }

    #[test]
    fn entry_refuses_a_series_without_a_legend_entry() {
        let mut d = Description::new("t");
        d.legend("a");
        assert_eq!(d.entry("a").unwrap(), "a");
        let e = d.entry("b").unwrap_err().to_string();
        assert!(e.contains("'b' has no legend entry"), "{e}");
    }

    #[test]
    fn sig_keeps_four_digits_and_plain_numbers_in_range() {
        assert_eq!(sig(3.7223), "3.722");
        assert_eq!(sig(2640.4), "2640");
        assert_eq!(sig(0.012345), "0.01235");
        assert_eq!(sig(3.5066e6), "3.507e6");
        assert_eq!(sig(0.0), "0");
        assert_eq!(sig(f64::INFINITY), "n/a");
    }

    #[test]
    fn unit_words_differ_by_kind() {
        assert_eq!(unit_words(true), ("N·m/rad", "N·m·s/rad"));
        assert_eq!(unit_words(false), ("N/m", "N·s/m"));
    }
}
