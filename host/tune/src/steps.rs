//! One run's tests on the device: the identified device and the tune's targets (`Run`), a
//! search step (the full-energy release, plus impacts at v above the force-saturation K or with
//! a damper), the whole verification set and its confirmation with back-off.
//!
//! Units: SI (N/m, N·s/m, kg, m/s; rotary N·m/rad, N·m·s/rad, kg·m², rad/s), ticks.

use super::error::Result;
use super::launch::Delivered;
use super::progress::Progress;
use super::release::Verdict;
use super::settings::{
    Settings, CONFIRM_BACKOFF, CONFIRM_TRIES, DAMPED_TEST_MIN_TICKS, TEST_NATURAL_PERIODS,
    TEST_TICKS,
};
use super::test_set::{
    impact, min_settle_run, test_set, Test, WallSides, BOTH_SIDES_IMPACT_SHARES,
};
use super::verify::{run_test_at, Judging, TestResult, TestRun};
use stiffwall_client::Client;
use stiffwall_core::params::PhysicalParams;
use stiffwall_proto::ServoConfig;

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

/// The brake between tests ([`Judging::brake_damping`]), B·T/m: a time constant of ten ticks,
/// far inside the sampled damper's stable range (B·T/m < 2 without delay, about π/(2d + 1)
/// behind d ticks of delay).
const BRAKE_BT_PER_M: f64 = 0.1;

/// What every test of one run needs beyond the config: the identified device and the tune's
/// targets.
pub(crate) struct Run<'a> {
    pub(crate) s: &'a Settings,
    pub(crate) p: PhysicalParams,
    /// Maximum velocity v, m/s (rad/s).
    pub(crate) v: f64,
    /// Above this K the wall's peak force at v saturates (see `procedure::tune_inner`).
    pub(crate) k_force: f64,
    pub(crate) one_sided_wall: bool,
    /// Force of one output code, N (N·m).
    pub(crate) force_per_code: f64,
    pub(crate) progress: &'a dyn Fn(Progress),
    /// The slowest impact launch that passed below its asked speed (see [`Delivered::slow`]).
    pub(crate) slow_launch: std::cell::Cell<Option<Delivered>>,
    /// The last impact launch that failed off its asked speed ([`Verdict::NotLaunched`]).
    pub(crate) missed_launch: std::cell::Cell<Option<Delivered>>,
    /// Room each side of the tests' wall, raw counts (issue 46): a device a test left farther
    /// than half of it away is walked back before the next test.
    pub(crate) room: i64,
    /// The push of the move that walks a drifting device back, N (N·m).
    pub(crate) move_force_n: f64,
    /// The travel window the tests carry when none is configured ([`Judging::window`]).
    pub(crate) window: Option<(i32, i32)>,
    /// The static friction F_s the breakaway ramps measured above c, N (N·m): the small-swing
    /// screen's model sticks up to it.
    pub(crate) static_n: Option<f64>,
}

/// What the searches found beside their result.
#[derive(Default)]
pub(crate) struct Notes {
    /// The smallest K at which an impact's launch failed (see `Verdict::NotLaunched`).
    pub(crate) not_launched: Option<f64>,
    /// The largest K whose release passed at B = 0, with its counts.
    pub(crate) best: Option<(f64, Vec<i64>)>,
    /// The last verification test that failed.
    pub(crate) last_failure: Option<TestResult>,
    /// The verification set left out the impacts at v (see `frontier::choose_wall`).
    pub(crate) impacts_capped: bool,
    /// Per side (toward +, toward −), the smallest K whose impact at v the launch could not
    /// deliver in a search step: a stiffer hold (the wall's K, μ smaller) lags and catches up
    /// at least as much, so the searches skip that side's impacts from there up.
    pub(crate) unlaunched_from: [Option<f64>; 2],
}

impl Run<'_> {
    pub(crate) fn period_s(&self) -> f64 {
        self.p.period_s
    }

    /// How this run's tests are judged ([`Settings::criterion`]).
    pub(crate) fn judging(&self) -> Judging {
        Judging {
            criterion: self.s.criterion,
            period_s: self.period_s(),
            force_per_code: self.force_per_code,
            coulomb_n: self.p.coulomb,
            brake_damping: BRAKE_BT_PER_M * self.p.mass / self.period_s(),
            window: self.window,
        }
    }

    pub(crate) fn natural_ticks(&self, k: f64) -> f64 {
        std::f64::consts::TAU * (self.p.mass / k).sqrt() / self.period_s()
    }

    pub(crate) fn ticks_for(&self, k: f64, thorough: bool, damped: bool) -> u32 {
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

    pub(crate) fn test(
        &self,
        c: &mut Client,
        base: &ServoConfig,
        k: f64,
        test: Test,
        thorough: bool,
    ) -> Result<TestRun> {
        let back = crate::travel::GentleMove {
            k: k / 16.0,
            b: 0.0,
            damper: base.damper,
            force_n: self.move_force_n,
            chatters: false,
            mass: Some(self.p.mass),
            k_settle: 0.0,
            friction: Some(crate::approach::MoveFriction {
                coulomb_n: self.p.coulomb,
                viscous: self.p.viscous,
            }),
        };
        let rest = crate::travel::recentre(c, base, back, self.room, self.judging().brake_damping)?;
        let run = run_test_at(
            c,
            base,
            k,
            test,
            (
                self.ticks_for(k, thorough, base.damping > 0.0),
                min_settle_run(self.p.mass, k, self.period_s()),
            ),
            &self.judging(),
            rest,
        )?;
        if let Some(d) = run.delivered {
            // The slowest launch that passed (as the slower impact it was) and the last one
            // that failed off its speed: reported with the findings.
            if d.slow() && run.verdict.passes() {
                let slowest = self.slow_launch.get().filter(|s| s.contact <= d.contact);
                self.slow_launch.set(Some(slowest.unwrap_or(d)));
            }
            if run.verdict == Verdict::NotLaunched {
                self.missed_launch.set(Some(d));
            }
        }
        Ok(run)
    }

    /// One search step at `k`: the full-energy release, and above `k_force` the impacts at v.
    pub(crate) fn step(
        &self,
        c: &mut Client,
        base: &ServoConfig,
        k: f64,
        thorough: bool,
        notes: &mut Notes,
    ) -> Result<Verdict> {
        let d = deflection_for(&self.p, k, self.v);
        let b = base.damping;
        (self.progress)(Progress::ReleaseStep {
            k,
            b: b.into(),
            deflection_ticks: d,
        });
        let TestRun {
            verdict, counts, ..
        } = self.test(
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
            let impact = self.step_impacts(c, base, k, thorough, notes)?;
            if !impact.passes() {
                return Ok(impact);
            }
        }
        if base.damping == 0.0 && notes.best.as_ref().is_none_or(|(kb, _)| k > *kb) {
            notes.best = Some((k, counts));
        }
        Ok(verdict)
    }

    /// The impacts of a search step at `k` (above `k_force`, or with a damper): the first that
    /// fails, else [`Verdict::Settles`]. One side below `k_force` (the confirmation runs both);
    /// a damped wall through the bidirectional wall also at the verification's lower speeds
    /// ([`BOTH_SIDES_IMPACT_SHARES`]): its failing bands are narrow, and one at
    /// 0.8 v alone put maxon-re35-amp-3khz's frontier 1.27 × the truth's K*(B).
    fn step_impacts(
        &self,
        c: &mut Client,
        base: &ServoConfig,
        k: f64,
        thorough: bool,
        notes: &mut Notes,
    ) -> Result<Verdict> {
        let dirs: &[f64] = if self.one_sided_wall || k <= self.k_force {
            &[1.0]
        } else {
            &[1.0, -1.0]
        };
        let shares: &[f64] = if base.damping > 0.0 && !self.one_sided_wall {
            &BOTH_SIDES_IMPACT_SHARES
        } else {
            &[1.0]
        };
        let speeds = dirs
            .iter()
            .flat_map(|&dir| shares.iter().map(move |&share| dir * share));
        // A side whose impact at v the launch could not deliver is not tried at its lower
        // speeds either, nor at any stiffer K ([`Notes::unlaunched_from`]): the hold that
        // lagged and caught up at v does so below it too (seen on maxon-re35 near its quiet
        // ceiling: every one not launched, 2.5 to 8 s of real time each, a third of the tune).
        // The verification set still runs them at the K set.
        let side = |dir: f64| usize::from(dir < 0.0);
        for dir in speeds {
            if notes.unlaunched_from[side(dir)].is_some_and(|k0| k >= k0) {
                continue;
            }
            let v_ticks = dir * self.v * self.period_s() / self.p.resolution;
            let sides = if self.one_sided_wall {
                WallSides::OneSided
            } else {
                WallSides::Both
            };
            let test = impact(v_ticks, self.natural_ticks(k), sides);
            let why = if k > self.k_force {
                "force saturates"
            } else {
                "damped wall"
            };
            (self.progress)(Progress::ImpactStep {
                k,
                test: test.describe(),
                reason: why.into(),
            });
            let impact = self.test(c, base, k, test, thorough)?.verdict;
            if impact == Verdict::NotLaunched {
                // A launch at a lower speed that the hold cannot deliver (it lags and catches
                // up when μ is small) says nothing, and is no finding: the one at v of the
                // spring-only search is reported. A damped frontier step's K lies above the
                // wall set (μ smaller still, the hold oscillates at the wall's K near the quiet
                // ceiling): the verification set runs the impacts at the K set, and reports a
                // launch it cannot deliver there.
                if dir.abs() >= 1.0 {
                    if base.damping == 0.0 {
                        notes.not_launched.get_or_insert(k);
                    }
                    let from = &mut notes.unlaunched_from[side(dir)];
                    *from = Some(from.map_or(k, |k0: f64| k0.min(k)));
                }
            } else if !impact.passes() {
                return Ok(impact);
            }
        }
        Ok(Verdict::Settles)
    }

    /// The whole verification set at `k` and the config `base` (its damping): whether every
    /// test passed, and the results up to the first failure.
    pub(crate) fn verify_set(
        &self,
        c: &mut Client,
        base: &ServoConfig,
        k: f64,
        thorough: bool,
        notes: &mut Notes,
    ) -> Result<(bool, Vec<TestResult>)> {
        let d = deflection_for(&self.p, k, self.v);
        (self.progress)(Progress::Verifying {
            k,
            b: base.damping.into(),
            deflection_ticks: d,
        });
        let v_ticks = self.v * self.period_s() / self.p.resolution;
        let mut set = test_set(
            d,
            v_ticks,
            self.natural_ticks(k),
            thorough,
            true,
            self.one_sided_wall,
        );
        if notes.impacts_capped {
            // The impacts this device's launch could run: below v.
            let full = (1000.0 * v_ticks * 0.99) as u32;
            set.retain(|t| {
                !matches!(t, Test::Impact { velocity_milliticks, .. }
                    if velocity_milliticks.unsigned_abs() >= full)
            });
        }
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
            let TestRun {
                verdict,
                counts,
                chatter,
                ..
            } = self.test(c, base, k, test, thorough)?;
            results.push(TestResult {
                test,
                k,
                verdict,
                ticks_judged: counts.len(),
                chatter,
            });
            if verdict == Verdict::NotLaunched {
                // Judged by the releases of the set, which reach the same energy from both
                // sides; reported by the caller.
                notes.not_launched.get_or_insert(k);
                continue;
            }
            if !verdict.passes() {
                notes.last_failure = results.last().copied();
                (self.progress)(Progress::VerifyFailed {
                    k,
                    test: test.describe(),
                    verdict: verdict.describe().to_string(),
                    backoff: CONFIRM_BACKOFF,
                });
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
    pub(crate) fn confirm(
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
