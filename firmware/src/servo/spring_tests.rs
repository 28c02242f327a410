//! Unit tests of the spring: the fixed-point force against an exact reference (eq. (2)) on
//! every numeric back-end, the precomputed bounds against clamp-then-multiply, the counter
//! wrap, and saturation at extreme counts. Units: output codes, raw and effective counts.

use super::*;
use crate::channels::Channels;
use crate::hal::{HeldCode as Out, SampledCount as Enc};
use crate::numeric::{Fx32, F32};
use proptest::prelude::*;
use stiffwall_proto::WallMode;

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
    let mut ch = Channels::<Nm>::for_numeric();
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
    let mut ch = Channels::<Nm>::for_numeric();
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
