//! Unit tests of the tick: the spring against an exact reference on every backend, the
//! damper laws, the delay line, the supervisor's faults, experiments and telemetry.

use super::*;
use crate::channels::{Channels, TELEMETRY_QUEUE};
use crate::config::DAMPER_V_MAX;
use crate::hal::{HeldCode as Out, SampledCount as Enc};
use crate::numeric::{Fx32, F32};
use proptest::prelude::*;
use stiffwall_proto::{DamperLaw, ExciteProfile, WallMode, MAX_DEADBAND_COUNTS};

use super::fixture::board;

/// Exact force in codes for count n, from the SI config (f64).
fn exact(cfg: &ServoConfig, b: &BoardInfo, n: i32) -> f64 {
    let de = f64::from(b.resolution) * f64::from(1u32 << cfg.coarsen_shift);
    -f64::from(cfg.stiffness) * de * (n as f64 + 0.5) / f64::from(b.force_per_code)
}

fn check_backend<Nm: Numeric>(
    k: f32,
    shift: u8,
    n: i32,
    tol_extra: f64,
    range: f64,
) -> Result<(), TestCaseError> {
    let b = board();
    let cfg = ServoConfig {
        stiffness: k,
        coarsen_shift: shift,
        force_limit: 30.0,
        ..ServoConfig::default()
    };
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let s: Servo<'_, Nm> = Servo::new(b, &cfg, sp);
    let code = s.spring_code(n);
    let lim = f64::from(s.gains().limit);
    let want = exact(&cfg, &b, n);
    let clamped = i64::from(code).clamp(-(lim as i64), lim as i64) as f64;
    let want_c = want.clamp(-lim, lim);
    prop_assert!(
        (clamped - want_c).abs() <= 1.0 + tol_extra,
        "n={n} code={code} want={want}"
    );
    // Exactly the documented integer formula on the gain's bits, then the clamp.
    let g = Nm::to_f64(s.gains().k_half);
    let formula = -(2.0 * n as f64 + 1.0) * g;
    if formula.abs() < range - 1.0 && formula.abs() < lim {
        // f32 products round to 24 bits: allow 2^-22 relative for that back-end.
        let rel = if Nm::NAME == "f32" { 2.4e-7 } else { 1e-9 };
        prop_assert!((f64::from(code) - formula).abs() <= 0.5 + rel * formula.abs());
    } else {
        // Saturated: the clamped output is the limit with the sign of the formula.
        prop_assert_eq!(clamped, lim * formula.signum());
    }
    Ok(())
}

/// The spring code as computed before the precomputed bounds: clamp n to
/// [−n_sat−1, n_sat], then `mul_bounded(k_half, −(2n+1))`; 0 for n < 0 one-sided.
fn spring_reference<Nm: Numeric>(g: &Gains<Nm>, n: i32) -> i32 {
    if g.one_sided && n < 0 {
        return 0;
    }
    let n = n.max(-g.n_sat - 1).min(g.n_sat);
    Nm::mul_bounded(g.k_half, -(2 * n + 1))
}

fn check_same_as_reference<Nm: Numeric>(
    k: f32,
    limit: f32,
    one_sided: bool,
    n: i32,
) -> Result<(), TestCaseError> {
    let cfg = ServoConfig {
        stiffness: k,
        force_limit: limit,
        wall: if one_sided {
            WallMode::OneSided
        } else {
            WallMode::Bidirectional
        },
        ..ServoConfig::default()
    };
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let s: Servo<'_, Nm> = Servo::new(board(), &cfg, sp);
    let g = s.gains();
    prop_assert_eq!(s.spring_code(n), spring_reference(g, n), "n={}", n);
    let two = Gains {
        one_sided: false,
        ..*g
    };
    prop_assert_eq!(s.spring_raw(n), spring_reference(&two, n), "raw n={}", n);
    Ok(())
}

proptest! {
    // K·Δ_eff/2 from 1e-4 to ~15 codes; counts over the whole i32 range and beyond.
    #[test]
    fn spring_code_same_as_clamp_then_multiply(k in 0.0f32..600.0, limit in 0.0f32..29.0, one_sided in any::<bool>(), n in any::<i32>(), near in -3000i32..3000) {
        for n in [n, near, i32::MIN, i32::MAX, -1, 0] {
            check_same_as_reference::<Fx64>(k, limit, one_sided, n)?;
            check_same_as_reference::<Fx32>(k.min(300.0), limit, one_sided, n)?;
            check_same_as_reference::<F32>(k, limit, one_sided, n)?;
        }
    }

    #[test]
    fn fixed_point_force_matches_eq2(k in 0.002f32..300.0, shift in 0u8..4, n in any::<i32>()) {
        check_backend::<Fx64>(k, shift, n, 0.0, 2147483648.0)?;
    }

    #[test]
    fn fixed_point_force_small_counts(k in 0.002f32..300.0, n in -5000i32..5000) {
        check_backend::<Fx64>(k, 0, n, 0.0, 2147483648.0)?;
    }

    #[test]
    fn fx32_force_within_one_code_near_the_wall(k in 0.2f32..300.0, n in -3000i32..3000) {
        // I16F16: the gain error (≤ 2^-17 code) times |2n+1| ≤ 6001 adds < 0.05 code.
        check_backend::<Fx32>(k, 0, n, 0.05, 32768.0)?;
    }

    #[test]
    fn f32_force_within_one_code_near_the_wall(k in 0.2f32..300.0, n in -3000i32..3000) {
        check_backend::<F32>(k, 0, n, 0.0, 2147483648.0)?;
    }

    #[test]
    fn counter_wrap_never_flips_the_force(bits in prop::sample::select(std::vec![16u8, 32]), start in any::<u32>(), steps in 1usize..400, stride in 1u32..2000) {
        // Drive the counter monotonically up through several wraps: the force must be
        // monotone non-increasing and end saturated at -limit, never jump back positive.
        let b = BoardInfo { encoder_bits: bits, ..board() };
        let cfg = ServoConfig { stiffness: 50.0, force_limit: 20.0, encoder_jump_counts: 1 << 30, ..ServoConfig::default() };
        let mut ch = Channels::new();
        let (sp, _hp) = ch.split();
        let mut s: Servo<'_> = Servo::new(b, &cfg, sp);
        let mask = if bits == 32 { u32::MAX } else { (1u32 << bits) - 1 };
        let stride = stride.min(mask / 4);
        let mut raw = start & mask;
        let mut enc = Enc(raw);
        let mut out = Out(0);
        let mut prev = s.tick_spring(&mut enc, &mut out);
        let wraps_needed = (u64::from(mask) + 1) * 2 / u64::from(stride) + 1;
        for _ in 0..(steps as u64 + wraps_needed.min(70_000)) {
            raw = raw.wrapping_add(stride) & mask;
            enc.0 = raw;
            let c = s.tick_spring(&mut enc, &mut out);
            prop_assert!(c <= prev, "force went up from {prev} to {c}");
            prev = c;
        }
        if wraps_needed <= 70_000 {
            prop_assert_eq!(prev, -s.gains().limit);
        }
    }
}

#[test]
fn saturates_at_extreme_counts() {
    let b = board();
    let cfg = ServoConfig {
        stiffness: 80.0,
        force_limit: 10.0,
        ..ServoConfig::default()
    };
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let s: Servo<'_> = Servo::new(b, &cfg, sp);
    let lim = s.gains().limit;
    assert_eq!(lim, 10240);
    assert!(s.spring_code(i32::MAX) <= -lim);
    assert!(s.spring_code(i32::MIN) >= lim);
    assert_eq!(s.spring_code(0), -5); // −K·Δ·½ / fs = −80/16 = −5
    assert_eq!(s.spring_code(-1), 5);
    assert_eq!(s.spring_code(3), -35);
}

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
