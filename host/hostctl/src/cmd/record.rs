//! `hostctl record`: record telemetry losslessly to CSV (format: [`crate::recording`]).
//!
//! Units: `--seconds` is *device* time (servo ticks / servo rate), so a `--fast` virtual
//! device records the same samples as a paced one, only sooner; the recording holds exactly
//! ⌈seconds · rate / decimation⌉ sample numbers (fewer rows if some were lost, each loss noted
//! in place). Wall-clock figures (samples per wall second) are reported separately.
//!
//! Invariants: every sample received is written, in order; every gap in the device's sample
//! numbers is written where it happened, attributed to the device (its `dropped` counter grew)
//! or to the link, and counted in the summary; a disconnect or a silent device keeps what was
//! received (the file is flushed and closed with an `# end:` note) and exits non-zero. The file
//! is flushed at least every 100 ms, so an abrupt kill loses at most that much.

use crate::config_flags::Overrides;
use crate::device::connect::ConnectArgs;
use crate::output::emit;
pub use crate::session::header;
use anyhow::{bail, Context, Result};
use std::path::PathBuf;
pub use stiffwall_client::{pump, record, End, Plan, SessionOutcome as Outcome, Stats};

/// Arguments of `hostctl record`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  hostctl record wall.csv --seconds 10 --rate 5000 --stiffness 2 --fast\n  hostctl record release.csv --seconds 2 --stiffness 3 --delay-ticks 1 --release 20\n  hostctl record run.csv --port /dev/ttyACM0 --seconds 30 --decimation 5"
)]
pub struct Args {
    /// Output CSV file.
    pub file: PathBuf,
    /// Device time to record [s], > 0.
    #[arg(long, default_value_t = 10.0, allow_hyphen_values = true)]
    pub seconds: f64,
    /// Servo ticks per sample, 1..=65535.
    #[arg(long, default_value_t = 1, allow_hyphen_values = true)]
    pub decimation: i64,
    /// Run a release test (paper Fig. 8) from this deflection [effective ticks] while
    /// recording (needs --decimation 1).
    #[arg(long, allow_hyphen_values = true, value_name = "TICKS")]
    pub release: Option<i32>,
    /// Exit 0 even when samples were lost (they are always noted in the file).
    #[arg(long)]
    pub allow_gaps: bool,
    /// Configuration changes applied before recording (not saved).
    #[command(flatten)]
    pub set: Overrides,
    /// How to reach the device.
    #[command(flatten)]
    pub connect: ConnectArgs,
}

/// Runs `hostctl record`.
pub fn run(args: &Args) -> Result<()> {
    // Validate what can be validated before connecting.
    Plan::new(args.decimation, Some(args.seconds), 1)?;
    if let Some(d) = args.release {
        if d == 0 || d.unsigned_abs() > 1 << 20 {
            bail!("--release must be non-zero and within [-1048576, 1048576] (got {d})");
        }
    }
    crate::session::stop_on_ctrl_c();
    let (mut client, cfg) = args.set.connect_and_apply(&args.connect)?;
    let mut plan = Plan::new(args.decimation, Some(args.seconds), cfg.servo_rate_hz)?;
    plan.release = args.release;
    let h = header(&client, cfg, plan.decimation, Some(&args.connect));
    let file = std::fs::File::create(&args.file)
        .with_context(|| format!("creating {}", args.file.display()))?;
    let bar = indicatif::ProgressBar::new(plan.samples.unwrap_or(0));
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} samples {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let out = record(
        &mut client,
        &plan,
        &h,
        std::io::BufWriter::new(file),
        |st| {
            bar.set_position(st.received + st.missing);
            bar.set_message(format!("gaps {}", st.missing));
        },
    )?;
    bar.finish_and_clear();
    let n = plan.samples.unwrap_or(0);
    let msg = format!(
        "{}: {} rows of {} planned ({} Hz / decimation {}, {:.3} s device time); {}",
        args.file.display(),
        out.rows,
        n,
        cfg.servo_rate_hz,
        plan.decimation,
        n as f64 * f64::from(plan.decimation) / f64::from(cfg.servo_rate_hz.max(1)),
        out.stats.summary()
    );
    match &out.end {
        End::Complete | End::Interrupted => {
            emit(&msg)?;
            if out.stats.missing > 0 && !args.allow_gaps {
                bail!(
                    "the recording has {} missing sample(s) in {} gap(s) ({} dropped on the device, {} lost on the link); they are noted in the file; pass --allow-gaps to accept",
                    out.stats.missing,
                    out.stats.gap_events,
                    out.stats.device_dropped,
                    out.stats.link_lost
                );
            }
            Ok(())
        }
        End::Disconnected(e) => bail!(
            "the device disconnected during the recording ({e}); kept the {} samples received in {} ({})",
            out.rows,
            args.file.display(),
            out.stats.summary()
        ),
        End::Silent(d) => bail!(
            "the device sent no telemetry for {:.1} s; kept the {} samples received in {} ({})",
            d.as_secs_f64(),
            out.rows,
            args.file.display(),
            out.stats.summary()
        ),
    }
}
