//! The device's main-loop step on the link: requests read and decoded, telemetry moved from
//! the servo's queue into batches, the experiment's end reported after its samples, and
//! frames sent as far as the link takes them.
//!
//! Units: `now` is the servo tick (it ages partial telemetry batches: one is flushed after
//! `servo_rate_hz / 100` ticks, 10 ms). Invariants: see the module [`super`]: no reply is lost
//! (bytes are read only while a reply has room), at most [`REPLY_BUDGET`] replies go before a
//! ready batch, work per `poll` is bounded ([`READ_BUDGET`] bytes, [`FRAME_BUDGET`] frames).

use super::{Device, RejectedRun, REPLIES, REPLY_BUDGET};
use crate::channels::ServoEvent;
use crate::hal::{ByteLink, ConfigStorage};
use crate::numeric::Numeric;
use stiffwall_proto::{encode, DeviceMsg, ErrorDetail, HostMsg, TelemetryBatch, TELEMETRY_BATCH};

/// Bytes read per `poll` at most.
const READ_BUDGET: usize = 512;
/// Frames started per `poll` at most.
const FRAME_BUDGET: usize = 4;

fn seq_reached(next: u32, target: u32) -> bool {
    next.wrapping_sub(target) as i32 >= 0
}

/// The one reply to a run of bad frames (the detail of its first, or `Repeated`).
fn rejected_reply(run: RejectedRun) -> DeviceMsg {
    DeviceMsg::Error {
        code: run.code,
        detail: if run.count > 1 {
            ErrorDetail::Repeated { count: run.count }
        } else {
            run.detail
        },
    }
}

impl<S: ConfigStorage, N: Numeric> Device<'_, S, N> {
    /// One main-loop step: read and handle frames, collect telemetry, send what the link takes.
    pub fn poll(&mut self, now: u32, link: &mut impl ByteLink) {
        // 1. Requests (only while a reply has room; the pending run of bad frames holds one).
        self.read_requests(link);
        // 2. Telemetry into the batch.
        self.collect(now);
        // 3. Experiment end, after its samples.
        self.experiment_end();
        // 4. Transmit.
        self.transmit(now, link);
    }

    /// A reply has room in the queue (counting the pending run of bad frames).
    fn reply_room(&self) -> bool {
        self.replies.len() + usize::from(self.rejected.is_some()) < REPLIES
    }

    /// Reads and handles frames while a reply has room, [`READ_BUDGET`] bytes at most.
    fn read_requests(&mut self, link: &mut impl ByteLink) {
        let mut budget = READ_BUDGET;
        while budget > 0 && self.reply_room() {
            budget -= 1;
            let Some(b) = link.read() else { break };
            match self.decoder.feed::<HostMsg>(b) {
                None => {}
                Some(Ok(msg)) => {
                    self.stats.frames_ok = self.stats.frames_ok.wrapping_add(1);
                    // The run's reply goes first: replies keep the order of the frames.
                    self.flush_rejected();
                    let reply = self.handle(msg);
                    if matches!(reply, DeviceMsg::Error { .. }) {
                        self.stats.refused = self.stats.refused.wrapping_add(1);
                    }
                    let _ = self.replies.push_back(reply);
                }
                Some(Err(e)) => {
                    self.stats.frames_bad = self.stats.frames_bad.wrapping_add(1);
                    self.stats.refused = self.stats.refused.wrapping_add(1);
                    match &mut self.rejected {
                        Some(run) if run.code == e.code() && run.count < u32::MAX => {
                            run.count += 1;
                        }
                        _ => {
                            self.flush_rejected();
                            self.rejected = Some(RejectedRun {
                                code: e.code(),
                                detail: e.detail(),
                                count: 1,
                            });
                        }
                    }
                }
            }
        }
    }

    /// Queues `ExperimentDone` once the experiment's last sample has left (cutting the batch
    /// short so that it leaves) and a reply has room.
    fn experiment_end(&mut self) {
        if self.pending_event.is_none() {
            self.pending_event = self.port.events.dequeue();
        }
        if let Some(ServoEvent::ExperimentDone {
            kind,
            completed,
            faults,
            next_seq,
        }) = self.pending_event
        {
            // Every sample of the experiment has been collected.
            let collected = seq_reached(self.next_seq, next_seq);
            if collected && self.batch.samples.is_empty() && self.reply_room() {
                let _ = self.replies.push_back(DeviceMsg::ExperimentDone {
                    kind,
                    completed,
                    faults,
                });
                self.pending_event = None;
            } else if collected {
                self.batch_cut = true;
            }
        }
    }

    /// Sends frames while the link takes bytes, [`FRAME_BUDGET`] frames at most.
    fn transmit(&mut self, now: u32, link: &mut impl ByteLink) {
        for _ in 0..FRAME_BUDGET {
            while self.tx_pos < self.tx_len {
                let Some(&b) = self.tx.get(self.tx_pos) else {
                    break;
                };
                if !link.write(b) {
                    return;
                }
                self.tx_pos += 1;
            }
            if !self.next_frame(now) {
                return;
            }
            self.collect(now);
        }
    }

    /// Queues the reply to the pending run of bad frames, if any (the caller keeps a slot free).
    fn flush_rejected(&mut self) {
        if let Some(r) = self.rejected.take() {
            let _ = self.replies.push_back(rejected_reply(r));
        }
    }

    /// Moves samples from the servo queue into the batch (consecutive numbers only).
    fn collect(&mut self, now: u32) {
        while self.batch.samples.len() < TELEMETRY_BATCH && !self.batch_cut {
            let Some(item) = self.port.telemetry.peek().copied() else {
                break;
            };
            let gap = item.seq.wrapping_sub(self.next_seq);
            if gap != 0 && !self.batch.samples.is_empty() {
                self.batch_cut = true;
                break;
            }
            let _ = self.port.telemetry.dequeue();
            self.dropped = self.dropped.wrapping_add(gap);
            self.next_seq = item.seq.wrapping_add(1);
            if self.batch.samples.is_empty() {
                self.batch.seq = item.seq;
                self.batch_tick = now;
            }
            let _ = self.batch.samples.push(item.sample);
        }
        self.batch.dropped = self.dropped;
    }

    /// Encodes the next frame into `tx`; `false` if there is nothing to send.
    fn next_frame(&mut self, now: u32) -> bool {
        let flush_ticks = (self.config.servo_rate_hz / 100).max(1);
        let telemetry_ready = !self.batch.samples.is_empty()
            && (self.batch.samples.len() >= TELEMETRY_BATCH
                || self.batch_cut
                || now.wrapping_sub(self.batch_tick) >= flush_ticks
                || self.pending_event.is_some());
        let reply_turn = !(telemetry_ready && self.replies_in_row >= REPLY_BUDGET);
        let reply = if reply_turn {
            // Older replies first, then the run of bad frames (newer than every queued reply).
            self.replies
                .pop_front()
                .or_else(|| self.rejected.take().map(rejected_reply))
        } else {
            None
        };
        let msg = if let Some(r) = reply {
            self.replies_in_row = self.replies_in_row.saturating_add(1).min(REPLY_BUDGET);
            r
        } else if telemetry_ready {
            self.replies_in_row = 0;
            self.batch_cut = false;
            let b = core::mem::replace(
                &mut self.batch,
                TelemetryBatch {
                    seq: 0,
                    dropped: self.dropped,
                    samples: heapless::Vec::new(),
                },
            );
            DeviceMsg::Telemetry(b)
        } else {
            self.batch_cut = false;
            return false;
        };
        match encode(&msg, &mut self.tx) {
            Ok(f) => {
                self.tx_len = f.len();
                self.tx_pos = 0;
                true
            }
            Err(_) => false,
        }
    }
}
