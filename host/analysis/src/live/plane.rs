//! What the page draws in the (β, σ) plane, computed here with the same code as the PNG
//! figures: the operating point and stiffness limits of [`crate::device_report::analyze`], the
//! region polygons and the critical line of `stiffwall_core::regions` (as in
//! `stiffwall_figures::plane`), and, for an opened `hostctl map` JSON, the file's validation
//! ([`crate::map_file::validate`]) and the analytic boundaries of `hostctl map --overlay`.
//! The (B, K) frontier beside it is [`super::frontier`].
//!
//! Units: β, σ, ξ̇ dimensionless (ξ̇ in encoder ticks per servo period); m, b, c, K SI (N/m or
//! N·m/rad etc.). Invariants: nothing here restates a threshold; a missing model or a wall
//! that is off (K = 0) gives a plane without an operating point and says why.

use crate::device_report as analysis;
use crate::map_file::{self, MapFile, MapFileError};
use serde_json::{json, Value};
use stiffwall_core::params::PhysicalParams;
use stiffwall_core::regions::{self, Boundary, Region, Window};
use stiffwall_proto::{DeviceInfo, ServoConfig};

/// The device model the plane is drawn for: mass, viscous and Coulomb friction (SI).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Model {
    /// m [kg or kg·m²].
    pub mass: f64,
    /// b [N·s/m or N·m·s/rad].
    pub viscous: f64,
    /// c [N or N·m].
    pub coulomb: f64,
    /// Where the numbers come from ("preset maxon-re35", "--model", "identified by tune").
    pub source: &'static str,
}

/// Regions drawn, back to front, with their legend text (as in the PNG figure).
const REGIONS: [(Region, &str); 7] = [
    (Region::C, "C: unstable"),
    (Region::B, "B: limit cycle < 1 tick"),
    (Region::F2, "F2: stable, brief energy generation"),
    (Region::A, "A: passive, globally stable"),
    (Region::F1, "F1: stable, energy decreasing"),
    (Region::D, "D: locally unstable"),
    (Region::E, "E: locally stable"),
];

/// The physical parameters of `model` at the device's configuration `cfg`.
#[must_use]
pub fn params(model: &Model, info: &DeviceInfo, cfg: &ServoConfig) -> PhysicalParams {
    let rate = f64::from(cfg.servo_rate_hz.max(1));
    PhysicalParams {
        mass: model.mass,
        viscous: model.viscous,
        coulomb: model.coulomb,
        resolution: f64::from(info.resolution) * f64::from(1u32 << cfg.coarsen_shift.min(16)),
        period_s: 1.0 / rate,
        stiffness: f64::from(cfg.stiffness),
        delay_s: f64::from(cfg.extra_delay_ticks) / rate,
        rotational: info.counts_per_rev > 0,
    }
}

/// The plane message: `{type: "plane", ...}` with the operating point (or `point: null` and a
/// `note`), the regions as polygons, the critical line at `xidot` ticks per period, the window
/// and the stiffness limits on the path of the point; with a model also `frontier`, the
/// (B, K) panel of [`super::frontier::frontier`] for the same [`params`] and the config's B.
#[must_use]
pub fn plane(model: Option<&Model>, info: &DeviceInfo, cfg: &ServoConfig, xidot: f64) -> Value {
    let mut v = beta_sigma(model, info, cfg, xidot);
    if let (Some(m), Some(obj)) = (model, v.as_object_mut()) {
        let p = params(m, info, cfg);
        obj.insert(
            "frontier".into(),
            super::frontier::frontier(&p, f64::from(cfg.damping)),
        );
    }
    v
}

/// The (β, σ) part of [`plane`].
fn beta_sigma(model: Option<&Model>, info: &DeviceInfo, cfg: &ServoConfig, xidot: f64) -> Value {
    let Some(model) = model else {
        return json!({"type": "plane", "point": null, "note":
            "no device model: give --model M B C, or run tune to identify m, b, c"});
    };
    let p = params(model, info, cfg);
    if p.stiffness.is_nan() || p.stiffness <= 0.0 {
        return wall_off(model, info, cfg, xidot);
    }
    let v = xidot * p.resolution / p.period_s;
    let r = match analysis::analyze(None, &p, Some(v), None) {
        Ok(r) => r,
        Err(e) => {
            return json!({"type": "plane", "point": null, "model": model, "note": e.to_string()})
        }
    };
    let tau = r.tau_d;
    let b_star = regions::beta_star(tau);
    let s_star = regions::sigma_star(tau, r.xiddot).unwrap_or(0.5);
    // The window shows the point at half the stiffness limit as well as the current one, so
    // that it does not rescale with K (β, σ ∝ 1/K would otherwise keep the point in place on
    // the screen) while K stays above half the limit.
    let k0 = p.stiffness;
    let k_lim = r
        .k_max_at_velocity
        .filter(|k| k.is_finite() && *k > 0.0)
        .unwrap_or(r.k_max_passive);
    let reach = if k_lim.is_finite() && k_lim > 0.0 {
        (2.0 * k0 / k_lim).max(1.0)
    } else {
        1.0
    };
    let window = Window {
        beta_min: 0.0,
        beta_max: (1.5 * b_star).max(1.2 * r.beta * reach).max(1.0),
        sigma_min: 0.0,
        sigma_max: (1.25 * r.sigma * reach).max(s_star + 0.6).max(2.0),
    };
    let polygons: Vec<Value> = REGIONS
        .iter()
        .filter_map(|(reg, label)| {
            let poly = regions::region_polygon(*reg, tau, Some(xidot), r.xiddot, &window).ok()?;
            (poly.vertices().len() >= 3)
                .then(|| json!({"region": reg.label(), "label": label, "points": poly.vertices()}))
        })
        .collect();
    let critical = regions::boundaries(tau, Some(xidot), r.xiddot, &window)
        .ok()
        .and_then(|b| b.get(Boundary::Critical))
        .map(|s| json!([s.from, s.to]));
    let limits: Vec<Value> = [
        (r.k_max_at_velocity, "K_max (12)"),
        (r.k_max_delayed.filter(|_| tau > 0.0), "K_max (19)"),
        (Some(r.k_max_passive), "K_max region A"),
    ]
    .into_iter()
    .filter_map(|(k, label)| {
        let k = k.filter(|k| k.is_finite() && *k > 0.0)?;
        Some(json!({"label": label, "k": k, "beta": r.beta * k0 / k, "sigma": r.sigma * k0 / k}))
    })
    .collect();
    json!({
        "type": "plane",
        "model": model,
        "point": {"beta": r.beta, "sigma": r.sigma, "k": k0},
        "mu": r.mu,
        "tau_d": tau,
        "xidot": xidot,
        "velocity": v,
        "region": r.region.label(),
        "region_meaning": r.region_meaning,
        "window": [window.beta_max, window.sigma_max],
        "polygons": polygons,
        "critical": critical,
        "limits": limits,
    })
}

/// The plane of a wall that is off (K = 0): no operating point, but the regions and the
/// device's line (the ray the point moves along as K changes, Fig. 4) drawn at a reference K,
/// the region-A limit (2b/T and 2c/Δ), with the limits marked on it.
fn wall_off(model: &Model, info: &DeviceInfo, cfg: &ServoConfig, xidot: f64) -> Value {
    let note = format!(
        "the wall is off (K = {}): set K in Config to see the operating point",
        cfg.stiffness
    );
    let p = PhysicalParams {
        stiffness: 1.0,
        ..params(model, info, cfg)
    };
    let reference = stiffwall_core::limits::k_max_passive(&p)
        .ok()
        .filter(|k| k.is_finite() && *k > 0.0);
    let Some(k_ref) = reference else {
        return json!({"type": "plane", "point": null, "model": model, "note": note});
    };
    let at_ref = ServoConfig {
        stiffness: k_ref as f32,
        ..*cfg
    };
    let mut v = beta_sigma(Some(model), info, &at_ref, xidot);
    if let Some(o) = v.as_object_mut() {
        let point = o.insert("point".into(), Value::Null).unwrap_or(Value::Null);
        o.insert("line".into(), point);
        o.insert("region".into(), Value::Null);
        o.insert(
            "note".into(),
            json!(format!(
                "{note}; the regions and the device's line are drawn at K = {k_ref:.4} (its \
                 region-A limit)"
            )),
        );
    }
    v
}

/// A `hostctl map` JSON opened on the page: validated like every map file read from disk, then
/// returned with the analytic boundaries of `hostctl map --overlay` for each panel (none for a
/// map with a virtual damper, `spec.damping` > 0: those boundaries are the spring-only wall's).
///
/// # Errors
/// [`MapViewError`]: the JSON does not parse as a map file, or the file is invalid (the message names the field).
pub fn map_view(text: &str) -> Result<Value, MapViewError> {
    let m: MapFile = serde_json::from_str(text).map_err(MapViewError::Parse)?;
    map_file::validate(std::path::Path::new("the opened map"), &m)?;
    if m.shard.is_some() {
        return Err(MapViewError::Shard(m.shard));
    }
    let s = &m.spec;
    let half = |a: &stiffwall_sim::map::Axis| {
        if a.n > 1 {
            (a.hi - a.lo) / (a.n - 1) as f64 / 2.0
        } else {
            0.05
        }
    };
    let (db, ds) = (half(&s.beta), half(&s.sigma));
    let window = Window {
        beta_min: s.beta.lo - db,
        beta_max: s.beta.hi + db,
        sigma_min: s.sigma.lo - ds,
        sigma_max: s.sigma.hi + ds,
    };
    let mut panels = Vec::new();
    for panel in &m.panels {
        let v = panel.xidot0.abs();
        let lines = regions::boundaries(panel.tau_d, Some(v), Some(v / panel.mu.sqrt()), &window)?;
        // The analytic boundaries are the spring-only wall's: none for a damped map.
        let lines: Vec<Value> = if s.damping == 0.0 {
            lines
                .as_slice()
                .iter()
                .map(|seg| json!([seg.from, seg.to]))
                .collect()
        } else {
            Vec::new()
        };
        let points: Vec<Value> = panel
            .points
            .iter()
            .map(|pt| json!([pt.beta, pt.sigma, pt.class]))
            .collect();
        panels.push(
            json!({"mu": panel.mu, "tau_d": panel.tau_d, "xidot0": panel.xidot0,
                           "points": points, "lines": lines}),
        );
    }
    Ok(json!({
        "type": "map",
        "mu": serde_json::to_value(&s.mu)?,
        "tau_d": serde_json::to_value(&s.tau_d)?,
        "periods": s.periods,
        "window": [window.beta_min, window.beta_max, window.sigma_min, window.sigma_max],
        "cell": [2.0 * db, 2.0 * ds],
        "panels": panels,
    }))
}

/// Why an opened map file cannot be shown.
#[derive(Debug, thiserror::Error)]
pub enum MapViewError {
    /// The text is not a map file's JSON.
    #[error("not a hostctl map JSON file: {0}")]
    Parse(serde_json::Error),
    /// The map file is invalid (the message names the field).
    #[error(transparent)]
    Invalid(#[from] MapFileError),
    /// The file is one shard of a sweep.
    #[error(
        "the opened map is shard {0:?} of a sweep; merge the shards with `hostctl map --merge` first"
    )]
    Shard(Option<(usize, usize)>),
    /// A panel's parameters are refused by core's region boundaries.
    #[error(transparent)]
    Regions(#[from] stiffwall_core::ParamError),
    /// The view could not be serialised.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info() -> DeviceInfo {
        let d = stiffwall_core::devices::find("maxon-re35").unwrap();
        DeviceInfo {
            protocol_version: stiffwall_proto::PROTOCOL_VERSION,
            firmware_name: Default::default(),
            firmware_version: Default::default(),
            board: Default::default(),
            servo_rate_hz: 1000,
            counts_per_rev: 8192,
            resolution: d.params.resolution as f32,
            encoder_bits: 32,
            force_per_code: 1e-4,
            max_code: 32767,
            limits: stiffwall_proto::Limits {
                min_rate_hz: 100,
                max_rate_hz: 20_000,
                max_stiffness: 100.0,
                max_force: 3.0,
                max_delay_ticks: 31,
                max_coarsen_shift: 16,
                telemetry_batch: 24,
                max_table: 512,
            },
        }
    }

    fn model() -> Model {
        let d = stiffwall_core::devices::find("maxon-re35").unwrap().params;
        Model {
            mass: d.mass,
            viscous: d.viscous,
            coulomb: d.coulomb,
            source: "preset maxon-re35",
        }
    }

    #[test]
    fn point_moves_towards_the_origin_as_k_grows() {
        let cfg1 = ServoConfig {
            stiffness: 1.0,
            servo_rate_hz: 1000,
            ..ServoConfig::default()
        };
        let cfg2 = ServoConfig {
            stiffness: 2.0,
            ..cfg1
        };
        let a = plane(Some(&model()), &info(), &cfg1, 5.0);
        let b = plane(Some(&model()), &info(), &cfg2, 5.0);
        let (b1, s1) = (
            a["point"]["beta"].as_f64().unwrap(),
            a["point"]["sigma"].as_f64().unwrap(),
        );
        let (b2, s2) = (
            b["point"]["beta"].as_f64().unwrap(),
            b["point"]["sigma"].as_f64().unwrap(),
        );
        // β = b/(KT), σ = c/(KΔ): doubling K halves both (Fig. 4).
        assert!((b2 - b1 / 2.0).abs() < 1e-12 * b1.max(1.0));
        assert!((s2 - s1 / 2.0).abs() < 1e-9 * s1);
        // The paper's rig at K = 2: σ = 2e-3 / (2 · 2π/8192) ≈ 1.30 (devices.rs).
        assert!((s2 - 1.304).abs() < 0.01, "sigma {s2}");
        assert!(!a["polygons"].as_array().unwrap().is_empty());
        assert!(a["critical"].is_array());
        // Above half the limit the window does not follow K: the point moves on the screen.
        assert_eq!(a["window"], b["window"]);
    }

    #[test]
    fn wall_off_and_no_model_have_no_point() {
        let cfg = ServoConfig {
            stiffness: 0.0,
            ..ServoConfig::default()
        };
        let a = plane(Some(&model()), &info(), &cfg, 5.0);
        assert!(a["point"].is_null());
        assert!(a["note"].as_str().unwrap().contains("wall is off"));
        let b = plane(None, &info(), &cfg, 5.0);
        assert!(b["note"].as_str().unwrap().contains("--model"));
    }

    #[test]
    fn map_view_refuses_bad_files() {
        let e = map_view("{}").unwrap_err().to_string();
        assert!(e.contains("not a hostctl map JSON"), "{e}");
    }

    #[test]
    fn a_damped_map_gets_no_spring_only_boundaries() {
        use crate::map_file::{Spec, Values};
        use stiffwall_sim::map::Axis;
        let axis = |hi| Axis { lo: 0.0, hi, n: 3 };
        let mut spec = Spec {
            mu: Values::One(100.0),
            tau_d: Values::One(0.0),
            xidot0: vec![5.0],
            beta: axis(1.0),
            sigma: axis(2.0),
            periods: 50,
            history: stiffwall_sim::History::HoldInitial,
            damping: 0.0,
        };
        let lines = |spec: &Spec| {
            let m = map_file::compute(
                spec,
                None,
                &|| {},
                stiffwall_sim::map::RunOptions::default(),
            );
            let v = map_view(&serde_json::to_string(&m).unwrap()).unwrap();
            v["panels"][0]["lines"].as_array().unwrap().len()
        };
        assert!(lines(&spec) > 0);
        spec.damping = 1.0;
        assert_eq!(lines(&spec), 0);
    }
}
