//! Shared by the flood tests of the virtual device (`link_flood.rs`) and of the QEMU image
//! (`qemu.rs`): a second writer floods a device's serial line with short bad frames (`01 00`)
//! while the host records from it.
//!
//! Units: rates in bytes per second, durations in seconds; sample counts are rows of the
//! recording plus the samples its `# gap:` notes account for.

#![allow(dead_code)] // each test crate that includes this module uses part of it

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use stiffwall_client::Client;
use stiffwall_client::{End, Plan};
use stiffwall_host::cmd::replay::trailing_gap;

/// A second, non-blocking writer on the host side of a pty the client already holds (as
/// another program on the same serial line would be). The client's port is opened exclusive
/// (TIOCEXCL), which a process with CAP_SYS_ADMIN (these tests' usual CI user, root) may
/// still open; that is what this needs.
/// `nonblocking`: writes return `WouldBlock` instead of waiting when the pty is full;
/// blocking writes go in whole (one write() call holds the tty's write lock throughout).
pub fn second_writer(path: &str, nonblocking: bool) -> std::fs::File {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new()
        .write(true)
        .custom_flags(if nonblocking { 0o4000 } else { 0 }) // O_NONBLOCK
        .open(path)
        .unwrap_or_else(|e| panic!("opening a second writer on {path}: {e}"))
}

/// Samples kept, samples planned, samples written as gaps, and bad frames the host saw.
pub struct FloodRun {
    pub rows: u64,
    pub planned: u64,
    pub gap_samples: u64,
    pub end: End,
    pub wall_s: f64,
    pub flood_bytes: u64,
}

/// Records `seconds` from the connected device `c` while another writer floods its serial
/// line `path` with `01 00` at `rate_bytes_s`.
pub fn record_under_flood(c: &mut Client, path: &str, seconds: f64, rate_bytes_s: f64) -> FloodRun {
    let cfg = c.get_config().unwrap();
    let rate_hz = cfg.servo_rate_hz;
    let mut flood = second_writer(path, false);
    let stop = Arc::new(AtomicBool::new(false));
    let stop2 = Arc::clone(&stop);
    let flooder = std::thread::spawn(move || {
        // Chunks of whole `01 00` pairs every 5 ms; each write() ends on a delimiter, so the
        // host's own frames (single writes) are never cut.
        let start = Instant::now();
        let mut sent = 0u64;
        let pairs = [0x01u8, 0x00].repeat(1024);
        while !stop2.load(Ordering::Relaxed) {
            let due = (start.elapsed().as_secs_f64() * rate_bytes_s) as u64;
            let n = (due.saturating_sub(sent) as usize & !1).min(pairs.len());
            if n > 0 && flood.write_all(&pairs[..n]).is_ok() {
                sent += n as u64;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        sent
    });
    // Let the flood start before the stream does.
    std::thread::sleep(Duration::from_millis(100));
    let plan = Plan::new(1, Some(seconds), rate_hz).unwrap();
    let header = stiffwall_client::header_for_target(c, cfg, 1, "device".into(), None);
    let mut out = Vec::new();
    let outcome = stiffwall_client::record(c, &plan, &header, &mut out, |_| {}).unwrap();
    stop.store(true, Ordering::Relaxed);
    let flood_bytes = flooder.join().unwrap();
    let text = String::from_utf8(out).unwrap();
    let rec = stiffwall_client::parse_recording(&text).expect("the recording parses");
    let rows = rec.rows.len() as u64;
    assert_eq!(rows, outcome.rows);
    FloodRun {
        rows,
        planned: plan.samples.unwrap(),
        gap_samples: rec.missing() + trailing_gap(&text),
        end: outcome.end,
        wall_s: outcome.stats.wall_s,
        flood_bytes,
    }
}

/// The recording completed, every lost sample is written as a gap, and at least `min_kept`
/// of the planned samples arrived.
pub fn check(run: &FloodRun, min_kept: f64, what: &str) {
    let kept = run.rows as f64 / run.planned as f64;
    eprintln!(
        "{what}: {} of {} samples kept ({:.2} %), {} written as gaps, {:.1} s wall, {} flood bytes ({:.0} B/s)",
        run.rows,
        run.planned,
        100.0 * kept,
        run.gap_samples,
        run.wall_s,
        run.flood_bytes,
        run.flood_bytes as f64 / run.wall_s.max(1e-3)
    );
    assert_eq!(run.end, End::Complete, "{what}");
    assert_eq!(
        run.rows + run.gap_samples,
        run.planned,
        "{what}: every lost sample written as a gap"
    );
    assert!(kept >= min_kept, "{what}: kept {:.2} %", 100.0 * kept);
}
