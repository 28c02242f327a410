//! Host side of the stiffwall protocol over any byte port: handshake with version check,
//! request/answer with timeouts, telemetry with sequence-gap accounting, and experiments.
//!
//! Telemetry that arrives while a request waits for its answer is queued, never lost. A gap in
//! sample numbers is attributed to the device (its cumulative `dropped` counter grew by the
//! same amount) or to the link (it did not).

use crate::cancel::Cancel;
use crate::error::{ClientError, Result};
use crate::transport::Transport;
use std::time::Duration;
use stiffwall_proto::{
    DeviceInfo, DeviceMsg, FaultReport, HostMsg, Profile, Sample, ServoConfig, TelemetryBatch,
    PROTOCOL_VERSION,
};

mod experiment;
mod link;

pub use link::{GapStats, Link, ANSWER_TIMEOUT, BACKLOG_WAIT_MAX, QUEUE_FULL_RETRY};

/// Heartbeat period during experiments (the firmware's default timeout is 500 ms).
pub const HEARTBEAT_PERIOD: Duration = Duration::from_millis(100);

/// Keeps whatever serves the port (virtual device thread, QEMU process) alive with the client.
pub trait Backend: std::fmt::Debug + Send {}
impl<T: std::fmt::Debug + Send> Backend for T {}

/// Judges the samples of a running experiment so far: true ends it early (see
/// [`Client::release_until`]).
pub type EnoughFn<'a> = dyn FnMut(&[Sample]) -> bool + 'a;

/// Samples of one experiment with their bookkeeping.
#[derive(Debug, Clone)]
pub struct Record {
    /// Samples in order.
    pub samples: Vec<Sample>,
    /// Whether the experiment ran its full length.
    pub completed: bool,
    /// Fault bits latched when it ended.
    pub faults: u32,
    /// Telemetry gaps seen.
    pub gaps: GapStats,
}

/// A connected device: made only by a handshake that the device answered with its
/// [`DeviceInfo`] ([`Client::connect`]).
#[derive(Debug)]
pub struct Client {
    link: Link,
    /// The device's handshake answer.
    pub info: DeviceInfo,
    /// Checked while an experiment runs (see [`Client::set_cancel`]).
    cancel: Cancel,
    _backend: Option<Box<dyn Backend>>,
}

impl Client {
    /// Performs the handshake on an opened port (any [`Transport`]: a serial port, a pty, an
    /// in-memory pair). `backend` is kept alive with the client.
    pub fn connect(
        port: impl Transport + 'static,
        backend: Option<Box<dyn Backend>>,
    ) -> Result<Self> {
        let mut link = Link::new(Box::new(port));
        let info = handshake(&mut link)?;
        Ok(Self {
            link,
            info,
            cancel: Cancel::default(),
            _backend: backend,
        })
    }

    /// Makes `cancel` the token this client's experiments check (returning the previous one):
    /// once it is cancelled, a running or starting release, impact or excitation sends `Stop`,
    /// lets the device end the test and fails with [`ClientError::Cancelled`]. Requests
    /// (config, faults) are not affected, so a front end can restore a config after a cancel.
    /// A new client checks a detached token (Ctrl-C does not reach it unless the front end
    /// gives it one made by [`Cancel::on_ctrl_c`]).
    pub fn set_cancel(&mut self, cancel: Cancel) -> Cancel {
        std::mem::replace(&mut self.cancel, cancel)
    }

    /// The token this client's experiments check.
    #[must_use]
    pub fn cancel_token(&self) -> &Cancel {
        &self.cancel
    }

    /// Telemetry bookkeeping since connecting.
    #[must_use]
    pub fn gaps(&self) -> GapStats {
        self.link.gaps()
    }

    /// Sends one message.
    pub fn send(&mut self, msg: &HostMsg) -> Result<()> {
        self.link.send(msg)
    }

    /// Writes raw bytes (tests of malformed input).
    pub fn send_raw(&mut self, bytes: &[u8]) -> Result<()> {
        self.link.send_raw(bytes)
    }

    /// Reads what is available and returns the next message, waiting up to `timeout`.
    pub fn recv(&mut self, timeout: Duration) -> Result<Option<DeviceMsg>> {
        self.link.recv(timeout)
    }

    /// Sends a request and waits for its answer ([`Link::request`]); a device `Error` becomes
    /// an error.
    pub fn request(&mut self, msg: &HostMsg) -> Result<DeviceMsg> {
        self.link.request(msg)
    }

    /// Next telemetry batch, or None after `timeout` (on time whatever else arrives).
    pub fn next_batch(&mut self, timeout: Duration) -> Result<Option<TelemetryBatch>> {
        self.link.next_batch(timeout)
    }

    /// Reads the active configuration.
    pub fn get_config(&mut self) -> Result<ServoConfig> {
        match self.request(&HostMsg::GetConfig)? {
            DeviceMsg::Config(c) => Ok(c),
            other => Err(unexpected("GetConfig", &other)),
        }
    }

    /// Applies a configuration (validated by the device; refused ones change nothing).
    pub fn set_config(&mut self, config: &ServoConfig) -> Result<()> {
        self.request(&HostMsg::SetConfig(*config)).map(drop)
    }

    /// Applies a haptic profile (protocol 5; validated by the device element by element: a
    /// refused one changes nothing, and the error names the element, its field and range, in
    /// [`crate::describe_error`]'s words). An empty profile renders the config's wall again.
    /// Persisted with the config by [`Client::save_config`].
    pub fn set_profile(&mut self, profile: &Profile) -> Result<()> {
        self.request(&HostMsg::SetProfile(profile.clone()))
            .map(drop)
    }

    /// Reads the active haptic profile (empty: the config's wall).
    pub fn get_profile(&mut self) -> Result<Profile> {
        match self.request(&HostMsg::GetProfile)? {
            DeviceMsg::Profile(p) => Ok(p),
            other => Err(unexpected("GetProfile", &other)),
        }
    }

    /// Persists the active configuration and haptic profile.
    pub fn save_config(&mut self) -> Result<()> {
        self.request(&HostMsg::SaveConfig).map(drop)
    }

    /// Applies the firmware defaults and returns them.
    pub fn load_defaults(&mut self) -> Result<ServoConfig> {
        match self.request(&HostMsg::LoadDefaults)? {
            DeviceMsg::Config(c) => Ok(c),
            other => Err(unexpected("LoadDefaults", &other)),
        }
    }

    /// Reads latched faults.
    pub fn faults(&mut self) -> Result<FaultReport> {
        match self.request(&HostMsg::GetFaults)? {
            DeviceMsg::Faults(f) => Ok(f),
            other => Err(unexpected("GetFaults", &other)),
        }
    }

    /// Asks the board to end its run (the QEMU image exits through semihosting).
    ///
    /// The board exits as soon as its acknowledgement has left its UART. A host that is still
    /// reading a backlog (error replies to a flood, say) can then see the link hang up before
    /// it reads the Ack: the serial driver reports the hangup (`POLLHUP`, "Broken pipe") in
    /// place of the bytes still queued. A hangup after the request was written is therefore
    /// the shutdown having happened, and counts as acknowledged; callers that need proof check
    /// the board's exit status (the QEMU scenarios do). Any other error is returned.
    pub fn shutdown(&mut self, exit_code: u8) -> Result<()> {
        match self.request(&HostMsg::Shutdown { exit_code }) {
            Ok(_) => Ok(()),
            Err(e) if e.is_hangup() => Ok(()),
            Err(e) => Err(e),
        }
    }

    /// Has the device run the next release or impact test with `config` (the active config
    /// is back on the tick it ends) and end it itself as soon as its released counts decide
    /// it (the rule of [`HostMsg::PrepareTest`]: settled after a run of at least
    /// `min_run_ticks` equal counts, within one count with `within_one_count`, 0 for never;
    /// or at a decay checkpoint from `decay_base_ticks`, 0 for none). Neither the test's start
    /// nor its end then depends on the link's latency.
    pub fn prepare_test(
        &mut self,
        config: &ServoConfig,
        min_run_ticks: u32,
        within_one_count: bool,
        decay_base_ticks: u32,
    ) -> Result<()> {
        self.request(&HostMsg::PrepareTest {
            config: *config,
            min_run_ticks,
            within_one_count,
            decay_base_ticks,
        })
        .map(drop)
    }

    /// Clears latched faults.
    pub fn clear_faults(&mut self) -> Result<()> {
        self.request(&HostMsg::ClearFaults).map(drop)
    }

    /// Starts telemetry at one sample per `decimation` ticks.
    pub fn stream_start(&mut self, decimation: u16) -> Result<()> {
        self.link.restart_sequence();
        self.request(&HostMsg::StreamStart { decimation }).map(drop)
    }

    /// Stops telemetry and discards batches still queued.
    pub fn stream_stop(&mut self) -> Result<()> {
        self.request(&HostMsg::StreamStop)?;
        self.link.drop_telemetry();
        Ok(())
    }
}

/// The handshake on a fresh link: a `Hello` (after a 0x00 that ends whatever a board still
/// booting holds), retried up to three times, answered with the device's info at this host's
/// protocol version.
fn handshake(link: &mut Link) -> Result<DeviceInfo> {
    link.write_sync_byte();
    let mut last_err = None;
    for _ in 0..3 {
        link.send(&HostMsg::Hello {
            protocol_version: PROTOCOL_VERSION,
        })?;
        match link.wait(ANSWER_TIMEOUT, "Hello", |m| match m {
            DeviceMsg::HelloReply(_) => true,
            DeviceMsg::Error { code, .. } => !code.is_framing(),
            _ => false,
        }) {
            Ok(DeviceMsg::HelloReply(info)) => {
                if info.protocol_version != PROTOCOL_VERSION {
                    return Err(ClientError::VersionMismatch {
                        device: info.protocol_version,
                        host: PROTOCOL_VERSION,
                    });
                }
                // Framing errors seen so far answer bytes from before the link was in sync (a
                // Hello that reached a board still booting, whose UART overran, or a banner):
                // they are about no request of the caller's, so they are not handed on as if
                // they had come later.
                link.drop_framing_errors();
                return Ok(info);
            }
            Ok(DeviceMsg::Error { code, detail }) => {
                return Err(ClientError::Refused {
                    request: "handshake".into(),
                    code,
                    detail,
                })
            }
            Ok(_) => unreachable!("filtered by the predicate"),
            Err(e) => last_err = Some(e),
        }
    }
    Err(ClientError::NoHandshake(Box::new(last_err.unwrap_or(
        ClientError::Timeout {
            request: Some("Hello".into()),
            waited: ANSWER_TIMEOUT,
            bad_frames: None,
        },
    ))))
}

fn unexpected(request: &str, answer: &DeviceMsg) -> ClientError {
    ClientError::Unexpected {
        request: request.to_string(),
        answer: answer.name().to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::pty_pair;
    use std::io::{Read, Write};
    use std::time::Instant;
    use stiffwall_proto::{encode, FrameDecoder, MAX_FRAME};

    /// A device's info for the scripted devices' handshake answers.
    fn placeholder_info() -> DeviceInfo {
        DeviceInfo {
            protocol_version: 0,
            firmware_name: heapless::String::new(),
            firmware_version: heapless::String::new(),
            board: heapless::String::new(),
            servo_rate_hz: 1000,
            counts_per_rev: 0,
            resolution: 0.0,
            encoder_bits: 32,
            force_per_code: 0.0,
            max_code: 0,
            limits: stiffwall_proto::Limits {
                min_rate_hz: 0,
                max_rate_hz: 0,
                max_stiffness: 0.0,
                max_force: 0.0,
                max_delay_ticks: 0,
                max_coarsen_shift: 0,
                telemetry_batch: 0,
                max_table: 0,
            },
        }
    }
    use stiffwall_proto::ErrorDetail;
    use stiffwall_proto::{ErrorCode, Request};

    fn is_hangup(e: &ClientError) -> bool {
        e.is_hangup()
    }

    /// A scripted device on the master side of a pty: answers the handshake, then reads one
    /// request and does `then` with the port (answer, or hang up by dropping it).
    fn scripted(then: fn(&mut serialport::TTYPort, HostMsg)) -> Client {
        let (mut master, host, _name) = pty_pair().unwrap();
        std::thread::spawn(move || {
            let mut dec = FrameDecoder::new();
            let mut requests = 0;
            let mut byte = [0u8; 1];
            while master.read_exact(&mut byte).is_ok() {
                let Some(Ok(msg)) = dec.feed::<HostMsg>(byte[0]) else {
                    continue;
                };
                requests += 1;
                if requests == 1 {
                    let mut info = placeholder_info();
                    info.protocol_version = PROTOCOL_VERSION;
                    reply(&mut master, &DeviceMsg::HelloReply(info));
                } else {
                    then(&mut master, msg);
                    return; // drops the master: the host sees the pty hang up
                }
            }
        });
        Client::connect(host, None).unwrap()
    }

    fn reply(port: &mut serialport::TTYPort, msg: &DeviceMsg) {
        let mut buf = [0u8; MAX_FRAME];
        port.write_all(encode(msg, &mut buf).unwrap()).unwrap();
    }

    #[test]
    fn framing_errors_from_before_the_handshake_are_not_handed_on() {
        // A board whose UART overran on the host's first bytes answers them with a COBS error
        // ahead of the HelloReply; the caller's first `recv` must not see it as a new error,
        // while a framing error that comes after the handshake still comes through.
        let (mut master, host, _name) = pty_pair().unwrap();
        std::thread::spawn(move || {
            let mut dec = FrameDecoder::new();
            let mut byte = [0u8; 1];
            while master.read_exact(&mut byte).is_ok() {
                if let Some(Ok(HostMsg::Hello { .. })) = dec.feed::<HostMsg>(byte[0]) {
                    let junk = DeviceMsg::Error {
                        code: ErrorCode::Cobs,
                        detail: ErrorDetail::None,
                    };
                    reply(&mut master, &junk);
                    let mut info = placeholder_info();
                    info.protocol_version = PROTOCOL_VERSION;
                    reply(&mut master, &DeviceMsg::HelloReply(info));
                    let later = DeviceMsg::Error {
                        code: ErrorCode::Crc,
                        detail: ErrorDetail::None,
                    };
                    std::thread::sleep(Duration::from_millis(100));
                    reply(&mut master, &later);
                    std::thread::sleep(Duration::from_millis(500));
                    return;
                }
            }
        });
        let mut c = Client::connect(host, None).unwrap();
        let first = c.recv(Duration::from_secs(2)).unwrap();
        assert!(
            matches!(
                first,
                Some(DeviceMsg::Error {
                    code: ErrorCode::Crc,
                    ..
                })
            ),
            "{first:?}"
        );
    }

    #[test]
    fn a_hangup_after_shutdown_counts_as_the_shutdown() {
        let mut c = scripted(|_, msg| assert_eq!(msg, HostMsg::Shutdown { exit_code: 3 }));
        c.shutdown(3)
            .expect("the board hung up after reading Shutdown");
    }

    /// A device that answers the handshake, then each request by `answer(n, msg)` (n = 1 for
    /// the first after the handshake) until `answer` returns None; counts the requests.
    fn answering(
        answer: fn(usize, &HostMsg) -> Option<DeviceMsg>,
    ) -> (Client, std::sync::Arc<std::sync::atomic::AtomicUsize>) {
        let (mut master, host, _name) = pty_pair().unwrap();
        let seen = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let counter = seen.clone();
        std::thread::spawn(move || {
            let mut dec = FrameDecoder::new();
            let mut byte = [0u8; 1];
            while master.read_exact(&mut byte).is_ok() {
                let Some(Ok(msg)) = dec.feed::<HostMsg>(byte[0]) else {
                    continue;
                };
                if let HostMsg::Hello { .. } = msg {
                    let mut info = placeholder_info();
                    info.protocol_version = PROTOCOL_VERSION;
                    reply(&mut master, &DeviceMsg::HelloReply(info));
                    continue;
                }
                let n = counter.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
                match answer(n, &msg) {
                    Some(m) => reply(&mut master, &m),
                    None => return,
                }
            }
        });
        (Client::connect(host, None).unwrap(), seen)
    }

    #[test]
    fn a_full_servo_queue_is_retried_by_its_code_and_a_busy_device_is_not() {
        let (mut c, seen) = answering(|n, msg| {
            assert_eq!(*msg, HostMsg::ClearFaults);
            Some(if n < 3 {
                DeviceMsg::Error {
                    code: ErrorCode::QueueFull,
                    detail: ErrorDetail::None,
                }
            } else {
                DeviceMsg::Ack(Request::ClearFaults)
            })
        });
        c.clear_faults().expect("acknowledged on the third try");
        assert_eq!(seen.load(std::sync::atomic::Ordering::SeqCst), 3);
        // `Busy` (an experiment running, faults latched) is a refusal, whatever its text.
        let (mut c, seen) = answering(|_, _| {
            Some(DeviceMsg::Error {
                code: ErrorCode::Busy,
                detail: ErrorDetail::Text(heapless::String::try_from("servo queue full").unwrap()),
            })
        });
        let e = c.clear_faults().unwrap_err();
        assert!(
            matches!(
                e,
                ClientError::Refused {
                    code: ErrorCode::Busy,
                    ..
                }
            ),
            "{e:#}"
        );
        assert_eq!(seen.load(std::sync::atomic::Ordering::SeqCst), 1);
    }

    #[test]
    fn a_refused_shutdown_is_an_error() {
        let mut c = scripted(|port, _| {
            reply(
                port,
                &DeviceMsg::Error {
                    code: ErrorCode::Busy,
                    detail: ErrorDetail::None,
                },
            );
            std::thread::sleep(Duration::from_millis(200)); // the host reads it before the hangup
        });
        let e = c.shutdown(0).unwrap_err();
        assert!(format!("{e:#}").contains("Shutdown refused"), "{e:#}");
    }

    #[test]
    fn bad_frames_answered_ahead_of_a_request_extend_its_wait() {
        // The device works through a backlog of garbage for 2.3 s (longer than ANSWER_TIMEOUT),
        // answering it with framing errors every 0.5 s, then answers the request.
        let mut c = scripted(|port, msg| {
            assert_eq!(msg, HostMsg::GetFaults);
            for _ in 0..5 {
                let cobs = DeviceMsg::Error {
                    code: ErrorCode::Cobs,
                    detail: ErrorDetail::None,
                };
                reply(port, &cobs);
                std::thread::sleep(Duration::from_millis(500));
            }
            std::thread::sleep(Duration::from_millis(300));
            let report = FaultReport {
                latched: 4,
                first_tick: 9,
                safe_mode: false,
            };
            reply(port, &DeviceMsg::Faults(report));
            std::thread::sleep(Duration::from_millis(200));
        });
        assert!(Duration::from_millis(2300) > ANSWER_TIMEOUT);
        let t = Instant::now();
        assert_eq!(c.faults().unwrap().latched, 4);
        assert!(t.elapsed() > ANSWER_TIMEOUT, "{:?}", t.elapsed());
    }

    #[test]
    fn silence_after_bad_frames_still_times_out() {
        let mut c = scripted(|port, _| {
            let cobs = DeviceMsg::Error {
                code: ErrorCode::Cobs,
                detail: ErrorDetail::None,
            };
            reply(port, &cobs);
            std::thread::sleep(Duration::from_secs(4));
        });
        let t = Instant::now();
        let e = c.faults().unwrap_err();
        assert!(
            format!("{e:#}").contains("the device reported bad frames: bad COBS framing"),
            "{e:#}"
        );
        assert!(t.elapsed() < Duration::from_secs(3), "{:?}", t.elapsed());
    }

    #[test]
    fn a_hangup_during_any_other_request_is_an_error() {
        let mut c = scripted(|_, msg| assert_eq!(msg, HostMsg::GetFaults));
        let e = c.faults().unwrap_err();
        assert!(is_hangup(&e), "{e:#}");
    }

    /// A scripted device on an in-memory link: answers the handshake, then refuses every
    /// request with the stiffness out of [0, 10].
    fn in_memory_refusing() -> Client {
        let (mut device, host) = crate::transport::memory_pair();
        std::thread::spawn(move || {
            let mut dec = FrameDecoder::new();
            let mut buf = [0u8; 256];
            loop {
                let n = match device.read(&mut buf) {
                    Ok(0) => return,
                    Ok(n) => n,
                    Err(_) => continue,
                };
                for &b in &buf[..n] {
                    let Some(Ok(msg)) = dec.feed::<HostMsg>(b) else {
                        continue;
                    };
                    let answer = if matches!(msg, HostMsg::Hello { .. }) {
                        let mut info = placeholder_info();
                        info.protocol_version = PROTOCOL_VERSION;
                        DeviceMsg::HelloReply(info)
                    } else {
                        DeviceMsg::Error {
                            code: ErrorCode::InvalidConfig,
                            detail: ErrorDetail::Field {
                                field: stiffwall_proto::ConfigField::Stiffness,
                                min: 0.0,
                                max: 10.0,
                            },
                        }
                    };
                    let mut out = [0u8; MAX_FRAME];
                    if device
                        .write_all(encode(&answer, &mut out).unwrap())
                        .is_err()
                    {
                        return;
                    }
                }
            }
        });
        Client::connect(host, None).unwrap()
    }

    #[test]
    fn a_refusal_carries_the_proto_field_and_its_range() {
        let mut c = in_memory_refusing();
        let e = c.set_config(&ServoConfig::default()).unwrap_err();
        match &e {
            ClientError::Refused {
                request,
                code: ErrorCode::InvalidConfig,
                detail:
                    ErrorDetail::Field {
                        field: stiffwall_proto::ConfigField::Stiffness,
                        min,
                        max,
                    },
            } => {
                assert_eq!(request, "SetConfig");
                assert_eq!((*min, *max), (0.0, 10.0));
            }
            other => panic!("not a refusal of the stiffness: {other:?}"),
        }
        assert_eq!(
            e.to_string(),
            "SetConfig refused: configuration refused: stiffness must be within [0, 10]"
        );
        assert!(!e.is_hangup());
    }

    #[test]
    fn a_silent_in_memory_device_times_out_and_a_dropped_one_hangs_up() {
        let (device, host) = crate::transport::memory_pair();
        let t = Instant::now();
        let e = Client::connect(host, None).unwrap_err();
        assert!(
            matches!(&e, ClientError::NoHandshake(inner)
            if matches!(**inner, ClientError::Timeout { .. })),
            "{e:?}"
        );
        assert!(t.elapsed() >= ANSWER_TIMEOUT, "{:?}", t.elapsed());
        drop(device);
        // Gone before the handshake: the hello cannot be written.
        let (device, host) = crate::transport::memory_pair();
        drop(device);
        let e = Client::connect(host, None).unwrap_err();
        assert!(e.is_hangup(), "{e:?}");
    }
}
