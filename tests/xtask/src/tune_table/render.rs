//! The Markdown table: one line per plant ([`render`]), its cells, and the summary line
//! under it.
use super::row::{describe_trial, Row, Tuned};
use std::fmt::Write as _;
use stiffwall_tests::family::{self, PlantCase, Supervised, SupervisorReport};

fn effects(case: &PlantCase) -> String {
    let m = &case.model;
    let mut e = Vec::new();
    if let Some(s) = m.stiction {
        e.push(format!(
            "stiction {:.2}×",
            s.static_n / m.coulomb_n.max(1e-300)
        ));
    }
    if let Some(c) = m.cogging {
        e.push(format!(
            "cogging {:.0} %",
            100.0 * c.amplitude_n / m.coulomb_n.max(1e-300)
        ));
    }
    if let Some(t) = m.transmission {
        let m1 = m.mass_kg;
        let m2 = t.link_mass_kg + m.hand.map_or(0.0, |h| h.mass_kg);
        let f = (t.stiffness_n_per_m * (1.0 / m1 + 1.0 / m2)).sqrt() / std::f64::consts::TAU;
        e.push(format!("transmission {f:.0} Hz"));
    }
    if let Some(a) = m.amplifier {
        if let Some(f) = a.cutoff_hz {
            e.push(format!("amp {f:.0} Hz"));
        }
        if let Some(d) = a.deadband_n {
            e.push(format!("dead band {d:.3}"));
        }
    }
    if let Some(h) = m.hand {
        e.push(format!("hand {:.2e}", h.mass_kg));
    }
    if case.rig.delay_ticks > 0 {
        e.push(format!("delay {}T", case.rig.delay_ticks));
    }
    if case.rig.one_sided {
        e.push("one-sided".into());
    }
    e.push(format!("T {:.2} ms", case.controller.period_s * 1e3));
    e.join(", ")
}

fn g(v: f64) -> String {
    format!("{v:.4}")
}

/// The supervisor cell of one v_max impact.
fn trip(s: &Supervised) -> String {
    match (s.unsupervised_settles, s.run.trip_tick) {
        (true, None) => "settles".to_string(),
        (true, Some(t)) => format!("settles (trip {t})"),
        (false, Some(t)) if s.run.stopped() => t.to_string(),
        (false, _) if s.left_and_released() => format!(
            "thrown out {:+.1} % faster once, no fault, force 0 after",
            100.0 * (s.left_faster.unwrap_or(1.0) - 1.0)
        ),
        (false, _) if s.safe_by_decay() => "decays under the firmware".to_string(),
        (false, _) => "NOT STOPPED".to_string(),
    }
}

/// The cell of the other unstable trials under the supervisor.
fn others(sup: &SupervisorReport) -> String {
    if sup.other_unstable.is_empty() {
        return "none".to_string();
    }
    let stopped = sup.other_unstable.iter().filter(|s| s.safe()).count();
    let worst = sup
        .other_unstable
        .iter()
        .filter_map(|s| s.run.trip_tick)
        .max()
        .map_or(String::new(), |t| format!(", latest trip {t}"));
    let decays = sup
        .other_unstable
        .iter()
        .filter(|s| s.safe_by_decay())
        .count();
    let decays = if decays > 0 {
        format!(" ({decays} decay under the firmware)")
    } else {
        String::new()
    };
    format!(
        "{stopped} of {} safe{decays}{worst}",
        sup.other_unstable.len()
    )
}

/// The tune's cells: K set, B set, damper law, K*(B set), K/K*(B set), rests at the set
/// point, K/K*(0), seconds, m, b, c, quiet ceiling, mismatch findings.
fn tune_cells(r: &Row, quick: bool) -> [String; 13] {
    match &r.tune {
        Some(Ok(t)) => tuned_cells(r, t),
        other => untuned_cells(r, other.as_ref(), quick),
    }
}

/// The plant's true moving mass and viscous damping (hand included), for the "id / true"
/// cells.
fn true_mass_and_damping(r: &Row) -> (f64, f64) {
    let m = &r.case.model;
    let true_m = family::moving_mass_kg(m);
    let true_b = m.viscous_ns_per_m + m.hand.map_or(0.0, |h| h.damping_ns_per_m);
    (true_m, true_b)
}

/// [`tune_cells`] of a tune that set (K, B).
fn tuned_cells(r: &Row, t: &Tuned) -> [String; 13] {
    let m = &r.case.model;
    let (true_m, true_b) = true_mass_and_damping(r);
    let dash = || "—".to_string();
    let (ks, ratio) = match &r.k_star_set {
        Some(Ok(k)) => (g(k.k_star), format!("{:.3}", t.k_set / k.k_star)),
        Some(Err(e)) => (format!("failed: {}", e.replace('|', "/")), dash()),
        None => (dash(), dash()),
    };
    [
        g(t.k_set),
        format!("{:.4e}", t.b_set),
        if t.b_set > 0.0 {
            t.damper.clone()
        } else {
            "—".to_string()
        },
        ks,
        ratio,
        match &r.at_set {
            Some(a) => format!(
                "{}{}",
                a.cell(),
                if t.rests {
                    ""
                } else {
                    " (tune: no wall rests)"
                }
            ),
            None => dash(),
        },
        format!("{:.3}", t.k_set / r.k_star.k_star),
        format!("{:.1}", t.seconds),
        format!("{:.3e} / {:.3e}", t.mass, true_m),
        format!("{:.2e} / {:.2e}", t.viscous, true_b),
        format!(
            "{:.3e} / {:.3e} ({:.3e})",
            t.coulomb,
            m.coulomb_n,
            m.static_friction_n()
        ),
        format!(
            "{} / {}",
            g(t.quiet_ceiling),
            g(stiffwall_core::rest::quiet_ceiling(
                m.coulomb_n,
                m.static_friction_n(),
                r.case.rig.resolution_m
            ))
        ),
        match &t.mismatch {
            None => "(not reported)".to_string(),
            Some(v) if v.is_empty() => "none".to_string(),
            Some(v) => v.join("; ").replace('|', "/"),
        },
    ]
}

/// [`tune_cells`] without a tune (failed, or `--quick`): only the true plant's values.
fn untuned_cells(r: &Row, other: Option<&Result<Tuned, String>>, quick: bool) -> [String; 13] {
    let m = &r.case.model;
    let (true_m, true_b) = true_mass_and_damping(r);
    let dash = || "—".to_string();
    [
        match other {
            Some(Err(e)) => format!("failed: {}", e.replace('|', "/")),
            _ if quick => "(--quick)".into(),
            _ => dash(),
        },
        dash(),
        dash(),
        dash(),
        dash(),
        dash(),
        dash(),
        dash(),
        format!("— / {true_m:.3e}"),
        format!("— / {true_b:.2e}"),
        format!("— / {:.3e} ({:.3e})", m.coulomb_n, m.static_friction_n()),
        dash(),
        dash(),
    ]
}

pub(super) fn render(rows: &[Row], quick: bool) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| plant | effects | K*(0) | first failure above K*(0) | best K*(B) of the grid (B) | K set | B set | damper | K*(B set) | K/K*(B set) | rests in every run at (K, B) set | K/K*(0) | tune s | m id / true | b id / true | c id / true (static) | quiet ceiling 2·max(c, F_s)/Δ id / true | mismatch findings | v_max impact at 1.5 K*(B set), B set: ticks to trip (+/−) | other unstable trials there | all safe | travel used / travel |"
    );
    let _ = writeln!(
        s,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in rows {
        let sup = &r.supervisor;
        let trips = sup
            .v_max_impacts
            .iter()
            .map(trip)
            .collect::<Vec<_>>()
            .join(" / ");
        let best = r
            .best
            .map_or("—".to_string(), |(b, k)| format!("{} ({b:.3e})", g(k)));
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {best} | {} | {trips} | {} | {} | {} |",
            r.case.name,
            effects(&r.case),
            g(r.k_star.k_star),
            describe_trial(&r.k_star),
            tune_cells(r, quick).join(" | "),
            others(sup),
            if sup.all_safe() { "yes" } else { "NO" },
            travel_cell(r),
        );
    }
    if let Some(summary) = summary(rows) {
        let _ = writeln!(s, "\n{summary}");
    }
    s
}

/// The "travel used / travel" cell: the range the plant's trace covered over the whole tune
/// (identification, tests, the way back), in mm or rad, against the plant's travel (its end
/// stops; "none" for an unbounded plant, tuned with ±[`UNBOUNDED_TRAVEL`] given), and whether
/// an end stop was touched.
pub(super) fn travel_cell(r: &Row) -> String {
    let Some(Ok(t)) = &r.tune else {
        return "—".into();
    };
    let rotary = r.case.model.counts_per_rev.is_some();
    let (scale, unit) = if rotary { (1.0, "rad") } else { (1e3, "mm") };
    let ([lo, hi], contact) = t.travel_used;
    let travel = match (&r.case.model.travel, t.window) {
        (Some(tr), _) => format!(
            "stops {:.4}..{:.4} {unit}",
            tr.min_m * scale,
            tr.max_m * scale
        ),
        (None, Some((a, b, source))) => {
            let why = match source {
                stiffwall_tune::TravelSource::DefaultWindow => "tune's default window",
                _ => "given: the default window lowered v",
            };
            format!("none; {:.4}..{:.4} {unit} ({why})", a * scale, b * scale)
        }
        (None, None) => "none".into(),
    };
    format!(
        "{:.4}..{:.4} {unit} / {travel}{}",
        lo * scale,
        hi * scale,
        if contact { ", END STOP TOUCHED" } else { "" }
    )
}

/// The median of `v` (sorted in place); None when empty.
pub(super) fn median(v: &mut [f64]) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    (n > 0).then(|| {
        if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        }
    })
}

/// The line under the table: median gain k_set / K*(0), smallest K/K*(B set), rest counts.
fn summary(rows: &[Row]) -> Option<String> {
    let mut gains = Vec::new();
    let mut ratios = Vec::new();
    let (mut not_resting, mut unstable, mut speckled, mut worst_small) = (0, 0, 0, 0usize);
    for r in rows {
        if let (Some(Ok(t)), Some(Ok(k))) = (&r.tune, &r.k_star_set) {
            gains.push(t.k_set / r.k_star.k_star);
            ratios.push(t.k_set / k.k_star);
        }
        if let Some(a) = &r.at_set {
            not_resting += usize::from(!a.all_rest());
            unstable += usize::from(!a.unstable.is_empty());
            speckled += usize::from(!a.small_swings.is_empty());
            worst_small = worst_small.max(a.small_swings.len());
        }
    }
    let n = gains.len();
    let median = median(&mut gains)?;
    let min_ratio = ratios.iter().copied().fold(f64::INFINITY, f64::min);
    let max_ratio = ratios.iter().copied().fold(0.0, f64::max);
    Some(format!(
        "Over {n} tuned plants: median K set / K*(0) = {median:.2} (the damper's gain, quietly), \
         K set / K*(B set) from {min_ratio:.3} to {max_ratio:.3}; {not_resting} set walls do not \
         come to rest in every run; {unstable} are unstable (buzz or growth) in some run; \
         {speckled} keep a small swing from some small states (at most {worst_small} of a wall's \
         small states; {:.0} % allowed).",
        100.0 * super::row::SMALL_SWING_SHARE
    ))
}
