//! Step 1 of `hostctl tune`, the experiments with the wall off: the chirp excitation and its
//! identification (m, b, c and, when resolved, a spring-like force), and the breakaway ramps
//! that the model check compares with the identified model.
//!
//! Units: SI at this API (forces N or N·m, positions m or rad); the device speaks in counts
//! and output codes, converted with its reported resolution and force per code. Invariant:
//! every experiment starts from rest with the wall off, so its record depends on the device's
//! counts only (the determinism of [`super::procedure`]).

use super::error::{bail, Context, Result, StepError};
use super::ident::{self, Identified};
use super::model_check::{self, Evidence};
use super::progress::{Progress, Reporter};
use super::settings::{check_cancel, Settings, RAMP_SECONDS};
use super::verify::rest_position;
use stiffwall_client::Client;
use stiffwall_proto::{flags, ExciteProfile, HostMsg, ServoConfig, TABLE_CHUNK};

/// Raw-count resolution and servo period of the connected device.
pub(super) fn device_scale(c: &Client) -> Result<(f64, f64)> {
    let res = f64::from(c.info.resolution);
    let rate = f64::from(c.info.servo_rate_hz);
    if !(res.is_finite() && res > 0.0 && rate > 0.0) {
        bail!("device reports resolution {res} and rate {rate} Hz; cannot tune");
    }
    Ok((res, 1.0 / rate))
}

/// The chirp's and the ramps' config: `cfg` with a centring spring (issue 46) that deflects
/// by [`crate::travel::CENTRING_SHARE`] of `room` counts under `peak_codes` and a damper of
/// ratio [`crate::travel::CENTRING_DAMPING_RATIO`] with the device's `mass`, at least K·T,
/// when the mass is known; without it (the first probe) a stiffer spring,
/// [`crate::travel::PROBE_CENTRING_SHARE`], and the damper K·T. The damper's law is a dead
/// band of one count. The firmware adds both to the excitation's code and records the total,
/// so the fit sees the whole force.
fn centred(
    c: &Client,
    cfg: &ServoConfig,
    peak_codes: i32,
    room: Option<i64>,
    mass: Option<f64>,
) -> ServoConfig {
    let Some(room) = room else {
        // The open-loop fallback: the wall off, the travel window the only guard.
        return ServoConfig {
            stiffness: 0.0,
            damping: 0.0,
            energy_monitor: false,
            ..*cfg
        };
    };
    let fpc = f64::from(c.info.force_per_code);
    let res = f64::from(c.info.resolution) * f64::from(1u32 << cfg.coarsen_shift.min(16));
    let room = room >> cfg.coarsen_shift.min(16);
    let share = if mass.is_some() {
        super::travel::CENTRING_SHARE
    } else {
        super::travel::PROBE_CENTRING_SHARE
    };
    let t = 1.0 / f64::from(c.info.servo_rate_hz.max(1));
    let k = f64::from(peak_codes) * fpc / ((room.max(1) as f64 * share).max(1.0) * res);
    // The sampled spring's own negative damping is about K·T/2: a damper of K·T (β_v = 1)
    // more than cancels it whatever the mass (as long as K·T²/m < 1), so the spring cannot
    // grow even on a device without friction; with the mass known, also ζ = 0.7.
    let b = mass.map_or(k * t, |m| {
        (2.0 * super::travel::CENTRING_DAMPING_RATIO * (k * m.max(0.0)).sqrt()).max(k * t)
    });
    ServoConfig {
        stiffness: k as f32,
        damping: b as f32,
        // It centres from both sides, whatever the user's wall: a one-sided spring (the
        // user's `wall = one-sided`) let omega-one-sided-delay's probe chirp drive the device
        // out of its room on the free side, where it coasted 0.22 m.
        wall: stiffwall_proto::WallMode::Bidirectional,
        // A dead band of one count: the damper answers motion, not a count toggling at rest,
        // so that the same config lets the device come to rest after the excitation.
        damper: stiffwall_proto::DamperLaw::DeadBand { counts: 1 },
        // The centring spring is no wall under test: its one-count toggling at rest (a buzz to
        // the monitor) must not latch a fault between excitations.
        energy_monitor: false,
        ..*cfg
    }
}

/// After an excitation the centring spring stays on until the host's next config, a delay that
/// depends on the link: the device is let come to rest under it first (the same config, so
/// nothing changes with the link's delay), so that where the next step starts depends on the
/// device's counts alone (the determinism of
/// [`crate::procedure`]). Nothing to wait for when the excitation ran with the wall off.
fn settle(c: &mut Client, spring: &ServoConfig) -> Result<()> {
    if spring.stiffness <= 0.0 {
        return Ok(());
    }
    rest_position(c).map(drop)
}

/// The centring spring of one chirp: the room each side (None: the wall off) and the device's
/// mass when known (see [`centred`]).
#[derive(Debug, Clone, Copy)]
struct Centring {
    room: Option<i64>,
    mass: Option<f64>,
}

/// The chirp every level plays: its length, its top frequency (Hz) and its centring spring.
#[derive(Debug, Clone, Copy)]
struct Chirp {
    ticks: u32,
    f1: f32,
    centring: Centring,
}

/// What one chirp gave: the fit, where the device ended (counts from the wall position) and
/// the span of its counts during the excitation.
struct Excited {
    id: Identified,
    end: i32,
    span_counts: i64,
}

/// Least span of counts (peak to peak) the full chirp should move the device over: a device
/// held by a spring (a hand) that the probe moved over fewer counts gets a stronger full chirp
/// (up to [`MAX_CHIRP_BOOST`] times the probe), since a fit over a few counts is biased by
/// quantization (freedom6-firm-grip, a 1500 N/m grip: from a 16-count chirp m = 0.39 kg and
/// c = 0.044 N, from twice the amplitude 0.743 kg and 0.059 N, the plant's 0.75 and 0.06).
const MIN_CHIRP_SPAN_COUNTS: i64 = 32;
/// Fewest ticks of a chirp.
const MIN_CHIRP_TICKS: f64 = 1500.0;
/// Most the full chirp's amplitude grows over the probe's for [`MIN_CHIRP_SPAN_COUNTS`].
const MAX_CHIRP_BOOST: f64 = 4.0;

/// One chirp excitation of `amplitude` codes against `chirp`'s centring spring about where the
/// device rests (the wall of `cfg` moved there), and its identification.
fn excite_and_identify(
    c: &mut Client,
    cfg: &ServoConfig,
    chirp: Chirp,
    amplitude: i32,
    progress: &Reporter<'_>,
) -> Result<Excited> {
    progress.report(Progress::Chirp {
        amplitude_codes: amplitude,
        f1_hz: chirp.f1,
        ticks: chirp.ticks,
    });
    // From rest with the wall off, so that the record does not depend on how long the host took
    // since the previous excitation (determinism: `--fast` and real time see the same counts);
    // the centring spring comes on with the chirp (its damper, which answers every count
    // change, would keep a device behind a slow amplifier from ever resting first).
    c.set_config(&ServoConfig {
        stiffness: 0.0,
        damping: 0.0,
        ..*cfg
    })?;
    super::rest::clear_faults(c)?;
    let rest = rest_position(c)?;
    // The spring's origin where the device rests, so that it holds still until the chirp
    // starts however long the host takes (its force there, K·Δ/2, is below friction); the
    // chirp then swings it about that point, a few counts from the centre at most.
    let at_rest = ServoConfig {
        wall_position: cfg
            .wall_position
            .saturating_add(rest << cfg.coarsen_shift.min(16)),
        ..*cfg
    };
    let Centring { room, mass } = chirp.centring;
    let spring = centred(c, &at_rest, amplitude, room, mass);
    c.set_config(&spring)?;
    let profile = ExciteProfile::Chirp {
        amplitude,
        f0_hz: 0.5,
        f1_hz: chirp.f1,
    };
    let rec = c.excite(profile, chirp.ticks)?;
    settle(c, &spring)?;
    if rec.gaps.missing > 0 {
        bail!(
            "{} telemetry samples lost during identification; use a faster link or --fast",
            rec.gaps.missing
        );
    }
    // The counts in the frame of `cfg`'s wall (the record's are from the spring's origin at
    // the rest): a spring-like force the fit finds (a hand) has its offset there, where the
    // breakaway ramps' model places its preload.
    fit_chirp(c, &rec, i64::from(rest) << cfg.coarsen_shift.min(16))
}

/// The fit of a chirp's record, its counts moved by `origin` into the frame of the tests' wall.
fn fit_chirp(c: &mut Client, rec: &stiffwall_client::Record, origin: i64) -> Result<Excited> {
    let (res, t) = device_scale(c)?;
    let samples: Vec<ident::Sample> = rec
        .samples
        .iter()
        .filter(|x| x.flags & flags::EXCITE != 0)
        .map(|x| ident::Sample {
            count: i64::from(x.count) + origin,
            force: f64::from(x.force_code) * f64::from(c.info.force_per_code),
        })
        .collect();
    let settings = ident::Settings {
        period_s: t,
        resolution: res,
        ..ident::Settings::default()
    };
    let id = ident::identify(&samples, &settings).map_err(|e| {
        // Say why when the supervisor stopped the excitation (e.g. an encoder jump: a fine
        // encoder moves many counts per tick); `identify` then tries gentler levels.
        match c.faults().map_or(0, |f| f.latched) {
            0 => e,
            latched => StepError::Context {
                context: e.to_string(),
                inner: Box::new(StepError::ExcitationTripped { latched }),
            },
        }
    })?;
    if !(id.mass > 0.0 && id.coulomb >= 0.0 && id.equations >= 20) {
        bail!(
            "implausible fit: m = {:.3e}, c = {:.3e} from {} windows",
            id.mass,
            id.coulomb,
            id.equations
        );
    }
    let last = rec.samples.last().map_or(0, |x| {
        x.count.saturating_add(i32::try_from(origin).unwrap_or(0))
    });
    let lo = samples.iter().map(|x| x.count).min().unwrap_or(0);
    let hi = samples.iter().map(|x| x.count).max().unwrap_or(0);
    Ok(Excited {
        id,
        end: last,
        span_counts: hi - lo,
    })
}

/// Step 1: identification with the wall off. A low-frequency chirp (0.5 Hz up to 4 Hz, or
/// rate/250) keeps the velocity fit accurate; the amplitude of half-length probes grows from
/// 5 % of the force limit until a fit succeeds (when the supervisor stops the 5 % probe — an
/// encoder jump on a fine encoder, say — gentler levels down to 0.08 % are tried first), then
/// the full chirp runs at about 5·c (when the limit allows, else at the probe's level) so that
/// the device slides most of the time and Coulomb friction acts as c·sgn(v).
/// Returns the fit, the amplitude used (codes) and where the device ended, in raw counts from
/// the configured wall position.
pub(crate) fn identify(
    c: &mut Client,
    cfg: &ServoConfig,
    s: &Settings,
    progress: &Reporter<'_>,
    room: Option<i64>,
) -> Result<(Identified, i32, i32)> {
    let rate = f64::from(c.info.servo_rate_hz);
    // At least [`MIN_CHIRP_TICKS`]: against the centring spring a device sticks near each
    // turn, and a slow servo's 3 s (600 ticks at 200 Hz) left 16 sliding windows, too few for
    // a fit (maxon-re35-slow-servo then fell back to the chirp with the wall off).
    let chirp = Chirp {
        ticks: (s.excite_seconds * rate)
            .round()
            .clamp(MIN_CHIRP_TICKS, 1e6) as u32,
        f1: (rate / 250.0).min(4.0) as f32,
        centring: Centring { room, mass: None },
    };
    let fpc = f64::from(c.info.force_per_code);
    let limit_code = ((f64::from(cfg.force_limit) / fpc) as i32).clamp(1, c.info.max_code.max(1));
    let mut last_err: Option<StepError> = None;
    let mut levels = vec![0.05, 0.1, 0.2, 0.4];
    let mut i = 0;
    while i < levels.len() {
        let frac = levels[i];
        i += 1;
        check_cancel(c)?;
        let amplitude = ((f64::from(limit_code) * frac) as i32).max(1);
        // A probe finds the level; the full chirp then gives the fit. Both are full length:
        // against the centring spring the device sticks near each turn, and half the windows
        // of a slow servo's chirp are too few for a fit.
        match excite_and_identify(c, cfg, chirp, amplitude, progress) {
            Ok(probe) => {
                let level = Level {
                    amplitude,
                    limit_code,
                };
                return full_chirp(c, cfg, chirp, probe, level, progress);
            }
            Err(e) => {
                // The supervisor stopped the first level: the device may be driven too fast
                // for its limits (a fine encoder), so gentler levels (halving, down to
                // 0.05 / 64) come first, then the stronger ones as before.
                if frac == 0.05 && e.tripped().is_some() {
                    levels = (1..=6).map(|j| 0.05 / f64::from(1u32 << j)).collect();
                    levels.extend([0.1, 0.2, 0.4]);
                    i = 0;
                }
                last_err = Some(e);
            }
        }
    }
    let e = last_err.unwrap_or_else(|| StepError::Failed("no excitation".into()));
    failed_at_every_level(e, cfg)
}

/// A probe's level: its amplitude and the force limit, output codes.
#[derive(Debug, Clone, Copy)]
struct Level {
    amplitude: i32,
    limit_code: i32,
}

/// The full chirp after the probe at `level` moved the device: at about 5·c (at least enough
/// to move it over [`MIN_CHIRP_SPAN_COUNTS`], at most 60 % of the limit; the probe's own level
/// when that is within a quarter of it), its fit; the probe's when the full chirp fails.
fn full_chirp(
    c: &mut Client,
    cfg: &ServoConfig,
    chirp: Chirp,
    probe: Excited,
    level: Level,
    progress: &Reporter<'_>,
) -> Result<(Identified, i32, i32)> {
    let Level {
        amplitude,
        limit_code,
    } = level;
    let fpc = f64::from(c.info.force_per_code);
    let boost = (MIN_CHIRP_SPAN_COUNTS as f64 / probe.span_counts.max(1) as f64)
        .clamp(1.0, MAX_CHIRP_BOOST);
    let floor = (f64::from(amplitude) * boost) as i32;
    let mut wanted = ((5.0 * probe.id.coulomb / fpc) as i32)
        .max(floor)
        .clamp(amplitude, (f64::from(limit_code) * 0.6) as i32);
    if wanted <= amplitude * 5 / 4 {
        wanted = amplitude;
    }
    check_cancel(c)?;
    let full = Chirp {
        centring: Centring {
            mass: Some(probe.id.mass),
            ..chirp.centring
        },
        ..chirp
    };
    Ok(match excite_and_identify(c, cfg, full, wanted, progress) {
        Ok(Excited { id, end, .. }) => (id, wanted, end),
        Err(_) => (probe.id, amplitude, probe.end),
    })
}

/// The error of an identification that failed at every level, naming the faults the
/// supervisor latched (and what to do about an encoder jump).
fn failed_at_every_level<T>(e: StepError, cfg: &ServoConfig) -> Result<T> {
    let Some(latched) = e.tripped() else {
        return Err(e).context("identification failed at every excitation level");
    };
    let advice = if latched & stiffwall_proto::fault::ENCODER_JUMP != 0 {
        format!(
            " (encoder jump: more than {} counts in one tick; a fine encoder needs a higher \
             limit, `hostctl config set --encoder-jump N`)",
            cfg.encoder_jump_counts
        )
    } else {
        String::new()
    };
    Err(e).context(format!(
        "identification failed at every excitation level from 0.08 % to 40 % of the force \
         limit: the supervisor latched faults {}{advice} during the chirp",
        super::left::fault_names(latched).join(", "),
    ))
}

/// Breakaway evidence: a slow force ramp from rest (wall off, config `base` with K = 0) in each
/// direction, up to 3·c (at most 60 % of the force limit), against the identified model on the
/// same ramp. `rest` is where the chirp left the device, in counts of the chirp's frame (the
/// wall was moved there). Fills `e.breakaway_*`.
pub(super) fn breakaway(
    c: &mut Client,
    base: &ServoConfig,
    id: &Identified,
    rest: i32,
    e: &mut Evidence,
    progress: &Reporter<'_>,
    room: i64,
) -> Result<()> {
    let (res, t) = device_scale(c)?;
    let rate = f64::from(c.info.servo_rate_hz);
    let fpc = f64::from(c.info.force_per_code);
    let limit_code = ((f64::from(base.force_limit) / fpc) as i32).clamp(1, c.info.max_code.max(1));
    let peak = ((3.0 * id.coulomb / fpc) as i32)
        .clamp(1, (f64::from(limit_code) * 0.6) as i32)
        .min(i32::from(i16::MAX));
    let ticks = (RAMP_SECONDS * rate).round().max(20.0) as usize;
    let hold = ticks.div_ceil(stiffwall_proto::MAX_TABLE).max(1);
    let len = ticks.div_ceil(hold);
    for (i, sign) in [1i32, -1].into_iter().enumerate() {
        check_cancel(c)?;
        progress.report(Progress::BreakawayRamp {
            peak_codes: sign * peak,
        });
        let table: Vec<i16> = (0..len)
            .map(|k| (sign * (i64::from(peak) * k as i64 / len as i64) as i32) as i16)
            .collect();
        for (j, chunk) in table.chunks(TABLE_CHUNK).enumerate() {
            let values = heapless::Vec::from_slice(chunk)
                .map_err(|_| StepError::Failed("table chunk too long".into()))?;
            c.request(&HostMsg::TableChunk {
                offset: u16::try_from(j * TABLE_CHUNK)?,
                values,
            })?;
        }
        let spring = centred(c, base, peak, Some(room), Some(id.mass));
        c.set_config(&spring)?;
        rest_position(c)?;
        super::verify::clear_faults(c)?;
        let rec = c.excite(
            ExciteProfile::Table {
                len: u16::try_from(len)?,
                hold_ticks: u16::try_from(hold)?,
            },
            u32::try_from(len * hold)?,
        )?;
        settle(c, &spring)?;
        let (counts, force): (Vec<i64>, Vec<f64>) = rec
            .samples
            .iter()
            .filter(|x| x.flags & flags::EXCITE != 0)
            .map(|x| (i64::from(x.count), f64::from(x.force_code) * fpc))
            .unzip();
        e.breakaway_measured[i] = model_check::breakaway_force(&counts, &force);
        // The spring force (if one was identified) at the ramp's start, in the chirp's frame
        // (counts there were relative to the wall before it moved by `rest`).
        let preload = match (id.spring, counts.first()) {
            (Some(sp), Some(&n0)) => {
                -(sp.stiffness * ((n0 + i64::from(rest)) as f64 + 0.5) * res + sp.offset)
            }
            _ => 0.0,
        };
        let model = model_check::model_counts(id, &force, preload, t, res);
        e.breakaway_model[i] = model_check::breakaway_force(&model, &force);
    }
    Ok(())
}
