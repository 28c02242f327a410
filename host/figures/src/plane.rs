//! `--plot`: the (β, σ) plane of Fig. 3 (τ_D = 0) or Fig. 5 (τ_D > 0) with the device's
//! operating point, the critical line of (12)/(19) for the velocity bound, and the path of the
//! point as K grows (Fig. 4: a ray towards the origin, β and σ both ∝ 1/K).
//!
//! Units: dimensionless axes. Invariants: the region polygons and the critical line come from
//! `stiffwall_core::regions::{region_polygon, boundaries}`, the same thresholds as
//! `classify_delayed` (β* = ½ + τ_D, σ = ½, σ* = ½ + ξ̈(τ_D² + τ_D), critical line
//! σ = σ* + ξ̇(β* − β)); nothing here restates them.

use crate::figure::{self, DrawError, DrawResult, Figure, FigureError};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use stiffwall_analysis::device_report::Report;
use stiffwall_core::regions::{self, Boundary, Region, Window};

const W: u32 = 1000;
const H: u32 = 720;

/// Figure size in pixels.
pub const SIZE_PX: (u32, u32) = (W, H);

/// The plane of one report as a [`Figure`].
#[derive(Debug, Clone, Copy)]
pub struct Plane<'a>(pub &'a Report);

impl Figure for Plane<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw(root.clone(), self.0)
    }
}

/// Writes the plot to `path` (`.svg` or `.png`, any case).
///
/// # Errors
/// Unsupported extension, or a drawing/IO error.
pub fn write(path: &Path, r: &Report) -> Result<(), FigureError> {
    figure::write(path, SIZE_PX, &Plane(r))
}

fn e<E: std::fmt::Display>(err: E) -> DrawError {
    format!("plot: {err}").into()
}

/// The plane's chart: β on x, σ on y, over `f64` ranges.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draws the plane into `root` (which it fills), e.g. one panel of a larger figure.
///
/// # Errors
/// A drawing error.
pub fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, r: &Report) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(e)?;
    let tau = r.tau_d;
    let b_star = regions::beta_star(tau);
    let s_star = regions::sigma_star(tau, r.xiddot).unwrap_or(0.5);
    let bmax = (1.5 * b_star).max(1.2 * r.beta).max(1.0);
    let smax = (1.25 * r.sigma).max(s_star + 0.6).max(2.0);
    let title = format!(
        "{}: (β, σ) plane, {} — region {}",
        r.device.as_deref().unwrap_or("device"),
        if tau > 0.0 {
            format!("Fig. 5 regions, τ_D = {tau:.3}")
        } else {
            "Fig. 3 regions".to_string()
        },
        r.region
    );
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 24))
        .margin(18)
        .x_label_area_size(55)
        .y_label_area_size(65)
        .build_cartesian_2d(0f64..bmax, 0f64..smax)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("β = b/(KT)   (dimensionless viscous friction)")
        .y_desc("σ = c/(KΔ)   (dimensionless Coulomb friction)")
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 15))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(e)?;
    let window = Window {
        beta_min: 0.0,
        beta_max: bmax,
        sigma_min: 0.0,
        sigma_max: smax,
    };
    draw_regions(&mut chart, r, &window)?;
    draw_path(&mut chart, r, bmax, smax)?;
    draw_operating_point(&mut chart, r)?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

/// The slope of the critical line: the given velocity bound, else the velocity limit (15)
/// (the line through the operating point), with its legend label.
fn critical_slope(r: &Report) -> (Option<f64>, String) {
    match (r.xidot, r.xidot_max) {
        (Some(x), _) => (
            Some(x),
            format!("critical line, dξ/dτ max = {x:.3} (--velocity)"),
        ),
        (None, Some(x)) if x > 0.0 => (
            Some(x),
            format!("critical line at the velocity limit dξ/dτ max = {x:.3}"),
        ),
        _ => (None, String::new()),
    }
}

/// The regions of Fig. 3/5 in `window` and the critical line.
fn draw_regions<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    r: &Report,
    window: &Window,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let tau = r.tau_d;
    let (slope, slope_label) = critical_slope(r);
    let c_a = RGBColor(120, 200, 120);
    let regions_drawn = [
        (Region::C, RGBColor(235, 120, 120), "C: unstable"),
        (
            Region::B,
            RGBColor(140, 170, 235),
            "B: limit cycle < 1 tick",
        ),
        (
            Region::F2,
            RGBColor(170, 220, 210),
            "F2: stable, brief energy generation",
        ),
        (Region::A, c_a, "A: passive, globally stable"),
        (Region::F1, c_a, "F1: stable, energy decreasing"),
        (Region::D, RGBColor(245, 190, 120), "D: locally unstable"),
        (Region::E, RGBColor(200, 235, 150), "E: locally stable"),
    ];
    for (reg, color, label) in regions_drawn {
        let poly = regions::region_polygon(reg, tau, slope, r.xiddot, window).map_err(e)?;
        let pts = poly.vertices().to_vec();
        if pts.len() < 3 {
            continue;
        }
        chart
            .draw_series(std::iter::once(Polygon::new(pts, color.mix(0.55).filled())))
            .map_err(e)?
            .label(label)
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 16, y + 6)], color.filled()));
    }
    let lines = regions::boundaries(tau, slope, r.xiddot, window).map_err(e)?;
    if let Some(seg) = lines.get(Boundary::Critical) {
        chart
            .draw_series(LineSeries::new(
                vec![seg.from, seg.to],
                BLACK.stroke_width(2),
            ))
            .map_err(e)?
            .label(slope_label)
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(2)));
    }
    Ok(())
}

/// The path of the operating point as K grows, (β, σ)·K0/K (a ray to the origin), with K/2,
/// 2K, 4K and the stiffness limits marked on it.
fn draw_path<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    r: &Report,
    bmax: f64,
    smax: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (b0, s0) = (r.beta, r.sigma);
    let far = if b0 > 0.0 || s0 > 0.0 {
        (bmax / b0.max(1e-300)).min(smax / s0.max(1e-300))
    } else {
        1.0
    };
    let path_color = RGBColor(90, 40, 160);
    chart
        .draw_series(LineSeries::new(
            vec![(0.0, 0.0), (b0 * far, s0 * far)],
            ShapeStyle::from(&path_color).stroke_width(2),
        ))
        .map_err(e)?
        .label("path as K grows (towards origin)")
        .legend(move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 16, y)], path_color.stroke_width(2))
        });
    let inside = |pt: (f64, f64)| pt.0 <= bmax && pt.1 <= smax;
    for (factor, label) in [(0.5, "K/2"), (2.0, "2K"), (4.0, "4K")] {
        let pt = (b0 / factor, s0 / factor);
        if inside(pt) {
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at(pt)
                        + Circle::new((0, 0), 4, path_color.filled())
                        + Text::new(label, (8, -6), ("sans-serif", 15)),
                ))
                .map_err(e)?;
        }
    }
    // Stiffness limits on the path: the point the device reaches at K = K_max.
    let k0 = r.params.stiffness;
    let limits = [
        (r.k_max_at_velocity, "K_max (12)"),
        (r.k_max_delayed.filter(|_| r.tau_d > 0.0), "K_max (19)"),
        (Some(r.k_max_passive), "K_max region A"),
    ];
    for (km, label) in limits {
        let Some(km) = km.filter(|k| k.is_finite() && *k > 0.0) else {
            continue;
        };
        let pt = (b0 * k0 / km, s0 * k0 / km);
        if inside(pt) {
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at(pt)
                        + Cross::new((0, 0), 6, BLACK.stroke_width(2))
                        + Text::new(format!("{label} = {km:.4e}"), (10, 4), ("sans-serif", 15)),
                ))
                .map_err(e)?;
        }
    }
    Ok(())
}

/// The operating point, labelled with K, β and σ.
fn draw_operating_point<DB: DrawingBackend>(chart: &mut Chart<'_, DB>, r: &Report) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (b0, s0) = (r.beta, r.sigma);
    chart
        .draw_series(std::iter::once(
            EmptyElement::at((b0, s0))
                + Circle::new((0, 0), 7, BLACK.filled())
                + Text::new(
                    format!("K = {:.4e}", r.params.stiffness),
                    (10, -14),
                    ("sans-serif", 16),
                ),
        ))
        .map_err(e)?
        .label(format!("operating point (β = {b0:.4}, σ = {s0:.3})"))
        .legend(|(x, y)| Circle::new((x + 8, y), 5, BLACK.filled()));
    Ok(())
}
