//! The profile module's tests: lowering and the check on literal files and envelopes, every
//! expected number derived by hand in the comments.

use super::*;
use stiffwall_proto::{DamperLaw, ProfileElement, Side};

const DB1: DamperLaw = DamperLaw::DeadBand { counts: 1 };

fn parse(text: &str) -> ProfileFile {
    ProfileFile::from_toml(text).unwrap_or_else(|e| panic!("{e}"))
}

fn linear(resolution: f64) -> Device {
    Device {
        rotational: false,
        resolution,
    }
}

fn rotary(counts_per_rev: f64) -> Device {
    Device {
        rotational: true,
        resolution: core::f64::consts::TAU / counts_per_rev,
    }
}

fn envelope(
    device: Device,
    frontier: &[(f64, f64)],
    margin: f64,
    ceiling: f64,
    fs: f64,
) -> Envelope {
    Envelope {
        source: "by hand".into(),
        device,
        frontier: frontier
            .iter()
            .map(|&(b, k)| Point {
                b,
                k: Some(k),
                damper: DB1,
            })
            .collect(),
        margin,
        quiet_ceiling: ceiling,
        coulomb: fs,
        static_friction: fs,
        force_limit: None,
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-4 * b.abs().max(1e-12)
}

const KNOB: &str = r#"
[profile]
name = "knob"
axis = "rotary"

[[element]]
kind = "detents"
first = 0
count = 13
per_rev = 24
strength = 0.1
damping = 0.005

[[element]]
kind = "end-stops"
min = -0.1309
max = 3.2725
stiffness = 2.5
"#;

/// 8192 counts/rev: Δ = 7.6699e-4 rad; pitch 8192/24 = 341.33 counts; min −0.1309/Δ = −170.67
/// → −171, max 3.2725/Δ = 4266.7 → 4267; the end stops become a lower and an upper wall.
#[test]
fn a_knob_lowers_to_counts() {
    let l = lower(&parse(KNOB), &rotary(8192.0)).unwrap();
    let w = l.wire();
    assert_eq!(w.elements.len(), 3);
    let ProfileElement::Detents {
        first,
        pitch_counts,
        count,
        ..
    } = w.elements[0]
    else {
        panic!("{w:?}")
    };
    assert_eq!((first, count), (0, 13));
    assert!(close(pitch_counts, 341.333_333));
    assert!(matches!(
        w.elements[1],
        ProfileElement::Wall {
            position: -171,
            side: Side::Lower,
            ..
        }
    ));
    assert!(matches!(
        w.elements[2],
        ProfileElement::Wall {
            position: 4267,
            side: Side::Upper,
            ..
        }
    ));
    assert_eq!(l.elements[2].origin.part, Some("upper"));
    // In counts the same file: positions as written.
    let counts = KNOB
        .replace(
            "axis = \"rotary\"",
            "axis = \"rotary\"\npositions = \"counts\"",
        )
        .replace("-0.1309", "-171")
        .replace("3.2725", "4267");
    assert_eq!(lower(&parse(&counts), &rotary(8192.0)).unwrap().wire(), w);
}

/// A linear device, Δ = 10 µm; frontier K* 600 N/m at B = 0 and 2000 N/m at B = 2 N·s/m,
/// margin 0.8, quiet ceiling 1500 N/m, F_s = 0.0075 N.
#[test]
fn each_element_against_its_limit() {
    let text = r#"
[profile]
name = "mixed"
axis = "linear"

[[element]]   # 1: counts ≥ 1000, K 1000 at B 2: min(0.8 × 2000, 1500) = 1500 (ceiling), 1.5
kind = "wall"
at = 0.01
side = "upper"
stiffness = 1000
damping = 2.0

[[element]]   # 2: counts < −1000, K 500 at B 0: 0.8 × 600 = 480 < 500, FAIL, strongest 480
kind = "wall"
at = -0.01
side = "lower"
stiffness = 500

[[element]]   # 3: minima at −500, −300, −100 counts; K = 2π·0.1/0.002 = 314.16 N/m
kind = "detents"
first = -0.005
pitch = 0.002
count = 3
strength = 0.1

[[element]]   # 4: counts −600..=−301 over the detents: B 1 adds to theirs
kind = "viscous"
from = -0.006
to = -0.003
damping = 1.0

[[element]]   # 5: B 3 above the largest B tried (2)
kind = "viscous"
from = 0.0
to = 0.005
damping = 3.0
"#;
    let dev = linear(1e-5);
    let env = envelope(dev, &[(0.0, 600.0), (2.0, 2000.0)], 0.8, 1500.0, 0.0075);
    let r = check(&lower(&parse(text), &dev).unwrap(), &env);
    assert!(!r.pass);
    let e = &r.elements;
    // 1
    assert!(e[0].pass && e[0].at_quiet_ceiling);
    assert_eq!(e[0].k_limit, Some(1500.0));
    assert!(close(e[0].margin.unwrap(), 1.5));
    // 2
    assert!(!e[1].pass);
    assert!(close(e[1].k_limit.unwrap(), 480.0));
    assert!(close(e[1].margin.unwrap(), 0.96));
    let Some(Strongest::Stiffness(k)) = e[1].strongest else {
        panic!("{:?}", e[1])
    };
    assert!(close(k, 480.0));
    // 3: span: centres in [−600, 0): counts −600..=−1; overlapped by 4: B = 0 + 1, between
    // B = 0 and 2: K* = min(600, 2000) = 600, limit 480, margin 480/314.16 = 1.5279.
    assert_eq!((e[2].span.lo, e[2].span.hi), (Some(-600), Some(-1)));
    assert_eq!(e[2].overlaps, vec![4]);
    assert!(close(e[2].k_local, 314.159_27));
    assert_eq!(e[2].b_local, 1.0);
    assert!(close(e[2].margin.unwrap(), 1.527_89));
    // Centring: sin(3π/200) = 0.0471064, weakest 0.0075/0.0471064 = 0.15921 N > 0.1: FAIL;
    // count 1 (centre 1.5 counts) feels 0.1·sin(2π·1.5/200) = 0.00471 ≤ 0.0075, count 2
    // 0.1·sin(2π·2.5/200) = 0.00785 > 0.0075: rests up to 1 count.
    let ct = e[2].centring.unwrap();
    assert!(close(ct.weakest_strength.unwrap(), 0.159_214));
    assert_eq!((ct.pass, ct.rests_up_to_counts), (false, Some(1)));
    assert!(!e[2].pass);
    assert!(e[2].problems[0].contains("rests up to 1 counts"));
    // 4: K = the detents' 314.16, B 1: the same limit and margin.
    assert!(e[3].pass);
    assert!(close(e[3].k_local, 314.159_27));
    // 5: no verified limit; its B at most 2.
    assert_eq!(e[4].k_limit, None);
    assert_eq!(e[4].strongest, Some(Strongest::Damping(2.0)));
    let text = render(&r);
    assert!(text.contains("verdict: FAIL (element 2 (wall), element 3 (detents), element 5"));
    assert!(text.contains("1500 N/m (ceiling)"), "{text}");
}

/// A spring (0.5 N·m/rad) under a wall (1.5): both feel 2.0 > 0.9 × 2.0 = 1.8; the wall may
/// have 1.8 − 0.5 = 1.3, the spring 1.8 − 1.5 = 0.3.
#[test]
fn overlapping_stiffness_adds() {
    let text = r#"
[profile]
name = "spring and wall"
axis = "rotary"
[[element]]
kind = "spring"
center = 0
stiffness = 0.5
[[element]]
kind = "wall"
at = 0.1
side = "upper"
stiffness = 1.5
"#;
    let dev = rotary(6_283.185_307);
    let env = envelope(dev, &[(0.0, 2.0)], 0.9, 10.0, 0.005);
    let r = check(&lower(&parse(text), &dev).unwrap(), &env);
    let [s, w] = &r.elements[..] else { panic!() };
    assert!(close(s.k_local, 2.0) && close(w.k_local, 2.0));
    assert!(!s.pass && !w.pass);
    let (Some(Strongest::Stiffness(ks)), Some(Strongest::Stiffness(kw))) =
        (s.strongest, w.strongest)
    else {
        panic!("{r:?}")
    };
    assert!(close(ks, 0.3) && close(kw, 1.3));
}

/// 24 detents per revolution of 8192 counts, A = 0.1 N·m: K = 2π·0.1/(2π/24) = 2.4 N·m/rad
/// above 0.8 × 1.3 = 1.04: the strongest passing A = 1.04/24 = 0.04333 N·m. It centres:
/// F_s/sin(3π/341.33) = 0.002/0.0276082 = 0.07244 N·m < 0.1.
#[test]
fn a_too_strong_detent_gets_its_strongest_passing_strength() {
    let text = r#"
[profile]
name = "strong"
axis = "rotary"
[[element]]
kind = "detents"
first = 0.0
count = 4
per_rev = 24
strength = 0.1
"#;
    let dev = rotary(8192.0);
    let env = envelope(dev, &[(0.0, 1.3), (0.005, 4.7)], 0.8, 5.2, 0.002);
    let r = check(&lower(&parse(text), &dev).unwrap(), &env);
    let d = &r.elements[0];
    assert!(close(d.k_local, 2.4));
    assert!(close(d.k_limit.unwrap(), 1.04));
    let Some(Strongest::Strength(a)) = d.strongest else {
        panic!("{d:?}")
    };
    assert!(close(a, 0.043_333_3));
    assert!(close(
        d.centring.unwrap().weakest_strength.unwrap(),
        0.072_442
    ));
    assert!(d.centring.unwrap().pass);
    assert!(render(&r).contains("strongest that passes: strength = 0.04333 N·m"));
}

/// The same train of 4 detents at 24 per revolution within its stiffness limit on a device
/// whose largest force is 0.08 N·m: A = 0.1 N·m is refused by the device, so the check fails
/// it and the strongest passing strength is that limit, 0.08 N·m (the stiffness limit alone,
/// 0.8 × 4.7 = 3.76 N·m/rad at B = 0.005, would allow 3.76/24 = 0.1567 N·m).
#[test]
fn a_detent_beyond_the_device_force_limit_fails() {
    let text = r#"
[profile]
name = "strong"
axis = "rotary"
[[element]]
kind = "detents"
first = 0.0
count = 4
per_rev = 24
strength = 0.1
damping = 0.005
"#;
    let dev = rotary(8192.0);
    let env = envelope(dev, &[(0.0, 1.3), (0.005, 4.7)], 0.8, 5.2, 0.002);
    let lowered = lower(&parse(text), &dev).unwrap();
    assert!(check(&lowered, &env).pass);
    let r = check(&lowered, &env.with_force_limit(0.08));
    let d = &r.elements[0];
    assert!(!d.pass && !r.pass);
    assert!(matches!(d.strongest, Some(Strongest::Strength(a)) if close(a, 0.08)));
    let text = render(&r);
    assert!(
        text.contains("strength A = 0.1000 N·m is above the device's force limit 0.08000 N·m"),
        "{text}"
    );
}

fn refused(text: &str, dev: Device) -> String {
    lower(&parse(text), &dev).unwrap_err().to_string()
}

const HEAD: &str = "[profile]\nname = \"x\"\naxis = \"linear\"\n";

#[test]
fn bad_numbers_are_refused_with_their_field_and_range() {
    let dev = linear(1e-5);
    let wall = |k: &str, b: &str| {
        format!("{HEAD}[[element]]\nkind = \"wall\"\nat = 0\nside = \"upper\"\nstiffness = {k}\ndamping = {b}\n")
    };
    let m = refused(&wall("nan", "0"), dev);
    assert_eq!(
        m,
        "element 1 (wall): `stiffness` must be finite and in [1e-6, 1e8] N/m (N·m/rad on a \
         rotary device) (got NaN)"
    );
    let m = refused(&wall("100", "-1"), dev);
    assert!(
        m.contains("`damping` must be finite, in [0, 1e4]") && m.ends_with("(got -1)"),
        "{m}"
    );
    let m = refused(&wall("1e300", "0"), dev);
    assert!(m.ends_with("(got 1e300)"), "{m}");
    let m = refused(&wall("100", "0").replace("at = 0", "at = inf"), dev);
    assert!(
        m.contains("`at` must be finite and within the encoder's range"),
        "{m}"
    );
    let m = refused(
        &wall("100", "0")
            .replace("dead", "x")
            .replace("damping = 0", "damper = \"dead-band-9\""),
        dev,
    );
    assert!(
        m.contains("`damper` must be a damper law: dead band 9 counts"),
        "{m}"
    );
}

#[test]
fn detent_pitches_are_one_of_two_and_at_least_two_counts() {
    let det = |extra: &str| {
        format!(
            "{HEAD}[[element]]\nkind = \"detents\"\nfirst = 0\ncount = 3\nstrength = 1\n{extra}"
        )
    };
    let dev = linear(1e-5);
    assert!(refused(&det("pitch = 0.001\nper_rev = 3\n"), dev)
        .contains("exactly one of `pitch` and `per_rev` (got both)"));
    assert!(refused(&det(""), dev).contains("(got neither)"));
    assert!(
        refused(&det("per_rev = 24\n"), dev).contains("`per_rev` must be only on a rotary axis")
    );
    let m = refused(&det("pitch = 1.5e-5\n"), dev);
    assert!(
        m.contains("`pitch` must be finite and at least 2 counts (2.000e-5 m)"),
        "{m}"
    );
    // 8192 counts per revolution: at most 4096 detents per revolution.
    let rot = det("per_rev = 5000\n").replace("linear", "rotary");
    let m = refused(&rot, rotary(8192.0));
    assert!(m.contains("in (0, 4096] detents per revolution"), "{m}");
    let m = refused(
        &det("pitch = 0.001\n").replace("count = 3", "count = 0"),
        dev,
    );
    assert!(
        m.contains("`count` must be a whole number in [1, 4096] (got 0)"),
        "{m}"
    );
}

#[test]
fn nonsense_overlaps_are_refused_naming_both_elements() {
    let dev = linear(1e-5);
    let wall = |at: f64, side: &str| {
        format!("[[element]]\nkind = \"wall\"\nat = {at}\nside = \"{side}\"\nstiffness = 100\n")
    };
    let m = refused(
        &format!("{HEAD}{}{}", wall(0.001, "lower"), wall(0.001, "upper")),
        dev,
    );
    assert!(m.starts_with("element 1 (wall) and element 2 (wall): the lower wall occupies the counts below 100 and the upper wall the counts from 100 on: no free space"), "{m}");
    let m = refused(
        &format!("{HEAD}{}{}", wall(0.001, "upper"), wall(0.002, "upper")),
        dev,
    );
    assert!(m.contains("two upper walls (at counts 100 and 200)"), "{m}");
    let det = |first: f64| {
        format!("[[element]]\nkind = \"detents\"\nfirst = {first}\npitch = 0.001\ncount = 2\nstrength = 1\n")
    };
    // Trains at 0 and 0.0015 m (100 counts each): counts −50..=149 and 100..=299 meet.
    let m = refused(&format!("{HEAD}{}{}", det(0.0), det(0.0015)), dev);
    assert!(
        m.contains("two detent trains overlap (counts -50..=149 and 100..=299)"),
        "{m}"
    );
    assert!(lower(&parse(&format!("{HEAD}{}{}", det(0.0), det(0.002))), &dev).is_ok());
    let m = refused(
        &format!("{HEAD}[[element]]\nkind = \"viscous\"\nfrom = 0.01\nto = 0.01\ndamping = 1\n"),
        dev,
    );
    assert!(
        m.contains("`to` must be above `from` by at least one count"),
        "{m}"
    );
    let m = refused(
        &format!("{HEAD}[[element]]\nkind = \"end-stops\"\nmin = 0.01\nmax = 0.0\nstiffness = 1\n"),
        dev,
    );
    assert!(
        m.starts_with("element 1 (end-stops): `max` must be above `min`"),
        "{m}"
    );
}

#[test]
fn too_many_elements_and_the_wrong_axis_are_refused() {
    let dev = linear(1e-5);
    let stops = |i: usize| {
        format!(
            "[[element]]\nkind = \"end-stops\"\nmin = {}\nmax = {}\nstiffness = 1\n",
            -0.01 * (i as f64 + 1.0),
            0.01 * (i as f64 + 1.0)
        )
    };
    let mut text = HEAD.to_owned();
    for i in 0..8 {
        text += &stops(i);
    }
    text += "[[element]]\nkind = \"spring\"\ncenter = 0\nstiffness = 1\n";
    assert_eq!(
        refused(&text, dev),
        "the profile lowers to 17 elements (an `end-stops` element is two walls); the device \
         renders at most 16"
    );
    let m = refused(HEAD, rotary(8192.0));
    assert!(
        m.starts_with("[profile]: `axis` must be `rotary` on this device"),
        "{m}"
    );
}

/// A spring of 1000 N/m with a viscous zone B = 2 N·s/m over counts 0..=999: inside,
/// min(0.8 × 2000, 1500) = 1500 N/m holds it; outside, at B = 0, 0.8 × 600 = 480 N/m does not:
/// the spring fails by its worst piece (counts ≥ 1000 or < 0, alone), and may have 480 N/m.
#[test]
fn an_element_is_as_good_as_its_worst_piece() {
    let text = format!(
        "{HEAD}[[element]]\nkind = \"spring\"\ncenter = 0\nstiffness = 1000\n\
         [[element]]\nkind = \"viscous\"\nfrom = 0\nto = 0.01\ndamping = 2\n"
    );
    let dev = linear(1e-5);
    let env = envelope(dev, &[(0.0, 600.0), (2.0, 2000.0)], 0.8, 1500.0, 0.0075);
    let r = check(&lower(&parse(&text), &dev).unwrap(), &env);
    let [s, v] = &r.elements[..] else { panic!() };
    assert!(!s.pass);
    assert_eq!((s.piece.lo, s.piece.hi), (None, Some(-1)));
    assert!(s.overlaps.is_empty());
    assert!(close(s.k_limit.unwrap(), 480.0));
    assert_eq!(s.strongest, Some(Strongest::Stiffness(480.0)));
    assert!(v.pass);
    assert_eq!(
        (v.k_local, v.b_local, v.k_limit),
        (1000.0, 2.0, Some(1500.0))
    );
    assert_eq!(v.overlaps, vec![1]);
}
