//! Unit tests of the travel window: the supervisor's `TRAVEL` fault on the raw count.

use super::*;
use crate::channels::Channels;
use crate::hal::HeldCode as Out;
use stiffwall_proto::{ExciteProfile, SafeMode};

use super::fixture::{board, count, samples, wall};

/// Inside the window (its ends included) the servo is bit for bit the servo without one;
/// the tick the raw count leaves it latches `TRAVEL`, publishes it with its tick and outputs
/// the safe mode's code (here the safe damper on the raw count delta); it stays latched back
/// inside until cleared, and re-latches at once when cleared outside.
#[test]
fn leaving_the_travel_window_trips_the_supervisor_into_safe_mode() {
    let b = board();
    let cfg = ServoConfig {
        travel_min: Some(-10),
        travel_max: Some(10),
        safe_mode: SafeMode::Damping,
        safe_damping: 1.0 / 64.0, // 2 codes per raw count per tick
        ..wall()
    };
    let plain = ServoConfig {
        travel_min: None,
        travel_max: None,
        ..cfg
    };
    let mut ch = Channels::new();
    let (sp, mut hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    let mut ch2 = Channels::new();
    let (sp2, _hp2) = ch2.split();
    let mut s2: Servo<'_> = Servo::new(b, &plain, sp2);
    s.command(0, ServoCmd::Stream { decimation: 1 });
    let mut out = Out(0);
    let inside = [0, 3, 7, 10, 10, 4, -2, -9, -10, -10, -6, 0, 9];
    for (t, &c) in inside.iter().enumerate() {
        let t = t as u32;
        assert_eq!(
            s.tick(t, &mut count(c), &mut out),
            s2.tick(t, &mut count(c), &mut out),
            "count {c}"
        );
    }
    assert_eq!(s.faults(), 0);
    // 9 → 11: outside by one count. Safe damping on the raw delta 2: −2·2 = −4.
    assert_eq!(s.tick(13, &mut count(11), &mut out), -4);
    assert_eq!(s.faults(), fault::TRAVEL);
    assert_eq!(hp.shared.faults.load(Ordering::Relaxed), fault::TRAVEL);
    assert_eq!(hp.shared.first_fault_tick.load(Ordering::Relaxed), 13);
    let last = *samples(&mut hp).last().unwrap();
    assert_eq!((last.tick, last.count, last.force_code), (13, 11, -4));
    assert_eq!(last.flags & flags::SAFE_MODE, flags::SAFE_MODE);
    // Back inside: still latched, still the safe mode (at rest: no force).
    assert_eq!(s.tick(14, &mut count(5), &mut out), 12);
    assert_eq!(s.tick(15, &mut count(5), &mut out), 0);
    assert_eq!(s.faults(), fault::TRAVEL);
    // Cleared inside: the wall again (−5 at count 5).
    s.command(16, ServoCmd::ClearFaults);
    assert_eq!(s.tick(16, &mut count(5), &mut out), -5);
    assert_eq!(s.faults(), 0);
    // Below the window: the same fault. Cleared outside: latched again on the next tick.
    s.tick(17, &mut count(-11), &mut out);
    assert_eq!(s.faults(), fault::TRAVEL);
    assert_eq!(hp.shared.first_fault_tick.load(Ordering::Relaxed), 17);
    s.command(18, ServoCmd::ClearFaults);
    s.tick(18, &mut count(-11), &mut out);
    assert_eq!(s.faults(), fault::TRAVEL);
}

/// One end alone bounds one side; a device that boots outside its window trips on its first
/// reading (a position, but outside); a window that is off never trips, not even at the ends
/// of the `i32` range, where the unwrapped count saturates.
#[test]
fn travel_window_ends_alone_first_reading_and_off() {
    let b = board();
    let run = |cfg: &ServoConfig, counts: &[i32]| {
        let mut ch = Channels::new();
        let (sp, _hp) = ch.split();
        let mut s: Servo<'_> = Servo::new(b, cfg, sp);
        let mut out = Out(0);
        let mut first = None;
        for (t, &c) in counts.iter().enumerate() {
            s.tick(t as u32, &mut count(c), &mut out);
            if s.faults() != 0 && first.is_none() {
                first = Some((t, s.faults()));
            }
        }
        first
    };
    let upper = ServoConfig {
        travel_max: Some(100),
        ..wall()
    };
    let lower = ServoConfig {
        travel_min: Some(-100),
        ..wall()
    };
    let far_below = [0, -50, -100, -150, -200];
    let far_above = [0, 50, 100, 150, 200];
    assert_eq!(run(&upper, &far_below), None);
    assert_eq!(run(&upper, &far_above), Some((3, fault::TRAVEL)));
    assert_eq!(run(&lower, &far_above), None);
    assert_eq!(run(&lower, &far_below), Some((3, fault::TRAVEL)));
    // The first reading: outside is outside.
    assert_eq!(run(&upper, &[500, 500]), Some((0, fault::TRAVEL)));
    assert_eq!(run(&upper, &[100, 100]), None);
    // Off (the default): the count driven to both ends of the i32 range, where it saturates
    // (an encoder-jump limit the strides stay under). With an end at i32::MAX the saturated
    // count is still inside.
    let wide = ServoConfig {
        encoder_jump_counts: 1 << 30,
        energy_monitor: false,
        ..wall()
    };
    let mut up = std::vec::Vec::new();
    let mut raw = 0u32;
    for _ in 0..40 {
        raw = raw.wrapping_add(1 << 29);
        up.push(raw as i32);
    }
    let down: std::vec::Vec<i32> = up.iter().map(|c| c.wrapping_neg()).collect();
    assert_eq!(run(&wide, &up), None);
    assert_eq!(run(&wide, &down), None);
    let at_max = ServoConfig {
        travel_max: Some(i32::MAX),
        travel_min: Some(i32::MIN),
        ..wide
    };
    assert_eq!(run(&at_max, &up), None);
    assert_eq!(run(&at_max, &down), None);
    let short_of_max = ServoConfig {
        travel_max: Some(i32::MAX - 1),
        ..wide
    };
    assert!(run(&short_of_max, &up).is_some());
}

/// A running experiment that leaves the window ends at once, not completed, with the fault.
#[test]
fn leaving_the_travel_window_ends_an_experiment() {
    let b = board();
    let cfg = ServoConfig {
        travel_min: Some(-20),
        travel_max: Some(20),
        ..wall()
    };
    let mut ch = Channels::new();
    let (sp, mut hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    let mut out = Out(0);
    s.command(
        0,
        ServoCmd::Excite {
            profile: ExciteProfile::Steps {
                low: 100,
                high: 100,
                half_period_ticks: 1,
            },
            ticks: 1000,
        },
    );
    for t in 0..30u32 {
        s.tick(t, &mut count(t as i32), &mut out);
    }
    assert!(!s.experiment_running());
    assert!(matches!(
        hp.events.dequeue(),
        Some(ServoEvent::ExperimentDone {
            kind: ExperimentKind::Excite,
            completed: false,
            faults: fault::TRAVEL,
            ..
        })
    ));
    assert_eq!(hp.shared.first_fault_tick.load(Ordering::Relaxed), 21);
}
