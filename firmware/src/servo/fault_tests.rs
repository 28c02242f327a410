//! Unit tests of the supervisor's faults: encoder jump, over-velocity and the energy
//! monitor's view of free motion, and what is not a motion (the first reading, a moved
//! wall). Units: raw counts per tick, output codes.

use super::*;
use crate::channels::Channels;
use crate::hal::{HeldCode as Out, SampledCount as Enc};
use stiffwall_proto::{DamperLaw, WallMode};

use super::fixture::board;

#[test]
fn encoder_jump_latches_and_zeroes_force_until_cleared() {
    let b = board();
    let cfg = ServoConfig {
        stiffness: 8.0,
        force_limit: 20.0 / 1024.0,
        encoder_jump_counts: 50,
        ..ServoConfig::default()
    };
    let mut ch = Channels::new();
    let (sp, hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    let mut out = Out(0);
    s.tick(0, &mut Enc(10), &mut out);
    assert_eq!(out.0, -10); // n=10: ⌊−21·0.5 + ½⌋ = −10
    s.tick(1, &mut Enc(100), &mut out);
    assert_eq!(s.faults(), fault::ENCODER_JUMP);
    assert_eq!(out.0, 0);
    assert_eq!(
        hp.shared.faults.load(Ordering::Relaxed),
        fault::ENCODER_JUMP
    );
    s.tick(2, &mut Enc(101), &mut out);
    assert_eq!((s.faults(), out.0), (fault::ENCODER_JUMP, 0), "latched");
    s.command(3, ServoCmd::ClearFaults);
    s.tick(3, &mut Enc(101), &mut out);
    assert_eq!(s.faults(), 0);
    assert_eq!(
        out.0, -20,
        "n=101 → −101.5 codes, clamped to the 20-code limit"
    );
}

/// The first reading is a position, not a motion: far from 0 it trips neither the jump
/// nor the velocity test and kicks no damper (the spring alone), and the next tick is an
/// ordinary one (a jump from there trips).
#[test]
fn the_first_reading_is_not_a_motion() {
    let cfg = ServoConfig {
        stiffness: 8.0,
        damping: 1.0 / 32.0,
        damper: DamperLaw::Difference,
        force_limit: 20.0,
        max_velocity: 625.0 / 1024.0,
        encoder_jump_counts: 50,
        heartbeat_timeout_ms: 0,
        ..ServoConfig::default()
    };
    let spring_only = ServoConfig {
        damping: 0.0,
        ..cfg
    };
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(board(), &cfg, sp);
    let mut ch2 = Channels::new();
    let (sp2, _hp2) = ch2.split();
    let mut s2: Servo<'_> = Servo::new(board(), &spring_only, sp2);
    let mut out = Out(0);
    // n = 1000: ⌊−2001·0.5 + ½⌋ = −1000.
    assert_eq!(s.tick(0, &mut Enc(1000), &mut out), -1000);
    assert_eq!(s2.tick(0, &mut Enc(1000), &mut out), -1000);
    assert_eq!(s.faults(), 0);
    // At rest after it: the spring alone, no fault from the velocity window.
    for t in 1..10 {
        assert_eq!(s.tick(t, &mut Enc(1000), &mut out), -1000);
    }
    assert_eq!(s.faults(), 0);
    // One count: the damper's −4.
    assert_eq!(s.tick(10, &mut Enc(1001), &mut out), -1001 - 4);
    s.tick(11, &mut Enc(1100), &mut out);
    assert_eq!(s.faults() & fault::ENCODER_JUMP, fault::ENCODER_JUMP);
}

#[test]
fn over_velocity_fault() {
    let b = board();
    // 8-tick window: 0.6103515625 m/s · 8 / (1000 Hz · 2^-13 m) = 40 counts.
    let cfg = ServoConfig {
        stiffness: 1.0,
        force_limit: 20.0,
        max_velocity: 625.0 / 1024.0,
        ..ServoConfig::default()
    };
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    let mut out = Out(0);
    for t in 0..40u32 {
        s.tick(t, &mut Enc(t * 5), &mut out); // 5 counts/tick = 40 per window: at the limit
    }
    assert_eq!(s.faults(), 0);
    for t in 40..60u32 {
        s.tick(t, &mut Enc(200 + (t - 40) * 6), &mut out);
    }
    assert_eq!(s.faults(), fault::OVER_VELOCITY);
}

#[test]
fn energy_monitor_ignores_free_motion_outside_a_one_sided_wall() {
    let b = board();
    let cfg = ServoConfig {
        stiffness: 8.0,
        wall: WallMode::OneSided,
        energy_limit: 1e-6, // e8 limit ≈ 8e-6/(8·2^-26) ≈ 67: |2n+1| ≤ 8
        energy_growth_cycles: 1,
        encoder_jump_counts: 1 << 20,
        ..ServoConfig::default()
    };
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    let mut out = Out(0);
    // Growing swings far outside the wall (negative counts): no fault.
    let mut t = 0;
    for a in 1..40 {
        for c in (-(a * 100)..=-10).rev().chain(-(a * 100 + 50)..-10) {
            s.tick(t, &mut Enc(c as u32), &mut out);
            t += 1;
        }
    }
    assert_eq!(s.faults(), 0);
    // Deep inside the wall the limit trips.
    for c in (0..50).step_by(5) {
        s.tick(t, &mut Enc(c), &mut out);
        t += 1;
    }
    assert_eq!(s.faults() & fault::ENERGY_LIMIT, fault::ENERGY_LIMIT);
}

/// Moving the wall is not a motion: at rest, the tick after a config with a new wall
/// position outputs the spring alone (no damper kick from a jump of the count).
#[test]
fn a_new_wall_position_does_not_kick_the_damper() {
    let b = board();
    let cfg = ServoConfig {
        stiffness: 8.0,
        damping: 0.05,
        force_limit: 20.0,
        heartbeat_timeout_ms: 0,
        ..ServoConfig::default()
    };
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    let mut out = Out(0);
    for t in 0..5 {
        s.tick(t, &mut Enc(7), &mut out);
    }
    s.apply_config(&ServoConfig {
        wall_position: 5,
        ..cfg
    });
    // The spring alone at count 2 from the new wall (the same config without the damper).
    let spring_at_2 = {
        s.apply_config(&ServoConfig {
            wall_position: 5,
            damping: 0.0,
            ..cfg
        });
        s.tick(5, &mut Enc(7), &mut out)
    };
    s.apply_config(&ServoConfig {
        wall_position: 0,
        ..cfg
    });
    s.tick(6, &mut Enc(7), &mut out);
    s.apply_config(&ServoConfig {
        wall_position: 5,
        ..cfg
    });
    assert_eq!(s.tick(7, &mut Enc(7), &mut out), spring_at_2);
}
