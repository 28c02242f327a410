//! The drawing of the (B, K) plane of one device (its data: [`stiffwall_analysis::frontier`],
//! re-exported here): virtual damping B on x, wall stiffness K on y, with core's
//! predicted exact linear boundary K_max(B) (`stiffwall_core::criteria::k_max_exact_linear`).
//! Shared by `hostctl map --k-b` (under its map), `hostctl analyze --damping B --plot` and
//! `hostctl tune --plot` (the frontier figure, [`Frontier`]).
//!
//! Units: B in N·s/m and K in N/m for a linear device, N·m·s/rad and N·m/rad for a rotational
//! one ([`Units`]); sizes in pixels.
//!
//! Invariants: the boundary is computed by core (here by [`boundary`], or by the caller), never
//! restated; a K_max that is not finite is not drawn, one outside the plotted K range is
//! clamped to it. The frontier figure's file is named [`kb_path`] of the (β, σ) figure's.

use crate::describe::Description;
use crate::figure::{self, DrawResult, Figure, FigureError};
use crate::layout::{self, Glyph};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
pub use stiffwall_analysis::frontier::*;

/// Size of the frontier figure in pixels.
pub const SIZE_PX: (u32, u32) = (1100, 680);
/// Width of the legend panel, px.
const LEGEND_W: u32 = 380;

/// A chart over the (B, K) plane.
pub type KbChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The axis labels of the (B, K) plane in `u`: B first.
#[must_use]
pub fn axis_labels(u: Units) -> [String; 2] {
    [
        format!("B, virtual damping of the wall [{}]", u.b),
        format!("K, wall stiffness [{}]", u.k),
    ]
}

/// Draws the axes (no mesh) with the labels of [`axis_labels`].
///
/// # Errors
/// A drawing error.
pub fn axes<DB: DrawingBackend>(chart: &mut KbChart<'_, DB>, u: Units) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let [x, y] = axis_labels(u);
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(x)
        .y_desc(y)
        .axis_desc_style(("sans-serif", layout::AXIS_PX))
        .label_style(("sans-serif", layout::TICK_PX))
        .y_label_formatter(&|k| sig(*k))
        .draw()?;
    Ok(())
}

/// The runs of the polyline `pts` inside `y0..=y1`, cut where it leaves the range (the
/// crossing interpolated); points that are not finite end a run.
#[must_use]
pub fn clip(pts: &[(f64, f64)], (y0, y1): (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    let inside = |p: &(f64, f64)| p.1.is_finite() && (y0..=y1).contains(&p.1);
    let cross = |a: (f64, f64), b: (f64, f64)| {
        let y = if a.1.max(b.1) > y1 { y1 } else { y0 };
        let t = (y - a.1) / (b.1 - a.1);
        (a.0 + t * (b.0 - a.0), y)
    };
    let mut runs = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    for (i, p) in pts.iter().enumerate() {
        let prev = i.checked_sub(1).map(|j| pts[j]);
        let finite_pair = |q: (f64, f64)| q.1.is_finite() && p.1.is_finite();
        match prev {
            Some(q) if inside(p) && !inside(&q) && finite_pair(q) => cur.push(cross(q, *p)),
            Some(q) if !inside(p) && inside(&q) && finite_pair(q) => cur.push(cross(q, *p)),
            _ => {}
        }
        if inside(p) {
            cur.push(*p);
        } else if !cur.is_empty() {
            runs.push(std::mem::take(&mut cur));
        }
    }
    runs.push(cur);
    runs.retain(|r| r.len() >= 2);
    runs
}

/// Draws the boundary `pts` (B, K_max) in red, only where K is inside `y0..=y1` (a curve
/// leaving the range ends at the border, it never runs along it).
///
/// # Errors
/// A drawing error.
pub fn draw_boundary<DB: DrawingBackend>(
    chart: &mut KbChart<'_, DB>,
    pts: &[(f64, f64)],
    range: (f64, f64),
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    for run in clip(pts, range) {
        chart.draw_series(LineSeries::new(run, RED.stroke_width(2)))?;
    }
    Ok(())
}

const BLUE_PT: RGBColor = RGBColor(40, 90, 200);
const GREEN: RGBColor = RGBColor(20, 140, 60);
const ORANGE: RGBColor = RGBColor(230, 130, 20);
/// The colour of the quiet ceiling, shared with the (K, B) map.
pub const PURPLE: RGBColor = RGBColor(130, 60, 170);

/// The legend text of the quiet ceiling `k` in unit `u`.
#[must_use]
pub fn quiet_ceiling_label(k: f64, unit: &str) -> String {
    format!(
        "quiet ceiling 2·max(c, F_s)/Δ = {} {unit}: above it no wall comes to rest (it chatters up to K_max(B), grows above)",
        sig(k)
    )
}

fn quiet(f: &Frontier) -> Option<f64> {
    f.quiet_ceiling.filter(|k| k.is_finite() && *k > 0.0)
}

/// The legend entries of `f` in drawing order, with their glyphs.
fn entries(f: &Frontier) -> Vec<(Glyph, String)> {
    let mut out = vec![(Glyph::Line(RED, 2), f.boundary_label.clone())];
    if let Some(k) = quiet(f) {
        out.push((Glyph::Dashed(PURPLE, 2), quiet_ceiling_label(k, f.units.k)));
    }
    if f.verified.iter().any(|v| v.1.is_some()) {
        out.push((
            Glyph::Dot(BLUE_PT),
            "verified: the largest resting K at each B tried".to_owned(),
        ));
    }
    if f.verified.iter().any(|v| v.1.is_none()) {
        out.push((
            Glyph::Cross(BLUE_PT),
            "B tried, no K at or above the best so far (on the B axis)".to_owned(),
        ));
    }
    if let Some(k) = f.spring_only {
        out.push((
            Glyph::Triangle(GREEN),
            format!("spring-only wall K = {} {}", sig(k), f.units.k),
        ));
    }
    if let Some(m) = &f.best {
        out.push((Glyph::Cross(ORANGE), m.label.clone()));
    }
    if let Some(m) = &f.chosen {
        out.push((Glyph::Ring(BLACK), m.label.clone()));
    }
    out
}

impl Figure for Frontier {
    fn describe(&self) -> Description {
        let mut d = Description::new(self.title.clone());
        for a in axis_labels(self.units) {
            d.axis(a);
        }
        for (_, e) in entries(self) {
            d.legend(e);
        }
        d
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let d = self.describe();
        let body = layout::titled(root, &d.title)?;
        let (w, _) = body.dim_in_pixel();
        let (left, right) = body.split_horizontally(w.saturating_sub(LEGEND_W));
        let (x1, y1) = self.ranges();
        let mut chart = ChartBuilder::on(&left)
            .margin(14)
            .x_label_area_size(50)
            .y_label_area_size(85)
            .build_cartesian_2d(0.0..x1, 0.0..y1)?;
        axes(&mut chart, self.units)?;
        draw_boundary(&mut chart, &self.boundary, (0.0, y1))?;
        if let Some(k) = quiet(self) {
            let style = PURPLE.stroke_width(2);
            chart.draw_series(DashedLineSeries::new(vec![(0.0, k), (x1, k)], 8, 5, style))?;
        }
        draw_points(self, &mut chart)?;
        let keys = layout::keys(&d, entries(self))?;
        layout::legend(&right.margin(14, 0, 0, 8), &keys)
    }
}

fn draw_points<DB: DrawingBackend>(f: &Frontier, chart: &mut KbChart<'_, DB>) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let ok = f.verified.iter().filter_map(|&(b, k)| k.map(|k| (b, k)));
    chart.draw_series(ok.map(|p| Circle::new(p, 5, BLUE_PT.filled())))?;
    let none = f.verified.iter().filter(|v| v.1.is_none());
    chart.draw_series(none.map(|v| Cross::new((v.0, 0.0), 7, BLUE_PT.stroke_width(2))))?;
    if let Some(k) = f.spring_only {
        chart.draw_series(std::iter::once(TriangleMarker::new(
            (0.0, k),
            8,
            GREEN.filled(),
        )))?;
    }
    if let Some(m) = &f.best {
        chart.draw_series(std::iter::once(Cross::new(
            (m.b, m.k),
            8,
            ORANGE.stroke_width(3),
        )))?;
    }
    if let Some(m) = &f.chosen {
        chart.draw_series(std::iter::once(
            EmptyElement::at((m.b, m.k))
                + Circle::new((0, 0), 9, BLACK.stroke_width(3))
                + Circle::new((0, 0), 4, BLACK.filled()),
        ))?;
    }
    Ok(())
}

/// Writes the frontier figure to `path` (.svg or .png, any case).
///
/// # Errors
/// An unsupported extension, or a drawing or file error.
pub fn write(path: &Path, f: &Frontier) -> Result<(), FigureError> {
    figure::write(path, SIZE_PX, f)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frontier(verified: Vec<(f64, Option<f64>)>, boundary: Vec<(f64, f64)>) -> Frontier {
        Frontier {
            title: "t".into(),
            units: Units::of(false),
            boundary,
            boundary_label: "boundary".into(),
            verified,
            spring_only: Some(100.0),
            best: None,
            chosen: Some(Mark {
                b: 0.0,
                k: 100.0,
                label: "set wall".into(),
            }),
            quiet_ceiling: None,
        }
    }

    #[test]
    fn a_b_without_verified_k_is_drawn_on_the_b_axis_with_its_legend_note() {
        let dir = std::env::temp_dir().join(format!("stiffwall-kb-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("f.svg");
        let mut f = frontier(
            vec![(0.0, Some(100.0)), (1.0, None), (2.0, Some(300.0))],
            boundary(
                &stiffwall_core::devices::find("phantom-1.0").unwrap().params,
                3.0,
            ),
        );
        f.quiet_ceiling = Some(250.0);
        write(&path, &f).unwrap();
        let svg = crate::describe::svg_text(&std::fs::read_to_string(&path).unwrap());
        for needle in [
            "B, virtual damping of the wall [N·s/m]",
            "K, wall stiffness [N/m]",
            "boundary",
            "verified: the largest resting K",
            "quiet ceiling 2·max(c, F_s)/Δ = 250.0 N/m",
            "no K at or above the best so far (on the B axis)",
            "spring-only wall K = 100.0 N/m",
            "set wall",
        ] {
            assert!(svg.contains(needle), "lacks {needle}");
        }
        assert!(crate::figure::audit(&f, SIZE_PX, Some(false))
            .unwrap()
            .is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_boundary_ends_at_the_top_border_instead_of_running_along_it() {
        let runs = clip(
            &[(0.0, 1.0), (1.0, 3.0), (2.0, 5.0), (3.0, 1.0)],
            (0.0, 4.0),
        );
        assert_eq!(runs.len(), 2, "{runs:?}");
        assert_eq!(runs[0], vec![(0.0, 1.0), (1.0, 3.0), (1.5, 4.0)]);
        assert_eq!(runs[1], vec![(2.25, 4.0), (3.0, 1.0)]);
        assert!(clip(&[(0.0, f64::NAN), (1.0, 1.0)], (0.0, 4.0)).is_empty());
    }
}
