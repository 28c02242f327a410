//! The flags of `hostctl map --k-b`, resolved once into the device ([`Plant`]) and the sweep
//! ([`KbSpec`]) that `stiffwall_analysis::kb::compute` maps.
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

use super::args::{history_of, Args};
use crate::plant_args::{PlantArgs, PlantSpecError};
use anyhow::{anyhow, ensure, Context, Result};
use std::path::{Path, PathBuf};
pub use stiffwall_analysis::kb::Plant;
use stiffwall_analysis::kb::{KbSpec, Units};
use stiffwall_core::params::check_positive;
use stiffwall_sim::exact::MAX_BETA_V;
use stiffwall_sim::map::{self as smap, Axis};

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

fn axis(flag: &str, s: Option<&str>, min: f64, strict: bool, unit: &str) -> Result<Axis> {
    let s = s.with_context(|| format!("--k-b needs {flag} LO:HI:N [{unit}]"))?;
    let a = Axis::parse(s).map_err(|e| anyhow::anyhow!("{flag} [{unit}]: {e}"))?;
    let ok = if strict { a.lo > min } else { a.lo >= min };
    ensure!(
        ok,
        "{flag} lo = {}: allowed range is {} {min} {unit}",
        a.lo,
        if strict { ">" } else { ">=" }
    );
    Ok(a)
}

/// Checks the flags of `--k-b` and returns the plant and sweep (nothing is computed).
///
/// # Errors
/// A flag out of range, naming it and its allowed range.
pub fn spec_of(a: &Args) -> Result<(Plant, KbSpec)> {
    let plant = resolve_plant(&a.kb)?;
    let tau_d = plant.delay_s / plant.period_s;
    ensure!(
        tau_d <= stiffwall_sim::params::MAX_TAU_D,
        "{}: delay T_D = {} s is {tau_d} periods; allowed range is T_D <= {} T",
        if a.kb.plant_file.is_some() {
            "--plant controller.extra_delay_s"
        } else {
            "--delay"
        },
        plant.delay_s,
        stiffwall_sim::params::MAX_TAU_D
    );
    let u = Units::of(plant.rotational);
    let k = axis("--k-axis", a.kb.k_axis.as_deref(), 0.0, true, u.k)?;
    let b = axis("--b-axis", a.kb.b_axis.as_deref(), 0.0, false, u.b)?;
    ensure!(
        k.n.checked_mul(b.n)
            .is_some_and(|n| n <= smap::MAX_GRID_POINTS),
        "--k-axis x --b-axis: {} x {} points, at most {}",
        k.n,
        b.n,
        smap::MAX_GRID_POINTS
    );
    let bv_max = b.hi / (k.lo * plant.period_s);
    ensure!(
        bv_max.is_finite() && bv_max <= MAX_BETA_V,
        "--b-axis hi = {} {}: beta_v = B/(K*T) = {bv_max:e} at K = {} (--k-axis lo); allowed \
         range is B <= {MAX_BETA_V}*K*T = {:e} {}",
        b.hi,
        u.b,
        k.lo,
        MAX_BETA_V * k.lo * plant.period_s,
        u.b
    );
    ensure!(
        a.xidot0.len() == 1 && a.xidot0[0].is_finite() && a.xidot0[0].abs() <= 1e12,
        "--xidot0 with --k-b: give one finite value, |v| <= 1e12 (counts per period)"
    );
    ensure!(
        (1..=smap::MAX_PERIODS).contains(&a.periods),
        "--periods {}: allowed range is [1, 1e8]",
        a.periods
    );
    let spec = KbSpec {
        k,
        b,
        xidot0: a.xidot0[0],
        velocity: a.xidot0[0] * plant.resolution / plant.period_s,
        periods: a.periods,
        history: history_of(a.history),
    };
    for kk in [k.lo, k.hi] {
        plant
            .at(kk, b.hi)
            .map_err(|e| anyhow::anyhow!("--k-axis K = {kk}: {e}"))?;
    }
    Ok((plant, spec))
}
