//! Figures of an atlas: one image per panel (simulated classes with the analytic lines drawn
//! over them) and a summary (agreement fraction against μ, one curve per τ_D and ξ̇₀).
//!
//! Units: dimensionless (β, σ, μ on the axes; fractions in [0, 1]). Invariant: drawn only from a
//! complete, validated map and the atlas computed from it; lines are clipped to the plot.

use crate::describe::{sig, Description};
use crate::figure::{self, DrawResult, Figure, FigureError};
use crate::layout::{self, Glyph};
use crate::map::{class_entries, draw_cells, AXES};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
pub use stiffwall_analysis::atlas::panel_file;
use stiffwall_analysis::atlas::{Atlas, Line, Slice};
use stiffwall_analysis::map_file::{MapFile, Panel};
use stiffwall_core::regions;

/// Size of a panel figure, px.
pub const PANEL_PX: (u32, u32) = (700, 760);
/// Size of the summary figure, px.
pub const SUMMARY_PX: (u32, u32) = (1300, 800);

fn line_color(l: Line) -> RGBColor {
    match l {
        Line::WorstCase => RGBColor(220, 30, 30),
        Line::Df72 => RGBColor(30, 60, 220),
        Line::Df74 => RGBColor(0, 170, 220),
        Line::LinearExact => RGBColor(20, 150, 40),
    }
}

/// Writes every panel image and `atlas-summary.<ext>` into `dir`; returns the paths.
///
/// # Errors
/// A drawing or file error.
pub fn plot_all(
    m: &MapFile,
    a: &Atlas,
    dir: &Path,
    ext: &str,
) -> Result<Vec<PathBuf>, FigureError> {
    let mut out = Vec::new();
    for (p, ap) in m.panels.iter().zip(&a.panels) {
        let path = dir.join(panel_file(p.mu, p.tau_d, p.xidot0, ext));
        let fig = PanelFigure {
            map: m,
            panel: p,
            fractions: Line::ALL.map(|l| ap.fraction(l)),
        };
        figure::write(&path, PANEL_PX, &fig)?;
        out.push(path);
    }
    let path = dir.join(format!("atlas-summary.{ext}"));
    figure::write(&path, SUMMARY_PX, &SummaryFigure { atlas: a })?;
    out.push(path);
    Ok(out)
}

/// One atlas panel: the simulated classes with the analytic lines over them.
#[derive(Debug, Clone, Copy)]
pub struct PanelFigure<'a> {
    /// The map.
    pub map: &'a MapFile,
    /// The panel drawn.
    pub panel: &'a Panel,
    /// The agreement of each line of [`Line::ALL`] with the simulated growth.
    pub fractions: [Option<f64>; 4],
}

impl PanelFigure<'_> {
    fn entries(&self) -> Vec<(Glyph, String)> {
        let mut out = class_entries();
        for (l, fr) in Line::ALL.iter().zip(self.fractions) {
            let agree = fr.map_or_else(|| "n/a".to_owned(), |v| format!("{:.1} %", 100.0 * v));
            out.push((
                Glyph::Line(line_color(*l), 2),
                format!(
                    "{}: agrees with the simulated growth in {agree} of the cells",
                    l.label()
                ),
            ));
        }
        out
    }
}

impl Figure for PanelFigure<'_> {
    fn describe(&self) -> Description {
        let p = self.panel;
        let mut d = Description::new(format!(
            "atlas panel μ = {}, τ_D = {}, dξ/dτ(0) = {}: simulated class ({} periods) and the analytic stability lines",
            sig(p.mu),
            sig(p.tau_d),
            sig(p.xidot0),
            self.map.spec.periods
        ));
        d.axis(AXES[0]).axis(AXES[1]);
        for (_, e) in self.entries() {
            d.legend(e);
        }
        d
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw_panel(root, self)
    }
}

fn step(lo: f64, hi: f64, n: usize) -> f64 {
    if n > 1 {
        (hi - lo) / (n - 1) as f64
    } else {
        0.1
    }
}

fn draw_panel<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, f: &PanelFigure) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let s = &f.map.spec;
    let p = f.panel;
    let slice = Slice {
        mu: p.mu,
        tau_d: p.tau_d,
        xidot0: p.xidot0,
    };
    let db = step(s.beta.lo, s.beta.hi, s.beta.n);
    let ds = step(s.sigma.lo, s.sigma.hi, s.sigma.n);
    let (bx0, bx1) = (s.beta.lo - db / 2.0, s.beta.hi + db / 2.0);
    let (sy0, sy1) = (s.sigma.lo - ds / 2.0, s.sigma.hi + ds / 2.0);
    let d = f.describe();
    let body = layout::titled(root, &d.title)?;
    let keys = layout::keys(&d, f.entries())?;
    let body = layout::legend_above(&body, &keys)?;
    let mut chart = ChartBuilder::on(&body)
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(bx0..bx1, sy0..sy1)?;
    draw_cells(&mut chart, &p.points, db, ds)?;
    let v = p.xidot0.abs();
    let window = regions::Window {
        beta_min: bx0.max(0.0),
        beta_max: bx1,
        sigma_min: sy0.max(0.0),
        sigma_max: sy1,
    };
    let wc = line_color(Line::WorstCase).stroke_width(2);
    for seg in regions::boundaries(p.tau_d, Some(v), Some(v / p.mu.sqrt()), &window)?.as_slice() {
        chart.draw_series(LineSeries::new(vec![seg.from, seg.to], wc))?;
    }
    for l in [Line::Df72, Line::Df74] {
        let mut pts = Vec::new();
        for i in 0..=200 {
            let b = window.beta_min + (window.beta_max - window.beta_min) * f64::from(i) / 200.0;
            if let Some(sig) = slice.df_sigma(l, b)? {
                if (window.sigma_min..=window.sigma_max).contains(&sig) {
                    pts.push((b, sig));
                }
            }
        }
        chart.draw_series(LineSeries::new(pts, line_color(l).stroke_width(2)))?;
    }
    for b in slice.linear_flips(window.beta_min, window.beta_max)? {
        chart.draw_series(LineSeries::new(
            vec![(b, window.sigma_min), (b, window.sigma_max)],
            line_color(Line::LinearExact).stroke_width(2),
        ))?;
    }
    Ok(())
}

/// The atlas summary: agreement of each line against μ, one curve per (τ_D, ξ̇₀).
#[derive(Debug, Clone, Copy)]
pub struct SummaryFigure<'a> {
    /// The atlas.
    pub atlas: &'a Atlas,
}

const SUMMARY_AXES: [&str; 2] = [
    "μ = m/(KT²) (dimensionless inertia), log scale",
    "cells where the line agrees [fraction]",
];

impl SummaryFigure<'_> {
    /// One curve per (τ_D, ξ̇₀), in order of first appearance.
    fn keys(&self) -> Vec<(f64, f64)> {
        let mut keys: Vec<(f64, f64)> = Vec::new();
        for p in &self.atlas.panels {
            let k = (p.tau_d, p.xidot0);
            if !keys
                .iter()
                .any(|q| q.0.to_bits() == k.0.to_bits() && q.1.to_bits() == k.1.to_bits())
            {
                keys.push(k);
            }
        }
        keys
    }

    fn entries(&self) -> Vec<(Glyph, String)> {
        self.keys()
            .iter()
            .enumerate()
            .map(|(i, (tau, xi))| {
                let c = Palette99::pick(i).to_rgba();
                (
                    Glyph::Line(RGBColor(c.0, c.1, c.2), 2),
                    format!("τ_D = {}, dξ/dτ(0) = {}", sig(*tau), sig(*xi)),
                )
            })
            .collect()
    }
}

impl Figure for SummaryFigure<'_> {
    fn describe(&self) -> Description {
        let mut d = Description::new(format!(
            "Atlas summary: agreement of each analytic line with the simulated growth ({} periods), one panel per line, one curve per slice",
            self.atlas.periods
        ));
        d.axis(SUMMARY_AXES[0]).axis(SUMMARY_AXES[1]);
        for (_, e) in self.entries() {
            d.legend(e);
        }
        for l in Line::ALL {
            d.value(format!("panel: {}", l.label()));
        }
        d
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw_summary(root, self)
    }
}

/// A tick label of the log μ axis: only 1, 2 and 5 times a power of ten are written (the
/// others crowd each other out).
fn log_tick(v: &f64) -> String {
    let m = *v / 10f64.powf(v.log10().floor());
    if [1.0, 2.0, 5.0, 10.0].iter().any(|k| (m - k).abs() < 1e-6) {
        sig(*v)
    } else {
        String::new()
    }
}

fn draw_summary<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, f: &SummaryFigure) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let a = f.atlas;
    let d = f.describe();
    let body = layout::titled(root, &d.title)?;
    let (w, _) = body.dim_in_pixel();
    let (body, right) = body.split_horizontally(w.saturating_sub(300));
    let keys = f.keys();
    let mu_lo = a.panels.iter().map(|p| p.mu).fold(f64::INFINITY, f64::min);
    let mu_hi = a.panels.iter().map(|p| p.mu).fold(0.0, f64::max);
    let (mu_lo, mu_hi) = if mu_hi > mu_lo {
        (mu_lo / 1.2, mu_hi * 1.2)
    } else {
        (mu_lo / 2.0, mu_lo * 2.0)
    };
    for (line, area) in Line::ALL.iter().zip(body.split_evenly((2, 2)).iter()) {
        let mut chart = ChartBuilder::on(area)
            .caption(line.label(), ("sans-serif", layout::LEGEND_PX + 1))
            .margin(10)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d((mu_lo..mu_hi).log_scale(), 0.0..1.02)?;
        chart
            .configure_mesh()
            .x_desc(SUMMARY_AXES[0])
            .x_label_formatter(&log_tick)
            .y_desc(SUMMARY_AXES[1])
            .axis_desc_style(("sans-serif", layout::TICK_PX))
            .label_style(("sans-serif", layout::TICK_PX))
            .draw()?;
        for (i, &(tau, xi)) in keys.iter().enumerate() {
            let color = Palette99::pick(i).to_rgba();
            let pts: Vec<(f64, f64)> = a
                .panels
                .iter()
                .filter(|p| {
                    p.tau_d.to_bits() == tau.to_bits() && p.xidot0.to_bits() == xi.to_bits()
                })
                .filter_map(|p| p.fraction(*line).map(|f| (p.mu, f)))
                .collect();
            chart.draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?;
            chart.draw_series(pts.iter().map(|&q| Circle::new(q, 3, color.filled())))?;
        }
    }
    let entries = layout::keys(&d, f.entries())?;
    layout::legend(&right.margin(14, 0, 0, 8), &entries)
}
