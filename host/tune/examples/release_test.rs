//! Runs one release test on the built-in virtual device with the public API of
//! `stiffwall-tune`: the device brought to rest with the wall off, then a release from 10
//! ticks into a wall of K = 1 N·m/rad (without damping, below its quiet limit), judged as the tune judges it, and
//! its verdict printed.
//!
//! `cargo run -p stiffwall-tune --example release_test [-- K]`

use stiffwall_client::{connect, ConnectSpec, Pace};
use stiffwall_tune::{clear_faults, rest_position, run_test, Criterion, Judging, Test};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let k: f64 = match std::env::args().nth(1) {
        Some(k) => k.parse()?,
        None => 1.0,
    };
    let mut client = connect(&ConnectSpec::preset("maxon-re35", Pace::Fast))?;
    let original = client.get_config()?;
    // Tests run from rest with the wall off, the wall where the device stopped.
    let base = stiffwall_proto::ServoConfig {
        stiffness: 0.0,
        damping: 0.0,
        energy_monitor: true,
        ..original
    };
    client.set_config(&base)?;
    clear_faults(&mut client)?;
    let rest = rest_position(&mut client)?;
    let base = stiffwall_proto::ServoConfig {
        wall_position: base.wall_position.saturating_add(rest),
        ..base
    };
    let preset = stiffwall_core::devices::find("maxon-re35").ok_or("no maxon-re35 preset")?;
    let judging = Judging {
        criterion: Criterion::Rest,
        period_s: 1.0 / f64::from(client.info.servo_rate_hz),
        force_per_code: f64::from(client.info.force_per_code),
        coulomb_n: preset.params.coulomb,
        brake_damping: 0.0,
        window: None,
    };
    let test = Test::Release {
        deflection_ticks: 10,
    };
    let run = run_test(&mut client, &base, k, test, 3000, 200, &judging)?;
    client.set_config(&original)?;
    println!(
        "{} at K = {k}: {} ({} ticks judged)",
        test.describe(),
        run.verdict.describe(),
        run.counts.len()
    );
    Ok(())
}
