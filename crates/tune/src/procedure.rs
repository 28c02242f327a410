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

use super::excite::{breakaway, device_scale};
use super::model_check::{self, Evidence};
use super::release::Verdict;
use super::search::{largest_settling_k, Found, Search};
use super::verify::{min_settle_run, rest_position, run_test, test_set, Test, TestResult};
use anyhow::{bail, Context, Result};
use stiffwall_client::Client;
use stiffwall_core::criteria;
use stiffwall_core::params::PhysicalParams;
use stiffwall_proto::ServoConfig;

/// Step 1, identification with the wall off (in [`super::excite`]).
pub use super::excite::identify;
pub use super::outcome::{FrontierPoint, IdentifiedReport, Outcome, Predicted};
pub use super::settings::*;
/// Set by the Ctrl-C handler; checked between experiments (the one flag of every session).
pub use stiffwall_client::session::INTERRUPTED;

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

/// The linear device whose viscous damping adds Coulomb friction's describing-function damping
/// 4c/(πv) at velocity amplitude v (v in m/s or rad/s).
#[must_use]
pub fn df_equivalent(p: &PhysicalParams, v: f64) -> PhysicalParams {
    PhysicalParams {
        viscous: p.viscous + 4.0 * p.coulomb / (std::f64::consts::PI * v),
        ..*p
    }
}

/// Release deflection (effective ticks) whose spring energy equals the kinetic energy at v.
#[must_use]
pub fn deflection_for(p: &PhysicalParams, k: f64, v: f64) -> i32 {
    let d = v * (p.mass / k).sqrt() / p.resolution;
    d.round().clamp(2.0, 1e6) as i32
}

/// Runs the whole procedure. `progress` receives one-line status messages.
pub fn tune(
    c: &mut Client,
    s: &Settings,
    dry_run: bool,
    progress: &dyn Fn(&str),
) -> Result<Outcome> {
    s.validate()?;
    let original = c.get_config()?;
    if let Damping::Fixed(b) = s.damping {
        // Checked before any test: the firmware's limit at the config's rate and coarsening.
        let cap = b_cap(c, &original, device_scale(c)?.1);
        if b > cap {
            bail!(
                "--damping must be within [0, {cap:.4e}] N·s/m (N·m·s/rad) on this device (the \
                 firmware's limit at its rate and coarsening; got {b})"
            );
        }
    }
    let result = tune_inner(c, s, &original, dry_run, progress);
    // Leave the device as it was unless a new config was deliberately set.
    let keep = matches!(&result, Ok(o) if !dry_run && o.saved);
    if !keep {
        c.clear_faults().ok();
        c.set_config(&original)
            .context("restoring the previous config")?;
    }
    result
}

/// What every test of one run needs beyond the config: the identified device and the tune's
/// targets.
struct Run<'a> {
    s: &'a Settings,
    p: PhysicalParams,
    /// Maximum velocity v, m/s (rad/s).
    v: f64,
    /// Above this K the wall's peak force at v saturates (see [`tune_inner`]).
    k_force: f64,
    one_sided_wall: bool,
    progress: &'a dyn Fn(&str),
}

/// What the searches found beside their result.
#[derive(Default)]
struct Notes {
    /// The smallest K at which an impact's launch failed (see `Verdict::NotLaunched`).
    not_launched: Option<f64>,
    /// The largest K whose release passed at B = 0, with its counts.
    best: Option<(f64, Vec<i64>)>,
}

impl Run<'_> {
    fn period_s(&self) -> f64 {
        self.p.period_s
    }

    fn natural_ticks(&self, k: f64) -> f64 {
        std::f64::consts::TAU * (self.p.mass / k).sqrt() / self.period_s()
    }

    fn ticks_for(&self, k: f64, thorough: bool, damped: bool) -> u32 {
        let fewest = if damped {
            DAMPED_TEST_MIN_TICKS
        } else {
            TEST_TICKS.0
        };
        let n = self.s.release_ticks.unwrap_or_else(|| {
            (TEST_NATURAL_PERIODS * self.natural_ticks(k)).clamp(fewest, TEST_TICKS.1) as u32
        });
        if thorough {
            n.saturating_mul(2)
        } else {
            n
        }
    }

    fn test(
        &self,
        c: &mut Client,
        base: &ServoConfig,
        k: f64,
        test: Test,
        thorough: bool,
    ) -> Result<(Verdict, Vec<i64>)> {
        run_test(
            c,
            base,
            k,
            test,
            self.ticks_for(k, thorough, base.damping > 0.0),
            min_settle_run(self.p.mass, k, self.period_s()),
        )
    }

    /// One search step at `k`: the full-energy release, and above `k_force` the impacts at v.
    fn step(
        &self,
        c: &mut Client,
        base: &ServoConfig,
        k: f64,
        thorough: bool,
        notes: &mut Notes,
    ) -> Result<Verdict> {
        let d = deflection_for(&self.p, k, self.v);
        let b = base.damping;
        (self.progress)(&format!("release test K={k:.4} B={b:.4} from {d} ticks"));
        let (verdict, counts) = self.test(
            c,
            base,
            k,
            Test::Release {
                deflection_ticks: d,
            },
            thorough,
        )?;
        if !verdict.passes() {
            return Ok(verdict);
        }
        // With a damper, every step also runs the impacts: the damper acts on the contact
        // speed, which a release from rest does not reach at the same energy.
        if k > self.k_force || base.damping > 0.0 {
            // Below k_force a damped step runs one side (the confirmation runs both).
            let dirs: &[f64] = if self.one_sided_wall || k <= self.k_force {
                &[1.0]
            } else {
                &[1.0, -1.0]
            };
            for &dir in dirs {
                let v_ticks = dir * self.v * self.period_s() / self.p.resolution;
                let test =
                    super::verify::impact(v_ticks, self.natural_ticks(k), self.one_sided_wall);
                let why = if k > self.k_force {
                    "force saturates"
                } else {
                    "damped wall"
                };
                (self.progress)(&format!("{} test K={k:.4} ({why})", test.describe()));
                let (impact, _) = self.test(c, base, k, test, thorough)?;
                if impact == Verdict::NotLaunched {
                    notes.not_launched.get_or_insert(k);
                } else if !impact.passes() {
                    return Ok(impact);
                }
            }
        }
        if base.damping == 0.0 && notes.best.as_ref().is_none_or(|(kb, _)| k > *kb) {
            notes.best = Some((k, counts));
        }
        Ok(verdict)
    }

    /// The whole verification set at `k` and the config `base` (its damping): whether every
    /// test passed, and the results up to the first failure.
    fn verify_set(
        &self,
        c: &mut Client,
        base: &ServoConfig,
        k: f64,
        thorough: bool,
        notes: &mut Notes,
    ) -> Result<(bool, Vec<TestResult>)> {
        let d = deflection_for(&self.p, k, self.v);
        (self.progress)(&format!(
            "verifying K={k:.4} B={:.4}: releases from ±{d} ticks and below, impacts",
            base.damping
        ));
        let v_ticks = self.v * self.period_s() / self.p.resolution;
        let mut set = test_set(
            d,
            v_ticks,
            self.natural_ticks(k),
            thorough,
            true,
            self.one_sided_wall,
        );
        // The tests most likely to fail first (impacts at v, then the full-energy releases),
        // so that a K that fails costs one or two tests, not the whole set.
        set.sort_by_key(|test| match *test {
            Test::Impact {
                velocity_milliticks,
                ..
            } if velocity_milliticks.unsigned_abs() >= (1000.0 * v_ticks) as u32 => 0,
            Test::Release { deflection_ticks } if deflection_ticks.abs() >= d.abs() => 1,
            _ => 2,
        });
        let mut results = Vec::new();
        for test in set {
            let (verdict, counts) = self.test(c, base, k, test, thorough)?;
            results.push(TestResult {
                test,
                k,
                verdict,
                ticks_judged: counts.len(),
            });
            if verdict == Verdict::NotLaunched {
                // Judged by the releases of the set, which reach the same energy from both
                // sides; reported by the caller.
                notes.not_launched.get_or_insert(k);
                continue;
            }
            if !verdict.passes() {
                (self.progress)(&format!(
                    "verification at K={k:.4}: {} {}; backing off ×{CONFIRM_BACKOFF}",
                    test.describe(),
                    verdict.describe()
                ));
                return Ok((false, results));
            }
        }
        Ok((true, results))
    }

    /// Confirms `k` with the verification set, backing off in steps of [`CONFIRM_BACKOFF`].
    /// After a confirmation failed, the first K that passes may sit right at the limit (it
    /// only lies between that failure and it): the K set is one more step down. That step is
    /// not verified again (it is 5 % below a K that passed the whole set; re-running the set
    /// would cost the real-time budget a third of its time). None: no K passed.
    fn confirm(
        &self,
        c: &mut Client,
        base: &ServoConfig,
        mut k: f64,
        thorough: bool,
        notes: &mut Notes,
    ) -> Result<Option<(f64, Vec<TestResult>)>> {
        let mut backed_off = false;
        for _ in 0..CONFIRM_TRIES {
            let (confirmed, results) = self.verify_set(c, base, k, thorough, notes)?;
            if confirmed {
                if backed_off {
                    k *= CONFIRM_BACKOFF;
                }
                return Ok(Some((k, results)));
            }
            backed_off = true;
            k *= CONFIRM_BACKOFF;
        }
        Ok(None)
    }
}

/// The wall chosen: stiffness, damping, the verification at it and the frontier tried.
struct Wall {
    k_set: f64,
    b_set: f64,
    /// The margin applied to the chosen wall's largest settling K.
    margin: f64,
    k_spring_only: f64,
    verification: Vec<TestResult>,
    frontier: Vec<FrontierPoint>,
}

/// Largest B the firmware accepts at the config's rate and coarsening, N·s/m: its limit
/// K_max(shift)·T/2 (`Board::max_damping`), a little inside for the f32 round trip.
fn b_cap(c: &Client, base: &ServoConfig, period_s: f64) -> f64 {
    let k_cap = f64::from(c.info.limits.max_stiffness) / f64::from(1u32 << base.coarsen_shift);
    0.999 * k_cap * period_s / 2.0
}

fn damped(base: &ServoConfig, b: f64) -> ServoConfig {
    ServoConfig {
        damping: b as f32,
        ..*base
    }
}

/// The largest settling K at damping `b`: from `start` down by [`FRONTIER_STEP`] until a step
/// passes, then up and bisected ([`FRONTIER_REL_TOL`]); None when no K above `floor` passes.
#[allow(clippy::too_many_arguments)]
fn search_at(
    run: &Run<'_>,
    c: &mut Client,
    base: &ServoConfig,
    b: f64,
    start: f64,
    floor: f64,
    search: &Search,
    thorough: bool,
    notes: &mut Notes,
) -> Result<Option<Found>> {
    let cfg = damped(base, b);
    // Verdicts already measured, looked up by K (the bracketing revisits the K it came down
    // from).
    let mut seen: Vec<(f64, Verdict)> = Vec::new();
    let mut k = start;
    loop {
        let v = run.step(c, &cfg, k, thorough, notes)?;
        seen.push((k, v));
        if v.passes() {
            break;
        }
        k /= FRONTIER_STEP;
        if k < floor {
            return Ok(None);
        }
    }
    let search = Search {
        step: FRONTIER_STEP,
        rel_tol: search.rel_tol.max(FRONTIER_REL_TOL),
        ..*search
    };
    largest_settling_k(k, &search, |k| {
        match seen.iter().find(|(k0, _)| (k / k0 - 1.0).abs() < 1e-9) {
            Some(&(_, v)) => Ok(v),
            None => run.step(c, &cfg, k, thorough, notes),
        }
    })
    .map(Some)
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

/// The damping levels of [`DAMPING_BETAS`] within the firmware's limit `cap`, with their
/// predicted K, stiffest first; only those predicted to gain [`DAMPING_MIN_GAIN`] over `k0`.
fn predicted_frontier(run: &Run<'_>, k0: f64, cap: f64) -> Vec<(f64, f64)> {
    let mut levels: Vec<(f64, f64)> = DAMPING_BETAS
        .iter()
        .map(|beta| beta * k0 * run.period_s())
        .filter(|&b| b <= cap)
        .filter_map(|b| predicted_k(run, k0, b).map(|k| (b, k)))
        .filter(|&(_, k)| k > k0 * (1.0 + DAMPING_MIN_GAIN))
        .collect();
    levels.sort_by(|a, b| b.1.total_cmp(&a.1));
    levels
}

/// Chooses the wall after the spring-only search `found`: spring only, a fixed B, or the
/// stiffest verified pair of the frontier ([`DAMPING_BETAS`]); the chosen pair is confirmed
/// with the whole verification set, the spring only is the fallback of the search.
#[allow(clippy::too_many_arguments)]
fn choose_wall(
    run: &Run<'_>,
    c: &mut Client,
    base: &ServoConfig,
    found: &Found,
    search: &Search,
    thorough: bool,
    margin: f64,
    notes: &mut Notes,
) -> Result<Wall> {
    let k_spring = found.k_pass * margin;
    let mut frontier = vec![FrontierPoint {
        b: 0.0,
        k_verified: Some(found.k_pass),
    }];
    let cap = b_cap(c, base, run.period_s());
    let mut best = (0.0, found.k_pass);
    match run.s.damping {
        Damping::Fixed(b) if b > 0.0 => {
            let start = predicted_k(run, found.k_pass, b).map_or(found.k_pass, |k| {
                (k * FRONTIER_START).clamp(found.k_pass * 1e-3, search.k_cap)
            });
            let floor = found.k_pass * 1e-3;
            let f = search_at(run, c, base, b, start, floor, search, thorough, notes)?;
            let Some(f) = f else {
                bail!("no stiffness down to {floor:.4e} settles at the fixed damping B = {b:.4e}");
            };
            frontier.push(FrontierPoint {
                b,
                k_verified: Some(f.k_pass),
            });
            best = (b, f.k_pass);
        }
        Damping::Fixed(_) => {}
        Damping::Search => {
            let floor = found.k_pass * (1.0 + DAMPING_MIN_GAIN);
            for (b, k_pred) in predicted_frontier(run, found.k_pass, cap)
                .into_iter()
                .take(FRONTIER_TRIES)
            {
                (run.progress)(&format!(
                    "damping B = {b:.4e}: predicted K {k_pred:.4}, searching from {:.4}",
                    (k_pred * FRONTIER_START).max(floor)
                ));
                let start = (k_pred * FRONTIER_START).clamp(floor, search.k_cap);
                let f = search_at(run, c, base, b, start, floor, search, thorough, notes)?;
                let k = f.map(|f| f.k_pass).filter(|&k| k >= floor);
                frontier.push(FrontierPoint { b, k_verified: k });
                if let Some(k) = k {
                    best = (b, k);
                    break;
                }
            }
        }
    }
    if best.0 > 0.0 {
        let cfg = damped(base, best.0);
        if let Some((k_set, verification)) =
            run.confirm(c, &cfg, best.1 * margin.min(DAMPED_MARGIN), thorough, notes)?
        {
            return Ok(Wall {
                k_set,
                b_set: best.0,
                margin: margin.min(DAMPED_MARGIN),
                k_spring_only: k_spring,
                verification,
                frontier,
            });
        }
        if let Damping::Fixed(b) = run.s.damping {
            bail!("no stiffness passed the verification set at the fixed damping B = {b:.4e}");
        }
        (run.progress)(&format!(
            "no K passed the verification set at B = {:.4e}; setting the spring-only wall",
            best.0
        ));
    }
    let Some((k_set, verification)) = run.confirm(c, base, k_spring, thorough, notes)? else {
        bail!(
            "no stiffness passed the verification set (last tried {:.4})",
            k_spring * CONFIRM_BACKOFF.powi(CONFIRM_TRIES as i32)
        );
    };
    Ok(Wall {
        k_set,
        b_set: 0.0,
        margin,
        k_spring_only: k_set,
        verification,
        frontier,
    })
}

fn tune_inner(
    c: &mut Client,
    s: &Settings,
    original: &ServoConfig,
    dry_run: bool,
    progress: &dyn Fn(&str),
) -> Result<Outcome> {
    let (res, t) = device_scale(c)?;
    // Experiments run with the wall off between them, without extra damping and with the
    // energy monitor on, whatever the user's config; the servo rate, delay and coarsening stay
    // as configured.
    let base = ServoConfig {
        damping: 0.0,
        energy_monitor: true,
        stiffness: 0.0,
        ..*original
    };
    super::verify::clear_faults(c)?;
    c.set_config(&base)?;
    let (id, amplitude, _) = identify(c, &base, s, progress)?;
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
    breakaway(c, &base, &id, rest, &mut evidence, progress)?;
    let delta = res * f64::from(1u32 << base.coarsen_shift);
    let rotational = c.info.counts_per_rev > 0;
    let mut p = PhysicalParams {
        mass: id.mass,
        viscous: id.viscous.max(0.0),
        coulomb: id.coulomb.max(0.0),
        resolution: delta,
        period_s: t,
        stiffness: 1.0,
        delay_s: f64::from(base.extra_delay_ticks) * t,
        rotational,
    };
    let v = s.max_velocity.unwrap_or(DEFAULT_XIDOT * delta / t);
    let predicted = predict(&p, v)?;
    progress(&format!(
        "identified m={:.3e} b={:.3e} c={:.3e}; K guaranteed {:.4} expected {:.4}",
        id.mass, id.viscous, id.coulomb, predicted.guaranteed, predicted.expected
    ));
    let units = if rotational {
        ("N·m", "N·m/rad")
    } else {
        ("N", "N/m")
    };
    let early = model_check::findings(&id, &evidence, units);
    // Force regime: above k_force the wall's peak force at v, K·Δ·(d + ½) with
    // d = v√(m/K)/Δ, i.e. about v√(mK), exceeds the force limit and the firmware saturates it.
    // A full-energy release then no longer stores the impact's energy, so above k_force each
    // search step also runs what saturates first in use: an impact at v from each side.
    let f_lim = f64::from(base.force_limit);
    let run = Run {
        s,
        p,
        v,
        k_force: (f_lim / (v * id.mass.sqrt())).powi(2),
        one_sided_wall: original.wall == stiffwall_proto::WallMode::OneSided,
        progress,
    };
    let search = Search {
        k_cap: f64::from(c.info.limits.max_stiffness),
        rel_tol: s.rel_tol,
        ..Search::default()
    };
    let start = predicted
        .expected
        .min(search.k_cap)
        .max(predicted.guaranteed.min(search.k_cap) * 0.5);
    let thorough_search = !early.is_empty();
    let mut notes = Notes::default();
    let found = largest_settling_k(start, &search, |k| {
        run.step(c, &base, k, thorough_search, &mut notes)
    })?;
    if let Some((k, counts)) = &notes.best {
        evidence.release_k = Some(*k);
        evidence.release_hz = model_check::release_frequency_hz(counts, t, 12);
        evidence.model_hz = Some((k / id.mass).sqrt() / std::f64::consts::TAU);
    }
    let mut model_mismatch = model_check::findings(&id, &evidence, units);
    // Only a search that found a failing K measured the limit (otherwise the force cap did).
    if found.k_fail.is_some() {
        model_mismatch.extend(model_check::prediction_finding(
            found.k_pass,
            predicted.expected,
        ));
    }
    // An impact the search could not launch was judged by releases only: the search's
    // largest K is then less well tested, so the mismatch margin applies as well.
    let thorough = !model_mismatch.is_empty() || notes.not_launched.is_some();
    for f in &model_mismatch {
        progress(&format!("model mismatch: {f}"));
    }
    let margin_used = s.margin
        * if !thorough {
            1.0
        } else if notes.not_launched.is_none() && model_check::dynamics_fit(&id, &evidence) {
            FRICTION_MISMATCH_MARGIN
        } else {
            MISMATCH_MARGIN
        };
    let wall = choose_wall(
        &run,
        c,
        &base,
        &found,
        &search,
        thorough,
        margin_used,
        &mut notes,
    )?;
    if let Some(k) = notes.not_launched {
        let finding = not_launched_finding(k, id.mass, t);
        progress(&format!("model mismatch: {finding}"));
        model_mismatch.push(finding);
    }
    p.stiffness = wall.k_set;
    let mut saved = false;
    if !dry_run {
        c.clear_faults().ok();
        c.set_config(&ServoConfig {
            stiffness: wall.k_set as f32,
            damping: wall.b_set as f32,
            ..*original
        })?;
        c.save_config().context("saving the tuned config")?;
        saved = true;
    }
    Ok(Outcome {
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
        xidot: v * t / delta,
        predicted,
        search: found,
        k_set: wall.k_set,
        b_set: wall.b_set,
        k_spring_only: wall.k_spring_only,
        frontier: wall.frontier,
        confirmation: wall.verification.iter().map(|r| r.verdict).collect(),
        verification: wall.verification,
        model_mismatch,
        model_evidence: evidence,
        margin_used: wall.margin,
        saved,
    })
}

fn not_launched_finding(k: f64, mass: f64, t: f64) -> String {
    let mu = mass / (k * t * t);
    format!(
        "at K = {k:.4} the firmware's impact launch (a hold moving at the requested speed, with \
         damping β = {}) did not \
         bring the device to the wall at the requested speed (μ = m/(KT²) = {mu:.3}; the \
         hold oscillates when μ is small, e.g. a light device on a slow servo), and the \
         impact failed; those impacts were judged by the releases of the same energy \
         from both sides",
        stiffwall_firmware::config::HOLD_BETA
    )
}
