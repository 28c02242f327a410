//! Tests of the device: replies to requests and refusals, the command queue, prepared tests,
//! and the link's fairness (slow links, floods of bad frames and of requests).
//!
//! `Link` is an in-memory byte link (optionally taking only `tx_room` bytes per poll); `rig`
//! is the common setup of a device and its servo on the default board.

use super::*;
use crate::channels::Channels;
use crate::hal::{ByteLink, HeldCode, SampledCount};
use crate::servo::Servo;
use crate::store::MemStorage;
use std::collections::VecDeque;
use std::vec::Vec;
use stiffwall_proto::frame::decode_frame;
use stiffwall_proto::{encode, ConfigField, HostMsg, Request, PROTOCOL_VERSION, TELEMETRY_BATCH};

#[derive(Default)]
struct Link {
    rx: VecDeque<u8>,
    tx: Vec<u8>,
    tx_room: Option<usize>,
}
impl ByteLink for Link {
    fn read(&mut self) -> Option<u8> {
        self.rx.pop_front()
    }
    fn write(&mut self, b: u8) -> bool {
        if let Some(r) = &mut self.tx_room {
            if *r == 0 {
                return false;
            }
            *r -= 1;
        }
        self.tx.push(b);
        true
    }
}
impl Link {
    fn send(&mut self, m: &HostMsg) {
        let mut buf = [0u8; MAX_FRAME];
        self.rx.extend(encode(m, &mut buf).unwrap());
    }
    fn frames(&mut self) -> Vec<DeviceMsg> {
        let mut out = Vec::new();
        let mut cur = Vec::new();
        for b in self.tx.drain(..) {
            cur.push(b);
            if b == 0 {
                out.push(decode_frame::<DeviceMsg>(&mut cur).unwrap());
                cur.clear();
            }
        }
        self.tx = cur;
        out
    }
}

/// The common setup: the device on the default board with `defaults` (no config stored), its
/// servo, and an empty link. `ch` is the caller's: the ports borrow it.
fn rig(ch: &mut Channels, defaults: ServoConfig) -> (Device<'_, MemStorage>, Servo<'_>, Link) {
    let (sp, hp) = ch.split();
    let b = BoardInfo::default();
    let dev = Device::new(b, ConfigStore::new(MemStorage::default()), hp, defaults);
    let servo: Servo<'_> = Servo::new(b, dev.config(), sp);
    (dev, servo, Link::default())
}

#[test]
fn hello_config_and_refusal() {
    let mut ch = Channels::new();
    let (mut dev, mut servo, mut link) = rig(&mut ch, ServoConfig::default());
    link.send(&HostMsg::Hello {
        protocol_version: PROTOCOL_VERSION,
    });
    link.send(&HostMsg::Hello {
        protocol_version: 9,
    });
    link.send(&HostMsg::SetConfig(ServoConfig {
        coarsen_shift: 40,
        ..ServoConfig::default()
    }));
    link.send(&HostMsg::GetConfig);
    for t in 0..10 {
        dev.poll(t, &mut link);
        servo.tick(t, &mut SampledCount(0), &mut HeldCode(0));
    }
    let f = link.frames();
    assert_eq!(f.len(), 4);
    assert!(
        matches!(&f[0], DeviceMsg::HelloReply(i) if i.protocol_version == PROTOCOL_VERSION && i.board == "generic")
    );
    assert_eq!(
        f[1],
        DeviceMsg::Error {
            code: ErrorCode::VersionMismatch,
            detail: ErrorDetail::Version {
                got: 9,
                expected: PROTOCOL_VERSION
            }
        }
    );
    assert_eq!(
        f[2],
        DeviceMsg::Error {
            code: ErrorCode::InvalidConfig,
            detail: ErrorDetail::Field {
                field: ConfigField::CoarsenShift,
                min: 0.0,
                max: 16.0
            }
        }
    );
    assert_eq!(f[3], DeviceMsg::Config(ServoConfig::default()));
}

/// Requests beyond the servo's command queue are answered `QueueFull` (a code of its own,
/// no text), and accepted again once the servo has taken the queued commands.
#[test]
fn a_full_command_queue_answers_queue_full_by_its_code() {
    let mut ch = Channels::new();
    let (mut dev, mut servo, mut link) = rig(&mut ch, ServoConfig::default());
    let sent = 3 * crate::channels::COMMAND_QUEUE;
    for _ in 0..sent {
        link.send(&HostMsg::ClearFaults);
    }
    for t in 0..(4 * sent as u32) {
        dev.poll(t, &mut link);
    }
    let f = link.frames();
    assert_eq!(f.len(), sent);
    let acked = f
        .iter()
        .filter(|m| **m == DeviceMsg::Ack(Request::ClearFaults))
        .count();
    let full = DeviceMsg::Error {
        code: ErrorCode::QueueFull,
        detail: ErrorDetail::None,
    };
    assert!(
        (1..=crate::channels::COMMAND_QUEUE).contains(&acked),
        "{f:?}"
    );
    assert!(f[acked..].iter().all(|m| *m == full), "{f:?}");
    // The servo takes the queued commands; the next request is accepted.
    for t in 0..(2 * sent as u32) {
        servo.tick(t, &mut SampledCount(0), &mut HeldCode(0));
    }
    link.send(&HostMsg::ClearFaults);
    for t in 0..8 {
        dev.poll(t, &mut link);
    }
    assert_eq!(link.frames(), [DeviceMsg::Ack(Request::ClearFaults)]);
}

/// `PrepareTest` with a bad rule or config is refused naming the field and its range and
/// changes nothing; a prepared release runs with its config while `GetConfig` shows the
/// active one, ends settled, and is used once.
#[test]
fn a_prepared_test_is_checked_runs_its_config_and_is_used_once() {
    let mut ch = Channels::new();
    let active = ServoConfig {
        stiffness: 0.0,
        heartbeat_timeout_ms: 0,
        ..ServoConfig::default()
    };
    let wall = ServoConfig {
        stiffness: 100.0,
        damping: 0.1,
        ..active
    };
    let (mut dev, mut servo, mut link) = rig(&mut ch, active);
    let mut run = |link: &mut Link, dev: &mut Device<'_, MemStorage>, ticks: u32| {
        for t in 0..ticks {
            dev.poll(t, link);
            servo.tick(t, &mut SampledCount(0), &mut HeldCode(0));
        }
        link.frames()
            .into_iter()
            .filter(|m| !matches!(m, DeviceMsg::Telemetry(_)))
            .collect::<Vec<_>>()
    };
    let prepare = |config, decay_base_ticks| HostMsg::PrepareTest {
        config,
        min_run_ticks: 50,
        within_one_count: false,
        decay_base_ticks,
    };
    link.send(&prepare(wall, MAX_EXPERIMENT_TICKS + 1));
    link.send(&prepare(
        ServoConfig {
            coarsen_shift: 40,
            ..wall
        },
        0,
    ));
    // Nothing prepared: the active K = 0 wall cannot be tested.
    link.send(&HostMsg::Release {
        deflection_ticks: 0,
        ticks: 5000,
    });
    let f = run(&mut link, &mut dev, 40);
    let field = |code, field, min, max| DeviceMsg::Error {
        code,
        detail: ErrorDetail::Field { field, min, max },
    };
    assert_eq!(
        f[..2],
        [
            field(ErrorCode::InvalidArgument, ConfigField::Argument, 0.0, 1e7),
            field(
                ErrorCode::InvalidConfig,
                ConfigField::CoarsenShift,
                0.0,
                16.0
            ),
        ]
    );
    assert!(
        matches!(
            &f[2],
            DeviceMsg::Error {
                code: ErrorCode::InvalidArgument,
                detail: ErrorDetail::Field {
                    field: ConfigField::Stiffness,
                    ..
                }
            }
        ),
        "{f:?}"
    );
    link.send(&prepare(wall, 5000));
    link.send(&HostMsg::Release {
        deflection_ticks: 0,
        ticks: 5000,
    });
    link.send(&HostMsg::GetConfig);
    // Held at count 0 (its target) for the hold's settling time, then 50 ticks at rest.
    let f = run(&mut link, &mut dev, 400);
    assert!(f.contains(&DeviceMsg::Config(active)), "{f:?}");
    assert!(
        f.contains(&DeviceMsg::ExperimentDone {
            kind: stiffwall_proto::ExperimentKind::Release,
            completed: true,
            faults: 0
        }),
        "{f:?}"
    );
    // Used once: the next release is tested with the active (K = 0) config: refused.
    link.send(&HostMsg::Release {
        deflection_ticks: 0,
        ticks: 5000,
    });
    let f = run(&mut link, &mut dev, 10);
    assert!(
        matches!(
            &f[0],
            DeviceMsg::Error {
                code: ErrorCode::InvalidArgument,
                detail: ErrorDetail::Field {
                    field: ConfigField::Stiffness,
                    ..
                }
            }
        ),
        "{f:?}"
    );
}

#[test]
fn slow_link_keeps_every_reply() {
    let mut ch = Channels::new();
    let (_sp, hp) = ch.split();
    let b = BoardInfo::default();
    let mut dev = Device::new(
        b,
        ConfigStore::new(MemStorage::default()),
        hp,
        ServoConfig::default(),
    );
    let mut link = Link {
        tx_room: Some(0),
        ..Link::default()
    };
    for _ in 0..20 {
        link.send(&HostMsg::GetFaults);
    }
    let mut got = Vec::new();
    for t in 0..2000 {
        link.tx_room = Some(3);
        dev.poll(t, &mut link);
        got.extend(link.frames());
    }
    assert_eq!(got.len(), 20);
    assert!(got.iter().all(|m| matches!(m, DeviceMsg::Faults(_))));
}

/// Replies to the bad frames of a flood: (frames they stand for, reply frames).
fn bad_frames_answered(frames: &[DeviceMsg]) -> (u64, usize) {
    let mut n = 0;
    let mut replies = 0;
    for m in frames {
        if let DeviceMsg::Error { code, detail } = m {
            assert_eq!(*code, ErrorCode::Cobs, "{m:?}");
            replies += 1;
            n += match detail {
                ErrorDetail::Repeated { count } => {
                    assert!(*count >= 2, "{m:?}");
                    u64::from(*count)
                }
                ErrorDetail::None => 1,
                other => panic!("unexpected detail {other:?}"),
            };
        }
    }
    (n, replies)
}

/// Issue 11, item 1: `01 00` (an empty-payload frame) written at 40 bytes per servo tick
/// (40 KB/s at 1 kHz) while streaming one sample per tick over a link taking 200 bytes per
/// tick. Every telemetry sample gets out (no gap, nothing dropped on the device) and every
/// bad frame is answered (the counts of the coalesced error replies add up).
#[test]
fn flood_of_bad_frames_does_not_starve_telemetry() {
    let mut ch = Channels::new();
    let (mut dev, mut servo, mut link) = rig(&mut ch, ServoConfig::default());
    link.send(&HostMsg::StreamStart { decimation: 1 });
    let flood_ticks = 3000u32;
    let per_tick = 20usize;
    let mut frames = Vec::new();
    for t in 0..flood_ticks + 200 {
        if t < flood_ticks {
            for _ in 0..per_tick {
                link.rx.extend([0x01, 0x00]);
            }
        }
        link.tx_room = Some(200);
        dev.poll(t, &mut link);
        servo.tick(t, &mut SampledCount(0), &mut HeldCode(0));
        frames.extend(link.frames());
    }
    assert!(link.rx.is_empty(), "the device kept up with the flood");
    let sent = u64::from(flood_ticks) * per_tick as u64;
    let (answered, replies) = bad_frames_answered(&frames);
    assert_eq!(answered, sent, "every bad frame accounted for");
    assert_eq!(u64::from(dev.stats().frames_bad), sent);
    // Coalesced: at most one reply per poll for the 20 bad frames each tick brings.
    assert!(
        replies <= flood_ticks as usize,
        "coalesced: {replies} replies"
    );
    assert_eq!(dev.dropped(), 0, "no sample dropped on the device");
    let mut next = None;
    let mut samples = 0u32;
    for m in &frames {
        if let DeviceMsg::Telemetry(tb) = m {
            assert_eq!(tb.dropped, 0);
            if let Some(n) = next {
                assert_eq!(tb.seq, n, "consecutive batches");
            }
            next = Some(tb.seq + tb.samples.len() as u32);
            samples += tb.samples.len() as u32;
        }
    }
    // Streaming starts within the first ticks; all but the last batch's worth are out.
    assert!(
        samples + 2 * TELEMETRY_BATCH as u32 + 5 >= flood_ticks + 200,
        "{samples} samples of {}",
        flood_ticks + 200
    );
}

/// A flood of well-formed requests (each answered) still leaves telemetry its share: with
/// [`REPLY_BUDGET`] replies per batch, no sample is dropped while the link has room.
#[test]
fn flood_of_requests_shares_the_link_with_telemetry() {
    let mut ch = Channels::new();
    let (mut dev, mut servo, mut link) = rig(&mut ch, ServoConfig::default());
    link.send(&HostMsg::StreamStart { decimation: 1 });
    let mut acks = 0;
    let mut samples = 0u32;
    for t in 0..3000u32 {
        for _ in 0..4 {
            link.send(&HostMsg::Heartbeat);
        }
        link.tx_room = Some(400);
        dev.poll(t, &mut link);
        servo.tick(t, &mut SampledCount(0), &mut HeldCode(0));
        for m in link.frames() {
            match m {
                DeviceMsg::Ack(Request::Heartbeat) => acks += 1,
                DeviceMsg::Telemetry(tb) => samples += tb.samples.len() as u32,
                _ => {}
            }
        }
    }
    assert_eq!(dev.dropped(), 0, "no sample dropped on the device");
    assert!(
        samples + 2 * TELEMETRY_BATCH as u32 + 5 >= 3000,
        "{samples}"
    );
    assert!(acks > 3000, "replies still flow: {acks}");
}
