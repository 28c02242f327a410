//! The `tune` procedure on a connected device: identify, predict, verify, set.
//!
//! 1. **Identify** m, b, c with the wall off from an open-loop chirp the firmware plays
//!    ([`super::ident`]); the amplitude starts small and grows until the device moves freely.
//! 2. **Predict** K limits with `stiffwall-core` at the maximum velocity v (default: 5 encoder
//!    ticks per servo period, [`DEFAULT_XIDOT`]): the guaranteed limit (worst case, criterion
//!    (12), or (19) with delay and a harmonic acceleration bound) and the expected limit: the
//!    describing-function view of Sec. VII-D with the ZOH approximation replaced by the exact
//!    sampled linear boundary (Gil–Avello–Rubio), i.e. the largest K for which the sampled
//!    system is stable with Coulomb friction counted as its describing-function damping
//!    b + 4c/(πv) at the peak speed v. The paper's approximation (74) is reported beside it.
//! 3. **Check the model** ([`super::model_check`]): the fit residual, slow force ramps from rest
//!    in both directions (breakaway against the model's), and, after the search, the frequency
//!    of a release against √(K/m)/2π and the verified K against the expected one. What does
//!    not fit is reported (`model_mismatch`) and makes the verification thorough: the margin is
//!    multiplied by [`MISMATCH_MARGIN`] ([`FRICTION_MISMATCH_MARGIN`] when only the friction
//!    does not fit), the verification set gains a lower energy level and every test runs twice
//!    as long.
//! 4. **Verify** ([`super::verify`]): the search of [`super::search`] brackets and bisects the
//!    largest K whose full-energy release (deflection d = v·√(m/K)/Δ, spring energy = kinetic
//!    energy at v) passes, never above the firmware's stiffness limit. Where the wall's peak
//!    force v·√(mK) exceeds the force limit (the firmware saturates it), a search step also
//!    runs impacts at v from both sides, since a saturated release no longer stores the
//!    impact's energy. Then K = margin × that, and the whole verification set (releases
//!    from both sides at several energies up to v) must pass at K, backing off in steps of
//!    [`CONFIRM_BACKOFF`] otherwise; after a failed confirmation the K that passes is taken
//!    one step further down, since it may lie right under the limit.
//! 5. **Set** K and save it (unless dry-run). On any error or Ctrl-C the previous config is
//!    restored.
//!
//! Determinism: every step depends only on the device's counts (tests start from rest with the
//! wall off and end at points computed from their counts), not on when the host's messages
//! arrive, so `--fast` and real time give the same K on the virtual device.

use super::error::TuneError;
use super::error::{Result, SettingsError, StepError};
use super::excite::device_scale;
use super::frontier::{b_cap, choose_wall, Searched};
use super::identification::{force_regime_k, identify_and_predict, Identification};
use super::launch::Delivered;
use super::model_check;
use super::outcome::{IdentifiedReport, Outcome};
use super::progress::{Progress, Reporter};
use super::search::{largest_settling_k, Search};
use super::settings::{
    velocity_error, Criterion, Damping, Settings, FRICTION_MISMATCH_MARGIN, MISMATCH_MARGIN,
};
use super::steps::{Notes, Run};
use super::workspace::{finish, home_of, Place};
use stiffwall_client::{Cancel, Client};
use stiffwall_proto::ServoConfig;

/// Runs the whole procedure on `c`: identify, predict, verify and (unless
/// [`Settings::dry_run`]) set and save the wall. `progress` receives one event per step as it
/// starts. Cancelling `cancel` ends the running test and the tune ([`TuneError::Cancelled`]);
/// whatever the error, the device is left with the config it had before.
///
/// # Errors
/// A setting out of range (before any test), a cancel, the device failing, or no verifiable
/// wall (see [`TuneError`]).
pub fn tune(
    c: &mut Client,
    s: &Settings,
    cancel: &Cancel,
    progress: &mut dyn FnMut(Progress),
) -> Result<Outcome, TuneError> {
    s.validate()?;
    let original = c.get_config().map_err(|e| TuneError::Device {
        during: format!("reading the config: {e}"),
        source: e,
    })?;
    if let Damping::Fixed(b) = s.damping {
        // Checked before any test: the firmware's limit at the config's rate and coarsening.
        let t = device_scale(c)
            .map_err(|e| TuneError::from_step(e, false))?
            .1;
        let cap = b_cap(c, &original, t);
        if b > cap {
            return Err(SettingsError {
                field: "damping",
                range: format!(
                    "within [0, {cap:.4e}] N·s/m (N·m·s/rad) on this device (the firmware's \
                     limit at its rate and coarsening)"
                ),
                got: b.to_string(),
            }
            .into());
        }
    }
    if let Some(v) = s.max_velocity {
        // The plausible range of the device's kind (m/s or rad/s), before any test.
        let rotational = c.info.counts_per_rev > 0;
        if stiffwall_sim::scene::field_bounds::VELOCITY
            .check("max_velocity", v, rotational)
            .is_err()
        {
            return Err(velocity_error(v).into());
        }
    }
    // A haptic profile renders in place of the config's wall, including the walks' springs
    // between tests: off for the tune, back (and saved with a saved wall) after it.
    let profile = c.get_profile().map_err(|e| TuneError::Device {
        during: format!("reading the active profile: {e}"),
        source: e,
    })?;
    let reporter = Reporter::new(progress);
    if !profile.elements.is_empty() {
        c.set_profile(&stiffwall_proto::Profile::default())
            .map_err(|e| TuneError::Device {
                during: format!("turning the active profile off for the tune: {e}"),
                source: e,
            })?;
        reporter.report(Progress::Finding {
            text: format!(
                "a haptic profile of {} elements is active: off during the tune, back after it",
                profile.elements.len()
            ),
        });
    }
    // The client's experiments check the caller's token for the whole tune.
    let outer = c.set_cancel(cancel.clone());
    let mut place = Place::default();
    let result = tune_inner(c, s, &original, &reporter, &mut place)
        .map_err(|e| TuneError::from_step(e, cancel.is_cancelled()));
    // The way back is not cancelled: a cancelled tune still leaves the device where it was.
    c.set_cancel(stiffwall_client::Cancel::default());
    let finished = finish(c, s, &original, &place, result, &reporter);
    c.set_cancel(outer);
    restore_profile(c, &profile, finished)
}

/// The profile that was active before the tune, back (and saved when the tune saved its
/// wall, so the store holds both); a failure to restore it is the tune's error.
fn restore_profile(
    c: &mut Client,
    profile: &stiffwall_proto::Profile,
    finished: Result<Outcome, TuneError>,
) -> Result<Outcome, TuneError> {
    if profile.elements.is_empty() {
        return finished;
    }
    let device = |during: &str, e: stiffwall_client::ClientError| TuneError::Device {
        during: format!("{during}: {e}"),
        source: e,
    };
    c.set_profile(profile)
        .map_err(|e| device("restoring the haptic profile active before the tune", e))?;
    if finished.as_ref().is_ok_and(|o| o.saved) {
        c.save_config()
            .map_err(|e| device("saving the config with the restored profile", e))?;
    }
    finished
}

/// The spring-only search starts at the expected limit, but not below this fraction of the
/// guaranteed one (an expected limit far below the guaranteed one means the friction estimate
/// is off, and the bracket would start needlessly low).
const SEARCH_START_OF_GUARANTEED: f64 = 0.5;

/// Zero crossings of the best release used to measure its frequency (the first ones: the
/// oscillation before friction and quantization distort it).
const FREQUENCY_CROSSINGS: usize = 12;

fn tune_inner(
    c: &mut Client,
    s: &Settings,
    original: &ServoConfig,
    progress: &Reporter<'_>,
    place: &mut Place,
) -> Result<Outcome> {
    let mut ident = identify_and_predict(c, s, original, progress, place)?;
    let ceiling = quiet_ceiling(&ident);
    place.static_friction = Some(static_friction_band(&ident, ceiling));
    // The quiet search runs on a copy: where no wall rests, the search for the least chatter
    // starts again from what identification found.
    let mut tried = ident.clone();
    let quiet = (s.criterion == Criterion::Rest && ceiling > 0.0)
        .then(|| search_walls(c, s, &mut tried, original, progress, ceiling));
    let (searched, no_rest) = match quiet {
        Some(Ok(found)) => {
            ident = tried;
            (found, None)
        }
        Some(Err(e)) if matches!(e.root(), StepError::NoWallPassed(_)) => {
            let why = no_rest_reason(&ident, ceiling, Some(&e));
            progress.report(Progress::Finding { text: why.clone() });
            let chatter = least_chatter_settings(s);
            let found = search_walls(c, &chatter, &mut ident, original, progress, 0.0)?;
            (found, Some(why))
        }
        Some(Err(e)) => return Err(e),
        None if s.criterion == Criterion::Rest => {
            let why = no_rest_reason(&ident, ceiling, None);
            progress.report(Progress::Finding { text: why.clone() });
            let chatter = least_chatter_settings(s);
            let found = search_walls(c, &chatter, &mut ident, original, progress, 0.0)?;
            (found, Some(why))
        }
        None => (
            search_walls(c, s, &mut ident, original, progress, 0.0)?,
            None,
        ),
    };
    let (found, wall, mut model_mismatch) = searched;
    // The wall with the least chatter may still have come to rest in every test of its set.
    let no_rest = no_rest.filter(|_| !wall.rests());
    if let Some(why) = &no_rest {
        model_mismatch.push(why.clone());
    }
    // Step 5 (in `finish`, after the way back): set, check and save.
    prepare_finish(place, &wall, original)?;
    let saved = false;
    let quiet = Quiet {
        ceiling,
        no_rest,
        criterion: s.criterion,
    };
    Ok(outcome(ident, found, wall, model_mismatch, saved, quiet))
}

/// The band the user's own wall holds the device in (the final check) counts on the breakaway
/// measured, the smaller direction's (at least c); without one, the quiet ceiling's credit.
fn static_friction_band(ident: &Identification, ceiling: f64) -> f64 {
    let breakaway = ident
        .evidence
        .breakaway_measured
        .iter()
        .flatten()
        .map(|f| f.abs())
        .fold(f64::INFINITY, f64::min);
    if breakaway.is_finite() {
        breakaway.max(ident.p.coulomb)
    } else {
        ceiling * ident.p.resolution / 2.0
    }
}

/// What `finish` needs for step 5: the way back's walk and the config to set.
fn prepare_finish(
    place: &mut Place,
    wall: &super::frontier::Wall,
    original: &ServoConfig,
) -> Result<()> {
    // The way back walks with a sixteenth of the wall found (as the search's own walks do):
    // far below the stiffness verified, so a step of the walk, a deflection of up to its push
    // F/(KΔ), cannot ring it (at the wall's own K, behind a delay, it can: a light rotor with
    // two ticks of delay grew from a 20-count step to the force limit's limit cycle).
    place.home = Some(super::travel::GentleMove {
        k: wall.k_set / 16.0,
        b: 0.0,
        damper: wall.damper,
        chatters: !wall.rests(),
        // The final approach may stiffen to a quarter of the spring-only wall that rested:
        // still far below it (at the wall's own K a light rotor behind two ticks of delay,
        // rotary-light-stiction-delay2, went from a 13-count nudge into a limit cycle at the
        // walk's force limit: a start the verification had not tried).
        k_settle: if wall.rests() {
            wall.k_spring_only / 4.0
        } else {
            0.0
        },
        ..home_of(place)?
    });
    place.final_cfg = Some(ServoConfig {
        stiffness: wall.k_set as f32,
        damping: wall.b_set as f32,
        damper: wall.damper,
        ..*original
    });
    Ok(())
}

/// The settings of the search for the wall with the least chatter, where no wall rests: chatter
/// within one count accepted, and no damper (it cannot make a wall rest where friction cannot
/// hold it, and adds to the force swing) unless the user fixed one.
fn least_chatter_settings(s: &Settings) -> Settings {
    Settings {
        criterion: Criterion::AcceptChatter,
        damping: match s.damping {
            Damping::Fixed(b) => Damping::Fixed(b),
            Damping::Search => Damping::Fixed(0.0),
        },
        ..s.clone()
    }
}

/// The quiet ceiling 2·max(c, F_s)/Δ of the identified device (`stiffwall_core::rest`), N/m
/// (N·m/rad). F_s, the static friction, is c plus the least, over the two directions, of what
/// the breakaway ramp measured beyond the identified model's breakaway on the same ramp: the
/// ramp's own overshoot and a spring's preload (a hand), which the model's breakaway carries
/// too, cancel (phantom-stiction: measured 0.0685 N, model 0.0519 N, c = 0.038 N, so F_s ≈
/// 0.0546 N, the plant's 0.057 N; phantom-realistic, with a hand: +0.0877/−0.0558 N measured,
/// +0.0708/−0.0389 N model, 0.0169 N beyond it either way).
/// Share of the static friction's excess over c that the quiet ceiling counts on: a device
/// that keeps moving feels only the sliding friction c, and stiction holds only one that has
/// stopped, so a wall just under 2F_s/Δ rests from some starts and keeps a small buzz from others
/// (random plants with 1.3–1.7 × static friction and T = 2 ms: with the whole excess, a ±2-count
/// buzz at 1.0–1.24 K*(B) from 4 of 28 starts, with tune's own tests resting; with 3/4 they rest
/// in all 28, and phantom-realistic, a hand and 1.5 × static friction, is set at 0.715 K*(B),
/// where half the excess gave 0.656).
const STATIC_FRICTION_CREDIT: f64 = 0.75;

fn quiet_ceiling(ident: &Identification) -> f64 {
    let excess = static_excess(ident);
    let c = ident.p.coulomb;
    let static_n = if excess.is_finite() {
        c + STATIC_FRICTION_CREDIT * excess.max(0.0)
    } else {
        c
    };
    stiffwall_core::rest::quiet_ceiling(c, static_n, ident.p.resolution)
}

/// The least, over the two directions, of what the breakaway ramps measured beyond the
/// identified model's breakaway on the same ramp, N (N·m): static friction above c (∞ when
/// no ramp measured it).
fn static_excess(ident: &Identification) -> f64 {
    let e = &ident.evidence;
    e.breakaway_measured
        .iter()
        .zip(&e.breakaway_model)
        .filter_map(|(m, model)| Some(m.as_ref()?.abs() - model.as_ref()?.abs()))
        .fold(f64::INFINITY, f64::min)
}

/// Why no wall rests on this device, in words (`failure`: the search's or verification's).
fn no_rest_reason(ident: &Identification, ceiling: f64, failure: Option<&StepError>) -> String {
    let (f, k) = ident.units;
    let head = if ceiling <= 0.0 {
        format!(
            "no wall comes to rest on this device: no Coulomb friction was identified (c = \
             {:.3e} {f}), and with the wall's force −KΔ(n + ½) at least KΔ/2 at every count, \
             nothing holds the device still, so the count toggles between two counts for ever \
             at any K",
            ident.p.coulomb
        )
    } else {
        format!(
            "no wall comes to rest on this device: no stiffness down to a quarter of the smaller of \
             the quiet ceiling 2·max(c, F_s)/Δ = {ceiling:.4e} {k} and the guaranteed limit came \
             to rest in every test (a hand or \
             a spring pushing the device, or friction too small to hold the wall's force KΔ/2)"
        )
    };
    let what = failure.map_or(String::new(), |e| format!(" ({e})"));
    format!(
        "{head}{what}; the wall set is the stiffest that stays within one count and never \
         grows, without a damper (the least chatter): it chatters, as reported for each test"
    )
}

/// What the tune found about rest (see `stiffwall_core::rest`).
struct Quiet {
    ceiling: f64,
    no_rest: Option<String>,
    criterion: Criterion,
}

/// Steps 4–4b under `s.criterion`: the spring-only search (not below `k_floor`), the model
/// findings, the (K, B) frontier and the verification of the chosen wall.
fn search_walls(
    c: &mut Client,
    s: &Settings,
    ident: &mut Identification,
    original: &ServoConfig,
    progress: &Reporter<'_>,
    ceiling: f64,
) -> Result<(super::search::Found, super::frontier::Wall, Vec<String>)> {
    let early = model_check::findings(&ident.id, &ident.evidence, ident.units);
    let report = |e: Progress| progress.report(e);
    let run = Run {
        s,
        p: ident.p,
        v: ident.v,
        k_force: force_regime_k(ident),
        one_sided_wall: original.wall == stiffwall_proto::WallMode::OneSided,
        force_per_code: f64::from(c.info.force_per_code),
        progress: &report,
        slow_launch: std::cell::Cell::new(None),
        missed_launch: std::cell::Cell::new(None),
        room: ident.room,
        move_force_n: ident.move_force_n,
        window: ident.window,
        static_n: Some(static_excess(ident))
            .filter(|x| x.is_finite() && *x > 0.0)
            .map(|x| ident.p.coulomb + x),
    };
    // Above the quiet ceiling no count can hold the wall's force KΔ/2 against friction: a test
    // that rests there rested on a bias (a hand or cable pulling to one side of the wall, a
    // cogging detent) that a user does not keep in place, so no K above it is tried.
    let device_cap = f64::from(c.info.limits.max_stiffness);
    let search = Search {
        k_cap: if ceiling > 0.0 {
            device_cap.min(ceiling)
        } else {
            device_cap
        },
        rel_tol: s.rel_tol,
        // Below a quarter of both the quiet ceiling (σ ≥ 2: friction holds the wall at four
        // counts either side) and the guaranteed limit (no growth at v), a spring that still
        // does not rest is held off rest by something else: the device has no quiet wall.
        k_floor: ceiling.min(ident.predicted.guaranteed) / 4.0,
        ..Search::default()
    };
    // Step 4a: the spring-only search (a model that does not fit makes every test thorough).
    let mut notes = Notes::default();
    let (found, repeat) = spring_search(&run, c, ident, &search, !early.is_empty(), &mut notes)?;
    let mut model_mismatch = model_check::findings(&ident.id, &ident.evidence, ident.units);
    // Only a search that found a failing K measured the limit (otherwise the force cap did).
    if found.k_fail.is_some() {
        model_mismatch.extend(model_check::prediction_finding(
            found.k_pass,
            ident.predicted.expected,
        ));
    }
    // An impact the search could not launch was judged by releases only: the search's
    // largest K is then less well tested, so the mismatch margin applies as well.
    let thorough = !model_mismatch.is_empty() || notes.not_launched.is_some();
    for f in &model_mismatch {
        progress.report(Progress::Finding { text: f.clone() });
    }
    let margin_used = margin_for(s, thorough, &notes, ident);
    // Step 4b: the (K, B) frontier and the verification set of the chosen wall.
    let base = ident.base;
    let searched = Searched {
        found: &found,
        repeat,
        search: &search,
        thorough,
        margin: margin_used,
    };
    let wall = choose_wall(&run, c, &base, &searched, &mut notes)?;
    for finding in launch_findings(&run, &notes, ident) {
        progress.report(Progress::Finding {
            text: finding.clone(),
        });
        model_mismatch.push(finding);
    }
    Ok((found, wall, model_mismatch))
}

/// Step 4a: the largest resting K at B = 0, from the prediction (the expected limit, not below
/// half the guaranteed one); the release frequency of its best test goes into the evidence.
fn spring_search(
    run: &Run<'_>,
    c: &mut Client,
    ident: &mut Identification,
    search: &Search,
    thorough: bool,
    notes: &mut Notes,
) -> Result<(super::search::Found, super::repeat::Repeat)> {
    let start = ident
        .predicted
        .expected
        .min(search.k_cap)
        .max(ident.predicted.guaranteed.min(search.k_cap) * SEARCH_START_OF_GUARANTEED);
    let base = ident.base;
    let mut found = largest_settling_k(start, search, |k| run.step(c, &base, k, thorough, notes))?;
    // The largest resting K counts only when it rests again from a new start (issue 42).
    let repeat = super::repeat::repeated(found.k_pass, found.k_fail, search.rel_tol, |k| {
        (run.progress)(Progress::Repeating { k, b: 0.0 });
        run.step(c, &base, k, thorough, notes)
    })?;
    // No K rested twice within the repeat's steps: the last K tried, one step down (its
    // wall is confirmed by the verification set before it is set).
    found.k_pass = repeat
        .k_repeated
        .unwrap_or_else(|| repeat.k_failed.unwrap_or(found.k_pass) / (1.0 + search.rel_tol));
    if let Some((k, counts)) = &notes.best {
        let e = &mut ident.evidence;
        e.release_k = Some(*k);
        e.release_hz =
            model_check::release_frequency_hz(counts, ident.p.period_s, FREQUENCY_CROSSINGS);
        e.model_hz = Some((k / ident.id.mass).sqrt() / std::f64::consts::TAU);
    }
    Ok((found, repeat))
}

/// The margin applied to the largest resting K: the user's, times [`MISMATCH_MARGIN`] when
/// the model does not fit (or an impact could not be launched), [`FRICTION_MISMATCH_MARGIN`]
/// when only the friction does not fit.
fn margin_for(s: &Settings, thorough: bool, notes: &Notes, ident: &Identification) -> f64 {
    s.margin
        * if !thorough {
            1.0
        } else if notes.not_launched.is_none()
            && model_check::dynamics_fit(&ident.id, &ident.evidence)
        {
            FRICTION_MISMATCH_MARGIN
        } else {
            MISMATCH_MARGIN
        }
}

/// What the impact launches showed: not launched, launched slowly, impacts at v left out.
fn launch_findings(run: &Run<'_>, notes: &Notes, ident: &Identification) -> Vec<String> {
    let (v, t) = (ident.v, ident.p.period_s);
    [
        notes
            .not_launched
            .map(|k| not_launched_finding(k, ident.id.mass, t, run.missed_launch.get())),
        run.slow_launch.get().map(|d| slow_launch_finding(&d)),
        notes.impacts_capped.then(|| {
            format!(
                "impacts at the maximum velocity ({v:.4} {}) failed at every stiffness tried: \
                 the wall set is verified by releases of the same energy from both sides and by \
                 impacts at half that speed and below only; a hit faster than v/2 is not tested \
                 on this device",
                if ident.p.rotational { "rad/s" } else { "m/s" }
            )
        }),
    ]
    .into_iter()
    .flatten()
    .collect()
}

fn outcome(
    ident: Identification,
    found: super::search::Found,
    wall: super::frontier::Wall,
    model_mismatch: Vec<String>,
    saved: bool,
    quiet: Quiet,
) -> Outcome {
    let Identification {
        id,
        amplitude,
        evidence,
        mut p,
        v,
        predicted,
        ..
    } = ident;
    p.stiffness = wall.k_set;
    let rests = wall.rests();
    let repeatability = repeatability(&wall);
    Outcome {
        repeatability,
        rests,
        identified: IdentifiedReport {
            mass: [id.mass, id.mass_se],
            viscous: [id.viscous, id.viscous_se],
            viscous_upper_bound: id.viscous_upper_bound(),
            viscous_only_bounded: id.viscous_only_bounded(),
            coulomb: [id.coulomb, id.coulomb_se],
            equations: id.equations,
            excite_amplitude_codes: amplitude,
            spring: id.spring.map(|sp| [sp.stiffness, sp.stiffness_se]),
        },
        params: p,
        max_velocity: v,
        xidot: v * p.period_s / p.resolution,
        predicted,
        search: found,
        k_set: wall.k_set,
        b_set: wall.b_set,
        k_spring_only: wall.k_spring_only,
        frontier: wall.frontier,
        confirmation: wall.verification.iter().map(|r| r.verdict).collect(),
        verification: wall.verification,
        criterion: quiet.criterion,
        damper: wall.damper.to_string(),
        quiet_ceiling: quiet.ceiling,
        no_rest: quiet.no_rest,
        model_mismatch,
        model_evidence: evidence,
        margin_used: wall.margin,
        small_swing: wall.small_swing,
        saved,
        workspace: None,
        device_left: None,
    }
}

/// The set wall's frontier point's repeat, with the margin the wall was set at.
fn repeatability(wall: &super::frontier::Wall) -> Option<super::outcome::Repeatability> {
    let point = wall.frontier.iter().rev().find(|p| p.b == wall.b_set)?;
    let r = point.repeat?;
    Some(super::outcome::Repeatability {
        b: wall.b_set,
        k_searched: r.k_searched,
        k_repeated: r.k_repeated,
        k_failed: r.k_failed,
        spread: r.spread(),
        margin: wall.margin,
        spread_room: super::repeat::spread_room(wall.margin),
        set_by_screen: wall.small_swing.is_some_and(|s| s.k < s.k_asked),
    })
}

fn not_launched_finding(k: f64, mass: f64, t: f64, missed: Option<Delivered>) -> String {
    let mu = mass / (k * t * t);
    let what = missed.map_or(String::new(), |d| {
        format!(
            " (it arrived at {:.1} ticks/tick, fastest step {:.0}, for {:.2} asked, also after \
             re-aiming)",
            d.contact, d.fastest, d.asked
        )
    });
    format!(
        "at K = {k:.4} the firmware's impact launch (a hold moving at the requested speed, with \
         damping β = {}) did not bring the device to the wall at the requested speed{what}, \
         and the impact failed: that says nothing about the wall at that speed (μ = m/(KT²) = \
         {mu:.3}; the hold lags and catches up, or oscillates, when μ is small, behind a slow \
         amplifier or extra delay); those impacts were judged by the releases of the same \
         energy from both sides",
        stiffwall_firmware::config::HOLD_BETA
    )
}

fn slow_launch_finding(d: &Delivered) -> String {
    format!(
        "the firmware's impact launch reached the wall at only {:.1} ticks/tick of the {:.2} \
         asked (its hold could not accelerate the device: a force limit or friction); those \
         impacts passed at the speed they reached, and the full energy was verified by \
         releases from both sides",
        d.contact, d.asked
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn where_no_wall_rests_the_search_accepts_chatter_without_a_damper_unless_one_is_fixed() {
        let s = least_chatter_settings(&Settings::default());
        assert_eq!(s.criterion, Criterion::AcceptChatter);
        assert_eq!(s.damping, Damping::Fixed(0.0));
        let fixed = Settings {
            damping: Damping::Fixed(2.5e-3),
            margin: 0.7,
            ..Settings::default()
        };
        let s = least_chatter_settings(&fixed);
        assert_eq!(s.damping, Damping::Fixed(2.5e-3));
        assert_eq!((s.criterion, s.margin), (Criterion::AcceptChatter, 0.7));
    }
}
