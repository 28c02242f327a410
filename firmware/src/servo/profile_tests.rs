//! Unit tests of profile mode: the profile renders in place of the config's wall, is no
//! experiment, gives way to an experiment (which runs on the config's wall) and comes back when
//! it ends; the energy monitor does not watch it; the profile arrives whole through the
//! channels. Units: servo ticks, output codes, raw counts.

use super::fixture::{board, count, wall};
use super::*;
use crate::channels::Channels;
use crate::hal::HeldCode as Out;
use crate::profile::compile;
use stiffwall_proto::profile::{Profile, ProfileElement};
use stiffwall_proto::DamperLaw;

/// A K = 8 centring spring at count 1000 (k_half = ½: code −(n − 1000) − ½ rounded).
fn spring_at_1000() -> Profile {
    let mut p = Profile::default();
    p.elements
        .push(ProfileElement::Spring {
            center: 1000,
            stiffness: 8.0,
            damping: 0.0,
            damper: DamperLaw::Difference,
        })
        .unwrap();
    p
}

#[test]
fn a_profile_renders_instead_of_the_wall_and_returns_after_an_experiment() {
    let b = board();
    let cfg = wall();
    let mut ch = Channels::new();
    let (sp, mut hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    let mut out = Out(0);
    s.tick(0, &mut count(990), &mut out);
    // Through the channels, as the device sends it: the table, then its command.
    assert!(hp
        .profiles
        .enqueue(compile(&spring_at_1000(), &cfg, &b))
        .is_ok());
    assert!(hp.commands.enqueue(ServoCmd::Profile).is_ok());
    // The wall at count 990 pushes down (−990); the profile's spring pushes up (+10).
    let c = s.tick(1, &mut count(990), &mut out);
    assert_eq!(c, 10);
    assert_eq!(s.mode, Mode::Profile);
    assert!(!s.experiment_running());
    // An experiment runs on the config's wall, then the profile is back.
    s.command(
        2,
        ServoCmd::Release {
            deflection: 3,
            ticks: 5,
            end: None,
        },
    );
    assert!(s.experiment_running());
    s.tick(3, &mut count(990), &mut out);
    s.command(4, ServoCmd::Stop);
    assert!(!s.experiment_running());
    assert_eq!(s.mode, Mode::Profile);
    assert_eq!(s.tick(5, &mut count(1003), &mut out), -3);
    // An empty profile: the wall again.
    s.set_profile(crate::profile::ProfileTable::empty());
    assert_eq!(s.mode, Mode::Wall);
    assert_eq!(s.tick(6, &mut count(3), &mut out), -3);
}

#[test]
fn the_energy_monitor_does_not_watch_a_profile() {
    let b = board();
    let cfg = ServoConfig {
        energy_monitor: true,
        energy_limit: 1e-9,
        ..wall()
    };
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    s.set_profile(compile(&spring_at_1000(), &cfg, &b));
    let mut out = Out(0);
    for t in 0..50u32 {
        // Deep in the config's wall, far from the profile's spring centre.
        s.tick(t, &mut count(40 + (t % 3) as i32), &mut out);
    }
    assert_eq!(s.faults(), 0);
    // The same on the wall trips it.
    s.set_profile(crate::profile::ProfileTable::empty());
    for t in 50..100u32 {
        s.tick(t, &mut count(40 + (t % 3) as i32), &mut out);
    }
    assert_ne!(s.faults() & fault::ENERGY_LIMIT, 0);
}
