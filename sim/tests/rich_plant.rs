//! The issue-10 plant effects against independent references: closed form vs Dormand–Prince,
//! analytic breakaway thresholds, cogging equilibria, the two-mass resonance
//! √(k(1/m₁+1/m₂)), saturation and dead band, and the sampled scene loop against the
//! paper-model solvers.

use stiffwall_sim::rich::{
    Amplifier, Cogging, HandSi, OdeMethod, PlantModel, RichPlant, Stiction, Transmission,
};

const DOPRI_TIGHT: Option<OdeMethod> = Some(OdeMethod::Dopri {
    rtol: 1e-12,
    atol: 1e-9,
});

fn base() -> PlantModel {
    PlantModel::rigid(0.25, 0.01, 0.06, 20e-6).unwrap()
}

fn amp(limit: Option<f64>, deadband: Option<f64>) -> Option<Amplifier> {
    Some(Amplifier {
        cutoff_hz: None,
        damping_ratio: 0.7,
        force_limit_n: limit,
        deadband_n: deadband,
    })
}

/// A deterministic, sign-changing command sequence (N) that makes the mass stick and slip.
fn command(i: u32) -> f64 {
    let t = f64::from(i);
    0.12 * (t * 0.031).sin() + 0.05 * (t * 0.173).sin()
}

#[test]
fn static_switch_exact_equals_dopri() {
    let mut m = base();
    m.stiction = Some(Stiction {
        static_n: 0.1,
        stribeck_m_per_s: 0.0,
    });
    m.amplifier = amp(Some(0.15), Some(0.005));
    let mut exact = RichPlant::new(&m).unwrap();
    assert!(exact.is_exact());
    let mut dp = RichPlant::with_method(&m, DOPRI_TIGHT).unwrap();
    assert!(!dp.is_exact());
    let (mut stuck_periods, mut moving_periods) = (0, 0);
    for i in 0..3000 {
        exact.advance(command(i), 1e-3);
        dp.advance(command(i), 1e-3);
        let (xe, xd) = (exact.position_m(), dp.position_m());
        assert!(
            (xe - xd).abs() < 1e-12 + 1e-9 * xe.abs(),
            "period {i}: {xe} vs {xd}"
        );
        let (ve, vd) = (exact.velocity_m_per_s(), dp.velocity_m_per_s());
        assert!((ve - vd).abs() < 1e-10, "period {i}: {ve} vs {vd}");
        assert_eq!(exact.is_stuck(), dp.is_stuck(), "period {i}");
        if exact.is_stuck() {
            stuck_periods += 1;
        } else {
            moving_periods += 1;
        }
    }
    assert!(
        stuck_periods > 100 && moving_periods > 100,
        "{stuck_periods} {moving_periods}"
    );
}

#[test]
fn breakaway_threshold_is_static_n() {
    for vs in [0.0, 0.002] {
        let mut m = base();
        m.stiction = Some(Stiction {
            static_n: 0.09,
            stribeck_m_per_s: vs,
        });
        for (f, moves) in [
            (0.0899, false),
            (0.0901, true),
            (-0.0899, false),
            (-0.0901, true),
        ] {
            let mut p = RichPlant::new(&m).unwrap();
            for _ in 0..100 {
                p.advance(f, 1e-3);
            }
            assert_eq!(p.position_m() != 0.0, moves, "vs {vs} f {f}");
            if moves {
                assert_eq!(p.position_m() > 0.0, f > 0.0);
            }
        }
    }
}

/// Stribeck decay: at speeds ≫ v_s the friction is the dynamic c, so the terminal velocity
/// is (F − c)/b; with a pure switch (v_s = 0) a moving mass below breakaway keeps sliding
/// while one with v_s > 0 decelerates near v = 0 through the higher friction.
#[test]
fn stribeck_decays_to_the_dynamic_level() {
    let mut m = PlantModel::rigid(0.1, 0.5, 0.06, 1e-6).unwrap();
    m.stiction = Some(Stiction {
        static_n: 0.12,
        stribeck_m_per_s: 0.001,
    });
    let mut p = RichPlant::new(&m).unwrap();
    for _ in 0..5000 {
        p.advance(0.2, 1e-3);
    }
    let v_inf = (0.2 - 0.06) / 0.5;
    assert!(
        (p.velocity_m_per_s() - v_inf).abs() < 1e-8,
        "{}",
        p.velocity_m_per_s()
    );
}

#[test]
fn cogging_equilibria_are_at_half_periods() {
    for rotary in [false, true] {
        let period = if rotary { 0.1 } else { 0.5e-3 };
        // Linearised cogging stiffness A·2π/P, damped at ζ = 0.7.
        let k_cog = 0.05 * std::f64::consts::TAU / period;
        let b = 1.4 * (k_cog * 0.05_f64).sqrt();
        let mut m = PlantModel::rigid(0.05, b, 0.0, period / 1000.0).unwrap();
        if rotary {
            m.counts_per_rev = Some(62_832);
            m.resolution_m = std::f64::consts::TAU / 62_832.0;
        }
        m.cogging = Some(Cogging {
            amplitude_n: 0.05,
            period_m: period,
        });
        // F = A sin(2πx/P): stable equilibria at (j + ½)P, unstable at jP.
        for (x0, j) in [(0.3, 0.5), (0.7, 0.5), (1.2, 1.5), (-0.2, -0.5), (2.9, 2.5)] {
            let mut p = RichPlant::new(&m).unwrap();
            p.set_state(x0 * period, 0.0);
            for _ in 0..8000 {
                p.advance(0.0, 1e-3);
            }
            let x = p.position_m() / period;
            assert!((x - j).abs() < 1e-6, "rotary {rotary} x0 {x0}: {x}");
        }
    }
}

#[test]
fn cogging_within_coulomb_does_not_move_a_mass_at_rest() {
    let mut m = base();
    m.cogging = Some(Cogging {
        amplitude_n: 0.05,
        period_m: 1e-3,
    });
    let mut p = RichPlant::new(&m).unwrap();
    p.set_state(0.25e-3, 0.0);
    for _ in 0..100 {
        p.advance(0.0, 1e-3);
    }
    assert_eq!(p.position_m(), 0.25e-3);
}

/// Counts sign changes of link − motor deflection at a fine sampling: the frequency of the
/// free two-mass oscillation must be √(k(1/m₁+1/m₂))/2π.
#[test]
fn transmission_resonance_matches_the_two_mass_formula() {
    for (m1, m2, k) in [(0.05, 0.02, 5e4), (0.2, 0.2, 1e4), (0.01, 0.1, 2e5)] {
        let mut m = PlantModel::rigid(m1, 0.0, 0.0, 1e-6).unwrap();
        m.transmission = Some(Transmission {
            link_mass_kg: m2,
            stiffness_n_per_m: k,
            damping_ns_per_m: 0.0,
        });
        let mut p = RichPlant::new(&m).unwrap();
        p.advance(1.0, 1e-4); // a push on the motor excites the mode
        let dt = 1e-6;
        let mut prev = p.link_position_m() - p.position_m();
        let (mut first, mut last, mut n) = (None, 0.0, 0);
        for i in 1..=200_000 {
            p.advance(0.0, dt);
            let d = p.link_position_m() - p.position_m();
            if prev != 0.0 && d * prev < 0.0 {
                // Linear interpolation of the crossing instant.
                let t = (f64::from(i) - 1.0 + prev / (prev - d)) * dt;
                if first.is_none() {
                    first = Some(t);
                } else {
                    n += 1;
                }
                last = t;
            }
            prev = d;
        }
        let f = 0.5 * f64::from(n) / (last - first.unwrap());
        let f_ref = (k * (1.0 / m1 + 1.0 / m2)).sqrt() / std::f64::consts::TAU;
        assert!(
            (f / f_ref - 1.0).abs() < 1e-4,
            "{m1} {m2} {k}: {f} vs {f_ref}"
        );
    }
}

/// Undamped, frictionless two masses under a constant motor force: the centre of mass moves
/// as F t²/2(m₁+m₂) and the deflection as (F m₂/(k(m₁+m₂)))(1 − cos ωt): closed form.
#[test]
fn transmission_dopri_matches_the_modal_closed_form() {
    let (m1, m2, k, f) = (0.05, 0.02, 5e4, 0.7);
    let mut m = PlantModel::rigid(m1, 0.0, 0.0, 1e-6).unwrap();
    m.transmission = Some(Transmission {
        link_mass_kg: m2,
        stiffness_n_per_m: k,
        damping_ns_per_m: 0.0,
    });
    let mut p = RichPlant::with_method(&m, DOPRI_TIGHT).unwrap();
    let w = (k * (1.0 / m1 + 1.0 / m2)).sqrt();
    for i in 1..=500 {
        p.advance(f, 1e-3);
        let t = f64::from(i) * 1e-3;
        let xc = f * t * t / (2.0 * (m1 + m2));
        let q = f * m2 / (k * (m1 + m2)) * (1.0 - (w * t).cos());
        // Motor: x₁ = x_c − m₂/(m₁+m₂)·(x₂ − x₁) with x₂ − x₁ = −q.
        let x1 = xc + m2 / (m1 + m2) * q;
        assert!(
            (p.position_m() - x1).abs() < 1e-9 * (1.0 + x1.abs()) + 1e-12,
            "t {t}"
        );
        let x2 = xc - m1 / (m1 + m2) * q;
        assert!((p.link_position_m() - x2).abs() < 1e-9 * (1.0 + x2.abs()) + 1e-12);
    }
}

#[test]
fn force_limit_saturates_and_deadband_cuts_small_commands() {
    let mut m = PlantModel::rigid(0.5, 0.0, 0.0, 1e-6).unwrap();
    m.amplifier = amp(Some(2.0), Some(0.1));
    let mut p = RichPlant::new(&m).unwrap();
    p.advance(0.1, 1e-3);
    assert_eq!(p.position_m(), 0.0);
    p.advance(1000.0, 0.01);
    // a = 2 N / 0.5 kg = 4 m/s².
    assert!((p.velocity_m_per_s() - 0.04).abs() < 1e-15);
    assert!((p.position_m() - 0.5 * 4.0 * 1e-4).abs() < 1e-15);
    p.set_state(0.0, 0.0);
    p.advance(1.1, 0.01); // 1.1 − 0.1 = 1 N
    assert!((p.velocity_m_per_s() - 0.02).abs() < 1e-15);
    // With a second-order filter the settled output is the limit too.
    m.amplifier = Some(Amplifier {
        cutoff_hz: Some(500.0),
        damping_ratio: 0.3,
        force_limit_n: Some(2.0),
        deadband_n: None,
    });
    let mut p = RichPlant::new(&m).unwrap();
    let mut peak: f64 = 0.0;
    for _ in 0..100 {
        p.advance(-50.0, 1e-4);
        peak = peak.max(p.actuator_force_n().abs());
    }
    assert!(
        (p.actuator_force_n() + 2.0).abs() < 1e-9,
        "{}",
        p.actuator_force_n()
    );
    assert!(peak <= 2.0);
}

/// A very stiff, well-damped transmission behaves as one rigid mass m₁ + m₂ (closed form).
#[test]
fn stiff_transmission_tends_to_the_rigid_plant() {
    let mut m = PlantModel::rigid(0.05, 0.01, 0.0, 1e-6).unwrap();
    m.transmission = Some(Transmission {
        link_mass_kg: 0.05,
        stiffness_n_per_m: 1e7,
        damping_ns_per_m: 200.0,
    });
    let rigid = PlantModel::rigid(0.1, 0.01, 0.0, 1e-6).unwrap();
    let mut a = RichPlant::new(&m).unwrap();
    let mut b = RichPlant::new(&rigid).unwrap();
    for i in 0..200 {
        a.advance(command(i), 1e-3);
        b.advance(command(i), 1e-3);
    }
    assert!((a.position_m() - b.position_m()).abs() < 1e-4 * b.position_m().abs().max(1e-6));
}

/// Motor 0.05 kg, link 0.02 kg on 1e4 N/m (1 N·s/m), a hand of 0.1 kg on 100 N/m (2 N·s/m).
fn link_with_hand() -> PlantModel {
    let mut m = PlantModel::rigid(0.05, 0.0, 0.0, 1e-6).unwrap();
    m.transmission = Some(Transmission {
        link_mass_kg: 0.02,
        stiffness_n_per_m: 1e4,
        damping_ns_per_m: 1.0,
    });
    m.hand = Some(HandSi {
        mass_kg: 0.1,
        damping_ns_per_m: 2.0,
        stiffness_n_per_m: 100.0,
    });
    m
}

#[test]
fn hand_on_the_link_side_loads_only_the_link() {
    let mut p = RichPlant::new(&link_with_hand()).unwrap();
    for _ in 0..3000 {
        p.advance(0.5, 1e-3);
    }
    // Static equilibrium: the hand spring carries the force; the transmission deflects by F/k.
    assert!(
        (p.link_position_m() - 0.5 / 100.0).abs() < 1e-6,
        "{}",
        p.link_position_m()
    );
    assert!((p.position_m() - p.link_position_m() - 0.5 / 1e4).abs() < 1e-7);
}

#[test]
fn bad_models_name_the_field() {
    let mut m = base();
    m.stiction = Some(Stiction {
        static_n: 0.01,
        stribeck_m_per_s: 0.0,
    });
    let e = RichPlant::new(&m).unwrap_err();
    assert_eq!(e.key, "effects.stiction.static_n");
    let mut m = base();
    m.transmission = Some(Transmission {
        link_mass_kg: 0.0,
        stiffness_n_per_m: 1.0,
        damping_ns_per_m: 0.0,
    });
    assert_eq!(
        RichPlant::new(&m).unwrap_err().key,
        "effects.transmission.link_mass_kg"
    );
}

#[test]
fn non_finite_commands_and_durations_are_harmless() {
    let mut m = base();
    m.transmission = Some(Transmission {
        link_mass_kg: 0.02,
        stiffness_n_per_m: 1e4,
        damping_ns_per_m: 1.0,
    });
    let mut p = RichPlant::new(&m).unwrap();
    p.advance(f64::NAN, 1e-3);
    p.advance(f64::INFINITY, 1e-3);
    p.advance(1.0, f64::NAN);
    p.advance(1.0, -1.0);
    assert_eq!(p.position_m(), 0.0);
    assert_eq!(p.encoder_count(), 0);
}

#[test]
fn a_held_plant_is_in_static_equilibrium_under_its_holding_force() {
    // The link and hand of `link_with_hand`, a 500 Hz filter.
    let mut m = link_with_hand();
    m.amplifier = Some(Amplifier {
        cutoff_hz: Some(500.0),
        damping_ratio: 0.7,
        force_limit_n: None,
        deadband_n: None,
    });
    let mut p = RichPlant::new(&m).unwrap();
    let x1 = 2e-4;
    p.set_held(x1);
    // The link where the transmission balances the hand: x₂ = k_t·x₁/(k_t + k_h).
    let x2 = 1e4 * x1 / (1e4 + 100.0);
    assert!((p.link_position_m() - x2).abs() < 1e-15);
    // The filter carries the holding force k_t(x₁ − x₂) = k_h·x₂.
    assert!((p.actuator_force_n() - 100.0 * x2).abs() < 1e-12);
    // Commanding that force keeps everything where it is.
    for _ in 0..200 {
        p.advance(100.0 * x2, 1e-4);
    }
    assert!((p.position_m() - x1).abs() < 1e-12, "{}", p.position_m());
    assert!((p.link_position_m() - x2).abs() < 1e-12);
    // `set_state` instead leaves the link at x₁ with the filter idle: the same command moves it.
    p.set_state(x1, 0.0);
    for _ in 0..200 {
        p.advance(100.0 * x2, 1e-4);
    }
    assert!((p.link_position_m() - x2).abs() > 1e-9 || (p.position_m() - x1).abs() > 1e-9);
}
