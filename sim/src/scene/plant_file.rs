//! Plant files (`sim/plants/*.toml`): a physical scene whose `[controller]`, `[initial]` and
//! `[run]` may be omitted; [`PlantModel::from_scene_toml`] reads one. std only.
//!
//! Units: SI, as a physical scene (rotary devices: rad, N·m, …). Defaults: T = 1 ms, no extra
//! delay, a boot stiffness with σ = c/(KΔ) = 4 (a passive wall, which `hostctl tune` replaces),
//! x = 0, v = 0, Dormand–Prince at rtol 1e-9, atol 1e-6. Invariant: a plant file loads exactly
//! as the scene it completes; errors name the key and the allowed range.

use super::error::SceneError;
use super::spec::Scene;
use crate::rich::{Controller, PlantModel};

impl PlantModel {
    /// Parses a plant file (a physical scene; `[controller]`, `[initial]` and `[run]`
    /// optional: module header).
    ///
    /// # Errors
    /// [`SceneError`] naming the offending key.
    pub fn from_scene_toml(text: &str) -> Result<(PlantModel, Controller), SceneError> {
        from_scene_toml(text).map(|(m, c, _)| (m, c))
    }

    /// [`PlantModel::from_scene_toml`] and the file's start position `[initial] position_m`,
    /// m (rad; 0 without `[initial]`): where the virtual device's plant starts, at rest (inside
    /// `effects.travel` when the file has one).
    ///
    /// # Errors
    /// [`SceneError`] naming the offending key.
    pub fn from_scene_toml_with_start(
        text: &str,
    ) -> Result<(PlantModel, Controller, f64), SceneError> {
        from_scene_toml(text)
    }
}

/// Period of a plant file without `[controller]`, s (the virtual device's 1 kHz servo).
const DEFAULT_PERIOD_S: f64 = 1e-3;

/// The boot stiffness of a plant file without `[controller]`: σ = c/(KΔ) = 4, a wall its
/// friction makes passive (region A, eq. (12)), N/m (N·m/rad); `None` when the device table
/// does not give c and Δ (the scene's own errors then name what is missing).
fn default_stiffness(table: &toml::Table) -> Option<f64> {
    let dev = table.get("device")?.as_table()?;
    let num = |k: &str| {
        dev.get(k)
            .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
    };
    let c = num("coulomb_n")?;
    let delta = match (num("resolution_m"), num("counts_per_rev")) {
        (Some(d), None) => d,
        (None, Some(n)) if n >= 1.0 => 2.0 * core::f64::consts::PI / n,
        _ => return None,
    };
    let k = c.max(1e-6) / (4.0 * delta);
    (k.is_finite() && k > 0.0).then_some(k)
}

/// Parses a plant file: a physical scene whose `[initial]` and `[run]` may be omitted (then
/// x = 0, v = 0 and Dormand–Prince are assumed), and whose `[controller]` may be omitted (then
/// T = 1 ms, no extra delay, and a boot stiffness with σ = c/(KΔ) = 4: a passive wall, which
/// `hostctl tune` replaces). Errors name the key and the allowed range.
fn from_scene_toml(text: &str) -> Result<(PlantModel, Controller, f64), SceneError> {
    let table: toml::Table = toml::from_str(text)?;
    let mut full = String::from(text);
    if !table.contains_key("controller") {
        if let Some(k) = default_stiffness(&table) {
            full.push_str(&format!(
                "\n[controller]\nstiffness_n_per_m = {k:e}\nperiod_s = {DEFAULT_PERIOD_S:e}\n\
                 extra_delay_s = 0.0\n"
            ));
        }
    }
    if !table.contains_key("initial") {
        full.push_str("\n[initial]\nposition_m = 0.0\nvelocity_m_per_s = 0.0\n");
    }
    if !table.contains_key("run") {
        full.push_str(
            "\n[run]\nperiods = 1\nsolver = { kind = \"dopri\", rtol = 1e-9, atol = 1e-6 }\n",
        );
    }
    let scene = Scene::from_toml(&full)?;
    let rich = scene.rich.ok_or_else(|| {
        SceneError::Effect(
            "device: a plant file is a physical scene (mass_kg, viscous_ns_per_m, coulomb_n, \
             resolution_m or counts_per_rev)"
                .into(),
        )
    })?;
    let start_m = scene.init.x * rich.model.resolution_m;
    Ok((rich.model, rich.controller, start_m))
}
