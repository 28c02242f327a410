//! Verification of a stiffness on the device: one test run (the tests are `test_set`'s), its
//! early end and its judgement.
//!
//! Each test starts from a reproducible state: the wall off until the device has stopped, the
//! wall position moved to where it stopped (so the wall's force while the hold starts is the
//! smallest, KΔ/2), faults cleared, then the release. The device runs the test with the wall
//! under test from its first tick only and ends it itself, on the tick its counts decide it
//! ([`judged_len_within`]'s rule, sent as
//! [`HostMsg::PrepareTest`](stiffwall_proto::HostMsg::PrepareTest)), back at the wall-off
//! config on that tick: neither the verdict nor the next test's start depends on how quickly
//! the host reacts. A test still oscillating at its base length whose oscillation
//! still shrinks runs on, up to [`DECAY_EXTENSION`] × (see [`judged_len`]): a slow mode the
//! encoder sees (a heavy hand ringing on a soft transmission) is not judged a buzz while it
//! decays, and a persistent buzz is still judged at the base length.

use super::error::{bail, Result};
use super::judged::{judged_len_within, max_test_len};
use super::launch::{judge_impact, Delivered, LAUNCH_REAIMS};
use super::reaim::{reaim, short_of, HOLD_REAIMS};
pub use super::rest::{clear_faults, rest_position};
use super::test_set::Test;
use super::verdict::{classify, Criterion, Verdict, Wall, MIN_TAIL};
use stiffwall_client::Client;
use stiffwall_proto::{ServoConfig, WallMode};

/// A test with its stiffness and verdict.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TestResult {
    /// The test.
    pub test: Test,
    /// Stiffness tested.
    pub k: f64,
    /// Verdict.
    pub verdict: Verdict,
    /// Ticks judged (after the release).
    pub ticks_judged: usize,
    /// A test that kept toggling within one count: how fast and how hard.
    pub chatter: Option<ChatterReport>,
}

/// How a test is judged and how its chatter is measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Judging {
    /// What passes.
    pub criterion: Criterion,
    /// Servo period T, s.
    pub period_s: f64,
    /// Force of one output code, N (N·m).
    pub force_per_code: f64,
    /// The identified Coulomb friction c, N (N·m): the unit of the chatter's force swing.
    pub coulomb_n: f64,
    /// Damping of the wall-off config each test starts from and the firmware returns to on
    /// the tick the test ends (dead band of one count, so it never acts on a device at rest),
    /// N·s/m (N·m·s/rad), ≥ 0; 0: none, the device coasts. A test whose wall grew ends with
    /// the device moving fast: without a brake an unbounded device of little friction coasted
    /// on for metres (omega-one-sided-delay, 1.3 m past a default window of ±50 mm).
    pub brake_damping: f64,
    /// Travel window, raw counts [min, max], each test's config carries when the base config
    /// has none (tune's default window: a device whose travel nobody stated); leaving it trips
    /// the supervisor, whose safe mode is the brake. None: the base config's own.
    pub window: Option<(i32, i32)>,
}

/// The chatter of a test that kept toggling within one count, over its judged tail
/// (`stiffwall_core::rest::Chatter`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChatterReport {
    /// Count changes per second.
    pub toggles_per_s: f64,
    /// Peak-to-peak force output, N (N·m).
    pub force_pp_n: f64,
    /// The same in units of the identified Coulomb friction c.
    pub force_pp_c: f64,
}

impl ChatterReport {
    /// One line for a report.
    #[must_use]
    pub fn describe(&self, force_unit: &str) -> String {
        format!(
            "{:.0} toggles/s, force swing {:.3e} {force_unit} peak to peak ({:.1} × c)",
            self.toggles_per_s, self.force_pp_n, self.force_pp_c
        )
    }
}

/// The firmware's longest hold before a release or launch, s (`experiment::Hold`: it
/// releases after 2 s whether or not the device came to rest).
pub const HOLD_LONGEST_S: f64 = 2.0;

/// Seconds of the record's hold and launch (samples flagged `HOLD`), by their ticks.
fn held_s(samples: &[stiffwall_proto::Sample], period_s: f64) -> f64 {
    let mut held = samples
        .iter()
        .filter(|x| x.flags & stiffwall_proto::flags::HOLD != 0);
    let (Some(first), Some(last)) = (held.next(), held.next_back()) else {
        return 0.0;
    };
    f64::from(last.tick.wrapping_sub(first.tick).wrapping_add(1)) * period_s
}

/// One test's outcome: the verdict, the counts judged and, for an impact, what its launch
/// delivered.
#[derive(Debug, Clone)]
pub struct TestRun {
    /// Verdict.
    pub verdict: Verdict,
    /// Counts judged (after the release or from contact).
    pub counts: Vec<i64>,
    /// An impact's launch at contact (None for a release, or an impact that never arrived).
    pub delivered: Option<Delivered>,
    /// The supervisor tripped before the release or contact (during the hold or launch): the
    /// record holds no motion of the wall under test.
    pub hold_tripped: bool,
    /// The hold before the release or launch ran the firmware's longest hold
    /// ([`HOLD_LONGEST_S`]) or more: it never came to rest at its target.
    pub hold_timed_out: bool,
    /// A test that kept toggling within one count: how fast and how hard.
    pub chatter: Option<ChatterReport>,
}

/// Runs one test at stiffness `k` (config `base` with that K) for a base length of `ticks`
/// ticks after the release, longer while its oscillation still decays (at most
/// `max_test_len`); the record ends at `judged_len` (settled: run `min_run`). A release
/// whose hold stopped off target is re-aimed (`reaim`, at most `HOLD_REAIMS` times); an
/// impact whose launch arrived too fast and failed is re-aimed at a launch speed that should
/// deliver the asked one ([`Delivered::reaimed`], at most `LAUNCH_REAIMS` times). The last
/// attempt's outcome is the test's, but for a release that passed only from short of its
/// deflection after an attempt failed from farther: that failure stands (see `run_release`).
pub fn run_test(
    c: &mut Client,
    base: &ServoConfig,
    k: f64,
    test: Test,
    ticks: u32,
    min_run: usize,
    judging: &Judging,
) -> Result<TestRun> {
    run_test_at(c, base, k, test, (ticks, min_run), judging, None)
}

/// [`run_test`] (its `ticks` and `min_run` as a pair) for a device known to rest at `rest`
/// (counts of `base`'s wall frame) under the wall-off brake of a test's start
/// (`travel::recentre` just read it there): the first attempt's config takes that rest instead
/// of waiting for rest again (about 0.1 s of device time a test); a fault latched since, or a
/// later attempt, reads it afresh.
pub(crate) fn run_test_at(
    c: &mut Client,
    base: &ServoConfig,
    k: f64,
    test: Test,
    (ticks, min_run): (u32, usize),
    judging: &Judging,
    rest: Option<i32>,
) -> Result<TestRun> {
    let run = Attempt {
        base,
        k,
        ticks,
        min_run,
        judging,
        rest_hint: std::cell::Cell::new(rest),
    };
    run_attempts(c, &run, test)
}

/// The attempts of one test (module docs of [`run_test`]).
fn run_attempts(c: &mut Client, run: &Attempt<'_>, test: Test) -> Result<TestRun> {
    match test {
        Test::Release { deflection_ticks } => run_release(c, run, deflection_ticks),
        Test::Impact {
            start_ticks,
            velocity_milliticks,
            one_sided,
        } => {
            let mut result = run.once(c, test, None)?;
            let mut milli = velocity_milliticks;
            for _ in 0..LAUNCH_REAIMS {
                // A hold that never came to rest at the start oscillates at this K whatever
                // the launch speed: a re-aimed launch starts from the same motion (seen on
                // maxon-re35 at its quiet ceiling: three launches of 2.6 s each, all too fast).
                if result.verdict.passes() || result.hold_timed_out {
                    break;
                }
                let Some(next) = result.delivered.and_then(|d| d.reaimed(milli)) else {
                    break;
                };
                milli = next;
                let aimed = Test::Impact {
                    start_ticks,
                    velocity_milliticks: milli,
                    one_sided,
                };
                // Judged against the speed the test asks for, not the re-aimed launch's.
                let asked = f64::from(velocity_milliticks).abs() / 1000.0;
                let again = run.once(c, aimed, Some(asked))?;
                result = again;
            }
            Ok(result)
        }
    }
}

/// [`run_test`] for a release from `deflection_ticks`: re-aimed while its hold stops off
/// target ([`reaim`]). When the last attempt passed from short of the deflection asked (by
/// more than [`reaim`]'s tolerance: stuck on the way, or re-aimed nearer after a failure from
/// farther) and an earlier attempt failed from farther than asked, the failure stands: the
/// wall failed at a higher energy and no attempt showed it holding the energy asked for (seen
/// on a light rotor behind two ticks of delay with static friction 1.9 × Coulomb: the hold
/// rang out to 54 ticks for 9 asked and failed; re-aimed at 1 tick, it stuck at the wall and
/// "passed" at every K, while the brute force fails the release from 9 above 0.4 K of that).
/// A pass from short of the target on the first attempt stays a pass only when re-aiming
/// cannot help: a hold that could not move the device off the wall (start 0) pulled with the
/// wall's force at the deflection asked, which static friction held.
fn run_release(c: &mut Client, run: &Attempt<'_>, deflection_ticks: i32) -> Result<TestRun> {
    let test = Test::Release { deflection_ticks };
    let mut target = deflection_ticks;
    let mut result = run.once(c, test, None)?;
    let mut failed_farther: Option<TestRun> = None;
    for _ in 0..HOLD_REAIMS {
        let Some(start) = result.counts.first().copied() else {
            break;
        };
        let passes = result.verdict.passes();
        let Some(next) = reaim(deflection_ticks, target, start, passes) else {
            break;
        };
        if !passes {
            failed_farther = Some(result.clone());
        }
        target = next;
        let aimed = Test::Release {
            deflection_ticks: target,
        };
        let again = run.once(c, aimed, None)?;
        if again.hold_tripped {
            // The hold's own step to the farther target tripped the supervisor (its
            // overshoot, not the wall, ran faster than the encoder-jump or velocity
            // limit: a damped wall's hold on a light device): no release was run, so
            // nothing was learnt about the wall; the first attempt's outcome stands.
            break;
        }
        result = again;
    }
    Ok(release_outcome(deflection_ticks, result, failed_farther))
}

/// The outcome of a release asked from `requested` ticks whose last attempt was `last`:
/// `failed_farther` (an earlier attempt that failed from farther than asked) when `last`
/// passed only from short of the deflection ([`short_of`]), else `last`.
#[must_use]
pub fn release_outcome(requested: i32, last: TestRun, failed_farther: Option<TestRun>) -> TestRun {
    let short = last
        .counts
        .first()
        .is_some_and(|&start| short_of(requested, start));
    match failed_farther {
        Some(failure) if last.verdict.passes() && short => failure,
        _ => last,
    }
}

/// One test's settings: the wall under test, its length and how it is judged.
struct Attempt<'a> {
    base: &'a ServoConfig,
    k: f64,
    ticks: u32,
    min_run: usize,
    judging: &'a Judging,
    /// Where the device rests under the test's start brake, known before the first attempt
    /// (taken by it); None: read it.
    rest_hint: std::cell::Cell<Option<i32>>,
}

impl Attempt<'_> {
    /// One attempt at `test`, an impact judged against the speed `asked` (counts per tick;
    /// None: its own).
    fn once(&self, c: &mut Client, test: Test, asked: Option<f64>) -> Result<TestRun> {
        super::settings::check_cancel(c)?;
        let cfg = self.test_config(c, test)?;
        clear_faults(c)?;
        // A test ends when its wall has come to rest ([`settled_within`]: the last third of
        // the record at one count), or within one count only when chatter is accepted
        // (`Criterion::AcceptChatter`). The device runs the test with the wall under test
        // from its first tick, ends it on the tick its counts decide it
        // ([`judged_len_within`]'s rule, `PrepareTest`), and is back at the wall-off config on
        // that tick: neither where a test starts or ends nor the state it leaves for the next
        // one depends on the link's latency, so `--fast` and real time run the same tests,
        // count for count. The host never stops a test.
        let one_count = self.judging.criterion == Criterion::AcceptChatter;
        c.prepare_test(
            &cfg,
            u32::try_from(self.min_run).unwrap_or(u32::MAX),
            one_count,
            self.ticks.max(1),
        )?;
        let budget = u32::try_from(max_test_len(self.ticks as usize)).unwrap_or(u32::MAX);
        let Some(rec) = record(c, test, budget)? else {
            // The wall at (K, B) tripped the supervisor at rest, before the test could start
            // (a damper too strong for the device's mass: B·T/m large): the wall is not
            // stable, which is this test's verdict; the next test clears the faults.
            return Ok(TestRun {
                verdict: Verdict::Growing,
                counts: Vec::new(),
                delivered: None,
                hold_tripped: true,
                hold_timed_out: false,
                chatter: None,
            });
        };
        let judged = Judged {
            ticks: self.ticks as usize,
            min_run: self.min_run,
            budget: budget as usize,
            judging: *self.judging,
            shift: self.base.coarsen_shift,
        };
        Ok(judged.judge(test, &rec, asked))
    }

    /// The config the device runs `test` with: the wall under test at this K from a braked
    /// start ([`wall_under_test`]), inside the tests' travel window when the config has none
    /// ([`Judging::window`]), and a one-sided impact's window ended on its free side
    /// ([`free_side_window`]).
    fn test_config(&self, c: &mut Client, test: Test) -> Result<ServoConfig> {
        let cfg = wall_under_test(
            c,
            self.base,
            self.k,
            test,
            self.judging.brake_damping,
            self.rest_hint.take(),
        )?;
        let cfg = match self.judging.window {
            Some((lo, hi)) if cfg.travel_min.is_none() && cfg.travel_max.is_none() => ServoConfig {
                travel_min: Some(lo),
                travel_max: Some(hi),
                ..cfg
            },
            _ => cfg,
        };
        Ok(free_side_window(cfg, test))
    }
}

/// The record of `test` (prepared on the device) for at most `budget` ticks after its release
/// or contact; None when the supervisor tripped before the test could start (faults latched);
/// an error when telemetry was lost.
fn record(c: &mut Client, test: Test, budget: u32) -> Result<Option<stiffwall_client::Record>> {
    let mut enough = |_: &[stiffwall_proto::Sample]| false;
    let rec = match test {
        Test::Release { deflection_ticks } => {
            c.release_until(deflection_ticks, budget, &mut enough)
        }
        Test::Impact {
            start_ticks,
            velocity_milliticks,
            ..
        } => c.impact_until(start_ticks, velocity_milliticks, budget, &mut enough),
    };
    let rec = match rec {
        Ok(rec) => rec,
        Err(_) if c.faults().is_ok_and(|f| f.latched != 0) => return Ok(None),
        Err(e) => return Err(e.into()),
    };
    if rec.gaps.missing > 0 {
        bail!(
            "{} telemetry samples lost during a wall test",
            rec.gaps.missing
        );
    }
    Ok(Some(rec))
}

/// The wall under test at `k` (config `base` with that K, its wall at the device's rest
/// position), after a reproducible start (see the module header): the device brought to rest
/// with the wall off and the test's damper off too (a damper alone can be unstable, B·T/m
/// large or behind a slow amplifier, and must not keep the device from coming to rest between
/// tests), under the gentle brake `brake` ([`Judging::brake_damping`], capped at the
/// firmware's largest damping), which is also the test's safe mode (the supervisor's damping on
/// a fault). A fault the last test latched is cleared once first, so the brake with its dead
/// band acts; one that latches again (the device outside the travel window) stays for the
/// caller's walk back.
fn wall_under_test(
    c: &mut Client,
    base: &ServoConfig,
    k: f64,
    test: Test,
    brake: f64,
    rest_hint: Option<i32>,
) -> Result<ServoConfig> {
    let brake = brake
        .min(super::approach::firmware_damping_cap(c, base))
        .max(0.0);
    // A test the supervisor stops (an energy fault of a wall that grew) would leave the device
    // coasting with no force until the host's next config: the same brake is its safe mode.
    let base = &if brake > 0.0 {
        ServoConfig {
            safe_mode: stiffwall_proto::SafeMode::Damping,
            safe_damping: brake as f32,
            ..*base
        }
    } else {
        *base
    };
    c.set_config(&ServoConfig {
        stiffness: 0.0,
        damping: brake as f32,
        damper: stiffwall_proto::DamperLaw::DeadBand { counts: 1 },
        travel_min: None,
        travel_max: None,
        ..*base
    })?;
    let latched = brake > 0.0 && c.faults()?.latched != 0;
    if latched {
        c.clear_faults()?;
    }
    let rest = match rest_hint {
        Some(rest) if !latched => rest,
        _ => rest_position(c)?,
    };
    let one_sided = matches!(
        test,
        Test::Impact {
            one_sided: true,
            ..
        }
    );
    Ok(ServoConfig {
        stiffness: k as f32,
        wall_position: base.wall_position.saturating_add(rest),
        wall: if one_sided {
            WallMode::OneSided
        } else {
            WallMode::Bidirectional
        },
        ..*base
    })
}

/// Effective counts past a one-sided impact's launch start at which its free side's window
/// ends, at least ([`free_side_window`]).
const FREE_SIDE_MARGIN_TICKS: i64 = 16;

/// `cfg` for `test` with, for a one-sided impact, the travel window's end on the free side
/// (the launch's side of the wall) moved in to just past the launch start: the launch distance
/// or twice the exit window at the launch speed (at least [`FREE_SIDE_MARGIN_TICKS`]) beyond
/// it. A one-sided wall has no force on its free side, so a device it throws out coasts on
/// with the speed it left with: on a device of little friction (omega-one-sided-delay with
/// ±40 mm of travel, 0.67 m/s² of friction) into its end stop, where a window at the travel's
/// end tripped the brake too late. Leaving this window trips the supervisor (its safe mode is
/// the brake), and a test whose device had left the wall is judged by what it did there.
fn free_side_window(cfg: ServoConfig, test: Test) -> ServoConfig {
    let Test::Impact {
        start_ticks,
        velocity_milliticks,
        one_sided: true,
    } = test
    else {
        return cfg;
    };
    let v_ticks = i64::from(velocity_milliticks.unsigned_abs() / 1000 + 1);
    let start = i64::from(start_ticks).abs();
    let margin = start
        .max(2 * super::verdict::EXIT_WINDOW as i64 * v_ticks)
        .max(FREE_SIDE_MARGIN_TICKS);
    let reach = (start + margin) << cfg.coarsen_shift.min(16);
    let wall = i64::from(cfg.wall_position);
    if start_ticks < 0 {
        let edge = i32::try_from(wall - reach).unwrap_or(i32::MIN);
        ServoConfig {
            travel_min: Some(cfg.travel_min.map_or(edge, |m| m.max(edge))),
            ..cfg
        }
    } else {
        let edge = i32::try_from(wall + reach).unwrap_or(i32::MAX);
        ServoConfig {
            travel_max: Some(cfg.travel_max.map_or(edge, |m| m.min(edge))),
            ..cfg
        }
    }
}

/// How a test's record is cut and judged.
struct Judged {
    /// Base length, ticks after the release.
    ticks: usize,
    /// Constant run that settles the record.
    min_run: usize,
    /// Most ticks the test may run.
    budget: usize,
    /// What passes, and the scale of the chatter report.
    judging: Judging,
    /// The config's coarsening shift (effective counts).
    shift: u8,
}

impl Judged {
    /// The verdict of `test`'s record; an impact judged against the speed `asked` (counts per
    /// tick; None: its own).
    fn judge(&self, test: Test, rec: &stiffwall_client::Record, asked: Option<f64>) -> TestRun {
        let mut counts = super::release::released_counts(&rec.samples, self.shift);
        // Judge only up to where the record settled (what came after is the Stop's latency).
        // A one-sided impact whose device left the wall and then the travel window (coasting
        // on the free side, where the wall has no force) is judged by what it did at the wall.
        let departed = matches!(
            test,
            Test::Impact {
                one_sided: true,
                ..
            }
        ) && rec.faults & !stiffwall_proto::fault::TRAVEL == 0
            && super::verdict::exit_speed(&counts).is_some()
            && counts.last().is_some_and(|&n| n < 0);
        let tripped = rec.faults != 0 && !departed;
        let one_count = self.judging.criterion == Criterion::AcceptChatter;
        if let Some(len) = judged_len_within(&counts, self.ticks, self.min_run, one_count) {
            counts.truncate(len);
        } else if !tripped {
            counts.truncate(self.budget);
        }
        let (verdict, delivered) = match test {
            Test::Release { .. } => (classify(&counts, tripped), None),
            Test::Impact {
                one_sided,
                velocity_milliticks,
                ..
            } => {
                let asked = asked.unwrap_or(f64::from(velocity_milliticks).abs() / 1000.0);
                let delivered = Delivered::from_record(&rec.samples, &counts, self.shift, asked);
                let wall = if one_sided {
                    Wall::OneSided
                } else {
                    Wall::Bidirectional
                };
                let verdict = judge_impact(&counts, wall, delivered.as_ref(), tripped);
                (verdict, delivered)
            }
        };
        let chatter = verdict
            .chatters()
            .then(|| self.chatter(&rec.samples, &counts));
        TestRun {
            hold_tripped: tripped && counts.is_empty(),
            hold_timed_out: held_s(&rec.samples, self.judging.period_s) >= HOLD_LONGEST_S,
            verdict: verdict.under(self.judging.criterion),
            counts,
            delivered,
            chatter,
        }
    }

    /// The chatter over the judged tail of `counts` (the released samples' first
    /// `counts.len()`), with the force each of those samples output.
    fn chatter(&self, samples: &[stiffwall_proto::Sample], counts: &[i64]) -> ChatterReport {
        let forces: Vec<f64> = samples
            .iter()
            .filter(|s| s.flags & stiffwall_proto::flags::RELEASED != 0)
            .take(counts.len())
            .map(|s| f64::from(s.force_code) * self.judging.force_per_code)
            .collect();
        let tail = (counts.len() / 4).max(MIN_TAIL).min(counts.len());
        let from = counts.len() - tail;
        let ch = stiffwall_core::rest::Chatter::of_window(
            &counts[from..],
            forces.get(from..).unwrap_or(&[]),
            self.judging.period_s,
            self.judging.coulomb_n,
        );
        ChatterReport {
            toggles_per_s: ch.toggles_per_s,
            force_pp_n: ch.force_pp_n,
            force_pp_c: ch.force_pp_c,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(verdict: Verdict, counts: &[i64]) -> TestRun {
        TestRun {
            verdict,
            counts: counts.to_vec(),
            delivered: None,
            hold_tripped: false,
            hold_timed_out: false,
            chatter: None,
        }
    }

    #[test]
    fn a_pass_only_from_short_after_a_failure_from_farther_keeps_the_failure() {
        // Asked 9: the hold rang out to 54 and the release grew; re-aimed at 1 it stuck at the
        // wall and "settled": the failure stands.
        let rang = run(Verdict::Growing, &[54, 60, 71]);
        let stuck = run(Verdict::Settles, &[0, 0, 0]);
        assert_eq!(
            release_outcome(9, stuck.clone(), Some(rang.clone())).verdict,
            Verdict::Growing
        );
        // Re-aimed and passed from the energy asked (8 is within 9's tolerance): the pass.
        let held = run(Verdict::Settles, &[8, 3, 0]);
        assert_eq!(
            release_outcome(9, held, Some(rang.clone())).verdict,
            Verdict::Settles
        );
        // Stuck at the wall on the first attempt (no failure from farther): the pass stands.
        assert_eq!(release_outcome(9, stuck, None).verdict, Verdict::Settles);
        // A last attempt that failed is the outcome either way.
        let failed = run(Verdict::Growing, &[2, 9, 20]);
        assert_eq!(
            release_outcome(9, failed, Some(rang)).counts,
            vec![2, 9, 20]
        );
    }
}
