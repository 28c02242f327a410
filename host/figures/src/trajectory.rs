//! `hostctl simulate --plot`: the trajectory of a simulated scene, ξ(τ) in the top panel and
//! the energy bound H_T(τ) below it.
//!
//! Units: τ in servo periods on both x axes; ξ in encoder ticks (dimensionless position of
//! Table I); H_T dimensionless. Invariants: non-finite values are drawn as 0; a flat ξ gets a
//! ±1 range.

use crate::figure::{DrawResult, Figure};
use plotters::coord::Shift;
use plotters::prelude::*;
use stiffwall_sim::scene::Row;

/// Size of the figure in pixels.
pub const SIZE_PX: (u32, u32) = (900, 600);

/// ξ(τ) above H_T(τ) of a scene's rows.
#[derive(Debug, Clone, Copy)]
pub struct Trajectory<'a>(pub &'a [Row]);

impl Figure for Trajectory<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw(root, self.0)
    }
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, rows: &[Row]) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (a, b) = root.split_vertically(300);
    let t1 = rows.last().map_or(1.0, |r| r.period as f64).max(1.0);
    let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for r in rows {
        lo = lo.min(finite(r.xi));
        hi = hi.max(finite(r.xi));
    }
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        lo -= 1.0;
        hi += 1.0;
    }
    let mut c = ChartBuilder::on(&a)
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t1, lo..hi)?;
    c.configure_mesh()
        .x_desc("tau")
        .y_desc("xi [ticks]")
        .draw()?;
    c.draw_series(LineSeries::new(
        rows.iter().map(|r| (r.period as f64, finite(r.xi))),
        &BLUE,
    ))?;
    let hmax = rows
        .iter()
        .map(|r| finite(r.h_t))
        .fold(0.0, f64::max)
        .max(1e-12);
    let mut c = ChartBuilder::on(&b)
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t1, 0.0..hmax * 1.05)?;
    c.configure_mesh().x_desc("tau").y_desc("H_T").draw()?;
    c.draw_series(LineSeries::new(
        rows.iter().map(|r| (r.period as f64, finite(r.h_t))),
        &RED,
    ))?;
    Ok(())
}
