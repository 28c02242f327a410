//! Figure of a (K, B) map: B on x, K on y (SI, the units of [`stiffwall_analysis::kb::Units`]), classes as
//! the grey levels of the (β, σ) map, and core's predicted exact linear boundary K_max(B) in
//! red (clamped to the plotted K range; K_max = 0 where no K is stable). Axes and boundary are
//! drawn by [`crate::frontier`], shared with the frontier figures of analyze and tune.
//!
//! Invariant: cells are centred on the grid points; drawn only from a computed [`KbFile`].

use crate::figure::{self, DrawResult, Figure, FigureError};
use crate::frontier as kb_plot;
use crate::map::class_color;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use stiffwall_analysis::kb::KbFile;

struct KbFigure<'a>(&'a KbFile);

fn step(lo: f64, hi: f64, n: usize) -> f64 {
    if n > 1 {
        (hi - lo) / (n - 1) as f64
    } else if lo > 0.0 {
        0.1 * lo
    } else {
        1.0
    }
}

impl Figure for KbFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let m = self.0;
        let (k, b, u) = (&m.spec.k, &m.spec.b, m.units);
        root.fill(&WHITE)?;
        let (dk, db) = (step(k.lo, k.hi, k.n), step(b.lo, b.hi, b.n));
        let (x0, x1) = (b.lo - db / 2.0, b.hi + db / 2.0);
        let (y0, y1) = (k.lo - dk / 2.0, k.hi + dk / 2.0);
        let mut chart = ChartBuilder::on(root)
            .caption(
                format!(
                    "(K, B) map, xidot0 = {}, {} periods; purple: chatter; dashed: quiet ceiling 2c/Δ; red: exact linear K_max(B)",
                    m.spec.xidot0, m.spec.periods
                ),
                ("sans-serif", 16),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        kb_plot::axes(&mut chart, u)?;
        chart.draw_series(m.points.iter().map(|p| {
            Rectangle::new(
                [
                    (p.b - db / 2.0, p.k - dk / 2.0),
                    (p.b + db / 2.0, p.k + dk / 2.0),
                ],
                if p.chatter {
                    RGBColor(150, 90, 200).filled()
                } else {
                    class_color(p.class).filled()
                },
            )
        }))?;
        let line: Vec<(f64, f64)> = m.boundary.iter().map(|p| (p.b, p.k_max)).collect();
        kb_plot::draw_boundary(&mut chart, &line, (y0, y1), None)?;
        // The quiet ceiling 2c/Δ (dashed): above it no count can hold the wall's force KΔ/2, so
        // between it and K_max(B) lies the chatter band.
        let qc = stiffwall_core::rest::quiet_ceiling(m.plant.coulomb, 0.0, m.plant.resolution);
        if qc > y0 && qc < y1 {
            chart.draw_series(DashedLineSeries::new(
                vec![(x0, qc), (x1, qc)],
                8,
                5,
                RGBColor(106, 44, 154).stroke_width(2),
            ))?;
        }
        Ok(())
    }
}

/// Draws the (K, B) map to `path` (.svg or .png).
///
/// # Errors
/// An unsupported extension, or a drawing or file error.
pub fn plot(m: &KbFile, path: &Path) -> Result<(), FigureError> {
    figure::write(path, (720, 600), &KbFigure(m))
}
