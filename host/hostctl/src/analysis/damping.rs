//! The text of the spring + damper part of `hostctl analyze --damping B`, computed by
//! [`stiffwall_analysis::damping`] (re-exported here).
//!
//! Units: B in N·s/m (N·m·s/rad with `--rotational`), K in N/m (N·m/rad).

use std::fmt::Write as _;
pub use stiffwall_analysis::damping::*;
use stiffwall_core::PhysicalParams;

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
