//! The integer gains derived from a valid config ([`Gains`]), in device units: output codes,
//! raw or effective encoder counts (Δ_eff = 2^shift counts), servo ticks.
//!
//! Invariant: [`Gains::from_config`] never saturates for a config that passed
//! [`super::validate`]; out-of-range values saturate, never wrap or panic. Derived in `f64`
//! once per config change, never in a tick without one.

use super::board::BoardInfo;
use super::limits::{
    MAX_COARSEN_SHIFT, MAX_DEADBAND_COUNTS, MAX_DELAY_TICKS, MAX_LIMIT_CODES, VEL_WINDOW,
};
use crate::numeric::{AbsBound, Numeric, RangeBound, Shift, DAMPER_V_MAX};
use stiffwall_proto::{DamperLaw, ServoConfig, WallMode};

/// Dimensionless hold damping β of the release test's holding controller (see [`Gains`]).
pub const HOLD_BETA: f32 = 2.0;

/// Smallest β_v = B/(KT) of the wall's virtual damper at which the release hold (and the
/// impact's hold before its launch) uses the wall's own damping instead of β = `HOLD_BETA`:
/// with a damper of that size a β = 2 hold at a stiffness far above the spring-only limit
/// buzzes (the damped frontier is not monotone in B), while a small damper (a hold of β_v
/// 0.4 behind 2 ticks of delay diverged) is better held at β = 2.
pub const HOLD_WALL_DAMPING: f64 = 0.5;

/// Integer / fixed-point servo parameters derived from a valid config.
///
/// `repr(C)`, the wall tick's fields first (as [`crate::Servo`], whose first field this is):
/// the tick's loads then use small offsets and paired loads whatever the back-end's gain sizes.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Gains<N: Numeric> {
    /// `k_half` precomputed for [`Numeric::spring`].
    pub spring: N::Spring,
    /// `damp` in the form [`Numeric::damper`] uses.
    pub damp_s: N::Spring,
    /// When the wall's damper acts: |dn| > the law's dead band ([`DamperLaw::dead_band`]: 0
    /// for the plain difference, which acts on any motion), never without a damper (B = 0).
    /// Where it does not act its term is exactly 0 (v = 0, or a zero gain), so one unsigned
    /// compare is the damper's on/off test and its dead band at once.
    pub damper_band: AbsBound,
    /// |v| > [`DAMPER_V_MAX`] (a constant, kept here, beside `damper_band`, so the tick loads
    /// both with one multiple load instead of building it).
    pub damper_v: AbsBound,
    /// The wall's counts strictly between `wall_n_lo` and `n_sat`, where the spring is
    /// computed: n with `(n − wall_in) as u32 < wall_span` (one unsigned compare; see
    /// `Servo::spring_code`). `wall_in` = `wall_n_lo` + 1.
    pub wall_in: i32,
    /// `n_sat` − `wall_in`: how many counts that is.
    pub wall_span: u32,
    /// Count clamp of the spring: the smallest n ≥ 0 with (2n+1)·k_half ≥ limit + the largest
    /// damper code (0 without a damper). Clamping n to [−n_sat−1, n_sat] leaves the clamped
    /// force of spring + damper unchanged and keeps the product in range.
    pub n_sat: i32,
    /// The wall's lower count bound: −1 for a one-sided wall (the force is 0 for n < 0), else
    /// −`n_sat`−1. At or below it the wall's code is `wall_lo`.
    pub wall_n_lo: i32,
    /// The wall's code for n ≤ `wall_n_lo`: 0 (one-sided) or `spring_lo`.
    pub wall_lo: i32,
    /// The spring code at n = `n_sat` (before the output clamp): the code for every n ≥ `n_sat`.
    pub spring_hi: i32,
    /// Output clamp, codes (≤ board max and ≤ [`MAX_LIMIT_CODES`]).
    pub limit: i32,
    /// The lowest effective count in contact: 0 for a one-sided wall (n < 0 is free space),
    /// `i32::MIN` for a two-sided one. "Outside a one-sided wall" is `n < contact_n`.
    pub contact_n: i32,
    /// Wall position, raw counts.
    pub wall: i32,
    /// Extra delay, ticks.
    pub delay: u32,
    /// `jump` as an [`AbsBound`].
    pub jump_bound: AbsBound,
    /// The over-velocity test, `vel_window_counts` as an [`AbsBound`] (never exceeded when
    /// the test is off), so the tick needs no separate on/off test.
    pub vel_bound: AbsBound,
    /// The travel window on the raw count ([`RangeBound::travel`]; the whole `i32` range, never
    /// left, when the config sets none).
    pub travel: RangeBound,
    /// The energy limit as the largest allowed |2n+1|: ⌊√(e8_limit − 1)⌋
    /// ([`stiffwall_core::monitor::limit_m`], `u64::isqrt`), so that |2n+1| > this ⟺
    /// e8(n) = (2n+1)² + 1 > e8_limit (no multiply in the servo).
    pub energy_limit_m: u32,
    /// Growth score that trips the energy monitor.
    pub growth_trip: i32,
    /// Heartbeat timeout, ticks; 0 = off.
    pub heartbeat_ticks: u32,
    /// `shift` as a [`Shift`] (for the servo path).
    pub coarsen: Shift,
    /// `damp` is not zero.
    pub damping_on: bool,
    /// An excitation adds the wall's centring spring and damper (`k_half` or `damp` is not
    /// zero: K > 0 or B > 0); without, its codes are the profile's alone, flagged `WALL_OFF`.
    pub excite_centring: bool,
    /// One-sided wall.
    pub one_sided: bool,
    /// Energy monitor on (and K > 0).
    pub energy_monitor: bool,
    /// Safe mode outputs damping (else zero).
    pub safe_damping: bool,
    /// K·Δ_eff/2 in output codes: the force code for effective count n is
    /// `-mul(k_half, 2n+1)`.
    pub k_half: N::Gain,
    /// Virtual damping B·Δ_eff·rate in codes per effective count per tick.
    pub damp: N::Gain,
    /// Release-test hold damping, codes per effective count per tick: β = `HOLD_BETA` = 2
    /// (2·β·k_half), or the wall's own `damp` when its β_v = B/(KT) is at least
    /// [`HOLD_WALL_DAMPING`] (the hold is then the wall under test centred on its target).
    pub hold_damp: N::Gain,
    /// The impact launch's damping while its target moves: always β = `HOLD_BETA`.
    pub launch_damp: N::Gain,
    /// Safe-mode damping B_safe·Δ·rate in codes per raw count per tick.
    pub safe_damp: N::Gain,
    /// Coarsening shift.
    pub shift: u32,
    /// The spring code at n = −`n_sat`−1: the code for every n ≤ −`n_sat`−1.
    pub spring_lo: i32,
    /// Over-velocity threshold in raw counts per [`VEL_WINDOW`] ticks; 0 = off.
    pub vel_window_counts: u32,
    /// Encoder-jump threshold, raw counts per tick.
    pub jump: u32,
    /// Energy limit in units of K·Δ_eff²/8.
    pub energy_limit_e8: u64,
    /// Longest buzz window, ticks ([`stiffwall_core::monitor::buzz_window_ticks`]).
    pub buzz_window_ticks: u32,
    /// Servo rate, Hz.
    pub rate_hz: u32,
}

/// The output limit in codes: `force_limit` over the code's force, rounded, within
/// [0, min(board max, `MAX_LIMIT_CODES`)] (0 when not finite).
pub(crate) fn limit_codes(cfg: &ServoConfig, board: &BoardInfo) -> i32 {
    let codes = libm::round(f64::from(cfg.force_limit) / f64::from(board.force_per_code));
    if codes.is_finite() {
        (codes as i32).clamp(0, board.max_code.clamp(0, MAX_LIMIT_CODES))
    } else {
        0
    }
}

/// The energy limit in the monitor's units e8 = 8·E/(K·Δ_eff²) (`kd2` = K·Δ_eff²); no limit
/// (u64::MAX) when K = 0 or the quotient is not a positive finite number.
fn energy_limit_e8(cfg: &ServoConfig, kd2: f64) -> u64 {
    let e8 = if kd2 > 0.0 {
        8.0 * f64::from(cfg.energy_limit) / kd2
    } else {
        0.0
    };
    if e8.is_finite() && e8 > 0.0 {
        e8 as u64
    } else {
        u64::MAX
    }
}

/// The count beyond which the spring's code is at the limit even after the damper's largest
/// code (|g|·DAMPER_V_MAX, rounded up, + 1 for the rounding), so that spring + damper is still
/// exactly clamped at every count (without a damper the bound is the spring-only one, bit for
/// bit); `kf` = K·Δ_eff/2 and `damp` the damper gain, in codes. At most 2^29.
pub(crate) fn saturation_count(limit: i32, kf: f64, damp: f64) -> i32 {
    let damp_max = libm::ceil(libm::fabs(damp) * f64::from(DAMPER_V_MAX));
    let damp_max = if damp_max > 0.0 { damp_max + 1.0 } else { 0.0 };
    if kf > 0.0 {
        (libm::ceil((f64::from(limit) + damp_max) / (2.0 * kf)) as i32).clamp(0, 1 << 29)
    } else {
        1 << 29
    }
}

/// The over-velocity bound: `max_velocity` as counts over [`VEL_WINDOW`] ticks, rounded up
/// (0: off).
fn velocity_window_counts(cfg: &ServoConfig, board: &BoardInfo, rate: f64) -> u32 {
    let vel =
        f64::from(cfg.max_velocity) * VEL_WINDOW as f64 / (rate * f64::from(board.resolution));
    if vel.is_finite() && vel > 0.0 {
        libm::ceil(vel) as u32
    } else {
        0
    }
}

impl<N: Numeric> Gains<N> {
    /// Derives the gains (call only with a config that passed [`validate`](super::validate()); out-of-range
    /// values saturate).
    #[must_use]
    pub fn from_config(cfg: &ServoConfig, board: &BoardInfo) -> Self {
        // Derived in f64, in software on the M4F (about 7000 instructions): only in the tick
        // that applies a config (a change, a prepared test's first and last tick), the worst
        // tick of `cargo xtask bench-firmware` (docs/BENCHMARKS.md), never in a tick without one.
        let de = f64::from(board.delta_eff(cfg.coarsen_shift));
        let fs = f64::from(board.force_per_code);
        let rate = f64::from(cfg.servo_rate_hz.max(1));
        let k = f64::from(cfg.stiffness);
        let k_half = k * de / (2.0 * fs);
        let limit = limit_codes(cfg, board);
        let kd2 = k * de * de;
        let e8_limit = energy_limit_e8(cfg, kd2);
        let limit_m = stiffwall_core::monitor::limit_m(e8_limit);
        let k_half = N::gain(k_half);
        let kf = N::to_f64(k_half);
        let damp = N::gain(f64::from(cfg.damping) * de * rate / fs);
        // The largest damper code (|g|·DAMPER_V_MAX, rounded up, + 1 for the rounding): the
        // spring saturates only where its code exceeds the limit by that much, so that
        // spring + damper is still exactly clamped at every count (0 without a damper: the
        // bound is the spring-only one, bit for bit).
        let n_sat = saturation_count(limit, kf, N::to_f64(damp));
        let one_sided = cfg.wall == WallMode::OneSided;
        let (spring_hi, spring_lo) = Self::spring_bounds(k_half, n_sat);
        let vel_window_counts = velocity_window_counts(cfg, board, rate);
        let wall_n_lo = wall_n_lo(n_sat, one_sided);
        // n_sat ≤ 2^29: no overflow.
        let wall_in = wall_n_lo + 1;
        Self {
            k_half,
            n_sat,
            wall_in,
            wall_span: (n_sat - wall_in) as u32,
            spring: N::spring_gain(k_half),
            spring_hi,
            spring_lo,
            wall_n_lo,
            wall_lo: if one_sided { 0 } else { spring_lo },
            damp,
            damp_s: N::damper_gain(damp),
            damper_band: damper_band(damp != N::ZERO, cfg.damper),
            damper_v: AbsBound::new(DAMPER_V_MAX.unsigned_abs()),
            damping_on: damp != N::ZERO,
            excite_centring: k_half != N::ZERO || damp != N::ZERO,
            hold_damp: Self::hold_damp(damp, kf),
            launch_damp: N::gain(2.0 * f64::from(HOLD_BETA) * kf),
            safe_damp: N::gain(
                f64::from(cfg.safe_damping) * f64::from(board.resolution) * rate / fs,
            ),
            shift: u32::from(cfg.coarsen_shift.min(MAX_COARSEN_SHIFT)),
            coarsen: Shift::new(u32::from(cfg.coarsen_shift.min(MAX_COARSEN_SHIFT))),
            wall: cfg.wall_position,
            one_sided,
            contact_n: if one_sided { 0 } else { i32::MIN },
            delay: u32::from(cfg.extra_delay_ticks.min(MAX_DELAY_TICKS)),
            limit,
            vel_window_counts,
            vel_bound: velocity_bound(vel_window_counts),
            travel: RangeBound::travel(cfg),
            jump: cfg.encoder_jump_counts.max(1),
            jump_bound: AbsBound::new(cfg.encoder_jump_counts.max(1)),
            energy_monitor: cfg.energy_monitor && kd2 > 0.0,
            energy_limit_e8: e8_limit,
            energy_limit_m: limit_m,
            growth_trip: i32::from(cfg.energy_growth_cycles.max(1)),
            buzz_window_ticks: stiffwall_core::monitor::buzz_window_ticks(cfg.servo_rate_hz),
            heartbeat_ticks: heartbeat_ticks(cfg),
            safe_damping: cfg.safe_mode == stiffwall_proto::SafeMode::Damping,
            rate_hz: cfg.servo_rate_hz,
        }
    }

    /// The spring codes at the count clamp: at n = `n_sat` (the code for every n ≥ `n_sat`)
    /// and at n = −`n_sat`−1 (for every n below). n_sat ≤ 2^29: |2n+1| < 2^31 (the codes at
    /// the bounds, as the servo used to compute them after clamping n).
    pub(crate) fn spring_bounds(k_half: N::Gain, n_sat: i32) -> (i32, i32) {
        let spring_hi =
            N::mul_bounded(k_half, n_sat.wrapping_mul(2).wrapping_add(1).wrapping_neg());
        let spring_lo = N::mul_bounded(k_half, n_sat.wrapping_mul(2).wrapping_add(1));
        (spring_hi, spring_lo)
    }

    /// The release-test hold's damping: the wall's own `damp` when its β_v is at least
    /// [`HOLD_WALL_DAMPING`] (and K > 0), else β = `HOLD_BETA` (2·β·k_half; `kf` = k_half).
    fn hold_damp(damp: N::Gain, kf: f64) -> N::Gain {
        if N::to_f64(damp) >= HOLD_WALL_DAMPING * 2.0 * kf && kf > 0.0 {
            damp
        } else {
            N::gain(2.0 * f64::from(HOLD_BETA) * kf)
        }
    }
}

/// When the wall's damper acts ([`Gains::damper_band`]): |dn| above the law's dead band
/// (saturated to [`MAX_DEADBAND_COUNTS`]), never when `on` is false (no damper).
pub(crate) fn damper_band(on: bool, law: DamperLaw) -> AbsBound {
    if on {
        AbsBound::new(u32::from(law.dead_band().min(MAX_DEADBAND_COUNTS)))
    } else {
        AbsBound::new(u32::MAX)
    }
}

/// The wall's lower count bound: −1 for a one-sided wall, else −`n_sat`−1.
fn wall_n_lo(n_sat: i32, one_sided: bool) -> i32 {
    if one_sided {
        -1
    } else {
        n_sat.wrapping_neg().wrapping_sub(1)
    }
}

/// The over-velocity test as an [`AbsBound`]: `vel_window_counts`, or never exceeded when
/// the test is off (0).
fn velocity_bound(vel_window_counts: u32) -> AbsBound {
    AbsBound::new(if vel_window_counts > 0 {
        vel_window_counts
    } else {
        u32::MAX
    })
}

/// The heartbeat timeout in servo ticks (saturating; 0 = off).
fn heartbeat_ticks(cfg: &ServoConfig) -> u32 {
    let hb = u64::from(cfg.heartbeat_timeout_ms) * u64::from(cfg.servo_rate_hz) / 1000;
    u32::try_from(hb).unwrap_or(u32::MAX)
}
