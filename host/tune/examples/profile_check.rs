//! Checks a profile file against a saved tune: `cargo run -p stiffwall-tune --example
//! profile_check -- profiles/knob-24-detents.toml tune.json` (tune.json: `hostctl tune --json`).
use stiffwall_tune::profile::{check, lower, render, Envelope, ProfileFile};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [file, tune] = &args[..] else {
        return Err("usage: profile_check PROFILE.toml TUNE.json".into());
    };
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(tune)?)?;
    let outcome = serde_json::from_value(json.get("tune").unwrap_or(&json).clone())?;
    let envelope = Envelope::from_outcome(&outcome, tune.as_str());
    let profile = lower(
        &ProfileFile::from_toml(&std::fs::read_to_string(file)?)?,
        &envelope.device,
    )?;
    print!("{}", render(&check(&profile, &envelope)));
    Ok(())
}
