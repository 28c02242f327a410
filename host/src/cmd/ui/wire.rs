//! What travels between `hostctl ui` and its page.
//!
//! - **Commands** (page → server, JSON text on `/ws` or the body of `POST /api/cmd`):
//!   `{"id": 7, "cmd": "config", "set": {"stiffness": 2, "wall": "one-sided"}}`,
//!   `{"cmd": "release", "args": {"deflection": 20, "ticks": 3000, "stiffness": 1}}`,
//!   `{"cmd": "tune", "args": {"margin": 0.9, "dry-run": true}}`, `{"cmd": "clear_faults"}`,
//!   `{"cmd": "record_start", "file": "run.csv"}`, `{"cmd": "record_stop"}`,
//!   `{"cmd": "velocity", "xidot": 5}`, `{"cmd": "get"}`. The keys of `set` and `args` are the command-line
//!   flags of `hostctl config set`, `experiment release` and `tune`; they are turned into an
//!   argument list and parsed by the same clap definitions, then checked by the same
//!   functions, so the page gets the same messages as the terminal.
//! - **Answers** (server → page): `{"type": "reply", "id": 7, "ok": true, "result": …}` or
//!   `{"type": "reply", "id": 7, "ok": false, "error": "--stiffness must be …"}`.
//! - **Events** (server → page, JSON): `hello`, `config`, `plane`, `status`, `faults`,
//!   `release`, `tune`, `log` (see [`super::device`]).
//! - **Telemetry** (server → page, binary, little-endian): `u32` magic [`FRAME_MAGIC`], `u32`
//!   chunk count; per chunk `u32` seq of its first sample, `u32` n, then n samples of
//!   [`SAMPLE_BYTES`] bytes: `u32` tick, `i32` count, `i32` force_code, `u16` flags, `u32`
//!   energy (the units of [`stiffwall_proto::Sample`]). Every sample the device sent is in
//!   exactly one frame.

use crate::cmd::experiment::ReleaseArgs;
use crate::config_flags::Overrides;
use anyhow::{bail, Result};
use clap::Parser;
use serde_json::Value;
use stiffwall_proto::{fault, Sample};

/// First word of every binary telemetry frame ("SWT1").
pub const FRAME_MAGIC: u32 = 0x3154_5753;
/// Bytes per sample in a telemetry frame.
pub const SAMPLE_BYTES: usize = 18;

/// The answer to one command.
pub type Reply = Result<Value, String>;

/// A command from the page.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(tag = "cmd", rename_all = "snake_case", deny_unknown_fields)]
pub enum Command {
    /// `hostctl config set` with these flags.
    Config {
        /// Flag name (without dashes) → value.
        set: serde_json::Map<String, Value>,
    },
    /// `hostctl experiment release` with these flags (deflection, ticks, stiffness).
    Release {
        /// Flag name → value.
        args: serde_json::Map<String, Value>,
    },
    /// `hostctl tune` with these flags (max-velocity, margin, release-ticks,
    /// excite-seconds, dry-run).
    Tune {
        /// Flag name → value.
        #[serde(default)]
        args: serde_json::Map<String, Value>,
    },
    /// Clear latched faults.
    ClearFaults,
    /// The velocity of the critical line, encoder ticks per servo period.
    Velocity {
        /// ξ̇ (> 0).
        xidot: f64,
    },
    /// Start recording (lossless CSV, as `hostctl record`) into the record directory.
    RecordStart {
        /// Plain file name ending in `.csv`.
        file: String,
    },
    /// Stop recording.
    RecordStop,
    /// The active configuration, latched faults, counters and the latest `plane` message
    /// (with its (B, K) `frontier`); changes nothing.
    Get,
}

/// A command with its request id, as sent by the page.
#[derive(Debug, Clone, serde::Deserialize)]
pub struct Envelope {
    /// Echoed in the reply.
    #[serde(default)]
    pub id: Value,
    /// The command.
    #[serde(flatten)]
    pub cmd: Command,
}

/// Flags the page may give to `release` (the rest of `experiment release`'s flags pick the
/// device, the output or the plot, which the page does not choose).
pub const RELEASE_FLAGS: &[&str] = &["deflection", "ticks", "stiffness"];
/// Flags the page may give to `tune`.
pub const TUNE_FLAGS: &[&str] = &[
    "max-velocity",
    "margin",
    "release-ticks",
    "excite-seconds",
    "dry-run",
];

/// The argument list `program --key value …` of a JSON object of flags: `true` is a bare
/// flag, `false` and `null` are left out, numbers and strings are values, arrays give one value
/// per element.
///
/// # Errors
/// A key that is not a flag name, or a value of another type.
pub fn argv(program: &str, flags: &serde_json::Map<String, Value>) -> Result<Vec<String>> {
    let mut v = vec![program.to_string()];
    for (k, val) in flags {
        let name_ok = k.starts_with(|c: char| c.is_ascii_lowercase())
            && k.chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-');
        if !name_ok {
            bail!("{program}: {k:?} is not a flag name");
        }
        let flag = format!("--{k}");
        let scalar = |x: &Value| -> Result<String> {
            match x {
                Value::Number(n) => Ok(n.to_string()),
                Value::String(s) => Ok(s.clone()),
                other => bail!("{program}: {flag} takes a number or a word, got {other}"),
            }
        };
        match val {
            Value::Null | Value::Bool(false) => {}
            Value::Bool(true) => v.push(flag.clone()),
            Value::Array(xs) => {
                v.push(flag.clone());
                for x in xs {
                    v.push(scalar(x)?);
                }
            }
            x => {
                v.push(flag.clone());
                v.push(scalar(x)?);
            }
        }
    }
    Ok(v)
}

fn only(program: &str, argv: &[String], allowed: &[&str]) -> Result<()> {
    for a in argv.iter().skip(1).filter(|a| a.starts_with("--")) {
        if !allowed.contains(&&a[2..]) {
            bail!(
                "{program}: the page cannot set {a} (allowed: {})",
                allowed
                    .iter()
                    .map(|f| format!("--{f}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    Ok(())
}

/// A clap error as the terminal shows it, without the usage lines.
fn clap_message(e: &clap::Error) -> String {
    e.to_string()
        .lines()
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .map(str::trim_end)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// `hostctl config set`'s flags.
#[derive(Debug, Parser)]
#[command(name = "config set")]
pub struct ConfigCli {
    #[command(flatten)]
    set: Overrides,
}

impl ConfigCli {
    /// Parses `argv` (program name first) with `config set`'s definitions.
    ///
    /// # Errors
    /// clap's message (unknown flag, bad number, unknown wall mode, …).
    pub fn parse_argv(argv: &[String]) -> Result<Overrides> {
        Self::try_parse_from(argv)
            .map(|c| c.set)
            .map_err(|e| anyhow::anyhow!("{}", clap_message(&e)))
    }
}

/// `hostctl experiment release`'s flags.
#[derive(Debug, Parser)]
#[command(name = "release")]
pub struct ReleaseCli {
    #[command(flatten)]
    args: ReleaseArgs,
}

impl ReleaseCli {
    /// Parses `argv` (program name first) with `experiment release`'s definitions.
    ///
    /// # Errors
    /// A flag the page may not give, or clap's message.
    pub fn parse_argv(argv: &[String]) -> Result<ReleaseArgs> {
        only("release", argv, RELEASE_FLAGS)?;
        Self::try_parse_from(argv)
            .map(|c| c.args)
            .map_err(|e| anyhow::anyhow!("{}", clap_message(&e)))
    }
}

/// `hostctl tune`'s flags.
#[derive(Debug, Parser)]
#[command(name = "tune")]
pub struct TuneCli {
    #[command(flatten)]
    args: crate::cmd::tune::Args,
}

impl TuneCli {
    /// Parses `argv` (program name first) with `tune`'s definitions.
    ///
    /// # Errors
    /// A flag the page may not give, or clap's message.
    pub fn parse_argv(argv: &[String]) -> Result<crate::cmd::tune::Args> {
        only("tune", argv, TUNE_FLAGS)?;
        Self::try_parse_from(argv)
            .map(|c| c.args)
            .map_err(|e| anyhow::anyhow!("{}", clap_message(&e)))
    }
}

/// Appends one chunk (consecutive samples from `seq`) to a frame body.
pub fn push_chunk(body: &mut Vec<u8>, seq: u32, samples: &[Sample]) {
    body.extend_from_slice(&seq.to_le_bytes());
    body.extend_from_slice(&(samples.len() as u32).to_le_bytes());
    for s in samples {
        body.extend_from_slice(&s.tick.to_le_bytes());
        body.extend_from_slice(&s.count.to_le_bytes());
        body.extend_from_slice(&s.force_code.to_le_bytes());
        body.extend_from_slice(&s.flags.to_le_bytes());
        body.extend_from_slice(&s.energy.to_le_bytes());
    }
}

/// A whole frame: header and `chunks` chunks of `body`.
#[must_use]
pub fn frame(chunks: u32, body: &[u8]) -> Vec<u8> {
    let mut v = Vec::with_capacity(8 + body.len());
    v.extend_from_slice(&FRAME_MAGIC.to_le_bytes());
    v.extend_from_slice(&chunks.to_le_bytes());
    v.extend_from_slice(body);
    v
}

/// Names of the latched fault bits.
#[must_use]
pub fn fault_names(bits: u32) -> Vec<&'static str> {
    fault::NAMES
        .into_iter()
        .filter(|(b, _, _)| bits & b != 0)
        .map(|(_, _, label)| label)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn map(v: Value) -> serde_json::Map<String, Value> {
        v.as_object().unwrap().clone()
    }

    #[test]
    fn config_flags_parse_like_the_terminal() {
        let argv = argv(
            "config set",
            &map(json!({"stiffness": 2.5, "wall": "one-sided"})),
        )
        .unwrap();
        let o = ConfigCli::parse_argv(&argv).unwrap();
        assert_eq!(o.stiffness, Some(2.5));
        assert_eq!(o.wall, Some(crate::config_flags::WallArg::OneSided));
        // The host-side check is the one of `config set`: same message.
        let bad = ConfigCli::parse_argv(&argv_of(json!({"stiffness": -1}))).unwrap();
        let e = bad
            .apply(&stiffwall_proto::ServoConfig::default())
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "--stiffness must be a finite number >= 0 (got -1)"
        );
        let e = ConfigCli::parse_argv(&argv_of(json!({"wall": "sideways"}))).unwrap_err();
        assert!(
            e.to_string()
                .contains("invalid value 'sideways' for '--wall"),
            "{e}"
        );
        let e = ConfigCli::parse_argv(&argv_of(json!({"port": "/dev/x"}))).unwrap_err();
        assert!(
            e.to_string().contains("unexpected argument '--port'"),
            "{e}"
        );
    }

    fn argv_of(v: Value) -> Vec<String> {
        argv("config set", &map(v)).unwrap()
    }

    #[test]
    fn release_and_tune_take_only_their_test_flags() {
        let a = ReleaseCli::parse_argv(
            &argv("release", &map(json!({"deflection": 20, "stiffness": 1.5}))).unwrap(),
        )
        .unwrap();
        assert_eq!((a.deflection, a.ticks, a.stiffness), (20, 3000, Some(1.5)));
        let e = ReleaseCli::parse_argv(
            &argv("release", &map(json!({"deflection": 20, "port": "x"}))).unwrap(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("cannot set --port"), "{e}");
        let t = TuneCli::parse_argv(
            &argv("tune", &map(json!({"dry-run": true, "margin": 0.8}))).unwrap(),
        )
        .unwrap();
        assert!(t.dry_run);
        assert_eq!(crate::cmd::tune::settings(&t).unwrap().margin, 0.8);
        let e = TuneCli::parse_argv(&argv("tune", &map(json!({"plot": "x.png"}))).unwrap())
            .unwrap_err();
        assert!(e.to_string().contains("cannot set --plot"), "{e}");
    }

    #[test]
    fn flag_names_are_checked() {
        assert!(argv("x", &map(json!({"--evil": 1}))).is_err());
        assert!(argv("x", &map(json!({"Stiffness": 1}))).is_err());
        assert!(argv("x", &map(json!({"a": {"b": 1}}))).is_err());
        assert_eq!(
            argv(
                "x",
                &map(json!({"a": true, "b": false, "c": null, "d": [1, 2]}))
            )
            .unwrap(),
            ["x", "--a", "--d", "1", "2"]
        );
    }

    #[test]
    fn commands_parse() {
        let e: Envelope = serde_json::from_str(r#"{"id": 3, "cmd": "clear_faults"}"#).unwrap();
        assert!(matches!(e.cmd, Command::ClearFaults));
        assert_eq!(e.id, json!(3));
        assert!(serde_json::from_str::<Envelope>(r#"{"cmd": "format_disk"}"#).is_err());
    }

    #[test]
    fn frame_layout() {
        let s = Sample {
            tick: 7,
            count: -3,
            force_code: 120,
            flags: 5,
            energy: 26,
        };
        let mut body = Vec::new();
        push_chunk(&mut body, 1200, &[s, s]);
        let f = frame(1, &body);
        assert_eq!(f.len(), 8 + 8 + 2 * SAMPLE_BYTES);
        assert_eq!(&f[0..4], b"SWT1");
        assert_eq!(u32::from_le_bytes(f[8..12].try_into().unwrap()), 1200);
        assert_eq!(i32::from_le_bytes(f[20..24].try_into().unwrap()), -3);
        assert_eq!(u16::from_le_bytes(f[28..30].try_into().unwrap()), 5);
        assert_eq!(u32::from_le_bytes(f[30..34].try_into().unwrap()), 26);
    }

    #[test]
    fn fault_bits_are_named() {
        assert_eq!(
            fault_names(fault::BUZZ | fault::ENERGY_GROWTH),
            ["energy growth", "buzz"]
        );
        assert!(fault_names(0).is_empty());
    }
}
