//! The workspace's steps of the tune procedure (issue 46): where the device starts and the
//! travel the experiments keep to ([`enter_workspace`]), the maximum velocity that travel leaves
//! room for ([`velocity_within`]), and the end of every tune ([`finish`]): the way back, the
//! final config, the `device left` check, then the save.
//!
//! Units: raw encoder counts for positions, SI for forces and velocities. Invariant: whatever
//! the tune's result, [`finish`] walks the device back to its start before the final config.

use super::error::TuneError;
use super::error::{Result, StepError};
use super::outcome::{Outcome, Predicted};
use super::progress::{Progress, Reporter};
use super::settings::Settings;
use super::travel::DeviceLeft;
use stiffwall_client::Client;
use stiffwall_core::params::PhysicalParams;
use stiffwall_proto::ServoConfig;

/// What the procedure learnt about where the device is, for the way back (issue 46).
#[derive(Debug, Default)]
pub(super) struct Place {
    /// Where the device started, raw counts.
    pub(super) start: Option<i64>,
    /// The travel the experiments kept to.
    pub(super) ws: Option<super::travel::Workspace>,
    /// The tests' config (the travel window set), the base of the way back.
    pub(super) test_base: Option<ServoConfig>,
    /// The spring of the way back: the wall found (verified to rest), else the centring one.
    pub(super) home: Option<super::travel::GentleMove>,
    /// The config to set and save when the tune succeeds (not on a dry run).
    pub(super) final_cfg: Option<ServoConfig>,
    /// The static friction F_s the quiet ceiling counts on, N (N·m), once identified.
    pub(super) static_friction: Option<f64>,
}

/// The end of every tune (success, error or cancel): the device back where it started,
/// gently; the final config set (the wall found, or the original); the check that it is at
/// rest, without a fault, where it started (`DeviceLeft`); then saved, or an error.
pub(super) fn finish(
    c: &mut Client,
    s: &Settings,
    original: &ServoConfig,
    place: &Place,
    result: Result<Outcome, TuneError>,
    progress: &Reporter<'_>,
) -> Result<Outcome, TuneError> {
    let mut problem = None;
    let start = place.start;
    let wall = place.final_cfg.filter(|_| result.is_ok() && !s.dry_run);
    let final_cfg = wall.unwrap_or(*original);
    if let (Some(start), Some(how)) = (start, place.home) {
        progress.report(Progress::Returning { target: start });
        let base = place.test_base.unwrap_or(*original);
        c.clear_faults().ok();
        if let Err(e) = super::travel::move_to(c, &base, free_side_of(&final_cfg, start), how) {
            problem = Some(format!("the way back failed: {e}"));
        }
    }
    // Only this tune's faults are latched now (the procedure cleared any before its tests).
    c.clear_faults().ok();
    if let Err(restore) = c.set_config(&final_cfg) {
        let error = result
            .err()
            .unwrap_or_else(|| TuneError::Procedure("the tune finished but was not set".into()));
        return Err(TuneError::NotRestored {
            error: Box::new(error),
            restore,
        });
    }
    let came_back = problem.is_none();
    let left = start.map(|st| {
        let settle = place.home.as_ref();
        super::travel::check_left(c, st, &final_cfg, place.static_friction, settle, problem)
    });
    if let Some(l) = &left {
        progress.report(Progress::Left(l.clone()));
    }
    // A dry run leaves the device's own config: when the device came back and that config then
    // raised a fault (a wall stiffer than the device holds: maxon-re35-stiction-amp1k-delay
    // boots with K = 0.5, above its K*(0) = 0.42), the check reports it (device_left, not ok)
    // but the tune, which changed nothing, does not fail on it.
    let own_config_fault = |l: &DeviceLeft| wall.is_none() && came_back && !l.faults.is_empty();
    let bad = left.clone().filter(|l| !l.ok && !own_config_fault(l));
    match result {
        Ok(mut o) => {
            if let Some(l) = bad {
                // A wall that does not hold is never saved: the previous config is back.
                c.clear_faults().ok();
                c.set_config(original).ok();
                return Err(TuneError::Left { left: Box::new(l) });
            }
            if wall.is_some() {
                c.save_config().map_err(|e| TuneError::Device {
                    during: format!("saving the tuned config: {e}"),
                    source: e,
                })?;
                o.saved = true;
            }
            o.device_left = left;
            o.workspace = place.ws;
            Ok(o)
        }
        // A failed (or cancelled) tune stays that error; its check was reported as progress.
        Err(e) => Err(e),
    }
}

/// Where the way back aims: `start`, or a count short of it on the free side when the final
/// config's one-sided wall would be in contact there (n = count − wall ≥ 0): a device a count
/// inside a stiff wall is pushed out by it, at rest a count outside nothing touches it.
fn free_side_of(final_cfg: &ServoConfig, start: i64) -> i64 {
    let in_contact = final_cfg.stiffness > 0.0
        && final_cfg.wall == stiffwall_proto::WallMode::OneSided
        && start >= i64::from(final_cfg.wall_position);
    if in_contact {
        start - 1
    } else {
        start
    }
}

/// The spring of the moves so far (the centring one until a wall is found).
pub(super) fn home_of(place: &Place) -> Result<super::travel::GentleMove> {
    place
        .home
        .ok_or_else(|| StepError::Failed("no spring to move the device with".into()))
}

/// Share of the force limit the way back and the move to the middle push with, before the
/// breakaway ramps have measured the static friction.
pub(super) const MOVE_FORCE_SHARE: f64 = 0.02;
pub(super) use super::approach::BREAKAWAY_MARGIN;
/// The moves' push, share of the force limit at most.
pub(super) const MOVE_MAX_FORCE_SHARE: f64 = 0.25;

/// The workspace (issue 46): where the device starts, the travel the experiments keep to
/// (reported), the firmware's travel window in the tests' config, and the device moved to the
/// middle of the travel when it starts near an end. Returns the tests' base config (the wall
/// at the test centre) and the room each side of it, counts.
pub(super) fn enter_workspace(
    c: &mut Client,
    s: &Settings,
    original: &ServoConfig,
    base: ServoConfig,
    progress: &Reporter<'_>,
    place: &mut Place,
) -> Result<(ServoConfig, i64)> {
    use super::travel::{centring_stiffness, GentleMove, Workspace};
    let res = f64::from(c.info.resolution);
    let rotational = c.info.counts_per_rev > 0;
    let start = super::travel::where_now(c, &base)?;
    let ws = Workspace::resolve(s.travel, original, start, res, rotational)?;
    progress.report(Progress::Travel {
        text: ws.describe(if rotational { "rad" } else { "m" }),
    });
    let (travel_min, travel_max) = ws.firmware_window(original);
    let base = ServoConfig {
        travel_min,
        travel_max,
        ..base
    };
    let force = MOVE_FORCE_SHARE * f64::from(original.force_limit);
    let centre = ws.test_centre();
    // The spring of the way back until a wall is found: the centring spring of the move's force.
    let how = GentleMove {
        k: centring_stiffness(force, ws.room_at(centre).max(1), res),
        b: 0.0,
        damper: base.damper,
        force_n: force,
        chatters: false,
        mass: None,
        friction: None,
        k_settle: 0.0,
    };
    place.start = Some(start);
    place.ws = Some(ws);
    place.test_base = Some(base);
    place.home = Some(how);
    if centre != start {
        progress.report(Progress::Travel {
            text: format!(
                "the device starts {} counts from the nearer end of the window: the experiments \
             run from the middle, count {centre}",
                ws.room_at(start)
            ),
        });
        super::travel::move_to(c, &base, centre, how)?;
    }
    let base = ServoConfig {
        wall_position: i32::try_from(centre).unwrap_or(base.wall_position),
        ..base
    };
    c.set_config(&base)?;
    Ok((base, ws.room_at(centre)))
}

/// The maximum velocity the travel leaves room for: `asked`, or less when a release or impact
/// test at the lowest K the search may try (a quarter of the smaller predicted limit) would
/// reach beyond `room` counts each side of the wall (saying so); an error naming the test and
/// the travel it needs when even a tenth of a count per tick does not fit.
pub(super) fn velocity_within(
    p: &PhysicalParams,
    asked: f64,
    predicted: &Predicted,
    room: i64,
    rotational: bool,
    progress: &Reporter<'_>,
) -> Result<f64> {
    let k_low = predicted.guaranteed.min(predicted.expected).max(1e-12) / 4.0;
    let ticks_per = p.period_s / p.resolution;
    let reach = super::travel::test_reach_counts(asked * ticks_per, p.mass, k_low, p.period_s);
    if reach <= room as f64 {
        return Ok(asked);
    }
    let unit = if rotational { "rad/s" } else { "m/s" };
    let v = asked * room as f64 / reach;
    if v * ticks_per < 0.1 {
        return Err(StepError::Failed(format!(
            "the travel is too short to tune: the release and impact tests at K = {k_low:.4} \
             and the maximum velocity {asked:.4} {unit} reach {reach:.0} counts each side of the \
             wall, and the travel leaves {room} counts (even 0.1 count per tick would not fit); \
             give the device's full travel with --travel MIN:MAX"
        )));
    }
    progress.report(Progress::Travel {
        text: format!(
            "the release and impact tests at K = {k_low:.4} and the maximum velocity \
             {asked:.4} {unit} need {reach:.0} counts of travel each side of the wall, and the \
             travel leaves {room}: the maximum velocity is lowered to {v:.4} {unit} (walls are \
             verified for hits up to that speed only)"
        ),
    });
    Ok(v)
}
