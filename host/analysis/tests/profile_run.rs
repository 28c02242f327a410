//! The profile runner: the firmware's servo renders a profile against the virtual device's
//! plant. Expected results are the physics of the profile header: a spring comes to rest where
//! friction holds its force, a detent where its force falls under static friction.

use stiffwall_analysis::profile_run::{run, starts, within_one_count, Start};
use stiffwall_client::{ConnectSpec, Pace, VirtualSpec};
use stiffwall_proto::{DamperLaw, Profile, ProfileElement, Side};

fn spec(name: &str) -> VirtualSpec {
    ConnectSpec::preset(name, Pace::Fast)
        .virtual_spec()
        .unwrap()
        .unwrap()
}

fn profile(elements: &[ProfileElement]) -> Profile {
    let mut p = Profile::default();
    for e in elements {
        p.elements.push(*e).unwrap();
    }
    p
}

/// Static friction of the preset (its Coulomb c: the presets' rigid plants have F_s = c).
fn friction(s: &VirtualSpec) -> f64 {
    s.plant.coulomb
}

#[test]
fn a_detent_released_a_quarter_pitch_away_rests_within_one_count_of_its_minimum() {
    let s = spec("maxon-re35");
    let d = s.plant.resolution;
    let pitch = 40.5;
    // K_local = 2πA/(pitch·Δ) at 0.6 of the quiet ceiling 2c/Δ: A·sin(3πΔ/pitch) > c, so it
    // cannot rest two counts away, and KΔ/2 < c, so a count beside the minimum holds it.
    let a = 0.6 * 2.0 * friction(&s) / d * pitch * d / (2.0 * std::f64::consts::PI);
    assert!(a * (3.0 * std::f64::consts::PI / pitch).sin() > friction(&s));
    let p = profile(&[ProfileElement::Detents {
        first: 100,
        pitch_counts: pitch,
        count: 5,
        strength: a as f32,
        damping: 5e-3,
        damper: DamperLaw::default(),
    }]);
    let all = starts(&p, d, 0.0, 10);
    assert_eq!(all.len(), 5 * 2 + 2);
    for st in all.iter().filter(|s| s.label.contains("release")) {
        let r = run(&s, &p, st, 20_000, f64::NAN).unwrap();
        assert!(r.rests, "{}: does not rest", st.label);
        let j: usize = st.label.rsplit(' ').next().unwrap().parse().unwrap();
        let m = 100.0 + j as f64 * pitch;
        assert!(
            within_one_count(r.final_count(), m),
            "{}: rests at count {}, minimum {m}",
            st.label,
            r.final_count()
        );
    }
}

#[test]
fn a_wall_pushes_back_and_free_space_is_free() {
    let s = spec("maxon-re35");
    let d = s.plant.resolution;
    let k = 0.5 * 2.0 * friction(&s) / d;
    let p = profile(&[ProfileElement::Wall {
        position: 0,
        side: Side::Upper,
        stiffness: k as f32,
        damping: 0.0,
        damper: DamperLaw::default(),
    }]);
    // Released 10 counts into the wall: pushed out to the surface (count 0 or just outside).
    let inside = Start {
        label: "inside".into(),
        element: 0,
        position: 10.5 * d,
        velocity: 0.0,
    };
    let r = run(&s, &p, &inside, 20_000, f64::NAN).unwrap();
    assert!(r.rests && r.final_count() <= 1, "{}", r.final_count());
    // Released 10 counts outside: no force, it stays.
    let outside = Start {
        position: -9.5 * d,
        ..inside
    };
    let r = run(&s, &p, &outside, 2_000, f64::NAN).unwrap();
    assert!(r.counts.iter().all(|&n| n == -10), "{:?}", &r.counts[..10]);
}

/// Three times the quiet ceiling 2c/Δ: no count beside a minimum holds the detent's force
/// (K·Δ/2 > c), so from no start does it come to rest at a minimum: it chatters, grows, or is
/// thrown out of its train. Damped or not.
#[test]
fn a_detent_far_above_the_quiet_ceiling_never_rests_at_a_minimum() {
    let s = spec("maxon-re35");
    let d = s.plant.resolution;
    let pitch = 40.5;
    let a = 3.0 * 2.0 * friction(&s) / d * pitch * d / (2.0 * std::f64::consts::PI);
    for b in [0.0, 5e-3] {
        let p = profile(&[ProfileElement::Detents {
            first: 100,
            pitch_counts: pitch,
            count: 3,
            strength: a as f32,
            damping: b,
            damper: DamperLaw::default(),
        }]);
        let minima = stiffwall_analysis::profile_run::detent_minima(&p.elements[0]);
        for st in starts(&p, d, 0.0, 10) {
            let r = run(&s, &p, &st, 20_000, f64::NAN).unwrap();
            let at_minimum = minima.iter().any(|&m| within_one_count(r.final_count(), m));
            assert!(
                !(r.rests && at_minimum),
                "B = {b}: {}: rests at {}",
                st.label,
                r.final_count()
            );
        }
    }
}
