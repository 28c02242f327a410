//! The replay engines of `hostctl replay`: a recording checked against the models it came
//! from.
//!
//! (a) **Plant replay** ([`replay_model`]): the recorded force codes, each held for one servo
//! period T = 1/`config.servo_rate_hz` (ZOH), drive the exact simulated plant
//! (`stiffwall_sim::rich::RichPlant`; Δ from the recorded `DeviceInfo`). Each run of
//! consecutive samples starts inside its first recorded count n₀ (raw counts), at
//! x₀ = (n₀ + f)·Δ with f the best of [`START_GRID`] positions in [0, 1) and v₀ the better of
//! the estimate from the first ≤ 10 samples and 0, judged on the first [`FIT_WINDOW`] samples.
//! The model's count ⌊x/Δ⌋ after each period is compared with the next recorded count; the
//! error is in encoder ticks (raw counts), RMS and max. Needs decimation 1.
//!
//! (b) **Servo replay** ([`replay_servo`]): the recorded encoder counts are fed, tick by tick,
//! to the firmware's own servo core (`stiffwall_firmware::Servo`) built from the recorded
//! `DeviceInfo` and `ServoConfig`, and its force codes are compared bit for bit with the
//! recorded ones. The supervisor is off on the host; safe mode is read from the recorded
//! flags. Comparable samples: decimation 1; not in safe mode, not in an experiment's hold or
//! excitation phase; and at least `extra_delay_ticks + 1` samples after the start of each run
//! and after any excluded sample.
//!
//! (c) **Energy monitor** ([`crate::monitor_report`]).
//!
//! Units: counts are raw encoder counts relative to the recorded wall, errors in encoder ticks,
//! m, b, c in SI (kg, N·s/m, N; kg·m², N·m·s/rad, N·m for a rotary device), force codes as
//! recorded (× `force_per_code` gives N or N·m), times in servo periods of the recording.
//!
//! Invariants: nothing panics on bad input; every refusal is a [`ReplayError`] naming what the
//! replay needs (decimation 1, a position in range, a valid plant); the monitor's are
//! `MonitorError`s.

use crate::monitor_report::{monitor_recording, MonitorReplay};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;
use stiffwall_client::{Recording, Row};
use stiffwall_firmware::{BoardInfo, Channels, HeldCode, SampledCount, Servo};
use stiffwall_proto::{flags, ServoConfig};
use stiffwall_sim::rich::{ModelError, PlantModel, RichPlant};

/// Why a replay cannot run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReplayError {
    /// (b) on a decimated recording.
    #[error(
        "servo replay needs every servo tick (decimation 1); this recording has decimation {decimation}"
    )]
    ServoDecimated {
        /// The recording's decimation.
        decimation: u16,
    },
    /// (a) on a decimated recording.
    #[error("plant replay needs the force of every servo tick (decimation 1); this recording has decimation {decimation}")]
    PlantDecimated {
        /// The recording's decimation.
        decimation: u16,
    },
    /// (b) with a recorded position the servo's i32 cannot hold.
    #[error("servo replay: the recorded position {pos0} is outside the servo's i32 range")]
    PositionRange {
        /// The recorded absolute position, counts.
        pos0: i64,
    },
    /// (a) with a plant model out of range (the model's error names the field).
    #[error("plant replay: {0}")]
    Plant(#[from] ModelError),
}

/// `Result` of this module.
pub type Result<T, E = ReplayError> = std::result::Result<T, E>;

/// Samples at the start of each run used to fit its initial state in the plant replay.
pub const FIT_WINDOW: usize = 20_000;
/// Candidate positions within the first count tried for the plant replay's start.
pub const START_GRID: usize = 20;

/// Result of the plant replay (a).
#[derive(Debug, Clone, Serialize)]
pub struct PlantReplay {
    /// m, b, c used (SI).
    pub mass: f64,
    /// Viscous friction.
    pub viscous: f64,
    /// Coulomb friction.
    pub coulomb: f64,
    /// Where they came from.
    pub source: String,
    /// Samples compared (all but the first of each run).
    pub compared: usize,
    /// Runs of consecutive samples (each restarted from its first recorded count).
    pub runs: usize,
    /// RMS of model − recorded count, encoder ticks.
    pub rms_ticks: f64,
    /// Largest |model − recorded count|, encoder ticks.
    pub max_ticks: i64,
    /// Fitted start of each run: position within the first count (fraction of Δ) and
    /// velocity (m/s or rad/s).
    pub starts: Vec<(f64, f64)>,
    /// Time (s, from the first sample) and recorded / model counts, for plotting.
    #[serde(skip)]
    pub trace: Vec<(f64, i64, i64)>,
}

/// One force code that the host servo did not reproduce.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Mismatch {
    /// Sample number.
    pub seq: u32,
    /// Recorded count.
    pub count: i32,
    /// Recorded force code.
    pub recorded: i32,
    /// Host servo's force code.
    pub replayed: i32,
}

/// Result of the servo replay (b).
#[derive(Debug, Clone, Default, Serialize)]
pub struct ServoReplay {
    /// Samples compared.
    pub compared: usize,
    /// Of those, reproduced bit for bit.
    pub matched: usize,
    /// Excluded: delay-line / velocity warm-up after a run start or an excluded sample.
    pub excluded_warmup: usize,
    /// Excluded: safe mode.
    pub excluded_safe_mode: usize,
    /// Excluded: release hold phase or excitation (force not from the wall law).
    pub excluded_experiment: usize,
    /// The first mismatches (at most 20).
    pub mismatches: Vec<Mismatch>,
    /// Total mismatches.
    pub mismatch_count: usize,
}

/// Both replays (None with the reason when one cannot run).
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Samples in the recording.
    pub samples: usize,
    /// Sample numbers missing in the recording.
    pub missing: u64,
    /// (a), if it ran.
    pub plant: Option<PlantReplay>,
    /// Why (a) did not run.
    pub plant_skipped: Option<String>,
    /// (b), if it ran.
    pub servo: Option<ServoReplay>,
    /// Why (b) did not run.
    pub servo_skipped: Option<String>,
    /// (c) the firmware's energy monitor over the recording, if it ran.
    pub monitor: Option<MonitorReplay>,
    /// Why (c) did not run.
    pub monitor_skipped: Option<String>,
}

/// The firmware's board facts, rebuilt from the recorded handshake.
#[must_use]
pub fn board_of(d: &stiffwall_proto::DeviceInfo) -> BoardInfo {
    BoardInfo {
        name: "recorded",
        resolution: d.resolution,
        counts_per_rev: d.counts_per_rev,
        encoder_bits: d.encoder_bits,
        force_per_code: d.force_per_code,
        max_code: d.max_code,
        min_rate_hz: d.limits.min_rate_hz,
        max_rate_hz: d.limits.max_rate_hz,
    }
}

/// Replay (b): the recorded counts through the firmware servo core.
///
/// # Errors
/// A decimated recording, or a recorded position outside the servo's range.
pub fn replay_servo(rec: &Recording) -> Result<ServoReplay> {
    if rec.header.decimation != 1 {
        return Err(ReplayError::ServoDecimated {
            decimation: rec.header.decimation,
        });
    }
    let board = board_of(&rec.header.device);
    let wall = rec.header.config.wall_position;
    let cfg_base = ServoConfig {
        energy_monitor: false,
        max_velocity: 0.0,
        encoder_jump_counts: u32::MAX,
        heartbeat_timeout_ms: 0,
        ..rec.header.config
    };
    let warm = usize::from(rec.header.config.extra_delay_ticks) + 1;
    let encoder = Encoder::of(&board, wall);
    let mut r = ServoReplay::default();
    for seg in rec.segments() {
        let rows = &rec.rows[seg];
        let cfg = ServoConfig {
            wall_position: encoder.host_wall(rows[0].sample.count)?,
            ..cfg_base
        };
        replay_run(&mut r, rows, board, &cfg, encoder, warm);
    }
    Ok(r)
}

/// The recorded device's encoder: the hardware counter's width in bits (1..=32) and their
/// mask, and the recorded wall (the device's absolute position is count + wall).
#[derive(Debug, Clone, Copy)]
struct Encoder {
    bits: u32,
    mask: u32,
    wall: i32,
}

impl Encoder {
    /// The encoder of `board` (its `encoder_bits`, clamped to 1..=32) with the recorded `wall`.
    fn of(board: &BoardInfo, wall: i32) -> Self {
        let bits = u32::from(board.encoder_bits.clamp(1, 32));
        let mask: u32 = if bits >= 32 {
            u32::MAX
        } else {
            (1u32 << bits) - 1
        };
        Self { bits, mask, wall }
    }

    /// The counter's reading `raw` sign-extended from its width.
    fn sext(self, raw: u32) -> i64 {
        let sh = 32 - self.bits;
        i64::from((raw.wrapping_shl(sh) as i32).wrapping_shr(sh))
    }

    /// The counter's reading at the recorded `count`.
    fn raw(self, count: i32) -> u32 {
        ((i64::from(count) + i64::from(self.wall)) as u32) & self.mask
    }

    /// The host servo's wall for a run starting at the recorded count `count0`: the host
    /// servo primes its position from the (sign-extended) hardware counter, so its wall is
    /// the recorded one shifted by the difference.
    fn host_wall(self, count0: i32) -> Result<i32> {
        let pos0 = i64::from(count0) + i64::from(self.wall);
        let raw0 = (pos0 as u32) & self.mask;
        let host_wall = i64::from(self.wall) + (self.sext(raw0) - pos0);
        i32::try_from(host_wall).map_err(|_| ReplayError::PositionRange { pos0 })
    }
}

/// One run of consecutive `rows` through a fresh servo of `board` with `cfg`, counted into
/// `r`: samples in safe mode or an experiment excluded, then `warm` samples of warm-up, the
/// rest compared with the recorded force codes.
fn replay_run(
    r: &mut ServoReplay,
    rows: &[Row],
    board: BoardInfo,
    cfg: &ServoConfig,
    encoder: Encoder,
    warm: usize,
) {
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut servo: Servo<'_> = Servo::new(board, cfg, sp);
    let mut since_clean = 0usize;
    for row in rows {
        let s = row.sample;
        let raw = encoder.raw(s.count);
        let mut out = HeldCode(0);
        let code = servo.tick(s.tick, &mut SampledCount(raw), &mut out);
        if s.flags & flags::SAFE_MODE != 0 {
            r.excluded_safe_mode += 1;
            since_clean = 0;
            continue;
        }
        if s.flags & (flags::HOLD | flags::EXCITE) != 0 {
            r.excluded_experiment += 1;
            since_clean = 0;
            continue;
        }
        since_clean += 1;
        if since_clean <= warm {
            r.excluded_warmup += 1;
            continue;
        }
        r.compared += 1;
        if code == s.force_code {
            r.matched += 1;
        } else {
            r.mismatch_count += 1;
            if r.mismatches.len() < 20 {
                r.mismatches.push(Mismatch {
                    seq: row.seq,
                    count: s.count,
                    recorded: s.force_code,
                    replayed: code,
                });
            }
        }
    }
}

/// Replay (a): the recorded forces through the exact simulated plant.
///
/// # Errors
/// A decimated recording, or m, b, c out of the model's range.
pub fn replay_plant(rec: &Recording, m: f64, b: f64, c: f64) -> Result<PlantReplay> {
    let delta = f64::from(rec.header.device.resolution);
    let model = PlantModel::rigid(m, b, c, delta)?;
    replay_model(rec, &model)
}

/// Replay (a) through any plant model (a plant file's): the recorded force codes are the
/// commands, the model's amplifier (limit, dead band, filter) acts on them.
///
/// # Errors
/// A decimated recording, or a model out of range.
pub fn replay_model(rec: &Recording, model: &PlantModel) -> Result<PlantReplay> {
    let (m, b, c) = (model.mass_kg, model.viscous_ns_per_m, model.coulomb_n);
    if rec.header.decimation != 1 {
        return Err(ReplayError::PlantDecimated {
            decimation: rec.header.decimation,
        });
    }
    let d = &rec.header.device;
    let delta = f64::from(d.resolution);
    let fpc = f64::from(d.force_per_code);
    let period = 1.0 / f64::from(rec.header.config.servo_rate_hz.max(1));
    let wall = i64::from(rec.header.config.wall_position);
    let model = PlantModel {
        resolution_m: delta,
        ..*model
    };
    let mut plant = RichPlant::new(&model)?;
    let t0 = rec.rows.first().map_or(0, |r| r.seq);
    let mut trace = Vec::with_capacity(rec.rows.len());
    let (mut sum2, mut max, mut n, mut runs) = (0.0f64, 0i64, 0usize, 0usize);
    let mut starts = Vec::new();
    for seg in rec.segments() {
        let rows = &rec.rows[seg];
        runs += 1;
        let abs = |i: usize| i64::from(rows[i].sample.count) + wall;
        let k = (rows.len() - 1).min(10);
        let v_est = if k > 0 {
            (abs(k) - abs(0)) as f64 * delta / (k as f64 * period)
        } else {
            0.0
        };
        // The recording cannot say where inside its first count the device was, nor its exact
        // velocity: pick the start (x₀ within the first count, v₀ ∈ {estimate, 0}) that best
        // explains the first FIT_WINDOW samples, then replay the whole run from it.
        let window = rows.len().min(FIT_WINDOW);
        let mut best = (f64::INFINITY, 0.5, v_est);
        for v0 in [v_est, 0.0] {
            for j in 0..START_GRID {
                let frac = (j as f64 + 0.5) / START_GRID as f64;
                plant.set_state((abs(0) as f64 + frac) * delta, v0);
                let mut sse = 0.0;
                for i in 1..window {
                    plant.advance(f64::from(rows[i - 1].sample.force_code) * fpc, period);
                    let e = (plant.encoder_count() - abs(i)) as f64;
                    sse += e * e;
                }
                if sse < best.0 {
                    best = (sse, frac, v0);
                }
            }
        }
        plant.set_state((abs(0) as f64 + best.1) * delta, best.2);
        starts.push((best.1, best.2));
        let t = |i: usize| f64::from(rows[i].seq.wrapping_sub(t0)) * period;
        trace.push((t(0), abs(0) - wall, abs(0) - wall));
        for i in 1..rows.len() {
            plant.advance(f64::from(rows[i - 1].sample.force_code) * fpc, period);
            let model = plant.encoder_count();
            let e = model - abs(i);
            sum2 += (e as f64) * (e as f64);
            max = max.max(e.abs());
            n += 1;
            trace.push((t(i), abs(i) - wall, model - wall));
        }
    }
    Ok(PlantReplay {
        mass: m,
        viscous: b,
        coulomb: c,
        source: String::new(),
        compared: n,
        runs,
        rms_ticks: if n > 0 { (sum2 / n as f64).sqrt() } else { 0.0 },
        max_ticks: max,
        starts,
        trace,
    })
}

/// Samples missing after the last row of a recording's text: the sum of the `# gap: N samples
/// missing …` notes that no data row follows (a recording that lost its last samples ends with
/// such a note; gaps between rows are counted from the rows' `seq`).
#[must_use]
pub fn trailing_gap(text: &str) -> u64 {
    let mut trailing = 0u64;
    for line in text.lines() {
        let line = line.trim();
        if let Some(rest) = line.strip_prefix("# gap:") {
            let n = rest
                .split_whitespace()
                .next()
                .and_then(|w| w.parse::<u64>().ok())
                .unwrap_or(0);
            trailing = trailing.saturating_add(n);
        } else if !line.is_empty() && !line.starts_with('#') && !line.starts_with("seq") {
            trailing = 0; // a data row: the notes before it are gaps between rows
        }
    }
    trailing
}

/// All three replays of a parsed recording: (a) through `plant` (the model and where it came
/// from, or why there is none), (b) and (c); a replay that cannot run says why in its
/// `*_skipped` field.
#[must_use]
pub fn replay(rec: &Recording, plant: Result<(PlantModel, String), String>) -> Report {
    let (plant, plant_skipped) = match plant {
        Err(e) => (None, Some(e)),
        Ok((model, source)) => match replay_model(rec, &model) {
            Ok(mut p) => {
                p.source = source;
                (Some(p), None)
            }
            Err(e) => (None, Some(e.to_string())),
        },
    };
    let (servo, servo_skipped) = match replay_servo(rec) {
        Ok(s) => (Some(s), None),
        Err(e) => (None, Some(e.to_string())),
    };
    let (monitor, monitor_skipped) = match monitor_recording(rec, &board_of(&rec.header.device)) {
        Ok(m) => (Some(m), None),
        Err(e) => (None, Some(e.to_string())),
    };
    Report {
        samples: rec.rows.len(),
        missing: rec.missing(),
        plant,
        plant_skipped,
        servo,
        servo_skipped,
        monitor,
        monitor_skipped,
    }
}

/// The text of `hostctl replay`: the file's sample counts, then the plant (a), servo (b) and
/// energy-monitor (c) replays, each as run or why it was skipped.
#[must_use]
pub fn render(file: &Path, r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: {} samples, {} missing sample numbers",
        file.display(),
        r.samples,
        r.missing
    );
    match (&r.plant, &r.plant_skipped) {
        (Some(p), _) => {
            let _ = writeln!(
                s,
                "(a) plant replay [m = {:.4e}, b = {:.4e}, c = {:.4e}; {}]: {} samples in {} run(s): model − recording RMS {:.3} ticks, max {} ticks",
                p.mass, p.viscous, p.coulomb, p.source, p.compared, p.runs, p.rms_ticks, p.max_ticks
            );
        }
        (None, Some(why)) => {
            let _ = writeln!(s, "(a) plant replay skipped: {why}");
        }
        (None, None) => {}
    }
    match (&r.servo, &r.servo_skipped) {
        (Some(v), _) => {
            let _ = writeln!(
                s,
                "(b) servo replay: {}/{} force codes reproduced bit for bit{} (excluded: {} warm-up, {} safe mode, {} hold/excitation)",
                v.matched,
                v.compared,
                if v.mismatch_count == 0 { "" } else { " — MISMATCHES" },
                v.excluded_warmup,
                v.excluded_safe_mode,
                v.excluded_experiment
            );
            for m in &v.mismatches {
                let _ = writeln!(
                    s,
                    "    seq {}: count {} recorded {} replayed {}",
                    m.seq, m.count, m.recorded, m.replayed
                );
            }
        }
        (None, Some(why)) => {
            let _ = writeln!(s, "(b) servo replay skipped: {why}");
        }
        (None, None) => {}
    }
    match (&r.monitor, &r.monitor_skipped) {
        (Some(m), _) => {
            let _ = writeln!(s, "{}", crate::monitor_report::render(m));
        }
        (None, Some(why)) => {
            let _ = writeln!(s, "(c) energy monitor skipped: {why}");
        }
        (None, None) => {}
    }
    s.pop();
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use stiffwall_client::Header;
    use stiffwall_proto::{DeviceInfo, Limits, Sample};

    fn info(bits: u8) -> DeviceInfo {
        DeviceInfo {
            protocol_version: stiffwall_proto::PROTOCOL_VERSION,
            firmware_name: "stiffwall".try_into().unwrap(),
            firmware_version: "0.1.0".try_into().unwrap(),
            board: "test".try_into().unwrap(),
            servo_rate_hz: 1000,
            counts_per_rev: 0,
            resolution: 1.0 / 8192.0,
            encoder_bits: bits,
            force_per_code: 1.0 / 1024.0,
            max_code: 30_000,
            limits: Limits {
                min_rate_hz: 100,
                max_rate_hz: 20_000,
                max_stiffness: 1.0e4,
                max_force: 29.0,
                max_delay_ticks: 31,
                max_coarsen_shift: 16,
                telemetry_batch: 24,
                max_table: 1024,
            },
        }
    }

    /// Issue 11, item 7: a recording that lost its last samples ends with a gap note and no
    /// row after it; replay counts those samples with the gaps between rows.
    #[test]
    fn trailing_gap_is_reported() {
        let header = Header {
            host_time_unix_s: 0.0,
            target: "test".into(),
            virtual_plant: None,
            decimation: 1,
            device: info(32),
            config: ServoConfig::default(),
        };
        let sample = |t: u32| Sample {
            tick: t,
            count: 0,
            force_code: 0,
            flags: 0,
            energy: 0,
        };
        let mut out = Vec::new();
        let mut w = stiffwall_client::Writer::new(&mut out, &header).unwrap();
        w.batch(0, &[sample(0), sample(1)], 0).unwrap();
        w.batch(5, &[sample(5)], 0).unwrap(); // 3 missing between rows
        w.batch(10, &[], 4).unwrap(); // 4 missing at the end, as session::pump writes them
        w.note("end: test").unwrap();
        w.finish().unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(
            text.contains("# gap: 4 samples missing before seq 10"),
            "{text}"
        );
        let rec = stiffwall_client::parse_recording(&text).unwrap();
        assert_eq!(rec.missing(), 3);
        assert_eq!(trailing_gap(&text), 4);
        assert_eq!(rec.missing() + trailing_gap(&text), 7);
        // Without a trailing note nothing is added.
        let cut = text.replace(
            "# gap: 4 samples missing before seq 10 (device-dropped 4, link-lost 0)\n",
            "",
        );
        assert_eq!(trailing_gap(&cut), 0, "{cut}");
    }

    /// A "device" run on the host: the firmware servo fed a trajectory that crosses the
    /// 16-bit counter's wrap several times; the recording starts mid-way, where the device's
    /// unwrapped position no longer fits the counter. Replay (b) must still match bit for bit,
    /// and a changed code must be caught.
    #[test]
    fn sixteen_bit_counter_recording_mid_wrap_replays_bit_for_bit() {
        const WALL: i32 = 38_000;
        let dev = info(16);
        let cfg = ServoConfig {
            stiffness: 3.0,
            damping: 0.01,
            extra_delay_ticks: 3,
            wall_position: WALL,
            force_limit: 20.0,
            energy_monitor: false,
            encoder_jump_counts: 1 << 20,
            ..ServoConfig::default()
        };
        let board = board_of(&dev);
        let mut ch = Channels::new();
        let (sp, _hp) = ch.split();
        let mut servo: Servo<'_> = Servo::new(board, &cfg, sp);
        let mut rows = Vec::new();
        for t in 0..20_000u32 {
            // Up to ±40000 counts: beyond the 16-bit counter's signed range, around the wall.
            let pos = (40_000.0 * (f64::from(t) * 0.0005).sin()).round() as i64;
            let raw = (pos as u32) & 0xffff;
            let mut out = HeldCode(0);
            let code = servo.tick(t, &mut SampledCount(raw), &mut out);
            // From t = 2500 on, the position (≈ 38000) no longer fits the counter.
            if t >= 2_500 {
                rows.push(Row {
                    seq: t,
                    sample: Sample {
                        tick: t,
                        // As the device reports it: its own unwrapped position relative to
                        // the wall.
                        count: servo.position() - WALL,
                        force_code: code,
                        flags: 0,
                        energy: 0,
                    },
                });
            }
        }
        let mut rec = Recording {
            header: Header {
                host_time_unix_s: 0.0,
                target: "test".into(),
                virtual_plant: None,
                decimation: 1,
                device: dev,
                config: cfg,
            },
            rows,
        };
        let r = replay_servo(&rec).unwrap();
        assert_eq!(r.excluded_warmup, 4);
        assert_eq!((r.compared, r.mismatch_count), (17_496, 0), "{r:?}");
        assert!(rec
            .rows
            .iter()
            .any(|r| r.sample.force_code.abs() > 100 && r.sample.force_code.abs() < 20_000));
        rec.rows[9_000].sample.force_code += 1;
        let r = replay_servo(&rec).unwrap();
        assert_eq!(r.mismatch_count, 1);
        assert_eq!(r.mismatches[0].seq, 11_500);
    }
}
