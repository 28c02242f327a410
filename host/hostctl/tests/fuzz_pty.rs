//! End-to-end fuzz harness (issue 11): the virtual device (the real firmware core behind a
//! pty) records while a second writer on its pty floods it with garbage frames — tiny
//! (`01 00`, `00`), oversize (2000 bytes before the delimiter), random bytes, and valid frames
//! with random bit flips, insertions and deletions (any piece that would still decode is left
//! out, so every frame sent is invalid). What must hold, per recording:
//! - the recording completes and, in `--fast`, loses no sample (rows = planned, no gap);
//! - the device still answers and its config is the one it had before (nothing invalid was
//!   accepted as a command);
//! - no panic and no hang (each recording is bounded by the session's own watchdogs).
//!
//! Budget: `STIFFWALL_FUZZ_PTY_FRAMES` garbage frames (default 20 000: about 2–5 s here);
//! `cargo xtask fuzz --frames N` runs N/10. Seeded by `STIFFWALL_FUZZ_SEED` (default 1).

use proptest::prelude::Rng;
use proptest::test_runner::{RngAlgorithm, TestRng};
use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;
use stiffwall_client::Client;
use stiffwall_client::{spawn_virtual_device as spawn, Pace, VirtualSpec as Spec};
use stiffwall_client::{End, Plan};
use stiffwall_proto::frame::decode_frame;
use stiffwall_proto::{encode, HostMsg, ServoConfig, MAX_FRAME};

#[path = "support/flood.rs"]
mod flood;

fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// True when some 0-delimited piece of `bytes` decodes as a host message.
fn any_piece_valid(bytes: &[u8]) -> bool {
    bytes.split(|&b| b == 0).any(|piece| {
        let mut f = piece.to_vec();
        f.push(0);
        piece.len() > 1 && decode_frame::<HostMsg>(&mut f).is_ok()
    })
}

/// One garbage frame (ends with the delimiter; invalid by construction).
fn garbage(r: &mut TestRng, valid: &[Vec<u8>]) -> (usize, Vec<u8>) {
    let kind = (r.next_u32() % 4) as usize;
    let mut f: Vec<u8> = match kind {
        0 => {
            if r.next_u32().is_multiple_of(2) {
                vec![0x01, 0x00]
            } else {
                vec![0x00]
            }
        }
        1 => (0..2000).map(|_| (r.next_u32() % 255 + 1) as u8).collect(),
        2 => {
            let n = 1 + (r.next_u32() % 300) as usize;
            (0..n).map(|_| (r.next_u32() % 255 + 1) as u8).collect()
        }
        _ => {
            let mut f = valid[(r.next_u32() as usize) % valid.len()].clone();
            f.pop();
            for _ in 0..1 + r.next_u32() % 4 {
                let i = (r.next_u32() as usize) % f.len().max(1);
                match r.next_u32() % 3 {
                    0 if !f.is_empty() => f[i] ^= 1 << (r.next_u32() % 8),
                    1 => f.insert(i.min(f.len()), r.next_u32() as u8),
                    _ if f.len() > 1 => {
                        f.remove(i.min(f.len() - 1));
                    }
                    _ => {}
                }
            }
            f
        }
    };
    f.push(0);
    (kind, f)
}

fn maxon() -> Spec {
    Spec {
        plant: stiffwall_core::devices::find("maxon-re35").unwrap().params,
        counts_per_rev: 8192,
        pace: Pace::Fast,
        initial_position: 0.0,
        output_range: None,
        scene: None,
        travel: None,
        trace: None,
    }
}

#[test]
fn garbage_through_the_pty_while_recording_changes_nothing_and_loses_nothing() {
    let budget = env_u64("STIFFWALL_FUZZ_PTY_FRAMES", 20_000);
    let seed = env_u64("STIFFWALL_FUZZ_SEED", 1);
    let mut r = TestRng::from_seed(
        RngAlgorithm::ChaCha,
        &[seed.to_le_bytes(), [7; 8], [9; 8], [3; 8]].concat(),
    );
    let mut out = [0u8; MAX_FRAME];
    let valid: Vec<Vec<u8>> = [
        HostMsg::GetConfig,
        HostMsg::SetConfig(ServoConfig::default()),
        HostMsg::SaveConfig,
        HostMsg::LoadDefaults,
        HostMsg::StreamStop,
        HostMsg::ClearFaults,
        HostMsg::Release {
            deflection_ticks: 12,
            ticks: 1000,
        },
    ]
    .iter()
    .map(|m| encode(m, &mut out).unwrap().to_vec())
    .collect();
    // The frames, generated up front (seeded), in chunks of whole frames.
    let mut chunks: Vec<Vec<u8>> = Vec::new();
    let mut kinds = [0u64; 4];
    let mut left_out = 0u64;
    let mut chunk = Vec::new();
    let mut made = 0u64;
    while made < budget {
        let (kind, f) = garbage(&mut r, &valid);
        if any_piece_valid(&f) {
            left_out += 1;
            continue;
        }
        kinds[kind] += 1;
        made += 1;
        chunk.extend_from_slice(&f);
        if chunk.len() > 4096 {
            chunks.push(std::mem::take(&mut chunk));
        }
    }
    chunks.push(chunk);

    let (vd, port) = spawn(maxon()).expect("spawn virtual device");
    let path = vd.pty.clone();
    let mut c = Client::connect(port, Some(Box::new(vd))).expect("handshake");
    let before = c.get_config().unwrap();
    let rate_hz = before.servo_rate_hz;
    let sent = Arc::new(AtomicU64::new(0));
    let done = Arc::new(AtomicBool::new(false));
    let (sent2, done2) = (Arc::clone(&sent), Arc::clone(&done));
    let mut w = flood::second_writer(&path, false);
    let flooder = std::thread::spawn(move || {
        for ch in &chunks {
            if w.write_all(ch).is_err() {
                break;
            }
            sent2.fetch_add(ch.len() as u64, Ordering::Relaxed);
        }
        done2.store(true, Ordering::Relaxed);
    });
    let mut recordings = 0u32;
    let mut rows = 0u64;
    while !done.load(Ordering::Relaxed) || recordings == 0 {
        assert!(
            recordings < 200,
            "the flood did not finish in 200 recordings"
        );
        let plan = Plan::new(1, Some(30.0), rate_hz).unwrap();
        let header = stiffwall_client::header_for_target(&c, before, 1, "device".into(), None);
        let mut text = Vec::new();
        let outcome = stiffwall_client::record(&mut c, &plan, &header, &mut text, |_| {})
            .expect("recording under garbage");
        assert_eq!(outcome.end, End::Complete, "recording {recordings}");
        let rec =
            stiffwall_client::parse_recording(&String::from_utf8(text).unwrap()).expect("parses");
        assert_eq!(
            rec.rows.len() as u64,
            plan.samples.unwrap(),
            "recording {recordings}: --fast lost samples under garbage"
        );
        assert_eq!(rec.missing(), 0);
        rows += rec.rows.len() as u64;
        recordings += 1;
    }
    flooder.join().unwrap();
    std::thread::sleep(Duration::from_millis(100));
    let after = c.get_config().expect("the device still answers");
    assert_eq!(after, before, "garbage changed the config");
    eprintln!(
        "{made} garbage frames ({} tiny, {} oversize, {} random, {} mutated; {left_out} \
         mutations that still decoded left out), {} bytes, during {recordings} recordings \
         ({rows} samples, none lost); config unchanged",
        kinds[0],
        kinds[1],
        kinds[2],
        kinds[3],
        sent.load(Ordering::Relaxed)
    );
}
