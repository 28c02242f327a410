//! A move's spring walk and its final approach (issue 46): the walk's state and one step of it
//! ([`Walk`], [`GentleMove`]), and the last counts to the target, against friction ([`nudge`]).
//!
//! Units: raw encoder counts (the frame of `ServoConfig::wall_position`); forces N (N·m);
//! stiffness N/m (N·m/rad).
//!
//! A spring K holds a device with Coulomb friction c anywhere within its *band* c/(KΔ) counts
//! of its origin, and static friction F_s holds it until the spring pulls harder than F_s. A
//! move's weak spring (K/16 of a wall) has a band of tens of counts, so moving the origin by
//! the remaining offset (the old nudge) mostly moves nothing: the origin has to cross the whole
//! band before the device breaks away, and then it throws the device twice as far as meant.
//!
//! Each nudge here instead places the origin where the friction model says the device will
//! stop at the target. Released from rest at an offset D > band from the origin, a spring–mass
//! with Coulomb friction swings to the far side of its kinetic equilibrium (band short of the
//! origin) and stops there: it moves (D − band)·(1 + r), where r is the half-cycle decay of its
//! viscous damping (r = 1 undamped, 0 at and above critical damping). So the nudge sets
//! D = band + e/(1 + r) for a remaining offset e. The band starts from the identified c (or,
//! before identification, from how far the device lagged its origin) and is re-measured after
//! every nudge that moves (band = D − moved/(1 + r)); a nudge that does not move raises the
//! least D that breaks away (static friction above c). Static friction F_s above c makes the
//! least move a release can make (F_s − c)/(KΔ)·(1 + r): when that is more than twice the
//! offset left, the nudges go on with a spring [`SETTLE_STEP`] times as stiff, up to
//! `GentleMove::k_settle` (a quarter of a spring-only wall verified to rest), and beyond that
//! they stop: any move would land the device farther off than it is. Invariants: each nudge's push
//! is K·Δ·D, just above the friction; at most [`NUDGES`] nudges; no allocation.

use super::error::{bail, Result};
use super::left::fault_names;
use stiffwall_client::Client;
use stiffwall_proto::ServoConfig;

/// The gentle move of [`super::travel::move_to`]: a spring `k` with damper `b` (the firmware's default law)
/// whose origin steps so that the spring never pushes harder than `force_n`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GentleMove {
    /// Spring, N/m (N·m/rad), > 0.
    pub k: f64,
    /// Damper, N·s/m (N·m·s/rad), ≥ 0.
    pub b: f64,
    /// The damper's law.
    pub damper: stiffwall_proto::DamperLaw,
    /// Largest push of one step, N (N·m).
    pub force_n: f64,
    /// The spring may chatter within one count (a wall set with `--accept-chatter`): a step
    /// then waits until the device stays within one count, not for exact rest (which makes
    /// where it stops depend on the link's timing, so only the way back uses it).
    pub chatters: bool,
    /// The device's mass (inertia), kg (kg·m²), once identified: it bounds the glide's damper.
    pub mass: Option<f64>,
    /// The device's friction, once identified: the final approach aims with it.
    pub friction: Option<super::approach::MoveFriction>,
    /// The stiffest spring (with damper `b`) the final approach may use when static friction
    /// throws the device past the target with `k` ([`super::approach::nudge`]): a spring-only
    /// wall verified to rest, N/m (N·m/rad), else `k`.
    pub k_settle: f64,
}

/// The damper that keeps a walk's spring `k` passive behind `delay_ticks` of extra delay,
/// N·s/m (N·m·s/rad): B = K·T·(d + 1), above the paper's passivity bound K·(T/2 + τ_d)
/// (region A), so a walk released from far off cannot pump energy into a limit cycle.
/// Without it a light rotor behind two ticks of delay (random-launch-1 of the launch family)
/// grew from a re-centring nudge to a limit cycle at the walk's force limit, 600 counts wide,
/// because K/16 of the wall under test is far above its passive K. Capped at B·T/m = ¼ when the
/// mass is known (a sampled damper alone is stable up to about π/(2d + 1)).
#[must_use]
pub fn passive_walk_damping(k: f64, period_s: f64, delay_ticks: u8, mass: Option<f64>) -> f64 {
    let b = k * period_s * (f64::from(delay_ticks) + 1.0);
    match mass {
        Some(m) if m > 0.0 && period_s > 0.0 => b.min(WALK_DAMPER_BT_PER_M * m / period_s),
        _ => b,
    }
}

/// Once measured, the moves push at least this many times the breakaway force.
pub const BREAKAWAY_MARGIN: f64 = 1.5;

/// The firmware's largest damping for `cfg`'s servo rate and coarsening, with a margin for
/// rounding, N·s/m (N·m·s/rad): its damper gain is at most 2^14 codes per effective count per
/// tick, half the stiffness limit's per tick.
#[must_use]
pub fn firmware_damping_cap(c: &Client, cfg: &ServoConfig) -> f64 {
    let t = 1.0 / f64::from(cfg.servo_rate_hz.max(1));
    0.99 * f64::from(c.info.limits.max_stiffness) * t
        / 2.0
        / f64::from(1u32 << cfg.coarsen_shift.min(16))
}

/// A walk's damper, B·T/m at most ([`passive_walk_damping`]).
const WALK_DAMPER_BT_PER_M: f64 = 0.25;

/// Raw count of a count `n` read relative to the wall of `cfg` (effective counts).
pub(super) fn raw_of(cfg: &ServoConfig, n: i32) -> i64 {
    i64::from(cfg.wall_position) + (i64::from(n) << cfg.coarsen_shift.min(16))
}

/// `n` as an i32, saturated.
pub(super) fn clamp_i32(n: i64) -> i32 {
    i32::try_from(n).unwrap_or(if n < 0 { i32::MIN } else { i32::MAX })
}

/// Waits until the device stays within one count (50 samples 2 ms apart spanning at most two
/// neighbouring counts: a spring that chatters within one count is as settled as a move needs);
/// returns the lower of the two counts, from the wall.
///
/// # Errors
/// The device failing, or not settled within [`REST_WAIT_S`](super::rest::REST_WAIT_S).
fn settled_within_one(c: &mut Client) -> Result<i32> {
    let rate = c.info.servo_rate_hz.max(1);
    let decimation = u16::try_from((rate / 500).max(1)).unwrap_or(u16::MAX);
    c.stream_start(decimation)?;
    let wait_s = super::rest::REST_WAIT_S;
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs_f64(wait_s);
    let mut recent = std::collections::VecDeque::with_capacity(51);
    let result = loop {
        if std::time::Instant::now() > deadline {
            break Err(super::error::StepError::Failed(format!(
                "the device did not settle within one count within {wait_s:.0} s"
            )));
        }
        if let Some(b) = c.next_batch(super::rest::BATCH_WAIT)? {
            for x in &b.samples {
                recent.push_back(x.count);
                if recent.len() > 50 {
                    recent.pop_front();
                }
            }
            let lo = recent.iter().copied().min().unwrap_or(0);
            let hi = recent.iter().copied().max().unwrap_or(0);
            if recent.len() == 50 && i64::from(hi) - i64::from(lo) <= 1 {
                break Ok(lo);
            }
        }
    };
    c.stream_stop()?;
    result
}

/// The state of a [`super::travel::move_to`]: the config it sets, where the device is, the target.
pub struct Walk {
    /// The config the move sets (its spring replaced at every step).
    pub cfg: ServoConfig,
    /// Where the device rests, raw counts.
    pub at: i64,
    /// Where the move goes, raw counts.
    pub target: i64,
}

impl Walk {
    /// The spring `how` with its origin at `origin`, then a wait for rest.
    pub fn set(&mut self, c: &mut Client, origin: i64, how: GentleMove) -> Result<()> {
        let period_s = 1.0 / f64::from(c.info.servo_rate_hz.max(1));
        let passive = passive_walk_damping(how.k, period_s, self.cfg.extra_delay_ticks, how.mass)
            .min(firmware_damping_cap(c, &self.cfg));
        self.cfg = ServoConfig {
            stiffness: how.k as f32,
            damping: how.b.max(passive) as f32,
            damper: how.damper,
            wall_position: clamp_i32(origin),
            ..self.cfg
        };
        c.set_config(&self.cfg)?;
        let n = if how.chatters {
            settled_within_one(c)?
        } else {
            match super::rest::rest_position(c) {
                // A walk's spring on a coarse output (the board's DAC: one code is 18 of the
                // virtual device's) can toggle between two counts at its origin for ever: as
                // settled as a move needs (seen once in 20 phantom-1.0 tunes on the emulated
                // board: "the way back failed", the device then at rest 2 counts off).
                Err(super::error::StepError::NotAtRest { .. }) => settled_within_one(c)?,
                r => r?,
            }
        };
        self.at = raw_of(&self.cfg, n);
        self.check_faults(c)
    }

    /// An error naming the faults the supervisor latched on the way, if any.
    pub fn check_faults(&self, c: &mut Client) -> Result<()> {
        let latched = c.faults()?.latched;
        if latched != 0 {
            bail!(
                "the move to count {} stopped at count {}: the supervisor latched {}",
                self.target,
                self.at,
                fault_names(latched).join(", ")
            );
        }
        Ok(())
    }

    /// Walks the spring's origin from where the device is to `to` in steps of `step` counts
    /// (whether or not friction lets the device follow at once: it lags by at most F_s/K).
    pub fn go(&mut self, c: &mut Client, to: i64, how: GentleMove, step: i64) -> Result<()> {
        let mut origin = self.at;
        let steps = (to - origin).unsigned_abs() / step.unsigned_abs().max(1) + 2;
        for _ in 0..steps {
            let gap = to - origin;
            origin = if gap.abs() <= step {
                to
            } else {
                origin + step * gap.signum()
            };
            self.set(c, origin, how)?;
            if origin == to {
                return Ok(());
            }
        }
        bail!(
            "the move to count {} did not get there in {steps} steps (at count {})",
            self.target,
            self.at
        )
    }
}

/// Corrections of the final approach at most.
pub const NUDGES: usize = 16;
/// A stiffer spring for the nudges is this many times the last, up to `GentleMove::k_settle`.
const SETTLE_STEP: f64 = 4.0;

/// The device's friction as identified: what the final approach's nudges aim with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MoveFriction {
    /// Coulomb (kinetic) friction c, N (N·m), ≥ 0.
    pub coulomb_n: f64,
    /// Viscous friction b, N·s/m (N·m·s/rad), ≥ 0.
    pub viscous: f64,
}

/// What the nudges have learnt of the device under the move's spring, counts of offset D.
#[derive(Debug, Clone, Copy)]
struct Learnt {
    /// Kinetic band c/(KΔ): where a released device's kinetic equilibrium lies from the origin.
    band: f64,
    /// Largest offset that did not break the device away (0: none yet).
    stuck: f64,
    /// Least offset that did (infinite: none yet).
    moving: f64,
    /// Nudges in a row that did not move the device.
    stuck_streak: i32,
    /// How far a release swings past the kinetic equilibrium, 1 + r.
    gain: f64,
}

impl Learnt {
    fn new(band: f64, gain: f64) -> Self {
        Self {
            band,
            stuck: 0.0,
            moving: f64::INFINITY,
            stuck_streak: 0,
            gain,
        }
    }

    /// The offset D of the origin from the device that should stop it `e` counts on (|e|).
    fn offset_for(&self, e: f64) -> f64 {
        let need = (self.band + e / self.gain).round();
        if need > self.stuck {
            return need.max(1.0);
        }
        // Static friction holds the device at that offset. Between an offset that stuck and
        // one that moved, halve the interval (the least move the friction allows); above all
        // that stuck, step by the remaining offset's share, doubling while it still sticks.
        if self.moving.is_finite() {
            (self.stuck + 1.0)
                .round()
                .max(((self.stuck + self.moving) / 2.0).round())
        } else {
            let step = (e / self.gain).max(1.0) * f64::from(1 << self.stuck_streak.min(10));
            (self.stuck + step).round()
        }
    }

    /// The least move a release can make, counts: from just past the largest offset that
    /// stuck (0 until a nudge has both stuck and moved).
    fn least_move(&self) -> f64 {
        if self.moving.is_finite() && self.stuck > 0.0 {
            ((self.stuck + 1.0 - self.band) * self.gain).max(0.0)
        } else {
            0.0
        }
    }

    /// What is learnt, carried to a spring 1/`ratio` times as stiff (every offset is a force
    /// over K·Δ, so it scales by `ratio`).
    fn scaled(&self, ratio: f64) -> Self {
        Self {
            band: self.band * ratio,
            stuck: self.stuck * ratio,
            moving: self.moving * ratio,
            stuck_streak: 0,
            gain: self.gain,
        }
    }

    /// Learns from a nudge at offset `d` that moved the device `moved` counts toward its origin.
    fn observe(&mut self, d: f64, moved: f64) {
        if moved <= 0.0 {
            self.stuck = self.stuck.max(d);
            self.stuck_streak += 1;
        } else {
            self.band = (d - moved / self.gain).max(0.0);
            self.moving = self.moving.min(d);
            self.stuck_streak = 0;
        }
    }
}

/// The spring's half-cycle swing 1 + r for `how` on a device of `mass` with viscous friction
/// `viscous` (undamped 2 when the mass is not known yet: the first nudge then undershoots,
/// and the band it measures carries the rest).
fn swing_gain(how: &GentleMove, viscous: f64) -> f64 {
    let Some(mass) = how.mass.filter(|m| *m > 0.0) else {
        return 2.0;
    };
    let zeta = (viscous.max(0.0) + how.b.max(0.0)) / (2.0 * (how.k * mass).sqrt());
    if zeta >= 1.0 {
        1.0
    } else {
        1.0 + (-core::f64::consts::PI * zeta / (1.0 - zeta * zeta).sqrt()).exp()
    }
}

/// Nudges the device from where `walk` left it (at rest, its origin at `origin`) to within a
/// count of `walk.target` (module header), with `how`'s spring; `res` is a raw count's size,
/// m (rad). Returns after [`NUDGES`] nudges wherever the device then is.
///
/// # Errors
/// The device failing, or a fault latched on the way.
pub fn nudge(
    c: &mut Client,
    walk: &mut Walk,
    how: GentleMove,
    origin: i64,
    res: f64,
) -> Result<()> {
    let Some(friction) = how.friction.filter(|_| how.k_settle > 0.0) else {
        return nudge_by_offset(c, walk, how, origin);
    };
    let viscous = friction.viscous;
    let mut how = how;
    let mut learnt = Learnt::new(
        friction.coulomb_n / (how.k * res),
        swing_gain(&how, viscous),
    );
    for _ in 0..NUDGES {
        let e = walk.target - walk.at;
        if e.abs() <= 1 {
            break;
        }
        let overshoots = learnt.least_move() > 2.0 * e.abs() as f64;
        if overshoots && how.k >= how.k_settle {
            // Any move from here lands farther off than the device is: it stays.
            break;
        }
        if overshoots {
            // Static friction throws this spring's device farther than the offset left: a
            // stiffer one (bands ∝ 1/K) up to the wall verified to rest.
            let k = (SETTLE_STEP * how.k).min(how.k_settle);
            learnt = learnt.scaled(how.k / k);
            how.k = k;
            learnt.gain = swing_gain(&how, viscous);
        }
        let d = learnt.offset_for(e.abs() as f64);
        let from = walk.at;
        walk.set(c, from + e.signum() * d as i64, how)?;
        learnt.observe(d, ((walk.at - from) * e.signum()) as f64);
    }
    Ok(())
}

/// The nudges of a move without a friction model or a settling spring (`k_settle` 0): the
/// origin moved by the remaining offset each time (up to [`NUDGES`] times). Every move but the
/// way back uses it: the moves before identification, the move to the tests' middle and the
/// search's re-centring between tests, whose starts the search's outcome was measured from
/// (with the friction-aware nudges two plants' searches, started a count or so elsewhere,
/// set walls that buzz by the truth: maxon-re35-amp-3khz 4.15 for 3.83, K*(B) 3.60;
/// rotary-ironcore-cogging 4.54 for 4.26).
fn nudge_by_offset(c: &mut Client, walk: &mut Walk, how: GentleMove, target: i64) -> Result<()> {
    let mut origin = target;
    for _ in 0..NUDGES {
        let off = walk.target - walk.at;
        if off.abs() <= 1 {
            break;
        }
        origin += off;
        walk.set(c, origin, how)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frictional spring–mass as the module header models it: no motion up to `stick`,
    /// then (D − band)·gain, to the nearest count.
    fn device(d: f64, band: f64, stick: f64, gain: f64) -> f64 {
        if d <= stick {
            0.0
        } else {
            ((d - band) * gain).round()
        }
    }

    /// The nudges from `e0` counts short: the remaining offset and the nudges taken.
    fn approach(prior_band: f64, band: f64, stick: f64, gain: f64, e0: f64) -> (f64, usize) {
        let mut l = Learnt::new(prior_band, gain);
        let mut e = e0;
        for n in 0..NUDGES {
            if e.abs() <= 1.0 {
                return (e, n);
            }
            let d = l.offset_for(e.abs());
            let moved = device(d, band, stick, gain);
            l.observe(d, moved);
            e = e.signum() * (e.abs() - moved);
        }
        (e, NUDGES)
    }

    #[test]
    fn an_exact_model_lands_in_one_nudge() {
        // maxon-re35 under K/16 of its spring-only wall: a 37-count band, 5 counts short (the
        // old nudge, origin += 5, moved nothing for ten nudges).
        let (e, n) = approach(37.0, 37.0, 37.0, 2.0, 5.0);
        assert!(e.abs() <= 1.0 && n == 1, "e {e} after {n}");
    }

    #[test]
    fn a_band_off_by_forty_percent_is_learnt() {
        for true_band in [22.0, 30.0, 45.0, 52.0] {
            for e0 in [-9.0, 4.0, 40.0] {
                let (e, n) = approach(37.0, true_band, true_band, 2.0, e0);
                assert!(
                    e.abs() <= 1.0 && n <= 6,
                    "band {true_band}, {e0}: e {e} after {n}"
                );
            }
        }
    }

    #[test]
    fn static_friction_ends_within_its_least_move() {
        // c not known yet (band guessed at half), F_s = 1.5 c: a release from just past the
        // static offset 15 moves (16 − 10)·1.6 ≈ 10 counts, so no nudge can do better than
        // half that.
        for e0 in [6.0, 12.0, -20.0, 30.0] {
            let (e, _) = approach(5.0, 10.0, 15.0, 1.6, e0);
            assert!(e.abs() <= 5.0, "{e0}: e {e}");
        }
    }
    #[test]
    fn the_swing_gain_is_two_undamped_and_one_at_critical_damping() {
        let mut how = GentleMove {
            k: 4.0,
            b: 0.0,
            damper: stiffwall_proto::DamperLaw::Difference,
            force_n: 1.0,
            chatters: false,
            mass: None,
            friction: None,
            k_settle: 4.0,
        };
        assert_eq!(swing_gain(&how, 0.0), 2.0);
        how.mass = Some(1.0);
        assert!((swing_gain(&how, 0.0) - 2.0).abs() < 1e-12);
        how.b = 4.0; // 2·√(K·m): critical
        assert_eq!(swing_gain(&how, 0.0), 1.0);
        how.b = 0.4; // ζ = 0.1: r = exp(−0.1π/√0.99) ≈ 0.729
        assert!((swing_gain(&how, 0.0) - 1.729).abs() < 1e-3);
    }
}
