//! Figure of a map: one panel per (μ, τ_D, ξ̇₀), classes as grey levels, optional analytic
//! boundaries; a title and a legend of the grey levels above the panels.
//!
//! Units: dimensionless (β, σ on the axes; μ, τ_D, ξ̇₀ in the panel captions). Invariant: the
//! image is drawn only from a complete, validated [`MapFile`]; cells are centred on the grid
//! points; every text drawn is in the figure's [`Description`].

use crate::describe::{sig, Description};
use crate::figure::{self, DrawResult, Figure, FigureError};
use crate::layout::{self, Glyph};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use stiffwall_analysis::map_file::{MapFile, Panel};
use stiffwall_core::regions;
use stiffwall_sim::classify::Class;

/// The axis labels of a (β, σ) map panel.
pub const AXES: [&str; 2] = ["β = b/(KT) (dimensionless)", "σ = c/(KΔ) (dimensionless)"];

/// The legend of the four classes, in the order dark to white, with their colours.
#[must_use]
pub fn class_entries() -> Vec<(Glyph, String)> {
    [
        (Class::Growing, "growing: the energy grows (unstable)"),
        (
            Class::Persistent,
            "persistent: the oscillation neither grows nor stops",
        ),
        (
            Class::NonMonotoneDecay,
            "decays and stops, energy not monotone at the samples",
        ),
        (
            Class::MonotoneDecay,
            "decays and stops, energy decreasing at every sample",
        ),
    ]
    .into_iter()
    .map(|(c, l)| (Glyph::Swatch(class_color(c)), l.to_owned()))
    .collect()
}

/// The (β, σ) axes of a map panel and its grid points as cells of `db` × `ds`, coloured by
/// class (shared by `map --plot` and the atlas figures).
///
/// # Errors
/// A drawing error.
pub fn draw_cells<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
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
        .x_desc(AXES[0])
        .y_desc(AXES[1])
        .axis_desc_style(("sans-serif", layout::AXIS_PX))
        .label_style(("sans-serif", layout::TICK_PX))
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
#[must_use]
pub fn class_color(c: Class) -> RGBColor {
    match c {
        Class::Growing => RGBColor(40, 40, 40),
        Class::Persistent => RGBColor(120, 120, 120),
        Class::NonMonotoneDecay => RGBColor(200, 200, 200),
        Class::MonotoneDecay => RGBColor(255, 255, 255),
    }
}

/// The map (one panel per ξ̇₀) as a [`Figure`].
#[derive(Debug, Clone, Copy)]
pub struct MapFigure<'a> {
    /// The map.
    pub map: &'a MapFile,
    /// With the analytic boundaries drawn over the cells.
    pub overlay: bool,
}

const OVERLAY_LABEL: &str =
    "analytic boundaries of Fig. 3 (τ_D = 0) or Fig. 5 / (19), velocity bound dξ/dτ(0), d²ξ/dτ² max = dξ/dτ(0)/√μ";

impl MapFigure<'_> {
    fn grid(&self) -> (usize, usize) {
        let n = self.map.panels.len();
        let cols = match n {
            0..=3 => n.max(1),
            4 => 2,
            _ => (n as f64).sqrt().ceil() as usize,
        };
        (cols, n.div_ceil(cols).max(1))
    }

    /// The figure's size: 520 × 460 px per panel and room for the title and legend.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        let (cols, rows) = self.grid();
        let extra = if cols == 1 { 250 } else { 170 };
        (cols as u32 * 520, rows as u32 * 460 + extra)
    }

    fn entries(&self) -> Vec<(Glyph, String)> {
        let mut out = class_entries();
        if self.overlay {
            out.push((Glyph::Line(RED, 2), OVERLAY_LABEL.to_owned()));
        }
        out
    }
}

fn panel_caption(p: &Panel, damping: f64) -> String {
    format!(
        "μ = {}, τ_D = {}, dξ/dτ(0) = dξ/dτ max = {}{}",
        sig(p.mu),
        sig(p.tau_d),
        sig(p.xidot0),
        if damping == 0.0 {
            String::new()
        } else {
            format!(", β_v = {}", sig(damping))
        }
    )
}

impl Figure for MapFigure<'_> {
    fn describe(&self) -> Description {
        let s = &self.map.spec;
        let mut d = Description::new(format!(
            "(β, σ) map: the simulated class of the wall at each grid point, {} panel(s), {} periods from dξ/dτ(0), grid {} × {}",
            self.map.panels.len(),
            s.periods,
            s.beta.n,
            s.sigma.n
        ));
        d.axis(AXES[0]).axis(AXES[1]);
        for (_, e) in self.entries() {
            d.legend(e);
        }
        for p in &self.map.panels {
            d.value(format!("panel: {}", panel_caption(p, s.damping)));
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

/// Draws the map (one panel per ξ̇₀) to `path` (.svg or .png, any case).
///
/// # Errors
/// An unsupported extension, or a drawing or file error.
pub fn plot(m: &MapFile, path: &Path, overlay: bool) -> Result<(), FigureError> {
    let fig = MapFigure { map: m, overlay };
    figure::write(path, fig.size(), &fig)
}

fn step(lo: f64, hi: f64, n: usize) -> f64 {
    if n > 1 {
        (hi - lo) / (n - 1) as f64
    } else {
        0.1
    }
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, f: &MapFigure) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let d = f.describe();
    let body = layout::titled(root, &d.title)?;
    let keys = layout::keys(&d, f.entries())?;
    let panels = layout::legend_above(&body, &keys)?;
    let (cols, rows) = f.grid();
    let s = &f.map.spec;
    let (db, ds) = (
        step(s.beta.lo, s.beta.hi, s.beta.n),
        step(s.sigma.lo, s.sigma.hi, s.sigma.n),
    );
    let (bx0, bx1) = (s.beta.lo - db / 2.0, s.beta.hi + db / 2.0);
    let (sy0, sy1) = (s.sigma.lo - ds / 2.0, s.sigma.hi + ds / 2.0);
    for (panel, area) in f
        .map
        .panels
        .iter()
        .zip(panels.split_evenly((rows, cols)).iter())
    {
        let mut chart = ChartBuilder::on(area)
            .caption(
                panel_caption(panel, s.damping),
                ("sans-serif", layout::LEGEND_PX + 1),
            )
            .margin(10)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(bx0..bx1, sy0..sy1)?;
        draw_cells(&mut chart, &panel.points, db, ds)?;
        if f.overlay {
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
                chart.draw_series(LineSeries::new(vec![seg.from, seg.to], RED.stroke_width(2)))?;
            }
        }
    }
    Ok(())
}

/// `, beta_v = X` for a damped map, nothing for the spring-only wall (the text report's words;
/// the figure writes β_v).
#[must_use]
pub fn damping_label(beta_v: f64) -> String {
    if beta_v == 0.0 {
        String::new()
    } else {
        format!(", beta_v = {beta_v}")
    }
}
