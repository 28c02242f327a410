//! Text layout shared by the figures: a title wrapped to the figure's width and a legend panel
//! outside the plotting area (never over the data), its entries wrapped to the panel's width.
//!
//! Units: pixels. Invariants: text is measured with the backend's own font metrics
//! (`estimate_text_size`) and wrapped at spaces so that no line is wider than its area; a word
//! wider than the area stands alone on its line. The legend draws exactly the entries given, in
//! order, each with the glyph of its series.

use crate::describe::Description;
use crate::figure::DrawResult;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Title font size, px.
pub const TITLE_PX: u32 = 20;
/// Legend and note font size, px.
pub const LEGEND_PX: u32 = 14;
/// Axis description font size, px.
pub const AXIS_PX: u32 = 15;
/// Tick label font size, px.
pub const TICK_PX: u32 = 13;

/// The mark of one legend entry: what its series looks like.
#[derive(Debug, Clone, Copy)]
pub enum Glyph {
    /// A filled square (a region or cell colour), with a thin black border.
    Swatch(RGBColor),
    /// A solid line of this width.
    Line(RGBColor, u32),
    /// A dashed line of this width.
    Dashed(RGBColor, u32),
    /// A filled dot.
    Dot(RGBColor),
    /// A ring (hollow circle).
    Ring(RGBColor),
    /// A cross.
    Cross(RGBColor),
    /// A filled triangle.
    Triangle(RGBColor),
}

fn width_of<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, text: &str, px: u32) -> u32 {
    area.estimate_text_size(text, &TextStyle::from(("sans-serif", px).into_font()))
        .map_or(text.chars().count() as u32 * px * 6 / 10, |s| s.0)
}

/// Unit words that stay on the line of the number before them.
const UNITS: [&str; 11] = [
    "N/m",
    "N·m/rad",
    "N·s/m",
    "N·m·s/rad",
    "s",
    "ticks",
    "Hz",
    "rad/s",
    "m/s",
    "%",
    "J",
];

fn is_unit(word: &str) -> bool {
    UNITS.contains(&word.trim_end_matches([',', ';', ':', ')', '.']))
}

/// `text` wrapped at spaces (never before a unit word, nor on either side of an `=`) into lines no wider than `width` px at `px` font size.
pub fn wrap<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    px: u32,
    width: u32,
) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    // Byte offset in `line` where its last unbreakable group (a number with its `=` and
    // unit) starts: a glued word that does not fit moves the whole group to the next line.
    let mut group = 0;
    for word in text.split(' ') {
        let glued = is_unit(word) || word == "=" || line.ends_with(" =");
        if !glued && !line.is_empty() {
            group = line.len() + 1;
        }
        let candidate = if line.is_empty() {
            word.to_owned()
        } else {
            format!("{line} {word}")
        };
        if line.is_empty() || width_of(area, &candidate, px) <= width {
            line = candidate;
        } else if !glued {
            lines.push(std::mem::take(&mut line));
            line = word.to_owned();
            group = 0;
        } else if group > 0 {
            let tail = candidate[group..].to_owned();
            line.truncate(group - 1);
            lines.push(std::mem::replace(&mut line, tail));
            group = 0;
        } else {
            line = candidate;
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// Height in px of `text` wrapped into `width` px at the title size, with padding.
pub fn title_height<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, text: &str) -> u32 {
    let w = area.dim_in_pixel().0.saturating_sub(24);
    wrap(area, text, TITLE_PX, w).len() as u32 * (TITLE_PX + 6) + 12
}

/// Splits off the title band of `root` and draws `text` in it, centred and wrapped; returns
/// the rest.
///
/// # Errors
/// A drawing error.
pub fn titled<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    text: &str,
) -> DrawResult<DrawingArea<DB, Shift>>
where
    DB::ErrorType: 'static,
{
    let h = title_height(root, text);
    let (top, rest) = root.split_vertically(h);
    let w = top.dim_in_pixel().0;
    let style = TextStyle::from(("sans-serif", TITLE_PX).into_font())
        .pos(Pos::new(HPos::Center, VPos::Top));
    for (i, l) in wrap(&top, text, TITLE_PX, w.saturating_sub(24))
        .iter()
        .enumerate()
    {
        let y = 8 + i as i32 * (TITLE_PX as i32 + 6);
        top.draw(&Text::new(l.clone(), (w as i32 / 2, y), style.clone()))?;
    }
    Ok(rest)
}

/// Height in px of a legend of `entries` in a panel `width` px wide.
pub fn legend_height<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[String],
    width: u32,
) -> u32 {
    let lines: usize = entries
        .iter()
        .map(|e| wrap(area, e, LEGEND_PX, width.saturating_sub(40)).len())
        .sum();
    lines as u32 * (LEGEND_PX + 4) + entries.len() as u32 * 4 + 16
}

fn draw_glyph<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    g: Glyph,
    (x, y): (i32, i32),
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (l, r) = ((x, y), (x + 22, y));
    match g {
        Glyph::Swatch(c) => {
            area.draw(&Rectangle::new(
                [(x + 3, y - 7), (x + 19, y + 7)],
                c.filled(),
            ))?;
            area.draw(&Rectangle::new(
                [(x + 3, y - 7), (x + 19, y + 7)],
                BLACK.stroke_width(1),
            ))?;
        }
        Glyph::Line(c, w) => area.draw(&PathElement::new(vec![l, r], c.stroke_width(w)))?,
        Glyph::Dashed(c, w) => {
            for i in 0..3 {
                let x0 = x + i * 8;
                area.draw(&PathElement::new(
                    vec![(x0, y), (x0 + 5, y)],
                    c.stroke_width(w),
                ))?;
            }
        }
        Glyph::Dot(c) => area.draw(&Circle::new((x + 11, y), 5, c.filled()))?,
        Glyph::Ring(c) => area.draw(&Circle::new((x + 11, y), 7, c.stroke_width(3)))?,
        Glyph::Cross(c) => area.draw(&Cross::new((x + 11, y), 6, c.stroke_width(3)))?,
        Glyph::Triangle(c) => area.draw(&TriangleMarker::new((x + 11, y), 7, c.filled()))?,
    }
    Ok(())
}

/// The legend's keys of a figure: each `(glyph, label)` of `entries` checked against the
/// figure's description `d` ([`Description::entry`]), so no series is drawn without its legend
/// entry.
///
/// # Errors
/// A label the description does not list.
pub fn keys(
    d: &Description,
    entries: impl IntoIterator<Item = (Glyph, String)>,
) -> DrawResult<Vec<(Glyph, String)>> {
    entries
        .into_iter()
        .map(|(g, e)| d.entry(&e).map(|e| (g, e)))
        .collect()
}

/// Draws the legend `keys` across the top of `body` and returns the area below it.
///
/// # Errors
/// A drawing error.
pub fn legend_above<DB: DrawingBackend>(
    body: &DrawingArea<DB, Shift>,
    keys: &[(Glyph, String)],
) -> DrawResult<DrawingArea<DB, Shift>>
where
    DB::ErrorType: 'static,
{
    let (w, _) = body.dim_in_pixel();
    let texts: Vec<String> = keys.iter().map(|k| k.1.clone()).collect();
    let (top, below) = body.split_vertically(legend_height(body, &texts, w - 20));
    legend(&top.margin(0, 4, 10, 10), keys)?;
    Ok(below)
}

/// Draws the legend `entries` (glyph, text) into `area`, top to bottom, each text wrapped to
/// the area's width, with a border around them.
///
/// # Errors
/// A drawing error.
pub fn legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(Glyph, String)],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (w, _) = area.dim_in_pixel();
    let line_h = LEGEND_PX as i32 + 4;
    let style = TextStyle::from(("sans-serif", LEGEND_PX).into_font())
        .pos(Pos::new(HPos::Left, VPos::Center));
    let mut y = 10 + line_h / 2;
    for (g, text) in entries {
        draw_glyph(area, *g, (6, y))?;
        for l in wrap(area, text, LEGEND_PX, w.saturating_sub(40)) {
            area.draw(&Text::new(l, (34, y), style.clone()))?;
            y += line_h;
        }
        y += 4;
    }
    let bottom = (y - line_h / 2).min(area.dim_in_pixel().1 as i32 - 1);
    area.draw(&Rectangle::new(
        [(1, 1), (w as i32 - 2, bottom)],
        BLACK.mix(0.5).stroke_width(1),
    ))?;
    Ok(())
}

/// Draws notes (plain text lines, wrapped) into `area` from its top.
///
/// # Errors
/// A drawing error.
pub fn notes<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, lines: &[String]) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (w, _) = area.dim_in_pixel();
    let line_h = LEGEND_PX as i32 + 4;
    let mut y = 4;
    for text in lines {
        for l in wrap(area, text, LEGEND_PX, w.saturating_sub(12)) {
            area.draw(&Text::new(l, (6, y), ("sans-serif", LEGEND_PX)))?;
            y += line_h;
        }
    }
    Ok(())
}

/// Height in px of [`notes`] of `lines` in an area `width` px wide.
pub fn notes_height<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    lines: &[String],
    width: u32,
) -> u32 {
    let n: usize = lines
        .iter()
        .map(|t| wrap(area, t, LEGEND_PX, width.saturating_sub(12)).len())
        .sum();
    n as u32 * (LEGEND_PX + 4) + 8
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every wrapped line fits (a glued group that does not fit moves whole to the next line),
    /// no line starts with a unit or an `=`, and no word is lost.
    #[test]
    fn wrapped_lines_fit_and_keep_numbers_with_their_units() {
        let mut svg = String::new();
        let root = SVGBackend::with_string(&mut svg, (800, 600)).into_drawing_area();
        let text = "the spring alone at K = 3.347 N·m/rad: β = 0.002739, σ = 0.7764, region D; \
                    dots at K/2 = 1.674, 2K = 6.694, 4K = 13.39 N·m/rad";
        for width in [120, 200, 260, 330, 400] {
            let lines = wrap(&root, text, LEGEND_PX, width);
            assert_eq!(lines.join(" "), text, "width {width}");
            for l in &lines {
                assert!(
                    width_of(&root, l, LEGEND_PX) <= width,
                    "{width}: {l:?} of {lines:?}"
                );
                let first = l.split(' ').next().unwrap();
                assert!(!is_unit(first) && first != "=", "{width}: {l:?}");
            }
        }
    }
}
