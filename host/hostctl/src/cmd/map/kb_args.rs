//! The flags of `hostctl map --k-b` and the device they describe, resolved once into a
//! [`Plant`] (`stiffwall_analysis::kb`).
//!
//! Units: SI. A linear device: m [kg], b [N·s/m], c [N], Δ [m], K [N/m], B [N·s/m]; a
//! rotational one: kg·m², N·m·s/rad, N·m, rad, N·m/rad, N·m·s/rad. T and T_D in s.
//!
//! The device comes from exactly one of: a plant file (`--plant FILE`, the scene format of
//! `sim/plants/`, read as `hostctl tune --plant` reads it: `[device]` m, b, c, Δ and
//! `[controller]` period and extra delay; its stiffness is not used), a preset (`--device`,
//! whose m, b, c `--mass`, `--viscous`, `--coulomb` may override) or all of `--mass`,
//! `--viscous`, `--coulomb`, `--resolution`, `--period` (`--delay` 0 by default). Invariant:
//! every value is checked by `stiffwall-core`'s ranges, errors name the flag.

use crate::plant_args::{PlantArgs, PlantSpecError};
use anyhow::{anyhow, Context, Result};
use std::path::{Path, PathBuf};
pub use stiffwall_analysis::kb::Plant;
use stiffwall_core::params::check_positive;
use stiffwall_proto::DamperLaw;
use stiffwall_sim::rich::WallDamper;

/// Flags of the (K, B) map (`hostctl map --k-b`).
#[derive(Debug, Clone, Default, clap::Args)]
pub struct KbArgs {
    /// Map the (K, B) plane of one physical device instead of the (beta, sigma) plane.
    #[arg(
        long = "k-b",
        conflicts_with_all = ["mu", "tau_d", "beta", "sigma", "shard", "overlay", "beta_v"]
    )]
    pub k_b: bool,
    /// With --k-b: K axis lo:hi:n, N/m (N·m/rad for rotational devices), lo > 0.
    #[arg(long, requires = "k_b", allow_hyphen_values = true)]
    pub k_axis: Option<String>,
    /// With --k-b: virtual damping B axis lo:hi:n, N·s/m (N·m·s/rad), lo >= 0,
    /// B/(K*T) <= 1000 at the smallest K.
    #[arg(long, requires = "k_b", allow_hyphen_values = true)]
    pub b_axis: Option<String>,
    /// With --k-b: the device as a plant file (sim/plants/NAME.toml).
    #[arg(
        long = "plant",
        value_name = "FILE",
        requires = "k_b",
        conflicts_with = "device"
    )]
    pub plant_file: Option<PathBuf>,
    /// With --k-b: the device preset and m, b, c overrides.
    #[command(flatten)]
    pub plant: PlantArgs,
    /// With --k-b: encoder resolution Δ, m (rad), > 0 (default: the preset's).
    #[arg(long, requires = "k_b", allow_hyphen_values = true)]
    pub resolution: Option<f64>,
    /// With --k-b: sampling period T, s, > 0 (default: the preset's).
    #[arg(long, requires = "k_b", allow_hyphen_values = true)]
    pub period: Option<f64>,
    /// With --k-b: loop delay T_D beyond the ZOH, s, in [0, 250·T] (default: the preset's, or 0).
    #[arg(long, requires = "k_b", allow_hyphen_values = true)]
    pub delay: Option<f64>,
    /// With --k-b and physical numbers: the device is rotational (rad, N·m).
    #[arg(long, requires = "k_b")]
    pub rotational: bool,
    /// With --k-b: the damper law simulated, `difference` (v = dn) or `dead-band-N` (v = 0
    /// while |dn| <= N counts per period, N in 1..=8); default: the plant file's
    /// `controller.damper`, else the firmware's default (`dead-band-1`).
    #[arg(
        long,
        requires = "k_b",
        value_name = "difference|dead-band-N",
        value_parser = crate::config_flags::parse_damper
    )]
    pub damper: Option<DamperLaw>,
}

/// The damper law of the map: `--damper`, else the plant file's, else the firmware's default.
#[must_use]
pub fn damper_of(a: &KbArgs, plant: &Plant) -> WallDamper {
    let law = match (a.damper, plant.damper) {
        (Some(law), _) => law,
        (None, Some(file)) => return file,
        (None, None) => DamperLaw::default(),
    };
    match law {
        DamperLaw::Difference => WallDamper::Difference,
        DamperLaw::DeadBand { counts } => WallDamper::DeadBand(counts),
    }
}

fn from_file(path: &Path) -> Result<Plant> {
    let text =
        std::fs::read_to_string(path).map_err(|e| anyhow!("--plant {}: {e}", path.display()))?;
    Plant::from_scene_toml(format!("plant file {}", path.display()), &text)
        .map_err(|e| anyhow!("--plant {}: {e}", path.display()))
}

fn checked(
    flag: &str,
    v: Option<f64>,
    f: fn(&'static str, f64) -> Result<f64, stiffwall_core::ParamError>,
) -> Result<Option<f64>> {
    v.map(|x| f("value", x).map_err(|e| anyhow!("--{flag} {x}: {e}")))
        .transpose()
}

fn from_flags(a: &KbArgs) -> Result<Plant> {
    let friction = a.plant.friction(None).map_err(|e| match e {
        PlantSpecError::Incomplete => anyhow!(
            "--k-b needs a device: --plant FILE, --device NAME, or all of --mass, --viscous, \
             --coulomb, --resolution and --period"
        ),
        e => e.into(),
    })?;
    let preset = a.plant.preset()?.map(|d| d.params);
    let need = |flag: &str, v: Option<f64>, p: Option<f64>| {
        v.or(p)
            .with_context(|| format!("--k-b with physical numbers needs --{flag}"))
    };
    let resolution = checked("resolution", a.resolution, check_positive)?;
    let period = checked("period", a.period, check_positive)?;
    let delay = checked("delay", a.delay, stiffwall_core::params::check_non_negative)?;
    Ok(Plant {
        source: friction.source,
        mass: friction.mass,
        viscous: friction.viscous,
        coulomb: friction.coulomb,
        resolution: need("resolution", resolution, preset.map(|p| p.resolution))?,
        period_s: need("period", period, preset.map(|p| p.period_s))?,
        delay_s: delay.or(preset.map(|p| p.delay_s)).unwrap_or(0.0),
        rotational: a.rotational || preset.is_some_and(|p| p.rotational),
        ignored: Vec::new(),
        damper: None,
    })
}

/// The device of `--k-b`, checked.
///
/// # Errors
/// No device, two sources, or a value out of range (naming the flag).
pub fn resolve_plant(a: &KbArgs) -> Result<Plant> {
    let Some(path) = &a.plant_file else {
        return from_flags(a);
    };
    let extra = [
        ("mass", a.plant.mass),
        ("viscous", a.plant.viscous),
        ("coulomb", a.plant.coulomb),
        ("resolution", a.resolution),
        ("period", a.period),
        ("delay", a.delay),
    ];
    if let Some((flag, _)) = extra.iter().find(|(_, v)| v.is_some()) {
        anyhow::bail!("--plant gives the whole device: --{flag} cannot be combined with it");
    }
    from_file(path)
}
