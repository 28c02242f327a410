//! Experiments on a connected device: release and impact tests and open-loop excitations,
//! each run to its end (or ended early when the caller's judge has seen enough), with every
//! sample and the telemetry gaps seen while it ran.
//!
//! Units: ticks are servo ticks; deflections and start positions are effective encoder ticks;
//! velocities effective ticks per 1000 servo ticks. Heartbeats go out every
//! [`HEARTBEAT_PERIOD`] while an experiment runs.

use super::{Client, EnoughFn, Record, HEARTBEAT_PERIOD};
use crate::error::{ClientError, Result};
use std::time::{Duration, Instant};
use stiffwall_proto::{DeviceMsg, ExciteProfile, ExperimentKind, HostMsg};

/// How long a cancelled experiment waits for the device to report its end after `Stop`.
const CANCEL_STOP_WAIT: Duration = Duration::from_secs(2);

impl Client {
    /// Runs a release test and collects every sample until the device reports the end.
    pub fn release(&mut self, deflection_ticks: i32, ticks: u32) -> Result<Record> {
        self.experiment(
            &HostMsg::Release {
                deflection_ticks,
                ticks,
            },
            ExperimentKind::Release,
            ticks,
        )
    }

    /// Runs a release test like [`Client::release`], but sends `Stop` as soon as `enough`
    /// returns true for the samples received so far (the caller judges the record, so the
    /// samples after that point are only the `Stop`'s latency).
    pub fn release_until(
        &mut self,
        deflection_ticks: i32,
        ticks: u32,
        enough: &mut EnoughFn<'_>,
    ) -> Result<Record> {
        self.experiment_until(
            &HostMsg::Release {
                deflection_ticks,
                ticks,
            },
            ExperimentKind::Release,
            ticks,
            Some(enough),
        )
    }

    /// Runs an impact test (see [`HostMsg::Impact`]), ending it early like
    /// [`Client::release_until`].
    pub fn impact_until(
        &mut self,
        start_ticks: i32,
        velocity_milliticks: i32,
        ticks: u32,
        enough: &mut EnoughFn<'_>,
    ) -> Result<Record> {
        self.experiment_until(
            &HostMsg::Impact {
                start_ticks,
                velocity_milliticks,
                ticks,
            },
            ExperimentKind::Impact,
            ticks,
            Some(enough),
        )
    }

    /// Runs an open-loop excitation and collects every sample.
    pub fn excite(&mut self, profile: ExciteProfile, ticks: u32) -> Result<Record> {
        self.experiment(
            &HostMsg::Excite { profile, ticks },
            ExperimentKind::Excite,
            ticks,
        )
    }

    /// Stops the running experiment after a cancel and waits (briefly) for the device to
    /// report its end, so that the next request finds the device idle.
    fn stop_cancelled(&mut self, kind: ExperimentKind) -> ClientError {
        if let Err(e) = self.send(&HostMsg::Stop) {
            return e;
        }
        let deadline = Instant::now() + CANCEL_STOP_WAIT;
        while Instant::now() < deadline {
            match self.recv(Duration::from_millis(20)) {
                Ok(Some(DeviceMsg::ExperimentDone { kind: k, .. })) if k == kind => break,
                Ok(_) => {}
                Err(e) => return e,
            }
        }
        self.link.drop_telemetry();
        ClientError::Cancelled
    }

    fn experiment(&mut self, msg: &HostMsg, kind: ExperimentKind, ticks: u32) -> Result<Record> {
        self.experiment_until(msg, kind, ticks, None)
    }

    fn experiment_until(
        &mut self,
        msg: &HostMsg,
        kind: ExperimentKind,
        ticks: u32,
        mut enough: Option<&mut EnoughFn<'_>>,
    ) -> Result<Record> {
        self.link.drop_telemetry();
        if self.cancel.is_cancelled() {
            return Err(ClientError::Cancelled);
        }
        let before = self.gaps();
        self.link.restart_sequence();
        self.request(msg)?;
        let rate = f64::from(self.info.servo_rate_hz.max(1));
        // Generous: the virtual device may run slower than real time on a loaded machine.
        let limit = Duration::from_secs_f64(f64::from(ticks) / rate * 20.0 + 10.0);
        let start = Instant::now();
        let mut last_hb = Instant::now();
        let mut samples = Vec::with_capacity(ticks as usize + 16);
        loop {
            if last_hb.elapsed() >= HEARTBEAT_PERIOD {
                self.send(&HostMsg::Heartbeat)?;
                last_hb = Instant::now();
            }
            match self.recv(Duration::from_millis(20))? {
                Some(DeviceMsg::Telemetry(b)) => {
                    samples.extend_from_slice(&b.samples);
                    if let Some(f) = enough.as_mut() {
                        if f(&samples) {
                            enough = None;
                            self.send(&HostMsg::Stop)?;
                        }
                    }
                }
                Some(DeviceMsg::ExperimentDone {
                    kind: k,
                    completed,
                    faults,
                }) if k == kind => {
                    // Telemetry queued behind the end message.
                    while let Some(b) = self.next_batch(Duration::from_millis(50))? {
                        samples.extend_from_slice(&b.samples);
                    }
                    let mut gaps = self.gaps();
                    gaps.received -= before.received;
                    gaps.missing -= before.missing;
                    gaps.dropped_on_device -= before.dropped_on_device;
                    gaps.bad_frames -= before.bad_frames;
                    return Ok(Record {
                        samples,
                        completed,
                        faults,
                        gaps,
                    });
                }
                Some(_) | None => {}
            }
            if start.elapsed() > limit {
                let _ = self.send(&HostMsg::Stop);
                return Err(ClientError::ExperimentTimeout(limit));
            }
            if self.cancel.is_cancelled() {
                return Err(self.stop_cancelled(kind));
            }
        }
    }
}
