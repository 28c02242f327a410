//! Tests of the config module: validation field by field, the error text, and the gains
//! derived from known configs.

use super::*;
use crate::numeric::{Fx64, Numeric, RangeBound};
use stiffwall_proto::{ConfigField, DamperLaw, ServoConfig, MAX_DEADBAND_COUNTS};

#[test]
fn default_config_is_valid_and_each_field_is_checked() {
    let b = BoardInfo::default();
    let c = ServoConfig::default();
    assert_eq!(validate(&c, &b), Ok(()));
    let bad: [(ServoConfig, ConfigField); 16] = [
        (
            ServoConfig {
                stiffness: -1.0,
                ..c
            },
            ConfigField::Stiffness,
        ),
        (
            ServoConfig {
                stiffness: f32::NAN,
                ..c
            },
            ConfigField::Stiffness,
        ),
        (
            ServoConfig {
                damping: f32::INFINITY,
                ..c
            },
            ConfigField::Damping,
        ),
        (
            ServoConfig {
                servo_rate_hz: 99,
                ..c
            },
            ConfigField::ServoRateHz,
        ),
        (
            ServoConfig {
                extra_delay_ticks: 32,
                ..c
            },
            ConfigField::ExtraDelayTicks,
        ),
        (
            ServoConfig {
                coarsen_shift: 17,
                ..c
            },
            ConfigField::CoarsenShift,
        ),
        (
            ServoConfig {
                force_limit: 0.0,
                ..c
            },
            ConfigField::ForceLimit,
        ),
        (
            ServoConfig {
                max_velocity: -0.1,
                ..c
            },
            ConfigField::MaxVelocity,
        ),
        (
            ServoConfig {
                energy_limit: 0.0,
                ..c
            },
            ConfigField::EnergyLimit,
        ),
        (
            ServoConfig {
                energy_growth_cycles: 0,
                ..c
            },
            ConfigField::EnergyGrowthCycles,
        ),
        (
            ServoConfig {
                encoder_jump_counts: 0,
                ..c
            },
            ConfigField::EncoderJumpCounts,
        ),
        (
            ServoConfig {
                safe_damping: -1.0,
                ..c
            },
            ConfigField::SafeDamping,
        ),
        (
            ServoConfig {
                damper: DamperLaw::DeadBand { counts: 0 },
                ..c
            },
            ConfigField::Damper,
        ),
        (
            ServoConfig {
                damper: DamperLaw::DeadBand {
                    counts: MAX_DEADBAND_COUNTS + 1,
                },
                ..c
            },
            ConfigField::Damper,
        ),
        (
            ServoConfig {
                travel_min: Some(10),
                travel_max: Some(10),
                ..c
            },
            ConfigField::TravelMax,
        ),
        (
            ServoConfig {
                travel_min: Some(i32::MAX),
                travel_max: Some(i32::MIN),
                ..c
            },
            ConfigField::TravelMax,
        ),
    ];
    for (cfg, field) in bad {
        assert_eq!(validate(&cfg, &b).map_err(|e| e.field), Err(field));
    }
    let e = validate(
        &ServoConfig {
            servo_rate_hz: 50_000,
            ..c
        },
        &b,
    )
    .unwrap_err();
    assert_eq!((e.min, e.max), (100.0, 20_000.0));
}

#[test]
fn gains_of_a_known_config() {
    let b = BoardInfo {
        resolution: 1e-5,
        force_per_code: 1e-3,
        ..BoardInfo::default()
    };
    let c = ServoConfig {
        stiffness: 1000.0,
        coarsen_shift: 1,
        force_limit: 1.0,
        ..ServoConfig::default()
    };
    let g: Gains<Fx64> = Gains::from_config(&c, &b);
    // K·Δ_eff/2/fs = 1000 · 2e-5 / 2 / 1e-3 = 10 codes.
    assert!((Fx64::to_f64(g.k_half) - 10.0).abs() < 1e-4);
    assert_eq!(g.limit, 1000);
    assert_eq!(g.shift, 1);
}

#[test]
fn config_error_names_the_field_and_its_range() {
    use std::string::ToString;
    let e = validate(
        &ServoConfig {
            servo_rate_hz: 50_000,
            ..ServoConfig::default()
        },
        &BoardInfo::default(),
    )
    .unwrap_err();
    let err: &dyn core::error::Error = &e;
    assert_eq!(err.to_string(), "servo_rate_hz must be within [100, 20000]");
    let e = validate(
        &ServoConfig {
            damper: DamperLaw::DeadBand { counts: 0 },
            ..ServoConfig::default()
        },
        &BoardInfo::default(),
    )
    .unwrap_err();
    assert_eq!((e.field, e.min, e.max), (ConfigField::Damper, 1.0, 8.0));
    assert_eq!(
        e.to_string(),
        "damper: the dead band must be within [1, 8] counts (use `difference` for no dead band)"
    );
}

/// The travel window: off by default (and so in every older record), either end alone, or
/// both with min < max; min ≥ max is refused naming `travel_max` and its range.
#[test]
fn travel_window_is_checked_and_derived() {
    use std::string::ToString;
    let b = BoardInfo::default();
    let c = ServoConfig::default();
    assert_eq!((c.travel_min, c.travel_max), (None, None));
    let window = |lo: Option<i32>, hi: Option<i32>| ServoConfig {
        travel_min: lo,
        travel_max: hi,
        ..c
    };
    for (lo, hi) in [
        (None, None),
        (Some(-5), None),
        (None, Some(-5)),
        (Some(-5), Some(-4)),
        (Some(i32::MIN), Some(i32::MAX)),
    ] {
        assert_eq!(validate(&window(lo, hi), &b), Ok(()), "{lo:?}..{hi:?}");
    }
    let e = validate(&window(Some(100), Some(-100)), &b).unwrap_err();
    assert_eq!(
        (e.field, e.min, e.max),
        (ConfigField::TravelMax, 101.0, f64::from(i32::MAX))
    );
    assert_eq!(
        e.to_string(),
        "travel_max must be above travel_min, within [101, 2147483647] raw counts"
    );
    let g = |lo, hi| Gains::<Fx64>::from_config(&window(lo, hi), &b).travel;
    assert_eq!(g(None, None), RangeBound::new(i32::MIN, i32::MAX));
    let w = g(Some(-3), Some(7));
    assert!(w.outside(-4) && !w.outside(-3) && !w.outside(7) && w.outside(8));
    assert!(w.outside(i32::MIN) && w.outside(i32::MAX));
    let lower = g(Some(-3), None);
    assert!(lower.outside(-4) && !lower.outside(i32::MAX));
    let upper = g(None, Some(7));
    assert!(!upper.outside(i32::MIN) && upper.outside(8));
}

/// beyond the dead band otherwise (every law in range is accepted).
#[test]
fn damper_band_is_the_law_and_the_on_off_test() {
    let b = BoardInfo::default();
    let gains = |damping: f32, damper: DamperLaw| {
        let c = ServoConfig {
            damping,
            damper,
            ..ServoConfig::default()
        };
        assert_eq!(validate(&c, &b), Ok(()));
        Gains::<Fx64>::from_config(&c, &b)
    };
    for law in [DamperLaw::Difference, DamperLaw::DeadBand { counts: 3 }] {
        let off = gains(0.0, law);
        assert!(!off.damping_on);
        assert!([i32::MIN, -5, 0, 5, i32::MAX]
            .iter()
            .all(|&dn| !off.damper_band.exceeded(dn)));
    }
    let diff = gains(0.01, DamperLaw::Difference);
    assert!(!diff.damper_band.exceeded(0));
    assert!(diff.damper_band.exceeded(1) && diff.damper_band.exceeded(-1));
    for counts in 1..=MAX_DEADBAND_COUNTS {
        let g = gains(0.01, DamperLaw::DeadBand { counts });
        let c = i32::from(counts);
        assert!(!g.damper_band.exceeded(c) && !g.damper_band.exceeded(-c));
        assert!(g.damper_band.exceeded(c + 1) && g.damper_band.exceeded(-c - 1));
        assert!(g.damper_band.exceeded(i32::MIN) && g.damper_band.exceeded(i32::MAX));
    }
}
