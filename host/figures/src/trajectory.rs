//! `hostctl simulate --plot`: the trajectory of a simulated scene, ξ(τ) in the top panel, the
//! energy bound H_T(τ) (35) in the middle and the energy audit of each period below it: E_d
//! (28), E_g (29) and the residual of the balance (26).
//!
//! Units: τ = t/T in servo periods on every x axis; ξ = x/Δ in encoder ticks (Table I); the
//! energies in units of KΔ² (dimensionless, as the CSV). Invariants: non-finite values are
//! drawn as 0; a flat ξ gets a ±1 range, a zero energy range a tiny one; every text drawn is
//! in the figure's [`Description`].

use crate::describe::{sig, Description};
use crate::figure::{DrawResult, Figure};
use crate::layout::{self, Glyph};
use plotters::coord::Shift;
use plotters::prelude::*;
use stiffwall_sim::scene::Row;

/// Size of the figure in pixels.
pub const SIZE_PX: (u32, u32) = (1000, 900);

/// ξ(τ), H_T(τ) and the energy audit of a scene's rows.
#[derive(Debug, Clone, Copy)]
pub struct Trajectory<'a> {
    /// The rows drawn.
    pub rows: &'a [Row],
    /// The scene (its file name) named in the title.
    pub name: &'a str,
}

const X_AXIS: &str = "τ = t/T (periods)";
const AXES: [&str; 3] = [
    "ξ = x/Δ [encoder ticks]",
    "H_T [KΔ²]",
    "energy per period [KΔ²]",
];
const AUDIT: [(RGBColor, &str); 3] = [
    (
        RGBColor(20, 140, 60),
        "E_d (28): energy dissipated over the period",
    ),
    (
        RGBColor(230, 120, 20),
        "E_g (29): energy generated over the period",
    ),
    (RGBColor(0, 0, 0), "residual of the energy balance (26)"),
];

fn finite(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        0.0
    }
}

fn entries() -> Vec<(Glyph, String)> {
    let mut out = vec![
        (
            Glyph::Line(BLUE, 2),
            "ξ(τ), the position in encoder ticks".to_owned(),
        ),
        (Glyph::Line(RED, 2), "H_T (35): the energy bound".to_owned()),
    ];
    out.extend(
        AUDIT
            .iter()
            .map(|(c, l)| (Glyph::Line(*c, 2), (*l).to_owned())),
    );
    out
}

impl Figure for Trajectory<'_> {
    fn describe(&self) -> Description {
        let mut d = Description::new(format!(
            "{}: simulated wall, ξ(τ), the energy bound H_T and the energy audit of each period",
            self.name
        ));
        d.axis(X_AXIS);
        for a in AXES {
            d.axis(a);
        }
        for (_, e) in entries() {
            d.legend(e);
        }
        if let Some(last) = self.rows.last() {
            d.value(format!("{} periods simulated", last.period));
        }
        let silent = |r: &Row| r.e_d == 0.0 && r.e_g == 0.0 && r.residual == 0.0;
        if !self.rows.is_empty() && self.rows.iter().all(silent) {
            d.value("E_d, E_g and the residual are 0 in every row of this run");
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

/// The range of `vs` (finite values), widened to `pad` when empty or flat.
fn range(vs: impl Iterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vs.map(finite) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        let mid = if lo.is_finite() { lo } else { 0.0 };
        return (mid - pad, mid + pad);
    }
    let m = 0.05 * (hi - lo);
    (lo - m, hi + m)
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, f: &Trajectory) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let d = f.describe();
    let body = layout::titled(root, &d.title)?;
    let keys = layout::keys(&d, entries())?;
    let (w, h) = body.dim_in_pixel();
    let (plots, right) = body.split_horizontally(w.saturating_sub(300));
    let right = right.margin(14, 0, 0, 8);
    layout::legend(&right, &keys)?;
    let lh = layout::legend_height(&right, &d.legend, right.dim_in_pixel().0);
    layout::notes(&right.split_vertically(lh + 10).1, &d.values)?;
    let rows = f.rows;
    let t1 = rows.last().map_or(1.0, |r| r.period as f64).max(1.0);
    let tau = |r: &Row| r.period as f64;
    let (a, rest) = plots.split_vertically(h * 3 / 10);
    let (b, c) = rest.split_vertically(h * 3 / 10);
    let panels = [a, b, c];
    let series: [Vec<Vec<(f64, f64)>>; 3] = [
        vec![rows.iter().map(|r| (tau(r), finite(r.xi))).collect()],
        vec![rows.iter().map(|r| (tau(r), finite(r.h_t))).collect()],
        [|r: &Row| r.e_d, |r: &Row| r.e_g, |r: &Row| r.residual]
            .iter()
            .map(|g| rows.iter().map(|r| (tau(r), finite(g(r)))).collect())
            .collect(),
    ];
    let colors: [Vec<RGBColor>; 3] = [vec![BLUE], vec![RED], AUDIT.iter().map(|a| a.0).collect()];
    for (i, area) in panels.iter().enumerate() {
        let all = series[i].iter().flatten().map(|p| p.1);
        let (lo, hi) = range(all, if i == 0 { 1.0 } else { 1e-12 });
        let mut c = ChartBuilder::on(area)
            .margin(10)
            .x_label_area_size(45)
            .y_label_area_size(85)
            .build_cartesian_2d(0.0..t1, lo..hi)?;
        c.configure_mesh()
            .x_desc(X_AXIS)
            .y_desc(AXES[i])
            .axis_desc_style(("sans-serif", layout::AXIS_PX))
            .label_style(("sans-serif", layout::TICK_PX))
            .y_label_formatter(&|v| sig(*v))
            .draw()?;
        for (pts, color) in series[i].iter().zip(&colors[i]) {
            c.draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))?;
        }
    }
    Ok(())
}
