//! The experiment path of the tick: the forces a running experiment commands (hold, release,
//! impact launch, excitation), its advance from tick to tick, and its end (the active config
//! restored, the decided end reported once).
//!
//! Excitation with a centring spring: an excitation's code is the profile's code plus the
//! configured wall's spring and damper, `code = exc + spring_raw(n) − g_B·v` (saturating; the
//! delay line and the output clamp follow as for every code), where `spring_raw` is the
//! two-sided spring of eq. (2) around `wall_position` with the config's K (also on a
//! one-sided wall: it centres the device, it is not the wall), in the same fixed point as the
//! wall's and the hold's (beyond its count clamp n_sat, where the spring alone passes the
//! force limit, it keeps its value at n_sat), and −g_B·v the wall's damper with its law
//! ([`Servo::damping`]). A host can so run a chirp against a weak, known centring spring.
//! With K = 0 and B = 0 (the default) nothing is added: the codes are bit for bit the profile's
//! and the samples carry `WALL_OFF` as before; with either set they do not. The sample's
//! `force_code` is the total code output (after the delay and the clamp), as on every tick.
//!
//! Units: effective counts, output codes, ticks. Invariants: bounded work per tick, no
//! allocation or panic; the experiment's state lives in the servo (`exp`, `end`, `settle`).

use super::Servo;
use crate::channels::ServoEvent;
use crate::experiment::{EndWatch, Experiment, Mode};
use crate::hal::{Encoder, ForceOutput};
use crate::numeric::Numeric;
use core::sync::atomic::Ordering;
use stiffwall_proto::{flags, ExperimentKind};

impl<N: Numeric> Servo<'_, N> {
    pub(super) fn set_exp(&mut self, e: Experiment) {
        self.mode = match e.mode() {
            Mode::Wall => self.idle_mode(),
            m => m,
        };
        self.exp = e;
    }

    /// The tick while an experiment runs: [`Self::step`] for every mode but the wall's, out of
    /// line so the wall's tick is compiled for the wall alone.
    #[inline(never)]
    pub(super) fn step_experiment<const TEL: bool>(
        &mut self,
        now: u32,
        enc: &mut impl Encoder,
        out: &mut impl ForceOutput,
    ) -> i32 {
        self.step::<TEL, false>(now, enc, out)
    }

    /// Hold and excitation forces (out of the wall's hot path).
    #[inline(never)]
    pub(super) fn experiment_force(&mut self, n: i32, dn: i32) -> (i32, u16) {
        let hold_damp = self.damper(self.g.hold_damp, dn);
        // The launch itself (the target moving toward the wall) keeps β = 2, whose lag behind
        // the target the launch's speed was tuned with.
        let launch_damp = self.damper(self.g.launch_damp, dn);
        match &mut self.exp {
            Experiment::None | Experiment::Released { .. } => (0, 0),
            Experiment::Hold(h) => {
                let e = n.saturating_sub(h.target);
                (self.spring_raw(e).saturating_add(hold_damp), flags::HOLD)
            }
            Experiment::Launch(l) => {
                let e = n.saturating_sub(l.target());
                let d = if l.launched() { launch_damp } else { hold_damp };
                (self.spring_raw(e).saturating_add(d), flags::HOLD)
            }
            Experiment::Excite(x) => {
                let code = x.next_code(&self.table, self.g.rate_hz);
                if self.g.excite_centring {
                    let centring = self.spring_raw(n).saturating_add(self.damping(dn));
                    (code.saturating_add(centring), flags::EXCITE)
                } else {
                    (code, flags::EXCITE | flags::WALL_OFF)
                }
            }
        }
    }

    /// Bookkeeping after the output of a tick that is not the wall's: the previous raw count
    /// (the profile's backward differences), the experiment's.
    #[inline]
    pub(super) fn advance(&mut self, n: i32, dn: i32) {
        self.prev_pos = self.pos;
        if matches!(self.mode, Mode::Released | Mode::Other) {
            self.advance_experiment(n, dn);
        }
    }

    #[inline(never)]
    pub(super) fn advance_experiment(&mut self, n: i32, dn: i32) {
        let mut release = None;
        let mut done = false;
        match &mut self.exp {
            Experiment::None => {}
            Experiment::Hold(h) => {
                release = h
                    .advance(n, dn, self.g.rate_hz)
                    .map(|t| (t, ExperimentKind::Release));
            }
            Experiment::Launch(l) => {
                release = l
                    .advance(n, dn, self.g.rate_hz)
                    .map(|t| (t, ExperimentKind::Impact));
            }
            Experiment::Released { remaining, .. } => {
                *remaining = remaining.saturating_sub(1);
                let settled = self.settle.as_mut().is_some_and(|w| w.push(n));
                done = *remaining == 0 || settled;
            }
            Experiment::Excite(x) => done = x.advance(),
        }
        if let Some((ticks, kind)) = release {
            self.set_exp(Experiment::Released {
                remaining: ticks,
                kind,
            });
            self.settle = self
                .end
                .map(|e| EndWatch::new(e.min_run, e.one_count, e.decay_base));
            self.monitor.reset();
        }
        if done {
            self.end_experiment(true);
        }
    }

    /// Ends the running experiment (if any); a prepared test's active config is back.
    pub(super) fn end_experiment(&mut self, completed: bool) {
        let Some(kind) = self.exp.kind() else {
            return;
        };
        self.set_exp(Experiment::None);
        self.settle = None;
        if let Some(e) = self.end.take() {
            self.apply_config(&e.park);
        }
        self.monitor.reset();
        self.decimation = self.user_decimation;
        // An experiment streams every tick (`decimation` 1), so its count was at the start.
        self.decim_left = u32::from(self.decimation);
        self.port.shared.experiment.store(false, Ordering::Relaxed);
        let _ = self.port.events.enqueue(ServoEvent::ExperimentDone {
            kind,
            completed,
            faults: self.faults,
            next_seq: self.seq,
        });
    }
}
