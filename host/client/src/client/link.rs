//! The link to a device: the port, the frame decoder, the queue of messages not yet taken
//! (telemetry that arrives while a request waits is queued, never lost) and the telemetry gap
//! counts. A gap in sample numbers is attributed to the device (its cumulative `dropped`
//! counter grew by the same amount) or to the link (it did not). [`super::Client`] is made on
//! a link only after the handshake.
//!
//! Times are host time (`Duration`s); nothing here knows what a request means beyond which
//! reply answers it ([`HostMsg::ack_kind`]) and which replies are framing errors
//! ([`stiffwall_proto::ErrorCode::is_framing`]).

use crate::describe::{describe_error, is_framing_reply};
use crate::error::{ClientError, Result};
use crate::transport::Transport;
use std::collections::VecDeque;
use std::io::{ErrorKind, Read, Write};
use std::time::{Duration, Instant};
use stiffwall_proto::{encode, DeviceMsg, FrameDecoder, HostMsg, TelemetryBatch, MAX_FRAME};

/// How long a request waits for its answer.
pub const ANSWER_TIMEOUT: Duration = Duration::from_millis(1500);
/// How long a request waits at most while the device keeps answering bad frames queued ahead
/// of it (a flood or a noisy line): each such error reply restarts [`ANSWER_TIMEOUT`], up to
/// this long after the request was sent.
pub const BACKLOG_WAIT_MAX: Duration = Duration::from_secs(10);
/// How long a request refused with a full servo queue is repeated.
pub const QUEUE_FULL_RETRY: Duration = Duration::from_secs(2);
/// Telemetry bookkeeping.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct GapStats {
    /// Samples received.
    pub received: u64,
    /// Samples missing in sequence numbers.
    pub missing: u64,
    /// Of those, samples the device reports it dropped (queue overflow).
    pub dropped_on_device: u64,
    /// Frames that failed to decode (CRC, COBS, …), i.e. lost on the link.
    pub bad_frames: u64,
}

/// The port with its decoder, queue and gap counts.
#[derive(Debug)]
pub struct Link {
    port: Box<dyn Transport>,
    decoder: FrameDecoder,
    pending: VecDeque<DeviceMsg>,
    next_seq: Option<u32>,
    last_dropped: u32,
    gaps: GapStats,
}

impl Link {
    /// A link on an opened port, nothing read or written yet.
    #[must_use]
    pub fn new(port: Box<dyn Transport>) -> Self {
        Self {
            port,
            decoder: FrameDecoder::new(),
            pending: VecDeque::new(),
            next_seq: None,
            last_dropped: 0,
            gaps: GapStats::default(),
        }
    }

    /// Telemetry bookkeeping since the link was made.
    #[must_use]
    pub fn gaps(&self) -> GapStats {
        self.gaps
    }

    /// Writes one 0x00: it ends whatever frame a board still printing its boot banner, or
    /// mid-frame, holds (best effort: an error here shows in the handshake).
    pub(crate) fn write_sync_byte(&mut self) {
        let _ = self.port.write_all(&[0]);
    }

    /// The next telemetry batch starts a new sample sequence (no gap against the last one).
    pub(crate) fn restart_sequence(&mut self) {
        self.next_seq = None;
    }

    /// Discards queued telemetry.
    pub(crate) fn drop_telemetry(&mut self) {
        self.pending
            .retain(|m| !matches!(m, DeviceMsg::Telemetry(_)));
    }

    /// Discards queued framing-error replies.
    pub(crate) fn drop_framing_errors(&mut self) {
        self.pending
            .retain(|m| !matches!(m, DeviceMsg::Error { code, .. } if code.is_framing()));
    }

    /// Sends one message.
    pub fn send(&mut self, msg: &HostMsg) -> Result<()> {
        let mut buf = [0u8; MAX_FRAME];
        let frame = encode(msg, &mut buf)
            .map_err(|e| ClientError::Framing(format!("encoding {msg:?}: {e}")))?;
        self.write_bytes(frame)
    }

    /// Writes raw bytes (tests of malformed input).
    pub fn send_raw(&mut self, bytes: &[u8]) -> Result<()> {
        self.write_bytes(bytes)
    }

    /// Writes all bytes, waiting while the port is full (a device may read its UART one byte at
    /// a time); fails when the port errors or makes no progress for [`ANSWER_TIMEOUT`].
    ///
    /// While it waits, what the device sends is read and queued: framing-error replies show it
    /// is reading input from elsewhere on the line (a flood that fills the link), and each
    /// restarts the stall timeout, up to [`BACKLOG_WAIT_MAX`] in all.
    fn write_bytes(&mut self, mut bytes: &[u8]) -> Result<()> {
        let start = Instant::now();
        let mut stalled_since = start;
        let mut device_reading = false;
        while !bytes.is_empty() {
            match self.port.write(bytes) {
                Ok(0) => {}
                Ok(n) => {
                    bytes = &bytes[n..];
                    stalled_since = Instant::now();
                    continue;
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
                    ) => {}
                Err(e) => return Err(ClientError::io("writing", e)),
            }
            if self.port.bytes_to_read().unwrap_or(0) > 0 {
                let queued = self.pending.len();
                self.read_once()?;
                let answered_garbage = self
                    .pending
                    .iter()
                    .skip(queued)
                    .any(|m| matches!(m, DeviceMsg::Error { code, .. } if code.is_framing()));
                if answered_garbage && start.elapsed() < BACKLOG_WAIT_MAX {
                    device_reading = true;
                    stalled_since = Instant::now();
                }
            }
            if stalled_since.elapsed() > ANSWER_TIMEOUT {
                return Err(ClientError::WriteStalled {
                    waited: if device_reading {
                        start.elapsed()
                    } else {
                        ANSWER_TIMEOUT
                    },
                    link_full: device_reading,
                });
            }
        }
        self.port.flush().ok();
        Ok(())
    }

    /// Reads what is available and returns the next message, waiting up to `timeout`.
    pub fn recv(&mut self, timeout: Duration) -> Result<Option<DeviceMsg>> {
        if let Some(m) = self.pending.pop_front() {
            return Ok(Some(m));
        }
        let deadline = Instant::now() + timeout;
        loop {
            self.read_once()?;
            if let Some(m) = self.pending.pop_front() {
                return Ok(Some(m));
            }
            if Instant::now() >= deadline {
                return Ok(None);
            }
        }
    }

    /// One read from the port (waiting up to its read timeout); the messages it completes are
    /// queued, telemetry accounted, undecodable frames counted.
    fn read_once(&mut self) -> Result<()> {
        let mut buf = [0u8; 4096];
        let n = match self.port.read(&mut buf) {
            Ok(0) => {
                return Err(ClientError::io(
                    "reading",
                    std::io::Error::from(ErrorKind::UnexpectedEof),
                ))
            }
            Ok(n) => n,
            Err(e) if e.kind() == ErrorKind::TimedOut || e.kind() == ErrorKind::WouldBlock => 0,
            Err(e) if e.kind() == ErrorKind::Interrupted => 0,
            Err(e) => return Err(ClientError::io("reading", e)),
        };
        for &b in &buf[..n] {
            match self.decoder.feed::<DeviceMsg>(b) {
                Some(Ok(m)) => {
                    if let DeviceMsg::Telemetry(batch) = &m {
                        self.account(batch);
                    }
                    self.pending.push_back(m);
                }
                Some(Err(_)) => self.gaps.bad_frames += 1,
                None => {}
            }
        }
        Ok(())
    }

    fn account(&mut self, batch: &TelemetryBatch) {
        if let Some(expect) = self.next_seq {
            let gap = batch.seq.wrapping_sub(expect);
            if gap != 0 && gap < u32::MAX / 2 {
                self.gaps.missing += u64::from(gap);
                let dev = batch.dropped.wrapping_sub(self.last_dropped);
                self.gaps.dropped_on_device += u64::from(dev.min(gap));
            }
        }
        self.last_dropped = batch.dropped;
        self.gaps.received += batch.samples.len() as u64;
        self.next_seq = Some(batch.seq.wrapping_add(batch.samples.len() as u32));
    }

    /// Waits for a message matching `want`; other messages (telemetry) are kept for later.
    pub(crate) fn wait(
        &mut self,
        timeout: Duration,
        request: &str,
        want: impl Fn(&DeviceMsg) -> bool,
    ) -> Result<DeviceMsg> {
        self.wait_extending(timeout, timeout, want, |_| false)
            .map_err(|e| match e {
                ClientError::Timeout {
                    request: None,
                    waited,
                    bad_frames,
                } => ClientError::Timeout {
                    request: Some(request.to_string()),
                    waited,
                    bad_frames,
                },
                e => e,
            })
    }

    /// [`Self::wait`], where a message for which `progress` holds restarts the `timeout`, up to
    /// `cap` after the start: the device is visibly working through input queued ahead of the
    /// request.
    fn wait_extending(
        &mut self,
        timeout: Duration,
        cap: Duration,
        want: impl Fn(&DeviceMsg) -> bool,
        progress: impl Fn(&DeviceMsg) -> bool,
    ) -> Result<DeviceMsg> {
        let start = Instant::now();
        let end = start + cap.max(timeout);
        let mut deadline = start + timeout;
        let mut kept = VecDeque::new();
        let expired = |waited: Duration| ClientError::Timeout {
            request: None,
            waited,
            bad_frames: None,
        };
        let result = loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.recv(left)? {
                Some(m) if want(&m) => break Ok(m),
                // On time even while other messages keep arriving.
                Some(m) => {
                    if progress(&m) {
                        deadline = (Instant::now() + timeout).min(end).max(deadline);
                    }
                    kept.push_back(m);
                    if Instant::now() >= deadline {
                        break Err(expired(start.elapsed()));
                    }
                }
                None => break Err(expired(start.elapsed())),
            }
        };
        kept.extend(self.pending.drain(..));
        self.pending = kept;
        result
    }

    /// Sends a request and waits for its answer; a device `Error` becomes an error.
    ///
    /// Framing errors (CRC, COBS, oversize, unknown tag, malformed body) do not answer a
    /// request this client encoded: they answer bad frames from elsewhere on the link (a
    /// noisy line, another writer), so the wait goes on. They also show the device working
    /// through input queued ahead of the request, so each restarts the answer timeout, for at
    /// most [`BACKLOG_WAIT_MAX`]; if no answer comes, the timeout names the last one seen.
    ///
    /// A full servo command queue (`QueueFull`: the servo takes one command per tick) is
    /// transient ([`stiffwall_proto::ErrorCode::is_transient`]): the request is repeated, for at most
    /// [`QUEUE_FULL_RETRY`].
    pub fn request(&mut self, msg: &HostMsg) -> Result<DeviceMsg> {
        let deadline = Instant::now() + QUEUE_FULL_RETRY;
        loop {
            let m = self.request_once(msg)?;
            let full = matches!(&m, DeviceMsg::Error { code, .. } if code.is_transient());
            if !full || Instant::now() > deadline {
                if let DeviceMsg::Error { code, detail } = m {
                    return Err(ClientError::Refused {
                        request: msg.name().to_string(),
                        code,
                        detail,
                    });
                }
                return Ok(m);
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    fn request_once(&mut self, msg: &HostMsg) -> Result<DeviceMsg> {
        self.send(msg)?;
        let ack = msg.ack_kind();
        let last_framing = std::cell::Cell::new(None);
        let m = self
            .wait_extending(
                ANSWER_TIMEOUT,
                BACKLOG_WAIT_MAX,
                |m| match m {
                    DeviceMsg::Error { code, detail } if code.is_framing() => {
                        last_framing.set(Some(describe_error(*code, detail)));
                        false
                    }
                    DeviceMsg::Error { .. } => true,
                    DeviceMsg::Ack(r) => Some(*r) == ack,
                    DeviceMsg::Config(_) => {
                        matches!(msg, HostMsg::GetConfig | HostMsg::LoadDefaults)
                    }
                    DeviceMsg::Faults(_) => matches!(msg, HostMsg::GetFaults),
                    DeviceMsg::Profile(_) => matches!(msg, HostMsg::GetProfile),
                    DeviceMsg::HelloReply(_) => matches!(msg, HostMsg::Hello { .. }),
                    _ => false,
                },
                is_framing_reply,
            )
            .map_err(|e| match e {
                ClientError::Timeout { waited, .. } => ClientError::Timeout {
                    request: Some(msg.name().to_string()),
                    waited,
                    bad_frames: last_framing.take(),
                },
                e => e,
            })?;
        Ok(m)
    }

    /// Next telemetry batch, or None after `timeout` (on time whatever else arrives).
    pub fn next_batch(&mut self, timeout: Duration) -> Result<Option<TelemetryBatch>> {
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.recv(left)? {
                Some(DeviceMsg::Telemetry(b)) => return Ok(Some(b)),
                // Other messages (errors of a flood of bad frames, stray replies) never hold
                // the caller past its deadline: its watchdogs and heartbeats must run.
                Some(_) if Instant::now() < deadline => {}
                Some(_) | None => return Ok(None),
            }
        }
    }
}
