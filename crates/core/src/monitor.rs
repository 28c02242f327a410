//! The dissipation check of the paper in integer form: the energy monitor that the firmware runs
//! every servo tick and `hostctl replay` runs over a recording.
//!
//! Units: `n` is the effective count ⌊ξ⌋ (encoder counts at Δ_eff = 2^shift·Δ, relative to the
//! wall); energies `e8` are in units of K·Δ_eff²/8, i.e. eight times the dimensionless energy of
//! [`crate::energy`] (units K·Δ_eff²).
//!
//! The integer energy is the storage function H_T (35) at a turning point (ξ̇ = 0, so H_T equals
//! its potential part H_e (34), which needs no mass) with the unknown quantization error ρ at
//! the middle of the count, ξ = n + ½:
//!
//! ```text
//! energy_e8(n) = 8·H_T(ξ = n + ½, ξ̇ = 0) = 8·H_e(n + ½) = 8·(½(n + ½)² + ⅛) = (2n + 1)² + 1
//! ```
//!
//! exactly, for every `i32` n (property-tested against [`crate::energy::storage_energy`]).
//! On the count cell [n, n + 1) H_e is linear in ρ (H_e(n + ρ) = ½n² + (n + ½)ρ), so `e8` is
//! also the mean of 8·H_e over the cell and lies between its values at the cell's ends,
//! 4n² and 4(n + 1)².
//!
//! Invariants: no allocation, no floating point, no panics; every operation saturates or is
//! exact (`energy_e8` < 2^64 for every `i32`). The monitor's per-tick work is a compare, a
//! subtraction and a branch; scoring a turning point (rare) compares two |2n + 1| values, which
//! orders their energies exactly since e8 = |2n + 1|² + 1 is strictly increasing in |2n + 1|.

/// Bit returned by [`EnergyMonitor::update`] when the growth score reached its trip level
/// (the same bit as `stiffwall_proto::fault::ENERGY_GROWTH`).
pub const GROWTH: u32 = 1 << 0;
/// Bit returned by [`EnergyMonitor::update`] when the energy is above the limit on this tick
/// (the same bit as `stiffwall_proto::fault::ENERGY_LIMIT`).
pub const LIMIT: u32 = 1 << 1;

/// Bit returned by [`EnergyMonitor::buzz_turn`] when a persistent oscillation ("buzz") was seen
/// (the same bit as `stiffwall_proto::fault::BUZZ`).
pub const BUZZ: u32 = 1 << 5;
/// Consecutive half-cycles (turning points) a buzz must last: an even number, so that the first
/// and the last swing of the window start on the same side.
pub const BUZZ_HALF_CYCLES: u16 = 32;
/// Lowest oscillation frequency counted as buzz, Hz (above voluntary hand motion, < 10 Hz).
pub const BUZZ_MIN_HZ: u32 = 15;
/// Smallest swing between consecutive turning points that counts, effective counts: more than
/// one count peak to peak (a toggle between two neighbouring counts, region B, does not count).
pub const BUZZ_MIN_SWING: u32 = 2;

/// Swings at each end of a buzz window whose largest are compared (the envelope): a decaying
/// oscillation of two modes beats, so one swing can exceed an earlier one while the envelope
/// shrinks.
pub const BUZZ_ENVELOPE: usize = 8;
const _: () =
    assert!(BUZZ_ENVELOPE.is_power_of_two() && BUZZ_ENVELOPE <= BUZZ_HALF_CYCLES as usize);

/// A buzz window's envelope may shrink by up to 1/2^`BUZZ_DECAY_SHIFT` of its first envelope
/// (rounded down: none below 32 counts) and still count as persistent. Between the centres of
/// the first and last [`BUZZ_ENVELOPE`] swings lie 12 cycles, so this is an oscillation whose
/// equivalent damping ratio is below ln(32/31)/(2π·12) ≈ 0.0004: one that converges onto a
/// limit cycle (cogging and a hand at a stiffness above the stable one: 37 counts settling onto
/// 32 over 4 s) instead of decaying. Not 1/16: a two-mode beat below the stable stiffness (a
/// firm hand on a 51 Hz cable) hovers for 60 swings at an envelope of about 46 counts, losing 2
/// per window, before friction ends it, and 1/16 tripped on it. Coulomb friction alone takes 4σ
/// counts off every cycle, a damping ratio of 0.01 takes 53 % off a window.
pub const BUZZ_DECAY_SHIFT: u32 = 5;

/// The longest a buzz window of [`BUZZ_HALF_CYCLES`] may take at `rate_hz`, ticks: half-cycles
/// of at most rate/(2·[`BUZZ_MIN_HZ`]) ticks each.
#[must_use]
pub fn buzz_window_ticks(rate_hz: u32) -> u32 {
    u32::from(BUZZ_HALF_CYCLES).saturating_mul(rate_hz) / (2 * BUZZ_MIN_HZ)
}

/// The buzz detector: a persistent oscillation of more than one count that the growth score
/// misses because its peaks do not grow (a limit cycle, e.g. a firm grip or a slow servo at a
/// stiffness above the stable one). Fed at turning points only ([`EnergyMonitor::buzz_turn`]),
/// so it costs nothing on the other ticks. It trips when [`BUZZ_HALF_CYCLES`] consecutive
/// swings (peak to peak between turning points) of at least [`BUZZ_MIN_SWING`] counts fit in
/// `window_ticks` (a frequency of at least [`BUZZ_MIN_HZ`]) and the largest of its last
/// [`BUZZ_ENVELOPE`] swings is not smaller than the largest of its first ones, less
/// 1/2^[`BUZZ_DECAY_SHIFT`] of it: a decaying oscillation loses more than that over the window
/// and does not trip, even when
/// two modes beat (a motor mode against the wall and a hand or link mode behind a compliant
/// transmission: single swings then rise and fall while the envelope shrinks, and comparing
/// the last swing with the first tripped on decaying motion); any swing below the minimum
/// restarts the window.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BuzzDetector {
    have_prev: bool,
    prev_peak: i32,
    count: u16,
    start: u32,
    /// Largest of the window's first [`BUZZ_ENVELOPE`] swings.
    first_envelope: u32,
    /// The window's latest swings, by `count % BUZZ_ENVELOPE`.
    recent: [u32; BUZZ_ENVELOPE],
}

impl BuzzDetector {
    /// A turning point at count `peak`, tick `now`: returns [`BUZZ`] or 0.
    #[inline(never)]
    pub fn turn(&mut self, now: u32, peak: i32, window_ticks: u32) -> u32 {
        let swing = if self.have_prev {
            peak.abs_diff(self.prev_peak)
        } else {
            0
        };
        self.have_prev = true;
        self.prev_peak = peak;
        if swing < BUZZ_MIN_SWING {
            self.count = 0;
            return 0;
        }
        if self.count == 0 {
            self.start = now;
            self.first_envelope = 0;
        }
        if usize::from(self.count) < BUZZ_ENVELOPE {
            self.first_envelope = self.first_envelope.max(swing);
        }
        // BUZZ_ENVELOPE is a power of two: the index is a mask, in range.
        self.recent[usize::from(self.count) & (BUZZ_ENVELOPE - 1)] = swing;
        self.count = self.count.saturating_add(1);
        if self.count < BUZZ_HALF_CYCLES {
            return 0;
        }
        self.count = 0;
        let last_envelope = self.recent.iter().copied().fold(0, u32::max);
        let persistent = self.first_envelope - (self.first_envelope >> BUZZ_DECAY_SHIFT);
        if last_envelope >= persistent && now.wrapping_sub(self.start) <= window_ticks {
            BUZZ
        } else {
            0
        }
    }
}

/// `e8(n) = (2n+1)² + 1`: the storage function (35) at effective count n with ξ̇ = 0 and the
/// unknown quantization error ρ at its midpoint, 8·H_e(n + ½) = 8·(½(n+½)² + ⅛), in units of
/// K·Δ_eff²/8. Exact for every `i32` n.
#[inline]
#[must_use]
pub fn energy_e8(n: i32) -> u64 {
    // (2^32 − 1)² + 1 < 2^64: no overflow.
    let m = u64::from(odd_abs(n));
    m * m + 1
}

/// [`energy_e8`] saturated to `u32` (32-bit multiply only; for telemetry).
#[inline]
#[must_use]
pub fn energy_e8_u32(n: i32) -> u32 {
    let m = odd_abs(n);
    // m is odd: m² + 1 fits exactly when m ≤ 0xffff (0xffff² + 1 < 2^32 < 0x1_0001²).
    if m <= 0xffff {
        m * m + 1
    } else {
        u32::MAX
    }
}

/// |2n+1| as `u32`, exact for every `i32` n (≤ 2^32 − 1): 2·(n or !n) + 1, three instructions.
#[inline]
#[must_use]
pub fn odd_abs(n: i32) -> u32 {
    ((n ^ (n >> 31)) as u32).wrapping_mul(2).wrapping_add(1)
}

/// The energy limit `e8_limit` (units K·Δ_eff²/8) as the largest allowed |2n+1|:
/// ⌊√(e8_limit − 1)⌋ (saturated to `u32`), so that for every n
/// `odd_abs(n) > limit_m(e8_limit)` ⟺ `energy_e8(n) > e8_limit`: the per-tick limit check
/// needs no multiply. `limit_m(0)` = 0 (every count is over a zero limit).
#[must_use]
pub fn limit_m(e8_limit: u64) -> u32 {
    u32::try_from(e8_limit.saturating_sub(1).isqrt()).unwrap_or(u32::MAX)
}

/// [`LIMIT`] if the energy at effective count `n` is above the limit whose [`limit_m`] is
/// `limit_m`, else 0.
#[inline]
#[must_use]
pub fn limit_fault(n: i32, limit_m: u32) -> u32 {
    if odd_abs(n) > limit_m {
        LIMIT
    } else {
        0
    }
}

/// The energy monitor (see `docs/model-notes-firmware.md`): tracks turning points of the
/// effective count (where ξ̇ = 0, so H_T (35) equals its potential part and needs no mass),
/// compares each peak with the larger of the previous two peaks on the same side (one, for
/// the second peak of a side), and keeps a growth score (+1 peak energy grew, −1 shrank,
/// clamped to ±trip). Score ≥ trip → [`GROWTH`]; energy above
/// the limit on any tick → [`LIMIT`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EnergyMonitor {
    primed: bool,
    prev_n: i32,
    /// Direction of the current half-cycle (−1, 1; 0 before the first motion).
    dir: i8,
    peak: i32,
    /// Last scored peak count per side (0: a maximum, after rising; 1: a minimum).
    last: [i32; 2],
    /// |2n + 1| of the peak scored before `last` on each side (0: none yet).
    before_m: [u32; 2],
    have: [bool; 2],
    score: i32,
    buzz: BuzzDetector,
}

impl EnergyMonitor {
    /// Forgets the history (after a release, an excitation, clearing faults).
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// Current growth score.
    #[must_use]
    pub fn score(&self) -> i32 {
        self.score
    }

    /// Feeds the turning point that [`Self::update`] just reported (it returned `true`) to the
    /// buzz detector ([`BuzzDetector`]), at tick `now`; returns [`BUZZ`] or 0. Call it only on
    /// turning points: the other ticks cost nothing.
    #[inline]
    pub fn buzz_turn(&mut self, now: u32, window_ticks: u32) -> u32 {
        // The peak just scored (as in `last_peak`, without its energy).
        let side = usize::from(self.dir > 0);
        match (self.have.get(side), self.last.get(side)) {
            (Some(true), Some(&n)) => self.buzz.turn(now, n, window_ticks),
            _ => 0,
        }
    }

    /// The count and energy (`e8`) of the turning point scored last, if any.
    #[must_use]
    pub fn last_peak(&self) -> Option<(i32, u64)> {
        // The peak just scored was on the side of the direction before the reversal, the
        // opposite of the current one.
        let side = usize::from(self.dir > 0);
        match (self.have.get(side), self.last.get(side)) {
            (Some(true), Some(&n)) => Some((n, energy_e8(n))),
            _ => None,
        }
    }

    /// One tick at effective count `n`. `trip`: the growth score that trips; `limit_m`: the
    /// largest |2n+1| whose energy e8 is within the limit ([`limit_m`]). Returns (the bits
    /// [`GROWTH`] and [`LIMIT`], turning point seen).
    #[inline]
    pub fn update(&mut self, n: i32, trip: i32, limit_m: u32) -> (u32, bool) {
        let (f, turn) = self.track(n, trip);
        (limit_fault(n, limit_m) | f, turn)
    }

    /// [`EnergyMonitor::update`] without the energy-limit test ([`limit_fault`]): the growth
    /// bits and whether `n` is a turning point.
    #[inline]
    pub fn track(&mut self, n: i32, trip: i32) -> (u32, bool) {
        let dn = n.saturating_sub(self.prev_n);
        self.prev_n = n;
        // The common tick, moving on in the direction of the half-cycle, takes this one test
        // (dn·dir > 0; it misses only dn = i32::MIN, which wraps, and the rare updates below
        // handle that one exactly).
        if dn.wrapping_mul(i32::from(self.dir)) > 0 {
            self.peak = n;
            return (0, false);
        }
        if dn == 0 && self.primed {
            return (0, false);
        }
        self.change(n, dn, trip)
    }

    /// The rare updates: the first after a reset (`prev_n` is `n` already), the first motion,
    /// a reversal (and a motion by `i32::MIN` in the half-cycle's direction).
    #[cold]
    #[inline(never)]
    fn change(&mut self, n: i32, dn: i32, trip: i32) -> (u32, bool) {
        if !self.primed {
            // The start at count `n`, no motion yet.
            self.primed = true;
            self.peak = n;
            return (0, false);
        }
        // dn ≠ 0 here (a saturating difference is 0 only for equal counts).
        let s: i8 = if dn > 0 { 1 } else { -1 };
        if self.dir == 0 || s == self.dir {
            self.peak = n;
            self.dir = s;
            return (0, false);
        }
        (self.turn(n, s, trip), true)
    }

    /// A reversal at count `n` (new direction `s`): scores the peak just passed.
    fn turn(&mut self, n: i32, s: i8, trip: i32) -> u32 {
        let mut faults = 0;
        let side = usize::from(self.dir < 0);
        // e8 = m² + 1 is strictly increasing in m = |2n+1|: comparing m compares the energies.
        let m = odd_abs(self.peak);
        let before = self.before_m.get(side).copied().unwrap_or(0);
        if let (Some(&had), Some(&last)) = (self.have.get(side), self.last.get(side)) {
            if had {
                // Against the larger of the last two peaks on this side: a decaying motion of
                // two modes (a hand or link behind a compliant transmission) beats, and its
                // peaks rise for a few cycles while the envelope shrinks; a growing
                // oscillation exceeds both.
                let m_ref = odd_abs(last).max(before);
                if m > m_ref {
                    self.score = self.score.saturating_add(1).min(trip);
                } else if m < m_ref {
                    self.score = self.score.saturating_sub(1).max(-trip);
                }
                if self.score >= trip {
                    faults |= GROWTH;
                }
            }
        }
        if let (Some(b), Some(&had), Some(&last)) = (
            self.before_m.get_mut(side),
            self.have.get(side),
            self.last.get(side),
        ) {
            *b = if had { odd_abs(last) } else { 0 };
        }
        if let Some(l) = self.last.get_mut(side) {
            *l = self.peak;
        }
        if let Some(h) = self.have.get_mut(side) {
            *h = true;
        }
        self.peak = n;
        self.dir = s;
        faults
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::energy::{spring_energy, storage_energy};
    use proptest::prelude::*;

    #[test]
    fn odd_abs_and_energy_e8() {
        for n in [
            0,
            1,
            -1,
            2,
            -2,
            1000,
            -1001,
            i32::MAX,
            i32::MIN,
            i32::MIN + 1,
        ] {
            let want = (2 * i64::from(n) + 1).unsigned_abs();
            assert_eq!(u64::from(odd_abs(n)), want, "n = {n}");
            assert_eq!(energy_e8(n), want * want + 1);
            assert_eq!(
                u64::from(energy_e8_u32(n)),
                (want * want + 1).min(u64::from(u32::MAX))
            );
        }
    }

    /// The relation of the module header, checked against core's f64 storage function (35).
    /// Below |n| = 2^24 every f64 operation in `storage_energy` is exact ((n + ½)² needs
    /// < 50 bits), so the identity is checked with `==`; above, to f64 rounding (2^-50).
    fn check_tied_to_h_t(n: i32, mu: f64) -> Result<(), TestCaseError> {
        let xi = f64::from(n) + 0.5; // exact: 33 bits
        let h_t = storage_energy(mu, xi, 0.0);
        let e8 = energy_e8(n);
        if n.unsigned_abs() < 1 << 24 {
            prop_assert_eq!(e8 as f64, 8.0 * h_t, "n = {}", n);
            // The exact integer: (2n+1)² + 1 = 8·(½(n+½)² + ⅛) with every term an integer.
            prop_assert_eq!(8.0 * h_t - 1.0, (2.0 * f64::from(n) + 1.0).powi(2));
        } else {
            let rel = ((e8 as f64) - 8.0 * h_t).abs() / (8.0 * h_t);
            prop_assert!(rel <= f64::EPSILON, "n = {} rel = {}", n, rel);
        }
        // Between the cell's end values of 8·H_e (H_e is linear on the cell).
        let (a, b) = (
            8.0 * spring_energy(f64::from(n)),
            8.0 * spring_energy(f64::from(n) + 1.0),
        );
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        prop_assert!(
            e8 as f64 >= lo && e8 as f64 <= hi,
            "n = {}: {} ∉ [{}, {}]",
            n,
            e8,
            lo,
            hi
        );
        // The telemetry value is the same number, saturated.
        prop_assert_eq!(u64::from(energy_e8_u32(n)), e8.min(u64::from(u32::MAX)));
        Ok(())
    }

    #[test]
    fn energy_e8_is_8_h_t_at_the_edges() {
        for n in [
            i32::MIN,
            i32::MIN + 1,
            -(1 << 24),
            -1,
            0,
            1,
            (1 << 24) - 1,
            i32::MAX,
        ] {
            check_tied_to_h_t(n, 0.0).unwrap();
            check_tied_to_h_t(n, 100.0).unwrap();
        }
    }

    proptest! {
        /// energy_e8(n) = 8·H_T(n + ½, 0) (35) for every i32 count, any mass μ.
        #[test]
        fn energy_e8_is_8_h_t_at_the_count_midpoint(n in any::<i32>(), mu in 0.0f64..1e6) {
            check_tied_to_h_t(n, mu)?;
        }

        #[test]
        fn energy_e8_is_8_h_t_near_the_wall(n in -100_000i32..100_000) {
            check_tied_to_h_t(n, 1.0)?;
        }

        /// The limit check without a multiply is the energy comparison it stands for.
        #[test]
        fn limit_m_is_the_energy_comparison(n in any::<i32>(), near in -3000i32..3000, limit in any::<u64>(), small in 0u64..100_000) {
            for l in [limit, small, 0, 1, 2, u64::MAX, energy_e8(n), energy_e8(n) - 1] {
                for n in [n, near] {
                    prop_assert_eq!(odd_abs(n) > limit_m(l), energy_e8(n) > l, "n = {}, limit = {}", n, l);
                }
            }
        }
    }

    /// `limit_m` is ⌊√(x − 1)⌋ exactly (what the firmware's hand-written isqrt computed).
    #[test]
    fn limit_m_is_the_integer_square_root() {
        for x in [
            0u64,
            1,
            2,
            3,
            4,
            15,
            16,
            17,
            1 << 40,
            (1 << 62) + 12345,
            u64::MAX,
        ] {
            let r = u64::from(limit_m(x.saturating_add(1)));
            assert!(u128::from(r) * u128::from(r) <= u128::from(x));
            assert!(u128::from(r + 1) * u128::from(r + 1) > u128::from(x));
        }
    }

    #[test]
    fn energy_monitor_scores_growing_peaks() {
        let mut m = EnergyMonitor::default();
        let mut tripped = None;
        // Oscillation with growing amplitude 3, 4, 5, ... counts.
        let mut t = 0;
        'outer: for a in 3i32..20 {
            for n in (-a..=a).chain((-a..a).rev()) {
                let (f, _) = m.update(n, 4, u32::MAX);
                t += 1;
                if f & GROWTH != 0 {
                    tripped = Some((a, t));
                    break 'outer;
                }
            }
        }
        let (a, _) = tripped.expect("tripped");
        assert!(a <= 6, "tripped at amplitude {a}");
        // The peak that tripped is on the growing envelope.
        let (peak_n, peak_e8) = m.last_peak().expect("a scored peak");
        assert!(peak_n.abs() >= 5, "{peak_n}");
        assert_eq!(peak_e8, energy_e8(peak_n));
        // A steady cycle never trips.
        let mut m = EnergyMonitor::default();
        for _ in 0..1000 {
            for n in [-1, 0, 1, 0] {
                assert_eq!(m.update(n, 4, u32::MAX).0, 0);
            }
        }
    }

    #[test]
    fn shrinking_peaks_never_trip_and_the_limit_is_per_tick() {
        let mut m = EnergyMonitor::default();
        for a in (3i32..40).rev() {
            for n in (-a..=a).chain((-a..a).rev()) {
                let (f, _) = m.update(n, 2, limit_m(energy_e8(39)));
                assert_eq!(f & GROWTH, 0);
                assert_eq!(f & LIMIT, 0, "e8({n}) within the limit of e8(39)");
            }
        }
        assert_eq!(m.score(), -2);
        assert_eq!(m.update(40, 2, limit_m(energy_e8(39))).0, LIMIT);
        assert_eq!(m.update(-41, 2, limit_m(energy_e8(39))).0 & LIMIT, LIMIT);
    }

    /// Drives the monitor along the counts of a triangle oscillation between `lo` and `hi`
    /// (one count per tick), feeding its turning points to the buzz detector as the servo does;
    /// returns the tick of the first BUZZ, if any.
    fn buzz_tick(swings: &[(i32, i32)], window_ticks: u32) -> Option<u32> {
        let mut m = EnergyMonitor::default();
        let mut t = 0u32;
        let mut n = 0;
        for &(lo, hi) in swings {
            for target in [hi, lo] {
                while n != target {
                    n += (target - n).signum();
                    t += 1;
                    let (_, turn) = m.update(n, 64, u32::MAX);
                    if turn && m.buzz_turn(t, window_ticks) == BUZZ {
                        return Some(t);
                    }
                }
            }
        }
        None
    }

    #[test]
    fn buzz_trips_on_a_persistent_oscillation_only() {
        let w = buzz_window_ticks(1000);
        assert_eq!(w, 32 * 1000 / 30);
        // ±5 counts at one count per tick: 20 ticks per cycle (50 Hz), constant: trips after
        // BUZZ_HALF_CYCLES turning points.
        let steady = [(-5, 5); 40];
        let t = buzz_tick(&steady, w).expect("a steady ±5-count oscillation is buzz");
        assert!(t <= 20 * 20, "tripped at tick {t}");
        // Decaying by one count every 8 cycles: no trip.
        let decaying: std::vec::Vec<(i32, i32)> =
            (0..40).map(|i| (-12 + i / 8, 12 - i / 8)).collect();
        assert_eq!(buzz_tick(&decaying, w), None);
        // Toggling between two neighbouring counts (region B): no trip.
        assert_eq!(buzz_tick(&[(-1, 0); 200], w), None);
        // Too slow to be a buzz (±300 counts at one count per tick: 0.8 Hz): no trip.
        assert_eq!(buzz_tick(&[(-300, 300); 40], w), None);
        // Swings of two counts are enough.
        assert!(buzz_tick(&[(-1, 1); 40], w).is_some());
        // Converging onto a limit cycle: ±40 losing a count every 20 cycles (1.6 counts of
        // swing per window of 16 cycles, under 80/32 = 2) is persistent: trips in the first
        // window. Comparing envelopes without the 1/32 tolerance never tripped on it.
        let converging: std::vec::Vec<(i32, i32)> =
            (0..40).map(|i| (-40 + i / 20, 40 - i / 20)).collect();
        let t = buzz_tick(&converging, u32::MAX).expect("converging onto a limit cycle");
        assert!(t <= 34 * 80, "tripped at tick {t}: not in the first window");
        // Losing a count every 4 cycles (8 counts of swing per window) is a decay: no trip.
        // Nor is the beat of a firm hand on a 51 Hz cable below the stable stiffness (the
        // swings of a release of `cable-50hz-firm` at 2014 N/m from 66 counts, simulated):
        // its envelope hovers near 46 counts, losing 2 per window, then friction ends it.
        let beat = [
            31u32, 73, 31, 56, 53, 35, 67, 34, 57, 50, 38, 63, 36, 55, 48, 41, 59, 38, 54, 47, 44,
            56, 40, 55, 47, 45, 54, 42, 54, 46, 46, 53, 43, 52, 46, 47, 51, 44, 52, 46, 47, 50, 45,
            51, 46, 48, 49, 45, 50, 46, 48, 49, 46, 49, 45, 47, 47, 45, 48, 45, 47, 47, 46, 48, 45,
            46, 46, 45, 46, 44, 46, 46, 45, 46, 44, 45, 45, 44, 45, 44, 45, 45, 44, 44, 43, 44, 43,
            43, 44, 43, 43, 42, 42, 43, 42, 42, 39, 34, 31, 27, 25, 21, 18, 16, 13, 11, 8, 6, 3,
        ];
        let mut b = BuzzDetector::default();
        let (mut t, mut peak, mut fire) = (0u32, 0i32, 0u32);
        fire |= b.turn(t, peak, u32::MAX);
        for (i, &s) in beat.iter().enumerate() {
            t += 4;
            peak += if i % 2 == 0 { s as i32 } else { -(s as i32) };
            fire |= b.turn(t, peak, u32::MAX);
        }
        assert_eq!(fire, 0, "the cable's decaying beat");
        let decaying: std::vec::Vec<(i32, i32)> =
            (0..40).map(|i| (-40 + i / 4, 40 - i / 4)).collect();
        assert_eq!(buzz_tick(&decaying, u32::MAX), None);
    }

    #[test]
    fn a_decaying_beat_of_two_modes_does_not_trip_the_buzz_detector() {
        // The swings of a release on a plant with a hand behind a compliant transmission
        // (a two-mode decay, simulated: motor 0.039 kg, link 0.070 kg at 16 212 N/m, hand
        // 0.25 kg, K = 5618 N/m, T = 0.5 ms, from 88 counts): swings rise and fall with the
        // beat while the envelope shrinks. Its 32nd swing (34) exceeds its first (21), which
        // tripped the single-swing comparison; the envelopes are 69 and 41.
        let swings = [
            21u32, 69, 14, 65, 23, 41, 45, 20, 61, 15, 57, 24, 35, 41, 18, 54, 15, 48, 23, 31, 39,
            17, 47, 15, 41, 21, 26, 34, 15, 41, 13, 34, 19, 21, 30, 13, 34, 11, 28, 17,
        ];
        let mut b = BuzzDetector::default();
        let (mut t, mut peak, mut fire) = (0u32, 0i32, 0u32);
        fire |= b.turn(t, peak, u32::MAX);
        for (i, &s) in swings.iter().enumerate() {
            t += 7;
            peak = if i % 2 == 0 {
                peak + s as i32
            } else {
                peak - s as i32
            };
            fire |= b.turn(t, peak, u32::MAX);
        }
        assert_eq!(fire, 0);
        // The same beat without decay (its first 8 swings over and over) is a buzz.
        let mut b = BuzzDetector::default();
        let (mut peak, mut fire) = (0i32, 0u32);
        fire |= b.turn(t, peak, u32::MAX);
        for i in 0..40 {
            t += 7;
            let s = swings[i % 8] as i32;
            peak = if i % 2 == 0 { peak + s } else { peak - s };
            fire |= b.turn(t, peak, u32::MAX);
        }
        assert_eq!(fire, BUZZ);
    }

    #[test]
    fn the_buzz_detector_restarts_after_a_small_swing() {
        let mut b = BuzzDetector::default();
        let mut t = 0;
        let mut fire = 0;
        for i in 0..200 {
            t += 10;
            // Every 20th turning point is a sub-count wiggle: the window never completes.
            let peak = if i % 20 == 19 {
                4
            } else if i % 2 == 0 {
                5
            } else {
                -5
            };
            fire |= b.turn(t, peak, u32::MAX);
        }
        assert_eq!(fire, 0);
        for _ in 0..BUZZ_HALF_CYCLES + 1 {
            t += 10;
            fire |= b.turn(t, if t % 20 == 0 { 5 } else { -5 }, u32::MAX);
        }
        assert_eq!(fire, BUZZ);
    }

    /// The update as first written (the tests in order), for the equivalence test below.
    fn update_as_written(m: &mut EnergyMonitor, n: i32, trip: i32, limit_m: u32) -> (u32, bool) {
        let mut faults = 0;
        if odd_abs(n) > limit_m {
            faults |= LIMIT;
        }
        if !m.primed {
            m.primed = true;
            m.prev_n = n;
            m.peak = n;
            return (faults, false);
        }
        let dn = n.saturating_sub(m.prev_n);
        m.prev_n = n;
        if dn == 0 {
            return (faults, false);
        }
        let s: i8 = if dn > 0 { 1 } else { -1 };
        if m.dir == 0 || s == m.dir {
            m.peak = n;
            m.dir = s;
            return (faults, false);
        }
        (faults | m.turn(n, s, trip), true)
    }

    proptest! {
        /// The update (the common tick's one test first, the rest out of line) is the update
        /// as first written: same results, same state, through resets and saturation.
        #[test]
        fn update_is_the_update_as_written(
            start in any::<i32>(),
            steps in proptest::collection::vec((-3i32..=3, 0u8..40), 1..400),
            trip in 1i32..5,
            limit_m in prop_oneof![Just(u32::MAX), 0u32..200],
        ) {
            let (mut a, mut b) = (EnergyMonitor::default(), EnergyMonitor::default());
            let mut n = start;
            for (dn, op) in steps {
                match op {
                    0 => {
                        a.reset();
                        b.reset();
                    }
                    1 => n = i32::MAX,
                    2 => n = i32::MIN,
                    _ => n = n.saturating_add(dn),
                }
                let got = a.update(n, trip, limit_m);
                let want = update_as_written(&mut b, n, trip, limit_m);
                prop_assert_eq!(got, want, "n = {}", n);
                prop_assert_eq!(a, b);
            }
        }
    }
}
