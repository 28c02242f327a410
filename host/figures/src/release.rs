//! `hostctl experiment release --plot`: the (β, σ) plane of the device (when a model is known,
//! as [`crate::plane`]) beside the released trajectory x(t), with the ±1 tick band dashed.
//!
//! Units: t in seconds; x in encoder ticks; the plane's axes dimensionless. Invariants: the
//! verdict is the caller's words; nothing is classified here.

use crate::figure::{DrawError, DrawResult, Figure};
use plotters::coord::Shift;
use plotters::prelude::*;
use stiffwall_analysis::device_report::Report;

/// Size of the figure in pixels.
pub const SIZE_PX: (u32, u32) = (1500, 600);

/// The release figure: the (β, σ) plane (when a model is known) beside x(t).
#[derive(Debug, Clone, Copy)]
pub struct Release<'a> {
    /// The released encoder counts, one per servo tick.
    pub counts: &'a [i64],
    /// Servo rate 1/T, Hz.
    pub rate: f64,
    /// The verdict in words (the caption's "release test: …").
    pub verdict: &'a str,
    /// The device report whose (β, σ) plane is drawn on the left, if a model is known.
    pub report: Option<&'a Report>,
}

impl Figure for Release<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw(
            root.clone(),
            self.counts,
            self.rate,
            self.verdict,
            self.report,
        )
    }
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    counts: &[i64],
    rate: f64,
    verdict: &str,
    report: Option<&Report>,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| -> DrawError { format!("plot: {e}").into() };
    root.fill(&WHITE).map_err(err)?;
    let (left, right) = root.split_horizontally(600);
    if let Some(r) = report {
        crate::plane::draw(left, r)?;
    }
    let t_end = counts.len() as f64 / rate;
    let lo = counts.iter().copied().min().unwrap_or(-2).min(-2) as f64 - 0.5;
    let hi = counts.iter().copied().max().unwrap_or(2).max(2) as f64 + 1.5;
    let mut chart = ChartBuilder::on(&right)
        .caption(format!("release test: {}", verdict), ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t_end.max(1e-3), lo..hi)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("t [s]")
        .y_desc("x [encoder ticks]")
        .draw()
        .map_err(err)?;
    chart
        .draw_series(LineSeries::new(
            counts
                .iter()
                .enumerate()
                .map(|(i, n)| (i as f64 / rate, *n as f64)),
            BLUE.stroke_width(2),
        ))
        .map_err(err)?
        .label("x(t) (encoder count)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    for level in [-1.0, 1.0] {
        chart
            .draw_series(DashedLineSeries::new(
                vec![(0.0, level), (t_end, level)],
                6,
                4,
                BLACK.into(),
            ))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}
