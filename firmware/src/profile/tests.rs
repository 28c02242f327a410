//! The profile's tests: a one-element wall or spring is the config's wall bit for bit, the
//! detent force against an f64 reference of the protocol header's law, validation's refusals,
//! and the servo rendering random valid profiles within the force limit.

use super::*;
use crate::channels::Channels;
use crate::config::BoardInfo;
use crate::hal::{HeldCode, SampledCount};
use crate::numeric::{Fx32, F32};
use crate::numeric::{Fx64, Numeric};
use crate::Servo;
use proptest::prelude::*;
use stiffwall_proto::profile::Profile;
use stiffwall_proto::profile::{ProfileElement, ProfileField, Side};
use stiffwall_proto::{DamperLaw, ServoConfig, WallMode};

fn board() -> BoardInfo {
    BoardInfo {
        encoder_bits: 32,
        ..BoardInfo::default()
    }
}

fn profile(elements: &[ProfileElement]) -> Profile {
    let mut p = Profile::default();
    for e in elements {
        p.elements.push(*e).unwrap();
    }
    p
}

/// The counts and differences the exactness test walks: near the wall, around the
/// saturation counts, and far out to the `i32` ends.
fn probe_counts() -> std::vec::Vec<i32> {
    let mut v: std::vec::Vec<i32> = (-300..300).collect();
    for k in 0..31 {
        let x = 1i32 << k;
        v.extend([x - 1, x, x + 1, -x - 1, -x, -x + 1]);
    }
    v.extend([i32::MIN, i32::MIN + 1, i32::MAX - 1, i32::MAX]);
    v
}

/// A one-element profile with the config's K, B and law at its wall position: the element's
/// code is the config wall's for every n and dn (one-sided: `Upper`; two-sided: `Spring`, and
/// `Lower` below the wall).
fn check_exact<N: Numeric>(cfg: &ServoConfig) {
    let b = board();
    let mut ch = Channels::<N>::for_numeric();
    let (sp, _hp) = ch.split();
    let two: Servo<'_, N> = Servo::new(
        b,
        &ServoConfig {
            wall: WallMode::Bidirectional,
            ..*cfg
        },
        sp,
    );
    let mut ch1 = Channels::<N>::for_numeric();
    let (sp1, _hp1) = ch1.split();
    let one: Servo<'_, N> = Servo::new(
        b,
        &ServoConfig {
            wall: WallMode::OneSided,
            ..*cfg
        },
        sp1,
    );
    let (k, bb, law, at) = (cfg.stiffness, cfg.damping, cfg.damper, cfg.wall_position);
    let wall = |side| ProfileElement::Wall {
        position: at,
        side,
        stiffness: k,
        damping: bb,
        damper: law,
    };
    let spring = ProfileElement::Spring {
        center: at,
        stiffness: k,
        damping: bb,
        damper: law,
    };
    let p = profile(&[wall(Side::Upper), spring, wall(Side::Lower)]);
    assert_eq!(validate(&p, cfg, &b), Ok(()));
    let t = compile::<N>(&p, cfg, &b);
    let [upper, spring, lower] = t.elements() else {
        panic!("three elements");
    };
    let counts = probe_counts();
    for &n in &counts {
        for &dn in counts.iter().step_by(7).chain([-2, -1, 0, 1, 2].iter()) {
            assert_eq!(
                upper.code(n, dn, 0),
                one.wall_code(n, dn),
                "upper n {n} dn {dn}"
            );
            assert_eq!(
                spring.code(n, dn, 0),
                two.wall_code(n, dn),
                "spring n {n} dn {dn}"
            );
            let below = if n < 0 { two.wall_code(n, dn) } else { 0 };
            assert_eq!(lower.code(n, dn, 0), below, "lower n {n} dn {dn}");
        }
    }
}

#[test]
fn a_one_element_wall_is_the_config_wall_bit_for_bit() {
    for (k, b, law, shift, at) in [
        (100.0, 0.0, DamperLaw::DeadBand { counts: 1 }, 0, 0),
        (250.5, 0.17, DamperLaw::DeadBand { counts: 1 }, 0, 1234),
        (30.0, 0.04, DamperLaw::Difference, 2, -777),
        (
            200.0,
            0.1,
            DamperLaw::DeadBand { counts: 3 },
            1,
            i32::MAX - 5,
        ),
        (0.0, 0.2, DamperLaw::Difference, 0, i32::MIN + 9),
        (427.0, 0.21, DamperLaw::DeadBand { counts: 1 }, 0, 5),
    ] {
        let cfg = ServoConfig {
            stiffness: k,
            damping: b,
            damper: law,
            coarsen_shift: shift,
            wall_position: at,
            force_limit: 0.3,
            ..ServoConfig::default()
        };
        check_exact::<Fx64>(&cfg);
        check_exact::<Fx32>(&cfg);
        check_exact::<F32>(&cfg);
    }
}

/// The protocol header's detent force in f64: −A·sin(2π·d/pitch), d = (n + ½)·Δ_eff counts
/// from `first`, inside d ∈ [−pitch/2, (count − ½)·pitch), 0 outside; in codes.
fn detent_reference(n: i64, shift: u8, pitch: f64, count: u16, a_codes: f64) -> f64 {
    let d = (n as f64 + 0.5) * f64::from(1u32 << shift);
    if d < -pitch / 2.0 || d >= (f64::from(count) - 0.5) * pitch {
        return 0.0;
    }
    -a_codes * libm::sin(core::f64::consts::TAU * d / pitch)
}

#[test]
fn detents_follow_the_reference_within_one_code() {
    let b = board();
    for (pitch, count, strength, shift, first) in [
        (4096.0 / 24.0, 24u16, 0.3f32, 0u8, 0i32),
        (4096.0 / 24.0, 24, 0.3, 2, -5000),
        (2.0, 7, 0.327, 0, 100),
        (8.5, 100, 0.2, 2, 77),
        (1000.0 / 3.0, 4096, 0.31, 0, -600_000),
        (4096.0 / 24.0, 1, 0.0001, 0, 3),
    ] {
        let cfg = ServoConfig {
            coarsen_shift: shift,
            ..ServoConfig::default()
        };
        let p = profile(&[ProfileElement::Detents {
            first,
            pitch_counts: pitch,
            count,
            strength,
            damping: 0.0,
            damper: DamperLaw::Difference,
        }]);
        assert_eq!(validate(&p, &cfg, &b), Ok(()), "pitch {pitch}");
        let t = compile::<Fx64>(&p, &cfg, &b);
        let a = f64::from(strength) / f64::from(b.force_per_code);
        let de = 1i64 << shift;
        let extent = (f64::from(count) * pitch / de as f64) as i64 + 20;
        let lo = -(pitch as i64 / de) - 20;
        let step = (extent / 20_000).max(1);
        for n in (lo..extent).step_by(step as usize).chain(lo..lo + 60) {
            let pos = i64::from(first) + n * de;
            let Ok(pos) = i32::try_from(pos) else {
                continue;
            };
            let got = t.code(pos, pos);
            let want = detent_reference(n, shift, pitch, count, a);
            assert!(
                (f64::from(got) - want).abs() <= 1.0,
                "pitch {pitch} n {n}: {got} vs {want}"
            );
        }
        // Far beyond both ends: nothing.
        assert_eq!(t.code(i32::MAX, i32::MAX), 0);
        assert_eq!(t.code(i32::MIN, i32::MIN), 0);
    }
}

#[test]
fn validation_names_the_element_the_field_and_its_range() {
    let b = board();
    let cfg = ServoConfig::default();
    let kmax = f64::from(b.max_stiffness(0));
    let ok = ProfileElement::Spring {
        center: 0,
        stiffness: 100.0,
        damping: 0.0,
        damper: DamperLaw::Difference,
    };
    let refused = |e: ProfileElement| validate(&profile(&[ok, ok, e]), &cfg, &b).unwrap_err();
    let e = refused(ProfileElement::Wall {
        position: 0,
        side: Side::Lower,
        stiffness: f32::NAN,
        damping: 0.0,
        damper: DamperLaw::Difference,
    });
    assert_eq!(
        (e.element, e.field, e.min, e.max),
        (2, ProfileField::Stiffness, 0.0, kmax)
    );
    let detents = |pitch, count| ProfileElement::Detents {
        first: 0,
        pitch_counts: pitch,
        count,
        strength: 0.1,
        damping: 0.0,
        damper: DamperLaw::DeadBand { counts: 1 },
    };
    assert_eq!(refused(detents(1.5, 3)).field, ProfileField::PitchCounts);
    assert_eq!(refused(detents(1.5, 3)).min, 2.0);
    assert_eq!(refused(detents(1e9, 3)).field, ProfileField::PitchCounts);
    assert_eq!(refused(detents(10.0, 0)).field, ProfileField::Count);
    assert_eq!(refused(detents(10.0, 4097)).max, 4096.0);
    let viscous = ProfileElement::Viscous {
        from: 5,
        to: 5,
        damping: 0.0,
        damper: DamperLaw::Difference,
    };
    let e = refused(viscous);
    assert_eq!((e.field, e.min), (ProfileField::To, 6.0));
    let e = refused(ProfileElement::Spring {
        center: 0,
        stiffness: 1.0,
        damping: 0.0,
        damper: DamperLaw::DeadBand { counts: 0 },
    });
    assert_eq!(e.field, ProfileField::Damper);
    // A pitch of 2 counts is 1 effective count at shift 1: refused there.
    let shifted = ServoConfig {
        coarsen_shift: 1,
        ..cfg
    };
    let e = validate(&profile(&[detents(2.0, 3)]), &shifted, &b).unwrap_err();
    assert_eq!(
        (e.element, e.field, e.min),
        (0, ProfileField::PitchCounts, 4.0)
    );
}

/// A valid element, from random draws within the ranges `validate` allows.
fn element_strategy() -> impl Strategy<Value = ProfileElement> {
    let law = prop_oneof![
        Just(DamperLaw::Difference),
        (1u8..=8).prop_map(|counts| DamperLaw::DeadBand { counts })
    ];
    let kmax = board().max_stiffness(0);
    let bmax = board().max_damping(0, 1000);
    (
        0u8..4,
        any::<i32>(),
        0.0f32..=kmax,
        0.0f32..=bmax,
        law,
        2.0f64..5000.0,
        1u16..=300,
        0.0f32..=0.3,
        any::<bool>(),
        1i32..100_000,
    )
        .prop_map(
            |(kind, at, k, b, damper, pitch, count, a, upper, width)| match kind {
                0 => ProfileElement::Wall {
                    position: at,
                    side: if upper { Side::Upper } else { Side::Lower },
                    stiffness: k,
                    damping: b,
                    damper,
                },
                1 => ProfileElement::Spring {
                    center: at,
                    stiffness: k,
                    damping: b,
                    damper,
                },
                2 => ProfileElement::Detents {
                    first: at / 4,
                    pitch_counts: pitch,
                    count,
                    strength: a,
                    damping: b,
                    damper,
                },
                _ => ProfileElement::Viscous {
                    from: at.saturating_sub(width),
                    to: at,
                    damping: b,
                    damper,
                },
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// Random valid profiles, random counts and jumps: the tick never panics and its output
    /// stays within the force limit.
    #[test]
    fn random_profiles_render_within_the_force_limit(
        elements in proptest::collection::vec(element_strategy(), 1..=16),
        counts in proptest::collection::vec(any::<i32>(), 1..40),
        near in proptest::collection::vec(-3000i32..3000, 1..40),
    ) {
        let b = board();
        let cfg = ServoConfig {
            encoder_jump_counts: u32::MAX >> 2,
            heartbeat_timeout_ms: 0,
            ..ServoConfig::default()
        };
        let p = profile(&elements);
        if validate(&p, &cfg, &b).is_err() {
            return Ok(()); // a random pitch beyond a train's i32 extent
        }
        let mut ch = Channels::new();
        let (sp, _hp) = ch.split();
        let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
        s.set_profile(compile(&p, &cfg, &b));
        prop_assert!(!s.experiment_running());
        let limit = s.gains().limit;
        let mut out = HeldCode(0);
        for (i, c) in counts.iter().chain(near.iter()).enumerate() {
            let code = s.tick(i as u32, &mut SampledCount(*c as u32), &mut out);
            prop_assert!(code.unsigned_abs() <= limit.unsigned_abs(), "{} > {}", code, limit);
        }
    }
}
