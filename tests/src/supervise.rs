//! The firmware's supervisor against a simulated plant (issue 10, item 6): software in the
//! loop, the real firmware core (`stiffwall-firmware`'s `Servo`) stepping a [`SampledPlant`].
//!
//! Units: SI at the plant, raw counts and output codes at the firmware, ticks of the servo.
//! The board is the virtual device's for a plant file: a 32-bit counter with Δ of the plant,
//! a 16-bit amplifier (±32767 codes) whose full scale is the plant's force limit, and the
//! virtual device's boot config (energy monitor on, its 1 kJ energy limit, default growth trip,
//! force limit at full scale, no heartbeat) with the stiffness forced to a chosen K.
//!
//! One tick: read ⌊x/Δ⌋ → `Servo::tick` → hold the written code × force-per-code on the plant
//! for T (ZOH). Runs start like the trials of the K* criterion: an impact at the wall surface
//! moving into the wall, or a release from rest; "onset" is tick 0 (first contact, release).
//!
//! Invariant: deterministic; the run stops only at its length.

use crate::kstar::{SampledPlant, Trial};
use stiffwall_firmware::{BoardInfo, Channels, HeldCode, SampledCount, Servo};
use stiffwall_proto::{ServoConfig, WallMode};

/// Output codes of the virtual amplifier (16-bit bipolar), as the virtual device's.
pub const MAX_CODE: i32 = 32_767;

/// The virtual device's board for a plant: Δ, counts/rev (0 linear), full scale, N (N·m).
#[must_use]
pub fn board(resolution_m: f64, counts_per_rev: u32, full_scale_n: f64) -> BoardInfo {
    BoardInfo {
        name: "virtual",
        resolution: resolution_m as f32,
        counts_per_rev,
        encoder_bits: 32,
        force_per_code: (full_scale_n / f64::from(MAX_CODE)) as f32,
        max_code: MAX_CODE,
        min_rate_hz: 100,
        max_rate_hz: 20_000,
    }
}

/// The virtual device's boot config (fast mode) with stiffness `k`, the plant's servo rate,
/// delay and wall mode.
#[must_use]
pub fn config(
    b: &BoardInfo,
    k: f64,
    period_s: f64,
    delay_ticks: u8,
    one_sided: bool,
) -> ServoConfig {
    ServoConfig {
        stiffness: k as f32,
        servo_rate_hz: (1.0 / period_s).round().clamp(100.0, 20_000.0) as u32,
        extra_delay_ticks: delay_ticks,
        wall: if one_sided {
            WallMode::OneSided
        } else {
            WallMode::Bidirectional
        },
        force_limit: b.force_per_code * b.max_code as f32,
        energy_limit: 1.0e3,
        heartbeat_timeout_ms: 0,
        ..ServoConfig::default()
    }
}

/// What the supervisor did in one run.
#[derive(Debug, Clone, PartialEq)]
pub struct SupervisedRun {
    /// Tick (from the impact) at which the first fault latched.
    pub trip_tick: Option<usize>,
    /// Latched fault bits at the end.
    pub faults: u32,
    /// Ticks after the trip with a nonzero output code (0 when the force was zeroed).
    pub nonzero_after_trip: usize,
    /// Counts (from the wall), one per tick.
    pub counts: Vec<i64>,
    /// Output codes, one per tick.
    pub codes: Vec<i32>,
}

impl SupervisedRun {
    /// Largest |count| over the run.
    #[must_use]
    pub fn peak(&self) -> i64 {
        self.counts.iter().map(|n| n.abs()).max().unwrap_or(0)
    }

    /// Stopped: a fault latched and the output stayed zero after it.
    #[must_use]
    pub fn stopped(&self) -> bool {
        self.trip_tick.is_some() && self.nonzero_after_trip == 0
    }
}

/// A trial of the K* criterion ([`Trial::initial_state`]: an impact from the wall surface or
/// a release from rest) under the firmware servo of `b`/`cfg`, `ticks` long. The wall is at
/// count `trial.wall`; the firmware's origin is the count of the first reading.
pub fn run<P: SampledPlant>(
    mut plant: P,
    b: BoardInfo,
    cfg: &ServoConfig,
    period_s: f64,
    trial: Trial,
    resolution_m: f64,
    ticks: usize,
) -> SupervisedRun {
    trial.start(&mut plant, resolution_m);
    let cfg = ServoConfig {
        wall_position: trial.wall as i32,
        ..*cfg
    };
    let cfg = &cfg;
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut servo: Servo<'_> = Servo::new(b, cfg, sp);
    let fpc = f64::from(b.force_per_code);
    let mut run = SupervisedRun {
        trip_tick: None,
        faults: 0,
        nonzero_after_trip: 0,
        counts: Vec::with_capacity(ticks),
        codes: Vec::with_capacity(ticks),
    };
    for t in 0..ticks {
        let n = plant.encoder_count() - trial.wall;
        let mut out = HeldCode(0);
        servo.tick(
            t as u32,
            &mut SampledCount((n + trial.wall) as u32),
            &mut out,
        );
        plant.advance(f64::from(out.0) * fpc, period_s);
        run.counts.push(n);
        run.codes.push(out.0);
        if run.trip_tick.is_some() {
            if out.0 != 0 {
                run.nonzero_after_trip += 1;
            }
        } else if servo.faults() != 0 {
            run.trip_tick = Some(t);
            if out.0 != 0 {
                run.nonzero_after_trip += 1;
            }
        }
    }
    run.faults = servo.faults();
    run
}
