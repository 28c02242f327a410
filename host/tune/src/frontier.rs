//! The (K, B) frontier search after the spring-only one: the predicted frontier (the exact
//! linear boundary with the damper), the search at the stiffest predicted B, its confirmation,
//! and the spring-only fallback (`choose_wall`).
//!
//! Units: K N/m (N·m/rad), B N·s/m (N·m·s/rad), T s.

use super::error::Result;
use super::outcome::FrontierPoint;
use super::progress::Progress;
use super::release::Verdict;
use super::repeat::{margin_for_spread, repeated, Repeat};
use super::search::{largest_settling_k, Found, Search};
use super::settings::{
    Damping, CONFIRM_BACKOFF, CONFIRM_TRIES, DAMPED_MARGIN, DAMPING_BETAS, DAMPING_MIN_GAIN,
    DAMPING_SCALE_AGREEMENT, FRONTIER_REL_TOL, FRONTIER_START, FRONTIER_STEP, FRONTIER_TRIES,
};
use super::steps::{df_equivalent, Notes, Run};
use super::test_set::Test;
use super::verify::TestResult;
use stiffwall_client::Client;
use stiffwall_core::criteria;
use stiffwall_proto::{DamperLaw, ServoConfig};

/// The wall chosen: stiffness, damping, the verification at it and the frontier tried.
pub(crate) struct Wall {
    pub(crate) k_set: f64,
    pub(crate) b_set: f64,
    /// The damper's law (the tune's [`Settings::damper`]).
    pub(crate) damper: stiffwall_proto::DamperLaw,
    /// The margin applied to the chosen wall's largest resting K.
    pub(crate) margin: f64,
    pub(crate) k_spring_only: f64,
    pub(crate) verification: Vec<TestResult>,
    pub(crate) frontier: Vec<FrontierPoint>,
    /// The small-swing screen, when it lowered the damped wall.
    pub(crate) small_swing: Option<crate::small_swing::Screened>,
}

impl Wall {
    /// Every test of the verification set came to rest (or left a one-sided wall).
    pub(crate) fn rests(&self) -> bool {
        self.verification.iter().all(|r| {
            // An impact that was not launched says nothing about the wall (judged by the
            // releases of the same energy).
            r.verdict.settled() || matches!(r.verdict, Verdict::Departs | Verdict::NotLaunched)
        })
    }
}

/// Largest B the firmware accepts at the config's rate and coarsening, N·s/m: its limit
/// K_max(shift)·T/2 (`Board::max_damping`), a little inside for the f32 round trip.
pub(crate) fn b_cap(c: &Client, base: &ServoConfig, period_s: f64) -> f64 {
    let k_cap = f64::from(c.info.limits.max_stiffness) / f64::from(1u32 << base.coarsen_shift);
    0.999 * k_cap * period_s / 2.0
}

fn damped(base: &ServoConfig, b: f64) -> ServoConfig {
    ServoConfig {
        damping: b as f32,
        ..*base
    }
}

/// Where a search at one damping starts and what bounds it.
struct AtB<'a> {
    base: &'a ServoConfig,
    /// The damping searched, N·s/m (N·m·s/rad).
    b: f64,
    /// The first K tried.
    start: f64,
    /// No K below this counts.
    floor: f64,
    search: &'a Search,
    thorough: bool,
}

/// The largest resting K at damping `at.b`: from `at.start` down by [`FRONTIER_STEP`] until a
/// step passes, then up and bisected ([`FRONTIER_REL_TOL`]), then repeated from a new start
/// ([`crate::repeat`]); None when no K above `at.floor` passes, or none passes its repeat.
fn search_at(
    run: &Run<'_>,
    c: &mut Client,
    at: &AtB<'_>,
    notes: &mut Notes,
) -> Result<Option<(Found, Repeat)>> {
    let cfg = damped(at.base, at.b);
    let thorough = at.thorough;
    // Verdicts already measured, looked up by K (the bracketing revisits the K it came down
    // from).
    let mut seen: Vec<(f64, Verdict)> = Vec::new();
    let mut k = at.start;
    loop {
        let v = run.step(c, &cfg, k, thorough, notes)?;
        seen.push((k, v));
        if v.passes() {
            break;
        }
        k /= FRONTIER_STEP;
        if k < at.floor {
            return Ok(None);
        }
    }
    let search = Search {
        step: FRONTIER_STEP,
        rel_tol: at.search.rel_tol.max(FRONTIER_REL_TOL),
        ..*at.search
    };
    let mut found = largest_settling_k(k, &search, |k| {
        match seen.iter().find(|(k0, _)| (k / k0 - 1.0).abs() < 1e-9) {
            Some(&(_, v)) => Ok(v),
            None => run.step(c, &cfg, k, thorough, notes),
        }
    })?;
    let repeat = repeated(found.k_pass, found.k_fail, search.rel_tol, |k| {
        (run.progress)(Progress::Repeating { k, b: at.b });
        run.step(c, &cfg, k, thorough, notes)
    })?;
    match repeat.k_repeated {
        Some(k) if k >= at.floor => {
            found.k_pass = k;
            Ok(Some((found, repeat)))
        }
        _ => Ok(None),
    }
}

/// The K predicted at damping `b` for a device whose spring-only search found `k0`: the exact
/// linear boundary with the damper and Coulomb friction as describing-function damping at v,
/// times what the spring-only search measured against the same prediction at B = 0.
fn predicted_k(run: &Run<'_>, k0: f64, b: f64) -> Option<f64> {
    let eq = df_equivalent(&run.p, run.v);
    let at_0 = criteria::k_max_exact_linear(&eq, 0.0).ok()?;
    let at_b = criteria::k_max_exact_linear(&eq, b).ok()?;
    (at_0 > 0.0 && at_b > 0.0).then(|| k0 * at_b / at_0)
}

/// The K the damping levels are scaled by (B = β·K·T): the identified model's spring-only
/// limit (the exact linear boundary with Coulomb friction as describing-function damping at v)
/// where the spring-only search's `k0` agrees with it within [`DAMPING_SCALE_AGREEMENT`], else
/// `k0`. Issue 42: near its limit a spring's release verdict turns on where it starts, so `k0`
/// lands on one of two values run to run (1.19 or 1.30 on the emulated maxon-re35 board), and
/// a B scaled by it moved with it, and with B the wall set (a release that buzzes at 0.8 × the
/// frontier at the smaller B only). The model's K is the same every run.
fn damping_scale_k(run: &Run<'_>, k0: f64) -> f64 {
    let eq = df_equivalent(&run.p, run.v);
    match criteria::k_max_exact_linear(&eq, 0.0) {
        Ok(k) if k > 0.0 && (k0 / k - 1.0).abs() <= DAMPING_SCALE_AGREEMENT => k,
        _ => k0,
    }
}

/// The damping levels of [`DAMPING_BETAS`] within the firmware's limit `cap`, with their
/// predicted K, stiffest first; only those predicted to gain [`DAMPING_MIN_GAIN`] over `k0`.
fn predicted_frontier(run: &Run<'_>, k0: f64, cap: f64) -> Vec<(f64, f64)> {
    let k_ref = damping_scale_k(run, k0);
    let mut levels: Vec<(f64, f64)> = DAMPING_BETAS
        .iter()
        .map(|beta| beta * k_ref * run.period_s())
        .filter(|&b| b <= cap)
        .filter_map(|b| predicted_k(run, k0, b).map(|k| (b, k)))
        .filter(|&(_, k)| k > k0 * (1.0 + DAMPING_MIN_GAIN))
        .collect();
    levels.sort_by(|a, b| b.1.total_cmp(&a.1));
    levels
}

/// Chooses the wall after the spring-only search (`at.found`, repeated as `at.repeat`): spring
/// only, a fixed B, or the stiffest verified pair of the frontier ([`DAMPING_BETAS`]); the
/// chosen pair is confirmed with the whole verification set, the spring only is the fallback
/// of the search. Each wall's margin is `at.margin` (at most [`DAMPED_MARGIN`] with a damper),
/// lowered where its frontier K's repeat measured a spread it has no room for
/// ([`margin_for_spread`]).
pub(crate) fn choose_wall(
    run: &Run<'_>,
    c: &mut Client,
    base: &ServoConfig,
    at: &Searched<'_>,
    notes: &mut Notes,
) -> Result<Wall> {
    let found = at.found;
    let spring_margin = margin_for_spread(at.margin, at.repeat.spread());
    let k_spring = found.k_pass * spring_margin;
    let mut frontier = vec![FrontierPoint {
        b: 0.0,
        k_verified: Some(found.k_pass),
        damper: base.damper,
        repeat: Some(at.repeat),
    }];
    let (law, best) = damped_best(run, c, base, at, notes, &mut frontier)?;
    if best.0 > 0.0 {
        let cfg = ServoConfig {
            damper: law,
            ..damped(base, best.0)
        };
        let spread = frontier
            .iter()
            .rev()
            .find(|p| p.b == best.0)
            .and_then(|p| p.repeat)
            .map_or(0.0, |r| r.spread());
        let margin = margin_for_spread(at.margin.min(DAMPED_MARGIN), spread);
        let screened = small_swing_screen(run, &cfg, best.1 * margin, best.0, k_spring);
        // A damper the screen brings down to the spring-only wall buys nothing: that wall is set.
        let confirmed = if screened.k > k_spring {
            run.confirm(c, &cfg, screened.k, at.thorough, notes)?
        } else {
            None
        };
        if let Some((k_set, verification)) = confirmed {
            return Ok(Wall {
                k_set,
                b_set: best.0,
                damper: law,
                margin,
                k_spring_only: k_spring,
                verification,
                frontier,
                small_swing: screened.swing.map(|_| screened),
            });
        }
        let why = if screened.k > k_spring {
            "no stiffness passed the verification set"
        } else {
            "the small-swing screen leaves no stiffness above the spring-only wall's"
        };
        if let Damping::Fixed(b) = run.s.damping {
            return Err(super::error::NoWallPassed(format!(
                "{why} at the fixed damping B = {b:.4e}"
            ))
            .into());
        }
        (run.progress)(Progress::DamperDropped { b: best.0 });
    }
    let (k_set, verification) = confirm_spring(run, c, base, k_spring, at.thorough, notes)?;
    Ok(Wall {
        k_set,
        b_set: 0.0,
        damper: base.damper,
        margin: spring_margin,
        k_spring_only: k_set,
        verification,
        frontier,
        small_swing: None,
    })
}

/// The damped wall `k_asked` at `b`, lowered by the small-swing screen on the identified model
/// (`small_swing`) to below the first K that keeps a swing (not below the spring-only wall
/// `k_spring`); reported when it lowers.
fn small_swing_screen(
    run: &Run<'_>,
    cfg: &ServoConfig,
    k_asked: f64,
    b: f64,
    k_spring: f64,
) -> crate::small_swing::Screened {
    let model = crate::small_swing::SwingModel {
        accept_chatter: run.s.criterion == super::settings::Criterion::AcceptChatter,
        ..crate::small_swing::SwingModel::of(&run.p, cfg, run.one_sided_wall, run.static_n)
    };
    let screened = crate::small_swing::screen(&model, k_asked, b, k_spring);
    if screened.swing.is_some() {
        (run.progress)(Progress::SmallSwing(screened));
    }
    screened
}

/// The damped wall to confirm: its law and (B, largest resting K), or B = 0 when no damper
/// buys stiffness (or `--damping 0`). The default law is tried first; where it buys nothing,
/// the plain difference (stiffer on some devices, docs/DAMPER-LAWS.md) before the spring alone.
fn damped_best(
    run: &Run<'_>,
    c: &mut Client,
    base: &ServoConfig,
    at: &Searched<'_>,
    notes: &mut Notes,
    frontier: &mut Vec<FrontierPoint>,
) -> Result<(DamperLaw, (f64, f64))> {
    let best = match run.s.damping {
        Damping::Fixed(b) if b > 0.0 => fixed_damping(run, c, base, b, at, notes, frontier)?,
        Damping::Fixed(_) => return Ok((base.damper, (0.0, at.found.k_pass))),
        Damping::Search => search_frontier(run, c, base, at, notes, frontier)?,
    };
    if best.0 > 0.0
        || run.s.damper.is_some()
        || base.damper == DamperLaw::Difference
        || matches!(run.s.damping, Damping::Fixed(_))
    {
        return Ok((base.damper, best));
    }
    let plain = ServoConfig {
        damper: DamperLaw::Difference,
        ..*base
    };
    let best = search_frontier(run, c, &plain, at, notes, frontier)?;
    Ok((DamperLaw::Difference, best))
}

/// The spring-only search's result and the settings the frontier search runs with.
pub(crate) struct Searched<'a> {
    pub(crate) found: &'a Found,
    /// The repeat of the spring-only search's K.
    pub(crate) repeat: Repeat,
    pub(crate) search: &'a Search,
    pub(crate) thorough: bool,
    /// The spring-only wall's margin (before the spread's).
    pub(crate) margin: f64,
}

/// The largest resting K at the fixed damping `b` (`--damping B`), searched from the K the
/// linear boundary predicts there, added to `frontier`: (B, K), or an error naming B when no K
/// down to 10⁻³ of the spring-only one settles.
fn fixed_damping(
    run: &Run<'_>,
    c: &mut Client,
    base: &ServoConfig,
    b: f64,
    at: &Searched<'_>,
    notes: &mut Notes,
    frontier: &mut Vec<FrontierPoint>,
) -> Result<(f64, f64)> {
    let (found, search) = (at.found, at.search);
    let start = predicted_k(run, found.k_pass, b).map_or(found.k_pass, |k| {
        (k * FRONTIER_START).clamp((found.k_pass * 1e-3).min(search.k_cap), search.k_cap)
    });
    let floor = found.k_pass * 1e-3;
    let target = AtB {
        base,
        b,
        start,
        floor,
        search,
        thorough: at.thorough,
    };
    let Some((f, repeat)) = search_at(run, c, &target, notes)? else {
        return Err(super::error::NoWallPassed(format!(
            "no stiffness down to {floor:.4e} settles at the fixed damping B = {b:.4e}"
        ))
        .into());
    };
    frontier.push(FrontierPoint {
        b,
        k_verified: Some(f.k_pass),
        damper: base.damper,
        repeat: Some(repeat),
    });
    Ok((b, f.k_pass))
}

/// The frontier search: the predicted levels, stiffest first (at most [`FRONTIER_TRIES`]), each
/// searched from [`FRONTIER_START`] × its predicted K, added to `frontier`; the first whose
/// largest resting K buys [`DAMPING_MIN_GAIN`] of the stiffness set is (B, K), else
/// (0, the spring-only K).
fn search_frontier(
    run: &Run<'_>,
    c: &mut Client,
    base: &ServoConfig,
    at: &Searched<'_>,
    notes: &mut Notes,
    frontier: &mut Vec<FrontierPoint>,
) -> Result<(f64, f64)> {
    let (found, search, margin) = (at.found, at.search, at.margin);
    let cap = b_cap(c, base, run.period_s());
    // The damper must buy DAMPING_MIN_GAIN of the stiffness *set*: its wall is set at
    // DAMPED_MARGIN of its largest resting K, the spring-only one at `margin`.
    let floor = found.k_pass * (1.0 + DAMPING_MIN_GAIN) * margin / margin.min(DAMPED_MARGIN);
    if floor >= search.k_cap {
        // The largest K the search may try (the quiet ceiling, or the firmware's limit) leaves
        // no room for a damper to buy stiffness.
        return Ok((0.0, found.k_pass));
    }
    for (b, k_pred) in predicted_frontier(run, found.k_pass, cap)
        .into_iter()
        .take(FRONTIER_TRIES)
    {
        (run.progress)(Progress::DampingSearch {
            b,
            k_predicted: k_pred,
            k_start: (k_pred * FRONTIER_START).max(floor),
        });
        let target = AtB {
            base,
            b,
            start: (k_pred * FRONTIER_START).clamp(floor, search.k_cap),
            floor,
            search,
            thorough: at.thorough,
        };
        let f = search_at(run, c, &target, notes)?;
        let k = f.as_ref().map(|f| f.0.k_pass).filter(|&k| k >= floor);
        frontier.push(FrontierPoint {
            b,
            k_verified: k,
            damper: base.damper,
            repeat: f.map(|f| f.1),
        });
        if let Some(k) = k {
            return Ok((b, k));
        }
    }
    Ok((0.0, found.k_pass))
}

/// Confirms the spring-only wall from `k`. When no K passes and the last failure was an
/// impact at v, the releases passed: the wall is then confirmed without the impacts at v (the
/// releases at full energy from both sides and the slower impacts), and reported
/// (`notes.impacts_capped`). Only when a release fails at every K does it end with an error,
/// naming the test that failed and what to try.
fn confirm_spring(
    run: &Run<'_>,
    c: &mut Client,
    base: &ServoConfig,
    k: f64,
    thorough: bool,
    notes: &mut Notes,
) -> Result<(f64, Vec<TestResult>)> {
    if let Some(found) = run.confirm(c, base, k, thorough, notes)? {
        return Ok(found);
    }
    let last = k * CONFIRM_BACKOFF.powi(CONFIRM_TRIES as i32 - 1);
    let impact_failed = notes
        .last_failure
        .is_some_and(|r| matches!(r.test, Test::Impact { .. }));
    if impact_failed {
        (run.progress)(Progress::ImpactsCapped {
            k_from: k,
            k_to: last,
        });
        notes.impacts_capped = true;
        if let Some(found) = run.confirm(c, base, k, thorough, notes)? {
            return Ok(found);
        }
    }
    let what = notes.last_failure.map_or_else(
        || "no test ran".to_string(),
        |r| {
            format!(
                "at K = {:.4} the {} was {}",
                r.k,
                r.test.describe(),
                r.verdict.describe()
            )
        },
    );
    Err(super::error::NoWallPassed(format!(
        "no stiffness passed the verification set from {k:.4} down to {last:.4}: {what}. Try a \
         lower --max-velocity (the impacts and releases reach v), a smaller --margin, or check \
         the device: the force output's sign and scale (`hostctl experiment` runs one release \
         test), the encoder, and the amplifier's limit"
    ))
    .into())
}
