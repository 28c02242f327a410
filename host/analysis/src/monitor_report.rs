//! The firmware's energy monitor run over a recording (`hostctl replay`, part (c)): the same
//! dissipation check as on the device (`stiffwall_core::monitor`, storage function H_T (35) at
//! turning points, growth score, energy limit), so a user sees after the fact where and when
//! the energy grew and what the device latched.
//!
//! Units: `count` raw encoder counts relative to the wall, `n` effective counts
//! (`count >> coarsen_shift`), energies `e8` in units of K·Δ_eff²/8 (the telemetry `energy`
//! field; ×K·Δ_eff²/8 gives joules), ticks the device's servo ticks.
//!
//! Invariants: the host monitor starts, stops and forgets its history where the device's does,
//! read from the recorded flags: a run of consecutive samples starts fresh; the release (HOLD →
//! RELEASED), the start and the end of an experiment, and clearing faults (SAFE_MODE 1 → 0)
//! forget the history before the tick; a fault latched during an experiment (SAFE_MODE 0 → 1)
//! forgets it after the tick, whose update the device ran in its previous mode; hold and
//! excitation ticks and ticks outside a one-sided wall are not monitored. With these, the host
//! monitor's state equals the device's at every tick of a decimation-1 recording, so an event
//! is reported at the tick where the device (with its monitor on) latched it. It runs even when
//! the recording's config had the monitor off, and then says what *would* have latched.

use serde::Serialize;
use std::fmt::Write as _;
use stiffwall_client::{Recording, Row};
use stiffwall_core::monitor::{self, energy_e8, EnergyMonitor};
use stiffwall_firmware::{BoardInfo, Fx64, Gains};
use stiffwall_proto::{flags, ServoConfig, WallMode};

/// Why the monitor replay cannot run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MonitorError {
    /// A decimated recording.
    #[error("the energy monitor needs every servo tick (decimation 1); this recording has decimation {decimation}")]
    Decimated {
        /// The recording's decimation.
        decimation: u16,
    },
    /// K·Δ_eff² zero.
    #[error("the energy monitor needs a stiffness K > 0 (the storage function is K·Δ_eff²·H)")]
    NoStiffness,
}

/// One energy-monitor event: the first tick of a growth trip or of an excursion over the limit.
#[derive(Debug, Clone, Serialize)]
pub struct MonitorEvent {
    /// `ENERGY_GROWTH` or `ENERGY_LIMIT` (the fault the device latches).
    pub fault: &'static str,
    /// Sample number.
    pub seq: u32,
    /// Servo tick.
    pub tick: u32,
    /// Count at this tick, raw counts from the wall.
    pub count: i32,
    /// Growth score after this tick.
    pub score: i32,
    /// Effective count of the peak: the turning point that tripped (growth) or this tick's
    /// count (limit).
    pub peak_n: i32,
    /// Its energy e8, units K·Δ_eff²/8.
    pub peak_e8: u64,
    /// Its energy, J (J·rad⁻²… for rotary devices: K·Δ_eff² in the config's units).
    pub peak_energy_j: f64,
    /// The recording shows the device entering safe mode at this very tick.
    pub device_latched_here: bool,
}

/// Result of the monitor replay (c).
#[derive(Debug, Clone, Serialize)]
pub struct MonitorReplay {
    /// The device ran its monitor (config `energy_monitor` on and K > 0).
    pub device_monitor_on: bool,
    /// Growth score that trips (`energy_growth_cycles`).
    pub trip: i32,
    /// Energy limit, units K·Δ_eff²/8.
    pub limit_e8: u64,
    /// One unit of e8, K·Δ_eff²/8, in J (N·m/rad · rad² = J on a rotary device).
    pub e8_j: f64,
    /// Ticks monitored.
    pub monitored: usize,
    /// Turning points seen.
    pub turning_points: usize,
    /// Largest energy e8 on a monitored tick and its tick.
    pub max_e8: Option<(u64, u32)>,
    /// The events, in order.
    pub events: Vec<MonitorEvent>,
}

const PHASE: u16 = flags::HOLD | flags::RELEASED | flags::EXCITE;

/// Runs the energy monitor over `rec` (recorded on `board`) as the device ran it.
///
/// # Errors
/// When the recording is decimated (turning points need every tick) or K·Δ_eff² is zero.
pub fn monitor_recording(
    rec: &Recording,
    board: &BoardInfo,
) -> Result<MonitorReplay, MonitorError> {
    if rec.header.decimation != 1 {
        return Err(MonitorError::Decimated {
            decimation: rec.header.decimation,
        });
    }
    let cfg = rec.header.config;
    let g: Gains<Fx64> = Gains::from_config(
        &ServoConfig {
            energy_monitor: true,
            ..cfg
        },
        board,
    );
    if !g.energy_monitor {
        return Err(MonitorError::NoStiffness);
    }
    let de = f64::from(board.delta_eff(cfg.coarsen_shift));
    let mut r = MonitorReplay {
        device_monitor_on: cfg.energy_monitor && g.energy_monitor,
        trip: g.growth_trip,
        limit_e8: g.energy_limit_e8,
        e8_j: f64::from(cfg.stiffness) * de * de / 8.0,
        monitored: 0,
        turning_points: 0,
        max_e8: None,
        events: Vec::new(),
    };
    let mut t = Tracker {
        g: &g,
        m: EnergyMonitor::default(),
        growing: false,
        over: false,
    };
    let one_sided = cfg.wall == WallMode::OneSided;
    for seg in rec.segments() {
        t.reset();
        let mut prev: Option<u16> = None;
        for row in &rec.rows[seg] {
            let s = row.sample;
            let safe = s.flags & flags::SAFE_MODE != 0;
            let was_safe = prev.is_some_and(|p| p & flags::SAFE_MODE != 0);
            let prev_phase = prev.map_or(s.flags & PHASE, |p| p & PHASE);
            let latched_here = prev.is_some() && safe && !was_safe;
            // The mode the device's monitor ran in this tick: the previous one at a latch (the
            // latch ends the experiment after the update), else the recorded one.
            let phase = if latched_here {
                prev_phase
            } else {
                s.flags & PHASE
            };
            let forget_before =
                (was_safe && !safe) || (!safe && !latched_here && phase != prev_phase);
            if forget_before {
                t.reset();
            }
            let n = s.count >> g.shift.min(31);
            if phase & (flags::HOLD | flags::EXCITE) == 0 {
                if one_sided && n < 0 {
                    t.reset();
                } else {
                    t.update(&mut r, row, n, latched_here);
                }
            }
            if latched_here && prev_phase != 0 {
                t.reset();
            }
            prev = Some(s.flags);
        }
    }
    Ok(r)
}

/// The monitor as the device ran it over a recording, with the fault bits it last raised.
struct Tracker<'a> {
    g: &'a Gains<Fx64>,
    m: EnergyMonitor,
    /// The growth fault was raised at the last turning point.
    growing: bool,
    /// The limit fault was raised at the last update.
    over: bool,
}

impl Tracker<'_> {
    /// Forgets the motion (as the device's monitor does on a reset).
    fn reset(&mut self) {
        self.m.reset();
        (self.growing, self.over) = (false, false);
    }

    /// One monitored tick at effective count `n`: the monitor's update, the largest energy,
    /// and an event for every fault it newly raises.
    fn update(&mut self, r: &mut MonitorReplay, row: &Row, n: i32, latched_here: bool) {
        let s = row.sample;
        r.monitored += 1;
        let (bits, turn) = self.m.update(n, self.g.growth_trip, self.g.energy_limit_m);
        r.turning_points += usize::from(turn);
        let e8 = energy_e8(n);
        if r.max_e8.is_none_or(|(e, _)| e8 > e) {
            r.max_e8 = Some((e8, s.tick));
        }
        let score = self.m.score();
        let e8_j = r.e8_j;
        let mut event = |fault: &'static str, (peak_n, peak_e8): (i32, u64)| {
            r.events.push(MonitorEvent {
                fault,
                seq: row.seq,
                tick: s.tick,
                count: s.count,
                score,
                peak_n,
                peak_e8,
                peak_energy_j: peak_e8 as f64 * e8_j,
                device_latched_here: latched_here,
            });
        };
        if bits & monitor::GROWTH != 0 && !self.growing {
            event("ENERGY_GROWTH", self.m.last_peak().unwrap_or((n, e8)));
        }
        if bits & monitor::LIMIT != 0 && !self.over {
            event("ENERGY_LIMIT", (n, e8));
        }
        if turn {
            self.growing = bits & monitor::GROWTH != 0;
        }
        self.over = bits & monitor::LIMIT != 0;
    }
}

/// Text lines of the monitor replay.
#[must_use]
pub fn render(r: &MonitorReplay) -> String {
    let mut s = String::new();
    let _ = write!(
        s,
        "(c) energy monitor{} (trips at a growth score of {}, energy limit {:.3e} J = e8 {} in units of K·Δ_eff²/8): {} ticks, {} turning points",
        if r.device_monitor_on {
            ""
        } else {
            " [off on the device: what would have latched]"
        },
        r.trip,
        r.limit_e8 as f64 * r.e8_j,
        r.limit_e8,
        r.monitored,
        r.turning_points
    );
    if let Some((e8, tick)) = r.max_e8 {
        let _ = write!(
            s,
            ", largest energy {:.3e} J (e8 {e8}) at tick {tick}",
            e8 as f64 * r.e8_j
        );
    }
    let _ = write!(
        s,
        "; {} event(s){}",
        r.events.len(),
        if r.events.is_empty() { "" } else { ":" }
    );
    for e in &r.events {
        let _ = write!(
            s,
            "\n    tick {} (seq {}): {} at count {}, score {}, peak at count {}: {:.3e} J (e8 {}){}",
            e.tick,
            e.seq,
            e.fault,
            e.count,
            e.score,
            e.peak_n,
            e.peak_energy_j,
            e.peak_e8,
            if e.device_latched_here {
                "; the device latched a fault here"
            } else {
                ""
            }
        );
    }
    s
}
