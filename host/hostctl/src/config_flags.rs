//! Servo-configuration flags shared by `hostctl config set`, `stream` and `record`: the
//! fields to change on the device before anything else happens.
//!
//! Units: SI (N/m or N·m/rad, N·s/m or N·m·s/rad, N or N·m, m/s or rad/s, J, Hz); ticks,
//! counts and shifts are integers (the travel window's ends are raw encoder counts, or `off`).
//! Invariants: obviously bad numbers (NaN, infinite, negative,
//! zero where a positive value is needed) are refused on the host, naming the flag and its
//! range, before anything is sent (by `stiffwall_analysis::config_check`); the device validates
//! the rest and a refused config changes nothing.

use crate::device::connect::ConnectArgs;
use anyhow::{bail, Context, Result};
pub use stiffwall_analysis::config_check::FlagError;
use stiffwall_analysis::config_check::{int, real, travel};
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

/// One end of the travel window on the command line: a raw encoder count, or `off` (no end
/// on that side). In JSON (`hostctl ui`): an integer or `"off"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TravelEnd {
    /// No end on this side.
    Off,
    /// The end, raw encoder counts (inclusive: the window holds it).
    Counts(i32),
}

impl TravelEnd {
    /// The config field's value: `None` for `off`.
    #[must_use]
    pub fn counts(self) -> Option<i32> {
        match self {
            Self::Off => None,
            Self::Counts(n) => Some(n),
        }
    }
}

impl std::fmt::Display for TravelEnd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Off => f.write_str("off"),
            Self::Counts(n) => write!(f, "{n}"),
        }
    }
}

impl std::str::FromStr for TravelEnd {
    type Err = String;

    /// `off`, or an integer count within the `i32` range.
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "off" {
            return Ok(Self::Off);
        }
        s.parse::<i32>().map(Self::Counts).map_err(|_| {
            format!(
                "{s:?} is neither a raw encoder count (an integer within [{}, {}]) nor `off`",
                i32::MIN,
                i32::MAX
            )
        })
    }
}

impl<'de> serde::Deserialize<'de> for TravelEnd {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(serde::Deserialize)]
        #[serde(untagged)]
        enum Json {
            Counts(i64),
            Text(String),
        }
        match Json::deserialize(d)? {
            Json::Counts(n) => i32::try_from(n).map(Self::Counts).map_err(|_| {
                serde::de::Error::custom(format!(
                    "{n} is outside the raw count range [{}, {}]",
                    i32::MIN,
                    i32::MAX
                ))
            }),
            Json::Text(t) => t.parse().map_err(serde::de::Error::custom),
        }
    }
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
    /// Travel window, lower end [raw encoder counts], or `off`: the supervisor latches the
    /// `travel` fault (and the safe mode) when the raw count goes below it.
    #[arg(long, value_name = "COUNTS|off", allow_negative_numbers = true)]
    #[serde(default)]
    pub travel_min: Option<TravelEnd>,
    /// Travel window, upper end [raw encoder counts], or `off`: the `travel` fault when the
    /// raw count goes above it. With both ends, above `--travel-min`.
    #[arg(long, value_name = "COUNTS|off", allow_negative_numbers = true)]
    #[serde(default)]
    pub travel_max: Option<TravelEnd>,
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
        F::TravelMin => "--travel-min",
        F::TravelMax => "--travel-max",
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
            && self.travel_min.is_none()
            && self.travel_max.is_none()
    }

    /// `base` with the given fields changed; host-side validation of each given number.
    ///
    /// # Errors
    /// The first field out of range, named with its range.
    pub fn apply(&self, base: &ServoConfig) -> Result<ServoConfig, FlagError> {
        let mut c = *base;
        self.apply_wall(&mut c)?;
        self.apply_limits(&mut c)?;
        self.apply_supervisor(&mut c)?;
        self.apply_travel(&mut c)?;
        Ok(c)
    }

    /// The wall's law and timing: stiffness, damping, rate, delay, coarsening, mode, position.
    fn apply_wall(&self, c: &mut ServoConfig) -> Result<(), FlagError> {
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
        Ok(())
    }

    /// The output limits and the energy monitor.
    fn apply_limits(&self, c: &mut ServoConfig) -> Result<(), FlagError> {
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
        Ok(())
    }

    /// The supervisor: encoder jumps, heartbeat, safe mode and its damping, the damper.
    fn apply_supervisor(&self, c: &mut ServoConfig) -> Result<(), FlagError> {
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
        Ok(())
    }

    /// The travel window, checked as a whole when either end is given.
    fn apply_travel(&self, c: &mut ServoConfig) -> Result<(), FlagError> {
        if let Some(v) = self.travel_min {
            c.travel_min = v.counts();
        }
        if let Some(v) = self.travel_max {
            c.travel_max = v.counts();
        }
        if self.travel_min.is_some() || self.travel_max.is_some() {
            travel(c.travel_min, c.travel_max)?;
        }
        Ok(())
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

    #[test]
    fn travel_flags_set_either_end_or_turn_it_off() {
        assert_eq!("off".parse(), Ok(TravelEnd::Off));
        assert_eq!("-4000".parse(), Ok(TravelEnd::Counts(-4000)));
        for bad in ["", "Off", "1.5", "2147483648", "none"] {
            let e = bad.parse::<TravelEnd>().unwrap_err();
            assert!(e.contains("nor `off`"), "{bad:?}: {e}");
        }
        let base = ServoConfig::default();
        let both = Overrides {
            travel_min: Some(TravelEnd::Counts(-4000)),
            travel_max: Some(TravelEnd::Counts(4000)),
            ..Overrides::default()
        };
        assert!(!both.is_empty());
        let set = both.apply(&base).unwrap();
        assert_eq!(
            set,
            ServoConfig {
                travel_min: Some(-4000),
                travel_max: Some(4000),
                ..base
            }
        );
        // One end changed, the other kept; `off` removes one.
        let lower = Overrides {
            travel_min: Some(TravelEnd::Counts(3999)),
            ..Overrides::default()
        };
        assert_eq!(lower.apply(&set).unwrap().travel_min, Some(3999));
        let off = Overrides {
            travel_max: Some(TravelEnd::Off),
            ..Overrides::default()
        };
        assert_eq!(
            (
                off.apply(&set).unwrap().travel_min,
                off.apply(&set).unwrap().travel_max
            ),
            (Some(-4000), None)
        );
        // Out of order against the kept end: refused on the host.
        let crossed = Overrides {
            travel_min: Some(TravelEnd::Counts(4000)),
            ..Overrides::default()
        };
        let e = crossed.apply(&set).unwrap_err().to_string();
        assert!(
            e.starts_with("--travel-max must be above --travel-min"),
            "{e}"
        );
        assert_eq!(
            flag_name(stiffwall_proto::ConfigField::TravelMax),
            "--travel-max"
        );
        // JSON (`hostctl ui`): an integer or "off".
        let o: Overrides =
            serde_json::from_value(serde_json::json!({"travel-min": -10, "travel-max": "off"}))
                .unwrap();
        assert_eq!(
            (o.travel_min, o.travel_max),
            (Some(TravelEnd::Counts(-10)), Some(TravelEnd::Off))
        );
        for bad in [
            serde_json::json!({"travel-min": 1.5}),
            serde_json::json!({"travel-min": 3_000_000_000_i64}),
            serde_json::json!({"travel-max": "none"}),
        ] {
            assert!(
                serde_json::from_value::<Overrides>(bad.clone()).is_err(),
                "{bad}"
            );
        }
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
