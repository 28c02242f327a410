//! `hostctl replay --plot`: a recording replayed through the plant model, the recorded and the
//! model's encoder count against time above their difference.
//!
//! Units: t in seconds on both x axes; counts and their difference in encoder ticks.
//! Invariants: drawn only from a [`PlantReplay`] the replay engine computed.

use crate::figure::{DrawResult, Figure};
use plotters::coord::Shift;
use plotters::prelude::*;
use stiffwall_analysis::replay::PlantReplay;

/// Size of the figure in pixels.
pub const SIZE_PX: (u32, u32) = (1000, 650);

/// Recorded vs model count above their difference.
#[derive(Debug, Clone, Copy)]
pub struct PlantFigure<'a>(pub &'a PlantReplay);

impl Figure for PlantFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw(root, self.0)
    }
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, p: &PlantReplay) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(430);
    let t1 = p.trace.last().map_or(1.0, |r| r.0).max(1e-6);
    let lo = p.trace.iter().map(|r| r.1.min(r.2)).min().unwrap_or(0) - 1;
    let hi = p.trace.iter().map(|r| r.1.max(r.2)).max().unwrap_or(0) + 1;
    let mut ch = ChartBuilder::on(&top)
        .caption(
            format!(
                "replay through the plant: RMS {:.2} ticks, max {} ticks",
                p.rms_ticks, p.max_ticks
            ),
            ("sans-serif", 18),
        )
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t1, lo as f64..hi as f64)?;
    ch.configure_mesh()
        .x_desc("t [s]")
        .y_desc("count [ticks]")
        .draw()?;
    ch.draw_series(LineSeries::new(
        p.trace.iter().map(|r| (r.0, r.1 as f64)),
        &BLUE,
    ))?
    .label("recorded")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    ch.draw_series(LineSeries::new(
        p.trace.iter().map(|r| (r.0, r.2 as f64)),
        &RED,
    ))?
    .label("model")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    let emax = (p.max_ticks as f64).max(1.0) + 0.5;
    let mut ce = ChartBuilder::on(&bottom)
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t1, -emax..emax)?;
    ce.configure_mesh()
        .x_desc("t [s]")
        .y_desc("model − recorded [ticks]")
        .draw()?;
    ce.draw_series(LineSeries::new(
        p.trace.iter().map(|r| (r.0, (r.2 - r.1) as f64)),
        &BLACK,
    ))?;
    Ok(())
}
