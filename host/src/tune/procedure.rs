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
use crate::device::client::Client;
use anyhow::{bail, Context, Result};
use stiffwall_core::params::PhysicalParams;
use stiffwall_proto::ServoConfig;

/// Default maximum velocity, in encoder ticks per servo period (ξ̇ of Table I; independent of K).
pub const DEFAULT_XIDOT: f64 = 5.0;

/// Factor applied to K when a test of the verification set fails.
pub const CONFIRM_BACKOFF: f64 = 0.95;

/// Factor applied to the margin when the model does not fit the device.
pub const MISMATCH_MARGIN: f64 = 0.85;
/// Factor applied to the margin instead of [`MISMATCH_MARGIN`] when the only mismatch is the
/// friction (breakaway above sliding: static friction or a dead band) or the verified K below
/// the prediction, the identified dynamics fitting ([`model_check::dynamics_fit`]) and every
/// impact launched: static friction dissipates, and the release tests run at the energy asked
/// for (re-aimed where the hold stuck off target), so the verified K is the device's own.
pub const FRICTION_MISMATCH_MARGIN: f64 = 0.9;

/// Duration of each breakaway ramp, s.
pub const RAMP_SECONDS: f64 = 0.3;

/// Step 1, identification with the wall off (in [`super::excite`]).
pub use super::excite::identify;
/// Set by the Ctrl-C handler; checked between experiments (the one flag of every session).
pub use crate::session::INTERRUPTED;

/// Tune settings.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Expected maximum velocity, m/s (rad/s); None = [`DEFAULT_XIDOT`] ticks per period.
    pub max_velocity: Option<f64>,
    /// Fraction of the largest settling K that is set, in (0, 1].
    pub margin: f64,
    /// Ticks per release test; None = 60 natural periods (at least 1500, at most 30000).
    pub release_ticks: Option<u32>,
    /// Duration of the identification chirp, s.
    pub excite_seconds: f64,
    /// Relative tolerance of the K bisection.
    pub rel_tol: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            max_velocity: None,
            margin: 0.9,
            release_ticks: None,
            excite_seconds: 3.0,
            rel_tol: 0.02,
        }
    }
}

/// Predicted stiffness limits, N/m (N·m/rad).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Predicted {
    /// Region A (passive) limit, (17)–(18).
    pub passive: f64,
    /// Worst-case guaranteed limit at v: (12), or (19) with delay.
    pub guaranteed: f64,
    /// Expected limit: exact sampled linear boundary with Coulomb as DF damping at v.
    pub expected: f64,
    /// The paper's describing-function approximation (74) at v (ZOH as a ½-period delay).
    pub expected_paper_74: f64,
}

/// Everything `tune` found.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Outcome {
    /// Identified parameters.
    pub identified: IdentifiedReport,
    /// Device model used for predictions (K = the set value).
    pub params: PhysicalParams,
    /// Maximum velocity used, m/s (rad/s).
    pub max_velocity: f64,
    /// Same, ticks per period.
    pub xidot: f64,
    /// Predictions.
    pub predicted: Predicted,
    /// The release-test search.
    pub search: Found,
    /// The stiffness set.
    pub k_set: f64,
    /// Verdicts of the verification set at `k_set` (in the order of `verification`).
    pub confirmation: Vec<Verdict>,
    /// The verification set at `k_set`, test by test.
    pub verification: Vec<TestResult>,
    /// Where the identified model does not describe the device (plain language; empty when
    /// it does).
    pub model_mismatch: Vec<String>,
    /// What the model checks measured.
    pub model_evidence: Evidence,
    /// Margin applied (the requested one, times [`MISMATCH_MARGIN`] on a mismatch).
    pub margin_used: f64,
    /// Whether the config was saved.
    pub saved: bool,
}

/// Identified parameters as reported.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct IdentifiedReport {
    /// m and its standard error.
    pub mass: [f64; 2],
    /// b and its standard error.
    pub viscous: [f64; 2],
    /// Upper bound on b (estimate + 2 s.e.), meaningful when b is only bounded.
    pub viscous_upper_bound: f64,
    /// Whether b is indistinguishable from 0.
    pub viscous_only_bounded: bool,
    /// c and its standard error.
    pub coulomb: [f64; 2],
    /// Integrated equations used.
    pub equations: usize,
    /// Chirp amplitude used, output codes.
    pub excite_amplitude_codes: i32,
    /// Stiffness of a spring-like force beside the rigid model (a hand, a cable) and its
    /// standard error, N/m (N·m/rad); None when none was resolved.
    pub spring: Option<[f64; 2]>,
}

pub(super) fn check_interrupt() -> Result<()> {
    if crate::session::interrupted() {
        bail!("interrupted");
    }
    Ok(())
}

/// Step 2: predictions for the identified device.
pub fn predict(p: &PhysicalParams, v: f64) -> Result<Predicted> {
    use stiffwall_core::{criteria, limits};
    let passive = limits::k_max_passive(p)?;
    let guaranteed = if p.delay_s > 0.0 {
        limits::k_max_delayed_harmonic(p, v)?
    } else {
        limits::k_max_at_velocity(p, v)?
    };
    let equivalent = PhysicalParams {
        viscous: p.viscous + 4.0 * p.coulomb / (std::f64::consts::PI * v),
        ..*p
    };
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
    if !(s.margin.is_finite() && s.margin > 0.0 && s.margin <= 1.0) {
        bail!("--margin must be in (0, 1] (got {})", s.margin);
    }
    if let Some(v) = s.max_velocity {
        if !(v.is_finite() && v > 0.0) {
            bail!("--max-velocity must be finite and > 0 (got {v})");
        }
    }
    let original = c.get_config()?;
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
    let k_force = (f_lim / (v * id.mass.sqrt())).powi(2);
    let k_cap = f64::from(c.info.limits.max_stiffness);
    let one_sided_wall = original.wall == stiffwall_proto::WallMode::OneSided;
    let ticks_for = |k: f64, thorough: bool| {
        let n = s.release_ticks.unwrap_or_else(|| {
            let natural = std::f64::consts::TAU * (id.mass / k).sqrt() / t;
            (60.0 * natural).clamp(1500.0, 30_000.0) as u32
        });
        if thorough {
            n.saturating_mul(2)
        } else {
            n
        }
    };
    let search = Search {
        k_cap,
        rel_tol: s.rel_tol,
        ..Search::default()
    };
    let start = predicted
        .expected
        .min(k_cap)
        .max(predicted.guaranteed.min(k_cap) * 0.5);
    let thorough_search = !early.is_empty();
    // The smallest K at which an impact's launch failed (see `Verdict::NotLaunched`).
    let mut not_launched: Option<f64> = None;
    let mut best: Option<(f64, Vec<i64>)> = None;
    let found = largest_settling_k(start, &search, |k| {
        let d = deflection_for(&p, k, v);
        progress(&format!("release test K={k:.4} from {d} ticks"));
        let (verdict, counts) = run_test(
            c,
            &base,
            k,
            Test::Release {
                deflection_ticks: d,
            },
            ticks_for(k, thorough_search),
            min_settle_run(id.mass, k, t),
        )?;
        if !verdict.passes() {
            return Ok(verdict);
        }
        if k > k_force {
            let natural_ticks = std::f64::consts::TAU * (id.mass / k).sqrt() / t;
            let dirs: &[f64] = if one_sided_wall { &[1.0] } else { &[1.0, -1.0] };
            for &dir in dirs {
                let test =
                    super::verify::impact(dir * v * t / delta, natural_ticks, one_sided_wall);
                progress(&format!(
                    "{} test K={k:.4} (force saturates)",
                    test.describe()
                ));
                let (impact, _) = run_test(
                    c,
                    &base,
                    k,
                    test,
                    ticks_for(k, thorough_search),
                    min_settle_run(id.mass, k, t),
                )?;
                if impact == Verdict::NotLaunched {
                    not_launched.get_or_insert(k);
                } else if !impact.passes() {
                    return Ok(impact);
                }
            }
        }
        if best.as_ref().is_none_or(|(kb, _)| k > *kb) {
            best = Some((k, counts));
        }
        Ok(verdict)
    })?;
    if let Some((k, counts)) = &best {
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
    let thorough = !model_mismatch.is_empty() || not_launched.is_some();
    for f in &model_mismatch {
        progress(&format!("model mismatch: {f}"));
    }
    let margin_used = s.margin
        * if !thorough {
            1.0
        } else if not_launched.is_none() && model_check::dynamics_fit(&id, &evidence) {
            FRICTION_MISMATCH_MARGIN
        } else {
            MISMATCH_MARGIN
        };
    let mut k_set = found.k_pass * margin_used;
    let mut verification = Vec::new();
    // A failing test backs off in steps of CONFIRM_BACKOFF (finer than the margin).
    // After a confirmation failed, the first K that passes may sit right at the limit (it
    // only lies between that failure and it): the K set is one more step down. That step is
    // not verified again (it is 5 % below a K that passed the whole set; re-running the set
    // would cost the real-time budget a third of its time).
    let (mut backed_off, mut accepted) = (false, false);
    for _ in 0..8 {
        let d = deflection_for(&p, k_set, v);
        progress(&format!(
            "verifying K={k_set:.4}: releases from ±{d} ticks and below, impacts"
        ));
        verification.clear();
        let mut confirmed = true;
        let natural_ticks = std::f64::consts::TAU * (id.mass / k_set).sqrt() / t;
        let mut set = test_set(
            d,
            v * t / delta,
            natural_ticks,
            thorough,
            true,
            one_sided_wall,
        );
        // The tests most likely to fail first (impacts at v, then the full-energy releases),
        // so that a K that fails costs one or two tests, not the whole set.
        set.sort_by_key(|test| match *test {
            Test::Impact {
                velocity_milliticks,
                ..
            } if velocity_milliticks.unsigned_abs() >= (1000.0 * v * t / delta) as u32 => 0,
            Test::Release { deflection_ticks } if deflection_ticks.abs() >= d.abs() => 1,
            _ => 2,
        });
        for test in set {
            let (verdict, counts) = run_test(
                c,
                &base,
                k_set,
                test,
                ticks_for(k_set, thorough),
                min_settle_run(id.mass, k_set, t),
            )?;
            verification.push(TestResult {
                test,
                k: k_set,
                verdict,
                ticks_judged: counts.len(),
            });
            if verdict == Verdict::NotLaunched {
                // Judged by the releases of the set, which reach the same energy from both
                // sides; reported below.
                not_launched.get_or_insert(k_set);
                continue;
            }
            if !verdict.passes() {
                progress(&format!(
                    "verification at K={k_set:.4}: {} {}; backing off ×{CONFIRM_BACKOFF}",
                    test.describe(),
                    verdict.describe()
                ));
                confirmed = false;
                break;
            }
        }
        if confirmed {
            if backed_off {
                k_set *= CONFIRM_BACKOFF;
            }
            accepted = true;
            break;
        }
        backed_off = true;
        k_set *= CONFIRM_BACKOFF;
    }
    if !accepted {
        bail!("no stiffness passed the verification set (last tried {k_set:.4})");
    }
    if let Some(k) = not_launched {
        let mu = id.mass / (k * t * t);
        let finding = format!(
            "at K = {k:.4} the firmware's impact launch (a hold with damping β = {}) did not \
             bring the device to the wall at the requested speed (μ = m/(KT²) = {mu:.3}; the \
             hold oscillates when μ is small, e.g. a light device on a slow servo), and the \
             impact failed; those impacts were judged by the releases of the same energy \
             from both sides",
            stiffwall_firmware::config::HOLD_BETA
        );
        progress(&format!("model mismatch: {finding}"));
        model_mismatch.push(finding);
    }
    p.stiffness = k_set;
    let mut saved = false;
    if !dry_run {
        c.clear_faults().ok();
        c.set_config(&ServoConfig {
            stiffness: k_set as f32,
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
        k_set,
        confirmation: verification.iter().map(|r| r.verdict).collect(),
        verification,
        model_mismatch,
        model_evidence: evidence,
        margin_used,
        saved,
    })
}
