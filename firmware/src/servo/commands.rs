//! The servo's command handling: one `ServoCmd` from the main loop per tick (config, stream,
//! the experiments' starts, table chunks, fault clearing, stop), out of the wall's hot path.
//!
//! Units: as the servo's (effective counts, servo ticks, output codes). Invariants: bounded
//! work, no allocation or panics; an experiment starts only without latched faults, else its
//! end is reported at once.

use super::*;

impl<N: Numeric> Servo<'_, N> {
    /// A prepared test's config from its first tick on (see [`DecidedEnd`]).
    fn prepare(&mut self, end: Option<DecidedEnd>) {
        if let Some(e) = &end {
            self.apply_config(&e.run);
        }
        self.end = end;
    }

    /// Handles one command from the main loop.
    pub fn command(&mut self, now: u32, cmd: ServoCmd) {
        match cmd {
            ServoCmd::Config(cfg) => self.apply_config(&cfg),
            ServoCmd::Stream { decimation } => {
                self.user_decimation = decimation;
                if !self.experiment_running() {
                    self.decimation = decimation;
                }
                self.decim_left = u32::from(self.decimation);
            }
            ServoCmd::Release {
                deflection,
                ticks,
                end,
            } => {
                if self.faults == 0 {
                    self.end_experiment(false);
                    self.prepare(end);
                    let hold = Hold::new(deflection, ticks).toggle_settles(self.g.damping_on);
                    self.set_exp(Experiment::Hold(hold));
                    self.start_experiment(now);
                } else {
                    self.refuse_experiment(ExperimentKind::Release);
                }
            }
            ServoCmd::Impact {
                start,
                velocity_milli,
                ticks,
                end,
            } => {
                if self.faults == 0 {
                    self.end_experiment(false);
                    self.prepare(end);
                    let launch =
                        Launch::new(start, velocity_milli, ticks).toggle_settles(self.g.damping_on);
                    self.set_exp(Experiment::Launch(launch));
                    self.start_experiment(now);
                } else {
                    self.refuse_experiment(ExperimentKind::Impact);
                }
            }
            ServoCmd::Excite { profile, ticks } => {
                if self.faults == 0 {
                    self.end_experiment(false);
                    self.set_exp(Experiment::Excite(Excitation::new(profile, ticks)));
                    self.start_experiment(now);
                } else {
                    self.refuse_experiment(ExperimentKind::Excite);
                }
            }
            ServoCmd::TableChunk { offset, values } => {
                for (i, v) in values.iter().enumerate() {
                    if let Some(slot) = self.table.get_mut(usize::from(offset) + i) {
                        *slot = *v;
                    }
                }
            }
            ServoCmd::ClearFaults => {
                self.set_faults(0);
                self.port.shared.faults.store(0, Ordering::Relaxed);
                self.ring = [0; RING];
                self.monitor.reset();
            }
            ServoCmd::Stop => self.end_experiment(false),
            ServoCmd::Profile => self.take_profile(),
        }
    }

    /// A start refused because faults latched after the main loop checked: report it ended.
    fn refuse_experiment(&mut self, kind: ExperimentKind) {
        if !self.experiment_running() {
            self.port.shared.experiment.store(false, Ordering::Relaxed);
        }
        let _ = self.port.events.enqueue(ServoEvent::ExperimentDone {
            kind,
            completed: false,
            faults: self.faults,
            next_seq: self.seq,
        });
    }

    fn start_experiment(&mut self, now: u32) {
        self.monitor.reset();
        self.decimation = 1;
        self.decim_left = 1;
        self.hb_seen = self.port.shared.heartbeat.load(Ordering::Relaxed);
        self.hb_tick = now;
        self.port.shared.experiment.store(true, Ordering::Relaxed);
    }
}
