//! Steps 1 and 2 of `tune` (see `procedure`): identify the device with the wall off (the
//! chirp, the breakaway ramps), move it to the middle of its room, and predict its stiffness
//! limits at the maximum velocity.
//!
//! Units: SI (kg, N·s/m, N, m, s; rotary kg·m², N·m·s/rad, N·m, rad); counts where named.

use super::error::{Result, StepError};
use super::excite::{breakaway, device_scale, identify};
use super::model_check::Evidence;
use super::outcome::Predicted;
use super::progress::{Progress, Reporter};
use super::rest::rest_position;
use super::settings::{Settings, DEFAULT_XIDOT};
use super::steps::df_equivalent;
use super::travel::TravelSource;
use super::workspace::{
    enter_workspace, home_of, velocity_within, Place, BREAKAWAY_MARGIN, MOVE_MAX_FORCE_SHARE,
};
use stiffwall_client::Client;
use stiffwall_core::criteria;
use stiffwall_core::params::PhysicalParams;
use stiffwall_proto::ServoConfig;

/// Step 2: predictions for the identified device.
pub fn predict(p: &PhysicalParams, v: f64) -> Result<Predicted> {
    use stiffwall_core::limits;
    let passive = limits::k_max_passive(p)?;
    let guaranteed = if p.delay_s > 0.0 {
        limits::k_max_delayed_harmonic(p, v)?
    } else {
        limits::k_max_at_velocity(p, v)?
    };
    let equivalent = df_equivalent(p, v);
    let expected = criteria::k_max_gil_avello_rubio(&equivalent)?;
    // (74) with ξ̇ = vT/Δ: c/(KΔ) = (π/4)ξ̇(τ_L − b/(KT))  ⇒  K = (c/Δ + (π/4)ξ̇ b/T)/((π/4)ξ̇ τ_L).
    let xidot = v * p.period_s / p.resolution;
    let tau_l = 0.5 + p.delay_s / p.period_s;
    let q = std::f64::consts::FRAC_PI_4 * xidot;
    let expected_paper_74 = (p.coulomb / p.resolution + q * p.viscous / p.period_s) / (q * tau_l);
    Ok(Predicted {
        passive,
        guaranteed,
        expected,
        expected_paper_74,
    })
}

/// What identification (step 1) and prediction (step 2) give the rest of the procedure.
#[derive(Clone)]
pub(crate) struct Identification {
    pub(crate) id: super::ident::Identified,
    /// Chirp amplitude that moved the device, DAC codes.
    pub(crate) amplitude: i32,
    /// The tests' config: the wall off, no damping, the energy monitor on, the wall where
    /// the chirp left the device.
    pub(crate) base: ServoConfig,
    pub(crate) evidence: Evidence,
    /// The identified model (K = 1 until the wall is chosen).
    pub(crate) p: PhysicalParams,
    /// Maximum velocity v, m/s (rad/s).
    pub(crate) v: f64,
    pub(crate) predicted: Predicted,
    /// Force and stiffness units, for findings.
    pub(crate) units: (&'static str, &'static str),
    /// Room each side of the tests' wall, raw counts.
    pub(crate) room: i64,
    /// The push of the moves that walk a drifting device back, N (N·m).
    pub(crate) move_force_n: f64,
    /// The default window (no travel stated), raw counts: the release and impact tests carry
    /// it as the firmware's travel window (a stated travel is in `base` already).
    pub(crate) window: Option<(i32, i32)>,
}

/// Steps 1–2: the wall off, faults cleared, the chirp, the breakaway ramps, the model and its
/// predicted limits at v.
pub(crate) fn identify_and_predict(
    c: &mut Client,
    s: &Settings,
    original: &ServoConfig,
    progress: &Reporter<'_>,
    place: &mut Place,
) -> Result<Identification> {
    let (res, t) = device_scale(c)?;
    // Experiments run with the wall off between them, without extra damping and with the
    // energy monitor on, whatever the user's config; the servo rate, delay and coarsening stay
    // as configured.
    let base = ServoConfig {
        damping: 0.0,
        damper: s.damper.unwrap_or_default(),
        energy_monitor: true,
        stiffness: 0.0,
        ..*original
    };
    // The wall off first: a fault the user's wall keeps raising (an energy limit tripped by a
    // K the device cannot hold) would otherwise latch again as soon as it is cleared.
    c.set_config(&base)?;
    super::rest::clear_faults(c)?;
    let (base, room) = enter_workspace(c, s, original, base, progress, place)?;
    let (id, amplitude) = identify_guarded(c, &base, s, progress, place, room)?;
    c.set_config(&base)?;
    let rest = rest_position(c)?;
    // The chirp leaves the device wherever it stopped: the tests put the wall there (the
    // user's wall position is kept in the config that is finally set).
    let base = ServoConfig {
        wall_position: base.wall_position.saturating_add(rest),
        ..base
    };
    let mut evidence = Evidence {
        residual_rel: id.residual_rel,
        ..Evidence::default()
    };
    breakaway(c, &base, &id, rest, &mut evidence, progress, room)?;
    arm_moves(place, &id, &evidence, original);
    let base = centre_tests(c, &base, rest, place, room)?;
    let delta = res * f64::from(1u32 << base.coarsen_shift);
    let p = model_of(&id, delta, t, &base, c.info.counts_per_rev > 0);
    let ws = place
        .ws
        .ok_or_else(|| StepError::Failed("no workspace".into()))?;
    let room_raw = ws.room_at(i64::from(base.wall_position));
    let (v, predicted) = limits_at(&p, s, room_raw >> base.coarsen_shift.min(16), progress)?;
    progress.report(Progress::Identified {
        mass: id.mass,
        viscous: id.viscous,
        coulomb: id.coulomb,
        k_guaranteed: predicted.guaranteed,
        k_expected: predicted.expected,
    });
    Ok(Identification {
        id,
        amplitude,
        base,
        evidence,
        p,
        v,
        predicted,
        units: if p.rotational {
            ("N·m", "N·m/rad")
        } else {
            ("N", "N/m")
        },
        room: room_raw,
        move_force_n: home_of(place)?.force_n,
        window: default_window(&ws),
    })
}

/// The chirp against the centring spring; where the travel is unknown and that fails, with the
/// wall off and the default window as the firmware's guard (which identifies every plant of
/// the repository); a known travel is never left to that guard. The model and the chirp's
/// amplitude.
fn identify_guarded(
    c: &mut Client,
    base: &ServoConfig,
    s: &Settings,
    progress: &Reporter<'_>,
    place: &Place,
    room: i64,
) -> Result<(super::ident::Identified, i32)> {
    match identify(c, base, s, progress, Some(room)) {
        Ok((id, amplitude, _)) => Ok((id, amplitude)),
        Err(e) if matches!(place.ws, Some(w) if w.source == TravelSource::DefaultWindow) => {
            progress.report(Progress::Travel {
                text: format!(
                    "identification against the centring spring failed ({e}); the chirp runs \
                     with the wall off, the default window as the supervisor's travel limit"
                ),
            });
            let wall = i64::from(base.wall_position);
            super::travel::move_to(c, base, wall, home_of(place)?)?;
            let open = ServoConfig {
                travel_min: None,
                travel_max: None,
                ..*base
            };
            c.set_config(&open)?;
            let (id, amplitude, _) = identify(c, &open, s, progress, None)?;
            super::travel::move_to(c, base, wall, home_of(place)?)?;
            c.set_config(base)?;
            Ok((id, amplitude))
        }
        Err(e) => Err(e),
    }
}

/// The moves from now on know the mass (it bounds the glide's damper) and push harder than the
/// breakaway measured (a push below static friction never moves the device).
fn arm_moves(
    place: &mut Place,
    id: &super::ident::Identified,
    evidence: &Evidence,
    original: &ServoConfig,
) {
    let Some(home) = place.home.as_mut() else {
        return;
    };
    let breakaway = evidence
        .breakaway_measured
        .iter()
        .flatten()
        .fold(0.0f64, |a, f| a.max(f.abs()));
    home.mass = Some(id.mass);
    home.friction = Some(super::approach::MoveFriction {
        coulomb_n: id.coulomb.max(0.0),
        viscous: id.viscous.max(0.0),
    });
    home.force_n = home
        .force_n
        .max(BREAKAWAY_MARGIN * breakaway)
        .min(MOVE_MAX_FORCE_SHARE * f64::from(original.force_limit));
}

/// The tests start from the middle of the room, wherever the excitations left the device (at
/// `rest` counts from the wall of `base`): the tests' config with its wall there, set with the
/// wall off.
fn centre_tests(
    c: &mut Client,
    base: &ServoConfig,
    rest: i32,
    place: &Place,
    room: i64,
) -> Result<ServoConfig> {
    let centre = i64::from(base.wall_position) - (i64::from(rest) << base.coarsen_shift.min(16));
    let at = super::travel::move_into(c, base, centre, home_of(place)?, room)?;
    let base = ServoConfig {
        wall_position: i32::try_from(at).unwrap_or(base.wall_position),
        ..*base
    };
    c.set_config(&ServoConfig {
        stiffness: 0.0,
        damping: 0.0,
        ..base
    })?;
    Ok(base)
}

/// The identified model at effective resolution `delta` and period `t` (K = 1 until the wall
/// is chosen; the delay from the config).
fn model_of(
    id: &super::ident::Identified,
    delta: f64,
    t: f64,
    base: &ServoConfig,
    rotational: bool,
) -> PhysicalParams {
    PhysicalParams {
        mass: id.mass,
        viscous: id.viscous.max(0.0),
        coulomb: id.coulomb.max(0.0),
        resolution: delta,
        period_s: t,
        stiffness: 1.0,
        delay_s: f64::from(base.extra_delay_ticks) * t,
        rotational,
    }
}

/// The maximum velocity (the one asked, or the default ξ̇, lowered where `room` effective
/// ticks are short) and the limits predicted at it.
fn limits_at(
    p: &PhysicalParams,
    s: &Settings,
    room: i64,
    progress: &Reporter<'_>,
) -> Result<(f64, Predicted)> {
    let asked = s
        .max_velocity
        .unwrap_or(DEFAULT_XIDOT * p.resolution / p.period_s);
    let predicted = predict(p, asked)?;
    let v = velocity_within(p, asked, &predicted, room, p.rotational, progress)?;
    let predicted = if v < asked { predict(p, v)? } else { predicted };
    Ok((v, predicted))
}

/// The default window (no travel stated) as the firmware's travel window, raw counts.
fn default_window(ws: &super::travel::Workspace) -> Option<(i32, i32)> {
    (ws.source == TravelSource::DefaultWindow).then(|| {
        let clamp = |n: i64| i32::try_from(n).unwrap_or(if n < 0 { i32::MIN } else { i32::MAX });
        (clamp(ws.ends[0]), clamp(ws.ends[1]))
    })
}

/// Force regime: above this K the wall's peak force at v, K·Δ·(d + ½) with d = v√(m/K)/Δ,
/// i.e. about v√(mK), exceeds the force limit and the firmware saturates it. A full-energy
/// release then no longer stores the impact's energy, so above it each search step also runs
/// what saturates first in use: an impact at v from each side.
pub(crate) fn force_regime_k(ident: &Identification) -> f64 {
    let f_lim = f64::from(ident.base.force_limit);
    (f_lim / (ident.v * ident.id.mass.sqrt())).powi(2)
}
