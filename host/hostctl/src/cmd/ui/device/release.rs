//! The page's release test, run inside the telemetry stream by the device thread: checked in
//! the page's words (its fields are "deflection", "duration" and "K"), capped at
//! [`MAX_RELEASE_SECONDS`] of device time, abortable (the `abort` command cancels the
//! operation's token: the device is told to stop, the test ends and the previous config is
//! restored), and answered with a verdict and a decimated trace when it ends.
//!
//! Units: deflection in effective encoder ticks, duration in servo ticks, K in N/m (N·m/rad).
//! Memory: the released counts are 8 bytes per tick while the test runs (at most
//! [`MAX_RELEASE_SECONDS`] × the servo rate); only their decimated trace is kept.

use super::state::{Dev, Release};
use crate::cmd::ui::wire;
use crate::cmd::ui::wire::ReleaseTest;
use anyhow::{bail, Result};
use serde_json::json;
use std::time::{Duration, Instant};
use stiffwall_analysis::live::trace;
use stiffwall_analysis::release;
use stiffwall_client::HEARTBEAT_PERIOD;
use stiffwall_proto::HostMsg;
use stiffwall_tune::classify;

/// Longest release test the page runs, s of device time (duration ≤ this × the servo rate):
/// a release settles or fails within a few hundred natural periods (well under a minute on
/// any device), but a soak of a wall left running is a use too; 20 minutes holds 10⁶ ticks at
/// 1 kHz (9.6 MB of counts while it runs) and refuses the hours that 10⁷ ticks would take.
pub const MAX_RELEASE_SECONDS: f64 = 1200.0;

/// The page's checks of a release test's fields, in its words; `rate_hz` caps the duration.
///
/// # Errors
/// The first field out of range, named as the page labels it.
pub fn check_release_fields(a: &ReleaseTest, rate_hz: u32) -> Result<()> {
    if a.deflection == 0 || a.deflection.unsigned_abs() > 1 << 20 {
        bail!(
            "deflection must be non-zero and within [-1048576, 1048576] ticks (got {})",
            a.deflection
        );
    }
    let max_ticks = (MAX_RELEASE_SECONDS * f64::from(rate_hz.max(1))) as u32;
    if !(100..=max_ticks).contains(&a.ticks) {
        bail!(
            "duration must be within [100, {max_ticks}] ticks ({MAX_RELEASE_SECONDS} s at the \
             device's {rate_hz} Hz; got {})",
            a.ticks
        );
    }
    if let Some(k) = a.stiffness {
        if !(k.is_finite() && k > 0.0) {
            bail!("K must be finite and > 0 (got {k})");
        }
    }
    Ok(())
}

impl Dev {
    pub(super) fn release_start(&mut self, a: &ReleaseTest) -> Result<()> {
        self.busy_check("release")?;
        let original = self.client.get_config()?;
        check_release_fields(a, original.servo_rate_hz)?;
        let max_k = self.client.info.limits.max_stiffness;
        let Ok(test) = release::config(&original, a.stiffness, max_k) else {
            bail!(
                "the wall is off (K = 0): enter the test's stiffness in the release test's K \
                 field (> 0 and ≤ {} {} on this device), or set K in Config",
                stiffwall_client::readable(f64::from(max_k)),
                if self.client.info.counts_per_rev > 0 {
                    "N·m/rad"
                } else {
                    "N/m"
                }
            );
        };
        // As `experiment release`: faults cleared, the test's K set, the original restored.
        self.client.clear_faults().ok();
        self.client.set_config(&test)?;
        let rate = f64::from(test.servo_rate_hz.max(1));
        if let Err(e) = self.client.request(&HostMsg::Release {
            deflection_ticks: a.deflection,
            ticks: a.ticks,
        }) {
            let _ = self.client.set_config(&original);
            return Err(e.into());
        }
        self.poll_faults();
        self.shared.publish(
            "release",
            json!({"type": "release", "state": "running", "deflection": a.deflection,
                   "ticks": a.ticks, "stiffness": test.stiffness,
                   "seconds": f64::from(a.ticks) / rate}),
        );
        self.release = Some(Release {
            original,
            test,
            deflection: a.deflection,
            counts: Vec::with_capacity(a.ticks as usize),
            first_tick: None,
            start: Instant::now(),
            limit: Duration::from_secs_f64(f64::from(a.ticks) / rate * 20.0 + 10.0),
            last_hb: Instant::now(),
            aborted: false,
            reply: None,
        });
        Ok(())
    }

    /// Heartbeats, the page's abort and the time-out of a running release test.
    pub(super) fn release_tick(&mut self) -> Result<()> {
        let cancelled = self
            .shared
            .control
            .op_cancel()
            .is_some_and(|c| c.is_cancelled());
        let Some(rel) = &mut self.release else {
            return Ok(());
        };
        if rel.last_hb.elapsed() >= HEARTBEAT_PERIOD {
            self.client.send(&HostMsg::Heartbeat)?;
            rel.last_hb = Instant::now();
        }
        if cancelled && !rel.aborted {
            // The device ends the test and reports it (`release_done`).
            self.client.send(&HostMsg::Stop)?;
            rel.aborted = true;
        }
        if rel.start.elapsed() > rel.limit {
            let _ = self.client.send(&HostMsg::Stop);
            let rel = self.release.take().expect("release");
            let msg = format!(
                "the release test did not finish within {} s",
                rel.limit.as_secs()
            );
            let _ = self.client.set_config(&rel.original);
            self.shared.publish(
                "release",
                json!({"type": "release", "state": "error", "error": msg}),
            );
            self.finish_op();
            if let Some(tx) = rel.reply {
                let _ = tx.send(Err(msg));
            }
        }
        Ok(())
    }

    pub(super) fn release_done(&mut self, completed: bool, faults: u32) {
        let Some(mut rel) = self.release.take() else {
            return;
        };
        // The experiment's stiffness is not kept.
        let restored = self.client.set_config(&rel.original);
        self.finish_op();
        if rel.aborted {
            let msg = "release test aborted; the previous config was restored";
            self.shared.publish(
                "release",
                json!({"type": "release", "state": "aborted", "error": msg}),
            );
            if let Some(tx) = rel.reply.take() {
                let _ = tx.send(Err(msg.into()));
            }
            return;
        }
        let counts = std::mem::take(&mut rel.counts);
        let verdict = classify(&counts, faults != 0);
        let first = rel.first_tick.unwrap_or(0);
        // The page gets a bounded trace; the full one is in a recording.
        let trace = trace::decimate(&counts, trace::TRACE_POINTS);
        drop(counts);
        let v = json!({
            "type": "release",
            "state": "done",
            "verdict": verdict,
            "describe": verdict.describe(),
            "passes": verdict.passes(),
            "deflection": rel.deflection,
            "stiffness": rel.test.stiffness,
            "completed": completed,
            "faults": faults,
            "fault_names": wire::fault_names(faults),
            "trace": trace,
            "first_tick": first,
            "rate_hz": rel.test.servo_rate_hz,
        });
        self.shared.publish("release", v.clone());
        if faults != 0 {
            self.poll_faults();
        }
        let reply = match restored {
            Ok(()) => Ok(v),
            Err(e) => Err(format!(
                "the test ran ({}), but restoring the configuration failed: {e_text}",
                verdict.describe(),
                e_text = crate::cli_error::message(&e)
            )),
        };
        if let Some(tx) = rel.reply.take() {
            let _ = tx.send(reply);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn test(deflection: i32, ticks: u32, stiffness: Option<f64>) -> ReleaseTest {
        ReleaseTest {
            deflection,
            ticks,
            stiffness,
        }
    }

    #[test]
    fn the_page_words_and_the_rate_cap() {
        let e = check_release_fields(&test(0, 3000, None), 1000).unwrap_err();
        assert_eq!(
            e.to_string(),
            "deflection must be non-zero and within [-1048576, 1048576] ticks (got 0)"
        );
        // 1200 s at 1 kHz: 1.2 × 10⁶ ticks; 10⁷ (2.8 h) is refused, naming the cap and rate.
        assert!(check_release_fields(&test(20, 1_000_000, None), 1000).is_ok());
        let e = check_release_fields(&test(20, 10_000_000, None), 1000).unwrap_err();
        assert_eq!(
            e.to_string(),
            "duration must be within [100, 1200000] ticks (1200 s at the device's 1000 Hz; got \
             10000000)"
        );
        assert!(check_release_fields(&test(20, 1_000_000, None), 500).is_err());
        let e = check_release_fields(&test(20, 3000, Some(-1.0)), 1000).unwrap_err();
        assert_eq!(e.to_string(), "K must be finite and > 0 (got -1)");
    }
}
