//! The plant-effect keys of a scene (issue 10) and the [`RichScene`] they build. std only.
//!
//! Units: physical scenes only (the new effects need SI values): `[device] counts_per_rev`,
//! `[effects] stiction = { static_n, stribeck_m_per_s }`, `cogging = { amplitude_n, period_m }`,
//! `transmission = { link_mass_kg, stiffness_n_per_m, damping_ns_per_m }`, and
//! `amplifier.force_limit_n`, `amplifier.deadband_n` on every amplifier kind, and `travel = {
//! min_m, max_m, stop_stiffness_n_per_m, stop_damping_ns_per_m }` (the end stops; the last two
//! optional: a hard stop of [`crate::rich::HARD_STOP_HZ`] with the motor-side mass by default). Rotary devices
//! (`counts_per_rev` set) read every key in rad, N·m, kg·m², N·m·s/rad, N·m/rad.
//!
//! [`attach`] turns a resolved physical scene and the new keys into a [`RichScene`] (a
//! [`PlantModel`] and its [`Controller`]); the model's own validation
//! ([`PlantModel::validate`], a [`ModelError`]) is reported as a
//! [`SceneError::Effect`] quoting the key, the value and the range. Invariant: a returned
//! [`RichScene`] holds a validated model.

use super::error::SceneError;
use super::raw::{RawCogging, RawStiction, RawTransmission, RawTravel};
use super::spec::{RichScene, Scene, Solver};
use crate::dopri::OdeMethod;
use crate::reference::Method;
use crate::rich::{
    Amplifier, Cogging, Controller, HandSi, ModelError, PlantModel, Stiction, Transmission, Travel,
    WallDamper,
};

/// The plant-effect keys of a scene, collected by [`crate::scene::Scene::from_toml`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct RichKeys {
    /// `device.counts_per_rev`.
    pub(super) counts_per_rev: Option<u32>,
    /// `effects.stiction`.
    pub(super) stiction: Option<RawStiction>,
    /// `effects.cogging`.
    pub(super) cogging: Option<RawCogging>,
    /// `effects.transmission`.
    pub(super) transmission: Option<RawTransmission>,
    /// `effects.travel`.
    pub(super) travel: Option<RawTravel>,
    /// `effects.amplifier.force_limit_n`.
    pub(super) force_limit_n: Option<f64>,
    /// `effects.amplifier.deadband_n`.
    pub(super) deadband_n: Option<f64>,
    /// `controller.damper` (the virtual device's damper law; not a plant effect).
    pub(super) damper: Option<WallDamper>,
}

impl RichKeys {
    fn any_effect(&self) -> Option<&'static str> {
        if self.stiction.is_some() {
            Some("effects.stiction")
        } else if self.cogging.is_some() {
            Some("effects.cogging")
        } else if self.transmission.is_some() {
            Some("effects.transmission")
        } else if self.travel.is_some() {
            Some("effects.travel")
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

/// `device.resolution_m` for a rotary device given by `counts_per_rev` (2π/counts rad).
pub(super) fn rotary_resolution(counts_per_rev: u32) -> Result<f64, SceneError> {
    if counts_per_rev == 0 {
        return Err(SceneError::Effect(
            "device.counts_per_rev = 0: allowed range is [1, 4294967295]".into(),
        ));
    }
    Ok(core::f64::consts::TAU / f64::from(counts_per_rev))
}

/// Builds the [`RichScene`] of a resolved scene; `scale` = (K, T, Δ) of a physical scene,
/// `None` for a dimensionless one (then any new key is an error naming it).
pub(super) fn attach(
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
             transmission, travel, force_limit_n, deadband_n) is on"
                .into(),
        ));
    }
    let model = plant_model(scene, (k, t, delta), &keys);
    if let Err(me) = model.validate() {
        return Err(model_error(&me, &keys));
    }
    if let Some(tr) = model.travel {
        let x0 = scene.init.x * delta;
        if !tr.contains(x0) {
            return Err(SceneError::Effect(format!(
                "initial.position_m = {x0}: allowed range is [{}, {}] m (rad), inside \
                 effects.travel",
                tr.min_m, tr.max_m
            )));
        }
    }
    let method = method(scene.solver, &model, t)?;
    Ok(Some(RichScene {
        model,
        controller: Controller {
            stiffness_n_per_m: k,
            virtual_damping_ns_per_m: scene.beta_v * k * t,
            period_s: t,
            extra_delay_s: p.tau_d * t,
            one_sided: e.one_sided,
            quantization: e.quantization,
            damper: keys.damper,
        },
        method,
    }))
}

/// The [`PlantModel`] of a physical scene (unvalidated) at `kt_delta` = (K, T, Δ).
fn plant_model(scene: &Scene, (k, t, delta): (f64, f64, f64), keys: &RichKeys) -> PlantModel {
    let e = scene.effects;
    let p = scene.params;
    let amp_filter = scene
        .amp
        .map(|a| (a.omega / (core::f64::consts::TAU * t), a.zeta));
    let amplifier =
        if amp_filter.is_some() || keys.force_limit_n.is_some() || keys.deadband_n.is_some() {
            Some(Amplifier {
                cutoff_hz: amp_filter.map(|a| a.0),
                damping_ratio: amp_filter.map_or(0.7, |a| a.1),
                force_limit_n: keys.force_limit_n,
                deadband_n: keys.deadband_n,
            })
        } else {
            None
        };
    PlantModel {
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
        travel: keys.travel.map(|tr| {
            Travel::with_defaults(
                tr.min_m,
                tr.max_m,
                tr.stop_stiffness_n_per_m,
                tr.stop_damping_ns_per_m,
                p.mu * k * t * t,
            )
        }),
        hand: scene.hand.map(|h| HandSi {
            mass_kg: h.mu * k * t * t,
            damping_ns_per_m: h.beta * k * t,
            stiffness_n_per_m: h.kappa * k,
        }),
    }
}

/// A [`ModelError`] as the scene's error: the key, the value as written (for the
/// keys of this module) and the allowed range.
fn model_error(me: &ModelError, keys: &RichKeys) -> SceneError {
    let value = match me.key {
        "effects.stiction.static_n" => keys.stiction.map(|s| s.static_n),
        "effects.stiction.stribeck_m_per_s" => keys.stiction.map(|s| s.stribeck_m_per_s),
        "effects.cogging.amplitude_n" => keys.cogging.map(|c| c.amplitude_n),
        "effects.cogging.period_m" => keys.cogging.map(|c| c.period_m),
        "effects.transmission.link_mass_kg" => keys.transmission.map(|t| t.link_mass_kg),
        "effects.transmission.stiffness_n_per_m" => keys.transmission.map(|t| t.stiffness_n_per_m),
        "effects.transmission.damping_ns_per_m" => keys.transmission.map(|t| t.damping_ns_per_m),
        "effects.amplifier.force_limit_n" => keys.force_limit_n,
        "effects.amplifier.deadband_n" => keys.deadband_n,
        "effects.travel.min_m" => keys.travel.map(|t| t.min_m),
        "effects.travel.max_m" => keys.travel.map(|t| t.max_m),
        "effects.travel.stop_stiffness_n_per_m" => {
            keys.travel.and_then(|t| t.stop_stiffness_n_per_m)
        }
        "effects.travel.stop_damping_ns_per_m" => keys.travel.and_then(|t| t.stop_damping_ns_per_m),
        _ => None,
    };
    SceneError::Effect(match value {
        Some(v) => format!("{} = {v}: allowed range is {}", me.key, me.allowed),
        None => me.to_string(),
    })
}

/// The rich plant's engine for the scene's solver (RK4 steps of T/steps_per_period).
fn method(solver: Solver, model: &PlantModel, t: f64) -> Result<Option<OdeMethod>, SceneError> {
    Ok(match solver {
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
        Solver::Reference(Method::Rk4 { steps_per_period }) => Some(OdeMethod::Rk4 {
            step_s: t / f64::from(steps_per_period),
        }),
        Solver::Reference(Method::Dopri { rtol, atol }) => Some(OdeMethod::Dopri { rtol, atol }),
    })
}
