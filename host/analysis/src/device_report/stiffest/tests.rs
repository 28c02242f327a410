//! Tests of the "how stiff" report against closed forms and core, not against its own output.

use super::*;
use stiffwall_core::devices;

fn preset(name: &str) -> PhysicalParams {
    devices::find(name).unwrap().params
}

/// The case: maxon-re35 at B = 0.005 has K_max 4.3173 above the grid's best point
/// (4.3123 at B = 5.495e-3); the best B is never below the user's, nor below any grid point,
/// and it is a local maximum.
#[test]
fn best_b_is_never_below_the_users_or_the_grid() {
    let p = preset("maxon-re35");
    let r = stiffest(None, &p, Some(5.0), Some(0.005)).unwrap();
    let user = criteria::k_max_exact_linear(&p, 0.005).unwrap();
    let grid = criteria::frontier(&p, 4.0 * p.mass / p.period_s).unwrap();
    let best = r.best_damper.k_max;
    assert!(
        best >= user && best >= grid.k_max_opt,
        "{best} {user} {grid:?}"
    );
    assert!(
        best > grid.k_max_opt * (1.0 + 1e-4),
        "refined above the grid"
    );
    for db in [-1e-5, 1e-5] {
        let k = criteria::k_max_exact_linear(&p, r.best_damper.b * (1.0 + db)).unwrap();
        assert!(k <= best * (1.0 + 1e-9), "{db}: {k} > {best}");
    }
    // Not capped: 2c/Δ = 2·2e-3·8192/2π ≈ 5.215 N·m/rad is above 4.32.
    let ceiling = 2.0 * 2e-3 * 8192.0 / std::f64::consts::TAU;
    assert!((r.quiet_ceiling - ceiling).abs() < 1e-12 * ceiling);
    assert!(!r.best_damper.capped && r.predicted.k_predicted == best);
}

/// The table stops at its first K_max = 0, which the grid's previous point is above.
#[test]
fn the_table_stops_at_the_first_zero() {
    let p = preset("maxon-re35");
    let r = stiffest(None, &p, None, None).unwrap();
    let last = r.frontier.last().unwrap();
    assert_eq!(last.k_max, 0.0);
    assert_eq!(r.k_max_zero_from_b, Some(last.b));
    assert!(r.frontier[..r.frontier.len() - 1]
        .iter()
        .all(|f| f.k_max > 0.0));
    assert!(r.frontier.len() < criteria::FRONTIER_POINTS);
    let text = render(&r);
    assert!(text.contains(&format!(
        "K_max(B) = 0 from B = {:.4e} on: the damper alone destabilises",
        last.b
    )));
    assert_eq!(text.matches(" 0.0000e0\n").count(), 0, "{text}");
}

/// Phantom 1.0: the spring-only prediction is the describing-function limit, close to the
/// small-damping closed form (b + 4c/(πv))/(T/2) at v = 5 ticks per period; the best damper's
/// K_max is far above the quiet ceiling 2c/Δ, so the wall is capped there, at the least B
/// whose K_max reaches it.
#[test]
fn phantom_spring_only_and_capped_damper() {
    let p = preset("phantom-1.0");
    let r = stiffest(Some("phantom-1.0".into()), &p, None, None).unwrap();
    let v = 5.0 * 29.1e-6 / 1e-3;
    assert!((r.velocity - v).abs() < 1e-15 && r.velocity_default);
    let closed = (0.005 + 4.0 * 0.038 / (std::f64::consts::PI * v)) / 0.5e-3;
    let k = r.spring_only.k_describing;
    assert!((k - closed).abs() < 0.02 * closed, "{k} vs {closed}");
    assert_eq!(r.spring_only.k_predicted, k);
    let ceiling = 2.0 * 0.038 / 29.1e-6;
    assert!((r.quiet_ceiling - ceiling).abs() < 1e-9 * ceiling);
    assert!(r.best_damper.capped && r.best_damper.k_max > 10.0 * ceiling);
    assert_eq!(r.best_damper.k_predicted, r.quiet_ceiling);
    let b = r.predicted.b_least_at_ceiling.unwrap();
    assert_eq!(
        (r.predicted.b, r.predicted.k_predicted),
        (b, r.quiet_ceiling)
    );
    assert!(criteria::k_max_exact_linear(&p, b).unwrap() >= r.quiet_ceiling);
    assert!(criteria::k_max_exact_linear(&p, b * (1.0 - 1e-6)).unwrap() < r.quiet_ceiling);
    let text = render(&r);
    assert!(text.contains("not reachable at rest"), "{text}");
    assert!(text.contains("N/m") && !text.contains("rad"), "{text}");
}

/// A rotary device speaks N·m/rad and N·m·s/rad only; a linear one N/m and N·s/m only.
#[test]
fn units_are_the_devices_only() {
    let r = stiffest(None, &preset("maxon-re35"), None, Some(0.004)).unwrap();
    let text = render(&r);
    assert!(
        text.contains("N·m/rad") && text.contains("N·m·s/rad"),
        "{text}"
    );
    assert!(!text.contains("N/m") && !text.contains("N·s/m"), "{text}");
    let json = serde_json::to_string(&r).unwrap();
    assert!(json.contains("\"k\":\"N·m/rad\""), "{json}");
}

/// Without Coulomb friction no wall comes to rest: the predictions are 0 and the text says why.
#[test]
fn no_friction_no_wall_at_rest() {
    let p = PhysicalParams {
        coulomb: 0.0,
        ..preset("phantom-1.0")
    };
    let r = stiffest(None, &p, None, None).unwrap();
    assert_eq!(r.quiet_ceiling, 0.0);
    assert_eq!(r.predicted.k_predicted, 0.0);
    assert!(render(&r).contains("no wall comes to rest"));
}
