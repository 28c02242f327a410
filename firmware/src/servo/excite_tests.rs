//! Unit tests of the excitation's centring spring: the profile's code plus the configured
//! wall's two-sided spring and damper (bit for bit the profile alone with K = 0 and B = 0).

use super::*;
use crate::channels::Channels;
use crate::hal::HeldCode as Out;
use stiffwall_proto::{DamperLaw, ExciteProfile, WallMode};

use super::fixture::{board, count, samples, wall};

/// The codes of `profile` alone: its generator run on its own, which is what the servo
/// output before the centring spring.
fn profile_codes(
    profile: ExciteProfile,
    ticks: u32,
    table: &[i16],
    rate_hz: u32,
) -> std::vec::Vec<i32> {
    let mut x = Excitation::new(profile, ticks);
    (0..ticks)
        .map(|_| {
            let c = x.next_code(table, rate_hz);
            x.advance();
            c
        })
        .collect()
}

/// The three profiles of these tests (a 100-tick run) and the table they use.
fn profiles() -> ([ExciteProfile; 3], [i16; 5]) {
    (
        [
            ExciteProfile::Steps {
                low: -300,
                high: 500,
                half_period_ticks: 7,
            },
            ExciteProfile::Chirp {
                amplitude: 1000,
                f0_hz: 2.0,
                f1_hz: 200.0,
            },
            ExciteProfile::Table {
                len: 5,
                hold_ticks: 3,
            },
        ],
        [1, -2, 300, -4000, 5],
    )
}

/// Raw counts of a device swinging ±40 counts around count `centre` (one per tick).
fn swing(centre: i32, ticks: u32) -> std::vec::Vec<i32> {
    (0..ticks)
        .map(|t| centre + (40.0 * libm::sin(f64::from(t) * 0.21)).round() as i32)
        .collect()
}

/// One excitation of `profile` on a fresh servo with `cfg`, first at rest at `counts[0]`
/// for 5 ticks (the wall), then over `counts`; returns the codes output and the samples of
/// the excitation.
fn excite(
    cfg: &ServoConfig,
    profile: ExciteProfile,
    table: &[i16],
    counts: &[i32],
) -> (std::vec::Vec<i32>, std::vec::Vec<Sample>) {
    let mut ch = Channels::new();
    let (sp, mut hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(board(), cfg, sp);
    let mut out = Out(0);
    for t in 0..5 {
        s.tick(t, &mut count(counts[0]), &mut out);
    }
    let values = heapless::Vec::from_slice(table).unwrap();
    s.command(5, ServoCmd::TableChunk { offset: 0, values });
    s.command(
        5,
        ServoCmd::Excite {
            profile,
            ticks: counts.len() as u32,
        },
    );
    let codes = counts
        .iter()
        .enumerate()
        .map(|(i, &c)| s.tick(5 + i as u32, &mut count(c), &mut out))
        .collect();
    assert_eq!(s.faults(), 0);
    assert!(!s.experiment_running());
    (codes, samples(&mut hp))
}

/// With K = 0 and B = 0 (the default) an excitation's codes are the profile's, bit for bit,
/// flagged `EXCITE | WALL_OFF`, wherever the device is, on either wall geometry.
#[test]
fn excitation_without_a_wall_outputs_the_profile_bit_for_bit() {
    let (profiles, table) = profiles();
    for one_sided in [false, true] {
        let cfg = ServoConfig {
            stiffness: 0.0,
            wall_position: 1000,
            wall: if one_sided {
                WallMode::OneSided
            } else {
                WallMode::Bidirectional
            },
            ..wall()
        };
        let counts = swing(1000, 100);
        for p in profiles {
            let want = profile_codes(p, 100, &table, 1024);
            let (codes, samples) = excite(&cfg, p, &table, &counts);
            assert_eq!(codes, want, "{p:?}");
            assert_eq!(samples.len(), 100);
            for (x, c) in samples.iter().zip(&codes) {
                assert_eq!(x.force_code, *c);
                assert_eq!(x.flags & !flags::CLAMPED, flags::EXCITE | flags::WALL_OFF);
            }
        }
    }
}

/// With K > 0 the code is the profile's plus the spring at that count (−n for K = 8), on
/// both sides of the wall position whatever the wall geometry; with B > 0 plus the damper on
/// the count difference (−2·dn for B = 1/64 with the plain difference), also with K = 0. The
/// samples carry `EXCITE` without `WALL_OFF`, and their force code is the code output.
#[test]
fn excitation_adds_the_centring_spring_and_damper() {
    let (profiles, table) = profiles();
    let centre = -70;
    let counts = swing(centre, 100);
    let n: std::vec::Vec<i32> = counts.iter().map(|c| c - centre).collect();
    let dn: std::vec::Vec<i32> = counts
        .iter()
        .scan(counts[0], |prev, &c| {
            let d = c - *prev;
            *prev = c;
            Some(d)
        })
        .collect();
    assert!(n.iter().any(|&x| x < -30) && n.iter().any(|&x| x > 30));
    for (k, b) in [(8.0, 0.0), (8.0, 1.0 / 64.0), (0.0, 1.0 / 64.0)] {
        for wall_mode in [WallMode::Bidirectional, WallMode::OneSided] {
            let cfg = ServoConfig {
                stiffness: k,
                damping: b,
                damper: DamperLaw::Difference,
                wall: wall_mode,
                wall_position: centre,
                ..wall()
            };
            for p in profiles {
                let exc = profile_codes(p, 100, &table, 1024);
                let want: std::vec::Vec<i32> = (0..100)
                    .map(|i| {
                        let spring = if k > 0.0 { -n[i] } else { 0 };
                        let damper = if b > 0.0 { -2 * dn[i] } else { 0 };
                        exc[i] + spring + damper
                    })
                    .collect();
                let (codes, samples) = excite(&cfg, p, &table, &counts);
                assert_eq!(codes, want, "K {k}, B {b}, {wall_mode:?}, {p:?}");
                for (x, c) in samples.iter().zip(&codes) {
                    assert_eq!(x.force_code, *c);
                    assert_eq!(x.flags & !flags::CLAMPED, flags::EXCITE);
                }
            }
        }
    }
}

/// The sum is clamped to the force limit like any code (flagged `CLAMPED`), and saturates
/// instead of wrapping however far the count is from the wall.
#[test]
fn excitation_with_a_centring_spring_is_clamped_and_never_wraps() {
    let cfg = ServoConfig {
        stiffness: 8.0,
        force_limit: 1.0, // 1024 codes
        encoder_jump_counts: 1 << 30,
        energy_monitor: false, // the wall ticks before, far inside the wall
        ..wall()
    };
    let steps = ExciteProfile::Steps {
        low: 30000,
        high: 30000,
        half_period_ticks: 1,
    };
    // Far below the wall (beyond the spring's count clamp: its code there, about +limit),
    // excitation +30000: clamped to +1024.
    let far = 1_000_000_000; // a jump under the 2^30 limit
    let (codes, samples) = excite(&cfg, steps, &[], &[-5000, -5000, -far, -far]);
    assert_eq!(codes, [1024; 4]);
    assert!(samples.iter().all(|x| x.flags & flags::CLAMPED != 0));
    // Far above it, the other way round.
    let low = ExciteProfile::Steps {
        low: -30000,
        high: -30000,
        half_period_ticks: 1,
    };
    let (codes, _) = excite(&cfg, low, &[], &[5000, far, far]);
    assert_eq!(codes, [-1024; 3]);
    // Within the clamp, the excitation's code plus the spring's saturated one (no wrap).
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let s: Servo<'_> = Servo::new(board(), &cfg, sp);
    let small = ExciteProfile::Steps {
        low: -500,
        high: -500,
        half_period_ticks: 1,
    };
    let (codes, _) = excite(&cfg, small, &[], &[-far, -far]);
    assert_eq!(codes, [s.spring_raw(-far) - 500; 2]);
    assert!(codes[0] > 0 && codes[0] < 1024, "{codes:?}");
}
