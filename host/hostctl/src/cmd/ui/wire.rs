//! What travels between `hostctl ui` and its page.
//!
//! - **Commands** (page → server, JSON text on `/ws` or the body of `POST /api/cmd`):
//!   `{"id": 7, "cmd": "config", "set": {"stiffness": 2, "wall": "one-sided"}}`,
//!   `{"cmd": "release", "args": {"deflection": 20, "ticks": 3000, "stiffness": 1}}`,
//!   `{"cmd": "tune", "args": {"margin": 0.9, "dry-run": true}}`, `{"cmd": "clear_faults"}`,
//!   `{"cmd": "record_start", "file": "run.csv"}`, `{"cmd": "record_stop"}`,
//!   `{"cmd": "velocity", "xidot": 5}`, `{"cmd": "get"}`, `{"cmd": "abort"}` (the running
//!   release test or tune), `{"cmd": "take_control"}` (see [`super::control`]). They are typed ([`Command`]): the
//!   keys of `set` and `args` are the command-line flags' names of `hostctl config set`,
//!   `experiment release` and `tune`, each takes its field's type (a number is a JSON number,
//!   a word a JSON string, `dry-run` a boolean), and an unknown key or a value of another type
//!   refuses the command naming the field (`config: set.stiffness: invalid type: sequence,
//!   expected f32`). Nothing from the page is turned into a command line. The values are then
//!   checked: config by the terminal's own [`Overrides::apply`] (the terminal's range
//!   messages), the release test and tune in the page's words
//!   ([`super::device::release::check_release_fields`], `Settings::validate` rendered with the
//!   page's labels by [`super::device::tune::page_settings`]).
//! - **Answers** (server → page): `{"type": "reply", "id": 7, "ok": true, "result": …}` or
//!   `{"type": "reply", "id": 7, "ok": false, "error": "--stiffness must be …"}`.
//! - **Events** (server → page, JSON): `hello`, `config`, `plane`, `status`, `faults`,
//!   `release`, `tune`, `log` (see [`super::device`]).
//! - **Telemetry** (server → page, binary, little-endian): `u32` magic [`FRAME_MAGIC`], `u32`
//!   chunk count; per chunk `u32` seq of its first sample, `u32` n, then n samples of
//!   [`SAMPLE_BYTES`] bytes: `u32` tick, `i32` count, `i32` force_code, `u16` flags, `u32`
//!   energy (the units of [`stiffwall_proto::Sample`]). Every sample the device sent is in
//!   exactly one frame. The test arguments and the frame are `stiffwall_analysis::live::wire`'s,
//!   re-exported here.

use crate::config_flags::Overrides;
use anyhow::Result;
use serde::de::DeserializeOwned;
use serde_json::Value;
pub use stiffwall_analysis::live::wire::{
    fault_names, frame, push_chunk, ReleaseTest, TuneTest, FRAME_MAGIC, SAMPLE_BYTES,
};

/// The answer to one command.
pub type Reply = Result<Value, String>;

/// A command from the page.
#[derive(Debug, Clone)]
pub enum Command {
    /// `hostctl config set` with these fields (`"set"`).
    Config(Overrides),
    /// `hostctl experiment release` with these arguments (`"args"`).
    Release(ReleaseTest),
    /// `hostctl tune` with these arguments (`"args"`, optional).
    Tune(TuneTest),
    /// Clear latched faults.
    ClearFaults,
    /// The velocity of the critical line, encoder ticks per servo period (ξ̇ > 0).
    Velocity(f64),
    /// Start recording (lossless CSV, as `hostctl record`) into the record directory; a plain
    /// file name ending in `.csv`.
    RecordStart(String),
    /// Stop recording.
    RecordStop,
    /// The active configuration, latched faults, counters and the latest `plane` message
    /// (with its (B, K) `frontier`); changes nothing.
    Get,
    /// Abort the running release test or tune (the device ends the test and gets its previous
    /// config back); answered by the server at once (see [`super::control`]).
    Abort,
    /// Make this page the controller (see [`super::control`]).
    TakeControl,
}

/// A command with its request id, as sent by the page.
#[derive(Debug, Clone)]
pub struct Envelope {
    /// Echoed in the reply (a number, a string or null).
    pub id: Value,
    /// The command.
    pub cmd: Command,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ConfigBody {
    set: Overrides,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ReleaseBody {
    args: ReleaseTest,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct TuneBody {
    #[serde(default)]
    args: TuneTest,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct VelocityBody {
    xidot: f64,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RecordBody {
    file: String,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct NoFields {}

/// The names of the commands.
pub const COMMANDS: [&str; 10] = [
    "config",
    "release",
    "tune",
    "clear_faults",
    "velocity",
    "record_start",
    "record_stop",
    "get",
    "abort",
    "take_control",
];

/// `fields` (the command's object without `cmd` and `id`) as `T`, or the message naming the
/// field that does not fit.
fn typed<T: DeserializeOwned>(cmd: &str, fields: Value) -> Result<T, String> {
    serde_path_to_error::deserialize(fields).map_err(|e| {
        let path = e.path().to_string();
        if path == "." {
            format!("{cmd}: {}", e.inner())
        } else {
            format!("{cmd}: {path}: {}", e.inner())
        }
    })
}

/// Parses one command from the page (JSON text).
///
/// # Errors
/// The id (when one could be read) and a one-line message: not a JSON object, no or an
/// unknown `cmd`, an unknown field or a field of the wrong type (named).
pub fn parse_command(text: &[u8]) -> Result<Envelope, (Value, String)> {
    let bad = |id: &Value, e: String| (id.clone(), format!("bad command: {e}"));
    let v: Value = serde_json::from_slice(text).map_err(|e| bad(&Value::Null, e.to_string()))?;
    let Value::Object(mut fields) = v else {
        return Err(bad(&Value::Null, "a command is a JSON object".into()));
    };
    let id = fields.remove("id").unwrap_or(Value::Null);
    if !matches!(id, Value::Null | Value::Number(_) | Value::String(_)) {
        return Err(bad(&Value::Null, "id must be a number or a string".into()));
    }
    let name = match fields.remove("cmd") {
        Some(Value::String(s)) => s,
        _ => return Err(bad(&id, format!("\"cmd\" must be one of {COMMANDS:?}"))),
    };
    let rest = Value::Object(fields);
    let cmd = match name.as_str() {
        "config" => typed::<ConfigBody>(&name, rest).map(|b| Command::Config(b.set)),
        "release" => typed::<ReleaseBody>(&name, rest).map(|b| Command::Release(b.args)),
        "tune" => typed::<TuneBody>(&name, rest).map(|b| Command::Tune(b.args)),
        "velocity" => typed::<VelocityBody>(&name, rest).map(|b| Command::Velocity(b.xidot)),
        "record_start" => typed::<RecordBody>(&name, rest).map(|b| Command::RecordStart(b.file)),
        "clear_faults" => typed::<NoFields>(&name, rest).map(|_| Command::ClearFaults),
        "record_stop" => typed::<NoFields>(&name, rest).map(|_| Command::RecordStop),
        "get" => typed::<NoFields>(&name, rest).map(|_| Command::Get),
        "abort" => typed::<NoFields>(&name, rest).map(|_| Command::Abort),
        "take_control" => typed::<NoFields>(&name, rest).map(|_| Command::TakeControl),
        other => Err(format!("unknown command {other:?} (one of {COMMANDS:?})")),
    };
    cmd.map(|cmd| Envelope {
        id: id.clone(),
        cmd,
    })
    .map_err(|e| bad(&id, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn parse(v: Value) -> Result<Command, String> {
        parse_command(v.to_string().as_bytes())
            .map(|e| e.cmd)
            .map_err(|(_, e)| e)
    }

    #[test]
    fn config_fields_are_typed() {
        let Command::Config(o) =
            parse(json!({"cmd": "config", "set": {"stiffness": 2.5, "wall": "one-sided"}}))
                .unwrap()
        else {
            panic!("not a config command")
        };
        assert_eq!(o.stiffness, Some(2.5));
        assert_eq!(o.wall, Some(crate::config_flags::WallArg::OneSided));
        // The range check is `config set`'s: same message as the terminal.
        let Command::Config(bad) =
            parse(json!({"cmd": "config", "set": {"stiffness": -1}})).unwrap()
        else {
            panic!("not a config command")
        };
        let e = bad
            .apply(&stiffwall_proto::ServoConfig::default())
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "--stiffness must be a finite number >= 0 (got -1)"
        );
    }

    #[test]
    fn a_field_of_another_type_is_refused_naming_it() {
        for (set, field) in [
            (
                json!({"stiffness": [0.5, "--wall", "one-sided"]}),
                "set.stiffness",
            ),
            (json!({"stiffness": "2"}), "set.stiffness"),
            (json!({"damping": {"a": 1}}), "set.damping"),
            (json!({"rate": 5000.5}), "set.rate"),
            (json!({"wall": "sideways"}), "set.wall"),
            (json!({"wall": ["one-sided"]}), "set.wall"),
            (json!({"--wall": "one-sided"}), "--wall"),
            (json!({"port": "/dev/x"}), "port"),
        ] {
            let e = parse(json!({"cmd": "config", "set": set})).unwrap_err();
            assert!(e.starts_with("bad command: config: "), "{e}");
            assert!(e.contains(field), "{set}: {e}");
        }
        let e =
            parse(json!({"cmd": "release", "args": {"deflection": 20, "port": "x"}})).unwrap_err();
        assert!(e.contains("unknown field `port`"), "{e}");
        let e = parse(json!({"cmd": "tune", "args": {"plot": "x.png"}})).unwrap_err();
        assert!(e.contains("unknown field `plot`"), "{e}");
        let e = parse(json!({"cmd": "tune", "args": {"dry-run": "yes"}})).unwrap_err();
        assert!(e.contains("args.dry-run"), "{e}");
        let e = parse(json!({"cmd": "get", "extra": 1})).unwrap_err();
        assert!(e.contains("unknown field `extra`"), "{e}");
    }

    #[test]
    fn release_and_tune_take_only_their_test_fields() {
        let Command::Release(a) =
            parse(json!({"cmd": "release", "args": {"deflection": 20, "stiffness": 1.5}})).unwrap()
        else {
            panic!("not a release")
        };
        assert_eq!((a.deflection, a.ticks, a.stiffness), (20, 3000, Some(1.5)));
        let Command::Tune(t) =
            parse(json!({"cmd": "tune", "args": {"dry-run": true, "margin": 0.8}})).unwrap()
        else {
            panic!("not a tune")
        };
        assert!(t.dry_run);
        assert_eq!(t.margin, Some(0.8));
        let Command::Tune(t) = parse(json!({"cmd": "tune"})).unwrap() else {
            panic!("not a tune")
        };
        assert_eq!(t, TuneTest::default());
    }

    #[test]
    fn commands_parse() {
        let e = parse_command(br#"{"id": 3, "cmd": "clear_faults"}"#).unwrap();
        assert!(matches!(e.cmd, Command::ClearFaults));
        assert_eq!(e.id, json!(3));
        let (id, msg) = parse_command(br#"{"id": 4, "cmd": "format_disk"}"#).unwrap_err();
        assert_eq!(id, json!(4));
        assert!(msg.contains("unknown command"), "{msg}");
        assert!(parse_command(b"[1]").is_err());
        assert!(parse_command(br#"{"cmd": 1}"#).is_err());
        assert!(parse_command(br#"{"id": [1], "cmd": "get"}"#).is_err());
    }
}
