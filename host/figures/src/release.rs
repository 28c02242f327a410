//! `hostctl experiment release --plot`: the (β, σ) plane of the device (when a model is known,
//! as [`crate::plane`]) beside the released trajectory x(t), with the ±1 count band dashed, the
//! supervisor's trip marked, and the time axis zoomed to the transient.
//!
//! Units: t in seconds; x in encoder ticks (effective counts); K in N/m (N·m/rad on a rotary
//! device); the plane's axes dimensionless. Invariants: the verdict is the caller's words;
//! nothing is classified here; the time axis ends after the last change of the count (at
//! least 20 ticks, with room after it) and the figure says how much of the record it shows;
//! every text drawn is in the figure's [`Description`].

use crate::describe::{sig, unit_words, Description};
use crate::figure::{DrawResult, Figure};
use crate::layout::{self, Glyph};
use crate::plane::Plane;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Size of the figure in pixels.
pub const SIZE_PX: (u32, u32) = (1900, 820);
/// Width of the plane on the left, px.
const PLANE_W: u32 = 1100;

/// The release figure: the (β, σ) plane (when a model is known) beside x(t).
#[derive(Debug, Clone)]
pub struct Release<'a> {
    /// The released encoder counts, one per servo tick.
    pub counts: &'a [i64],
    /// Servo rate 1/T, Hz.
    pub rate: f64,
    /// The verdict in words (the caption's "release test: …").
    pub verdict: &'a str,
    /// The device named in the title.
    pub name: &'a str,
    /// The test's stiffness K, N/m (N·m/rad).
    pub stiffness: f64,
    /// The test's virtual damping B, N·s/m (N·m·s/rad); 0: the spring alone.
    pub damping: f64,
    /// A rotary device.
    pub rotary: bool,
    /// The index into `counts` where the supervisor tripped, if it did.
    pub trip: Option<usize>,
    /// The (β, σ) plane drawn on the left, if a model is known.
    pub plane: Option<Plane<'a>>,
}

const X_AXIS: &str = "t, time since the release [s]";
const Y_AXIS: &str = "x, encoder count [ticks]";
const TRACE: &str = "x(t), the encoder count after the release";
const BAND: &str = "±1 count: the band of a wall at rest or chattering";
const TRIP: RGBColor = RGBColor(220, 30, 30);

impl Release<'_> {
    /// The number of samples the time axis shows: past the last change of the count.
    fn shown(&self) -> usize {
        let n = self.counts.len();
        let last = self.counts.last().copied();
        let settled = self
            .counts
            .iter()
            .rposition(|c| Some(*c) != last)
            .map_or(0, |i| i + 1);
        let end = self.trip.map_or(settled, |t| settled.max(t + 1));
        (end + end / 2).max(20).min(n.max(1))
    }

    fn entries(&self) -> Vec<(Glyph, String)> {
        let mut out = vec![
            (Glyph::Line(BLUE, 2), TRACE.to_owned()),
            (Glyph::Dashed(BLACK, 1), BAND.to_owned()),
        ];
        if let Some(t) = self.trip {
            out.push((
                Glyph::Dashed(TRIP, 2),
                format!(
                    "supervisor trip at t = {} s (a fault latched)",
                    sig(t as f64 / self.rate)
                ),
            ));
        }
        out
    }

    fn title(&self) -> String {
        let (ku, bu) = unit_words(self.rotary);
        let start = self.counts.first().copied().unwrap_or(0);
        let b = if self.damping > 0.0 {
            format!(", B = {} {bu}", sig(self.damping))
        } else {
            String::new()
        };
        format!(
            "{}: release test at K = {} {ku}{b} from x = {start} ticks: {}",
            self.name,
            sig(self.stiffness),
            self.verdict
        )
    }
}

impl Figure for Release<'_> {
    fn describe(&self) -> Description {
        let mut d = Description::new(self.title());
        let plane = self.plane.as_ref().map(Figure::describe);
        d.axis(X_AXIS).axis(Y_AXIS);
        for (_, e) in self.entries() {
            d.legend(e);
        }
        let shown = self.shown();
        d.value(format!(
            "time axis: the first {} s of {} s recorded ({} of {} samples at {} Hz)",
            sig(shown as f64 / self.rate),
            sig(self.counts.len() as f64 / self.rate),
            shown,
            self.counts.len(),
            sig(self.rate)
        ));
        if let Some(p) = plane {
            d.value(format!("left panel: {}", p.title));
            for a in p.axes {
                d.axis(a);
            }
            for l in p.legend {
                d.legend(l);
            }
        }
        d
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw(root, self)
    }
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, f: &Release) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let d = f.describe();
    let right = match &f.plane {
        Some(p) => {
            let (left, right) = root.split_horizontally(PLANE_W);
            crate::plane::draw(&left, p)?;
            right
        }
        None => root.clone(),
    };
    let body = layout::titled(&right, &d.title)?;
    let keys = layout::keys(&d, f.entries())?;
    let (w, _) = body.dim_in_pixel();
    let texts: Vec<String> = keys.iter().map(|k| k.1.clone()).collect();
    let lh = layout::legend_height(&body, &texts, w - 30);
    let (top, chart_area) = body.split_vertically(lh + 40);
    let (leg, note) = top.split_vertically(lh);
    layout::legend(&leg.margin(0, 0, 20, 10), &keys)?;
    let time_note: Vec<String> = d.values.iter().take(1).cloned().collect();
    layout::notes(&note.margin(4, 0, 20, 0), &time_note)?;
    let shown = f.shown();
    let counts = &f.counts[..shown.min(f.counts.len())];
    let t_end = (shown as f64 / f.rate).max(1e-3);
    let lo = counts.iter().copied().min().unwrap_or(-2).min(-2) as f64 - 0.5;
    let hi = counts.iter().copied().max().unwrap_or(2).max(2) as f64 + 1.5;
    let mut chart = ChartBuilder::on(&chart_area)
        .margin(14)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..t_end, lo..hi)?;
    chart
        .configure_mesh()
        .x_desc(X_AXIS)
        .y_desc(Y_AXIS)
        .axis_desc_style(("sans-serif", layout::AXIS_PX))
        .label_style(("sans-serif", layout::TICK_PX))
        .draw()?;
    let pts = counts
        .iter()
        .enumerate()
        .map(|(i, n)| (i as f64 / f.rate, *n as f64));
    chart.draw_series(LineSeries::new(pts, BLUE.stroke_width(2)))?;
    for level in [-1.0, 1.0] {
        chart.draw_series(DashedLineSeries::new(
            vec![(0.0, level), (t_end, level)],
            6,
            4,
            BLACK.into(),
        ))?;
    }
    if let Some(t) = f.trip {
        let t = t as f64 / f.rate;
        chart.draw_series(DashedLineSeries::new(
            vec![(t, lo), (t, hi)],
            8,
            5,
            TRIP.stroke_width(2),
        ))?;
    }
    Ok(())
}
