//! SIL over the protocol: a host client talks to the firmware's `Device` through an in-memory
//! byte pipe while the servo drives the simulated plant every tick.

use proptest::prelude::*;
use stiffwall_firmware::{Channels, Device, MemStorage, Servo};
use stiffwall_proto::{
    encode, fault, flags, DeviceMsg, ErrorCode, ExciteProfile, ExperimentKind, HostMsg, Request,
    ServoConfig, TelemetryBatch, MAX_FRAME, PROTOCOL_VERSION, TABLE_CHUNK,
};
use stiffwall_tests::{board, config, device, tick, DeviceEnd, Host, Pipe, Point, SimPlant};

const A: Point = Point {
    mu: 100.0,
    beta: 1.0,
    sigma: 1.0,
};

struct Sil<'a> {
    servo: Servo<'a>,
    dev: Device<'a, MemStorage>,
    plant: SimPlant,
    pipe: Pipe,
    host: Host,
    now: u32,
    /// Telemetry batches received.
    batches: Vec<TelemetryBatch>,
    /// Other messages received.
    other: Vec<DeviceMsg>,
    /// Device bytes per tick (None = unlimited).
    budget: Option<usize>,
}

impl<'a> Sil<'a> {
    fn new(ch: &'a mut Channels, cfg: ServoConfig) -> Self {
        let (sp, hp) = ch.split();
        let dev = device(hp, cfg);
        let servo = Servo::new(board(), dev.config(), sp);
        Self {
            servo,
            dev,
            plant: A.sim_plant(),
            pipe: Pipe::default(),
            host: Host::default(),
            now: 0,
            batches: Vec::new(),
            other: Vec::new(),
            budget: None,
        }
    }

    fn servo_only(&mut self) {
        tick(&mut self.servo, &mut self.plant, self.now);
        self.now = self.now.wrapping_add(1);
    }

    fn step(&mut self) {
        self.servo_only();
        self.pipe.device_tx_budget = self.budget;
        self.dev.poll(self.now, &mut DeviceEnd(&mut self.pipe));
        for m in self.host.receive(&mut self.pipe) {
            match m.expect("device frames decode") {
                DeviceMsg::Telemetry(b) => self.batches.push(b),
                other => self.other.push(other),
            }
        }
    }

    /// Sends `msg` and runs until one non-telemetry reply arrives.
    fn request(&mut self, msg: &HostMsg) -> DeviceMsg {
        let before = self.other.len();
        self.host.send(&mut self.pipe, msg);
        for _ in 0..1000 {
            self.step();
            if self.other.len() > before {
                return self.other.remove(before);
            }
        }
        panic!("no reply to {msg:?}");
    }

    fn send_raw(&mut self, bytes: &[u8]) {
        self.pipe.to_device.extend(bytes);
    }

    fn run(&mut self, ticks: u32) {
        for _ in 0..ticks {
            self.step();
        }
    }

    fn get_config(&mut self) -> ServoConfig {
        match self.request(&HostMsg::GetConfig) {
            DeviceMsg::Config(c) => c,
            m => panic!("{m:?}"),
        }
    }
}

fn frame(m: &HostMsg) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    encode(m, &mut buf).unwrap().to_vec()
}

/// Frames a reply answers: a coalesced error (`ErrorDetail::Repeated { count }`, issue 11)
/// answers `count` consecutive bad frames, any other reply one.
fn frames_answered(m: &DeviceMsg) -> usize {
    match m {
        DeviceMsg::Error {
            detail: stiffwall_proto::ErrorDetail::Repeated { count },
            ..
        } => *count as usize,
        _ => 1,
    }
}

fn code_of(m: &DeviceMsg) -> Option<ErrorCode> {
    match m {
        DeviceMsg::Error { code, .. } => Some(*code),
        _ => None,
    }
}

#[test]
fn every_request_round_trips_through_the_handler() {
    let mut ch = Channels::new();
    let mut s = Sil::new(&mut ch, config(true));
    match s.request(&HostMsg::Hello {
        protocol_version: PROTOCOL_VERSION,
    }) {
        DeviceMsg::HelloReply(i) => {
            assert_eq!(
                (i.board.as_str(), i.servo_rate_hz, i.encoder_bits),
                ("sil", 1000, 16)
            );
        }
        m => panic!("{m:?}"),
    }
    assert_eq!(s.get_config(), config(true));
    let new = ServoConfig {
        damping: 0.25,
        extra_delay_ticks: 1,
        ..config(true)
    };
    assert_eq!(
        s.request(&HostMsg::SetConfig(new)),
        DeviceMsg::Ack(Request::SetConfig)
    );
    assert_eq!(s.get_config(), new);
    assert_eq!(
        s.request(&HostMsg::SaveConfig),
        DeviceMsg::Ack(Request::SaveConfig)
    );
    assert_eq!(s.dev.store_mut().load(), Some(new));
    assert_eq!(
        s.request(&HostMsg::LoadDefaults),
        DeviceMsg::Config(config(true))
    );
    assert_eq!(s.get_config(), config(true));
    assert_eq!(
        s.request(&HostMsg::StreamStart { decimation: 10 }),
        DeviceMsg::Ack(Request::StreamStart)
    );
    s.run(200);
    assert!(!s.batches.is_empty());
    assert_eq!(
        s.request(&HostMsg::StreamStop),
        DeviceMsg::Ack(Request::StreamStop)
    );
    let values = (0..TABLE_CHUNK as i16).map(|i| i * 10).collect();
    assert_eq!(
        s.request(&HostMsg::TableChunk { offset: 0, values }),
        DeviceMsg::Ack(Request::TableChunk)
    );
    assert_eq!(
        s.request(&HostMsg::Heartbeat),
        DeviceMsg::Ack(Request::Heartbeat)
    );
    let ex = HostMsg::Excite {
        profile: ExciteProfile::Table {
            len: 32,
            hold_ticks: 2,
        },
        ticks: 200,
    };
    assert_eq!(s.request(&ex), DeviceMsg::Ack(Request::Excite));
    s.run(300);
    assert!(s.other.contains(&DeviceMsg::ExperimentDone {
        kind: ExperimentKind::Excite,
        completed: true,
        faults: 0
    }));
    s.other.clear();
    let rel = HostMsg::Release {
        deflection_ticks: 5,
        ticks: 100,
    };
    assert_eq!(s.request(&rel), DeviceMsg::Ack(Request::Release));
    assert_eq!(s.request(&HostMsg::Stop), DeviceMsg::Ack(Request::Stop));
    s.run(5);
    assert!(s.other.contains(&DeviceMsg::ExperimentDone {
        kind: ExperimentKind::Release,
        completed: false,
        faults: 0
    }));
    match s.request(&HostMsg::GetFaults) {
        DeviceMsg::Faults(f) => assert_eq!((f.latched, f.safe_mode), (0, false)),
        m => panic!("{m:?}"),
    }
    assert_eq!(
        s.request(&HostMsg::ClearFaults),
        DeviceMsg::Ack(Request::ClearFaults)
    );
}

#[test]
fn refused_set_config_names_the_field_and_changes_nothing() {
    let mut ch = Channels::new();
    let mut s = Sil::new(&mut ch, config(true));
    let before = s.get_config();
    let bad = ServoConfig {
        stiffness: 1e12,
        damping: 1.0,
        ..before
    };
    match s.request(&HostMsg::SetConfig(bad)) {
        DeviceMsg::Error {
            code: ErrorCode::InvalidConfig,
            detail: stiffwall_proto::ErrorDetail::Field { field, min, max },
        } => {
            assert_eq!(field, stiffwall_proto::ConfigField::Stiffness);
            assert_eq!(min, 0.0);
            assert!(max > 1e4 && max < 1e12);
        }
        m => panic!("{m:?}"),
    }
    assert_eq!(s.get_config(), before);
}

#[test]
fn each_framing_failure_gets_its_own_error_and_the_servo_keeps_running() {
    let mut ch = Channels::new();
    let mut s = Sil::new(&mut ch, config(true));
    let good = frame(&HostMsg::Heartbeat);
    let mut bad_crc = good.clone();
    let l = bad_crc.len();
    bad_crc[l - 2] ^= 0x01;
    let mut cases: Vec<(Vec<u8>, ErrorCode)> = vec![(bad_crc, ErrorCode::Crc)];
    let mut oversize = vec![0x55u8; MAX_FRAME + 5];
    oversize.push(0);
    cases.push((oversize, ErrorCode::Oversize));
    cases.push((vec![0x05, 0x01, 0x00], ErrorCode::Cobs));
    // Hand-built payloads with a valid CRC: wrong version, unknown tag, truncated body.
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);
    for (payload, code) in [
        (vec![PROTOCOL_VERSION + 1, 10], ErrorCode::VersionMismatch),
        (vec![PROTOCOL_VERSION, 77], ErrorCode::UnknownTag),
        (vec![PROTOCOL_VERSION, 5], ErrorCode::Deserialize),
        (vec![PROTOCOL_VERSION, 10, 0xff], ErrorCode::Deserialize),
    ] {
        let mut p = payload.clone();
        p.extend_from_slice(&crc.checksum(&payload).to_le_bytes());
        let mut enc = vec![0u8; 64];
        let n = cobs::encode(&p, &mut enc);
        enc.truncate(n);
        enc.push(0);
        cases.push((enc, code));
    }
    let ticks_before = s.now;
    for (bytes, code) in &cases {
        s.send_raw(bytes);
        s.run(20);
        let got: Vec<_> = s.other.drain(..).collect();
        assert_eq!(got.len(), 1, "one reply per frame: {got:?}");
        assert_eq!(code_of(&got[0]), Some(*code), "{got:?}");
    }
    assert_eq!(s.now - ticks_before, 20 * cases.len() as u32);
    assert_eq!(
        s.request(&HostMsg::Heartbeat),
        DeviceMsg::Ack(Request::Heartbeat)
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn garbage_into_the_handler_never_panics_or_changes_config(
        junk in proptest::collection::vec(any::<u8>(), 0..2500),
        which in 0usize..4,
        cut in any::<prop::sample::Index>(),
        flip in any::<prop::sample::Index>(),
        bit in 0u8..8,
    ) {
        let mut ch = Channels::new();
        let mut s = Sil::new(&mut ch, config(true));
        let before = s.get_config();
        // A SetConfig that would change things, damaged in one of four ways.
        let f = frame(&HostMsg::SetConfig(ServoConfig { stiffness: 10.0, ..before }));
        let bytes = match which {
            0 => { let mut j = junk.clone(); j.push(0); j }
            1 => { let mut t = f[..cut.index(f.len() - 1)].to_vec(); t.push(0); t }
            2 => { let mut t = f.clone(); let i = flip.index(f.len() - 1); t[i] ^= 1 << bit; t }
            _ => { let mut t = vec![1u8; MAX_FRAME]; t.extend_from_slice(&f); t }
        };
        let frames = bytes.split(|&b| b == 0).filter(|p| !p.is_empty()).count()
            - usize::from(bytes.last() != Some(&0));
        s.send_raw(&bytes);
        s.run(50);
        let replies: Vec<_> = s.other.drain(..).collect();
        let answered: usize = replies.iter().map(frames_answered).sum();
        prop_assert_eq!(answered, frames.max(usize::from(which == 3)), "{:?}", replies);
        for r in &replies {
            if which != 0 {
                prop_assert!(code_of(r).is_some(), "damaged frame accepted: {:?}", r);
            }
        }
        if which == 3 {
            prop_assert_eq!(code_of(&replies[0]), Some(ErrorCode::Oversize));
        }
        if which != 0 {
            prop_assert_eq!(s.get_config(), before);
        }
        // Still answers.
        prop_assert_eq!(s.request(&HostMsg::Heartbeat), DeviceMsg::Ack(Request::Heartbeat));
    }
}

fn check_sequence(batches: &[TelemetryBatch]) -> (u64, u32) {
    let mut received = 0u64;
    for w in batches.windows(2) {
        let end = w[0].seq + w[0].samples.len() as u32;
        assert_eq!(
            w[1].seq - end,
            w[1].dropped - w[0].dropped,
            "gap must equal the drop count"
        );
        for s in w[0].samples.windows(2) {
            assert_eq!(
                s[1].tick,
                s[0].tick + 1,
                "samples within a batch are consecutive"
            );
        }
    }
    for b in batches {
        received += b.samples.len() as u64;
    }
    let last = batches.last().unwrap();
    assert_eq!(
        u64::from(last.seq) + last.samples.len() as u64,
        received + u64::from(last.dropped)
    );
    (received, last.dropped)
}

#[test]
fn telemetry_is_gap_free_when_the_link_keeps_up() {
    let mut ch = Channels::new();
    let mut s = Sil::new(&mut ch, config(true));
    s.request(&HostMsg::StreamStart { decimation: 1 });
    s.run(10_000);
    let (received, dropped) = check_sequence(&s.batches);
    assert_eq!(dropped, 0);
    assert_eq!(s.batches[0].dropped, 0);
    eprintln!(
        "telemetry at rest: {received} samples in {} batches, {:.1} bytes/sample on the wire",
        s.batches.len(),
        s.pipe.bytes_to_host as f64 / received as f64
    );
    assert!(received >= 9_950, "received {received}");
    for w in s.batches.windows(2) {
        assert_eq!(w[1].seq, w[0].seq + w[0].samples.len() as u32, "no gaps");
    }
}

#[test]
fn telemetry_wire_cost_while_moving() {
    let mut ch = Channels::new();
    let cfg = ServoConfig {
        heartbeat_timeout_ms: 0,
        ..config(true)
    };
    let mut s = Sil::new(&mut ch, cfg);
    let ex = HostMsg::Excite {
        profile: ExciteProfile::Chirp {
            amplitude: 3000,
            f0_hz: 1.0,
            f1_hz: 20.0,
        },
        ticks: 10_000,
    };
    assert_eq!(s.request(&ex), DeviceMsg::Ack(Request::Excite));
    let b0 = s.pipe.bytes_to_host;
    s.run(10_000);
    let (received, dropped) = check_sequence(&s.batches);
    assert_eq!(dropped, 0);
    let per = (s.pipe.bytes_to_host - b0) as f64 / received as f64;
    eprintln!("telemetry while moving: {received} samples, {per:.1} bytes/sample; 921600 baud carries {:.0} samples/s", 92160.0 / per);
    assert!(per < 16.0, "{per} bytes per sample");
}

#[test]
fn telemetry_drops_are_counted_exactly_when_the_queue_overflows() {
    let mut ch = Channels::new();
    let mut s = Sil::new(&mut ch, config(true));
    s.request(&HostMsg::StreamStart { decimation: 1 });
    s.run(100);
    // The main loop stalls for 1000 ticks: the 255-sample queue overflows.
    for _ in 0..1000 {
        s.servo_only();
    }
    s.run(200);
    // Then a link too slow for the stream (4 bytes per tick vs ≈ 8 needed at rest).
    s.budget = Some(4);
    s.run(3000);
    s.budget = None;
    s.request(&HostMsg::StreamStop);
    s.run(100);
    let (received, dropped) = check_sequence(&s.batches);
    assert!(
        dropped >= 745 + 500,
        "the stall's overflow and the slow link's: {dropped}"
    );
    let produced =
        u64::from(s.batches.last().unwrap().seq) + s.batches.last().unwrap().samples.len() as u64;
    assert_eq!(received + u64::from(dropped), produced);
    assert_eq!(dropped, s.dev.dropped());
    eprintln!(
        "overflow: received {received}, dropped {dropped}, produced {produced}, batches {}",
        s.batches.len()
    );
}

#[test]
fn release_test_over_the_protocol_settles_in_region_a() {
    let mut ch = Channels::new();
    let mut s = Sil::new(&mut ch, config(true));
    assert_eq!(
        s.request(&HostMsg::Release {
            deflection_ticks: 20,
            ticks: 3000
        }),
        DeviceMsg::Ack(Request::Release)
    );
    let mut done = None;
    for t in 0..6000 {
        if t % 100 == 0 {
            s.host.send(&mut s.pipe, &HostMsg::Heartbeat);
        }
        s.step();
        if let Some(d) = s
            .other
            .iter()
            .find(|m| matches!(m, DeviceMsg::ExperimentDone { .. }))
        {
            done = Some(d.clone());
            break;
        }
    }
    assert_eq!(
        done,
        Some(DeviceMsg::ExperimentDone {
            kind: ExperimentKind::Release,
            completed: true,
            faults: 0
        })
    );
    let samples: Vec<_> = s
        .batches
        .iter()
        .flat_map(|b| b.samples.iter().copied())
        .collect();
    let held: Vec<_> = samples
        .iter()
        .filter(|x| x.flags & flags::HOLD != 0)
        .collect();
    let released: Vec<_> = samples
        .iter()
        .filter(|x| x.flags & flags::RELEASED != 0)
        .collect();
    assert_eq!(released.len(), 3000, "every released tick streamed");
    let at_release = held.last().unwrap().count;
    assert!(
        (19..=21).contains(&at_release),
        "held at the deflection: {at_release}"
    );
    let tail = &released[2500..];
    assert!(
        tail.iter()
            .all(|x| x.count == tail[0].count && (-1..=0).contains(&x.count)),
        "settled at the wall"
    );
    check_sequence(&s.batches);
}

#[test]
fn heartbeat_loss_during_an_experiment_drops_to_safe_mode() {
    let mut ch = Channels::new();
    let cfg = ServoConfig {
        heartbeat_timeout_ms: 100,
        ..config(true)
    };
    let mut s = Sil::new(&mut ch, cfg);
    let ex = HostMsg::Excite {
        profile: ExciteProfile::Steps {
            low: -200,
            high: 200,
            half_period_ticks: 50,
        },
        ticks: 5000,
    };
    assert_eq!(s.request(&ex), DeviceMsg::Ack(Request::Excite));
    s.run(150);
    assert!(s.other.contains(&DeviceMsg::ExperimentDone {
        kind: ExperimentKind::Excite,
        completed: false,
        faults: fault::HEARTBEAT
    }));
    match s.request(&HostMsg::GetFaults) {
        DeviceMsg::Faults(f) => assert_eq!((f.latched, f.safe_mode), (fault::HEARTBEAT, true)),
        m => panic!("{m:?}"),
    }
    // Refused while latched, accepted after clearing.
    assert_eq!(code_of(&s.request(&ex)), Some(ErrorCode::Busy));
    assert_eq!(
        s.request(&HostMsg::ClearFaults),
        DeviceMsg::Ack(Request::ClearFaults)
    );
    s.run(2);
    match s.request(&HostMsg::GetFaults) {
        DeviceMsg::Faults(f) => assert_eq!(f.latched, 0),
        m => panic!("{m:?}"),
    }
}
