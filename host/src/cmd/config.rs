//! `hostctl config`: read, change, save or reset the device's servo configuration.
//!
//! Units: SI (N/m or N·m/rad, N·s/m or N·m·s/rad, N or N·m, m/s or rad/s, J, Hz); ticks,
//! counts and shifts are integers. `set` reads the active config, changes only the fields
//! given, and sends it back; the device validates it and a refused config changes nothing
//! (the device's error names the field and its range). Obviously bad numbers (NaN, infinite,
//! negative, zero where a positive value is needed) are refused on the host before anything
//! is sent. Nothing is persisted unless `save` is run.

use super::info::emit;
use crate::device::connect::ConnectArgs;
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use stiffwall_proto::{SafeMode, ServoConfig, WallMode};

/// Arguments of `hostctl config`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  hostctl config get --json\n  hostctl config set --stiffness 2.5 --delay-ticks 1\n  hostctl config set --rate 5000 --energy-monitor off\n  hostctl config save\n  hostctl config defaults\n\nThe built-in virtual device starts afresh with every hostctl run, so a `config set` on it\nlasts for that run only: `stream` and `record` take the same field flags (e.g.\n`hostctl record out.csv --stiffness 2 --rate 5000`)."
)]
pub struct Args {
    /// What to do.
    #[command(subcommand)]
    pub action: Action,
    /// How to reach the device.
    #[command(flatten)]
    pub connect: ConnectArgs,
    /// Print the resulting configuration as JSON.
    #[arg(long, global = true)]
    pub json: bool,
}

/// `config` actions.
#[derive(Debug, clap::Subcommand)]
pub enum Action {
    /// Print the active configuration.
    Get,
    /// Change the given fields of the active configuration (not persisted).
    Set(Overrides),
    /// Persist the active configuration to the device's config store.
    Save,
    /// Apply the firmware defaults (not persisted) and print them.
    Defaults,
}

/// `on` / `off`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OnOff {
    /// Enabled.
    On,
    /// Disabled.
    Off,
}

/// Wall geometry on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WallArg {
    /// Spring on both sides of the wall position.
    Bidirectional,
    /// Wall at counts ≥ the wall position only.
    OneSided,
}

/// Safe mode on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SafeModeArg {
    /// Zero force after a fault.
    ZeroForce,
    /// Virtual damping (`--safe-damping`) after a fault.
    Damping,
}

/// Configuration fields to change; fields not given keep their current value. Shared by
/// `config set`, `stream` and `record`.
#[derive(Debug, Clone, Default, clap::Args)]
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
}

fn real(name: &str, v: f32, positive: bool) -> Result<f32> {
    let ok = v.is_finite() && if positive { v > 0.0 } else { v >= 0.0 };
    if !ok {
        bail!(
            "--{name} must be a finite number {} (got {v})",
            if positive { "> 0" } else { ">= 0" }
        );
    }
    Ok(v)
}

fn int<T: TryFrom<i64>>(name: &str, v: i64, lo: i64, hi: i64) -> Result<T> {
    if v < lo || v > hi {
        bail!("--{name} must be within [{lo}, {hi}] (got {v})");
    }
    T::try_from(v).map_err(|_| anyhow::anyhow!("--{name} must be within [{lo}, {hi}] (got {v})"))
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
    }

    /// `base` with the given fields changed; host-side validation of each given number.
    pub fn apply(&self, base: &ServoConfig) -> Result<ServoConfig> {
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
        Ok(c)
    }

    /// Validates on the host, then reads, changes and writes the device's config. Returns the
    /// config now active (re-read from the device).
    pub fn set_on(&self, client: &mut crate::device::client::Client) -> Result<ServoConfig> {
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
    pub fn connect_and_apply(
        &self,
        connect: &crate::device::connect::ConnectArgs,
    ) -> Result<(crate::device::client::Client, ServoConfig)> {
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

/// Text rendering of a configuration.
#[must_use]
pub fn render(c: &ServoConfig) -> String {
    let mut s = String::new();
    let rows: [(&str, String); 16] = [
        ("stiffness", format!("{} N/m (N·m/rad)", c.stiffness)),
        ("damping", format!("{} N·s/m (N·m·s/rad)", c.damping)),
        ("rate", format!("{} Hz", c.servo_rate_hz)),
        ("delay-ticks", c.extra_delay_ticks.to_string()),
        ("coarsen-shift", c.coarsen_shift.to_string()),
        (
            "wall",
            match c.wall {
                WallMode::Bidirectional => "bidirectional".into(),
                WallMode::OneSided => "one-sided".into(),
            },
        ),
        ("wall-position", format!("{} counts", c.wall_position)),
        ("force-limit", format!("{} N (N·m)", c.force_limit)),
        (
            "max-velocity",
            if c.max_velocity > 0.0 {
                format!("{} m/s (rad/s)", c.max_velocity)
            } else {
                "off".into()
            },
        ),
        (
            "energy-monitor",
            if c.energy_monitor { "on" } else { "off" }.into(),
        ),
        ("energy-limit", format!("{} J", c.energy_limit)),
        ("energy-growth-cycles", c.energy_growth_cycles.to_string()),
        (
            "encoder-jump",
            format!("{} counts/tick", c.encoder_jump_counts),
        ),
        (
            "heartbeat-timeout-ms",
            if c.heartbeat_timeout_ms > 0 {
                c.heartbeat_timeout_ms.to_string()
            } else {
                "off".into()
            },
        ),
        (
            "safe-mode",
            match c.safe_mode {
                SafeMode::ZeroForce => "zero-force".into(),
                SafeMode::Damping => "damping".into(),
            },
        ),
        (
            "safe-damping",
            format!("{} N·s/m (N·m·s/rad)", c.safe_damping),
        ),
    ];
    for (k, v) in rows {
        let _ = writeln!(s, "{k:<21} {v}");
    }
    s.pop();
    s
}

/// Runs `hostctl config`.
pub fn run(args: &Args) -> Result<()> {
    if let Action::Set(o) = &args.action {
        // Refuse bad numbers before connecting.
        o.apply(&ServoConfig::default())?;
        if o.is_empty() {
            bail!(
                "config set: give at least one field to change (see `hostctl config set --help`)"
            );
        }
    }
    let mut c = args.connect.connect()?;
    let (cfg, what) = match &args.action {
        Action::Get => (c.get_config()?, None),
        Action::Set(o) => (
            o.set_on(&mut c).context("config set")?,
            Some("set (not saved)"),
        ),
        Action::Save => {
            c.save_config().context("config save")?;
            (c.get_config()?, Some("saved"))
        }
        Action::Defaults => (
            c.load_defaults().context("config defaults")?,
            Some("firmware defaults applied (not saved)"),
        ),
    };
    if args.json {
        emit(&serde_json::to_string_pretty(&cfg)?)?;
    } else {
        if let Some(w) = what {
            emit(&format!("# {w} on {}", args.connect.describe()))?;
        }
        emit(&render(&cfg))?;
    }
    Ok(())
}
