//! The (B, K) frontier panel of the live view: core's exact sampled linear K_max(B)
//! ([`stiffwall_core::criteria::frontier`], ZOH, backward-difference damper, physical damping b
//! and delay T_D) for the same [`PhysicalParams`] as the (β, σ) plane, and the operating point
//! (B, K) of the device's configuration.
//!
//! Units: B in N·s/m (N·m·s/rad on a rotary device), K in N/m (N·m/rad). The B axis runs from
//! 0 to max([`B_AXIS_M_PER_T`]·m/T, [`B_AXIS_OVER_SET`]·B): a fixed axis while B stays below
//! 2·m/T, so the point moves on the screen as B changes, and the point is always inside.
//! Invariants: nothing here restates a threshold (K_max and stability come from core); a
//! parameter core refuses gives a panel without a curve and says why.

use serde_json::{json, Value};
use stiffwall_core::criteria;
use stiffwall_core::params::PhysicalParams;

/// B axis for a small B (and B = 0), in units of m/T (as `hostctl analyze --damping`).
pub const B_AXIS_M_PER_T: f64 = 4.0;
/// B axis in units of the configured B when that is larger.
pub const B_AXIS_OVER_SET: f64 = 2.0;

/// The `frontier` part of the plane message for the device `p` (its `stiffness` is the
/// configured K; 0 when the wall is off) and the configured virtual damping `b_set`:
/// `{"b": [...], "k_max": [...], "b_axis", "b_opt", "k_max_opt", "quiet_ceiling", "point"}` with
/// `point` = `{"b", "k", "k_max", "stable", "region"}` (`region`: quiet, chatter or growth, as
/// `hostctl analyze --damping`) or `null` (wall off), or `{"note": ...}` when core refuses. The
/// quiet ceiling 2c/Δ splits the stable side of K_max(B) into the quiet region below it and the
/// chatter band above it.
#[must_use]
pub fn frontier(p: &PhysicalParams, b_set: f64) -> Value {
    match compute(p, b_set) {
        Ok(v) => v,
        Err(e) => json!({"note": format!("no (B, K) frontier: {e}")}),
    }
}

fn compute(p: &PhysicalParams, b_set: f64) -> Result<Value, stiffwall_core::ParamError> {
    let b_set = criteria::check_damping(b_set)?;
    let k = p.stiffness;
    // The curve does not depend on K; core's checks want K > 0 (the wall may be off).
    let on = k.is_finite() && k > 0.0;
    let curve_p = PhysicalParams {
        stiffness: if on { k } else { 1.0 },
        ..*p
    };
    let b_axis = (B_AXIS_M_PER_T * p.mass / p.period_s).max(B_AXIS_OVER_SET * b_set);
    let f = criteria::frontier(&curve_p, b_axis)?;
    let quiet_ceiling = stiffwall_core::rest::quiet_ceiling(p.coulomb, 0.0, p.resolution);
    let point = if on {
        let k_max = criteria::k_max_exact_linear(p, b_set)?;
        json!({"b": b_set, "k": k, "k_max": k_max,
               "stable": criteria::exact_linear_stable(p, b_set)?,
               "region": crate::damping::kb_region(k, k_max, quiet_ceiling)})
    } else {
        Value::Null
    };
    Ok(json!({
        "b": f.b_n_s_per_m.to_vec(),
        "k_max": f.k_max.to_vec(),
        "b_axis": b_axis,
        "b_opt": f.b_opt_n_s_per_m,
        "k_max_opt": f.k_max_opt,
        "quiet_ceiling": quiet_ceiling,
        "point": point,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rig(k: f64) -> PhysicalParams {
        PhysicalParams {
            stiffness: k,
            ..stiffwall_core::devices::find("maxon-re35").unwrap().params
        }
    }

    #[test]
    fn curve_is_cores_and_the_point_follows_the_config() {
        let p = rig(2.0);
        let v = frontier(&p, 0.0);
        let b = v["b"].as_array().unwrap();
        assert_eq!(b.len(), criteria::FRONTIER_POINTS);
        let axis = v["b_axis"].as_f64().unwrap();
        assert!((axis - 4.0 * p.mass / p.period_s).abs() < 1e-12 * axis);
        // K_max(0) is core's exact linear value, the same at any K.
        let k0 = criteria::k_max_exact_linear(&p, 0.0).unwrap();
        assert_eq!(v["k_max"][0].as_f64().unwrap(), k0);
        assert_eq!(frontier(&rig(0.0), 0.0)["k_max"], v["k_max"]);
        assert_eq!(v["point"]["k"], 2.0);
        let b1 = 0.25 * axis;
        let w = frontier(&p, b1);
        assert_eq!(w["point"]["b"], b1);
        assert_eq!(w["b_axis"], v["b_axis"], "a small B keeps the axis");
        assert_eq!(
            w["point"]["k_max"].as_f64().unwrap(),
            criteria::k_max_exact_linear(&p, b1).unwrap()
        );
        // A B beyond the axis widens it so the point stays inside.
        let big = frontier(&p, 3.0 * axis);
        assert_eq!(big["b_axis"].as_f64().unwrap(), 6.0 * axis);
        // The wall off: the curve, no point.
        assert!(frontier(&rig(0.0), 0.0)["point"].is_null());
    }

    #[test]
    fn bad_b_gives_a_note_naming_damping() {
        for b in [-1.0, f64::NAN, f64::INFINITY] {
            let v = frontier(&rig(2.0), b);
            let n = v["note"].as_str().unwrap();
            assert!(n.contains("damping"), "{n}");
        }
    }

    #[test]
    fn the_point_is_quiet_in_the_chatter_band_or_growing() {
        let phantom = |k: f64| PhysicalParams {
            stiffness: k,
            ..stiffwall_core::devices::find("phantom-1.0").unwrap().params
        };
        // 2c/Δ = 2·0.038/29.1e-6 = 2611.7 N/m.
        let v = frontier(&phantom(2000.0), 4.1);
        assert!((v["quiet_ceiling"].as_f64().unwrap() - 2611.7).abs() < 0.1);
        assert_eq!(v["point"]["region"], "quiet");
        assert_eq!(
            frontier(&phantom(3000.0), 4.1)["point"]["region"],
            "chatter"
        );
        assert_eq!(frontier(&phantom(3000.0), 0.0)["point"]["region"], "growth");
    }
}
