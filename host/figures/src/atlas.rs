//! Figures of an atlas: one image per panel (simulated classes with the analytic lines drawn
//! over them) and a summary (agreement fraction against μ, one curve per τ_D and ξ̇₀).
//!
//! Units: dimensionless (β, σ, μ on the axes; fractions in [0, 1]). Invariant: drawn only from a
//! complete, validated map and the atlas computed from it; lines are clipped to the plot.

use crate::figure::{self, DrawResult, Figure, FigureError};
use crate::map::draw_cells;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
pub use stiffwall_analysis::atlas::panel_file;
use stiffwall_analysis::atlas::{Atlas, Line, Slice};
use stiffwall_analysis::map_file::{MapFile, Panel};
use stiffwall_core::regions;

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
        figure::write(&path, (620, 560), &fig)?;
        out.push(path);
    }
    let path = dir.join(format!("atlas-summary.{ext}"));
    figure::write(&path, (1000, 760), &SummaryFigure { atlas: a })?;
    out.push(path);
    Ok(out)
}

struct PanelFigure<'a> {
    map: &'a MapFile,
    panel: &'a Panel,
    fractions: [Option<f64>; 4],
}

impl Figure for PanelFigure<'_> {
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

/// The title, the agreement of each line (in its colour) and the cell legend of a panel.
fn draw_panel_header<DB: DrawingBackend>(
    top: &DrawingArea<DB, Shift>,
    f: &PanelFigure,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (s, p) = (&f.map.spec, f.panel);
    let legend: Vec<String> = Line::ALL
        .iter()
        .zip(f.fractions)
        .map(|(l, fr)| {
            format!(
                "{}: {}",
                l.label(),
                fr.map_or_else(|| "n/a".to_owned(), |v| format!("{:.1} %", 100.0 * v))
            )
        })
        .collect();
    top.draw(&Text::new(
        format!(
            "mu = {:.4}, tau_D = {}, xidot0 = {}, {} periods; agreement with the simulated growth:",
            p.mu, p.tau_d, p.xidot0, s.periods
        ),
        (8, 6),
        ("sans-serif", 14),
    ))?;
    for (i, (l, text)) in Line::ALL.iter().zip(&legend).enumerate() {
        let (x, y) = (8 + (i as i32 % 2) * 300, 28 + (i as i32 / 2) * 20);
        top.draw(&Text::new(
            text.clone(),
            (x, y),
            ("sans-serif", 14).into_font().color(&line_color(*l)),
        ))?;
    }
    top.draw(&Text::new(
        "cells: dark growing, medium persistent, light/white decaying",
        (8, 68),
        ("sans-serif", 12),
    ))?;
    Ok(())
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
    let (top, body) = root.split_vertically(86);
    draw_panel_header(&top, f)?;
    let mut chart = ChartBuilder::on(&body)
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(45)
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

struct SummaryFigure<'a> {
    atlas: &'a Atlas,
}

impl Figure for SummaryFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw_summary(root, self.atlas)
    }
}

fn draw_summary<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, a: &Atlas) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (top, body) = root.split_vertically(30);
    top.titled(
        &format!(
            "Agreement of each analytic line with the simulated growth ({} periods), per slice",
            a.periods
        ),
        ("sans-serif", 16),
    )?;
    // One curve per (tau_D, xidot0), in order of first appearance.
    let mut keys: Vec<(f64, f64)> = Vec::new();
    for p in &a.panels {
        let k = (p.tau_d, p.xidot0);
        if !keys
            .iter()
            .any(|q| q.0.to_bits() == k.0.to_bits() && q.1.to_bits() == k.1.to_bits())
        {
            keys.push(k);
        }
    }
    let mu_lo = a.panels.iter().map(|p| p.mu).fold(f64::INFINITY, f64::min);
    let mu_hi = a.panels.iter().map(|p| p.mu).fold(0.0, f64::max);
    let (mu_lo, mu_hi) = if mu_hi > mu_lo {
        (mu_lo / 1.2, mu_hi * 1.2)
    } else {
        (mu_lo / 2.0, mu_lo * 2.0)
    };
    for (line, area) in Line::ALL.iter().zip(body.split_evenly((2, 2)).iter()) {
        let mut chart = ChartBuilder::on(area)
            .caption(line.label(), ("sans-serif", 15))
            .margin(8)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d((mu_lo..mu_hi).log_scale(), 0.0..1.02)?;
        chart
            .configure_mesh()
            .x_desc("mu")
            .y_desc("fraction correct")
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
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
                .label(format!("tau_D = {tau}, xidot0 = {xi}"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], color.stroke_width(2))
                });
            chart.draw_series(pts.iter().map(|&q| Circle::new(q, 3, color.filled())))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 11))
            .draw()?;
    }
    Ok(())
}
