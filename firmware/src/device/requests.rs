//! The device's answer to each request ([`Device::handle`]): config changes validated before
//! they reach the servo, experiments checked before they start, commands queued for the servo.
//!
//! Units: experiment lengths and delays in servo ticks, release deflection and impact start
//! in effective counts, launch velocity in thousandths of an effective count per tick, output
//! codes as the board's. Invariant: a refused request (range, busy, queue full, store) changes
//! nothing and is answered by one `Error` naming the field and its allowed range.

use super::{Device, EndRule, MAX_DEFLECTION, MAX_EXPERIMENT_TICKS, MAX_LAUNCH_MILLITICKS};
use crate::channels::{DecidedEnd, ServoCmd};
use crate::config::{validate, ConfigError};
use crate::hal::ConfigStorage;
use crate::numeric::Numeric;
use crate::profile::ProfileError;
use core::sync::atomic::Ordering;
use stiffwall_proto::{
    ConfigField, DeviceMsg, ErrorCode, ErrorDetail, ExciteProfile, FaultReport, HostMsg, Profile,
    Request, ServoConfig, MAX_TABLE, PROTOCOL_VERSION,
};

fn invalid(field: ConfigField, min: f64, max: f64) -> DeviceMsg {
    DeviceMsg::Error {
        code: ErrorCode::InvalidArgument,
        detail: ErrorDetail::Field { field, min, max },
    }
}

/// A config refused: the field and its range.
fn invalid_config(e: ConfigError) -> DeviceMsg {
    DeviceMsg::Error {
        code: ErrorCode::InvalidConfig,
        detail: ErrorDetail::Field {
            field: e.field,
            min: e.min,
            max: e.max,
        },
    }
}

/// A profile refused: the element, its field and the field's range.
fn invalid_profile(e: ProfileError) -> DeviceMsg {
    DeviceMsg::Error {
        code: ErrorCode::InvalidProfile,
        detail: ErrorDetail::ProfileField {
            element: e.element,
            field: e.field,
            min: e.min,
            max: e.max,
        },
    }
}

/// The servo's command queue had no room for the request's command (transient: the host
/// repeats the request).
fn queue_full() -> DeviceMsg {
    DeviceMsg::Error {
        code: ErrorCode::QueueFull,
        detail: ErrorDetail::None,
    }
}

fn busy(text: &str) -> DeviceMsg {
    DeviceMsg::Error {
        code: ErrorCode::Busy,
        detail: ErrorDetail::Text(heapless::String::try_from(text).unwrap_or_default()),
    }
}

/// The refusal of an experiment's length outside 1..=[`MAX_EXPERIMENT_TICKS`] ticks (`None`
/// for a length in range).
fn ticks_refused(ticks: u32) -> Option<DeviceMsg> {
    (ticks == 0 || ticks > MAX_EXPERIMENT_TICKS)
        .then(|| invalid(ConfigField::Argument, 1.0, f64::from(MAX_EXPERIMENT_TICKS)))
}

impl<S: ConfigStorage, N: Numeric> Device<'_, S, N> {
    fn send_servo(&mut self, cmd: ServoCmd) -> bool {
        self.port.commands.enqueue(cmd).is_ok()
    }

    fn experiment_running(&self) -> bool {
        self.port.shared.experiment.load(Ordering::Relaxed)
    }

    fn apply(&mut self, cfg: ServoConfig, ok: DeviceMsg) -> DeviceMsg {
        if let Err(e) = validate(&cfg, &self.board) {
            return invalid_config(e);
        }
        // The active profile, compiled again for the new config (rate, shift), must still be
        // in range under it.
        if let Err(e) = crate::profile::validate(&self.profile, &cfg, &self.board) {
            return invalid_profile(e);
        }
        if self.experiment_running() {
            return busy("experiment running");
        }
        let with_profile = !self.profile.elements.is_empty();
        // The config and the profile compiled for it go together, or neither.
        let room = self.port.commands.capacity() - self.port.commands.len();
        if room < 1 + usize::from(with_profile) || (with_profile && !self.port.profiles.ready()) {
            return queue_full();
        }
        if !self.send_servo(ServoCmd::Config(cfg)) {
            return queue_full();
        }
        if with_profile {
            let p = self.profile.clone();
            // Room checked above.
            let _ = self.send_profile(&p, &cfg);
        }
        if cfg.servo_rate_hz != self.config.servo_rate_hz {
            self.rate_change = Some(cfg.servo_rate_hz);
        }
        self.config = cfg;
        match ok {
            DeviceMsg::Config(_) => DeviceMsg::Config(cfg),
            other => other,
        }
    }

    /// `Err((min, max))` of the offending argument.
    fn check_profile(&self, p: &ExciteProfile) -> Result<(), (f64, f64)> {
        let mc = self.board.max_code;
        let code_ok = |c: i32| c.unsigned_abs() <= mc.unsigned_abs();
        let nyq = f64::from(self.config.servo_rate_hz) / 2.0;
        let bad_code = (-f64::from(mc), f64::from(mc));
        match *p {
            ExciteProfile::Steps {
                low,
                high,
                half_period_ticks,
            } => {
                if !code_ok(low) || !code_ok(high) {
                    return Err(bad_code);
                }
                if half_period_ticks == 0 {
                    return Err((1.0, f64::from(u32::MAX)));
                }
            }
            ExciteProfile::Chirp {
                amplitude,
                f0_hz,
                f1_hz,
            } => {
                if !code_ok(amplitude) {
                    return Err(bad_code);
                }
                for f in [f0_hz, f1_hz] {
                    if !(f.is_finite() && f >= 0.0 && f64::from(f) <= nyq) {
                        return Err((0.0, nyq));
                    }
                }
            }
            ExciteProfile::Table { len, hold_ticks } => {
                if len == 0 || usize::from(len) > MAX_TABLE {
                    return Err((1.0, MAX_TABLE as f64));
                }
                if hold_ticks == 0 {
                    return Err((1.0, f64::from(u16::MAX)));
                }
            }
        }
        Ok(())
    }

    /// Handles one request; returns the reply.
    pub fn handle(&mut self, msg: HostMsg) -> DeviceMsg {
        let ack = |r| DeviceMsg::Ack(r);
        match msg {
            HostMsg::Hello { protocol_version } => self.hello(protocol_version),
            HostMsg::GetConfig => DeviceMsg::Config(self.config),
            HostMsg::SetConfig(cfg) => self.apply(cfg, ack(Request::SetConfig)),
            HostMsg::LoadDefaults => {
                let d = self.defaults;
                self.apply(d, DeviceMsg::Config(d))
            }
            HostMsg::SaveConfig => {
                match self.store.save_with_profile(&self.config, &self.profile) {
                    Ok(()) => ack(Request::SaveConfig),
                    Err(_) => DeviceMsg::Error {
                        code: ErrorCode::StoreFailed,
                        detail: ErrorDetail::None,
                    },
                }
            }
            HostMsg::StreamStart { decimation } => {
                if decimation == 0 {
                    invalid(ConfigField::Argument, 1.0, f64::from(u16::MAX))
                } else {
                    self.queued(ServoCmd::Stream { decimation }, Request::StreamStart)
                }
            }
            HostMsg::StreamStop => {
                self.queued(ServoCmd::Stream { decimation: 0 }, Request::StreamStop)
            }
            HostMsg::Release {
                deflection_ticks,
                ticks,
            } => self.start_test(Request::Release, deflection_ticks, None, ticks),
            HostMsg::Impact {
                start_ticks,
                velocity_milliticks,
                ticks,
            } => self.start_test(
                Request::Impact,
                start_ticks,
                Some(velocity_milliticks),
                ticks,
            ),
            HostMsg::Excite { profile, ticks } => self.excite(profile, ticks),
            HostMsg::TableChunk { offset, values } => {
                if usize::from(offset) + values.len() > MAX_TABLE {
                    return invalid(
                        ConfigField::Argument,
                        0.0,
                        (MAX_TABLE - values.len()) as f64,
                    );
                }
                self.queued(ServoCmd::TableChunk { offset, values }, Request::TableChunk)
            }
            HostMsg::Heartbeat => {
                self.port.shared.heartbeat.fetch_add(1, Ordering::Relaxed);
                ack(Request::Heartbeat)
            }
            HostMsg::GetFaults => self.fault_report(),
            HostMsg::SetProfile(p) => self.set_profile(p),
            HostMsg::GetProfile => DeviceMsg::Profile(self.profile.clone()),
            HostMsg::ClearFaults => self.queued(ServoCmd::ClearFaults, Request::ClearFaults),
            HostMsg::Stop => self.queued(ServoCmd::Stop, Request::Stop),
            HostMsg::Shutdown { exit_code } => {
                self.shutdown = Some(exit_code);
                ack(Request::Shutdown)
            }
            HostMsg::PrepareTest {
                config,
                min_run_ticks,
                within_one_count,
                decay_base_ticks,
            } => self.prepare_test(config, min_run_ticks, within_one_count, decay_base_ticks),
        }
    }

    /// `SetProfile`: refused while an experiment runs, validated for the active config,
    /// compiled and queued for the servo (an empty profile: the config's wall again).
    fn set_profile(&mut self, p: Profile) -> DeviceMsg {
        if self.experiment_running() {
            return busy("experiment running");
        }
        if let Err(e) = crate::profile::validate(&p, &self.config, &self.board) {
            return invalid_profile(e);
        }
        let cfg = self.config;
        if !self.send_profile(&p, &cfg) {
            return queue_full();
        }
        self.profile = p;
        DeviceMsg::Ack(Request::SetProfile)
    }

    /// The reply to `Hello`: the device's identity, or a version mismatch.
    fn hello(&self, protocol_version: u8) -> DeviceMsg {
        if protocol_version == PROTOCOL_VERSION {
            DeviceMsg::HelloReply(self.board.device_info(self.config.servo_rate_hz))
        } else {
            DeviceMsg::Error {
                code: ErrorCode::VersionMismatch,
                detail: ErrorDetail::Version {
                    got: protocol_version,
                    expected: PROTOCOL_VERSION,
                },
            }
        }
    }

    /// `cmd` queued for the servo, acknowledged as `done`; busy when the queue is full.
    fn queued(&mut self, cmd: ServoCmd, done: Request) -> DeviceMsg {
        if self.send_servo(cmd) {
            DeviceMsg::Ack(done)
        } else {
            queue_full()
        }
    }

    /// Starts an excitation of `ticks` ticks (the profile plus the wall's centring spring and
    /// damper, none with K = 0 and B = 0) after checking its length and profile.
    fn excite(&mut self, profile: ExciteProfile, ticks: u32) -> DeviceMsg {
        if let Some(refused) = ticks_refused(ticks) {
            return refused;
        }
        if let Err((min, max)) = self.check_profile(&profile) {
            return invalid(ConfigField::Argument, min, max);
        }
        if self.port.shared.faults.load(Ordering::Relaxed) != 0 {
            return busy("faults latched");
        }
        if self.send_servo(ServoCmd::Excite { profile, ticks }) {
            self.port.shared.experiment.store(true, Ordering::Relaxed);
            DeviceMsg::Ack(Request::Excite)
        } else {
            queue_full()
        }
    }

    /// The latched faults, the tick of the first, and whether the servo is in safe mode.
    fn fault_report(&self) -> DeviceMsg {
        let latched = self.port.shared.faults.load(Ordering::Relaxed);
        DeviceMsg::Faults(FaultReport {
            latched,
            first_tick: if latched != 0 {
                self.port.shared.first_fault_tick.load(Ordering::Relaxed)
            } else {
                0
            },
            safe_mode: latched != 0,
        })
    }

    /// `HostMsg::PrepareTest`: checks and keeps the next test's config and end rule.
    fn prepare_test(
        &mut self,
        config: ServoConfig,
        min_run: u32,
        one_count: bool,
        decay_base: u32,
    ) -> DeviceMsg {
        if let Err(e) = validate(&config, &self.board) {
            return invalid_config(e);
        }
        if config.servo_rate_hz != self.config.servo_rate_hz {
            let hz = f64::from(self.config.servo_rate_hz);
            return invalid_config(ConfigError {
                field: ConfigField::ServoRateHz,
                min: hz,
                max: hz,
            });
        }
        if min_run.max(decay_base) > MAX_EXPERIMENT_TICKS {
            return invalid(ConfigField::Argument, 0.0, f64::from(MAX_EXPERIMENT_TICKS));
        }
        if self.experiment_running() {
            return busy("experiment running");
        }
        self.end_rule = Some(EndRule {
            config,
            min_run,
            one_count,
            decay_base,
        });
        DeviceMsg::Ack(Request::PrepareTest)
    }

    /// Starts a release test (`velocity_milli` None: hold at `at`) or an impact test (launch
    /// from `at` at `velocity_milli`), with the pending [`HostMsg::PrepareTest`] rule.
    fn start_test(
        &mut self,
        request: Request,
        at: i32,
        velocity_milli: Option<i32>,
        ticks: u32,
    ) -> DeviceMsg {
        if let Some(refused) = ticks_refused(ticks) {
            return refused;
        }
        // An impact starts off the wall (non-zero); a release may start on it.
        let at_ok = at.unsigned_abs() <= MAX_DEFLECTION.unsigned_abs()
            && (velocity_milli.is_none() || at != 0);
        if !at_ok {
            let m = f64::from(MAX_DEFLECTION);
            return invalid(ConfigField::Argument, -m, m);
        }
        if let Some(v) = velocity_milli {
            // Toward the wall: the velocity's sign is opposite to the start's.
            let toward = -at.signum() * v;
            if !(1..=MAX_LAUNCH_MILLITICKS).contains(&toward) {
                let m = f64::from(MAX_LAUNCH_MILLITICKS);
                return if at < 0 {
                    invalid(ConfigField::Argument, 1.0, m)
                } else {
                    invalid(ConfigField::Argument, -m, -1.0)
                };
            }
        }
        if self.port.shared.faults.load(Ordering::Relaxed) != 0 {
            return busy("faults latched");
        }
        // The test's config: the prepared one, or the active one.
        let cfg = self.end_rule.map_or(self.config, |r| r.config);
        if cfg.stiffness <= 0.0 {
            return invalid(
                ConfigField::Stiffness,
                f64::from(f32::MIN_POSITIVE),
                f64::from(self.board.max_stiffness(cfg.coarsen_shift)),
            );
        }
        let end = self.end_rule.map(|rule| DecidedEnd {
            min_run: rule.min_run,
            one_count: rule.one_count,
            decay_base: rule.decay_base,
            run: rule.config,
            park: self.config,
        });
        let cmd = match velocity_milli {
            None => ServoCmd::Release {
                deflection: at,
                ticks,
                end,
            },
            Some(v) => ServoCmd::Impact {
                start: at,
                velocity_milli: v,
                ticks,
                end,
            },
        };
        if !self.send_servo(cmd) {
            return queue_full();
        }
        self.end_rule = None;
        self.port.shared.experiment.store(true, Ordering::Relaxed);
        DeviceMsg::Ack(request)
    }
}
