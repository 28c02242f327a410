//! Board facts, configuration validation, and the integer gains derived from a config.
//!
//! Units: [`ServoConfig`] is SI (see `stiffwall_proto::msg`); [`Gains`] are in device units:
//! output codes, raw or effective encoder counts (Δ_eff = 2^shift counts), servo ticks.
//!
//! Invariant: [`validate`] accepts a config only if every derived gain fits its fixed-point
//! range, so [`Gains::from_config`] never saturates for a valid config. A refused config
//! reports the first offending field with its allowed `[min, max]`.

use crate::numeric::Numeric;
use stiffwall_proto::{
    ConfigField, DamperLaw, DeviceInfo, Limits, ServoConfig, WallMode, MAX_COARSEN_SHIFT,
    MAX_DEADBAND_COUNTS, MAX_DELAY_TICKS,
};

/// Largest |gain| accepted, output codes per count (keeps `I16F16` and `I32F32` in range).
pub const MAX_GAIN_CODES: f32 = 16384.0;
/// Largest force clamp, codes (keeps the spring product far from the `i32` range).
pub const MAX_LIMIT_CODES: i32 = 1 << 24;
/// Largest heartbeat timeout, ms.
pub const MAX_HEARTBEAT_MS: u32 = 600_000;
/// Largest encoder-jump threshold, counts per tick.
pub const MAX_JUMP_COUNTS: u32 = 1 << 30;
/// Largest energy limit, J.
pub const MAX_ENERGY_J: f32 = 1.0e6;
/// Velocity window of the over-velocity check, ticks (power of two).
pub const VEL_WINDOW: usize = 8;
/// Velocity clamp of the damping terms (defined beside the arithmetic that relies on it).
pub use crate::numeric::DAMPER_V_MAX;
/// Dimensionless hold damping β of the release test's holding controller (see [`Gains`]).
pub const HOLD_BETA: f32 = 2.0;

/// Smallest β_v = B/(KT) of the wall's virtual damper at which the release hold (and the
/// impact's hold before its launch) uses the wall's own damping instead of β = `HOLD_BETA`:
/// with a damper of that size a β = 2 hold at a stiffness far above the spring-only limit
/// buzzes (the damped frontier is not monotone in B), while a small damper (a hold of β_v
/// 0.4 behind 2 ticks of delay diverged) is better held at β = 2.
pub const HOLD_WALL_DAMPING: f64 = 0.5;

/// Fixed facts about the board the firmware runs on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoardInfo {
    /// Board name.
    pub name: &'static str,
    /// Encoder resolution Δ, m (rad) per raw count.
    pub resolution: f32,
    /// Counts per revolution (rotary), 0 for linear devices.
    pub counts_per_rev: u32,
    /// Hardware counter width, bits, 1..=32 (16 and 32 are usual).
    pub encoder_bits: u8,
    /// Force (N) or torque (N·m) per output code.
    pub force_per_code: f32,
    /// Largest output code magnitude (e.g. 2047 for a 12-bit bipolar DAC).
    pub max_code: i32,
    /// Lowest servo rate the board supports, Hz.
    pub min_rate_hz: u32,
    /// Highest servo rate the board supports, Hz.
    pub max_rate_hz: u32,
}

impl Default for BoardInfo {
    /// A generic simulated board: 8192 counts/rev rotary encoder on a 16-bit counter, 16-bit
    /// bipolar output with 10 µN·m per code, 100 Hz – 20 kHz.
    fn default() -> Self {
        Self {
            name: "generic",
            resolution: core::f32::consts::TAU / 8192.0,
            counts_per_rev: 8192,
            encoder_bits: 16,
            force_per_code: 1.0e-5,
            max_code: 32767,
            min_rate_hz: 100,
            max_rate_hz: 20_000,
        }
    }
}

impl BoardInfo {
    /// Largest stiffness at coarsening shift `shift`, N/m (N·m/rad).
    #[must_use]
    pub fn max_stiffness(&self, shift: u8) -> f32 {
        2.0 * MAX_GAIN_CODES * self.force_per_code / self.delta_eff(shift)
    }

    /// Largest damping at shift `shift` and rate `rate_hz`, N·s/m.
    #[must_use]
    pub fn max_damping(&self, shift: u8, rate_hz: u32) -> f32 {
        MAX_GAIN_CODES * self.force_per_code / (self.delta_eff(shift) * rate_hz as f32)
    }

    /// Δ_eff = 2^shift · Δ, m (rad).
    #[must_use]
    pub fn delta_eff(&self, shift: u8) -> f32 {
        self.resolution * (1u32 << u32::from(shift.min(31))) as f32
    }

    /// Largest force limit, N (N·m).
    #[must_use]
    pub fn max_force(&self) -> f32 {
        self.max_code as f32 * self.force_per_code
    }

    /// Largest over-velocity threshold at `rate_hz`, m/s.
    #[must_use]
    pub fn max_velocity(&self, rate_hz: u32) -> f32 {
        (MAX_JUMP_COUNTS as f32) * self.resolution * rate_hz as f32 / VEL_WINDOW as f32
    }

    /// The handshake reply for this board at `rate_hz`.
    #[must_use]
    pub fn device_info(&self, rate_hz: u32) -> DeviceInfo {
        let s = |x: &str| heapless::String::try_from(x).unwrap_or_default();
        DeviceInfo {
            protocol_version: stiffwall_proto::PROTOCOL_VERSION,
            firmware_name: s("stiffwall"),
            firmware_version: s(env!("CARGO_PKG_VERSION")),
            board: s(self.name),
            servo_rate_hz: rate_hz,
            counts_per_rev: self.counts_per_rev,
            resolution: self.resolution,
            encoder_bits: self.encoder_bits,
            force_per_code: self.force_per_code,
            max_code: self.max_code,
            limits: Limits {
                min_rate_hz: self.min_rate_hz,
                max_rate_hz: self.max_rate_hz,
                max_stiffness: self.max_stiffness(0),
                max_force: self.max_force(),
                max_delay_ticks: MAX_DELAY_TICKS,
                max_coarsen_shift: MAX_COARSEN_SHIFT,
                telemetry_batch: stiffwall_proto::TELEMETRY_BATCH as u16,
                max_table: stiffwall_proto::MAX_TABLE as u16,
            },
        }
    }
}

/// A refused configuration: the field and its allowed range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConfigError {
    /// The offending field.
    pub field: ConfigField,
    /// Smallest allowed value.
    pub min: f64,
    /// Largest allowed value.
    pub max: f64,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.field == ConfigField::Damper {
            // The range is the dead band's, in counts; `difference` is the law without one.
            return write!(
                f,
                "damper: the dead band must be within [{}, {}] counts (use `difference` for no \
                 dead band)",
                self.min, self.max
            );
        }
        if self.field == ConfigField::TravelMax {
            return write!(
                f,
                "travel_max must be above travel_min, within [{}, {}] raw counts",
                self.min, self.max
            );
        }
        write!(
            f,
            "{} must be within [{}, {}]",
            self.field, self.min, self.max
        )
    }
}

impl core::error::Error for ConfigError {}

fn check_f(field: ConfigField, v: f32, min: f32, max: f32) -> Result<(), ConfigError> {
    if v.is_finite() && v >= min && v <= max {
        Ok(())
    } else {
        Err(ConfigError {
            field,
            min: f64::from(min),
            max: f64::from(max),
        })
    }
}

fn check_u(field: ConfigField, v: u32, min: u32, max: u32) -> Result<(), ConfigError> {
    if v >= min && v <= max {
        Ok(())
    } else {
        Err(ConfigError {
            field,
            min: f64::from(min),
            max: f64::from(max),
        })
    }
}

/// Range-checks every field of `cfg` for `board`.
///
/// # Errors
/// The first field out of range, with its range.
pub fn validate(cfg: &ServoConfig, board: &BoardInfo) -> Result<(), ConfigError> {
    use ConfigField as F;
    check_u(
        F::ServoRateHz,
        cfg.servo_rate_hz,
        board.min_rate_hz,
        board.max_rate_hz,
    )?;
    check_u(
        F::ExtraDelayTicks,
        cfg.extra_delay_ticks.into(),
        0,
        MAX_DELAY_TICKS.into(),
    )?;
    check_u(
        F::CoarsenShift,
        cfg.coarsen_shift.into(),
        0,
        MAX_COARSEN_SHIFT.into(),
    )?;
    let s = cfg.coarsen_shift;
    check_f(F::Stiffness, cfg.stiffness, 0.0, board.max_stiffness(s))?;
    let dmax = board.max_damping(s, cfg.servo_rate_hz);
    check_f(F::Damping, cfg.damping, 0.0, dmax)?;
    check_f(
        F::ForceLimit,
        cfg.force_limit,
        board.force_per_code,
        board.max_force(),
    )?;
    check_f(
        F::MaxVelocity,
        cfg.max_velocity,
        0.0,
        board.max_velocity(cfg.servo_rate_hz),
    )?;
    check_f(
        F::EnergyLimit,
        cfg.energy_limit,
        f32::MIN_POSITIVE,
        MAX_ENERGY_J,
    )?;
    check_u(
        F::EnergyGrowthCycles,
        cfg.energy_growth_cycles.into(),
        1,
        64,
    )?;
    check_u(
        F::EncoderJumpCounts,
        cfg.encoder_jump_counts,
        1,
        MAX_JUMP_COUNTS,
    )?;
    check_u(
        F::HeartbeatTimeoutMs,
        cfg.heartbeat_timeout_ms,
        0,
        MAX_HEARTBEAT_MS,
    )?;
    let dsafe = board.max_damping(0, cfg.servo_rate_hz);
    check_f(F::SafeDamping, cfg.safe_damping, 0.0, dsafe)?;
    if let DamperLaw::DeadBand { counts } = cfg.damper {
        check_u(F::Damper, counts.into(), 1, MAX_DEADBAND_COUNTS.into())?;
    }
    if let (Some(lo), Some(hi)) = (cfg.travel_min, cfg.travel_max) {
        if hi <= lo {
            return Err(ConfigError {
                field: F::TravelMax,
                min: f64::from(lo) + 1.0,
                max: f64::from(i32::MAX),
            });
        }
    }
    Ok(())
}

/// A shift amount 0..=31. Its type tells the compiler the range, so shifting by it needs no
/// `& 31` mask (`wrapping_shl`/`wrapping_shr` by a plain `u32` do).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u8)]
#[allow(missing_docs)]
pub enum Shift {
    #[default]
    S0,
    S1,
    S2,
    S3,
    S4,
    S5,
    S6,
    S7,
    S8,
    S9,
    S10,
    S11,
    S12,
    S13,
    S14,
    S15,
    S16,
    S17,
    S18,
    S19,
    S20,
    S21,
    S22,
    S23,
    S24,
    S25,
    S26,
    S27,
    S28,
    S29,
    S30,
    S31,
}

impl Shift {
    const ALL: [Shift; 32] = [
        Shift::S0,
        Shift::S1,
        Shift::S2,
        Shift::S3,
        Shift::S4,
        Shift::S5,
        Shift::S6,
        Shift::S7,
        Shift::S8,
        Shift::S9,
        Shift::S10,
        Shift::S11,
        Shift::S12,
        Shift::S13,
        Shift::S14,
        Shift::S15,
        Shift::S16,
        Shift::S17,
        Shift::S18,
        Shift::S19,
        Shift::S20,
        Shift::S21,
        Shift::S22,
        Shift::S23,
        Shift::S24,
        Shift::S25,
        Shift::S26,
        Shift::S27,
        Shift::S28,
        Shift::S29,
        Shift::S30,
        Shift::S31,
    ];

    /// The shift `s`, saturated to 31.
    #[must_use]
    pub fn new(s: u32) -> Self {
        *Self::ALL.get(s.min(31) as usize).unwrap_or(&Shift::S31)
    }

    /// The amount.
    #[inline]
    #[must_use]
    pub fn get(self) -> u32 {
        self as u32
    }
}

/// The test `|x| > t` for every `i32` x as one unsigned compare,
/// `(x as u32).wrapping_add(bias) > span`: for t < 2^31, bias = t and span = 2t (x + t lands in
/// 0..=2t exactly when −t ≤ x ≤ t, and wraps above 2t when x < −t); for t ≥ 2^31 no |x|
/// exceeds t, and span = `u32::MAX` is never exceeded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AbsBound {
    bias: u32,
    span: u32,
}

impl AbsBound {
    /// The bound for threshold `t`.
    #[must_use]
    pub const fn new(t: u32) -> Self {
        if t < 1 << 31 {
            Self {
                bias: t,
                span: 2 * t,
            }
        } else {
            Self {
                bias: 0,
                span: u32::MAX,
            }
        }
    }

    /// `|x| > t`.
    #[inline(always)]
    #[must_use]
    pub fn exceeded(self, x: i32) -> bool {
        (x as u32).wrapping_add(self.bias) > self.span
    }
}

/// The test "x outside [lo, hi]" for every `i32` x as one unsigned compare,
/// `(x as u32).wrapping_sub(lo as u32) > span` with span = hi − lo (as `u32`): x − lo, taken
/// modulo 2^32, lies in 0..=span exactly when lo ≤ x ≤ hi, and wraps above span when x < lo.
/// The full `i32` range (lo = `i32::MIN`, span = `u32::MAX`) is never left: a window that is
/// off costs the same one compare.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RangeBound {
    lo: i32,
    span: u32,
}

impl RangeBound {
    /// The window [`lo`, `hi`] (lo ≤ hi; a reversed pair gives the empty-but-for-`lo` window
    /// [lo, lo], never a wrapped one).
    #[must_use]
    pub const fn new(lo: i32, hi: i32) -> Self {
        let hi = if hi < lo { lo } else { hi };
        Self {
            lo,
            span: (hi as u32).wrapping_sub(lo as u32),
        }
    }

    /// The travel window of a config: `travel_min` (`i32::MIN` when `None`) to `travel_max`
    /// (`i32::MAX` when `None`).
    #[must_use]
    pub fn travel(cfg: &ServoConfig) -> Self {
        Self::new(
            cfg.travel_min.unwrap_or(i32::MIN),
            cfg.travel_max.unwrap_or(i32::MAX),
        )
    }

    /// `x` < lo or `x` > hi.
    #[inline(always)]
    #[must_use]
    pub fn outside(self, x: i32) -> bool {
        (x as u32).wrapping_sub(self.lo as u32) > self.span
    }
}

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
fn limit_codes(cfg: &ServoConfig, board: &BoardInfo) -> i32 {
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
fn saturation_count(limit: i32, kf: f64, damp: f64) -> i32 {
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
    /// Derives the gains (call only with a config that passed [`validate`]; out-of-range
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
    fn spring_bounds(k_half: N::Gain, n_sat: i32) -> (i32, i32) {
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
fn damper_band(on: bool, law: DamperLaw) -> AbsBound {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::Fx64;
    use proptest::prelude::*;

    fn check_abs_bound(x: i32, t: u32) -> Result<(), TestCaseError> {
        prop_assert_eq!(
            AbsBound::new(t).exceeded(x),
            x.unsigned_abs() > t,
            "x = {}, t = {}",
            x,
            t
        );
        Ok(())
    }

    #[test]
    fn abs_bound_at_the_edges() {
        let edges = [
            0u32,
            1,
            2,
            (1 << 30) - 1,
            1 << 30,
            (1 << 31) - 1,
            1 << 31,
            u32::MAX,
        ];
        for &t in &edges {
            for x in [i32::MIN, i32::MIN + 1, -1, 0, 1, i32::MAX - 1, i32::MAX] {
                check_abs_bound(x, t).unwrap();
            }
            for dx in [-1i64, 0, 1] {
                for x in [i64::from(t) + dx, -i64::from(t) + dx] {
                    if let Ok(x) = i32::try_from(x) {
                        check_abs_bound(x, t).unwrap();
                    }
                }
            }
        }
    }

    proptest! {
        #[test]
        fn abs_bound_is_the_abs_test(x in any::<i32>(), t in any::<u32>(), small in 0u32..1000, near in -1000i32..1000) {
            for t in [t, small] {
                for x in [x, near] {
                    check_abs_bound(x, t)?;
                }
            }
        }
    }

    #[test]
    fn default_config_is_valid_and_each_field_is_checked() {
        let b = BoardInfo::default();
        let c = ServoConfig::default();
        assert_eq!(validate(&c, &b), Ok(()));
        let bad: [(ServoConfig, ConfigField); 16] = [
            (
                ServoConfig {
                    stiffness: -1.0,
                    ..c
                },
                ConfigField::Stiffness,
            ),
            (
                ServoConfig {
                    stiffness: f32::NAN,
                    ..c
                },
                ConfigField::Stiffness,
            ),
            (
                ServoConfig {
                    damping: f32::INFINITY,
                    ..c
                },
                ConfigField::Damping,
            ),
            (
                ServoConfig {
                    servo_rate_hz: 99,
                    ..c
                },
                ConfigField::ServoRateHz,
            ),
            (
                ServoConfig {
                    extra_delay_ticks: 32,
                    ..c
                },
                ConfigField::ExtraDelayTicks,
            ),
            (
                ServoConfig {
                    coarsen_shift: 17,
                    ..c
                },
                ConfigField::CoarsenShift,
            ),
            (
                ServoConfig {
                    force_limit: 0.0,
                    ..c
                },
                ConfigField::ForceLimit,
            ),
            (
                ServoConfig {
                    max_velocity: -0.1,
                    ..c
                },
                ConfigField::MaxVelocity,
            ),
            (
                ServoConfig {
                    energy_limit: 0.0,
                    ..c
                },
                ConfigField::EnergyLimit,
            ),
            (
                ServoConfig {
                    energy_growth_cycles: 0,
                    ..c
                },
                ConfigField::EnergyGrowthCycles,
            ),
            (
                ServoConfig {
                    encoder_jump_counts: 0,
                    ..c
                },
                ConfigField::EncoderJumpCounts,
            ),
            (
                ServoConfig {
                    safe_damping: -1.0,
                    ..c
                },
                ConfigField::SafeDamping,
            ),
            (
                ServoConfig {
                    damper: DamperLaw::DeadBand { counts: 0 },
                    ..c
                },
                ConfigField::Damper,
            ),
            (
                ServoConfig {
                    damper: DamperLaw::DeadBand {
                        counts: MAX_DEADBAND_COUNTS + 1,
                    },
                    ..c
                },
                ConfigField::Damper,
            ),
            (
                ServoConfig {
                    travel_min: Some(10),
                    travel_max: Some(10),
                    ..c
                },
                ConfigField::TravelMax,
            ),
            (
                ServoConfig {
                    travel_min: Some(i32::MAX),
                    travel_max: Some(i32::MIN),
                    ..c
                },
                ConfigField::TravelMax,
            ),
        ];
        for (cfg, field) in bad {
            assert_eq!(validate(&cfg, &b).map_err(|e| e.field), Err(field));
        }
        let e = validate(
            &ServoConfig {
                servo_rate_hz: 50_000,
                ..c
            },
            &b,
        )
        .unwrap_err();
        assert_eq!((e.min, e.max), (100.0, 20_000.0));
    }

    #[test]
    fn gains_of_a_known_config() {
        let b = BoardInfo {
            resolution: 1e-5,
            force_per_code: 1e-3,
            ..BoardInfo::default()
        };
        let c = ServoConfig {
            stiffness: 1000.0,
            coarsen_shift: 1,
            force_limit: 1.0,
            ..ServoConfig::default()
        };
        let g: Gains<Fx64> = Gains::from_config(&c, &b);
        // K·Δ_eff/2/fs = 1000 · 2e-5 / 2 / 1e-3 = 10 codes.
        assert!((Fx64::to_f64(g.k_half) - 10.0).abs() < 1e-4);
        assert_eq!(g.limit, 1000);
        assert_eq!(g.shift, 1);
    }

    #[test]
    fn config_error_names_the_field_and_its_range() {
        use std::string::ToString;
        let e = validate(
            &ServoConfig {
                servo_rate_hz: 50_000,
                ..ServoConfig::default()
            },
            &BoardInfo::default(),
        )
        .unwrap_err();
        let err: &dyn core::error::Error = &e;
        assert_eq!(err.to_string(), "servo_rate_hz must be within [100, 20000]");
        let e = validate(
            &ServoConfig {
                damper: DamperLaw::DeadBand { counts: 0 },
                ..ServoConfig::default()
            },
            &BoardInfo::default(),
        )
        .unwrap_err();
        assert_eq!((e.field, e.min, e.max), (ConfigField::Damper, 1.0, 8.0));
        assert_eq!(
            e.to_string(),
            "damper: the dead band must be within [1, 8] counts (use `difference` for no dead band)"
        );
    }

    /// The travel window: off by default (and so in every older record), either end alone, or
    /// both with min < max; min ≥ max is refused naming `travel_max` and its range.
    #[test]
    fn travel_window_is_checked_and_derived() {
        use std::string::ToString;
        let b = BoardInfo::default();
        let c = ServoConfig::default();
        assert_eq!((c.travel_min, c.travel_max), (None, None));
        let window = |lo: Option<i32>, hi: Option<i32>| ServoConfig {
            travel_min: lo,
            travel_max: hi,
            ..c
        };
        for (lo, hi) in [
            (None, None),
            (Some(-5), None),
            (None, Some(-5)),
            (Some(-5), Some(-4)),
            (Some(i32::MIN), Some(i32::MAX)),
        ] {
            assert_eq!(validate(&window(lo, hi), &b), Ok(()), "{lo:?}..{hi:?}");
        }
        let e = validate(&window(Some(100), Some(-100)), &b).unwrap_err();
        assert_eq!(
            (e.field, e.min, e.max),
            (ConfigField::TravelMax, 101.0, f64::from(i32::MAX))
        );
        assert_eq!(
            e.to_string(),
            "travel_max must be above travel_min, within [101, 2147483647] raw counts"
        );
        let g = |lo, hi| Gains::<Fx64>::from_config(&window(lo, hi), &b).travel;
        assert_eq!(g(None, None), RangeBound::new(i32::MIN, i32::MAX));
        let w = g(Some(-3), Some(7));
        assert!(w.outside(-4) && !w.outside(-3) && !w.outside(7) && w.outside(8));
        assert!(w.outside(i32::MIN) && w.outside(i32::MAX));
        let lower = g(Some(-3), None);
        assert!(lower.outside(-4) && !lower.outside(i32::MAX));
        let upper = g(None, Some(7));
        assert!(!upper.outside(i32::MIN) && upper.outside(8));
    }

    fn check_range_bound(x: i32, lo: i32, hi: i32) -> Result<(), TestCaseError> {
        let (lo, hi) = (lo.min(hi), lo.max(hi));
        prop_assert_eq!(
            RangeBound::new(lo, hi).outside(x),
            x < lo || x > hi,
            "x = {}, [{}, {}]",
            x,
            lo,
            hi
        );
        Ok(())
    }

    #[test]
    fn range_bound_at_the_edges() {
        let edges = [i32::MIN, i32::MIN + 1, -1, 0, 1, i32::MAX - 1, i32::MAX];
        for &lo in &edges {
            for &hi in &edges {
                for &x in &edges {
                    check_range_bound(x, lo, hi).unwrap();
                }
            }
        }
        // The full range is never left.
        assert!(edges
            .iter()
            .all(|&x| !RangeBound::new(i32::MIN, i32::MAX).outside(x)));
        // A reversed pair is [lo, lo], never a wrapped window.
        assert!(!RangeBound::new(5, 4).outside(5) && RangeBound::new(5, 4).outside(4));
    }

    proptest! {
        #[test]
        fn range_bound_is_the_interval_test(x in any::<i32>(), lo in any::<i32>(), hi in any::<i32>(), near in -1000i32..1000, small in -1000i32..1000) {
            for x in [x, near, lo, hi, lo.wrapping_sub(1), hi.wrapping_add(1)] {
                check_range_bound(x, lo, hi)?;
                check_range_bound(x, small, small.saturating_add(near.abs()))?;
            }
        }
    }

    /// The damper's one test: never without a damper; any motion for the plain difference;
    /// beyond the dead band otherwise (every law in range is accepted).
    #[test]
    fn damper_band_is_the_law_and_the_on_off_test() {
        let b = BoardInfo::default();
        let gains = |damping: f32, damper: DamperLaw| {
            let c = ServoConfig {
                damping,
                damper,
                ..ServoConfig::default()
            };
            assert_eq!(validate(&c, &b), Ok(()));
            Gains::<Fx64>::from_config(&c, &b)
        };
        for law in [DamperLaw::Difference, DamperLaw::DeadBand { counts: 3 }] {
            let off = gains(0.0, law);
            assert!(!off.damping_on);
            assert!([i32::MIN, -5, 0, 5, i32::MAX]
                .iter()
                .all(|&dn| !off.damper_band.exceeded(dn)));
        }
        let diff = gains(0.01, DamperLaw::Difference);
        assert!(!diff.damper_band.exceeded(0));
        assert!(diff.damper_band.exceeded(1) && diff.damper_band.exceeded(-1));
        for counts in 1..=MAX_DEADBAND_COUNTS {
            let g = gains(0.01, DamperLaw::DeadBand { counts });
            let c = i32::from(counts);
            assert!(!g.damper_band.exceeded(c) && !g.damper_band.exceeded(-c));
            assert!(g.damper_band.exceeded(c + 1) && g.damper_band.exceeded(-c - 1));
            assert!(g.damper_band.exceeded(i32::MIN) && g.damper_band.exceeded(i32::MAX));
        }
    }
}
