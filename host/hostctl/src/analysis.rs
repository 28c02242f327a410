//! The paper's analysis of one device (Diolaiti et al. 2006, Sec. III, VII), behind `hostctl
//! analyze` and reused by `tune` and `experiment`: computed by
//! [`stiffwall_analysis::device_report`] (re-exported here), rendered here as text, as the
//! (β, σ) figure ([`plot`]) and as the (K, B) frontier figure ([`kb_plot`]).
//!
//! Units: SI as in `stiffwall_analysis::device_report` (kg, N·s/m, N, m, s, N/m, m/s; with
//! `--rotational` kg·m², N·m·s/rad, N·m, rad, N·m/rad, rad/s). Invariants: nothing is computed
//! here beyond formatting.

pub mod damping;
pub use stiffwall_figures::frontier as kb_plot;
pub use stiffwall_figures::plane as plot;

use std::fmt::Write as _;
pub use stiffwall_analysis::device_report::*;
use stiffwall_core::devices;

/// The `--list-devices` text.
#[must_use]
pub fn list_devices() -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<16} {:>10} {:>10} {:>9} {:>11} {:>8} {:>9}  description",
        "name", "m", "b", "c", "Δ", "T [ms]", "K"
    );
    for d in &devices::DEVICES {
        let p = d.params;
        let _ = writeln!(
            s,
            "{:<16} {:>10.4e} {:>10.3e} {:>9.3e} {:>11.4e} {:>8.3} {:>9.4}  {}",
            d.name,
            p.mass,
            p.viscous,
            p.coulomb,
            p.resolution,
            p.period_s * 1e3,
            p.stiffness,
            d.description
        );
    }
    s
}

fn opt(v: Option<f64>, unbounded: &str) -> String {
    v.map_or_else(|| unbounded.to_string(), |v| format!("{v:.4}"))
}

/// The default, human-readable output.
#[must_use]
pub fn render_table(r: &Report) -> String {
    let p = &r.params;
    let (mu_u, b_u, c_u, x_u, k_u, v_u) = if p.rotational {
        ("kg·m²", "N·m·s/rad", "N·m", "rad", "N·m/rad", "rad/s")
    } else {
        ("kg", "N·s/m", "N", "m", "N/m", "m/s")
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Device: {}",
        r.device.as_deref().unwrap_or("(from flags)")
    );
    let _ = writeln!(s, "\nPhysical parameters");
    let _ = writeln!(s, "  mass m           {:>12.5e} {mu_u}", p.mass);
    let _ = writeln!(s, "  viscous b        {:>12.5e} {b_u}", p.viscous);
    let _ = writeln!(s, "  Coulomb c        {:>12.5e} {c_u}", p.coulomb);
    let _ = writeln!(s, "  resolution Δ     {:>12.5e} {x_u}", p.resolution);
    let _ = writeln!(s, "  period T         {:>12.5e} s", p.period_s);
    let _ = writeln!(s, "  stiffness K      {:>12.5e} {k_u}", p.stiffness);
    let _ = writeln!(s, "  delay T_D        {:>12.5e} s", p.delay_s);
    render_dimensionless(&mut s, r, v_u);
    render_limits(&mut s, r, k_u);
    render_describing(&mut s, r);
    if let Some(d) = &r.damping {
        s.push_str(&damping::render(d, p));
    }
    s
}

/// Table I's numbers, the region and the velocity limit (15).
fn render_dimensionless(s: &mut String, r: &Report, v_u: &str) {
    let _ = writeln!(s, "\nDimensionless (Table I)");
    let _ = writeln!(
        s,
        "  μ = m/(KT²)      {:>12.4}{}",
        r.mu,
        if r.mu_sampling_ok {
            ""
        } else {
            "   (warning: μ ≫ 1/π² of (11) not met)"
        }
    );
    let _ = writeln!(s, "  β = b/(KT)       {:>12.5}", r.beta);
    let _ = writeln!(s, "  σ = c/(KΔ)       {:>12.4}", r.sigma);
    let _ = writeln!(s, "  τ_D = T_D/T      {:>12.4}", r.tau_d);
    let _ = writeln!(s, "\nRegion {} — {}", r.region, r.region_meaning);
    let _ = writeln!(s, "  classified at: {}", r.region_assumption);
    let _ = writeln!(
        s,
        "  velocity limit (15): ξ̇_max = {} ticks/period = {} {v_u}",
        opt(r.xidot_max, "unbounded"),
        r.velocity_limit_m_s
            .map_or_else(|| "unbounded".to_string(), |v| format!("{v:.4e}"))
    );
}

/// Every criterion's stiffness limit against the current K.
fn render_limits(s: &mut String, r: &Report, k_u: &str) {
    let p = &r.params;
    let _ = writeln!(
        s,
        "\nStiffness limits [{k_u}]  (current K = {:.5e})",
        p.stiffness
    );
    let _ = writeln!(
        s,
        "  {:<28} {:>12} {:>8}  formula",
        "criterion", "K_max", "K/K_max"
    );
    for (name, c) in &r.criteria {
        let _ = writeln!(
            s,
            "  {:<28} {:>12} {:>8}  {}",
            name,
            c.k_max
                .map_or_else(|| "inf".to_string(), |k| format!("{k:.5e}")),
            c.k_ratio
                .map_or_else(|| "-".to_string(), |x| format!("{x:.3}")),
            c.formula
        );
    }
}

/// The describing-function predictions of Sec. VII.
fn render_describing(s: &mut String, r: &Report) {
    let _ = writeln!(s, "\nDescribing function (Sec. VII)");
    match &r.limit_cycle {
        Some(lc) => {
            let _ = writeln!(
                s,
                "  small limit cycle (68)-(70): amplitude {:.4} ticks, {:.1} Hz{}",
                lc.amplitude_ticks,
                lc.frequency_hz,
                if lc.amplitude_ticks < 1.0 {
                    ""
                } else {
                    "  (M >= 1: outside the small-amplitude approximation)"
                }
            );
        }
        None => {
            let _ = writeln!(
                s,
                "  small limit cycle (68)-(70): none predicted (σ >= 1/2)"
            );
        }
    }
    let _ = writeln!(
        s,
        "  large-amplitude bound (75): stable only if σ >= {:.4} (σ = {:.4})",
        r.sigma_min_large_amplitude, r.sigma
    );
}
