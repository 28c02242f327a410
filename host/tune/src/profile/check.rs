//! The check of a lowered profile against what a tune verified ([`Envelope`]): per wire
//! element its local stiffness and damping, its limit K_limit(B) (the envelope's), the margin
//! limit/K, pass or fail and, for a failing element, the strongest setting that passes; for a
//! detent train also whether it centres within one count. The profile passes when every
//! element does.
//!
//! Local stiffness: a wall's or spring's K; a detent train's slope at a minimum 2π·A/pitch
//! (its force −A·sin(2π·d/pitch)); a viscous zone's 0. Local damping: the element's B. Where
//! elements overlap (share a count), an element's local K and B are its own plus those of
//! every element overlapping it there: their forces add, so the loop sees the sum. An
//! element's span is cut into pieces where another element starts or ends, each piece is
//! checked with the elements overlapping it, and the worst piece (no verified limit, else the
//! smallest limit/K) is the element's: a spring that is stiff enough only inside a viscous
//! zone fails outside it. The strongest passing setting holds in every piece.
//!
//! Centring: with F_s the static friction, a detent whose force in the count next to the
//! minimum's two counts, A·sin(3π·Δ/pitch) (that count's centre is 1.5 counts from the
//! minimum), is at most F_s can rest there: the weakest strength that centres within one count
//! is F_s/sin(3π·Δ/pitch). A weaker train is reported with how far it may rest, N counts from
//! its minimum (the largest N whose count's centre (N + ½)·Δ feels at most F_s). A pitch of at
//! most 3 counts leaves no count more than one count from a minimum.
//!
//! Units: the device's (N/m, N·s/m, N, m; N·m/rad, N·m·s/rad, N·m, rad).

use super::envelope::{Envelope, Verified};
use super::overlap::{counts, span, Span};
use super::placed::Lowered;
use super::units::{sig, Units};
use core::f64::consts::{PI, TAU};
use serde::Serialize;
use stiffwall_proto::{DamperLaw, ProfileElement, Side};

/// The strongest setting of a failing element that passes (the others as they are).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Strongest {
    /// A wall's, spring's or end stop's K at its B.
    Stiffness(f64),
    /// A detent train's strength A = K·pitch/(2π).
    Strength(f64),
    /// The element's B at most this (the largest B the tune tried, less the overlapping B).
    Damping(f64),
}

/// Whether a detent train centres within one count.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Centring {
    /// The train's strength A, N (N·m).
    pub strength: f64,
    /// F_s/sin(3π·Δ/pitch), N (N·m); None when the pitch is at most 3 counts.
    pub weakest_strength: Option<f64>,
    /// How many counts from its minimum it may rest (1 with a pitch of at most 3 counts);
    /// None: anywhere (A ≤ F_s).
    pub rests_up_to_counts: Option<u64>,
    /// Centres within one count.
    pub pass: bool,
}

/// One wire element's check.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ElementCheck {
    /// Its element's number in the file, from 1.
    pub index: usize,
    /// Its `kind`.
    pub kind: &'static str,
    /// Which wall of an `end-stops` element.
    pub part: Option<&'static str>,
    /// Where it acts, in words with units.
    pub at: String,
    /// The counts it acts on.
    pub span: Span,
    /// The worst piece of the span (the same elements overlap all of a piece): the one the
    /// numbers below are of.
    pub piece: Span,
    /// The numbers of the elements overlapping that piece.
    pub overlaps: Vec<usize>,
    /// Its own K, N/m (N·m/rad).
    pub k_own: f64,
    /// K there, with the overlapping elements'.
    pub k_local: f64,
    /// Its own B, N·s/m (N·m·s/rad).
    pub b_own: f64,
    /// B there, with the overlapping elements'.
    pub b_local: f64,
    /// K*(B) at `b_local` and where it came from.
    pub verified: Verified,
    /// min(margin × K*, quiet ceiling); None: nothing verified at its B.
    pub k_limit: Option<f64>,
    /// Whether the quiet ceiling is the limit (else margin × K*).
    pub at_quiet_ceiling: bool,
    /// k_limit / k_local; None when K is 0 or there is no limit.
    pub margin: Option<f64>,
    /// A detent train's centring.
    pub centring: Option<Centring>,
    /// Passes.
    pub pass: bool,
    /// Why it fails, in words.
    pub problems: Vec<String>,
    /// The strongest setting that passes, for a failing element.
    pub strongest: Option<Strongest>,
}

/// The whole profile's check.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// `[profile] name`.
    pub profile: String,
    /// The units of every number.
    pub units: Units,
    /// What it was checked against.
    pub envelope: Envelope,
    /// Per wire element, in file order.
    pub elements: Vec<ElementCheck>,
    /// Every element passes.
    pub pass: bool,
}

/// Checks `profile` against `envelope` (module header). `profile` is lowered for the
/// envelope's device ([`Envelope::device`]).
#[must_use]
pub fn check(profile: &Lowered, envelope: &Envelope) -> Report {
    let spans: Vec<Span> = profile.elements.iter().map(|p| span(&p.element)).collect();
    let elements: Vec<ElementCheck> = (0..profile.elements.len())
        .map(|i| element(i, profile, &spans, envelope))
        .collect();
    Report {
        profile: profile.name.clone(),
        units: profile.device.units(),
        envelope: envelope.clone(),
        pass: elements.iter().all(|e| e.pass),
        elements,
    }
}

/// An element's own K (N/m, N·m/rad), B and damper law.
fn own(e: &ProfileElement, delta: f64) -> (f64, f64, DamperLaw) {
    match *e {
        ProfileElement::Wall {
            stiffness,
            damping,
            damper,
            ..
        }
        | ProfileElement::Spring {
            stiffness,
            damping,
            damper,
            ..
        } => (f64::from(stiffness), f64::from(damping), damper),
        ProfileElement::Detents {
            pitch_counts,
            strength,
            damping,
            damper,
            ..
        } => (
            TAU * f64::from(strength) / (pitch_counts * delta),
            f64::from(damping),
            damper,
        ),
        ProfileElement::Viscous {
            damping, damper, ..
        } => (0.0, f64::from(damping), damper),
    }
}

/// One piece of an element's span where the same elements overlap it: their K and B with its
/// own, and the limit there.
struct Piece {
    span: Span,
    others: Vec<usize>,
    k: f64,
    b: f64,
    k_others: f64,
    b_others: f64,
    verified: Verified,
    limit: Option<f64>,
}

impl Piece {
    /// Orders pieces worst first: no limit, then the smallest limit/K.
    fn badness(&self) -> (bool, f64) {
        let ratio = match self.limit {
            Some(l) if self.k > 0.0 => l / self.k,
            _ => f64::INFINITY,
        };
        (self.limit.is_some(), ratio)
    }
}

/// Cuts span `i` where another element's span starts or ends.
fn pieces(i: usize, spans: &[Span]) -> Vec<Span> {
    let own = spans[i];
    let inside = |x: i64| own.lo.is_none_or(|lo| x > lo) && own.hi.is_none_or(|hi| x <= hi);
    let mut cuts: Vec<i64> = spans
        .iter()
        .enumerate()
        .filter(|&(j, _)| j != i)
        .flat_map(|(_, s)| [s.lo, s.hi.map(|h| h + 1)])
        .flatten()
        .filter(|&x| inside(x))
        .collect();
    cuts.sort_unstable();
    cuts.dedup();
    let mut out = Vec::with_capacity(cuts.len() + 1);
    let mut lo = own.lo;
    for c in cuts {
        out.push(Span {
            lo,
            hi: Some(c - 1),
        });
        lo = Some(c);
    }
    out.push(Span { lo, hi: own.hi });
    out
}

/// Element `i` in one piece of its span.
fn evaluate(i: usize, piece: Span, profile: &Lowered, spans: &[Span], env: &Envelope) -> Piece {
    let delta = profile.device.resolution;
    let (k_own, b_own, law) = own(&profile.elements[i].element, delta);
    let mut laws = if b_own > 0.0 { vec![law] } else { Vec::new() };
    let (mut k_others, mut b_others, mut others) = (0.0, 0.0, Vec::new());
    for (j, q) in profile.elements.iter().enumerate() {
        if j == i || !spans[j].meets(&piece) {
            continue;
        }
        let (k, b, l) = own(&q.element, delta);
        (k_others, b_others) = (k_others + k, b_others + b);
        if b > 0.0 && !laws.contains(&l) {
            laws.push(l);
        }
        if !others.contains(&q.origin.index) {
            others.push(q.origin.index);
        }
    }
    let (verified, limit) = env.limit(b_own + b_others, &laws);
    Piece {
        span: piece,
        others,
        k: k_own + k_others,
        b: b_own + b_others,
        k_others,
        b_others,
        verified,
        limit,
    }
}

fn element(i: usize, profile: &Lowered, spans: &[Span], env: &Envelope) -> ElementCheck {
    let delta = profile.device.resolution;
    let p = &profile.elements[i];
    let (k_own, b_own, _) = own(&p.element, delta);
    let all: Vec<Piece> = pieces(i, spans)
        .into_iter()
        .map(|piece| evaluate(i, piece, profile, spans, env))
        .collect();
    // `pieces` returns at least the whole span.
    let worst = all
        .iter()
        .reduce(|w, x| if x.badness() < w.badness() { x } else { w })
        .expect("at least one piece");
    let mut c = ElementCheck {
        index: p.origin.index,
        kind: p.origin.kind,
        part: p.origin.part,
        at: where_(&p.element, delta, env.device.units()),
        span: spans[i],
        piece: worst.span,
        overlaps: worst.others.clone(),
        k_own,
        k_local: worst.k,
        b_own,
        b_local: worst.b,
        at_quiet_ceiling: worst.limit.is_some_and(|k| k == env.quiet_ceiling),
        margin: worst.limit.filter(|_| worst.k > 0.0).map(|k| k / worst.k),
        k_limit: worst.limit,
        verified: worst.verified.clone(),
        centring: centring(&p.element, env.static_friction),
        pass: true,
        problems: Vec::new(),
        strongest: None,
    };
    judge(&mut c, &p.element, delta, env.device.units(), &all);
    beyond_force_limit(&mut c, &p.element, env);
    c
}

/// A detent train stronger than the device's force limit (when known): the firmware refuses
/// it, so it fails, and the strongest that passes is at most that limit.
fn beyond_force_limit(c: &mut ElementCheck, e: &ProfileElement, env: &Envelope) {
    let (ProfileElement::Detents { strength, .. }, Some(limit)) = (*e, env.force_limit) else {
        return;
    };
    if f64::from(strength) > limit {
        let u = env.device.units();
        c.problems.push(format!(
            "strength A = {} {} is above the device's force limit {} {} (the device refuses it)",
            sig(f64::from(strength)),
            u.force,
            sig(limit),
            u.force
        ));
        c.strongest = Some(match c.strongest {
            Some(Strongest::Strength(a)) => Strongest::Strength(a.min(limit)),
            _ => Strongest::Strength(limit),
        });
        c.pass = false;
    }
}

/// Fills in pass, problems and the strongest passing setting.
fn judge(c: &mut ElementCheck, e: &ProfileElement, delta: f64, u: Units, all: &[Piece]) {
    match (c.k_limit, &c.verified) {
        (None, Verified::AboveTried { b_max, law }) => {
            c.problems.push(format!(
                "no verified limit at B = {} {}: above the largest B the tune tried with {law} \
                 ({} {})",
                sig(c.b_local),
                u.damping,
                sig(*b_max),
                u.damping
            ));
            // The most the element's own B may be in every piece.
            let room = all
                .iter()
                .map(|p| b_max - p.b_others)
                .fold(f64::INFINITY, f64::min);
            c.strongest = (room > 0.0).then_some(Strongest::Damping(room));
        }
        (None, _) => c.problems.push(format!(
            "no verified limit at B = {} {}: a tried B next to it found no resting K",
            sig(c.b_local),
            u.damping
        )),
        (Some(limit), _) if c.k_local > limit => {
            c.problems.push(format!(
                "K = {} {} is above its limit {} {}",
                sig(c.k_local),
                u.stiffness,
                sig(limit),
                u.stiffness
            ));
            // The most the element's own K may be in every piece (each with its limit).
            let room = all
                .iter()
                .map(|p| p.limit.map_or(f64::NEG_INFINITY, |l| l - p.k_others))
                .fold(f64::INFINITY, f64::min);
            c.strongest = match *e {
                _ if room <= 0.0 => None,
                ProfileElement::Detents { pitch_counts, .. } => {
                    Some(Strongest::Strength(room * pitch_counts * delta / TAU))
                }
                ProfileElement::Viscous { .. } => None,
                _ => Some(Strongest::Stiffness(room)),
            };
        }
        _ => {}
    }
    if let Some(ct) = c.centring.filter(|ct| !ct.pass) {
        c.problems.push(match ct.rests_up_to_counts {
            Some(n) => format!("too weak to centre: rests up to {n} counts from its minimum"),
            None => "too weak to centre: rests anywhere in the train".to_owned(),
        });
    }
    c.pass = c.problems.is_empty();
}

/// A detent train's centring against static friction `fs` (module header).
fn centring(e: &ProfileElement, fs: f64) -> Option<Centring> {
    let ProfileElement::Detents {
        pitch_counts: p,
        strength,
        ..
    } = *e
    else {
        return None;
    };
    let a = f64::from(strength);
    if p <= 3.0 {
        return Some(Centring {
            strength: a,
            weakest_strength: None,
            rests_up_to_counts: Some(1),
            pass: true,
        });
    }
    let s = (3.0 * PI / p).sin();
    let rests_up_to_counts = (a > fs).then(|| {
        // The first count j whose centre (j + ½) feels more than F_s: 2π(j + ½)/p > asin(F_s/A).
        let x = (fs / a).asin() * p / TAU - 0.5;
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let n = x.floor().max(0.0) as u64;
        n
    });
    Some(Centring {
        strength: a,
        weakest_strength: Some(fs / s),
        rests_up_to_counts,
        pass: a * s > fs,
    })
}

/// Where an element acts, in the device's units and counts.
fn where_(e: &ProfileElement, delta: f64, u: Units) -> String {
    let x = |n: i32| format!("{} {}", sig(f64::from(n) * delta), u.position);
    match *e {
        ProfileElement::Wall {
            position,
            side: Side::Upper,
            ..
        } => format!("x ≥ {} (count ≥ {position})", x(position)),
        ProfileElement::Wall { position, .. } => {
            format!("x < {} (count < {position})", x(position))
        }
        ProfileElement::Spring { center, .. } => format!("centre {} (count {center})", x(center)),
        ProfileElement::Detents {
            first,
            pitch_counts,
            count,
            ..
        } => format!(
            "{count} minima from {} every {} {} ({} counts); counts {}",
            x(first),
            sig(pitch_counts * delta),
            u.position,
            sig(pitch_counts),
            counts(span(e))
        ),
        ProfileElement::Viscous { from, to, .. } => format!(
            "{} ≤ x < {} (counts {from}..={})",
            x(from),
            x(to),
            i64::from(to) - 1
        ),
    }
}
