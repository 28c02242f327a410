//! The spring + damper part of `hostctl analyze --damping B`: the exact sampled linear
//! boundary K_max(B), its closed forms and the frontier over B (`stiffwall_core::criteria`).
//!
//! Units: B in N·s/m (N·m·s/rad with `--rotational`), K in N/m (N·m/rad). The frontier is
//! [`criteria::FRONTIER_POINTS`] values of B on the linear grid 0 ..= 4·m/T.
//!
//! [`figure`] is the frontier figure's data: K_max(B) over the same grid, the best B and the
//! operating point (B given, the device's K).
//!
//! Invariants: B is validated (finite, ≥ 0, named `damping`) before anything is computed.

use crate::frontier::{Frontier, Mark, Units};
use serde::Serialize;
use std::fmt::Write as _;
use stiffwall_core::{criteria, ParamError, PhysicalParams};

/// Upper end of the frontier's B grid, in units of m/T.
pub const FRONTIER_B_MAX_M_PER_T: f64 = 4.0;

/// One point of the K_max(B) frontier.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct FrontierPoint {
    /// Virtual damping B [N·s/m or N·m·s/rad].
    pub b: f64,
    /// Exact linear K_max at that B [N/m or N·m/rad] (0: no stable K).
    pub k_max: f64,
}

/// The `damping` key of the `--json` output.
#[derive(Debug, Clone, Serialize)]
pub struct DampingReport {
    /// The device's virtual damping B (from `--damping`).
    pub b_set: f64,
    /// β_v = B/(K·T) at the device's K.
    pub beta_v: f64,
    /// Exact sampled linear K_max at `b_set` ([`criteria::k_max_exact_linear`]).
    pub k_max: f64,
    /// Colgate–Schenkel passivity bound 2(b − B)/T (0 when B ≥ b).
    pub k_max_colgate_schenkel: f64,
    /// Small-B approximation (b + B)/(T/2 + T_D).
    pub k_max_small_b: f64,
    /// Whether the device's (K, B) is stable by the exact linear test.
    pub stable: bool,
    /// K_max(B) on the linear grid 0 ..= 4·m/T.
    pub frontier: Vec<FrontierPoint>,
    /// The grid B that maximises K_max.
    pub b_opt: f64,
    /// K_max at `b_opt`.
    pub k_max_opt: f64,
    /// The quiet ceiling 2c/Δ (`stiffwall_core::rest::quiet_ceiling`, Coulomb friction only:
    /// static friction raises it): above it no count can hold the wall's force KΔ/2.
    pub quiet_ceiling: f64,
    /// Where the operating point (K, B) lies of the three regions of the (K, B) plane:
    /// `quiet` (K ≤ 2c/Δ and K ≤ K_max(B): a wall that can come to rest), `chatter` (2c/Δ < K
    /// ≤ K_max(B): stable but toggling for ever), `growth` (K > K_max(B)).
    pub region: &'static str,
}

/// The region of (K, B) of the three the (K, B) plane has ([`DampingReport::region`]).
#[must_use]
pub fn kb_region(k: f64, k_max: f64, quiet_ceiling: f64) -> &'static str {
    if k > k_max {
        "growth"
    } else if k > quiet_ceiling {
        "chatter"
    } else {
        "quiet"
    }
}

/// Computes the damper analysis of `p` at virtual damping `b_set`.
///
/// # Errors
/// B negative, NaN or infinite (named `damping`), or a parameter out of range.
pub fn damping_report(p: &PhysicalParams, b_set: f64) -> Result<DampingReport, ParamError> {
    criteria::check_damping(b_set)?;
    let f = criteria::frontier(p, FRONTIER_B_MAX_M_PER_T * p.mass / p.period_s)?;
    let k_max = criteria::k_max_exact_linear(p, b_set)?;
    let quiet_ceiling = stiffwall_core::rest::quiet_ceiling(p.coulomb, 0.0, p.resolution);
    Ok(DampingReport {
        quiet_ceiling,
        region: kb_region(p.stiffness, k_max, quiet_ceiling),
        b_set,
        beta_v: criteria::beta_v(b_set, p.stiffness, p.period_s),
        k_max,
        k_max_colgate_schenkel: criteria::k_max_colgate_schenkel_damped(p, b_set)?,
        k_max_small_b: criteria::k_max_small_b(p, b_set)?,
        stable: criteria::exact_linear_stable(p, b_set)?,
        frontier: f
            .b_n_s_per_m
            .iter()
            .zip(f.k_max.iter())
            .map(|(&b, &k_max)| FrontierPoint { b, k_max })
            .collect(),
        b_opt: f.b_opt_n_s_per_m,
        k_max_opt: f.k_max_opt,
    })
}

/// The (B, K) frontier figure of `analyze --damping B --plot`: the K_max(B) table as a curve,
/// the best B and the operating point (B given, the device's K).
#[must_use]
pub fn figure(d: &DampingReport, p: &PhysicalParams, device: Option<&str>) -> Frontier {
    let u = Units::of(p.rotational);
    Frontier {
        title: format!(
            "{}: (K, B) frontier of the spring + damper wall, exact sampled linear K_max(B)",
            device.unwrap_or("plant given by flags")
        ),
        units: u,
        boundary: d.frontier.iter().map(|f| (f.b, f.k_max)).collect(),
        boundary_label: format!(
            "exact linear K_max(B) (Jury), B = 0 … {FRONTIER_B_MAX_M_PER_T}·m/T"
        ),
        verified: Vec::new(),
        spring_only: None,
        best: Some(Mark {
            b: d.b_opt,
            k: d.k_max_opt,
            label: format!(
                "best B = {:.4e} {}: K_max = {:.4e} {}",
                d.b_opt, u.b, d.k_max_opt, u.k
            ),
        }),
        chosen: Some(Mark {
            b: d.b_set,
            k: p.stiffness,
            label: format!(
                "operating point B = {:.4e} {}, K = {:.4e} {} ({})",
                d.b_set, u.b, p.stiffness, u.k, d.region
            ),
        }),
        quiet_ceiling: Some(d.quiet_ceiling),
    }
}

/// The text section printed after the main table.
#[must_use]
pub fn render(d: &DampingReport, p: &PhysicalParams) -> String {
    let (b_u, k_u) = if p.rotational {
        ("N·m·s/rad", "N·m/rad")
    } else {
        ("N·s/m", "N/m")
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\nSpring + damper wall (virtual damping B = {:.5e} {b_u})",
        d.b_set
    );
    let _ = writeln!(s, "  β_v = B/(KT)                 {:>12.5}", d.beta_v);
    let _ = writeln!(s, "  K_max exact linear (Jury)    {:>12.5e} {k_u}", d.k_max);
    let _ = writeln!(
        s,
        "  Colgate–Schenkel 2(b−B)/T    {:>12.5e} {k_u}",
        d.k_max_colgate_schenkel
    );
    let _ = writeln!(
        s,
        "  small-B (b+B)/(T/2+T_D)      {:>12.5e} {k_u}",
        d.k_max_small_b
    );
    let _ = writeln!(
        s,
        "  operating point K = {:.5e}, B = {:.5e}: {} by the exact linear boundary",
        p.stiffness,
        d.b_set,
        if d.stable { "stable" } else { "UNSTABLE" }
    );
    let _ = writeln!(
        s,
        "  best B on the grid: B = {:.5e} {b_u}, K_max = {:.5e} {k_u}",
        d.b_opt, d.k_max_opt
    );
    let _ = writeln!(
        s,
        "  three regions of (K, B): quiet below the quiet ceiling 2c/Δ = {:.5e} {k_u} (a wall \
         can come to rest there; the plain backward-difference damper chatters well below it, a \
         dead band of one count does not, docs/DAMPER-LAWS.md); chatter between it and \
         K_max(B) (stable, but the count toggles for ever); growth above K_max(B)",
        d.quiet_ceiling
    );
    let _ = writeln!(
        s,
        "  operating point: {} ({})",
        d.region,
        match d.region {
            "quiet" => "below both: it can come to rest",
            "chatter" => "above the quiet ceiling: no count can hold the wall's force KΔ/2, it toggles for ever",
            _ => "above the growth boundary",
        }
    );
    let _ = writeln!(
        s,
        "  K_max(B), B linear in 0 ..= {FRONTIER_B_MAX_M_PER_T}·m/T:\n  {:>12} {:>12}",
        "B", "K_max"
    );
    for pt in &d.frontier {
        let _ = writeln!(s, "  {:>12.4e} {:>12.4e}", pt.b, pt.k_max);
    }
    s
}
