//! Figure of a map: one panel per (μ, τ_D, ξ̇₀), classes as grey levels, optional analytic
//! boundaries.
//!
//! Units: dimensionless (β, σ on the axes). Invariant: the image is drawn only from a complete,
//! validated [`MapFile`]; cells are centred on the grid points.

use crate::figure::{self, DrawResult, Figure, FigureError};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use stiffwall_analysis::map_file::MapFile;
use stiffwall_core::regions;
use stiffwall_sim::classify::Class;

/// The (β, σ) axes of a map panel and its grid points as cells of `db` × `ds`, coloured by
/// class (shared by `map --plot` and the atlas figures).
pub fn draw_cells<DB: DrawingBackend>(
    chart: &mut ChartContext<
        '_,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    points: &[stiffwall_sim::map::MapPoint],
    db: f64,
    ds: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("beta")
        .y_desc("sigma")
        .draw()?;
    chart.draw_series(points.iter().map(|p| {
        Rectangle::new(
            [
                (p.beta - db / 2.0, p.sigma - ds / 2.0),
                (p.beta + db / 2.0, p.sigma + ds / 2.0),
            ],
            class_color(p.class).filled(),
        )
    }))?;
    Ok(())
}

/// The grey level (or colour) of a class, shared by the map, atlas and (K, B) map figures.
pub fn class_color(c: Class) -> RGBColor {
    match c {
        Class::Growing => RGBColor(40, 40, 40),
        Class::Persistent => RGBColor(120, 120, 120),
        Class::NonMonotoneDecay => RGBColor(200, 200, 200),
        Class::MonotoneDecay => RGBColor(255, 255, 255),
    }
}

/// The map (one panel per ξ̇₀) as a [`Figure`].
struct MapFigure<'a> {
    map: &'a MapFile,
    cols: usize,
    rows: usize,
    overlay: bool,
}

impl Figure for MapFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw(root, self.map, self.cols, self.rows, self.overlay)
    }
}

/// Draws the map (one panel per ξ̇₀) to `path` (.svg or .png, any case).
///
/// # Errors
/// An unsupported extension, or a drawing or file error.
pub fn plot(m: &MapFile, path: &Path, overlay: bool) -> Result<(), FigureError> {
    let n = m.panels.len();
    let cols = match n {
        0..=3 => n.max(1),
        4 => 2,
        _ => (n as f64).sqrt().ceil() as usize,
    };
    let rows = n.div_ceil(cols);
    let size = (cols as u32 * 480, rows as u32 * 440 + 30);
    let fig = MapFigure {
        map: m,
        cols,
        rows,
        overlay,
    };
    figure::write(path, size, &fig)
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    m: &MapFile,
    cols: usize,
    rows: usize,
    overlay: bool,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let s = &m.spec;
    let (top, body) = root.split_vertically(30);
    top.titled(
        &format!(
            "{} periods; dark: growing, medium: persistent, light: non-monotone decay, white: monotone decay",
            s.periods
        ),
        ("sans-serif", 14),
    )?;
    let areas = body.split_evenly((rows, cols));
    let db = if s.beta.n > 1 {
        (s.beta.hi - s.beta.lo) / (s.beta.n - 1) as f64
    } else {
        0.1
    };
    let ds = if s.sigma.n > 1 {
        (s.sigma.hi - s.sigma.lo) / (s.sigma.n - 1) as f64
    } else {
        0.1
    };
    let (bx0, bx1) = (s.beta.lo - db / 2.0, s.beta.hi + db / 2.0);
    let (sy0, sy1) = (s.sigma.lo - ds / 2.0, s.sigma.hi + ds / 2.0);
    for (panel, area) in m.panels.iter().zip(areas.iter()) {
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!(
                    "mu = {}, tau_D = {}, xidot0 = xidot_max = {}{}",
                    panel.mu,
                    panel.tau_d,
                    panel.xidot0,
                    damping_label(s.damping)
                ),
                ("sans-serif", 16),
            )
            .margin(8)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(bx0..bx1, sy0..sy1)?;
        draw_cells(&mut chart, &panel.points, db, ds)?;
        if overlay {
            // The boundaries of Fig. 3 (tau_D = 0) or Fig. 5 / (19), with the panel's xidot0 as
            // the velocity bound and xiddot_max ~ xidot_max / sqrt(mu) (harmonic motion).
            let red = RED.stroke_width(2);
            let v = panel.xidot0.abs();
            let window = regions::Window {
                beta_min: bx0,
                beta_max: bx1,
                sigma_min: sy0,
                sigma_max: sy1,
            };
            let lines =
                regions::boundaries(panel.tau_d, Some(v), Some(v / panel.mu.sqrt()), &window)?;
            for seg in lines.as_slice() {
                chart.draw_series(LineSeries::new(vec![seg.from, seg.to], red))?;
            }
        }
    }
    Ok(())
}

/// `, beta_v = X` for a damped map, nothing for the spring-only wall.
pub fn damping_label(beta_v: f64) -> String {
    if beta_v == 0.0 {
        String::new()
    } else {
        format!(", beta_v = {beta_v}")
    }
}
