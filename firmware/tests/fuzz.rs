//! Fuzz campaign (issue 11): randomized and mutation-based harnesses against the frame
//! decoder and the firmware `Device` + `Servo`, with power cuts during config saves.
//!
//! Units: counts of frames, chunks, ticks and power cuts. Budget: `STIFFWALL_FUZZ_FRAMES`
//! mutated frames (default 20 000); chunks are a tenth of that, power cuts a hundredth;
//! `STIFFWALL_FUZZ_SEED` picks the stream (default 1). `cargo xtask fuzz --frames N` runs this
//! with N and prints the table.
//!
//! Invariants checked (each a counter that must stay 0): a panic fails the test; no frame is
//! accepted unless it is exactly the canonical encoding of the message decoded from it; no
//! output code exceeds the force limit of the configs in effect; every frame the device sends
//! decodes; no telemetry sample is dropped while the link has room; a store cut mid-save
//! loads either the old or the new config, never anything else.

use std::collections::VecDeque;
use stiffwall_firmware::{
    BoardInfo, ByteLink, Channels, ConfigStore, Device, HeldCode, MemStorage, SampledCount, Servo,
};
use stiffwall_proto::frame::decode_frame;
use stiffwall_proto::{
    encode, DeviceMsg, ErrorDetail, ExciteProfile, FrameDecoder, HostMsg, ServoConfig, MAX_FRAME,
    PROTOCOL_VERSION,
};

/// xorshift64*: a small, seedable generator (no dependency; reproducible runs).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
    fn i32(&mut self) -> i32 {
        match self.below(4) {
            0 => [i32::MIN, i32::MAX, 0, -1, 1][self.below(5) as usize],
            1 => self.below(64) as i32 - 32,
            _ => self.next() as i32,
        }
    }
    fn u32(&mut self) -> u32 {
        match self.below(3) {
            0 => [0, 1, u32::MAX, 10_000_000][self.below(4) as usize],
            1 => self.below(5000) as u32,
            _ => self.next() as u32,
        }
    }
    fn f32(&mut self) -> f32 {
        match self.below(4) {
            0 => [0.0, -1.0, f32::NAN, f32::INFINITY, 1e30, f32::MIN_POSITIVE]
                [self.below(6) as usize],
            1 => (self.below(10_000) as f32) / 100.0,
            _ => f32::from_bits(self.next() as u32),
        }
    }
}

fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// A random request, hostile in its values (valid and invalid ranges, edge integers).
fn hostile_msg(r: &mut Rng) -> HostMsg {
    let mut cfg = ServoConfig::default();
    match r.below(14) {
        0 => HostMsg::Hello {
            protocol_version: if r.below(2) == 0 {
                PROTOCOL_VERSION
            } else {
                r.next() as u8
            },
        },
        1 => HostMsg::GetConfig,
        2 => {
            match r.below(6) {
                0 => cfg.stiffness = r.f32(),
                1 => cfg.force_limit = r.f32(),
                2 => cfg.wall_position = r.i32(),
                3 => cfg.damping = r.f32(),
                4 => cfg.servo_rate_hz = r.u32(),
                _ => cfg.extra_delay_ticks = r.next() as _,
            }
            HostMsg::SetConfig(cfg)
        }
        3 => HostMsg::LoadDefaults,
        4 => HostMsg::SaveConfig,
        5 => HostMsg::StreamStart {
            decimation: r.below(4) as u16,
        },
        6 => HostMsg::StreamStop,
        7 => HostMsg::Release {
            deflection_ticks: r.i32(),
            ticks: r.u32(),
        },
        8 => HostMsg::Excite {
            profile: ExciteProfile::Steps {
                low: r.i32(),
                high: r.i32(),
                half_period_ticks: r.u32(),
            },
            ticks: r.u32(),
        },
        9 => HostMsg::Heartbeat,
        10 => HostMsg::GetFaults,
        11 => HostMsg::ClearFaults,
        12 => HostMsg::Stop,
        _ => HostMsg::Excite {
            profile: ExciteProfile::Chirp {
                amplitude: r.i32(),
                f0_hz: r.f32(),
                f1_hz: r.f32(),
            },
            ticks: r.u32(),
        },
    }
}

fn frame_of(m: &HostMsg) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME];
    encode(m, &mut out).unwrap().to_vec()
}

fn mutate(r: &mut Rng, f: &mut Vec<u8>) {
    for _ in 0..=r.below(3) {
        let n = f.len().max(1) as u64;
        match r.below(6) {
            0 => {
                let i = r.below(n) as usize;
                if let Some(b) = f.get_mut(i) {
                    *b ^= 1 << r.below(8);
                }
            }
            1 => {
                let i = r.below(n) as usize;
                if let Some(b) = f.get_mut(i) {
                    *b = r.next() as u8;
                }
            }
            2 => f.insert(r.below(n + 1) as usize % (f.len() + 1), r.next() as u8),
            3 if !f.is_empty() => {
                f.remove(r.below(n) as usize);
            }
            4 => f.truncate(r.below(n + 1) as usize),
            _ => {
                let i = r.below(n) as usize;
                let tail: Vec<u8> = f.iter().skip(i).take(8).copied().collect();
                f.extend(tail);
            }
        }
    }
}

#[derive(Debug, Default)]
struct Counts {
    frames: u64,
    frames_accepted: u64,
    invalid_accepted: u64,
    chunks: u64,
    ticks: u64,
    force_above_limit: u64,
    device_bad_output: u64,
    samples_dropped: u64,
    power_cuts: u64,
    corrupt_config_loaded: u64,
}

/// Mutated frames against `decode_frame` and the streaming decoder.
fn fuzz_decoder(r: &mut Rng, frames: u64, c: &mut Counts) {
    let mut dec = FrameDecoder::new();
    for _ in 0..frames {
        let mut f = frame_of(&hostile_msg(r));
        mutate(r, &mut f);
        c.frames += 1;
        if let Ok(m) = decode_frame::<HostMsg>(&mut f.clone()) {
            c.frames_accepted += 1;
            let again = frame_of(&m);
            let body = f.strip_suffix(&[0]).unwrap_or(&f);
            if again.strip_suffix(&[0]) != Some(body) {
                c.invalid_accepted += 1;
                eprintln!("accepted a non-canonical frame {f:02x?} as {m:?}");
            }
        }
        for &b in &f {
            let _ = dec.feed::<HostMsg>(b);
        }
    }
}

struct Link {
    rx: VecDeque<u8>,
    tx: Vec<u8>,
    room: usize,
}
impl ByteLink for Link {
    fn read(&mut self) -> Option<u8> {
        self.rx.pop_front()
    }
    fn write(&mut self, b: u8) -> bool {
        if self.room == 0 {
            return false;
        }
        self.room -= 1;
        self.tx.push(b);
        true
    }
}

fn limit_codes(b: &BoardInfo, cfg: &ServoConfig) -> i64 {
    let l = (f64::from(cfg.force_limit) / f64::from(b.force_per_code)).round();
    if l.is_finite() {
        (l as i64).clamp(0, i64::from(b.max_code))
    } else {
        i64::from(b.max_code)
    }
}

/// Random chunks (random bytes, hostile requests, mutated frames) into `Device` + `Servo`,
/// with the encoder on a random walk with jumps.
fn fuzz_device(r: &mut Rng, chunks: u64, c: &mut Counts) {
    let b = BoardInfo::default();
    let mut ch = Box::new(Channels::new());
    let (sp, hp) = ch.split();
    let mut dev = Device::new(
        b,
        ConfigStore::new(MemStorage::default()),
        hp,
        ServoConfig::default(),
    );
    let mut servo: Servo<'_> = Servo::new(b, dev.config(), sp);
    let mut link = Link {
        rx: VecDeque::new(),
        tx: Vec::new(),
        room: 0,
    };
    let mut out_dec = FrameDecoder::new();
    let mut recent: VecDeque<i64> = VecDeque::from([limit_codes(&b, dev.config())]);
    let mut pos: u32 = 0;
    let mut tick: u32 = 0;
    let mut dropped_seen = 0u32;
    for _ in 0..chunks {
        c.chunks += 1;
        match r.below(3) {
            0 => {
                for _ in 0..=r.below(64) {
                    link.rx.push_back(r.next() as u8);
                }
            }
            1 => link.rx.extend(frame_of(&hostile_msg(r))),
            _ => {
                let mut f = frame_of(&hostile_msg(r));
                mutate(r, &mut f);
                link.rx.extend(f);
            }
        }
        for _ in 0..=r.below(8) {
            tick = tick.wrapping_add(1);
            link.room = 4096; // a link with room: nothing may be dropped
            dev.poll(tick, &mut link);
            recent.push_back(limit_codes(&b, dev.config()));
            if recent.len() > 20 {
                recent.pop_front();
            }
            pos = match r.below(50) {
                0 => r.next() as u32,
                _ => pos.wrapping_add((r.below(5) as u32).wrapping_sub(2)),
            };
            let mut o = HeldCode(0);
            let code = servo.tick(tick, &mut SampledCount(pos), &mut o);
            c.ticks += 1;
            let allowed = recent.iter().copied().max().unwrap_or(0);
            if i64::from(code).abs() > allowed || i64::from(o.0).abs() > allowed {
                c.force_above_limit += 1;
                eprintln!("code {code} above the limit {allowed} codes at tick {tick}");
            }
        }
        for byte in link.tx.drain(..) {
            match out_dec.feed::<DeviceMsg>(byte) {
                Some(Ok(DeviceMsg::Telemetry(t))) => {
                    dropped_seen = t.dropped;
                }
                Some(Ok(DeviceMsg::Error {
                    detail: ErrorDetail::Repeated { count },
                    ..
                })) if count < 2 => c.device_bad_output += 1,
                Some(Ok(_)) | None => {}
                Some(Err(_)) => c.device_bad_output += 1,
            }
        }
    }
    c.samples_dropped += u64::from(dropped_seen.max(dev.dropped()));
}

/// Saves with the write cut at a random byte; the store must then load the old or the new
/// config, never anything else.
fn fuzz_power_cuts(r: &mut Rng, cuts: u64, c: &mut Counts) {
    let mut store = ConfigStore::new(MemStorage::default());
    let mut current = ServoConfig::default();
    store.save(&current).unwrap();
    for i in 0..cuts {
        let mut next = current;
        next.stiffness = (i % 1000) as f32 / 10.0;
        next.wall_position = r.i32();
        store.storage_mut().interrupt_after = Some(r.below(160) as usize);
        let saved = store.save(&next).is_ok();
        c.power_cuts += 1;
        // A fresh boot reads the storage as the cut left it.
        let mut rebooted = ConfigStore::new(store.storage_mut().clone());
        match rebooted.load() {
            Some(l) if l == next || (l == current && !saved) => {
                if l == next {
                    current = next;
                }
            }
            other => {
                c.corrupt_config_loaded += 1;
                eprintln!("after a cut (saved {saved}) loaded {other:?}");
            }
        }
    }
}

#[test]
fn fuzz_campaign() {
    let frames = env_u64("STIFFWALL_FUZZ_FRAMES", 20_000);
    let seed = env_u64("STIFFWALL_FUZZ_SEED", 1).max(1);
    let mut r = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let mut c = Counts::default();
    fuzz_decoder(&mut r, frames, &mut c);
    fuzz_device(&mut r, (frames / 10).max(1), &mut c);
    fuzz_power_cuts(&mut r, (frames / 100).max(1), &mut c);
    eprintln!("fuzz (seed {seed}): {c:#?}");
    println!("| frames | accepted | invalid accepted | chunks | ticks | force above limit | bad device output | samples dropped | power cuts | corrupt config loaded |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    println!(
        "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
        c.frames,
        c.frames_accepted,
        c.invalid_accepted,
        c.chunks,
        c.ticks,
        c.force_above_limit,
        c.device_bad_output,
        c.samples_dropped,
        c.power_cuts,
        c.corrupt_config_loaded
    );
    assert_eq!(c.invalid_accepted, 0);
    assert_eq!(c.force_above_limit, 0);
    assert_eq!(c.device_bad_output, 0);
    assert_eq!(c.samples_dropped, 0);
    assert_eq!(c.corrupt_config_loaded, 0);
}
