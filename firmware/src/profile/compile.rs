//! Compiling a valid wire profile into the servo's table ([`compile`]): each element's gains
//! derived in f64 once, in the main loop, as [`crate::Gains::from_config`] derives the config
//! wall's, with the same helpers (force limit, saturation count, spring bounds, damper band),
//! so that a `Wall`/`Spring` element with the config's K, B and law renders its exact codes.
//!
//! Units: as the profile's on the way in (raw counts, N/m, N·s/m, N); output codes, effective
//! counts and the [`Numeric`] back-end's gain forms on the way out. Invariant: for a profile
//! that passed [`super::validate`] with the same config and board, no value saturates; out of
//! range values saturate (never wrap or panic).

use super::detent::Detent;
use super::element::{Element, Law};
use super::table::ProfileTable;
use crate::config::gains::{damper_band, limit_codes, saturation_count};
use crate::config::limits::MAX_COARSEN_SHIFT;
use crate::config::{BoardInfo, Gains};
use crate::numeric::{Numeric, RangeBound, Shift};
use stiffwall_proto::profile::{Profile, ProfileElement, Side};
use stiffwall_proto::{DamperLaw, ServoConfig};

/// The values every element's gains derive from: the config's and the board's.
#[derive(Debug, Clone, Copy)]
struct Frame {
    /// Δ_eff, m (rad), as the config wall's (`BoardInfo::delta_eff`, f32).
    de: f64,
    /// Δ_eff in raw counts, 2^shift.
    de_counts: f64,
    /// Force per code.
    fs: f64,
    /// Servo rate, Hz.
    rate: f64,
    /// The force limit, codes.
    limit: i32,
    shift: Shift,
}

/// Compiles `p` (validated with `cfg` and `board`: see [`super::validate`]) into the servo's
/// table for back-end `N`.
#[must_use]
pub fn compile<N: Numeric>(p: &Profile, cfg: &ServoConfig, board: &BoardInfo) -> ProfileTable<N> {
    let shift = cfg.coarsen_shift.min(MAX_COARSEN_SHIFT);
    let f = Frame {
        de: f64::from(board.delta_eff(cfg.coarsen_shift)),
        de_counts: f64::from(1u32 << u32::from(shift)),
        fs: f64::from(board.force_per_code),
        rate: f64::from(cfg.servo_rate_hz.max(1)),
        limit: limit_codes(cfg, board),
        shift: Shift::new(u32::from(shift)),
    };
    let mut t = ProfileTable::empty();
    for e in &p.elements {
        // At most as many elements as the profile holds: never full.
        let _ = t.elements.push(element(e, &f));
    }
    t
}

/// One element.
fn element<N: Numeric>(e: &ProfileElement, f: &Frame) -> Element<N> {
    match *e {
        ProfileElement::Wall {
            position,
            side,
            stiffness,
            damping,
            damper,
        } => {
            let active = match side {
                Side::Upper => RangeBound::new(0, i32::MAX),
                Side::Lower => RangeBound::new(i32::MIN, -1),
            };
            spring(position, active, stiffness, damping, damper, f)
        }
        ProfileElement::Spring {
            center,
            stiffness,
            damping,
            damper,
        } => spring(
            center,
            RangeBound::new(i32::MIN, i32::MAX),
            stiffness,
            damping,
            damper,
            f,
        ),
        ProfileElement::Detents {
            first,
            pitch_counts,
            count,
            strength,
            damping,
            damper,
        } => {
            let d = Detent {
                step: phase_step(pitch_counts, f.de_counts),
                strength_q8: strength_q8(strength, f.fs),
            };
            let (lo, hi) = train_counts(d.step, count);
            let mut el = with_damper::<N>(first, RangeBound::new(lo, hi), damping, damper, f);
            el.law = Law::Detents(d);
            el
        }
        ProfileElement::Viscous {
            from,
            to,
            damping,
            damper,
        } => {
            let mut el = with_damper::<N>(
                from,
                RangeBound::new(from, to.saturating_sub(1)),
                damping,
                damper,
                f,
            );
            el.on_raw = true;
            el
        }
    }
}

/// An element with no law of its own yet and its damper B with `law` (g_B = B·Δ_eff·rate/fs,
/// as the config wall's).
fn with_damper<N: Numeric>(
    anchor: i32,
    active: RangeBound,
    b: f32,
    law: DamperLaw,
    f: &Frame,
) -> Element<N> {
    let damp = N::gain(f64::from(b) * f.de * f.rate / f.fs);
    Element {
        anchor,
        shift: f.shift,
        active,
        on_raw: false,
        law: Law::Damper,
        damp: N::damper_gain(damp),
        band: damper_band(damp != N::ZERO, law),
    }
}

/// A wall or spring of eq. (2) around `anchor` acting on `active`: K and B as the config
/// wall's, its count clamp n_sat and the codes beyond it from the same helpers.
fn spring<N: Numeric>(
    anchor: i32,
    active: RangeBound,
    k: f32,
    b: f32,
    law: DamperLaw,
    f: &Frame,
) -> Element<N> {
    let k_half = N::gain(f64::from(k) * f.de / (2.0 * f.fs));
    let damp = N::gain(f64::from(b) * f.de * f.rate / f.fs);
    let n_sat = saturation_count(f.limit, N::to_f64(k_half), N::to_f64(damp));
    let (hi, lo) = Gains::<N>::spring_bounds(k_half, n_sat);
    let mut el = with_damper::<N>(anchor, active, b, law, f);
    el.law = Law::Spring {
        spring: N::spring_gain(k_half),
        n_sat,
        hi,
        lo,
    };
    el
}

/// 2^64·Δ_eff/(2·pitch), rounded: the phase per half effective count in 2^-64 pitch (≤ 2^62
/// for a pitch of at least 2 effective counts; a float-to-int `as` saturates).
fn phase_step(pitch: f64, de_counts: f64) -> u64 {
    libm::round(9_223_372_036_854_775_808.0 * de_counts / pitch) as u64
}

/// A in codes × 2^8, rounded (a float-to-int `as` saturates, NaN → 0).
fn strength_q8(a: f32, fs: f64) -> i64 {
    libm::round(f64::from(a) / fs * 256.0) as i64
}

/// The effective counts of a train of `count` detents with phase step `step`: n with
/// d/pitch = (n + ½)·Δ_eff/pitch = (2n+1)·step/2^64 in [−½, count − ½), i.e.
/// −2^63 ≤ (2n+1)·step < (2·count − 1)·2^63, exactly (in i128, on the step the phase uses):
/// an estimate in f64, then stepped to the exact bound.
fn train_counts(step: u64, count: u16) -> (i32, i32) {
    let step = i128::from(step.max(1));
    let at = |n: i64| i128::from(2 * n + 1) * step;
    let lo_bound = -(1i128 << 63);
    let hi_bound = (2 * i128::from(count) - 1) * (1i128 << 63);
    let per_count = step as f64 / 9_223_372_036_854_775_808.0; // pitches per effective count
    let clamp = |x: f64| libm::floor(x).clamp(-4.0e9, 4.0e9) as i64;
    let mut lo = clamp(-0.5 / per_count - 0.5);
    let mut hi = clamp((f64::from(count) - 0.5) / per_count - 0.5);
    for _ in 0..8 {
        if at(lo) < lo_bound {
            lo += 1;
        } else if at(lo - 1) >= lo_bound {
            lo -= 1;
        }
        if at(hi) >= hi_bound {
            hi -= 1;
        } else if at(hi + 1) < hi_bound {
            hi += 1;
        }
    }
    let to_i32 = |n: i64| n.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
    (to_i32(lo), to_i32(hi))
}
