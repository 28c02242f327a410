//! The telemetry recording format written by `hostctl record` and read by `hostctl replay`.
//!
//! A recording is a text file (CSV with `#` comment lines):
//!
//! ```text
//! # stiffwall recording v1
//! # host_time_unix_s: 1764000000.123
//! # target: virtual device (maxon-re35, fast)
//! # virtual_plant: maxon-re35            (only for the virtual device)
//! # firmware: stiffwall-fw 0.1.0 (protocol 1, board virtual)
//! # decimation: 1
//! # device: {...DeviceInfo as JSON...}
//! # config: {...ServoConfig as JSON...}
//! seq,tick,count,force_code,flags,energy
//! 1200,1201,-3,120,0,26
//! # gap: 24 samples missing before seq 1249 (device-dropped 0, link-lost 24)
//! 1249,1250,-2,80,0,10
//! # end: received 2, missing 24 (device-dropped 0, link-lost 24), bad frames 0, complete
//! ```
//!
//! Units: `seq` is the device's sample number, `tick` the servo tick counter, `count` raw
//! encoder counts relative to `config.wall_position`, `force_code` output codes (one code =
//! `device.force_per_code` N or N·m), `flags` the bits of `stiffwall_proto::flags`, `energy`
//! the potential part of H_T (35) in units of K·Δ_eff²/8 (see `stiffwall_proto::Sample`).
//!
//! Invariants: every sample received is written, in order, and every gap in `seq` is written
//! as a `# gap:` comment where it happened (never silently dropped); the reader is strict:
//! `seq` strictly increases, every row has exactly the six columns, every value parses into
//! its wire type, and the header carries `device`, `config` and `decimation`. Any violation is
//! an error naming the line and the column, and nothing is returned.

use std::io::Write;
use std::path::{Path, PathBuf};
use stiffwall_proto::{DeviceInfo, Sample, ServoConfig};

/// Why a recording could not be written or read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RecordingError {
    /// Writing failed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// The header could not be written as JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// The file could not be read.
    #[error("reading recording {}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The text breaks a rule of the format (the message names the line and the column).
    #[error("{0}")]
    Format(String),
    /// [`RecordingError::Format`] of a file.
    #[error("recording {}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// What is wrong in it.
        #[source]
        source: Box<RecordingError>,
    },
}

/// Result of the recording format.
pub type Result<T, E = RecordingError> = std::result::Result<T, E>;

/// Returns a [`RecordingError::Format`] error from the enclosing function.
macro_rules! fail {
    ($($t:tt)*) => {
        return Err(RecordingError::Format(format!($($t)*)))
    };
}

/// A [`RecordingError::Format`] error.
macro_rules! format_err {
    ($($t:tt)*) => {
        RecordingError::Format(format!($($t)*))
    };
}

/// First line of every recording.
pub const MAGIC: &str = "# stiffwall recording v1";
/// The column header line.
pub const COLUMNS: &str = "seq,tick,count,force_code,flags,energy";
const COLUMN_NAMES: [&str; 6] = ["seq", "tick", "count", "force_code", "flags", "energy"];

/// Facts recorded once, before the samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// Host time when recording started, seconds since the Unix epoch.
    pub host_time_unix_s: f64,
    /// Human description of the target (port, QEMU, virtual device).
    pub target: String,
    /// Preset name of the virtual device's plant, when recorded from the virtual device.
    pub virtual_plant: Option<String>,
    /// Servo ticks per sample (≥ 1).
    pub decimation: u16,
    /// The device's handshake answer.
    pub device: DeviceInfo,
    /// The servo configuration active during the recording.
    pub config: ServoConfig,
}

/// One recorded sample with its sample number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Row {
    /// The device's sample number.
    pub seq: u32,
    /// The sample.
    pub sample: Sample,
}

/// A whole recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// The header.
    pub header: Header,
    /// Samples in order of strictly increasing `seq`.
    pub rows: Vec<Row>,
}

impl Recording {
    /// Runs of rows with consecutive `seq` and consecutive `tick` (ticks may only be
    /// consecutive when `decimation` is 1), as index ranges into `rows`.
    #[must_use]
    pub fn segments(&self) -> Vec<std::ops::Range<usize>> {
        let mut out = Vec::new();
        let mut start = 0;
        for i in 1..=self.rows.len() {
            let cut = i == self.rows.len() || {
                let (a, b) = (&self.rows[i - 1], &self.rows[i]);
                b.seq != a.seq.wrapping_add(1)
                    || b.sample.tick
                        != a.sample
                            .tick
                            .wrapping_add(u32::from(self.header.decimation))
            };
            if cut {
                if i > start {
                    out.push(start..i);
                }
                start = i;
            }
        }
        out
    }

    /// Samples missing between rows (sum of the `seq` jumps).
    #[must_use]
    pub fn missing(&self) -> u64 {
        self.rows
            .windows(2)
            .map(|w| u64::from(w[1].seq.wrapping_sub(w[0].seq).saturating_sub(1)))
            .sum()
    }
}

/// Streams a recording to a writer: header first, then rows, gap notes and a trailer.
#[derive(Debug)]
pub struct Writer<W: Write> {
    out: W,
    next_seq: Option<u32>,
    rows: u64,
}

impl<W: Write> Writer<W> {
    /// Writes the header.
    pub fn new(mut out: W, h: &Header) -> Result<Self> {
        writeln!(out, "{MAGIC}")?;
        writeln!(out, "# host_time_unix_s: {:.3}", h.host_time_unix_s)?;
        writeln!(out, "# target: {}", one_line(&h.target))?;
        if let Some(p) = &h.virtual_plant {
            writeln!(out, "# virtual_plant: {}", one_line(p))?;
        }
        writeln!(
            out,
            "# firmware: {} {} (protocol {}, board {})",
            h.device.firmware_name,
            h.device.firmware_version,
            h.device.protocol_version,
            h.device.board
        )?;
        writeln!(out, "# decimation: {}", h.decimation)?;
        writeln!(out, "# device: {}", serde_json::to_string(&h.device)?)?;
        writeln!(out, "# config: {}", serde_json::to_string(&h.config)?)?;
        writeln!(out, "{COLUMNS}")?;
        Ok(Self {
            out,
            next_seq: None,
            rows: 0,
        })
    }

    /// Writes one batch: a `# gap:` note first if `seq` skipped samples. `device_dropped` is
    /// how many of the missing samples the device reports it dropped (the rest were lost on the
    /// link). Returns the number of missing samples before this batch.
    pub fn batch(&mut self, seq: u32, samples: &[Sample], device_dropped: u64) -> Result<u64> {
        let mut missing = 0;
        if let Some(expect) = self.next_seq {
            let gap = seq.wrapping_sub(expect);
            if gap >= u32::MAX / 2 {
                fail!(
                    "telemetry went backwards: got sample {seq} after {}",
                    expect.wrapping_sub(1)
                );
            }
            if gap != 0 {
                missing = u64::from(gap);
                let dev = device_dropped.min(missing);
                writeln!(
                    self.out,
                    "# gap: {missing} samples missing before seq {seq} (device-dropped {dev}, link-lost {})",
                    missing - dev
                )?;
            }
        }
        for (i, s) in samples.iter().enumerate() {
            writeln!(
                self.out,
                "{},{},{},{},{},{}",
                seq.wrapping_add(i as u32),
                s.tick,
                s.count,
                s.force_code,
                s.flags,
                s.energy
            )?;
        }
        self.rows += samples.len() as u64;
        self.next_seq = Some(seq.wrapping_add(samples.len() as u32));
        Ok(missing)
    }

    /// Writes a free comment line (e.g. the end-of-recording summary).
    pub fn note(&mut self, text: &str) -> Result<()> {
        writeln!(self.out, "# {}", one_line(text))?;
        Ok(())
    }

    /// Rows written so far.
    #[must_use]
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Flushes the underlying writer.
    pub fn flush(&mut self) -> Result<()> {
        self.out.flush()?;
        Ok(())
    }

    /// Flushes and returns the underlying writer.
    pub fn finish(mut self) -> Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

fn one_line(s: &str) -> String {
    s.replace(['\n', '\r'], " ")
}

/// Reads and validates a recording file.
pub fn read(path: &Path) -> Result<Recording> {
    let text = std::fs::read_to_string(path).map_err(|source| RecordingError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text).map_err(|e| RecordingError::InFile {
        path: path.to_path_buf(),
        source: Box::new(e),
    })
}

/// Parses and validates a recording (see the module docs for the rules).
pub fn parse(text: &str) -> Result<Recording> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    match lines.next() {
        Some((_, l)) if l.trim_end() == MAGIC => {}
        Some((_, l)) => fail!(
            "line 1: not a stiffwall recording (expected {MAGIC:?}, found {:?})",
            truncate(l)
        ),
        None => fail!("line 1: empty file, not a stiffwall recording"),
    }
    let mut fields = HeaderFields::default();
    let mut saw_columns = false;
    for (ln, line) in lines.by_ref() {
        let line = line.trim_end();
        if let Some(c) = line.strip_prefix('#') {
            if let Some((key, value)) = c.trim_start().split_once(':') {
                fields.read(ln, key.trim(), value.trim())?;
            }
            continue;
        }
        if line == COLUMNS {
            saw_columns = true;
            break;
        }
        fail!(
            "line {ln}: expected the column header {COLUMNS:?}, found {:?}",
            truncate(line)
        );
    }
    if !saw_columns {
        fail!("no column header {COLUMNS:?}: the file ends inside the header");
    }
    let header = fields.finish()?;
    let mut rows: Vec<Row> = Vec::new();
    for (ln, line) in lines {
        let line = line.trim_end();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let row = parse_row(ln, line)?;
        if let Some(prev) = rows.last() {
            if row.seq <= prev.seq {
                fail!(
                    "line {ln}, column 1 (seq): {} does not increase (previous row has {})",
                    row.seq,
                    prev.seq
                );
            }
        }
        rows.push(row);
    }
    Ok(Recording { header, rows })
}

/// The `# key: value` lines of a recording's header, as read so far.
#[derive(Default)]
struct HeaderFields {
    host_time: Option<f64>,
    target: Option<String>,
    plant: Option<String>,
    decimation: Option<u16>,
    device: Option<DeviceInfo>,
    config: Option<ServoConfig>,
}

impl HeaderFields {
    /// Reads the header line `ln` (`# key: value`); unknown keys are ignored.
    fn read(&mut self, ln: usize, key: &str, value: &str) -> Result<()> {
        match key {
            "host_time_unix_s" => {
                self.host_time = Some(value.parse::<f64>().map_err(|e| {
                    format_err!("line {ln}: header host_time_unix_s: {e} (found {value:?})")
                })?);
            }
            "target" => self.target = Some(value.to_string()),
            "virtual_plant" => self.plant = Some(value.to_string()),
            "decimation" => {
                let d = value.parse::<u16>().ok().filter(|d| *d >= 1).ok_or_else(|| {
                    format_err!("line {ln}: header decimation must be an integer in [1, 65535] (found {value:?})")
                })?;
                self.decimation = Some(d);
            }
            "device" => {
                self.device =
                    Some(serde_json::from_str(value).map_err(|e| {
                        format_err!("line {ln}: header device (DeviceInfo JSON): {e}")
                    })?);
            }
            "config" => {
                self.config = Some(serde_json::from_str(value).map_err(|e| {
                    format_err!("line {ln}: header config (ServoConfig JSON): {e}")
                })?);
            }
            _ => {}
        }
        Ok(())
    }

    /// The header, once the column line is reached: device, config and decimation required
    /// and checked against each other.
    fn finish(self) -> Result<Header> {
        let device = self
            .device
            .ok_or_else(|| format_err!("header: missing `# device:` line"))?;
        let config = self
            .config
            .ok_or_else(|| format_err!("header: missing `# config:` line"))?;
        let decimation = self
            .decimation
            .ok_or_else(|| format_err!("header: missing `# decimation:` line"))?;
        check_header(&device, &config)?;
        Ok(Header {
            host_time_unix_s: self.host_time.unwrap_or(f64::NAN),
            target: self.target.unwrap_or_default(),
            virtual_plant: self.plant,
            decimation,
            device,
            config,
        })
    }
}

fn check_header(d: &DeviceInfo, c: &ServoConfig) -> Result<()> {
    if !(d.resolution.is_finite() && d.resolution > 0.0) {
        fail!(
            "header device.resolution must be finite and > 0 (found {})",
            d.resolution
        );
    }
    if !(d.force_per_code.is_finite() && d.force_per_code > 0.0) {
        fail!(
            "header device.force_per_code must be finite and > 0 (found {})",
            d.force_per_code
        );
    }
    if c.servo_rate_hz == 0 {
        fail!("header config.servo_rate_hz must be >= 1 (found 0)");
    }
    if !(1..=32).contains(&d.encoder_bits) {
        fail!(
            "header device.encoder_bits must be within [1, 32] (found {})",
            d.encoder_bits
        );
    }
    Ok(())
}

fn truncate(s: &str) -> String {
    s.chars().take(60).collect()
}

fn parse_row(ln: usize, line: &str) -> Result<Row> {
    let fields: Vec<&str> = line.split(',').collect();
    if fields.len() != COLUMN_NAMES.len() {
        fail!(
            "line {ln}: expected {} columns ({COLUMNS}), found {}",
            COLUMN_NAMES.len(),
            fields.len()
        );
    }
    fn field<T: std::str::FromStr>(ln: usize, col: usize, s: &str) -> Result<T>
    where
        T::Err: std::fmt::Display,
    {
        s.trim().parse::<T>().map_err(|e| {
            format_err!(
                "line {ln}, column {} ({}): {e} (found {:?}, expected {})",
                col + 1,
                COLUMN_NAMES[col],
                truncate(s),
                std::any::type_name::<T>()
            )
        })
    }
    Ok(Row {
        seq: field(ln, 0, fields[0])?,
        sample: Sample {
            tick: field(ln, 1, fields[1])?,
            count: field(ln, 2, fields[2])?,
            force_code: field(ln, 3, fields[3])?,
            flags: field(ln, 4, fields[4])?,
            energy: field(ln, 5, fields[5])?,
        },
    })
}

// The tests take their board facts from the virtual device.
#[cfg(all(test, feature = "virtual"))]
mod tests {
    use super::*;

    fn info() -> DeviceInfo {
        let spec = crate::virtual_device::Spec {
            plant: stiffwall_core::devices::find("maxon-re35").unwrap().params,
            counts_per_rev: 8192,
            pace: crate::pace::Pace::Fast,
            initial_position: 0.0,
            output_range: None,
            scene: None,
            travel: None,
            trace: None,
        };
        let b = spec.board();
        DeviceInfo {
            protocol_version: stiffwall_proto::PROTOCOL_VERSION,
            firmware_name: "stiffwall".try_into().unwrap(),
            firmware_version: "0.1.0".try_into().unwrap(),
            board: "virtual".try_into().unwrap(),
            servo_rate_hz: 1000,
            counts_per_rev: 8192,
            resolution: b.resolution,
            encoder_bits: 32,
            force_per_code: b.force_per_code,
            max_code: b.max_code,
            limits: stiffwall_proto::Limits {
                min_rate_hz: 100,
                max_rate_hz: 20000,
                max_stiffness: 1.0e3,
                max_force: 1.0,
                max_delay_ticks: 31,
                max_coarsen_shift: 16,
                telemetry_batch: 24,
                max_table: 1024,
            },
        }
    }

    fn header() -> Header {
        Header {
            host_time_unix_s: 1.5e9,
            target: "test".into(),
            virtual_plant: Some("maxon-re35".into()),
            decimation: 1,
            device: info(),
            config: ServoConfig::default(),
        }
    }

    fn s(tick: u32, count: i32) -> Sample {
        Sample {
            tick,
            count,
            force_code: -count * 3,
            flags: 0,
            energy: 7,
        }
    }

    fn sample_file() -> String {
        let mut w = Writer::new(Vec::new(), &header()).unwrap();
        assert_eq!(w.batch(10, &[s(11, 1), s(12, -2)], 0).unwrap(), 0);
        assert_eq!(w.batch(15, &[s(16, 3)], 2).unwrap(), 3);
        w.note("end: test").unwrap();
        String::from_utf8(w.finish().unwrap()).unwrap()
    }

    #[test]
    fn round_trip_with_gap_note() {
        let text = sample_file();
        assert!(
            text.contains("# gap: 3 samples missing before seq 15 (device-dropped 2, link-lost 1)"),
            "{text}"
        );
        let r = parse(&text).unwrap();
        assert_eq!(r.header, header());
        let seqs: Vec<u32> = r.rows.iter().map(|r| r.seq).collect();
        assert_eq!(seqs, [10, 11, 15]);
        assert_eq!(r.rows[1].sample, s(12, -2));
        assert_eq!(r.missing(), 3);
        assert_eq!(r.segments(), [0..2, 2..3]);
    }

    /// A recording written before protocol 2 has no `damper` (nor the travel window of
    /// protocol 3) in its config line: it reads as the plain difference it ran with, without a
    /// travel window (so `hostctl replay` replays it bit for bit).
    #[test]
    fn a_config_line_without_damper_reads_as_the_plain_difference() {
        let text = sample_file();
        let line = text.lines().find(|l| l.starts_with("# config: ")).unwrap();
        let tail = r#","damper":{"DeadBand":{"counts":1}},"travel_min":null,"travel_max":null}"#;
        assert!(line.ends_with(tail), "{line}");
        let old = text.replace(tail, "}");
        assert_ne!(old, text);
        let r = parse(&old).unwrap();
        assert_eq!(
            r.header.config,
            ServoConfig {
                damper: stiffwall_proto::DamperLaw::Difference,
                ..ServoConfig::default()
            }
        );
    }

    /// A recording of protocol 2 (a `damper`, no travel window) reads with its damper and no
    /// travel window; one of protocol 3 keeps its window.
    #[test]
    fn a_config_line_without_the_travel_window_reads_without_one() {
        let text = sample_file();
        let old = text.replace(r#","travel_min":null,"travel_max":null}"#, "}");
        assert_ne!(old, text);
        assert_eq!(parse(&old).unwrap().header.config, ServoConfig::default());
        let with = text.replace(
            r#""travel_min":null,"travel_max":null}"#,
            r#""travel_min":-40,"travel_max":null}"#,
        );
        assert_ne!(with, text);
        let c = parse(&with).unwrap().header.config;
        assert_eq!((c.travel_min, c.travel_max), (Some(-40), None));
    }

    fn err_of(text: &str) -> String {
        format!("{:#}", parse(text).unwrap_err())
    }

    #[test]
    fn corrupted_rows_name_line_and_column() {
        let good = sample_file();
        let n_header = good.lines().position(|l| l == COLUMNS).unwrap() + 1;
        let first_row = n_header + 1;
        let bad = good.replacen("11,12,-2,6,0,7", "11,12,-2,six,0,7", 1);
        let e = err_of(&bad);
        assert!(
            e.contains(&format!("line {}, column 4 (force_code)", first_row + 1)),
            "{e}"
        );
        let bad = good.replacen("11,12,-2,6,0,7", "11,12,-2,6,0", 1);
        assert!(
            err_of(&bad).contains("expected 6 columns"),
            "{}",
            err_of(&bad)
        );
        let bad = good.replacen("15,16,3", "9,16,3", 1);
        assert!(err_of(&bad).contains("column 1 (seq)"), "{}", err_of(&bad));
        let bad = good.replacen("10,11,1,-3,0,7", "10,11,1,-3,70000,7", 1);
        assert!(
            err_of(&bad).contains("column 5 (flags)"),
            "{}",
            err_of(&bad)
        );
    }

    #[test]
    fn corrupted_headers_are_errors() {
        let good = sample_file();
        assert!(err_of("hello\n").contains("line 1: not a stiffwall recording"));
        assert!(err_of("").contains("empty file"));
        let no_dev: String = good
            .lines()
            .filter(|l| !l.starts_with("# device:"))
            .map(|l| format!("{l}\n"))
            .collect();
        assert!(err_of(&no_dev).contains("missing `# device:`"));
        let bad = good.replacen("\"stiffness\":0.0", "\"stiffness\":\"x\"", 1);
        assert!(err_of(&bad).contains("header config"), "{}", err_of(&bad));
        let bad = good.replacen("# decimation: 1", "# decimation: 0", 1);
        assert!(
            err_of(&bad).contains("decimation must be"),
            "{}",
            err_of(&bad)
        );
        let truncated: String = good.lines().take(4).map(|l| format!("{l}\n")).collect();
        assert!(err_of(&truncated).contains("no column header"));
    }

    #[test]
    fn garbage_never_panics() {
        let good = sample_file();
        for cut in 0..good.len() {
            if good.is_char_boundary(cut) {
                let _ = parse(&good[..cut]);
            }
        }
        let mut bytes = good.into_bytes();
        for i in (0..bytes.len()).step_by(7) {
            bytes[i] = b'x';
            let _ = parse(&String::from_utf8_lossy(&bytes));
        }
    }
}
