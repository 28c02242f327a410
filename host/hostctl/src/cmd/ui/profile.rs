//! The haptic profile in the live view (issue 43, item 5): `--profile FILE` read, lowered for
//! the connected device and (with `--tune-json`) checked before anything is loaded, and the
//! `profile` message that draws the device's active profile over the position trace.
//!
//! The file format, the lowering and the check are `stiffwall_tune::profile`'s (as `hostctl
//! profile check`); reading, lowering and checking the file is `cmd::profile::prepare`'s
//! (re-exported here; `hostctl virtual --profile` prepares its profile with it too); this module
//! only decides what the page is told.
//!
//! The `profile` message (server → page, JSON, [`PROFILE_MESSAGE_VERSION`]):
//! `{"type": "profile", "version": 1, "source": "file" | "device", "file", "name",
//! "checked_against", "pass", "near_limit", "units", "resolution", "elements": [...]}`; per
//! wire element: `n` (its number on the wire, from 0), `index` and `kind` (its element in the
//! file, from 1, and its kind; the wire's own numbering when the profile was not loaded from a
//! file), `wire_kind` (`wall`, `spring`, `detents`, `viscous`), `part` (which wall of `end-stops`), `span` (`lo`, `hi`: the counts it acts on,
//! inclusive, `null` unbounded: the position panel plots raw counts), `geometry` (kind by kind:
//! a wall's `position` and `side`, a spring's `center`, a train's `first`, `pitch`, `count`, a
//! zone's `from` and `to`, all in counts), `numbers` (`name`, `value`, `unit`: K, B, strength,
//! pitch in the device's units), `check` (`k_local`, `b_local`, `k_limit`, `margin`, `pass`,
//! `problems`; `null` unchecked) and `state` (`ok`, `near` (margin < [`NEAR_LIMIT`]), `fails`,
//! `unchecked`).
//!
//! Units: positions on the wire and in `span`/`geometry` are raw encoder counts (the host
//! assumes the servo's coarsening shift 0, as the profile library); numbers in the device's
//! units (N/m, N·s/m, N, m; N·m/rad, N·m·s/rad, N·m, rad).

use serde_json::{json, Value};
use stiffwall_proto::{DeviceInfo, Profile, ProfileElement, Side};
use stiffwall_tune::profile::{overlap, units::sig, Device};

// Read, lowered and checked as `hostctl virtual --profile` does: `cmd::profile`'s.
pub use crate::cmd::profile::{failures, prepare, Loaded};

/// The version of the `profile` message.
pub const PROFILE_MESSAGE_VERSION: u32 = 1;

/// An element whose margin (limit / local K) is below this is marked near its limit.
pub const NEAR_LIMIT: f64 = 1.25;

fn number(name: &str, value: f64, unit: &str) -> Value {
    json!({"name": name, "value": value, "unit": unit, "text": format!("{name} = {} {unit}", sig(value))})
}

/// The kind-specific geometry and key numbers of one wire element.
fn describe(e: &ProfileElement, device: &Device) -> (Value, Vec<Value>) {
    let u = device.units();
    let kb = |k: f32, b: f32| {
        vec![
            number("K", f64::from(k), u.stiffness),
            number("B", f64::from(b), u.damping),
        ]
    };
    match *e {
        ProfileElement::Wall {
            position,
            side,
            stiffness,
            damping,
            ..
        } => (
            json!({"position": position, "side": if side == Side::Upper { "upper" } else { "lower" }}),
            kb(stiffness, damping),
        ),
        ProfileElement::Spring {
            center,
            stiffness,
            damping,
            ..
        } => (json!({"center": center}), kb(stiffness, damping)),
        ProfileElement::Detents {
            first,
            pitch_counts,
            count,
            strength,
            damping,
            ..
        } => {
            let a = f64::from(strength);
            let pitch = pitch_counts * device.resolution;
            (
                json!({"first": first, "pitch": pitch_counts, "count": count}),
                vec![
                    number("strength", a, u.force),
                    number("pitch", pitch, u.position),
                    // The slope at a minimum, the check's local K (2π·A/pitch).
                    number("K", core::f64::consts::TAU * a / pitch, u.stiffness),
                    number("B", f64::from(damping), u.damping),
                ],
            )
        }
        ProfileElement::Viscous {
            from, to, damping, ..
        } => (
            json!({"from": from, "to": to}),
            vec![number("B", f64::from(damping), u.damping)],
        ),
    }
}

/// The `profile` message for the device's `active` profile; `loaded` (the file loaded at
/// start) names its elements and gives their check when `active` is what it loaded.
#[must_use]
pub fn message(info: &DeviceInfo, active: &Profile, loaded: Option<&Loaded>) -> Value {
    let device = Device::of_info(info);
    let u = device.units();
    let from_file = loaded.filter(|l| l.lowered.wire() == *active);
    let report = from_file.and_then(|l| l.report.as_ref());
    let elements: Vec<Value> = active
        .elements
        .iter()
        .enumerate()
        .map(|(n, e)| {
            let origin = from_file
                .and_then(|l| l.lowered.elements.get(n))
                .map(|p| p.origin);
            let span = overlap::span(e);
            let (geometry, numbers) = describe(e, &device);
            let c = report.and_then(|r| r.elements.get(n));
            let state = match c {
                None => "unchecked",
                Some(c) if !c.pass => "fails",
                Some(c) if c.margin.is_some_and(|m| m < NEAR_LIMIT) => "near",
                Some(_) => "ok",
            };
            json!({
                "n": n,
                "index": origin.map_or(n + 1, |o| o.index),
                "kind": origin.map_or(e.kind_name(), |o| o.kind),
                "wire_kind": e.kind_name(),
                "part": origin.and_then(|o| o.part),
                "span": {"lo": span.lo, "hi": span.hi},
                "geometry": geometry,
                "numbers": numbers,
                "check": c.map(|c| json!({
                    "k_local": c.k_local, "b_local": c.b_local, "k_limit": c.k_limit,
                    "margin": c.margin, "pass": c.pass, "problems": c.problems,
                })),
                "state": state,
            })
        })
        .collect();
    json!({
        "type": "profile",
        "version": PROFILE_MESSAGE_VERSION,
        "source": if from_file.is_some() { "file" } else { "device" },
        "file": from_file.map(|l| l.file.display().to_string()),
        "name": from_file.map(|l| l.lowered.name.clone()),
        "checked_against": report.map(|r| r.envelope.source.clone()),
        "pass": report.map(|r| r.pass),
        "near_limit": NEAR_LIMIT,
        "units": {"span": "counts", "position": u.position, "k": u.stiffness, "b": u.damping, "force": u.force},
        "resolution": device.resolution,
        "elements": elements,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use stiffwall_tune::profile::{self, ProfileFile};

    fn info(counts_per_rev: u32) -> DeviceInfo {
        DeviceInfo {
            protocol_version: stiffwall_proto::PROTOCOL_VERSION,
            firmware_name: Default::default(),
            firmware_version: Default::default(),
            board: Default::default(),
            servo_rate_hz: 1000,
            counts_per_rev,
            resolution: 1e-5,
            encoder_bits: 32,
            force_per_code: 1e-3,
            max_code: 32767,
            limits: stiffwall_proto::Limits {
                min_rate_hz: 100,
                max_rate_hz: 20_000,
                max_stiffness: 1e4,
                max_force: 3.0,
                max_delay_ticks: 31,
                max_coarsen_shift: 16,
                telemetry_batch: 24,
                max_table: 512,
            },
        }
    }

    #[test]
    fn the_message_names_file_elements_and_spans_in_counts() {
        let file = ProfileFile::from_toml(
            "[profile]\nname = \"slot\"\naxis = \"linear\"\n\n[[element]]\nkind = \"end-stops\"\n\
             min = -0.01\nmax = 0.01\nstiffness = 400\n\n[[element]]\nkind = \"viscous\"\n\
             from = -0.001\nto = 0.001\ndamping = 2\n",
        )
        .unwrap();
        let i = info(0);
        let lowered = profile::lower(&file, &Device::of_info(&i)).unwrap();
        let loaded = Loaded {
            file: "slot.toml".into(),
            lowered: lowered.clone(),
            report: None,
        };
        let m = message(&i, &lowered.wire(), Some(&loaded));
        assert_eq!(m["version"], 1);
        assert_eq!(m["source"], "file");
        let els = m["elements"].as_array().unwrap();
        assert_eq!(els.len(), 3);
        assert_eq!(els[0]["kind"], "end-stops");
        assert_eq!(els[0]["part"], "lower");
        assert_eq!(els[0]["span"]["lo"], Value::Null);
        assert_eq!(els[0]["span"]["hi"], json!(-1001));
        assert_eq!(els[1]["span"]["lo"], json!(1000));
        assert_eq!(els[2]["kind"], "viscous");
        assert_eq!(els[2]["index"], 2);
        assert_eq!(els[2]["span"], json!({"lo": -100, "hi": 99}));
        assert_eq!(els[2]["state"], "unchecked");
        // The device's profile alone (another one than the file's): wire kinds, no file.
        let m = message(&i, &lowered.wire(), None);
        assert_eq!(m["source"], "device");
        assert_eq!(m["elements"][0]["kind"], "wall");
    }
}
