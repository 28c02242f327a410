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

use crate::figure::{self, DrawResult, Figure, FigureError};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
pub use stiffwall_analysis::frontier::*;

/// Size of the frontier figure in pixels.
pub const SIZE_PX: (u32, u32) = (900, 660);

/// A chart over the (B, K) plane.
pub type KbChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draws the axes (no mesh) with the labels `B [unit]` and `K [unit]`.
///
/// # Errors
/// A drawing error.
pub fn axes<DB: DrawingBackend>(chart: &mut KbChart<'_, DB>, u: Units) -> DrawResult
where
    DB::ErrorType: 'static,
{
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(format!("B [{}]", u.b))
        .y_desc(format!("K [{}]", u.k))
        .draw()?;
    Ok(())
}

/// Draws the boundary `pts` (B, K_max) in red, K clamped to `y0..=y1`; with a `label`, as a
/// legend entry.
///
/// # Errors
/// A drawing error.
pub fn draw_boundary<DB: DrawingBackend>(
    chart: &mut KbChart<'_, DB>,
    pts: &[(f64, f64)],
    (y0, y1): (f64, f64),
    label: Option<String>,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let line: Vec<(f64, f64)> = pts
        .iter()
        .filter(|p| p.1.is_finite())
        .map(|&(b, k)| (b, k.clamp(y0, y1)))
        .collect();
    let series = chart.draw_series(LineSeries::new(line, RED.stroke_width(2)))?;
    if let Some(label) = label {
        series
            .label(label)
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], RED.stroke_width(2)));
    }
    Ok(())
}

impl Figure for Frontier {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let (x1, y1) = self.ranges();
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 20))
            .margin(14)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..x1, 0.0..y1)?;
        axes(&mut chart, self.units)?;
        let label = Some(self.boundary_label.clone());
        draw_boundary(&mut chart, &self.boundary, (0.0, y1), label)?;
        draw_quiet_ceiling(self, &mut chart, x1)?;
        draw_points(self, &mut chart)?;
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
        Ok(())
    }
}

/// The quiet ceiling as a dashed horizontal line over the whole B axis: below it a wall can
/// come to rest; between it and K_max(B) it chatters; above K_max(B) it grows.
fn draw_quiet_ceiling<DB: DrawingBackend>(
    f: &Frontier,
    chart: &mut KbChart<'_, DB>,
    x1: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let Some(k) = f.quiet_ceiling.filter(|k| k.is_finite() && *k > 0.0) else {
        return Ok(());
    };
    let purple = RGBColor(130, 60, 170);
    chart
        .draw_series(DashedLineSeries::new(
            vec![(0.0, k), (x1, k)],
            8,
            5,
            purple.stroke_width(2),
        ))?
        .label(format!(
            "quiet ceiling 2c/Δ = {k:.4e}: above it every wall chatters (up to K_max(B); above that it grows)"
        ))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], purple.stroke_width(2)));
    Ok(())
}

fn draw_points<DB: DrawingBackend>(f: &Frontier, chart: &mut KbChart<'_, DB>) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let blue = RGBColor(40, 90, 200);
    let ok: Vec<(f64, f64)> = f
        .verified
        .iter()
        .filter_map(|&(b, k)| k.map(|k| (b, k)))
        .collect();
    if !ok.is_empty() {
        chart
            .draw_series(ok.iter().map(|&p| Circle::new(p, 5, blue.filled())))?
            .label("verified: largest resting K at each B tried")
            .legend(move |(x, y)| Circle::new((x + 9, y), 5, blue.filled()));
    }
    let none: Vec<f64> = f
        .verified
        .iter()
        .filter(|v| v.1.is_none())
        .map(|v| v.0)
        .collect();
    if !none.is_empty() {
        chart
            .draw_series(
                none.iter()
                    .map(|&b| Cross::new((b, 0.0), 7, blue.stroke_width(2))),
            )?
            .label("B tried, no K at or above the best so far (on the B axis)")
            .legend(move |(x, y)| Cross::new((x + 9, y), 5, blue.stroke_width(2)));
    }
    if let Some(k) = f.spring_only {
        let green = RGBColor(20, 140, 60);
        chart
            .draw_series(std::iter::once(TriangleMarker::new(
                (0.0, k),
                8,
                green.filled(),
            )))?
            .label(format!("spring-only wall K = {k:.4e}"))
            .legend(move |(x, y)| TriangleMarker::new((x + 9, y), 6, green.filled()));
    }
    draw_marks(f, chart)
}

fn draw_marks<DB: DrawingBackend>(f: &Frontier, chart: &mut KbChart<'_, DB>) -> DrawResult
where
    DB::ErrorType: 'static,
{
    if let Some(m) = &f.best {
        let orange = RGBColor(230, 130, 20);
        chart
            .draw_series(std::iter::once(Cross::new(
                (m.b, m.k),
                8,
                orange.stroke_width(3),
            )))?
            .label(m.label.clone())
            .legend(move |(x, y)| Cross::new((x + 9, y), 6, orange.stroke_width(3)));
    }
    if let Some(m) = &f.chosen {
        chart
            .draw_series(std::iter::once(
                EmptyElement::at((m.b, m.k))
                    + Circle::new((0, 0), 9, BLACK.stroke_width(3))
                    + Circle::new((0, 0), 4, BLACK.filled()),
            ))?
            .label(m.label.clone())
            .legend(|(x, y)| Circle::new((x + 9, y), 7, BLACK.stroke_width(3)));
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
        let svg = std::fs::read_to_string(&path).unwrap();
        for needle in [
            "B [N·s/m]",
            "K [N/m]",
            "boundary",
            "verified: largest resting K",
            "quiet ceiling 2c/Δ = 2.5000e2",
            "no K at or above the best so far (on the B axis)",
            "spring-only wall K = 1.0000e2",
            "set wall",
        ] {
            assert!(svg.contains(needle), "lacks {needle}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
