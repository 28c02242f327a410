//! Records 10 s (device time) of telemetry from the built-in virtual device with the public
//! API of `stiffwall-client`: the lossless recorder writes the CSV recording format to a file,
//! which is then read back and summarized.
//!
//! `cargo run -p stiffwall-client --example record [-- FILE.csv]`

use stiffwall_client::{
    connect, header_for_target, read_recording, record, ConnectSpec, Pace, Plan,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).map_or_else(
        || std::env::temp_dir().join("stiffwall-record-example.csv"),
        std::path::PathBuf::from,
    );
    let spec = ConnectSpec::preset("maxon-re35", Pace::Fast);
    let mut client = connect(&spec)?;
    let cfg = client.get_config()?;
    // Every 10th sample of 10 s of device time.
    let decimation = 10;
    let plan = Plan::new(decimation, Some(10.0), client.info.servo_rate_hz)?;
    let header = header_for_target(
        &client,
        cfg,
        u16::try_from(decimation)?,
        spec.describe(),
        spec.virtual_plant_name(),
    );
    let file = std::io::BufWriter::new(std::fs::File::create(&path)?);
    let outcome = record(&mut client, &plan, &header, file, |_| {})?;
    println!("{}", outcome.stats.summary());

    let rec = read_recording(&path)?;
    let counts = rec.rows.iter().map(|r| r.sample.count);
    let (lo, hi) = counts.fold((i32::MAX, i32::MIN), |(lo, hi), c| (lo.min(c), hi.max(c)));
    println!(
        "{}: {} rows, {} missing, counts {lo}..={hi}",
        path.display(),
        rec.rows.len(),
        rec.missing()
    );
    Ok(())
}
