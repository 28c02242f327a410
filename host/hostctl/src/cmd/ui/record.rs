//! Recording from the page: the file format and header of `hostctl record`
//! ([`crate::recording::Writer`], [`crate::session::header`]) and its bookkeeping
//! ([`crate::session::Stats`]), fed batch by batch by the device thread.
//!
//! Units: sample numbers, rows. Invariants: every batch is written in order with its gap noted
//! (device-dropped vs link-lost) as `hostctl record` does; the file is flushed at least every
//! [`super::device::FLUSH_PERIOD`]; files are written only inside the record directory.

use anyhow::{bail, Result};
use serde_json::{json, Value};
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::time::Instant;
use stiffwall_client::Stats;
use stiffwall_client::Writer;
use stiffwall_proto::Sample;

/// A recording made from the page.
#[derive(Debug)]
pub struct Recorder {
    /// The file.
    pub path: PathBuf,
    /// Its writer.
    pub w: Writer<BufWriter<std::fs::File>>,
    /// Its bookkeeping (as `hostctl record`).
    pub stats: Stats,
    /// The device's `dropped` counter at the last batch.
    pub last_dropped: Option<u32>,
    /// When it started.
    pub start: Instant,
    /// When it was last flushed.
    pub last_flush: Instant,
}

/// A plain file name ending in `.csv` inside `dir`: pages cannot write elsewhere.
///
/// # Errors
/// The name has a path separator, starts with a dot, or does not end in `.csv`.
pub fn record_path(dir: &Path, file: &str) -> Result<PathBuf> {
    let ok = !file.is_empty()
        && file.len() <= 200
        && !file.starts_with('.')
        && file
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
        && file.ends_with(".csv");
    if !ok {
        bail!(
            "file must be a plain file name ending in .csv (letters, digits, '-', '_', '.'; written in {}), got {file:?}",
            dir.display()
        );
    }
    Ok(dir.join(file))
}

/// Writes one batch and counts its gap like [`crate::session::pump`].
///
/// # Errors
/// Writing failed, or the telemetry went backwards.
pub fn record_batch(
    r: &mut Recorder,
    seq: u32,
    dropped: u32,
    samples: &[Sample],
    bad_frames: u64,
) -> Result<()> {
    let dev = r
        .last_dropped
        .map_or(0, |d| u64::from(dropped.wrapping_sub(d)));
    r.last_dropped = Some(dropped);
    let missing = r.w.batch(seq, samples, dev)?;
    let st = &mut r.stats;
    if missing > 0 {
        let dev = dev.min(missing);
        st.missing += missing;
        st.device_dropped += dev;
        st.link_lost += missing - dev;
        st.gap_events += 1;
    }
    st.first_seq.get_or_insert(seq);
    if !samples.is_empty() {
        st.received += samples.len() as u64;
        st.last_seq = Some(seq.wrapping_add(samples.len() as u32 - 1));
    }
    st.bad_frames = bad_frames;
    st.wall_s = r.start.elapsed().as_secs_f64();
    Ok(())
}

/// Writes the `# end:` note and closes the file.
///
/// # Errors
/// Writing failed.
pub fn finish_recording(mut r: Recorder, how: &str) -> Result<Value> {
    r.stats.wall_s = r.start.elapsed().as_secs_f64();
    r.w.note(&format!("end: {}; {how}", r.stats.summary()))?;
    let rows = r.w.rows();
    r.w.finish()?;
    Ok(json!({"file": r.path.display().to_string(), "rows": rows, "stats": r.stats}))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn record_paths_stay_in_the_directory() {
        let d = Path::new("/tmp/rec");
        assert_eq!(record_path(d, "run-1.csv").unwrap(), d.join("run-1.csv"));
        for bad in [
            "../x.csv",
            "a/b.csv",
            ".hidden.csv",
            "x.txt",
            "",
            "/etc/x.csv",
        ] {
            let e = record_path(d, bad).unwrap_err().to_string();
            assert!(e.contains("plain file name ending in .csv"), "{bad}: {e}");
        }
    }
}
