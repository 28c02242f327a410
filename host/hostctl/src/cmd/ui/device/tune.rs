//! The page's tune, run by the device thread with the tune library ([`stiffwall_tune::tune`]):
//! settings checked in the page's words, every progress event published (`tune` events with
//! `state: "running"`, the message and the typed event), the operation's token as the tune's
//! [`stiffwall_client::Cancel`] (the page's Abort ends it; the previous config is restored),
//! and the telemetry stream paused meanwhile (the pages show "not live").

use super::state::Dev;
use crate::cmd::ui::wire::{Reply, TuneTest};
use anyhow::{anyhow, bail, Result};
use serde_json::{json, Value};
use std::sync::Arc;
use stiffwall_analysis::live::plane::Model;
use stiffwall_tune::{Settings, SettingsError, TuneError};

/// The page's label of a tune setting.
fn page_label(field: &str) -> &str {
    match field {
        "max_velocity" => "max velocity",
        "excite_seconds" => "excitation seconds",
        "release_ticks" => "release ticks",
        "dry_run" => "dry run",
        "rel_tol" => "tolerance",
        other => other,
    }
}

/// A settings error in the page's words.
pub fn page_error(e: &SettingsError) -> String {
    format!(
        "{} must be {} (got {})",
        page_label(e.field),
        e.range,
        e.got
    )
}

/// The page's tune fields as the library's settings, checked in the page's words.
///
/// # Errors
/// The first field out of range.
pub fn page_settings(a: &TuneTest) -> Result<Settings, String> {
    let d = Settings::default();
    let s = Settings {
        max_velocity: a.max_velocity,
        margin: a.margin.unwrap_or(d.margin),
        release_ticks: a.release_ticks,
        excite_seconds: a.excite_seconds.unwrap_or(d.excite_seconds),
        dry_run: a.dry_run,
        ..d
    };
    s.validate().map_err(|e| page_error(&e))?;
    Ok(s)
}

impl Dev {
    pub(super) fn tune(&mut self, a: &TuneTest) -> Reply {
        let r = self.tune_run(a);
        self.finish_op();
        if let Err(e) = &r {
            self.shared.publish(
                "tune",
                json!({"type": "tune", "state": if e == ABORTED { "aborted" } else { "error" },
                       "error": e}),
            );
            if !self.streaming {
                if let Err(e2) = self.start_stream() {
                    self.shared.event(&json!({"type": "log", "level": "error",
                        "message": format!("restarting telemetry: {}", crate::cli_error::message(&e2))}));
                }
            }
        }
        if let Ok(cfg) = self.client.get_config() {
            self.cfg = cfg;
        }
        self.publish_config();
        self.poll_faults();
        r
    }

    fn tune_run(&mut self, a: &TuneTest) -> Reply {
        let s = page_settings(a)?;
        let prepare = || -> Result<()> {
            self.busy_check("tune")?;
            if let Some(r) = &self.rec {
                bail!(
                    "tune: stop the recording to {} first (tune's experiments take the telemetry stream)",
                    r.path.display()
                );
            }
            Ok(())
        };
        prepare().map_err(|e| crate::cli_error::message(&e))?;
        // Flush what the page has, then give the link to tune.
        self.client
            .stream_stop()
            .map_err(|e| format!("stopping telemetry: {e}"))?;
        self.streaming = false;
        self.status();
        let shared = Arc::clone(&self.shared);
        shared.publish(
            "tune",
            json!({"type": "tune", "state": "running", "message": "starting"}),
        );
        let cancel = self.shared.control.op_cancel().unwrap_or_default();
        let outcome = stiffwall_tune::tune(&mut self.client, &s, &cancel, &mut |event| {
            shared.publish(
                "tune",
                json!({"type": "tune", "state": "running", "message": event.to_string(),
                       "event": event}),
            );
        });
        let restart = self.start_stream();
        let o = match outcome {
            Ok(o) => o,
            Err(TuneError::Cancelled) => return Err(ABORTED.into()),
            Err(TuneError::Settings(e)) => return Err(page_error(&e)),
            Err(e) => {
                return Err(format!(
                    "tune failed; the previous config was restored: {e}"
                ))
            }
        };
        restart.map_err(|e| crate::cli_error::message(&anyhow!(e)))?;
        self.setup.model = Some(Model {
            mass: o.params.mass,
            viscous: o.params.viscous,
            coulomb: o.params.coulomb,
            source: "identified by tune",
        });
        let v = done_event(&o);
        self.shared.publish("tune", v.clone());
        Ok(v)
    }
}

/// The answer to an aborted tune.
const ABORTED: &str = "tune aborted; the previous config was restored";

fn done_event(o: &stiffwall_tune::Outcome) -> Value {
    json!({
        "type": "tune",
        "state": "done",
        "guaranteed": o.predicted.guaranteed,
        "expected": o.predicted.expected,
        // The largest resting K at the damping set (the spring-only search's when B = 0), of
        // which the set K is the margin's fraction.
        "verified": o
            .frontier
            .iter()
            .find(|p| p.b == o.b_set)
            .and_then(|p| p.k_verified)
            .unwrap_or(o.search.k_pass),
        "set": o.k_set,
        "damping": o.b_set,
        "damper": o.damper,
        "rests": o.rests,
        "quiet_ceiling": o.quiet_ceiling,
        "no_rest": o.no_rest,
        "spring_only": o.k_spring_only,
        "frontier": o.frontier,
        "saved": o.saved,
        "trials": o.search.trials,
        "verification": o.verification,
        "model_mismatch": o.model_mismatch,
        "identified": o.identified,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_errors_in_the_page_words() {
        let bad = TuneTest {
            margin: Some(1.5),
            ..TuneTest::default()
        };
        assert_eq!(
            page_settings(&bad).unwrap_err(),
            "margin must be in (0, 1] (got 1.5)"
        );
        let bad = TuneTest {
            max_velocity: Some(-1.0),
            ..TuneTest::default()
        };
        assert_eq!(
            page_settings(&bad).unwrap_err(),
            "max velocity must be finite and in [0, 100] m/s, or [0, 1e4] rad/s on a rotary \
             device, and > 0 (got -1)"
        );
    }
}
