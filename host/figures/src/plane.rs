//! `--plot`: the (β, σ) plane of Fig. 3 (τ_D = 0) or Fig. 5 (τ_D > 0) with the device's
//! operating point (the spring alone at its K), the critical line of (12)/(19) for the velocity
//! bound, and the path of the point as K grows (Fig. 4: a ray towards the origin, β and σ both
//! ∝ 1/K). A wall with a virtual damper is drawn as a ring around the spring's point: the
//! regions are those of the spring alone, the damper is no coordinate of this plane.
//!
//! Units: dimensionless axes; K in N/m (N·m/rad on a rotary device), B in N·s/m (N·m·s/rad).
//! Invariants: the region polygons and the critical line come from
//! `stiffwall_core::regions::{region_polygon, boundaries}`, the same thresholds as
//! `classify_delayed` (β* = ½ + τ_D, σ = ½, σ* = ½ + ξ̈(τ_D² + τ_D), critical line
//! σ = σ* + ξ̇(β* − β)); nothing here restates them. Every text drawn is in [`Plane::describe`].

use crate::describe::{sig, unit_words, Description};
use crate::figure::{self, DrawResult, Figure, FigureError};
use crate::layout::{self, Glyph};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use stiffwall_analysis::device_report::Report;
use stiffwall_core::regions::{self, Boundary, Region, Window};

/// Figure size in pixels.
pub const SIZE_PX: (u32, u32) = (1150, 760);
/// Width of the legend panel, px.
const LEGEND_W: u32 = 400;

/// A virtual damper added to the wall: drawn apart from the spring's point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Damper {
    /// B, N·s/m (N·m·s/rad).
    pub b: f64,
    /// β_v = B/(KT), dimensionless.
    pub beta_v: f64,
    /// The exact linear K_max(B) with the damper, N/m (N·m/rad), if known.
    pub k_max: Option<f64>,
}

/// The plane of one report as a [`Figure`].
#[derive(Debug, Clone)]
pub struct Plane<'a> {
    /// The analysis drawn.
    pub report: &'a Report,
    /// The device or plant named in the title.
    pub name: String,
    /// Where the velocity bound of the critical line comes from (a flag such as
    /// `--velocity`, or words).
    pub velocity_source: String,
    /// The wall's virtual damper, if it has one.
    pub damper: Option<Damper>,
}

impl<'a> Plane<'a> {
    /// The plane of `analyze`: the report's device (else "the plant given by flags"), the
    /// velocity of `--velocity`, the damper of `--damping`.
    #[must_use]
    pub fn new(r: &'a Report) -> Self {
        Self {
            report: r,
            name: r
                .device
                .clone()
                .unwrap_or_else(|| "plant given by flags".to_owned()),
            velocity_source: "--velocity".to_owned(),
            damper: r
                .damping
                .as_ref()
                .filter(|d| d.b_set > 0.0)
                .map(|d| Damper {
                    b: d.b_set,
                    beta_v: d.beta_v,
                    k_max: Some(d.k_max),
                }),
        }
    }
}

impl Figure for Plane<'_> {
    fn describe(&self) -> Description {
        describe(self)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw(root, self)
    }
}

/// Writes the plane of `analyze` ([`Plane::new`]) to `path` (`.svg` or `.png`, any case).
///
/// # Errors
/// Unsupported extension, or a drawing/IO error.
pub fn write(path: &Path, r: &Report) -> Result<(), FigureError> {
    figure::write(path, SIZE_PX, &Plane::new(r))
}

/// The plane's chart: β on x, σ on y, over `f64` ranges.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The plotted window: β in 0..bmax, σ in 0..smax.
fn window(r: &Report) -> Window {
    let b_star = regions::beta_star(r.tau_d);
    let s_star = regions::sigma_star(r.tau_d, r.xiddot).unwrap_or(0.5);
    Window {
        beta_min: 0.0,
        beta_max: (1.5 * b_star).max(1.2 * r.beta).max(1.0),
        sigma_min: 0.0,
        sigma_max: (1.25 * r.sigma).max(s_star + 0.6).max(2.0),
    }
}

const REGIONS: [(Region, RGBColor, &str); 7] = [
    (Region::C, RGBColor(235, 120, 120), "C: unstable"),
    (
        Region::B,
        RGBColor(140, 170, 235),
        "B: limit cycle below one tick",
    ),
    (
        Region::F2,
        RGBColor(170, 220, 210),
        "F2: stable, brief energy generation",
    ),
    (
        Region::A,
        RGBColor(120, 200, 120),
        "A: passive, globally stable",
    ),
    (
        Region::F1,
        RGBColor(120, 200, 120),
        "F1: stable, energy decreasing",
    ),
    (Region::D, RGBColor(245, 190, 120), "D: locally unstable"),
    (Region::E, RGBColor(200, 235, 150), "E: locally stable"),
];
const PATH: RGBColor = RGBColor(90, 40, 160);
const DAMPED: RGBColor = RGBColor(0, 120, 200);

/// The slope of the critical line (the velocity bound, else the velocity limit (15)) and
/// where it comes from.
fn critical_slope(p: &Plane) -> (Option<f64>, String) {
    match (p.report.xidot, p.report.xidot_max) {
        (Some(x), _) => (Some(x), format!("from {}", p.velocity_source)),
        (None, Some(x)) if x > 0.0 => (Some(x), "at the velocity limit (15)".to_owned()),
        _ => (None, String::new()),
    }
}

/// The stiffness limits on the path that fall inside the window: (K_max, short tag, name).
fn limits(r: &Report, w: &Window) -> Vec<(f64, &'static str, &'static str)> {
    let all = [
        (r.k_max_at_velocity, "(12)", "K_max (12)"),
        (
            r.k_max_delayed.filter(|_| r.tau_d > 0.0),
            "(19)",
            "K_max (19)",
        ),
        (Some(r.k_max_passive), "A", "K_max of region A"),
    ];
    let k0 = r.params.stiffness;
    all.into_iter()
        .filter_map(|(k, tag, name)| {
            let k = k.filter(|k| k.is_finite() && *k > 0.0)?;
            let pt = (r.beta * k0 / k, r.sigma * k0 / k);
            (pt.0 <= w.beta_max && pt.1 <= w.sigma_max).then_some((k, tag, name))
        })
        .collect()
}

/// The multiples of K marked on the path inside the window.
fn multiples(r: &Report, w: &Window) -> Vec<(f64, &'static str)> {
    [(0.5, "K/2"), (2.0, "2K"), (4.0, "4K")]
        .into_iter()
        .filter(|(f, _)| r.beta / f <= w.beta_max && r.sigma / f <= w.sigma_max)
        .collect()
}

fn title(p: &Plane) -> String {
    let r = p.report;
    let (ku, bu) = unit_words(r.params.rotational);
    let fig = if r.tau_d > 0.0 {
        format!("Fig. 5 regions, τ_D = {}", sig(r.tau_d))
    } else {
        "Fig. 3 regions, τ_D = 0".to_owned()
    };
    let k = format!("K = {} {ku}", sig(r.params.stiffness));
    match p.damper {
        None => format!("{}: (β, σ) plane of the spring wall ({fig}); at {k} it lies in region {}", p.name, r.region),
        Some(d) => format!(
            "{}: (β, σ) plane of the spring alone ({fig}); at {k} the spring alone lies in region {}, the wall adds a damper B = {} {bu}",
            p.name, r.region, sig(d.b)
        ),
    }
}

/// The legend entries in drawing order, with their glyphs (regions only where drawn).
fn entries(p: &Plane) -> Vec<(Glyph, String)> {
    let r = p.report;
    let w = window(r);
    let (ku, _) = unit_words(r.params.rotational);
    let (slope, source) = critical_slope(p);
    let mut out = Vec::new();
    for (reg, color, label) in REGIONS {
        let drawn = regions::region_polygon(reg, r.tau_d, slope, r.xiddot, &w)
            .is_ok_and(|poly| poly.vertices().len() >= 3);
        if drawn {
            let label = match p.damper {
                Some(_) => format!("{label} (spring alone)"),
                None => label.to_owned(),
            };
            out.push((Glyph::Swatch(color), label));
        }
    }
    if let Some(x) = slope {
        out.push((
            Glyph::Line(BLACK, 2),
            format!(
                "critical line (12)/(19), velocity bound dξ/dτ max = {} ({source})",
                sig(x)
            ),
        ));
    }
    let marks: Vec<String> = multiples(r, &w)
        .iter()
        .map(|(f, tag)| format!("{tag} = {}", sig(r.params.stiffness * f)))
        .collect();
    let marks = if marks.is_empty() {
        String::new()
    } else {
        format!("; dots at {} {ku}", marks.join(", "))
    };
    out.push((
        Glyph::Line(PATH, 2),
        format!("path of the point as K grows (towards the origin){marks}"),
    ));
    let lims = limits(r, &w);
    if !lims.is_empty() {
        let l: Vec<String> = lims
            .iter()
            .map(|(k, _, name)| format!("{name} = {} {ku}", sig(*k)))
            .collect();
        out.push((
            Glyph::Cross(BLACK),
            format!("stiffness limits on the path: {}", l.join(", ")),
        ));
    }
    let spring = if p.damper.is_some() {
        "the spring alone"
    } else {
        "operating point"
    };
    out.push((
        Glyph::Dot(BLACK),
        format!(
            "{spring} at K = {} {ku}: β = {}, σ = {}, region {}",
            sig(r.params.stiffness),
            sig(r.beta),
            sig(r.sigma),
            r.region
        ),
    ));
    if let Some(d) = p.damper {
        out.push((Glyph::Ring(DAMPED), damped_label(r, d)));
    }
    out
}

fn damped_label(r: &Report, d: Damper) -> String {
    let (ku, bu) = unit_words(r.params.rotational);
    let limit = d.k_max.map_or(String::new(), |k| {
        format!(
            "; with it the exact linear limit is K_max(B) = {} {ku}",
            sig(k)
        )
    });
    format!(
        "the wall with its damper: this spring plus B = {} {bu} (β_v = B/(KT) = {}); the regions do not include a damper, so the region named is the spring's alone{limit}",
        sig(d.b),
        sig(d.beta_v)
    )
}

fn describe(p: &Plane) -> Description {
    let mut d = Description::new(title(p));
    d.axis("β = b/(KT) (dimensionless viscous friction)")
        .axis("σ = c/(KΔ) (dimensionless Coulomb friction)");
    for (_, e) in entries(p) {
        d.legend(e);
    }
    d
}

/// Draws the whole plane figure (title, chart, legend panel) into `root`, which it fills.
///
/// # Errors
/// A drawing error.
pub fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, p: &Plane) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let d = describe(p);
    let body = layout::titled(root, &d.title)?;
    let (w, _) = body.dim_in_pixel();
    let (left, right) = body.split_horizontally(w.saturating_sub(LEGEND_W));
    let r = p.report;
    let win = window(r);
    let mut chart = ChartBuilder::on(&left)
        .margin(14)
        .x_label_area_size(55)
        .y_label_area_size(70)
        .build_cartesian_2d(0f64..win.beta_max, 0f64..win.sigma_max)?;
    chart
        .configure_mesh()
        .x_desc(&d.axes[0])
        .y_desc(&d.axes[1])
        .axis_desc_style(("sans-serif", layout::AXIS_PX))
        .label_style(("sans-serif", layout::TICK_PX))
        .light_line_style(WHITE.mix(0.0))
        .draw()?;
    draw_regions(&mut chart, p, &win)?;
    draw_path(&mut chart, r, &win)?;
    draw_point(&mut chart, p)?;
    let keys = layout::keys(&d, entries(p))?;
    layout::legend(&right.margin(14, 0, 0, 8), &keys)
}

/// The regions of Fig. 3/5 in `w` and the critical line.
fn draw_regions<DB: DrawingBackend>(chart: &mut Chart<'_, DB>, p: &Plane, w: &Window) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let r = p.report;
    let (slope, _) = critical_slope(p);
    for (reg, color, _) in REGIONS {
        let poly = regions::region_polygon(reg, r.tau_d, slope, r.xiddot, w)?;
        let pts = poly.vertices().to_vec();
        if pts.len() >= 3 {
            chart.draw_series(std::iter::once(Polygon::new(pts, color.mix(0.55).filled())))?;
        }
    }
    let lines = regions::boundaries(r.tau_d, slope, r.xiddot, w)?;
    if let Some(seg) = lines.get(Boundary::Critical) {
        chart.draw_series(LineSeries::new(
            vec![seg.from, seg.to],
            BLACK.stroke_width(2),
        ))?;
    }
    Ok(())
}

/// The path of the operating point as K grows, (β, σ)·K0/K (a ray to the origin), with K/2,
/// 2K, 4K (dots) and the stiffness limits (crosses) marked on it by short tags.
fn draw_path<DB: DrawingBackend>(chart: &mut Chart<'_, DB>, r: &Report, w: &Window) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (b0, s0) = (r.beta, r.sigma);
    let far = if b0 > 0.0 || s0 > 0.0 {
        (w.beta_max / b0.max(1e-300)).min(w.sigma_max / s0.max(1e-300))
    } else {
        1.0
    };
    chart.draw_series(LineSeries::new(
        vec![(0.0, 0.0), (b0 * far, s0 * far)],
        PATH.stroke_width(2),
    ))?;
    let font = ("sans-serif", layout::LEGEND_PX);
    for (f, tag) in multiples(r, w) {
        chart.draw_series(std::iter::once(
            EmptyElement::at((b0 / f, s0 / f))
                + Circle::new((0, 0), 4, PATH.filled())
                + Text::new(tag, (9, -16), font),
        ))?;
    }
    let k0 = r.params.stiffness;
    for (k, tag, _) in limits(r, w) {
        chart.draw_series(std::iter::once(
            EmptyElement::at((b0 * k0 / k, s0 * k0 / k))
                + Cross::new((0, 0), 6, BLACK.stroke_width(2))
                + Text::new(tag, (9, 2), font),
        ))?;
    }
    Ok(())
}

/// The spring's point and, with a damper, the ring of the damped wall around it.
fn draw_point<DB: DrawingBackend>(chart: &mut Chart<'_, DB>, p: &Plane) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let pt = (p.report.beta, p.report.sigma);
    chart.draw_series(std::iter::once(Circle::new(pt, 6, BLACK.filled())))?;
    if p.damper.is_some() {
        chart.draw_series(std::iter::once(Circle::new(pt, 13, DAMPED.stroke_width(3))))?;
    }
    Ok(())
}
