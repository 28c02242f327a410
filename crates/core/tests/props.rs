//! Property tests of stiffwall-core (issue 2, "Must show").

use proptest::prelude::*;
use stiffwall_core::describing::{quantizer_df, small_limit_cycle};
use stiffwall_core::energy::storage_energy;
use stiffwall_core::limits::{
    holds_12, holds_19, k_max_at_velocity, k_max_delayed, k_max_delayed_harmonic, k_max_passive,
};
use stiffwall_core::regions::{classify, classify_delayed, velocity_limit};
use stiffwall_core::{criteria, describing, energy, regions, Dimensionless, PhysicalParams};

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..hi.ln()).prop_map(f64::exp)
}

prop_compose! {
    fn device()(
        mass in log_uniform(1e-6, 10.0),
        viscous in prop_oneof![Just(0.0), log_uniform(1e-7, 10.0)],
        coulomb in prop_oneof![Just(0.0), log_uniform(1e-5, 10.0)],
        resolution in log_uniform(1e-7, 1e-2),
        period_s in log_uniform(1e-5, 1e-2),
        stiffness in log_uniform(1.0, 1e6),
        delay_periods in prop_oneof![Just(0.0), 0.0..3.0f64],
        rotational in any::<bool>(),
    ) -> PhysicalParams {
        PhysicalParams { mass, viscous, coulomb, resolution, period_s, stiffness,
            delay_s: delay_periods * period_s, rotational }
    }
}

fn region_at(p: &PhysicalParams, k: f64, v: f64, a: f64) -> stiffwall_core::Region {
    let q = p.with_stiffness(k);
    let d = q.to_dimensionless().unwrap();
    classify_delayed(
        d.beta,
        d.sigma,
        d.tau_d,
        Some(q.xidot_from_velocity(v)),
        Some(q.xiddot_from_acceleration(a)),
    )
    .unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Raising K never moves a device to a more stable region (Fig. 4).
    #[test]
    fn raising_k_never_more_stable(p in device(), v in log_uniform(1e-4, 10.0),
                                   a in prop_oneof![Just(0.0), log_uniform(1e-3, 1e3)],
                                   f in 1.0001..50.0f64) {
        let r1 = region_at(&p, p.stiffness, v, a);
        let r2 = region_at(&p, p.stiffness * f, v, a);
        prop_assert!(r2.rank() >= r1.rank(), "{r1:?} -> {r2:?}");
        // τ_D = 0 classification too, with unbounded velocity
        let d1 = p.to_dimensionless().unwrap();
        let d2 = p.with_stiffness(p.stiffness * f).to_dimensionless().unwrap();
        prop_assert!(classify(d2.beta, d2.sigma, None).unwrap().rank()
            >= classify(d1.beta, d1.sigma, None).unwrap().rank());
    }

    /// At each computed K limit the criterion holds, and just above it fails.
    #[test]
    fn k_limits_hold_at_and_fail_above(p in device(), v in log_uniform(1e-4, 10.0),
                                       a in log_uniform(1e-3, 1e3)) {
        let up = 1.0 + 1e-9;
        let k = k_max_passive(&p).unwrap();
        if k > 0.0 {
            prop_assert!(holds_12(&p, k, None));
            prop_assert!(!holds_12(&p, k * up, None));
        }
        let k = k_max_at_velocity(&p, v).unwrap();
        if k > 0.0 {
            prop_assert!(holds_12(&p, k, Some(v)));
            prop_assert!(!holds_12(&p, k * up, Some(v)));
        }
        let k = k_max_delayed(&p, v, a).unwrap();
        if k > 0.0 {
            prop_assert!(holds_19(&p, k, v, a));
            prop_assert!(!holds_19(&p, k * up, v, a));
        }
        let k = k_max_delayed_harmonic(&p, v).unwrap();
        if k > 0.0 {
            let acc = |k: f64| v * (k / p.mass).sqrt();
            prop_assert!(holds_19(&p, k, v, acc(k)));
            prop_assert!(!holds_19(&p, k * up, v, acc(k * up)));
        }
    }

    /// The velocity limit (15) is the boundary of (12): E at it, D just above.
    #[test]
    fn velocity_limit_is_critical(beta in 0.0..0.499f64, sigma in 0.5..10.0f64) {
        let v = velocity_limit(beta, sigma).unwrap().unwrap();
        prop_assert_eq!(classify(beta, sigma, Some(v)).unwrap(), stiffwall_core::Region::E);
        if v > 1e-6 {
            prop_assert_eq!(classify(beta, sigma, Some(v * (1.0 + 1e-9))).unwrap(),
                            stiffwall_core::Region::D);
        }
    }

    /// Physical ↔ dimensionless round trips (Table I).
    #[test]
    fn round_trips(p in device()) {
        let d = p.to_dimensionless().unwrap();
        let q = d.to_physical(p.stiffness, p.period_s, p.resolution, p.rotational).unwrap();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()) + 1e-300;
        prop_assert!(close(p.mass, q.mass));
        prop_assert!(close(p.viscous, q.viscous));
        prop_assert!(close(p.coulomb, q.coulomb));
        prop_assert!(close(p.delay_s, q.delay_s));
        let d2 = q.to_dimensionless().unwrap();
        prop_assert!(close(d.mu, d2.mu) && close(d.beta, d2.beta) && close(d.sigma, d2.sigma));
    }

    /// H_T ≥ 0, and H_T = ½μξ̇² + ½ξ² at integer ξ (35).
    #[test]
    fn storage_energy_props(mu in log_uniform(1e-3, 1e4), xi in -1e6..1e6f64, xidot in -1e3..1e3f64,
                            n in -100_000i32..100_000) {
        prop_assert!(storage_energy(mu, xi, xidot) >= 0.0);
        let xi_n = f64::from(n);
        let h = storage_energy(mu, xi_n, xidot);
        let expect = 0.5 * mu * xidot * xidot + 0.5 * xi_n * xi_n;
        prop_assert!((h - expect).abs() <= 1e-12 * expect.max(1.0));
    }

    /// D(M) → 2/(πM) for small M and → 1 for large M (67), Fig. 11(b).
    #[test]
    fn describing_function_limits(small in log_uniform(1e-9, 0.999), large in log_uniform(10.0, 1e7)) {
        let d = quantizer_df(small).unwrap();
        let d1 = 2.0 / (std::f64::consts::PI * small);
        prop_assert!((d - d1).abs() <= 1e-12 * d1);
        let dl = quantizer_df(large).unwrap();
        prop_assert!((dl - 1.0).abs() <= 0.4 * large.powf(-1.5), "M={large} D={dl}");
    }

    /// No function panics or returns NaN on any finite input; errors are allowed.
    #[test]
    fn no_nan_on_finite_input(a in any::<f64>().prop_filter("finite", |x| x.is_finite()),
                              b in any::<f64>().prop_filter("finite", |x| x.is_finite()),
                              c in any::<f64>().prop_filter("finite", |x| x.is_finite()),
                              d in any::<f64>().prop_filter("finite", |x| x.is_finite()),
                              e in -1e3..1e3f64) {
        let ok = |r: Result<f64, stiffwall_core::ParamError>| r.map_or(true, |x| !x.is_nan());
        let oko = |r: Result<Option<f64>, stiffwall_core::ParamError>| r.map_or(true, |x| x.is_none_or(|x| !x.is_nan()));
        prop_assert!(oko(velocity_limit(a, b)));
        prop_assert!(oko(regions::velocity_limit_delayed(a, b, c, d)));
        prop_assert!(oko(regions::velocity_limit_harmonic(a, b, c, d)));
        let _ = classify(a, b, Some(c));
        let _ = classify_delayed(a, b, c, Some(d), Some(e));
        let _ = regions::criterion_19(a, b, c, Some(d), None);
        prop_assert!(ok(energy::dissipation_lower_bound(a, b, c, d)));
        prop_assert!(ok(energy::generation_upper_bound(a)));
        prop_assert!(ok(energy::generation_upper_bound_delayed(a, b, c)));
        prop_assert!(ok(energy::generation_sampled(a, b)));
        prop_assert!(ok(describing::quantizer_df(a.abs().min(1e9))));
        prop_assert!(ok(describing::large_cycle_omega(a, b)));
        prop_assert!(ok(describing::large_cycle_sigma(a, b, c, d)));
        prop_assert!(ok(describing::large_cycle_sigma_approx(a, b, c, d)));
        prop_assert!(ok(describing::sigma_min_large(a, b, c)));
        prop_assert!(ok(describing::small_cycle_sigma(a, b, c, d)));
        if let Ok(Some(lc)) = small_limit_cycle(a, b, c, d) {
            prop_assert!(lc.amplitude.is_finite() && lc.omega.is_finite());
        }
        let p = PhysicalParams { mass: a, viscous: b, coulomb: c, resolution: d, period_s: e,
            stiffness: a, delay_s: b, rotational: false };
        if let Ok(dl) = p.to_dimensionless() {
            prop_assert!(!dl.mu.is_nan() && !dl.beta.is_nan() && !dl.sigma.is_nan());
        }
        prop_assert!(ok(k_max_passive(&p)));
        prop_assert!(ok(k_max_at_velocity(&p, c)));
        prop_assert!(ok(k_max_delayed(&p, c, d)));
        prop_assert!(ok(criteria::k_max_colgate_schenkel(&p)));
        prop_assert!(ok(criteria::k_max_abbott_okamura(&p)));
        prop_assert!(ok(criteria::k_max_hulin(&p)));
        let dd = Dimensionless { mu: a, beta: b, sigma: c, tau_d: d };
        let _ = dd.to_physical(e, e, e, false);
    }

    /// Physically plausible finite input: the iterative solvers stay finite too.
    #[test]
    fn solvers_finite(p in device(), v in log_uniform(1e-4, 10.0)) {
        let k = k_max_delayed_harmonic(&p, v).unwrap();
        prop_assert!(k.is_finite() && k >= 0.0);
        let g = criteria::k_max_gil_avello_rubio(&p).unwrap();
        prop_assert!(g.is_finite() && g >= 0.0);
        let d = p.to_dimensionless().unwrap();
        if let Some(lc) = small_limit_cycle(d.mu, d.beta, d.sigma, 0.5 + d.tau_d).unwrap() {
            prop_assert!(lc.amplitude.is_finite() && lc.omega > 0.0);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// The exact sampled-linear boundary (Gil et al.): stable just below, unstable just above.
    #[test]
    fn gil_boundary_is_sharp(p in device()) {
        let k = criteria::k_max_gil_avello_rubio(&p).unwrap();
        let x = p.viscous * p.period_s / p.mass;
        // The polynomial test resolves the boundary to ~1e-16/x relative (documented).
        if k == 0.0 || x <= 1e-7 {
            return Ok(());
        }
        prop_assert!(criteria::gil_avello_rubio_stable(&p.with_stiffness(k * (1.0 - 1e-7))).unwrap());
        prop_assert!(!criteria::gil_avello_rubio_stable(&p.with_stiffness(k * (1.0 + 1e-7))).unwrap());
        // Never above Colgate's 2b/T by more than the exact no-delay factor (≤ 2b/T·(1 + x)).
        prop_assert!(k <= criteria::k_max_colgate_schenkel(&p).unwrap() * (1.0 + x) * (1.0 + 1e-9) || x > 0.1);
    }
}

/// Non-finite input is an error, never a value.
#[test]
fn non_finite_is_error() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert!(velocity_limit(bad, 1.0).is_err());
        assert!(classify(0.1, bad, None).is_err());
        assert!(classify(0.1, 1.0, Some(bad)).is_err());
        assert!(quantizer_df(bad).is_err());
        assert!(small_limit_cycle(bad, 0.1, 0.1, 0.5).is_err());
        assert!(energy::generation_upper_bound(bad).is_err());
        let p = PhysicalParams {
            mass: 1.0,
            viscous: 0.1,
            coulomb: 0.1,
            resolution: 1e-5,
            period_s: 1e-3,
            stiffness: bad,
            delay_s: 0.0,
            rotational: false,
        };
        assert!(p.to_dimensionless().is_err());
        assert!(k_max_at_velocity(&p.with_stiffness(1.0), bad).is_err());
        let p = PhysicalParams {
            period_s: bad,
            ..p.with_stiffness(1.0)
        };
        assert!(k_max_passive(&p).is_err());
        assert!(criteria::k_max_gil_avello_rubio(&p).is_err());
    }
}
