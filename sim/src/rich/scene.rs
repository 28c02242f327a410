//! Scene keys of the rich plant and the sampled loop that runs scenes using them. std only.
//!
//! Units: physical scenes only (the new effects need SI values): `[device] counts_per_rev`,
//! `[effects] stiction = { static_n, stribeck_m_per_s }`, `cogging = { amplitude_n, period_m }`,
//! `transmission = { link_mass_kg, stiffness_n_per_m, damping_ns_per_m }`, and
//! `amplifier.force_limit_n`, `amplifier.deadband_n` on every amplifier kind. Rotary devices
//! (`counts_per_rev` set) read every key in rad, N·m, kg·m², N·m·s/rad, N·m/rad.
//!
//! [`attach`] is the one call `crate::scene` makes: it turns a resolved physical scene and the
//! new keys into a [`RichScene`] (a [`PlantModel`] and its [`Controller`]). [`simulate`] runs it
//! when a new effect is on: the controller of eq. (8) (quantised or ideal, one-sided or not) is
//! sampled every period T (plus the virtual damper −β_v·(n_h − n_(h−1)) of `crate::exact`
//! when the scene sets `controller.virtual_damping_ns_per_m`), its force delayed by τ_D = n + f periods exactly as in
//! [`crate::exact`] (force F(h−n−1) over [h, h+f), F(h−n) over [h+f, h+1)), and held on a
//! [`RichPlant`]. Rows are in the scene's dimensionless units (ξ = x₁/Δ, ξ̇ = v₁T/Δ,
//! φ_A = F/(KΔ)); the energy audit columns `e_d`, `e_g`, `residual` are 0 (not audited).
//!
//! Invariant: a [`RichScene`] holds a validated model; [`simulate`] never panics.

use super::model::{Amplifier, Cogging, Controller, HandSi, PlantModel, Stiction, Transmission};
use super::plant::RichPlant;
use crate::dopri::OdeMethod;
use crate::exact::History;
use crate::scene::{Row, Scene, SceneError, Solver};
use serde::Deserialize;

/// `effects.stiction` as written.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawStiction {
    /// Breakaway force, N.
    pub static_n: f64,
    /// Stribeck velocity, m/s.
    pub stribeck_m_per_s: f64,
}

/// `effects.cogging` as written.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCogging {
    /// Amplitude, N.
    pub amplitude_n: f64,
    /// Period, m.
    pub period_m: f64,
}

/// `effects.transmission` as written.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawTransmission {
    /// Link-side mass, kg.
    pub link_mass_kg: f64,
    /// Spring, N/m.
    pub stiffness_n_per_m: f64,
    /// Damper, N·s/m.
    pub damping_ns_per_m: f64,
}

/// The new keys of a scene, collected by `crate::scene`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RichKeys {
    /// `device.counts_per_rev`.
    pub counts_per_rev: Option<u32>,
    /// `effects.stiction`.
    pub stiction: Option<RawStiction>,
    /// `effects.cogging`.
    pub cogging: Option<RawCogging>,
    /// `effects.transmission`.
    pub transmission: Option<RawTransmission>,
    /// `effects.amplifier.force_limit_n`.
    pub force_limit_n: Option<f64>,
    /// `effects.amplifier.deadband_n`.
    pub deadband_n: Option<f64>,
}

impl RichKeys {
    fn any_effect(&self) -> Option<&'static str> {
        if self.stiction.is_some() {
            Some("effects.stiction")
        } else if self.cogging.is_some() {
            Some("effects.cogging")
        } else if self.transmission.is_some() {
            Some("effects.transmission")
        } else if self.force_limit_n.is_some() {
            Some("effects.amplifier.force_limit_n")
        } else if self.deadband_n.is_some() {
            Some("effects.amplifier.deadband_n")
        } else if self.counts_per_rev.is_some() {
            Some("device.counts_per_rev")
        } else {
            None
        }
    }
}

/// The physical plant and controller of a physical scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RichScene {
    /// The plant.
    pub model: PlantModel,
    /// The controller (boot configuration of the virtual device).
    pub controller: Controller,
    /// Engine for [`simulate`]: `None` exact, otherwise the scene's reference integrator.
    pub method: Option<OdeMethod>,
}

impl RichScene {
    /// Whether [`simulate`] (rather than the paper-model solvers) must run the scene.
    #[must_use]
    pub fn needs_rich_loop(&self) -> bool {
        self.model.has_new_effects()
    }
}

/// `device.resolution_m` for a rotary device given by `counts_per_rev` (2π/counts rad).
pub fn rotary_resolution(counts_per_rev: u32) -> Result<f64, SceneError> {
    if counts_per_rev == 0 {
        return Err(SceneError::Effect(
            "device.counts_per_rev = 0: allowed range is [1, 4294967295]".into(),
        ));
    }
    Ok(core::f64::consts::TAU / f64::from(counts_per_rev))
}

/// Builds the [`RichScene`] of a resolved scene; `scale` = (K, T, Δ) of a physical scene,
/// `None` for a dimensionless one (then any new key is an error naming it).
pub fn attach(
    scene: &Scene,
    scale: Option<(f64, f64, f64)>,
    keys: RichKeys,
) -> Result<Option<RichScene>, SceneError> {
    let Some((k, t, delta)) = scale else {
        return match keys.any_effect() {
            Some(key) => Err(SceneError::Effect(format!(
                "{key}: allowed only in physical scenes (device.mass_kg, viscous_ns_per_m, \
                 coulomb_n, resolution_m)"
            ))),
            None => Ok(None),
        };
    };
    let e = scene.effects;
    let p = scene.params;
    if !e.coulomb && keys.stiction.is_some() {
        return Err(SceneError::Effect(
            "effects.stiction: needs effects.coulomb = true".into(),
        ));
    }
    if !scene.zoh && keys.any_effect().is_some() {
        return Err(SceneError::Effect(
            "effects.zoh = false: allowed range is true when a new effect (stiction, cogging, \
             transmission, force_limit_n, deadband_n) is on"
                .into(),
        ));
    }
    let amp_filter = scene
        .amp
        .map(|a| (a.omega / (core::f64::consts::TAU * t), a.zeta));
    let amplifier =
        if amp_filter.is_some() || keys.force_limit_n.is_some() || keys.deadband_n.is_some() {
            Some(Amplifier {
                cutoff_hz: amp_filter.map(|a| a.0),
                damping: amp_filter.map_or(0.7, |a| a.1),
                force_limit_n: keys.force_limit_n,
                deadband_n: keys.deadband_n,
            })
        } else {
            None
        };
    let model = PlantModel {
        mass_kg: p.mu * k * t * t,
        viscous_ns_per_m: if e.viscous { p.beta * k * t } else { 0.0 },
        coulomb_n: if e.coulomb { p.sigma * k * delta } else { 0.0 },
        resolution_m: delta,
        counts_per_rev: keys.counts_per_rev,
        stiction: keys.stiction.map(|s| Stiction {
            static_n: s.static_n,
            stribeck_m_per_s: s.stribeck_m_per_s,
        }),
        cogging: keys.cogging.map(|c| Cogging {
            amplitude_n: c.amplitude_n,
            period_m: c.period_m,
        }),
        transmission: keys.transmission.map(|t| Transmission {
            link_mass_kg: t.link_mass_kg,
            stiffness_n_per_m: t.stiffness_n_per_m,
            damping_ns_per_m: t.damping_ns_per_m,
        }),
        amplifier,
        hand: scene.hand.map(|h| HandSi {
            mass_kg: h.mu * k * t * t,
            damping_ns_per_m: h.beta * k * t,
            stiffness_n_per_m: h.kappa * k,
        }),
    };
    if let Err(me) = model.validate() {
        let value = match me.key {
            "effects.stiction.static_n" => keys.stiction.map(|s| s.static_n),
            "effects.stiction.stribeck_m_per_s" => keys.stiction.map(|s| s.stribeck_m_per_s),
            "effects.cogging.amplitude_n" => keys.cogging.map(|c| c.amplitude_n),
            "effects.cogging.period_m" => keys.cogging.map(|c| c.period_m),
            "effects.transmission.link_mass_kg" => keys.transmission.map(|t| t.link_mass_kg),
            "effects.transmission.stiffness_n_per_m" => {
                keys.transmission.map(|t| t.stiffness_n_per_m)
            }
            "effects.transmission.damping_ns_per_m" => {
                keys.transmission.map(|t| t.damping_ns_per_m)
            }
            "effects.amplifier.force_limit_n" => keys.force_limit_n,
            "effects.amplifier.deadband_n" => keys.deadband_n,
            _ => None,
        };
        return Err(SceneError::Effect(match value {
            Some(v) => format!("{} = {v}: allowed range is {}", me.key, me.allowed),
            None => me.to_string(),
        }));
    }
    let method = match scene.solver {
        Solver::Exact => {
            if model.has_new_effects() && !model.is_exact() {
                return Err(SceneError::Effect(
                    "run.solver: kind = \"exact\" needs a plant without cogging or Stribeck decay \
                     (stribeck_m_per_s = 0); use rk4 or dopri"
                        .into(),
                ));
            }
            None
        }
        Solver::Reference(crate::reference::Method::Rk4 { steps_per_period }) => {
            Some(OdeMethod::Rk4 {
                step_s: t / f64::from(steps_per_period),
            })
        }
        Solver::Reference(crate::reference::Method::Dopri { rtol, atol }) => {
            Some(OdeMethod::Dopri { rtol, atol })
        }
    };
    Ok(Some(RichScene {
        model,
        controller: Controller {
            stiffness_n_per_m: k,
            virtual_damping_ns_per_m: scene.beta_v * k * t,
            period_s: t,
            extra_delay_s: p.tau_d * t,
            one_sided: e.one_sided,
            quantization: e.quantization,
        },
        method,
    }))
}

/// Period of a plant file without `[controller]`, s (the virtual device's 1 kHz servo).
pub const DEFAULT_PERIOD_S: f64 = 1e-3;

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
pub fn from_scene_toml(text: &str) -> Result<(PlantModel, Controller), SceneError> {
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
    Ok((rich.model, rich.controller))
}

/// The spring of eq. (8) in units of K·Δ at ξ ticks.
fn spring(xi: f64, c: &Controller) -> f64 {
    let f = if c.quantization {
        -crate::math::floor_fast(xi) - 0.5
    } else {
        -xi
    };
    if c.one_sided {
        f.min(0.0)
    } else {
        f
    }
}

/// The wall law of the module header in units of K·Δ at ξ ticks, with the virtual damper
/// −β_v·(n_h − n_(h−1)) when β_v ≠ 0 (as [`crate::exact`]: n = ⌊ξ⌋, or ξ without
/// quantization; on a one-sided wall the whole law acts only in contact, n ≥ 0).
fn law(xi: f64, n_prev: f64, beta_v: f64, c: &Controller) -> f64 {
    if beta_v == 0.0 {
        return spring(xi, c);
    }
    let n = count(xi, c);
    let f = if c.quantization { -n - 0.5 } else { -n } - beta_v * (n - n_prev);
    if c.one_sided && n < 0.0 {
        0.0
    } else {
        f
    }
}

/// The count n_h of the damper's backward difference (ξ itself without quantization).
fn count(xi: f64, c: &Controller) -> f64 {
    if c.quantization {
        crate::math::floor_fast(xi)
    } else {
        xi
    }
}

/// Runs a scene with a [`RichScene`] in the sampled loop of the module header, calling `out`
/// at τ = 0 and at every sample instant.
pub fn simulate(
    scene: &Scene,
    rich: &RichScene,
    out: &mut dyn FnMut(&Row),
) -> Result<(), SceneError> {
    let c = rich.controller;
    let (k, t, delta) = (c.stiffness_n_per_m, c.period_s, rich.model.resolution_m);
    let kd = k * delta;
    let mut plant = RichPlant::with_method(&rich.model, rich.method)
        .map_err(|e| SceneError::Effect(e.to_string()))?;
    plant.set_tolerance_period(t);
    plant.set_state(scene.init.x * delta, scene.init.v * delta / t);
    let tau_d = scene.params.tau_d;
    let n = crate::math::floor_fast(tau_d);
    let frac = tau_d - n;
    let n = n as u64;
    const LINE: usize = 256;
    let hist = match scene.history {
        History::HoldInitial => spring(scene.init.x, &c),
        History::Zero => 0.0,
    };
    // As the reference integrators: the filter starts in steady state with the history force.
    plant.set_amplifier_output(hist * kd);
    let mut line = [hist; LINE];
    let delayed = |line: &[f64; LINE], h: u64, j: u64| -> f64 {
        if h < j {
            hist
        } else {
            line[((h - j) as usize) % LINE]
        }
    };
    let mu = scene.params.mu;
    let row = |h: u64, p: &RichPlant, phi: f64| {
        let xi = p.position_m() / delta;
        let xidot = p.velocity_m_per_s() * t / delta;
        Row {
            period: h,
            xi,
            xidot,
            phi_a: phi,
            h_t: crate::exact::storage(mu, xi, xidot),
            e_d: 0.0,
            e_g: 0.0,
            residual: 0.0,
        }
    };
    let beta_v = scene.beta_v;
    let mut n_prev = count(scene.init.x, &c);
    for h in 0..=scene.periods {
        let xi = plant.position_m() / delta;
        line[(h as usize) % LINE] = law(xi, n_prev, beta_v, &c);
        n_prev = count(xi, &c);
        let first = if frac > 0.0 {
            delayed(&line, h, n + 1)
        } else {
            delayed(&line, h, n)
        };
        out(&row(h, &plant, first));
        // Diverged: as the exact solver's driver, stop after the first row beyond 1e150.
        let v = plant.velocity_m_per_s() * t / delta;
        if h == scene.periods || !(xi.abs() <= 1e150 && v.abs() <= 1e150) {
            break;
        }
        if frac > 0.0 {
            plant.advance(first * kd, frac * t);
            plant.advance(delayed(&line, h, n) * kd, (1.0 - frac) * t);
        } else {
            plant.advance(first * kd, t);
        }
    }
    Ok(())
}
