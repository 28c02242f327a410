//! The device's workspace during tune (issue 46): where the experiments may go, how far each
//! test reaches, and how the device is brought back to where it started.
//!
//! Units: positions are raw encoder counts (the frame of `ServoConfig::wall_position`) inside
//! this module and SI (m or rad) in the report; forces N (N·m); stiffness N/m (N·m/rad).
//!
//! Where the travel comes from, first found first: the caller's `Settings::travel` (SI, the
//! encoder's frame), the device config's travel window (`travel_min`/`travel_max`, raw
//! counts), else a default window of ±[`DEFAULT_WINDOW_LINEAR_M`] (linear) or
//! ±[`DEFAULT_WINDOW_ROTARY_RAD`] (rotary) around the start, which the report states. Every
//! experiment keeps inside the travel less a margin ([`MARGIN_SHARE`] of the half-span, at
//! least [`MIN_MARGIN_COUNTS`]): the chirp and the breakaway ramps against a weak centring
//! spring whose static deflection under the drive is [`CENTRING_SHARE`] of the room, the
//! releases and impacts by their reach ([`test_reach_counts`]), lowering the maximum velocity
//! when the room is short. The test configs carry the travel as the firmware's travel window,
//! so a run that leaves it trips the supervisor instead of reaching a stop.
//!
//! Invariant: nothing here assumes unbounded travel; a workspace always has two finite ends.

pub use super::approach::GentleMove;
use super::approach::{clamp_i32, raw_of, Walk};
use super::error::{bail, Result};
pub use super::left::{fault_names, DeviceLeft, LEFT_TOLERANCE_COUNTS};
pub use super::reach::{
    centring_stiffness, test_reach_counts, CENTRING_DAMPING_RATIO, CENTRING_SHARE,
    PROBE_CENTRING_SHARE,
};
use stiffwall_client::Client;
use stiffwall_proto::ServoConfig;

/// Half-width of the default window of a linear device, m: room for the release and impact
/// tests of a desktop haptic device at the default maximum velocity (a Phantom-class device
/// needs about 35 mm each side); a device with less travel declares it (`--travel MIN:MAX` or
/// its travel window), or tune lowers the velocity or refuses.
pub const DEFAULT_WINDOW_LINEAR_M: f64 = 0.05;
/// Half-width of the default window of a rotary device, rad (one turn each way: a motor turns
/// freely; a knob with stops declares them).
pub const DEFAULT_WINDOW_ROTARY_RAD: f64 = core::f64::consts::TAU;
/// Share of the half-span kept free at each end.
pub const MARGIN_SHARE: f64 = 0.1;
/// Least margin at each end, counts.
pub const MIN_MARGIN_COUNTS: i64 = 4;

/// Where the travel tune kept to came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TravelSource {
    /// The caller's `--travel MIN:MAX`.
    Given,
    /// The device config's travel window.
    DeviceConfig,
    /// No travel known: the default window around the start.
    DefaultWindow,
}

impl core::fmt::Display for TravelSource {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Given => "--travel",
            Self::DeviceConfig => "the device's travel window",
            Self::DefaultWindow => "the default window (no travel given or configured)",
        })
    }
}

/// The travel tune keeps to, and where the device started.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Workspace {
    /// Where it came from.
    pub source: TravelSource,
    /// Travel ends, raw counts.
    pub ends: [i64; 2],
    /// The window the experiments keep inside (the ends less the margin), raw counts.
    pub inner: [i64; 2],
    /// Where the device started, raw counts.
    pub start: i64,
    /// Raw count resolution Δ, m (rad).
    pub resolution: f64,
}

impl Workspace {
    /// The travel for a device at rest at raw count `start` (module header for the order).
    ///
    /// # Errors
    /// The start outside the travel given or configured.
    pub fn resolve(
        given: Option<[f64; 2]>,
        original: &ServoConfig,
        start: i64,
        resolution: f64,
        rotational: bool,
    ) -> Result<Self> {
        let (source, ends) = if let Some([lo, hi]) = given {
            let ends = [
                (lo / resolution).ceil() as i64,
                (hi / resolution).floor() as i64,
            ];
            (TravelSource::Given, ends)
        } else if let (Some(lo), Some(hi)) = (original.travel_min, original.travel_max) {
            (TravelSource::DeviceConfig, [i64::from(lo), i64::from(hi)])
        } else {
            let half = if rotational {
                DEFAULT_WINDOW_ROTARY_RAD
            } else {
                DEFAULT_WINDOW_LINEAR_M
            };
            let n = ((half / resolution).floor() as i64).max(1);
            (TravelSource::DefaultWindow, [start - n, start + n])
        };
        if !(ends[0]..=ends[1]).contains(&start) {
            bail!(
                "the device is at count {start} ({:.4e}), outside the travel [{}, {}] counts \
                 ({:.4e}..{:.4e}) of {source}: bring it inside, or give --travel MIN:MAX",
                start as f64 * resolution,
                ends[0],
                ends[1],
                ends[0] as f64 * resolution,
                ends[1] as f64 * resolution
            );
        }
        let margin = (((ends[1] - ends[0]) as f64 * 0.5 * MARGIN_SHARE) as i64)
            .max(MIN_MARGIN_COUNTS)
            .min((ends[1] - ends[0]) / 4);
        Ok(Self {
            source,
            ends,
            inner: [ends[0] + margin, ends[1] - margin],
            start,
            resolution,
        })
    }

    /// Room each side of raw count `at` inside the inner window, counts (0 when outside).
    #[must_use]
    pub fn room_at(&self, at: i64) -> i64 {
        (at - self.inner[0]).min(self.inner[1] - at).max(0)
    }

    /// Where the experiments run: the start, or the middle of the inner window when the start
    /// is closer to an end than a third of the inner half-span.
    #[must_use]
    pub fn test_centre(&self) -> i64 {
        let mid = (self.inner[0] + self.inner[1]) / 2;
        let half = (self.inner[1] - self.inner[0]) / 2;
        if self.room_at(self.start) * 3 < half * 2 {
            mid
        } else {
            self.start
        }
    }

    /// The firmware travel window for the test configs: the device's own when configured,
    /// else the ends of a given travel (a run that leaves them trips the supervisor), none for
    /// the default window.
    #[must_use]
    pub fn firmware_window(&self, original: &ServoConfig) -> (Option<i32>, Option<i32>) {
        if original.travel_min.is_some() || original.travel_max.is_some() {
            return (original.travel_min, original.travel_max);
        }
        // The default window is tune's own limit on a device whose travel nobody stated (it
        // may turn freely): the supervisor is not told, so a test that overshoots it is walked
        // back rather than latched out of reach.
        if self.source == TravelSource::DefaultWindow {
            return (None, None);
        }
        let clamp = |n: i64| i32::try_from(n).ok();
        (clamp(self.ends[0]), clamp(self.ends[1]))
    }

    /// The travel in SI, [min, max] m (rad).
    #[must_use]
    pub fn ends_si(&self) -> [f64; 2] {
        [
            self.ends[0] as f64 * self.resolution,
            self.ends[1] as f64 * self.resolution,
        ]
    }

    /// The report's line: the travel, where it came from, and how to widen a default.
    #[must_use]
    pub fn describe(&self, unit: &str) -> String {
        let [lo, hi] = self.ends_si();
        let widen = if self.source == TravelSource::DefaultWindow {
            "; give the device's travel with --travel MIN:MAX (or set its travel window, \
             `hostctl config set`) to use more of it"
        } else {
            ""
        };
        format!(
            "travel {lo:.4e}..{hi:.4e} {unit} (counts {}..{}) from {}, experiments kept within \
             counts {}..{}{widen}",
            self.ends[0], self.ends[1], self.source, self.inner[0], self.inner[1]
        )
    }
}

/// Largest wall-position step of the return move, counts: the move's spring never pushes
/// harder than `force_n` (its K·Δ·step), at least one count.
fn move_step(force_n: f64, k: f64, resolution: f64) -> i64 {
    ((force_n / (k * resolution)).floor() as i64).max(1)
}

/// Where the device is now, raw counts: it is let come to rest with `base`'s wall off.
///
/// # Errors
/// The device failing or not coming to rest.
pub fn where_now(c: &mut Client, base: &ServoConfig) -> Result<i64> {
    where_now_braked(c, base, 0.0)
}

/// [`where_now`] with the wall off but a damper `brake` (N·s/m, N·m·s/rad; a dead band of
/// one count, so it never acts at rest) bringing a device that still moves to rest.
///
/// # Errors
/// The device failing or not coming to rest.
pub fn where_now_braked(c: &mut Client, base: &ServoConfig, brake: f64) -> Result<i64> {
    rest_braked(c, base, brake).map(|(raw, _)| raw)
}

/// [`where_now_braked`]'s raw count and the rest count it read, in the counts of `base`'s wall
/// frame (what `rest_position` returns there).
fn rest_braked(c: &mut Client, base: &ServoConfig, brake: f64) -> Result<(i64, i32)> {
    let cfg = ServoConfig {
        stiffness: 0.0,
        damping: brake.max(0.0) as f32,
        damper: if brake > 0.0 {
            stiffwall_proto::DamperLaw::DeadBand { counts: 1 }
        } else {
            base.damper
        },
        ..*base
    };
    c.set_config(&cfg)?;
    let rest = super::rest::rest_position(c)?;
    Ok((raw_of(&cfg, rest), rest))
}

/// Steps of the fine phase's reach: a move farther than this many fine steps glides first.
const COARSE_STEPS: i64 = 20;

/// Brings the device gently to raw count `target` (module header), in three phases:
/// - *glide* ([`glide`]), while the device is more than [`COARSE_STEPS`] fine steps away: the
///   firmware's force limit lowered to the move's push, a weak spring centred on the target
///   and a damper that holds the speed to what the push can reach (force and speed bounded
///   whatever the device does);
/// - *fine*: `how`'s spring, its origin walking to the target in steps of `how.force_n`;
/// - *nudges* ([`super::approach::nudge`]): the origin placed where the friction model says
///   the device stops at the target, up to [`super::approach::NUDGES`] times, until it rests
///   within a count of it (friction holds a spring's device up to F_s/(KΔ) counts off its
///   origin, so the origin alone at the target is not enough).
///
/// Each step waits for rest. `base` gives the other settings (stiffness, damping, wall and wall
/// position are replaced; the energy monitor is off, the travel window lifted: a device a test
/// left outside it would latch it again at once; the caller's next config has it again).
/// Returns the raw count reached.
///
/// # Errors
/// The device failing, a fault latched on the way, or not at rest within the wait of
/// [`crate::verify::rest_position`].
pub fn move_to(c: &mut Client, base: &ServoConfig, target: i64, how: GentleMove) -> Result<i64> {
    let shift = base.coarsen_shift.min(16);
    let res = f64::from(c.info.resolution) * f64::from(1u32 << shift);
    // A bounded speed too: a step of s counts rings the spring at most s·ωT counts per tick,
    // ωT ≤ 2 on any stable sampled spring, so s ≤ an eighth of the encoder-jump limit keeps
    // the move far from that fault.
    let jump_cap = i64::from(base.encoder_jump_counts / 8).max(1);
    let fine_step = (move_step(how.force_n, how.k, res) << shift).min(jump_cap);
    let base = &ServoConfig {
        travel_min: None,
        travel_max: None,
        ..*base
    };
    c.set_config(&ServoConfig {
        stiffness: 0.0,
        damping: 0.0,
        ..*base
    })?;
    super::rest::clear_faults(c)?;
    // No tick of the walk pushes harder than twice its step's push (a spring that rings
    // cannot feed a limit cycle with the full force range).
    let walk_limit = (2.0 * how.force_n).min(f64::from(base.force_limit)) as f32;
    let mut walk = Walk {
        cfg: ServoConfig {
            wall: stiffwall_proto::WallMode::Bidirectional,
            energy_monitor: false,
            force_limit: walk_limit,
            ..*base
        },
        at: where_now(c, base)?,
        target,
    };
    let far = COARSE_STEPS * fine_step;
    if (target - walk.at).abs() > far {
        glide(c, &mut walk, how, far)?;
    }
    walk.go(c, target, how, fine_step)?;
    super::approach::nudge(c, &mut walk, how, target, f64::from(c.info.resolution))?;
    Ok(walk.at)
}

/// Least band, share of the room, of the spring a move aims again with ([`move_into`]).
const AIM_BAND_SHARE: f64 = 0.125;

/// [`move_to`], and when the device then rests farther than half of `room` (raw counts each
/// side of `target`) from it, a second move whose final nudges aim with the friction model and
/// may stiffen the spring until static friction F_s holds the device within an eighth of the
/// room of the spring's origin ([`AIM_BAND_SHARE`]; needs `how.friction`). A move's weak spring
/// (its push a small share of the force limit) holds a device with F_s above it anywhere within
/// thousands of counts; its plain nudges build up the push until the device breaks away and
/// throws it farther than it was (random-launch-3 of the launch family: from count −690 to
/// 5001, outside the default window of ±4095, after the breakaway ramps). The second move runs
/// only then, so a move that lands inside the room is the same as [`move_to`]'s.
///
/// # Errors
/// As [`move_to`].
pub fn move_into(
    c: &mut Client,
    base: &ServoConfig,
    target: i64,
    how: GentleMove,
    room: i64,
) -> Result<i64> {
    let at = move_to(c, base, target, how)?;
    let Some(friction) = how.friction else {
        return Ok(at);
    };
    if room <= 0 || (at - target).abs() * 2 <= room {
        return Ok(at);
    }
    let res = f64::from(c.info.resolution) * f64::from(1u32 << base.coarsen_shift.min(16));
    let band = (AIM_BAND_SHARE * room as f64).max(1.0) * res;
    let holds = friction
        .coulomb_n
        .max(how.force_n / super::approach::BREAKAWAY_MARGIN);
    let aimed = GentleMove {
        k_settle: how.k.max(how.k_settle).max(holds / band),
        ..how
    };
    move_to(c, base, target, aimed)
}

/// A glide's speed, at most this share of the encoder-jump limit per tick.
const GLIDE_JUMP_SHARE: f64 = 1.0 / 16.0;
/// A glide's speed, at most this share of the over-velocity limit when one is set.
const GLIDE_VELOCITY_SHARE: f64 = 0.5;
/// The glide's damper, B·T/m at most when the mass is known: a sampled damper alone is
/// stable up to B·T/m = 2 without delay, and a delay of d ticks lowers that to about π/(2d).
const GLIDE_DAMPER_BT_PER_M: f64 = 0.25;
/// Most the glide's push grows to, share of the force limit, when the device does not move
/// (static friction above the push): it doubles from `GentleMove::force_n` up to this.
const GLIDE_MAX_FORCE_SHARE: f64 = 0.25;
/// Glides at most (each doubling the push when the device stalled).
const GLIDES: usize = 6;
/// Telemetry samples (2 ms apart) on one count after which a glide has ended (stopped where
/// its spring holds it, or stalled): half a second, since the damped approach's last counts
/// are slow (at 50 samples the glide ended a count or so early, and the tests of
/// maxon-re35-amp-3khz and rotary-ironcore-cogging, starting from there, set walls that
/// buzz by the truth).
const GLIDE_REST_SAMPLES: usize = 250;
/// Host time one glide is watched at most, s: a glide covers its distance in a few time
/// constants ([`GLIDE_TAU_S`]) at a speed capped by the encoder-jump limit, seconds in real
/// time even from far off; a device that neither rests nor turns back by then is not
/// following its spring (a board whose encoder counts backwards, far off after its tests, kept
/// the way back watching for tens of minutes while the wait grew with the distance).
const GLIDE_MAX_WAIT_S: f64 = 30.0;
/// Time constant of the glide's approach, s, at least: a tenth of the distance is left after
/// about 2.3 of them.
const GLIDE_TAU_S: f64 = 0.4;

/// The glide of [`move_to`]: a spring and a plain-difference damper that bring the device to
/// the target by themselves, without overshoot, whatever the host's link does, so the glide
/// ends in the same place every time. The spring's origin lies the kinetic band c/(KΔ) beyond
/// the target, so with the device's Coulomb friction c (once identified) its equilibrium is
/// the target; it pushes F at the start (K·Δ·distance = F − c) and less on the way. The damper
/// holds the start's speed to v, which covers the distance in about [`GLIDE_TAU_S`], capped by
/// [`GLIDE_JUMP_SHARE`] of the encoder-jump limit and [`GLIDE_VELOCITY_SHARE`] of the
/// over-velocity limit, and is at least critical (B ≥ 2√(K·m), when the mass is known, K
/// lowered where the damper's cap would not allow it). The firmware's force limit is lowered
/// to 1.1 F so no tick pushes harder. A device that stalls (static friction above the push,
/// or a Stribeck friction that holds it short) glides again from there, with twice the push
/// when it moved less than a quarter of the way, up to [`GLIDE_MAX_FORCE_SHARE`] of the limit.
fn glide(c: &mut Client, walk: &mut Walk, how: GentleMove, far: i64) -> Result<()> {
    let limit = f64::from(walk.cfg.force_limit);
    let mut force = how.force_n.min(limit);
    for _ in 0..GLIDES {
        let distance = (walk.target - walk.at).abs();
        if distance <= far / 2 {
            return Ok(());
        }
        let (push, v) = glide_config(c, walk, how, force, distance);
        let wait_s = (6.0 * distance as f64 * f64::from(c.info.resolution) / v
            + 10.0 * GLIDE_TAU_S
            + super::rest::REST_WAIT_S)
            .min(GLIDE_MAX_WAIT_S);
        let watched = std::time::Instant::now();
        let moved = watch_glide(c, walk, &push, wait_s)?;
        if watched.elapsed().as_secs_f64() >= GLIDE_MAX_WAIT_S {
            c.set_config(&ServoConfig {
                stiffness: 0.0,
                damping: 0.0,
                ..push
            })?;
            bail!(
                "the move to count {} did not come to rest under its spring within {GLIDE_MAX_WAIT_S:.0} s \
                 (from count {}): the device does not follow the spring",
                walk.target,
                walk.at
            );
        }
        walk.at = where_now(c, &walk.cfg)?;
        walk.check_faults(c)?;
        if moved * 4 < distance {
            force = (force * 2.0).min(GLIDE_MAX_FORCE_SHARE * limit).max(force);
        }
    }
    Ok(())
}

/// The config of one glide ([`glide`]) of `distance` counts with push `force`, and the start's
/// speed the damper allows, m/s (rad/s), > 0.
fn glide_config(
    c: &Client,
    walk: &Walk,
    how: GentleMove,
    force: f64,
    distance: i64,
) -> (ServoConfig, f64) {
    let raw_res = f64::from(c.info.resolution);
    let t = 1.0 / f64::from(walk.cfg.servo_rate_hz.max(1));
    let span = distance.max(1) as f64 * raw_res;
    let mut v = span / GLIDE_TAU_S;
    v = v.min(GLIDE_JUMP_SHARE * f64::from(walk.cfg.encoder_jump_counts) * raw_res / t);
    if walk.cfg.max_velocity > 0.0 {
        v = v.min(GLIDE_VELOCITY_SHARE * f64::from(walk.cfg.max_velocity));
    }
    let coulomb = how.friction.map_or(0.0, |f| f.coulomb_n).max(0.0);
    // What drives the device against its friction; at least a tenth of the push (a push below
    // the friction stalls, and the next glide doubles it).
    let drive = (force - coulomb).max(0.1 * force);
    let mut k = drive / span;
    // The firmware's largest damping at shift 0 (its gain of 2^14 codes per count per tick,
    // half the stiffness limit's per tick), with a margin for rounding.
    let mut b_cap = 0.99 * f64::from(c.info.limits.max_stiffness) * t / 2.0;
    if let Some(m) = how.mass.filter(|m| *m > 0.0) {
        b_cap = b_cap.min(GLIDE_DAMPER_BT_PER_M * m / t);
        k = k.min(b_cap * b_cap / (4.0 * m));
    }
    let mut b = drive / v.max(f64::MIN_POSITIVE);
    if let Some(m) = how.mass.filter(|m| *m > 0.0) {
        b = b.max(2.0 * (k * m).sqrt());
    }
    let b = b.min(b_cap);
    let dir = (walk.target - walk.at).signum();
    let band = (coulomb / (k * raw_res)).round() as i64;
    let cfg = ServoConfig {
        stiffness: k as f32,
        damping: b as f32,
        damper: stiffwall_proto::DamperLaw::Difference,
        force_limit: (1.1 * force).min(f64::from(walk.cfg.force_limit)) as f32,
        wall_position: clamp_i32(walk.target + dir * band),
        coarsen_shift: 0,
        ..walk.cfg
    };
    (cfg, (drive / b).max(f64::MIN_POSITIVE))
}

/// Least motion away from the target, counts, that stops a glide as going the wrong way
/// ([`watch_glide`]; or a quarter of the distance, whichever is more).
const GLIDE_WRONG_WAY_COUNTS: i64 = 16;

/// Sets `push` and watches the device until it is at rest ([`GLIDE_REST_SAMPLES`] samples on
/// one count: where it then is follows from the device alone, not from when the host looked),
/// the supervisor stops it, or `seconds` of host time pass. Returns how far it moved toward the
/// target, counts (0: it stalled).
///
/// # Errors
/// The device failing, or moving away from the target by more than a quarter of the distance
/// (at least [`GLIDE_WRONG_WAY_COUNTS`]): a glide starts at rest and never overshoots, so that
/// is a force or encoder of the wrong sign (a board whose encoder counts backwards ran away
/// under the glide's spring, and each glide's wait grew with the distance, for tens of
/// minutes); the spring and damper are then switched off at once.
fn watch_glide(c: &mut Client, walk: &Walk, push: &ServoConfig, seconds: f64) -> Result<i64> {
    let dir = (walk.target - walk.at).signum();
    let wrong_way = ((walk.target - walk.at).abs() / 4).max(GLIDE_WRONG_WAY_COUNTS);
    c.set_config(push)?;
    let rate = c.info.servo_rate_hz.max(1);
    let decimation = u16::try_from((rate / 500).max(1)).unwrap_or(u16::MAX);
    c.stream_start(decimation)?;
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs_f64(seconds);
    let (mut best, mut last, mut same) = (0i64, None::<i32>, 0usize);
    'watch: while std::time::Instant::now() <= deadline {
        let Some(batch) = c.next_batch(super::rest::BATCH_WAIT)? else {
            continue;
        };
        for x in &batch.samples {
            let at = i64::from(push.wall_position) + i64::from(x.count);
            if (walk.at - at) * dir > wrong_way {
                c.set_config(&ServoConfig {
                    stiffness: 0.0,
                    damping: 0.0,
                    ..*push
                })?;
                c.stream_stop()?;
                bail!(
                    "the move to count {} pushed the device the wrong way, from count {} to {at}: \
                     the force's sign or the encoder's direction is inverted",
                    walk.target,
                    walk.at
                );
            }
            best = best.max((at - walk.at) * dir);
            if last == Some(x.count) {
                same += 1;
            } else {
                (last, same) = (Some(x.count), 0);
            }
            if same >= GLIDE_REST_SAMPLES || x.flags & stiffwall_proto::flags::SAFE_MODE != 0 {
                break 'watch;
            }
        }
    }
    c.stream_stop()?;
    Ok(best)
}

/// Watches the device with `cfg` set for up to `seconds` of host time: whether it came to rest
/// (50 samples 2 ms apart on one count) and its last raw count (None: no sample arrived).
///
/// # Errors
/// The device failing.
pub fn watch_rest(c: &mut Client, cfg: &ServoConfig, seconds: f64) -> Result<(bool, Option<i64>)> {
    let rate = c.info.servo_rate_hz.max(1);
    let decimation = u16::try_from((rate / 500).max(1)).unwrap_or(u16::MAX);
    c.stream_start(decimation)?;
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs_f64(seconds);
    let (mut last, mut same) = (None::<i32>, 0u32);
    let at_rest = loop {
        if std::time::Instant::now() > deadline {
            break false;
        }
        if let Some(b) = c.next_batch(super::rest::BATCH_WAIT)? {
            for x in &b.samples {
                if last == Some(x.count) {
                    same += 1;
                } else {
                    (last, same) = (Some(x.count), 0);
                }
            }
            if same >= 50 {
                break true;
            }
        }
    };
    c.stream_stop()?;
    Ok((at_rest, last.map(|n| raw_of(cfg, n))))
}

/// The final check (issue 46): with `cfg` (the config tune leaves) set, the device must come to
/// rest, have no latched fault, and be within [`LEFT_TOLERANCE_COUNTS`] of `start` — or, when
/// `cfg` has a wall, within the band its spring cannot pull the device out of against the
/// static friction `static_friction_n` (N or N·m, when identified), or, when `cfg`'s
/// bidirectional wall has its origin away from the start, rest where that wall holds it.
/// `problem_before`: what went wrong on the way back, if anything.
#[must_use]
pub fn check_left(
    c: &mut Client,
    start: i64,
    cfg: &ServoConfig,
    static_friction_n: Option<f64>,
    settle: Option<&GentleMove>,
    problem_before: Option<String>,
) -> DeviceLeft {
    let watched = watch_rest(c, cfg, 20.0);
    let faults = c.faults().map(|f| f.latched);
    let (at_rest, count) = match &watched {
        Ok((r, n)) => (*r, n.unwrap_or(start)),
        Err(_) => (false, start),
    };
    let latched = faults.as_ref().copied().unwrap_or(0);
    let pulls_elsewhere = cfg.stiffness > 0.0
        && cfg.wall == stiffwall_proto::WallMode::Bidirectional
        && (i64::from(cfg.wall_position) - start).abs() > LEFT_TOLERANCE_COUNTS;
    // A wall left on at the start holds the device anywhere its force K·Δ·(|n| + ½) stays
    // below the static friction F_s: that band is where the user's own wall keeps it.
    let res = f64::from(c.info.resolution) * f64::from(1u32 << cfg.coarsen_shift.min(16));
    let band = match static_friction_n {
        Some(fs) if cfg.stiffness > 0.0 => {
            (fs / (f64::from(cfg.stiffness) * res) + 0.5).ceil() as i64
        }
        _ => 0,
    };
    let approach = approach_band(settle, static_friction_n, f64::from(c.info.resolution));
    let off = (count - start).abs();
    let near = off <= LEFT_TOLERANCE_COUNTS.max(band).max(approach);
    let note = (near && off > LEFT_TOLERANCE_COUNTS.max(band)).then(|| {
        format!(
            "within the {approach} counts that static friction leaves the way back's stiffest \
             spring: any nudge of it moves the device farther"
        )
    });
    let problem = if let Err(e) = &watched {
        Some(format!("the device did not answer: {e}"))
    } else if let Err(e) = &faults {
        Some(format!("reading its faults failed: {e}"))
    } else if let Some(p) = problem_before {
        Some(p)
    } else if !at_rest {
        Some("it did not come to rest within 20 s".into())
    } else if latched != 0 {
        Some("the config left raised a fault".into())
    } else if !near && !pulls_elsewhere {
        Some(format!(
            "it rests {} counts from where it started (tolerance {LEFT_TOLERANCE_COUNTS})",
            count - start
        ))
    } else {
        None
    };
    DeviceLeft {
        count,
        start,
        at_rest,
        faults: fault_names(latched),
        ok: problem.is_none(),
        problem,
        note,
    }
}

/// The least move a nudge of the way back's stiffest spring (`settle`: its `k_settle`, else its
/// K, and the identified Coulomb friction c) can make against static friction F_s
/// (`static_friction_n`), raw counts of `res` (m, rad): breaking away needs an offset F_s/(KΔ), and
/// the device then slides to the kinetic equilibrium c/(KΔ) and on past it by as much (an
/// undamped swing), 2·(F_s − c)/(KΔ). 0 without static friction above c (no device of the
/// model's).
fn approach_band(settle: Option<&GentleMove>, static_friction_n: Option<f64>, res: f64) -> i64 {
    let (Some(how), Some(fs)) = (settle, static_friction_n) else {
        return 0;
    };
    let Some(friction) = how.friction else {
        return 0;
    };
    let k = if how.k_settle > 0.0 {
        how.k_settle
    } else {
        how.k
    };
    let excess = fs - friction.coulomb_n;
    if !(k > 0.0 && res > 0.0 && excess > 0.0) {
        return 0;
    }
    (2.0 * excess / (k * res)).ceil() as i64
}

/// Where tests drift (each puts its wall where the last left the device): when the device
/// rests farther than half the `room` (raw counts; 0: no limit) from `base`'s wall, it is
/// walked back there gently with `how` ([`move_to`]; the search uses a spring of K/16 of the K
/// under test, far below it and so far more stable) and the wall is off again. Where the device
/// rests is read with the damper `brake` on (N·s/m, N·m·s/rad; 0: none): a test whose wall
/// grew leaves it moving. Returns where the device rests (counts of `base`'s wall frame) when
/// it was not moved: at rest there, under the same wall-off brake a test's start reads it
/// with, so the test need not wait for rest again.
///
/// # Errors
/// The device failing, or the move's.
pub fn recentre(
    c: &mut Client,
    base: &ServoConfig,
    how: GentleMove,
    room: i64,
    brake: f64,
) -> Result<Option<i32>> {
    if room <= 0 || how.k.is_nan() || how.k <= 0.0 {
        return Ok(None);
    }
    let wall = i64::from(base.wall_position);
    let brake = brake.min(super::approach::firmware_damping_cap(c, base));
    let (at, rest) = rest_braked(c, base, brake)?;
    if (at - wall).abs() * 2 <= room {
        return Ok(Some(rest));
    }
    move_into(c, base, wall, how, room)?;
    c.set_config(&ServoConfig {
        stiffness: 0.0,
        damping: 0.0,
        ..*base
    })?;
    Ok(None)
}
