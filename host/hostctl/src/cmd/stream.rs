//! `hostctl stream`: show live telemetry from the device in one refreshing terminal line.
//!
//! Units: tick (servo ticks), count (raw encoder counts from the wall position), force (output
//! codes and N or N·m), energy (H_T potential part, units of K·Δ_eff²/8), rate (samples per
//! wall second). Gaps in the device's sample numbers are counted and attributed (device
//! queue vs link), never hidden. `--seconds` is device time, as for `hostctl record`.

use crate::config_flags::Overrides;
use crate::device::connect::ConnectArgs;
use crate::output::emit;
use anyhow::{bail, Result};
use std::io::IsTerminal as _;
use std::time::{Duration, Instant};
use stiffwall_client::{pump, End, Plan};

/// Arguments of `hostctl stream`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  hostctl stream\n  hostctl stream --decimation 10 --seconds 5 --stiffness 2"
)]
pub struct Args {
    /// Servo ticks per sample, 1..=65535.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub decimation: i64,
    /// Device time to stream [s], > 0; default: until Ctrl-C.
    #[arg(long, allow_negative_numbers = true)]
    pub seconds: Option<f64>,
    /// Configuration changes applied before streaming (not saved).
    #[command(flatten)]
    pub set: Overrides,
    /// How to reach the device.
    #[command(flatten)]
    pub connect: ConnectArgs,
}

/// Runs `hostctl stream`.
pub fn run(args: &Args) -> Result<()> {
    Plan::new(args.decimation, args.seconds, 1)?;
    crate::session::stop_on_ctrl_c();
    let (mut client, cfg) = args.set.connect_and_apply(&args.connect)?;
    let plan = Plan::new(args.decimation, args.seconds, cfg.servo_rate_hz)?;
    let fpc = f64::from(client.info.force_per_code);
    let tty = std::io::stderr().is_terminal();
    let bar = indicatif::ProgressBar::new_spinner();
    if !tty {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let mut last_draw = Instant::now() - Duration::from_secs(1);
    let mut window = (Instant::now(), 0u64);
    let mut rate = 0.0;
    let mut line = String::new();
    let (end, st) = pump(&mut client, &plan, |_seq, samples, _m, _d, st| {
        if last_draw.elapsed() >= Duration::from_millis(100) {
            let dt = window.0.elapsed().as_secs_f64();
            if dt > 0.0 {
                rate = (st.received - window.1) as f64 / dt;
            }
            window = (Instant::now(), st.received);
            if let Some(s) = samples.last() {
                line = format!(
                    "tick {:>10}  count {:>7}  force {:>6} ({:+.4})  energy {:>8}  flags {:#06x}  {:>7.0} S/s  gaps {} (dev {}, link {}) bad {}",
                    s.tick,
                    s.count,
                    s.force_code,
                    f64::from(s.force_code) * fpc,
                    s.energy,
                    s.flags,
                    rate,
                    st.missing,
                    st.device_dropped,
                    st.link_lost,
                    st.bad_frames
                );
                bar.set_message(line.clone());
            }
            last_draw = Instant::now();
        }
        Ok(())
    })?;
    bar.finish_and_clear();
    if !line.is_empty() {
        emit(&format!("last: {line}"))?;
    }
    emit(&format!(
        "stream ({} Hz / decimation {}): {}",
        cfg.servo_rate_hz,
        plan.decimation,
        st.summary()
    ))?;
    match end {
        End::Complete | End::Interrupted => Ok(()),
        End::Disconnected(e) => bail!("the device disconnected: {e}"),
        End::Silent(d) => bail!("the device sent no telemetry for {:.1} s", d.as_secs_f64()),
    }
}
