//! Servo-configuration flags shared by `hostctl config set`, `stream` and `record`: the
//! fields to change on the device before anything else happens.
//!
//! Units: SI (N/m or N·m/rad, N·s/m or N·m·s/rad, N or N·m, m/s or rad/s, J, Hz); ticks,
//! counts and shifts are integers. Invariants: obviously bad numbers (NaN, infinite, negative,
//! zero where a positive value is needed) are refused on the host, naming the flag and its
//! range, before anything is sent (by `stiffwall_analysis::config_check`); the device validates
//! the rest and a refused config changes nothing.

use crate::device::connect::ConnectArgs;
use anyhow::{bail, Context, Result};
pub use stiffwall_analysis::config_check::FlagError;
use stiffwall_analysis::config_check::{int, real};
use stiffwall_client::Client;
use stiffwall_proto::{DamperLaw, ParseDamperLawError, SafeMode, ServoConfig, WallMode};

/// `on` / `off`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OnOff {
    /// Enabled.
    On,
    /// Disabled.
    Off,
}

/// Wall geometry on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WallArg {
    /// Spring on both sides of the wall position.
    Bidirectional,
    /// Wall at counts ≥ the wall position only.
    OneSided,
}

/// Safe mode on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SafeModeArg {
    /// Zero force after a fault.
    ZeroForce,
    /// Virtual damping (`--safe-damping`) after a fault.
    Damping,
}

/// Configuration fields to change; fields not given keep their current value. Shared by
/// `config set`, `stream` and `record`, and by `hostctl ui`'s `config` command, which reads it
/// from JSON with the flags' names as keys (`{"stiffness": 2, "wall": "one-sided"}`): each key
/// takes its field's type, unknown keys are refused.
#[derive(Debug, Clone, Default, clap::Args, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub struct Overrides {
    /// Wall stiffness K [N/m or N·m/rad], >= 0.
    #[arg(long, allow_negative_numbers = true)]
    pub stiffness: Option<f32>,
    /// Virtual damping B [N·s/m or N·m·s/rad], >= 0.
    #[arg(long, allow_negative_numbers = true)]
    pub damping: Option<f32>,
    /// Servo rate 1/T [Hz], >= 1 (the device enforces its own range).
    #[arg(long, allow_negative_numbers = true)]
    pub rate: Option<i64>,
    /// Extra delay T_V [servo ticks], 0..=31.
    #[arg(long, allow_negative_numbers = true)]
    pub delay_ticks: Option<i64>,
    /// Encoder coarsening shift s (Δ_eff = 2^s counts), 0..=16.
    #[arg(long, allow_negative_numbers = true)]
    pub coarsen_shift: Option<i64>,
    /// Wall geometry.
    #[arg(long, value_enum)]
    pub wall: Option<WallArg>,
    /// Wall position [raw encoder counts].
    #[arg(long, allow_negative_numbers = true)]
    pub wall_position: Option<i32>,
    /// Force limit [N or N·m], > 0.
    #[arg(long, allow_negative_numbers = true)]
    pub force_limit: Option<f32>,
    /// Over-velocity fault threshold [m/s or rad/s], >= 0 (0 disables).
    #[arg(long, allow_negative_numbers = true)]
    pub max_velocity: Option<f32>,
    /// Energy monitor.
    #[arg(long, value_enum)]
    pub energy_monitor: Option<OnOff>,
    /// Energy fault threshold on H_T (35) [J], > 0.
    #[arg(long, allow_negative_numbers = true)]
    pub energy_limit: Option<f32>,
    /// Growing oscillation peaks that trip the energy fault, 1..=64.
    #[arg(long, allow_negative_numbers = true)]
    pub energy_growth_cycles: Option<i64>,
    /// Encoder-jump fault threshold [raw counts per tick], >= 1.
    #[arg(long, allow_negative_numbers = true)]
    pub encoder_jump: Option<i64>,
    /// Heartbeat timeout during experiments [ms], >= 0 (0 disables).
    #[arg(long, allow_negative_numbers = true)]
    pub heartbeat_timeout_ms: Option<i64>,
    /// Behaviour after a fault.
    #[arg(long, value_enum)]
    pub safe_mode: Option<SafeModeArg>,
    /// Virtual damping in safe mode `damping` [N·s/m or N·m·s/rad], >= 0.
    #[arg(long, allow_negative_numbers = true)]
    pub safe_damping: Option<f32>,
    /// How the wall's virtual damper turns the count difference dn into a velocity:
    /// `difference` (v = dn) or `dead-band-N` (v = 0 while |dn| <= N counts per tick, N in
    /// 1..=8).
    #[arg(long, value_name = "difference|dead-band-N", value_parser = parse_damper)]
    #[serde(default, deserialize_with = "deserialize_damper")]
    pub damper: Option<DamperLaw>,
}

/// `--damper`'s value: exactly `difference` or `dead-band-N` (N in 1..=8).
///
/// # Errors
/// The allowed forms, or the dead band's range.
pub fn parse_damper(s: &str) -> Result<DamperLaw, ParseDamperLawError> {
    s.parse()
}

/// `damper` of a JSON `set` (`hostctl ui`): the flag's text form, `"dead-band-1"`.
fn deserialize_damper<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<DamperLaw>, D::Error> {
    let s = <String as serde::Deserialize>::deserialize(d)?;
    parse_damper(&s)
        .map(Some)
        .map_err(|e| serde::de::Error::custom(format!("{s:?}: {e}")))
}

/// The `hostctl` flag that sets a config field (`--stiffness` for `ConfigField::Stiffness`), or
/// the field's own name for fields no flag sets.
#[must_use]
pub fn flag_name(field: stiffwall_proto::ConfigField) -> &'static str {
    use stiffwall_proto::ConfigField as F;
    match field {
        F::Stiffness => "--stiffness",
        F::Damping => "--damping",
        F::ServoRateHz => "--rate",
        F::ExtraDelayTicks => "--delay-ticks",
        F::CoarsenShift => "--coarsen-shift",
        F::Wall => "--wall",
        F::WallPosition => "--wall-position",
        F::ForceLimit => "--force-limit",
        F::MaxVelocity => "--max-velocity",
        F::EnergyMonitor => "--energy-monitor",
        F::EnergyLimit => "--energy-limit",
        F::EnergyGrowthCycles => "--energy-growth-cycles",
        F::EncoderJumpCounts => "--encoder-jump",
        F::HeartbeatTimeoutMs => "--heartbeat-timeout-ms",
        F::SafeMode => "--safe-mode",
        F::SafeDamping => "--safe-damping",
        F::Damper => "--damper",
        F::Argument => "argument",
    }
}

impl Overrides {
    /// `true` when no field is given.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.stiffness.is_none()
            && self.damping.is_none()
            && self.rate.is_none()
            && self.delay_ticks.is_none()
            && self.coarsen_shift.is_none()
            && self.wall.is_none()
            && self.wall_position.is_none()
            && self.force_limit.is_none()
            && self.max_velocity.is_none()
            && self.energy_monitor.is_none()
            && self.energy_limit.is_none()
            && self.energy_growth_cycles.is_none()
            && self.encoder_jump.is_none()
            && self.heartbeat_timeout_ms.is_none()
            && self.safe_mode.is_none()
            && self.safe_damping.is_none()
            && self.damper.is_none()
    }

    /// `base` with the given fields changed; host-side validation of each given number.
    ///
    /// # Errors
    /// The first field out of range, named with its range.
    pub fn apply(&self, base: &ServoConfig) -> Result<ServoConfig, FlagError> {
        let mut c = *base;
        if let Some(v) = self.stiffness {
            c.stiffness = real("stiffness", v, false)?;
        }
        if let Some(v) = self.damping {
            c.damping = real("damping", v, false)?;
        }
        if let Some(v) = self.rate {
            c.servo_rate_hz = int("rate", v, 1, i64::from(u32::MAX))?;
        }
        if let Some(v) = self.delay_ticks {
            c.extra_delay_ticks = int(
                "delay-ticks",
                v,
                0,
                i64::from(stiffwall_proto::MAX_DELAY_TICKS),
            )?;
        }
        if let Some(v) = self.coarsen_shift {
            c.coarsen_shift = int(
                "coarsen-shift",
                v,
                0,
                i64::from(stiffwall_proto::MAX_COARSEN_SHIFT),
            )?;
        }
        if let Some(w) = self.wall {
            c.wall = match w {
                WallArg::Bidirectional => WallMode::Bidirectional,
                WallArg::OneSided => WallMode::OneSided,
            };
        }
        if let Some(v) = self.wall_position {
            c.wall_position = v;
        }
        if let Some(v) = self.force_limit {
            c.force_limit = real("force-limit", v, true)?;
        }
        if let Some(v) = self.max_velocity {
            c.max_velocity = real("max-velocity", v, false)?;
        }
        if let Some(v) = self.energy_monitor {
            c.energy_monitor = v == OnOff::On;
        }
        if let Some(v) = self.energy_limit {
            c.energy_limit = real("energy-limit", v, true)?;
        }
        if let Some(v) = self.energy_growth_cycles {
            c.energy_growth_cycles = int("energy-growth-cycles", v, 1, 64)?;
        }
        if let Some(v) = self.encoder_jump {
            c.encoder_jump_counts = int("encoder-jump", v, 1, i64::from(u32::MAX))?;
        }
        if let Some(v) = self.heartbeat_timeout_ms {
            c.heartbeat_timeout_ms = int("heartbeat-timeout-ms", v, 0, i64::from(u32::MAX))?;
        }
        if let Some(v) = self.safe_mode {
            c.safe_mode = match v {
                SafeModeArg::ZeroForce => SafeMode::ZeroForce,
                SafeModeArg::Damping => SafeMode::Damping,
            };
        }
        if let Some(v) = self.safe_damping {
            c.safe_damping = real("safe-damping", v, false)?;
        }
        if let Some(d) = self.damper {
            // Parsed values are in range; a value built otherwise is checked as the text is.
            c.damper = parse_damper(&d.to_string())
                .map_err(|reason| FlagError::Damper { value: d, reason })?;
        }
        Ok(c)
    }

    /// Validates on the host, then reads, changes and writes the device's config. Returns the
    /// config now active (re-read from the device).
    pub fn set_on(&self, client: &mut Client) -> Result<ServoConfig> {
        // Validate before talking to the device at all.
        self.apply(&ServoConfig::default())?;
        let cur = client.get_config()?;
        let new = self.apply(&cur)?;
        if new != cur {
            client.set_config(&new)?;
        }
        let now = client.get_config()?;
        if now != new {
            bail!("the device reports a different configuration than the one it accepted: {now:?}");
        }
        Ok(now)
    }

    /// Connects (after validating these changes on the host) and applies them, if any; returns
    /// the client and the active configuration. Shared by `stream` and `record`.
    pub fn connect_and_apply(&self, connect: &ConnectArgs) -> Result<(Client, ServoConfig)> {
        self.apply(&ServoConfig::default())?;
        let mut client = connect.connect()?;
        let cfg = if self.is_empty() {
            client.get_config()?
        } else {
            self.set_on(&mut client)
                .context("applying the config changes")?
        };
        Ok((client, cfg))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn damper_flag_takes_exactly_the_laws_text_forms() {
        assert_eq!(parse_damper("difference"), Ok(DamperLaw::Difference));
        assert_eq!(
            parse_damper("dead-band-3"),
            Ok(DamperLaw::DeadBand { counts: 3 })
        );
        let e = parse_damper("dead-band-0").unwrap_err().to_string();
        assert_eq!(
            e,
            "dead band 0 counts is outside 1..=8 (use `difference` for no dead band)"
        );
        let e = parse_damper("deadband").unwrap_err().to_string();
        assert!(e.contains("`difference` and `dead-band-N`"), "{e}");
        assert_eq!(flag_name(stiffwall_proto::ConfigField::Damper), "--damper");
    }

    #[test]
    fn damper_override_sets_the_law_and_nothing_else() {
        let base = ServoConfig {
            damper: DamperLaw::Difference,
            ..ServoConfig::default()
        };
        let o = Overrides {
            damper: Some(DamperLaw::DeadBand { counts: 2 }),
            ..Overrides::default()
        };
        assert!(!o.is_empty());
        let got = o.apply(&base).unwrap();
        assert_eq!(
            got,
            ServoConfig {
                damper: DamperLaw::DeadBand { counts: 2 },
                ..base
            }
        );
        // A law built past the parser is checked as its text would be.
        let bad = Overrides {
            damper: Some(DamperLaw::DeadBand { counts: 9 }),
            ..Overrides::default()
        };
        assert_eq!(
            bad.apply(&base).unwrap_err().to_string(),
            "--damper dead-band-9: dead band 9 counts is outside 1..=8 (use `difference` for no \
             dead band)"
        );
    }

    /// `hostctl ui`'s JSON `set` spells the law as the flag does.
    #[test]
    fn damper_reads_from_json_as_text() {
        let o: Overrides =
            serde_json::from_value(serde_json::json!({"damper": "difference"})).unwrap();
        assert_eq!(o.damper, Some(DamperLaw::Difference));
        let o: Overrides = serde_json::from_value(serde_json::json!({})).unwrap();
        assert_eq!(o.damper, None);
        for bad in [
            serde_json::json!({"damper": "dead-band-0"}),
            serde_json::json!({"damper": "Difference"}),
            serde_json::json!({"damper": 1}),
            serde_json::json!({"damper": {"DeadBand": {"counts": 1}}}),
        ] {
            let e = serde_json::from_value::<Overrides>(bad.clone())
                .unwrap_err()
                .to_string();
            assert!(!e.is_empty(), "{bad}");
        }
        let e = serde_json::from_value::<Overrides>(serde_json::json!({"damper": "dead-band-0"}))
            .unwrap_err()
            .to_string();
        assert!(e.contains("dead-band-0") && e.contains("1..=8"), "{e}");
    }
}
