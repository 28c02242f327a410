//! Unit tests of experiments and telemetry: prepared tests (their config, end rule and
//! restore), the buzz detector during them, excitation profiles, refusal while faulted, and
//! exact counts of dropped telemetry. Units: servo ticks, output codes, raw counts.

use super::*;
use crate::channels::{Channels, TELEMETRY_QUEUE};
use crate::hal::{HeldCode as Out, SampledCount as Enc};
use stiffwall_proto::ExciteProfile;

use super::fixture::board;

/// The K = 8 wall of the prepared-test tests (20 N limit, no host heartbeat).
fn wall_k8() -> ServoConfig {
    ServoConfig {
        stiffness: 8.0,
        force_limit: 20.0,
        heartbeat_timeout_ms: 0,
        ..ServoConfig::default()
    }
}

/// `HostMsg::PrepareTest`: a release runs with the prepared config from its first tick,
/// ends on the tick its released counts settle (a toggle counts only within one count),
/// and the active config is back on that tick however it ends.
#[test]
fn a_prepared_test_runs_its_config_ends_when_settled_and_restores_the_active_one() {
    let b = board();
    let wall = wall_k8();
    let off = ServoConfig {
        stiffness: 0.0,
        ..wall
    };
    // With `active` configured: ticks from the release to the end (None: still running
    // after 2000 ticks), completed, the first hold tick's code at count 0 (target 3),
    // and the wall's code at count 7 after the end.
    let run = |active: &ServoConfig, end: Option<DecidedEnd>, ticks: u32| {
        let mut ch = Channels::new();
        let (sp, mut hp) = ch.split();
        let mut s: Servo<'_> = Servo::new(b, active, sp);
        let mut out = Out(0);
        s.command(
            0,
            ServoCmd::Release {
                deflection: 3,
                ticks,
                end,
            },
        );
        let first_hold = s.tick(1, &mut Enc(0), &mut out);
        let mut released = None;
        for t in 2..2000u32 {
            // At the target while held, then toggling between counts 0 and 1.
            let c = if released.is_some() { t & 1 } else { 3 };
            s.tick(t, &mut Enc(c), &mut out);
            if released.is_none() && s.mode == Mode::Released {
                released = Some(t + 1); // the first released tick is the next
            }
            if let Some(ServoEvent::ExperimentDone { completed, .. }) = hp.events.dequeue() {
                let wall_at_7 = s.tick(t + 1, &mut Enc(7), &mut out);
                let len = t - released.unwrap() + 1;
                return (Some(len), completed, first_hold, wall_at_7);
            }
        }
        (None, false, first_hold, 0)
    };
    let prepared = |one_count| DecidedEnd {
        min_run: 30,
        one_count,
        decay_base: 0,
        run: wall,
        park: off,
    };
    // The hold spring at count 0 toward target 3 with K = 8: ⌊15·(3 − 0 − ½)…⌋ > 0.
    let (_, _, hold_code, _) = run(&wall, None, 200);
    assert!(hold_code > 0, "{hold_code}");
    // Settled at L = 30: the last max(30, ⌈30/3⌉) counts lie within one count; the
    // active wall (K = 0) is back: no force at count 7.
    assert_eq!(
        run(&off, Some(prepared(true)), 1000),
        (Some(30), true, hold_code, 0)
    );
    // A toggle is not "equal counts": it runs its length, and the active config is back.
    assert_eq!(
        run(&off, Some(prepared(false)), 200),
        (Some(200), true, hold_code, 0)
    );
    // Not prepared: the active config throughout (⌊−15·0.5 + ½⌋ = −7 at count 7).
    assert_eq!(run(&wall, None, 200), (Some(200), true, hold_code, -7));
    assert_eq!(
        run(&off, None, 200).2,
        0,
        "the hold of a K = 0 wall pushes nothing"
    );
}

/// The buzz detector does not end a prepared test (the host judges its counts, as the
/// stability criterion does); an unprepared release still trips on the same buzz (the
/// wall path calls the detector whatever the test).
#[test]
fn a_prepared_test_is_not_ended_by_the_buzz_detector() {
    let b = board();
    let wall = wall_k8();
    let prepared = DecidedEnd {
        min_run: 30,
        one_count: false,
        decay_base: 0,
        run: wall,
        park: wall,
    };
    // Held at 3, then a persistent ±3-count buzz at 250 Hz: latched faults after 1000
    // released ticks.
    let run = |end: Option<DecidedEnd>| {
        let mut ch = Channels::new();
        let (sp, _hp) = ch.split();
        let mut s: Servo<'_> = Servo::new(b, &wall, sp);
        let mut out = Out(0);
        s.command(
            0,
            ServoCmd::Release {
                deflection: 3,
                ticks: 5000,
                end,
            },
        );
        // Counts from 1000: the first reading is the origin (the wall at 0).
        s.tick(1, &mut Enc(1000), &mut out);
        let mut released = 0u32;
        for t in 2..3000u32 {
            let c = if released > 0 {
                [1003, 1000, 997, 1000][(released % 4) as usize]
            } else {
                1003
            };
            s.tick(t, &mut Enc(c), &mut out);
            if s.mode == Mode::Released || released > 0 {
                released += 1;
            }
            if released > 1000 {
                break;
            }
        }
        (released, s.faults())
    };
    assert_eq!(run(Some(prepared)), (1001, 0));
    let (released, faults) = run(None);
    assert!(released > 0);
    assert_eq!(faults & fault::BUZZ, fault::BUZZ, "{faults:#x}");
}

/// The profiles on a K = 8 wall at count 7, whose centring spring adds −7 to every code
/// (`travel_excite_tests` has the profile alone at K = 0 and the sum at other counts).
#[test]
fn excitation_profiles() {
    let b = board();
    let cfg = ServoConfig {
        stiffness: 8.0,
        force_limit: 20.0,
        heartbeat_timeout_ms: 0, // no host here
        ..ServoConfig::default()
    };
    let mut ch = Channels::new();
    let (sp, mut hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    let mut out = Out(0);
    let run = |s: &mut Servo<'_>, out: &mut Out, n: u32| -> std::vec::Vec<i32> {
        (0..n).map(|t| s.tick(t, &mut Enc(7), out)).collect()
    };
    s.command(
        0,
        ServoCmd::Excite {
            profile: ExciteProfile::Steps {
                low: -3,
                high: 5,
                half_period_ticks: 2,
            },
            ticks: 6,
        },
    );
    assert_eq!(
        run(&mut s, &mut out, 6),
        [5 - 7, 5 - 7, -3 - 7, -3 - 7, 5 - 7, 5 - 7]
    );
    assert!(matches!(
        hp.events.dequeue(),
        Some(ServoEvent::ExperimentDone {
            completed: true,
            ..
        })
    ));
    assert!(!s.experiment_running());
    // Back to the wall at count 7: ⌊−15·0.5 + ½⌋ = −7.
    assert_eq!(run(&mut s, &mut out, 1), [-7]);
    // Chirp 1 → 100 Hz at 1 kHz: bounded by the amplitude, sign changes speed up.
    s.command(
        0,
        ServoCmd::Excite {
            profile: ExciteProfile::Chirp {
                amplitude: 1000,
                f0_hz: 1.0,
                f1_hz: 100.0,
            },
            ticks: 2000,
        },
    );
    let c: std::vec::Vec<i32> = run(&mut s, &mut out, 2000).iter().map(|v| v + 7).collect();
    assert!(c.iter().all(|v| v.abs() <= 1000));
    let flips = |w: &[i32]| w.windows(2).filter(|p| (p[0] >= 0) != (p[1] >= 0)).count();
    assert!(flips(&c[..500]) < flips(&c[1500..]));
    // Table: uploaded values, each held twice.
    let values = heapless::Vec::from_slice(&[1, 2, 3]).unwrap();
    s.command(0, ServoCmd::TableChunk { offset: 0, values });
    s.command(
        0,
        ServoCmd::Excite {
            profile: ExciteProfile::Table {
                len: 3,
                hold_ticks: 2,
            },
            ticks: 8,
        },
    );
    assert_eq!(
        run(&mut s, &mut out, 8),
        [1, 1, 2, 2, 3, 3, 1, 1].map(|v| v - 7)
    );
}

#[test]
fn experiment_refused_while_faulted_is_reported_ended() {
    let b = board();
    let cfg = ServoConfig {
        stiffness: 8.0,
        encoder_jump_counts: 5,
        ..ServoConfig::default()
    };
    let mut ch = Channels::new();
    let (sp, mut hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    let mut out = Out(0);
    s.tick(0, &mut Enc(0), &mut out);
    s.tick(1, &mut Enc(100), &mut out);
    assert_eq!(s.faults(), fault::ENCODER_JUMP);
    // The main loop had already set the flag when it accepted the request.
    hp.shared.experiment.store(true, Ordering::Relaxed);
    s.command(
        2,
        ServoCmd::Release {
            deflection: 3,
            ticks: 10,
            end: None,
        },
    );
    assert!(!s.experiment_running());
    assert!(!hp.shared.experiment.load(Ordering::Relaxed));
    assert!(matches!(
        hp.events.dequeue(),
        Some(ServoEvent::ExperimentDone {
            completed: false,
            faults: fault::ENCODER_JUMP,
            ..
        })
    ));
}

#[test]
fn telemetry_counts_drops_exactly() {
    let b = board();
    let cfg = ServoConfig {
        stiffness: 1.0,
        ..ServoConfig::default()
    };
    let mut ch = Channels::new();
    let (sp, mut hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    s.command(0, ServoCmd::Stream { decimation: 1 });
    let mut out = Out(0);
    for t in 0..1000u32 {
        s.tick(t, &mut Enc(0), &mut out);
    }
    let cap = (TELEMETRY_QUEUE - 1) as u32;
    assert_eq!(hp.shared.dropped.load(Ordering::Relaxed), 1000 - cap);
    let mut seqs = std::vec::Vec::new();
    while let Some(i) = hp.telemetry.dequeue() {
        seqs.push(i.seq);
    }
    assert_eq!(seqs, (0..cap).collect::<std::vec::Vec<_>>());
}
