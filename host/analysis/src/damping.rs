//! The spring + damper part of `hostctl analyze --damping B`: the exact sampled linear
//! boundary K_max(B), its closed forms and the frontier over B (`stiffwall_core::criteria`).
//!
//! Units: B in N·s/m (N·m·s/rad with `--rotational`), K in N/m (N·m/rad). The frontier is
//! [`criteria::FRONTIER_POINTS`] values of B on the linear grid 0 ..= 4·m/T, cut after the first
//! B where K_max(B) is 0 (from there on the damper alone destabilises the loop); the best B
//! ([`search`]) is the grid's best refined by golden section between its neighbours, or the
//! user's B when that is higher, so it is never below any K_max it is compared with.
//!
//! [`figure`] is the frontier figure's data: K_max(B) over the same grid, the best B and the
//! operating point (B given, the device's K).
//!
//! Invariants: B is validated (finite, ≥ 0, named `damping`) before anything is computed.

use crate::frontier::{sig, Frontier, Mark, Units};
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
    /// K_max(B) on the linear grid 0 ..= 4·m/T, up to and including the first B where it is 0.
    pub frontier: Vec<FrontierPoint>,
    /// The first grid B where K_max(B) is 0 (null when it is positive on the whole grid).
    pub k_max_zero_from_b: Option<f64>,
    /// The B that maximises K_max ([`search`]: the grid refined by golden section, or `b_set`).
    pub b_opt: f64,
    /// K_max at `b_opt`.
    pub k_max_opt: f64,
    /// The stiffest wall at `b_opt` that can come to rest: min(`k_max_opt`, `quiet_ceiling`).
    pub k_opt_at_rest: f64,
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

/// The frontier K_max(B) of a device and its best B ([`search`]).
#[derive(Debug, Clone)]
pub struct Searched {
    /// K_max(B) on the grid 0 ..= 4·m/T, up to and including the first B where it is 0.
    pub frontier: Vec<FrontierPoint>,
    /// The first grid B where K_max(B) is 0.
    pub zero_from_b: Option<f64>,
    /// The best B found.
    pub b_opt: f64,
    /// K_max at `b_opt`, at least every K_max of the grid and at `b_user`.
    pub k_max_opt: f64,
}

/// Golden-section steps refining the grid's best B (the bracket shrinks to 0.618^40 ≈ 4e-9 of
/// two grid steps).
const GOLDEN_STEPS: usize = 40;

/// K_max(B) on the grid 0 ..= 4·m/T (cut after its first 0), and the best B: the grid's best
/// refined by golden section between its two neighbours, or `b_user` when K_max is higher
/// there. The best K_max is the largest of every K_max evaluated, so it is never below the
/// grid's or the user's.
///
/// # Errors
/// A parameter out of range, or `b_user` negative, NaN or infinite (named `damping`).
pub fn search(p: &PhysicalParams, b_user: Option<f64>) -> Result<Searched, ParamError> {
    let f = criteria::frontier(p, FRONTIER_B_MAX_M_PER_T * p.mass / p.period_s)?;
    let n = criteria::FRONTIER_POINTS;
    let mut best = (f.b_opt_n_s_per_m, f.k_max_opt);
    let i = f.b_n_s_per_m.iter().position(|&b| b == best.0).unwrap_or(0);
    let (mut lo, mut hi) = (
        f.b_n_s_per_m[i.saturating_sub(1)],
        f.b_n_s_per_m[(i + 1).min(n - 1)],
    );
    let eval = |b: f64, best: &mut (f64, f64)| -> Result<f64, ParamError> {
        let k = criteria::k_max_exact_linear(p, b)?;
        if k > best.1 {
            *best = (b, k);
        }
        Ok(k)
    };
    let r = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (hi - r * (hi - lo), lo + r * (hi - lo));
    let (mut k1, mut k2) = (eval(x1, &mut best)?, eval(x2, &mut best)?);
    for _ in 0..GOLDEN_STEPS {
        if k1 >= k2 {
            (hi, x2, k2) = (x2, x1, k1);
            x1 = hi - r * (hi - lo);
            k1 = eval(x1, &mut best)?;
        } else {
            (lo, x1, k1) = (x1, x2, k2);
            x2 = lo + r * (hi - lo);
            k2 = eval(x2, &mut best)?;
        }
    }
    if let Some(b) = b_user {
        eval(criteria::check_damping(b)?, &mut best)?;
    }
    let zero = f.k_max.iter().position(|&k| k <= 0.0);
    let frontier = f
        .b_n_s_per_m
        .iter()
        .zip(f.k_max.iter())
        .take(zero.map_or(n, |z| z + 1))
        .map(|(&b, &k_max)| FrontierPoint { b, k_max })
        .collect();
    Ok(Searched {
        frontier,
        zero_from_b: zero.map(|z| f.b_n_s_per_m[z]),
        b_opt: best.0,
        k_max_opt: best.1,
    })
}

/// Computes the damper analysis of `p` at virtual damping `b_set`.
///
/// # Errors
/// B negative, NaN or infinite (named `damping`), or a parameter out of range.
pub fn damping_report(p: &PhysicalParams, b_set: f64) -> Result<DampingReport, ParamError> {
    criteria::check_damping(b_set)?;
    let f = search(p, Some(b_set))?;
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
        frontier: f.frontier,
        k_max_zero_from_b: f.zero_from_b,
        b_opt: f.b_opt,
        k_max_opt: f.k_max_opt,
        k_opt_at_rest: f.k_max_opt.min(quiet_ceiling),
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
                "best B = {} {}: K_max = {} {}",
                sig(d.b_opt),
                u.b,
                sig(d.k_max_opt),
                u.k
            ),
        }),
        chosen: Some(Mark {
            b: d.b_set,
            k: p.stiffness,
            label: format!(
                "operating point B = {} {}, K = {} {} ({})",
                sig(d.b_set),
                u.b,
                sig(p.stiffness),
                u.k,
                d.region
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
        "  operating point K = {:.5e} {k_u}, B = {:.5e} {b_u}: {} by the exact linear boundary",
        p.stiffness,
        d.b_set,
        if d.stable { "stable" } else { "UNSTABLE" }
    );
    let _ = writeln!(
        s,
        "  best B (grid refined by golden section, your B included): B = {:.5e} {b_u}, K_max = \
         {:.5e} {k_u}",
        d.b_opt, d.k_max_opt
    );
    if d.k_max_opt > d.quiet_ceiling {
        let _ = writeln!(
            s,
            "  that K_max is {:.3} x the quiet ceiling: not reachable at rest (it would chatter); \
             the stiffest wall at rest there is capped at {:.5e} {k_u}",
            d.k_max_opt / d.quiet_ceiling,
            d.k_opt_at_rest
        );
    }
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
        "  K_max(B), B linear in 0 ..= {FRONTIER_B_MAX_M_PER_T}·m/T:"
    );
    render_frontier(&mut s, &d.frontier, d.k_max_zero_from_b, (b_u, k_u));
    s
}

/// The K_max(B) rows under a header naming the units (B's and K's), up to the first 0, then
/// one line for the rest.
pub(crate) fn render_frontier(
    s: &mut String,
    frontier: &[FrontierPoint],
    zero: Option<f64>,
    (b_unit, k_unit): (&str, &str),
) {
    let (b, k) = (format!("B [{b_unit}]"), format!("K_max [{k_unit}]"));
    let _ = writeln!(s, "  {b:>16} {k:>16}");
    for pt in frontier.iter().filter(|pt| pt.k_max > 0.0) {
        let _ = writeln!(s, "  {:>16.4e} {:>16.4e}", pt.b, pt.k_max);
    }
    if let Some(b) = zero {
        let _ = writeln!(
            s,
            "  K_max(B) = 0 from B = {b:.4e} on: the damper alone destabilises"
        );
    }
}
