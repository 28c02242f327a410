//! Tunes the built-in virtual device (maxon-re35, at the fast pace) with the public API of
//! `stiffwall-tune`: every progress event printed as it starts, Ctrl-C wired to the tune's
//! [`Cancel`] token (the running test stops and the previous config is restored), a dry run
//! (nothing is saved).
//!
//! `cargo run -p stiffwall-tune --example tune_virtual [-- PRESET]`

use stiffwall_client::{connect, ctrl_c, Cancel, ConnectSpec, Pace};
use stiffwall_tune::{tune, Progress, Settings, TuneError};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let preset = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "maxon-re35".into());
    // This crate's handler: Ctrl-C cancels the process's root token, which every token made
    // by `Cancel::on_ctrl_c` follows.
    ctrlc::set_handler(|| ctrl_c().cancel())?;
    let cancel = Cancel::on_ctrl_c();

    let mut client = connect(&ConnectSpec::preset(preset.as_str(), Pace::Fast))?;
    let settings = Settings {
        dry_run: true,
        ..Settings::default()
    };
    let started = std::time::Instant::now();
    let result = tune(&mut client, &settings, &cancel, &mut |event: Progress| {
        println!("[{:6.2} s] {event}", started.elapsed().as_secs_f64());
    });
    match result {
        Ok(o) => {
            println!(
                "{preset}: K = {:.4e}, B = {:.4e} (spring only {:.4e}), rests: {}",
                o.k_set, o.b_set, o.k_spring_only, o.rests
            );
            for finding in &o.model_mismatch {
                println!("finding: {finding}");
            }
            Ok(())
        }
        Err(TuneError::Cancelled) => {
            println!("cancelled; the device keeps the config it had");
            Ok(())
        }
        Err(e) => Err(e.into()),
    }
}
