//! The plant family of `sim/plants/*.toml` (issue 10, item 4): loading a plant file into what
//! the K* search ([`crate::kstar`]) and the supervisor runs ([`crate::supervise`]) need.
//!
//! Units: SI (rotary plants: rad, N·m, kg·m²). The controller of a plant file is its
//! `[controller]` (period T, extra delay rounded to whole periods as the firmware's delay line
//! does, wall mode); the force limit is the amplifier's `force_limit_n`, or the virtual device's
//! rule (32.767 × `coulomb_n`, at least 1 mN) when the file sets none; v_max is
//! [`crate::kstar::DEFAULT_XIDOT`] counts per period.
//!
//! Invariant: a [`PlantCase`] holds a validated model (its prototype plant was built from it).

use crate::kstar::{self, Rig, SampledPlant, Trial, TrialKind, DEFAULT_XIDOT};
use crate::supervise::{self, SupervisedRun};
use std::path::{Path, PathBuf};
use stiffwall_proto::ServoConfig;
use stiffwall_sim::rich::{Controller, PlantModel, RichPlant};

impl SampledPlant for RichPlant {
    fn set_state(&mut self, position_m: f64, velocity_m_per_s: f64) {
        RichPlant::set_state(self, position_m, velocity_m_per_s);
    }
    fn set_held(&mut self, position_m: f64) {
        RichPlant::set_held(self, position_m);
    }
    fn advance(&mut self, force_n: f64, dt_s: f64) {
        RichPlant::advance(self, force_n, dt_s);
    }
    fn encoder_count(&self) -> i64 {
        RichPlant::encoder_count(self)
    }
    fn velocity_m_per_s(&self) -> f64 {
        RichPlant::velocity_m_per_s(self)
    }
}

/// One supervised run of the criterion at a stiffness above K*.
#[derive(Debug, Clone, PartialEq)]
pub struct Supervised {
    /// The trial.
    pub trial: Trial,
    /// Whether it settles without the firmware (the sampled spring of eq. (2) alone).
    pub unsupervised_settles: bool,
    /// Peak |n + ½| without the firmware, counts.
    pub unsupervised_peak: f64,
    /// One-sided wall without a hand spring: the unsupervised plant left the wall at this
    /// speed, faster than a passive wall returns it (this speed over the passive one).
    pub left_faster: Option<f64>,
    /// The firmware's extra delay, ticks (codes computed inside the wall still go out).
    pub delay_ticks: u32,
    /// The run under the firmware.
    pub run: SupervisedRun,
}

impl Supervised {
    /// Safe: nothing to stop (settles without the firmware), or stopped (fault, zero force),
    /// or — the one failure no monitor can act on — the wall threw the plant out once, faster
    /// than it came, and the firmware applied no force after it left (a one-sided wall without
    /// a hand spring: nothing brings the plant back, so the energy gained is one contact's).
    /// Or — nothing left to stop — the motion under the firmware dies away by itself
    /// ([`Supervised::decays_under_firmware`]).
    #[must_use]
    pub fn safe(&self) -> bool {
        self.unsupervised_settles
            || self.run.stopped()
            || self.left_and_released()
            || self.decays_under_firmware()
    }

    /// Safe only because the motion died away under the firmware (not settled without it, not
    /// stopped, not thrown out): the "decays under the firmware" of the supervisor table.
    #[must_use]
    pub fn safe_by_decay(&self) -> bool {
        !self.unsupervised_settles
            && !self.run.stopped()
            && !self.left_and_released()
            && self.decays_under_firmware()
    }

    /// No fault latched, and the motion under the firmware dies away: the peak-to-peak
    /// excursion over the run's last sixth is at most a quarter of that over its first sixth
    /// (or within one count), and no count of the run lies farther from the wall than the
    /// first sixth reached. The firmware's output differs from the bare spring's (16-bit codes,
    /// fixed point), so near a limit cycle (cogging with a hand) a trial that does not settle
    /// without the firmware can converge under it; the monitors rightly leave a decaying
    /// motion alone.
    #[must_use]
    pub fn decays_under_firmware(&self) -> bool {
        let c = &self.run.counts;
        if self.run.trip_tick.is_some() || c.len() < 12 {
            return false;
        }
        let sixth = c.len() / 6;
        let ptp =
            |w: &[i64]| w.iter().max().copied().unwrap_or(0) - w.iter().min().copied().unwrap_or(0);
        let head = &c[..sixth];
        let reach = head.iter().map(|n| n.abs()).max().unwrap_or(0);
        let tail = ptp(&c[c.len() - sixth..]);
        (tail <= 1 || 4 * tail <= ptp(head)) && c.iter().all(|n| n.abs() <= reach)
    }

    /// The supervised plant left the one-sided wall (count < −1 after a contact), never came
    /// back, and every output code from the delay line's length after it left was 0.
    #[must_use]
    pub fn left_and_released(&self) -> bool {
        if self.left_faster.is_none() {
            return false;
        }
        let c = &self.run.counts;
        let mut touched = false;
        let Some(exit) = c.iter().position(|&n| {
            touched |= n >= 0;
            touched && n < -1
        }) else {
            return false;
        };
        let quiet = (exit + self.delay_ticks as usize).min(c.len());
        c[exit..].iter().all(|&n| n < 0) && self.run.codes[quiet..].iter().all(|&x| x == 0)
    }
}

/// The supervisor at one stiffness: the impacts at v_max, and every other trial of the
/// criterion that does not settle without the firmware.
#[derive(Debug, Clone, PartialEq)]
pub struct SupervisorReport {
    /// Stiffness, N/m (N·m/rad).
    pub k: f64,
    /// Impacts at v_max (+ side first).
    pub v_max_impacts: Vec<Supervised>,
    /// The other trials that do not settle without the firmware.
    pub other_unstable: Vec<Supervised>,
}

impl SupervisorReport {
    /// Every run that needed stopping was stopped.
    #[must_use]
    pub fn all_safe(&self) -> bool {
        self.v_max_impacts
            .iter()
            .chain(&self.other_unstable)
            .all(Supervised::safe)
    }

    /// Runs that needed stopping and were not stopped.
    pub fn unsafe_runs(&self) -> impl Iterator<Item = &Supervised> {
        self.v_max_impacts
            .iter()
            .chain(&self.other_unstable)
            .filter(|s| !s.safe())
    }
}

/// One plant file, loaded.
#[derive(Debug, Clone)]
pub struct PlantCase {
    /// File stem, e.g. `phantom-stiction`.
    pub name: String,
    /// Path of the file.
    pub path: PathBuf,
    /// The plant.
    pub model: PlantModel,
    /// Its controller (boot config of the virtual device).
    pub controller: Controller,
    /// The K* rig.
    pub rig: Rig,
    /// A plant at rest at 0 (tolerances scaled to the period).
    pub proto: RichPlant,
}

/// The directory of the plant family, `sim/plants` of the workspace.
#[must_use]
pub fn plants_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("sim")
        .join("plants")
}

/// Every `*.toml` in `dir`, sorted by name.
pub fn plant_files(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    v.sort();
    Ok(v)
}

/// Full scale of the virtual amplifier for a model, N (N·m): the model's force limit, or
/// 32.767 × c (at least 1 mN).
#[must_use]
pub fn full_scale_n(model: &PlantModel) -> f64 {
    model
        .force_limit_n()
        .unwrap_or_else(|| (model.coulomb_n * 32.767).max(1e-3))
}

/// Whole moving mass: motor side + link + hand, kg (kg·m²).
#[must_use]
pub fn moving_mass_kg(model: &PlantModel) -> f64 {
    model.mass_kg
        + model.transmission.map_or(0.0, |t| t.link_mass_kg)
        + model.hand.map_or(0.0, |h| h.mass_kg)
}

/// Extra delay in whole periods (as the virtual device's boot config).
#[must_use]
pub fn delay_ticks(c: &Controller) -> u32 {
    (c.extra_delay_s / c.period_s).round().clamp(0.0, 255.0) as u32
}

impl PlantCase {
    /// Loads a plant file. Errors carry the file name and the parser's message.
    pub fn load(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let (model, controller) =
            PlantModel::from_scene_toml(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut proto = RichPlant::new(&model).map_err(|e| format!("{}: {e}", path.display()))?;
        proto.set_tolerance_period(controller.period_s);
        let d = model.resolution_m;
        // With cogging, the wall is also tried a quarter cogging period further on.
        let mut wall_offsets = vec![0];
        if let Some(c) = model.cogging {
            let quarter = (c.period_m / 4.0 / d).round() as i64;
            if quarter > 0 {
                wall_offsets.push(quarter);
            }
        }
        let rig = Rig {
            period_s: controller.period_s,
            resolution_m: d,
            delay_ticks: delay_ticks(&controller),
            one_sided: controller.one_sided,
            free_exit: controller.one_sided
                && model.hand.is_none_or(|h| h.stiffness_n_per_m == 0.0),
            force_limit_n: full_scale_n(&model),
            damping: 0.0,
            deadband_counts: 0,
            v_max: DEFAULT_XIDOT * d / controller.period_s,
            moving_mass_kg: moving_mass_kg(&model),
            wall_offsets,
        };
        let name = path
            .file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        Ok(Self {
            name,
            path: path.to_path_buf(),
            model,
            controller,
            rig,
            proto,
        })
    }

    /// Loads `sim/plants/NAME.toml`.
    pub fn named(name: &str) -> Result<Self, String> {
        Self::load(&plants_dir().join(format!("{name}.toml")))
    }

    /// Where the K* scan starts: σ = c/(KΔ) = 4 (friction-dominated, settles), N/m.
    #[must_use]
    pub fn k_start(&self) -> f64 {
        (self.model.coulomb_n / (4.0 * self.rig.resolution_m)).max(1e-9)
    }

    /// A trial of the K* criterion at stiffness `k` under the firmware supervisor (the
    /// virtual device's board and boot config, with the rig's virtual damping and dead band),
    /// two K* trials long.
    #[must_use]
    pub fn supervised(&self, k: f64, trial: Trial) -> SupervisedRun {
        let c = &self.controller;
        let b = supervise::board(
            self.model.resolution_m,
            self.counts_per_rev(),
            full_scale_n(&self.model),
        );
        let cfg = ServoConfig {
            damping: self.rig.damping as f32,
            damper: match u8::try_from(self.rig.deadband_counts) {
                Ok(0) | Err(_) => stiffwall_proto::DamperLaw::Difference,
                Ok(counts) => stiffwall_proto::DamperLaw::DeadBand { counts },
            },
            ..supervise::config(
                &b,
                k,
                c.period_s,
                delay_ticks(c).min(255) as u8,
                c.one_sided,
            )
        };
        supervise::run(
            self.proto,
            b,
            &cfg,
            c.period_s,
            trial,
            self.model.resolution_m,
            // Twice a K* trial (120 natural periods, as before the trials were shortened to
            // the rest rule's 60): the supervisor gets the time its buzz window needs after a
            // decay from a full-energy release.
            (2 * self.rig.trial_ticks(k)).min(kstar::TRIAL_TICKS.1 as usize),
        )
    }

    /// The supervisor at stiffness `k` ([`SupervisorReport`]).
    #[must_use]
    pub fn supervisor_report(&self, k: f64) -> SupervisorReport {
        let mut rep = SupervisorReport {
            k,
            v_max_impacts: Vec::new(),
            other_unstable: Vec::new(),
        };
        for trial in self.rig.trials(k) {
            let bare = kstar::run_trial(&self.proto, &self.rig, k, trial);
            let v_max = trial == self.impact_at_v_max(trial.side);
            // The supervisor is for growth and buzz: a trial that chatters within one count is
            // not one it must stop.
            if bare.within_one_count() && !v_max {
                continue;
            }
            let s = Supervised {
                trial,
                unsupervised_settles: bare.within_one_count(),
                unsupervised_peak: bare.peak(),
                left_faster: bare.exit.map(|(v, passive)| v / passive),
                delay_ticks: self.rig.delay_ticks,
                run: self.supervised(k, trial),
            };
            if v_max {
                rep.v_max_impacts.push(s);
            } else {
                rep.other_unstable.push(s);
            }
        }
        rep
    }

    /// The impact at v_max from `side` (+1 into n ≥ 0, −1 into n < 0).
    #[must_use]
    pub fn impact_at_v_max(&self, side: i8) -> Trial {
        Trial {
            wall: 0,
            side,
            kind: TrialKind::Impact {
                velocity_m_per_s: self.rig.v_max,
            },
        }
    }

    /// Counts per revolution for the firmware board (0 for linear plants).
    #[must_use]
    pub fn counts_per_rev(&self) -> u32 {
        self.model.counts_per_rev.unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kstar::TrialKind;

    /// A run of `counts` (no fault unless `trip`) after a release that does not settle bare.
    fn supervised(counts: Vec<i64>, trip: Option<usize>) -> Supervised {
        let codes = vec![0; counts.len()];
        Supervised {
            trial: Trial {
                wall: 0,
                side: 1,
                kind: TrialKind::Release { counts: 40 },
            },
            unsupervised_settles: false,
            unsupervised_peak: 40.5,
            left_faster: None,
            delay_ticks: 0,
            run: SupervisedRun {
                trip_tick: trip,
                faults: u32::from(trip.is_some()),
                nonzero_after_trip: 0,
                counts,
                codes,
            },
        }
    }

    /// A triangle oscillation about `offset` whose amplitude, counts, is `amp(cycle)`; 20 ticks
    /// per cycle, 100 cycles.
    fn oscillation(offset: i64, amp: impl Fn(usize) -> i64) -> Vec<i64> {
        (0..2000)
            .map(|t| {
                let a = amp(t / 20);
                let phase = (t % 20) as i64;
                let tri = if phase < 10 { phase } else { 20 - phase };
                offset + a - tri * a / 5
            })
            .collect()
    }

    #[test]
    fn a_motion_that_dies_away_under_the_firmware_is_safe_and_a_persistent_one_is_not() {
        // From ±40 about −16 down to ±1: decays (the cogging-and-hand case).
        let dying = supervised(oscillation(-16, |c| (40 - c as i64 * 2 / 5).max(1)), None);
        assert!(dying.decays_under_firmware() && dying.safe());
        // Settled at rest after a few cycles.
        let settled = supervised(oscillation(0, |c| if c < 10 { 13 } else { 0 }), None);
        assert!(settled.decays_under_firmware());
        // Persistent ±32 (a limit cycle) is neither decaying nor safe without a trip.
        let persistent = supervised(oscillation(0, |_| 32), None);
        assert!(!persistent.decays_under_firmware() && !persistent.safe());
        // Shrinking to half only: not enough.
        let half = supervised(oscillation(0, |c| 40 - c as i64 / 5), None);
        assert!(!half.decays_under_firmware());
        // Growing, even if it ends small: it went farther than it started.
        let mut grew = oscillation(0, |c| if c < 50 { 10 + c as i64 } else { 0 });
        grew[1900] = 0;
        assert!(!supervised(grew, None).decays_under_firmware());
        // A latched fault is judged by `stopped`, not as a decay.
        let tripped = supervised(oscillation(0, |c| (40 - c as i64).max(0)), Some(100));
        assert!(!tripped.decays_under_firmware() && tripped.safe());
    }
}
