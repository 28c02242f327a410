//! Figure of a (K, B) map: B on x, K on y (SI, the units of [`stiffwall_analysis::kb::Units`]),
//! classes as the grey levels of the (β, σ) map, chatter in purple, the quiet ceiling 2c/Δ
//! dashed and core's predicted exact linear boundary K_max(B) in red (drawn only inside the
//! plotted K range; K_max = 0 where no K is stable), with a legend beside the map. Axes and
//! boundary are drawn by [`crate::frontier`], shared with the frontier figures of analyze and
//! tune.
//!
//! Invariants: cells are centred on the grid points, the axes start at the first cell's edge
//! but never below 0 (no negative B or K); drawn only from a computed [`KbFile`]; every text
//! drawn is in the figure's [`Description`].

use crate::describe::{sig, Description};
use crate::figure::{self, DrawResult, Figure, FigureError};
use crate::frontier::{self as kb_plot, PURPLE};
use crate::layout::{self, Glyph};
use crate::map::{class_color, class_entries};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use stiffwall_analysis::kb::KbFile;

/// Size of the figure, px.
pub const SIZE_PX: (u32, u32) = (1120, 680);
/// Width of the legend panel, px.
const LEGEND_W: u32 = 380;
const CHATTER: RGBColor = RGBColor(150, 90, 200);

/// A (K, B) map as a [`Figure`].
#[derive(Debug, Clone, Copy)]
pub struct KbFigure<'a>(pub &'a KbFile);

fn step(lo: f64, hi: f64, n: usize) -> f64 {
    if n > 1 {
        (hi - lo) / (n - 1) as f64
    } else if lo > 0.0 {
        0.1 * lo
    } else {
        1.0
    }
}

/// The plotted ranges: ((B0, B1), (K0, K1)), half a cell beyond the grid, not below 0.
fn ranges(m: &KbFile) -> ((f64, f64), (f64, f64)) {
    let (k, b) = (&m.spec.k, &m.spec.b);
    let (dk, db) = (step(k.lo, k.hi, k.n), step(b.lo, b.hi, b.n));
    (
        ((b.lo - db / 2.0).max(0.0), b.hi + db / 2.0),
        ((k.lo - dk / 2.0).max(0.0), k.hi + dk / 2.0),
    )
}

fn quiet(m: &KbFile) -> f64 {
    stiffwall_core::rest::quiet_ceiling(m.plant.coulomb, 0.0, m.plant.resolution)
}

impl KbFigure<'_> {
    fn entries(&self) -> Vec<(Glyph, String)> {
        let m = self.0;
        let mut out = class_entries();
        out.push((
            Glyph::Swatch(CHATTER),
            "chatter: toggles within one count of the wall for ever".to_owned(),
        ));
        out.push((
            Glyph::Dashed(PURPLE, 2),
            format!(
                "quiet ceiling 2c/Δ = {} {}: above it no count holds the wall's force KΔ/2",
                sig(quiet(m)),
                m.units.k
            ),
        ));
        out.push((
            Glyph::Line(RED, 2),
            "exact linear K_max(B) (core, no friction or quantization); not drawn above the plotted K range"
                .to_owned(),
        ));
        out
    }
}

impl Figure for KbFigure<'_> {
    fn describe(&self) -> Description {
        let m = self.0;
        let mut d =
            Description::new(format!(
            "{}: (K, B) map, the simulated class of each wall (damper law {}), dξ/dτ(0) = {}, {} periods, grid {} × {}",
            m.plant.source,
            m.spec.damper, sig(m.spec.xidot0), m.spec.periods, m.spec.k.n, m.spec.b.n
        ));
        for a in kb_plot::axis_labels(m.units) {
            d.axis(a);
        }
        for (_, e) in self.entries() {
            d.legend(e);
        }
        d
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let m = self.0;
        root.fill(&WHITE)?;
        let d = self.describe();
        let body = layout::titled(root, &d.title)?;
        let (w, _) = body.dim_in_pixel();
        let (left, right) = body.split_horizontally(w.saturating_sub(LEGEND_W));
        let (k, b) = (&m.spec.k, &m.spec.b);
        let (dk, db) = (step(k.lo, k.hi, k.n), step(b.lo, b.hi, b.n));
        let ((x0, x1), (y0, y1)) = ranges(m);
        let mut chart = ChartBuilder::on(&left)
            .margin(14)
            .x_label_area_size(50)
            .y_label_area_size(85)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        kb_plot::axes(&mut chart, m.units)?;
        chart.draw_series(m.points.iter().map(|p| {
            let color = if p.chatter {
                CHATTER
            } else {
                class_color(p.class)
            };
            Rectangle::new(
                [
                    (p.b - db / 2.0, p.k - dk / 2.0),
                    (p.b + db / 2.0, p.k + dk / 2.0),
                ],
                color.filled(),
            )
        }))?;
        let qc = quiet(m);
        if qc > y0 && qc < y1 {
            chart.draw_series(DashedLineSeries::new(
                vec![(x0, qc), (x1, qc)],
                8,
                5,
                PURPLE.stroke_width(2),
            ))?;
        }
        let line: Vec<(f64, f64)> = m.boundary.iter().map(|p| (p.b, p.k_max)).collect();
        kb_plot::draw_boundary(&mut chart, &line, (y0, y1))?;
        let keys = layout::keys(&d, self.entries())?;
        layout::legend(&right.margin(14, 0, 0, 8), &keys)
    }
}

/// Draws the (K, B) map to `path` (.svg or .png).
///
/// # Errors
/// An unsupported extension, or a drawing or file error.
pub fn plot(m: &KbFile, path: &Path) -> Result<(), FigureError> {
    figure::write(path, SIZE_PX, &KbFigure(m))
}
