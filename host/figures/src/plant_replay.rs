//! `hostctl replay --plot`: a recording replayed through the plant model, the recorded and the
//! model's encoder count against time above their difference.
//!
//! Units: t in seconds on both x axes; counts and their difference in encoder ticks.
//! Invariants: drawn only from a [`PlantReplay`] the replay engine computed.

use crate::describe::{sig, Description};
use crate::figure::{DrawResult, Figure};
use crate::layout::{self, Glyph};
use plotters::coord::Shift;
use plotters::prelude::*;
use stiffwall_analysis::replay::PlantReplay;

/// Size of the figure in pixels.
pub const SIZE_PX: (u32, u32) = (1200, 720);

/// Recorded vs model count above their difference.
#[derive(Debug, Clone, Copy)]
pub struct PlantFigure<'a>(pub &'a PlantReplay);

const X_AXIS: &str = "t, time from the first sample [s]";
const AXES: [&str; 2] = ["encoder count [ticks]", "model − recorded [ticks]"];
const ENTRIES: [(RGBColor, &str); 3] = [
    (BLUE, "recorded count (wide, beneath)"),
    (
        RED,
        "count of the plant model replayed from the recorded forces",
    ),
    (BLACK, "model − recorded (lower panel)"),
];

impl Figure for PlantFigure<'_> {
    fn describe(&self) -> Description {
        let p = self.0;
        let mut d = Description::new(format!(
            "{}: a recording replayed through the plant, the recorded and the modelled encoder count",
            p.source
        ));
        d.axis(X_AXIS).axis(AXES[0]).axis(AXES[1]);
        for (_, l) in ENTRIES {
            d.legend(l);
        }
        d.value(format!(
            "model − recorded: RMS {} ticks, max {} ticks over {} samples in {} run(s)",
            sig(p.rms_ticks),
            p.max_ticks,
            p.compared,
            p.runs
        ));
        d
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw(root, self)
    }
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, f: &PlantFigure) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let p = f.0;
    let d = f.describe();
    let body = layout::titled(root, &d.title)?;
    let keys: Vec<(Glyph, String)> = ENTRIES
        .iter()
        .map(|(c, l)| {
            let w = if *c == BLUE { 5 } else { 2 };
            d.entry(l).map(|e| (Glyph::Line(*c, w), e))
        })
        .collect::<DrawResult<_>>()?;
    let (w, h) = body.dim_in_pixel();
    let (plots, right) = body.split_horizontally(w.saturating_sub(320));
    let right = right.margin(14, 0, 0, 8);
    layout::legend(&right, &keys)?;
    let lh = layout::legend_height(&right, &d.legend, right.dim_in_pixel().0);
    layout::notes(&right.split_vertically(lh + 10).1, &d.values)?;
    let (top, bottom) = plots.split_vertically(h * 62 / 100);
    let t1 = p.trace.last().map_or(1.0, |r| r.0).max(1e-6);
    let lo = p.trace.iter().map(|r| r.1.min(r.2)).min().unwrap_or(0) - 1;
    let hi = p.trace.iter().map(|r| r.1.max(r.2)).max().unwrap_or(0) + 1;
    let mut ch = ChartBuilder::on(&top)
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d(0.0..t1, lo as f64..hi as f64)?;
    ch.configure_mesh()
        .x_desc(X_AXIS)
        .y_desc(AXES[0])
        .axis_desc_style(("sans-serif", layout::AXIS_PX))
        .label_style(("sans-serif", layout::TICK_PX))
        .draw()?;
    // The recorded count wide beneath the model's, so that both show where they agree.
    ch.draw_series(LineSeries::new(
        p.trace.iter().map(|r| (r.0, r.1 as f64)),
        BLUE.stroke_width(5),
    ))?;
    ch.draw_series(LineSeries::new(
        p.trace.iter().map(|r| (r.0, r.2 as f64)),
        RED.stroke_width(2),
    ))?;
    let drawn = p.trace.iter().map(|r| (r.2 - r.1).abs()).max().unwrap_or(0);
    let emax = (p.max_ticks.max(drawn) as f64).max(1.0) + 0.5;
    let mut ce = ChartBuilder::on(&bottom)
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d(0.0..t1, -emax..emax)?;
    ce.configure_mesh()
        .x_desc(X_AXIS)
        .y_desc(AXES[1])
        .axis_desc_style(("sans-serif", layout::AXIS_PX))
        .label_style(("sans-serif", layout::TICK_PX))
        .draw()?;
    ce.draw_series(LineSeries::new(
        p.trace.iter().map(|r| (r.0, (r.2 - r.1) as f64)),
        BLACK.stroke_width(2),
    ))?;
    Ok(())
}
