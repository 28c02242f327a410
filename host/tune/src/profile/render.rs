//! The check's report as text: the envelope it was checked against, one row per wire element
//! (local K and B, the limit, the margin limit/K, the verdict), the problems of a failing one
//! with the strongest setting that passes, each detent train's centring, and the verdict.
//!
//! Units: on every number, the device's (N/m, N·s/m, N, m; N·m/rad, N·m·s/rad, N·m, rad), to
//! about 4 significant digits ([`super::units::sig`]).

use super::check::{ElementCheck, Report, Strongest};
use super::envelope::Verified;
use super::overlap::counts;
use super::units::{sig, Units};
use std::fmt::Write as _;

/// The report as a table (ends with a newline).
#[must_use]
pub fn render(r: &Report) -> String {
    let u = r.units;
    let e = &r.envelope;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "profile {} checked against {} ({}: {}, {}, {}, {})",
        r.profile,
        e.source,
        if e.device.rotational {
            "rotary"
        } else {
            "linear"
        },
        u.position,
        u.stiffness,
        u.damping,
        u.force
    );
    let ceiling = if e.quiet_ceiling > 0.0 {
        format!("quiet ceiling {} {}", sig(e.quiet_ceiling), u.stiffness)
    } else {
        "no quiet ceiling (no friction identified)".to_owned()
    };
    let _ = writeln!(
        s,
        "limit K_limit(B) = min({} × K*(B), {ceiling}); Δ = {} {}, F_s = {} {}",
        sig(e.margin),
        sig(e.device.resolution),
        u.position,
        sig(e.static_friction),
        u.force
    );
    let points: Vec<String> = e
        .frontier
        .iter()
        .map(|p| {
            let k = p.k.map_or("none found".to_owned(), |k| {
                format!("{} {}", sig(k), u.stiffness)
            });
            format!("B = {} {} ({}): {k}", sig(p.b), u.damping, p.damper)
        })
        .collect();
    let _ = writeln!(s, "frontier K*(B) of the tune: {}", points.join("; "));
    let _ = writeln!(
        s,
        "{:<3} {:<24} {:>18} {:>22} {:>30} {:>7}  verdict",
        "#", "element", "local K", "local B", "K limit", "margin"
    );
    for c in &r.elements {
        row(&mut s, c, u);
    }
    let failing: Vec<String> = r.elements.iter().filter(|c| !c.pass).map(name).collect();
    if r.pass {
        let _ = writeln!(s, "verdict: PASS (every element within its limit)");
    } else {
        let _ = writeln!(s, "verdict: FAIL ({})", failing.join(", "));
    }
    s
}

fn name(c: &ElementCheck) -> String {
    match c.part {
        Some(p) => format!("element {} ({}, {p})", c.index, c.kind),
        None => format!("element {} ({})", c.index, c.kind),
    }
}

fn row(s: &mut String, c: &ElementCheck, u: Units) {
    let kind = match c.part {
        Some(p) => format!("{} ({p})", c.kind),
        None => c.kind.to_owned(),
    };
    let limit = match (c.k_limit, &c.verified) {
        (Some(k), _) if c.at_quiet_ceiling => format!("{} {} (ceiling)", sig(k), u.stiffness),
        (Some(k), Verified::Between { .. }) => format!("{} {} (between)", sig(k), u.stiffness),
        (Some(k), _) => format!("{} {}", sig(k), u.stiffness),
        (None, _) => "none verified".to_owned(),
    };
    let margin = c.margin.map_or("—".to_owned(), sig);
    let _ = writeln!(
        s,
        "{:<3} {:<24} {:>18} {:>22} {:>30} {:>7}  {}",
        c.index,
        kind,
        format!("{} {}", sig(c.k_local), u.stiffness),
        format!("{} {}", sig(c.b_local), u.damping),
        limit,
        margin,
        if c.pass { "pass" } else { "FAIL" }
    );
    let _ = writeln!(s, "      at {}", c.at);
    if c.piece != c.span {
        let _ = writeln!(
            s,
            "      the numbers above are of its worst piece, counts {}",
            counts(c.piece)
        );
    }
    if !c.overlaps.is_empty() {
        let list: Vec<String> = c.overlaps.iter().map(ToString::to_string).collect();
        let _ = writeln!(
            s,
            "      overlapped there by element(s) {}: K and B are its own ({} {}, {} {}) plus theirs",
            list.join(", "),
            sig(c.k_own),
            u.stiffness,
            sig(c.b_own),
            u.damping
        );
    }
    if let Some(ct) = c.centring {
        let line = match ct.weakest_strength {
            None => "centres within one count (a pitch of at most 3 counts)".to_owned(),
            Some(w) => format!(
                "centring: A = {} {} {} the weakest that centres within one count, \
                 F_s/sin(3πΔ/pitch) = {} {}",
                sig(ct.strength),
                u.force,
                if ct.pass { ">" } else { "≤" },
                sig(w),
                u.force
            ),
        };
        let _ = writeln!(s, "      {line}");
    }
    for p in &c.problems {
        let _ = writeln!(s, "      FAIL: {p}");
    }
    if let Some(st) = c.strongest {
        let _ = writeln!(
            s,
            "      strongest that passes: {}",
            match st {
                Strongest::Stiffness(k) => format!("stiffness = {} {}", sig(k), u.stiffness),
                Strongest::Strength(a) => format!("strength = {} {}", sig(a), u.force),
                Strongest::Damping(b) => format!("damping ≤ {} {}", sig(b), u.damping),
            }
        );
    }
}

/// A device's active profile (the wire form `GetProfile` answers) as one line per element,
/// positions in raw counts and in the device's units (`device`'s Δ), every number with its
/// unit; "none (the config's wall)" for an empty profile. Ends with a newline.
#[must_use]
pub fn render_wire(p: &stiffwall_proto::Profile, device: &super::units::Device) -> String {
    if p.elements.is_empty() {
        return "profile: none (the config's wall)\n".to_owned();
    }
    let mut s = format!("profile: {} elements\n", p.elements.len());
    for (i, e) in p.elements.iter().enumerate() {
        let _ = writeln!(s, "  {}. {}", i + 1, wire_line(e, device));
    }
    s
}

/// One wire element in words (see [`render_wire`]).
fn wire_line(e: &stiffwall_proto::ProfileElement, device: &super::units::Device) -> String {
    use stiffwall_proto::{ProfileElement as E, Side};
    let u = device.units();
    let at = |c: i32| {
        let x = f64::from(c) * device.resolution;
        format!("count {c} ({} {})", sig(x), u.position)
    };
    let kb = |k: f32, b: f32, law: stiffwall_proto::DamperLaw| {
        let (k, b) = (sig(f64::from(k)), sig(f64::from(b)));
        format!("K = {k} {}, B = {b} {} ({law})", u.stiffness, u.damping)
    };
    match *e {
        E::Wall {
            position,
            side,
            stiffness,
            damping,
            damper,
        } => {
            let side = if side == Side::Upper {
                "upper"
            } else {
                "lower"
            };
            format!(
                "{side} wall at {}: {}",
                at(position),
                kb(stiffness, damping, damper)
            )
        }
        E::Spring {
            center,
            stiffness,
            damping,
            damper,
        } => {
            format!(
                "spring centred at {}: {}",
                at(center),
                kb(stiffness, damping, damper)
            )
        }
        E::Detents {
            first,
            pitch_counts,
            count,
            strength,
            damping,
            damper,
        } => format!(
            "{count} detents from {}, pitch {} counts ({} {}): A = {} {}, B = {} {} ({damper})",
            at(first),
            sig(pitch_counts),
            sig(pitch_counts * device.resolution),
            u.position,
            sig(f64::from(strength)),
            u.force,
            sig(f64::from(damping)),
            u.damping
        ),
        E::Viscous {
            from,
            to,
            damping,
            damper,
        } => format!(
            "viscous zone from {} to {}: B = {} {} ({damper})",
            at(from),
            at(to),
            sig(f64::from(damping)),
            u.damping
        ),
    }
}
