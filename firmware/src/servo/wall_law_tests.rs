//! Unit tests of the wall law: the damper (its laws, its dead band, one-sided contact, the
//! hold and released phases), the delay line, the one-sided wall and coarsening. Units:
//! output codes, effective counts per tick, servo ticks.

use super::*;
use crate::channels::Channels;
use crate::config::DAMPER_V_MAX;
use crate::hal::{HeldCode as Out, SampledCount as Enc};
use proptest::prelude::*;
use stiffwall_proto::{DamperLaw, WallMode, MAX_DEADBAND_COUNTS};

use super::fixture::board;

/// Δ = 2^-13 m, 2^-10 N per code at 1024 Hz: g_B = B·Δ·rate/fs = 128·B codes per count
/// per tick, k_half = K/16.
fn damper_cfg(k: f32, b: f32, one_sided: bool) -> ServoConfig {
    ServoConfig {
        stiffness: k,
        damping: b,
        servo_rate_hz: 1024,
        force_limit: 100.0 / 1024.0,
        wall: if one_sided {
            WallMode::OneSided
        } else {
            WallMode::Bidirectional
        },
        energy_monitor: false,
        encoder_jump_counts: 1 << 20,
        heartbeat_timeout_ms: 0,
        ..ServoConfig::default()
    }
}

#[test]
fn one_sided_damper_acts_only_in_contact() {
    // K = 8 N/m: k_half = 0.5 code; B = 1/32 N·s/m: g_B = 4 codes per count per tick.
    let cfg = damper_cfg(8.0, 1.0 / 32.0, true);
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(board(), &cfg, sp);
    let mut out = Out(0);
    let mut t = 0;
    let mut run = |s: &mut Servo<'_>, c: i32| {
        t += 1;
        s.tick_supervised(t, &mut Enc(c as u32), &mut out)
    };
    // Free space, moving toward the wall at 5 counts per tick: no drag (was −4·5 = −20).
    for c in (-100..0).step_by(5) {
        assert_eq!(run(&mut s, c), 0, "free space at count {c}");
    }
    // Contact: spring ⌊−(2n+1)·0.5 + ½⌋ plus the damper −4·dn.
    assert_eq!(run(&mut s, 0), -20); // n = 0: 0 − 20
    assert_eq!(run(&mut s, 5), -25); // n = 5: −5 − 20
    assert_eq!(run(&mut s, 5), -5); // at rest: the spring alone
    assert_eq!(run(&mut s, 0), 20); // leaving at 5 counts per tick: 0 + 20
                                    // Out of contact again: nothing, whatever the velocity.
    assert_eq!(run(&mut s, -5), 0);
    assert_eq!(run(&mut s, -40), 0);
    // A two-sided wall with the same gains damps everywhere.
    let cfg = damper_cfg(8.0, 1.0 / 32.0, false);
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(board(), &cfg, sp);
    let mut out = Out(0);
    s.tick_supervised(0, &mut Enc((-100i32) as u32), &mut out);
    // n = −95: spring ⌊189·0.5 + ½⌋ = 95, damper −20 → 75.
    assert_eq!(
        s.tick_supervised(1, &mut Enc((-95i32) as u32), &mut out),
        75
    );
}

/// The wall law in f64 from the SI config: −K·Δ(n+½)/fs − B·Δ·v·rate/fs codes, clamped,
/// with v = dn, or 0 when |dn| is within the config's dead band.
fn wall_exact(cfg: &ServoConfig, n: i32, dn: i32, lim: f64) -> f64 {
    let b = board();
    let d = f64::from(b.resolution);
    let fs = f64::from(b.force_per_code);
    if cfg.wall == WallMode::OneSided && n < 0 {
        return 0.0;
    }
    let v = match cfg.damper {
        DamperLaw::DeadBand { counts } if dn.unsigned_abs() <= u32::from(counts) => 0,
        _ => dn,
    };
    let f = -f64::from(cfg.stiffness) * d * (f64::from(n) + 0.5) / fs
        - f64::from(cfg.damping) * d * f64::from(v) * f64::from(cfg.servo_rate_hz) / fs;
    f.clamp(-lim, lim)
}

/// The damper law of `band` (0: the plain difference).
fn law(band: u8) -> DamperLaw {
    if band == 0 {
        DamperLaw::Difference
    } else {
        DamperLaw::DeadBand { counts: band }
    }
}

proptest! {
    /// Spring + damper, both before the clamp, against the SI law at every count (the
    /// spring's saturation bound leaves room for the damper, so a deep count with a
    /// damper pulling back is still clamped exactly): within one code (two roundings) plus
    /// the gains' quantization, and exactly 0 outside a one-sided wall. Counts within
    /// ±2^24 (8 m at 0.5 µm per count; the encoder jump limit stops a device long before):
    /// beyond the spring's count clamp (±2^29) a damper larger than the clamped spring
    /// sets the sign, a known limit of the saturation bound (firmware model notes). Every
    /// damper law: the plain difference and each dead band (v = 0 for |dn| ≤ c).
    #[test]
    fn wall_law_is_spring_plus_backward_difference_damper(
        k in 0.0f32..300.0, b in 0.0f32..128.0, limit in 1.0f32..29.0,
        one_sided in any::<bool>(), n in -(1i32 << 24)..(1 << 24), near in -3000i32..3000,
        dn in -(DAMPER_V_MAX)..=DAMPER_V_MAX, small_dn in -20i32..20,
        band in 0u8..=MAX_DEADBAND_COUNTS,
    ) {
        let cfg = ServoConfig {
            force_limit: limit,
            damper: law(band),
            ..damper_cfg(k, b, one_sided)
        };
        prop_assert!(crate::config::validate(&cfg, &board()).is_ok());
        let mut ch = Channels::new();
        let (sp, _hp) = ch.split();
        let s: Servo<'_> = Servo::new(board(), &cfg, sp);
        let lim = f64::from(s.gains().limit);
        for (n, dn) in [(n, dn), (near, small_dn), (near, dn), (n, small_dn)] {
            let (code, _) = s.clamp(s.wall_code(n, dn));
            let want = wall_exact(&cfg, n, dn, lim);
            if one_sided && n < 0 {
                prop_assert_eq!(code, 0);
            }
            // Gain quantization: 2^-33 code per count on each gain.
            let q = (2.0 * f64::from(n).abs() + 1.0 + f64::from(dn).abs()) * 2f64.powi(-32);
            prop_assert!((f64::from(code) - want).abs() <= 1.0 + q,
                "n={} dn={} code={} want={}", n, dn, code, want);
        }
    }
}

/// A damped wall at rest toggling between two neighbouring counts: with the dead band of
/// one count (the default law) each tick outputs the spring alone; with the plain
/// difference every toggle adds a damper pulse g_B = 4 codes (B·Δ/T).
#[test]
fn a_toggle_between_two_counts_outputs_the_spring_alone_in_the_dead_band() {
    // K = 8 N/m: k_half = 0.5 code; B = 1/32 N·s/m: g_B = 4 codes per count per tick.
    // Spring ⌊−(2n+1)·0.5 + ½⌋: n = 3 → −3, n = 4 → −4.
    let run = |damper: DamperLaw| {
        let cfg = ServoConfig {
            damper,
            ..damper_cfg(8.0, 1.0 / 32.0, false)
        };
        let mut ch = Channels::new();
        let (sp, _hp) = ch.split();
        let mut s: Servo<'_> = Servo::new(board(), &cfg, sp);
        let mut out = Out(0);
        (0..8u32)
            .map(|t| s.tick_supervised(t, &mut Enc(3 + (t & 1)), &mut out))
            .collect::<std::vec::Vec<_>>()
    };
    assert_eq!(DamperLaw::default(), DamperLaw::DeadBand { counts: 1 });
    assert_eq!(run(DamperLaw::default()), [-3, -4, -3, -4, -3, -4, -3, -4]);
    // The plain difference (the law before protocol 2): −4 − 4·1 and −3 + 4.
    assert_eq!(run(DamperLaw::Difference), [-3, -8, 1, -8, 1, -8, 1, -8]);
}

/// Beyond the dead band the damper's pulse is the full g_B·dn (not g_B·(|dn| − c)).
#[test]
fn a_step_beyond_the_dead_band_gets_the_full_damper_pulse() {
    let steps = |damper: DamperLaw| {
        let cfg = ServoConfig {
            damper,
            ..damper_cfg(8.0, 1.0 / 32.0, false)
        };
        let mut ch = Channels::new();
        let (sp, _hp) = ch.split();
        let mut s: Servo<'_> = Servo::new(board(), &cfg, sp);
        let mut out = Out(0);
        [3i32, 5, 3, 6, 3]
            .iter()
            .zip(0..)
            .map(|(&c, t)| s.tick_supervised(t, &mut Enc(c as u32), &mut out))
            .collect::<std::vec::Vec<_>>()
    };
    // Spring at 3, 5, 6: −3, −5, −6; the damper −4·dn: dn = +2, −2, +3, −3.
    assert_eq!(
        steps(DamperLaw::DeadBand { counts: 1 }),
        [-3, -5 - 8, -3 + 8, -6 - 12, -3 + 12]
    );
    assert_eq!(
        steps(DamperLaw::DeadBand { counts: 2 }),
        [-3, -5, -3, -6 - 12, -3 + 12]
    );
    assert_eq!(
        steps(DamperLaw::DeadBand { counts: 3 }),
        [-3, -5, -3, -6, -3]
    );
    assert_eq!(
        steps(DamperLaw::Difference),
        steps(DamperLaw::DeadBand { counts: 1 })
    );
}

/// The released phase of a release or impact test is the wall (its damper law too); the
/// hold that precedes it keeps the plain difference (its damping acts on a one-count move).
#[test]
fn released_phase_uses_the_law_and_the_hold_damps_every_count() {
    let cfg = ServoConfig {
        damper: DamperLaw::DeadBand { counts: 1 },
        ..damper_cfg(8.0, 1.0 / 32.0, false)
    };
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(board(), &cfg, sp);
    s.set_exp(Experiment::Released {
        remaining: 10,
        kind: ExperimentKind::Release,
    });
    assert_eq!(s.force(4, 1), (-4, flags::RELEASED));
    assert_eq!(s.force(4, 2), (-4 - 8, flags::RELEASED));
    s.set_exp(Experiment::Hold(crate::experiment::Hold::new(4, 10)));
    let (code, fl) = s.force(4, 1);
    assert_eq!(fl, flags::HOLD);
    // At its target the hold's spring is ⌊−0.5 + ½⌋ = 0: the code is its damper alone.
    assert_eq!(code, s.damper(s.gains().hold_damp, 1));
    assert!(code < 0, "{code}");
}

#[test]
fn delay_line_delays_by_exact_ticks() {
    let b = board();
    let cfg = ServoConfig {
        stiffness: 8.0,
        force_limit: 20.0,
        extra_delay_ticks: 3,
        ..ServoConfig::default()
    };
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    let mut out = Out(0);
    let mut got = std::vec::Vec::new();
    for i in 0..8u32 {
        got.push(s.tick_spring_delay(&mut Enc(i * 10), &mut out));
    }
    // code(n) = ⌊−(2n+1)·0.5 + ½⌋: n = 0, 10, 20 ... → 0, −10, −20 ... (ties toward +∞)
    assert_eq!(got, [0, 0, 0, 0, -10, -20, -30, -40]);
}

#[test]
fn one_sided_wall_and_coarsening() {
    let b = board();
    let cfg = ServoConfig {
        stiffness: 8.0,
        force_limit: 20.0,
        wall: WallMode::OneSided,
        wall_position: 100,
        coarsen_shift: 2,
        ..ServoConfig::default()
    };
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
    let mut out = Out(0);
    // k_half = K·4Δ/(2·fs) = 8/4 = 2 codes per effective tick.
    assert_eq!(s.tick_spring(&mut Enc(99), &mut out), 0);
    assert_eq!(s.tick_spring(&mut Enc(100), &mut out), -2);
    assert_eq!(s.tick_spring(&mut Enc(103), &mut out), -2);
    assert_eq!(s.tick_spring(&mut Enc(104), &mut out), -6);
}
