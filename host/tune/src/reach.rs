//! How far the experiments of tune reach (issue 46): the centring spring's deflection and the
//! release and impact tests' reach, so that [`crate::workspace`] can keep them inside the
//! travel.
//!
//! Units: counts of the resolution given; forces N (N·m); stiffness N/m (N·m/rad); speeds m/s
//! (rad/s) unless named `_ticks` (counts per tick). Pure functions, no I/O.

/// Static deflection of the centring spring under the chirp's or a ramp's peak force, as a
/// share of the room each side (the rest is for the resonance and the friction's drift).
pub const CENTRING_SHARE: f64 = 0.3;

/// Static deflection of the first probe's centring spring, share of the room: the mass is not
/// known yet, so the spring's resonance with the device may lie in the chirp's band undamped;
/// a third of [`CENTRING_SHARE`] leaves room for a ringing of three times the drive (its
/// damper K·T only keeps it from growing).
pub const PROBE_CENTRING_SHARE: f64 = 0.1;

/// Damping ratio of the centring spring with the probe's mass on the full chirp and the ramps
/// (B = 2ζ√(K·m)): a resonance in the chirp's band does not ring the device out of its room.
pub const CENTRING_DAMPING_RATIO: f64 = 0.7;

/// Stiffness of a centring spring that deflects by [`CENTRING_SHARE`] of `room_counts` under
/// `force_n`, N/m (N·m/rad), with Δ = `resolution`.
#[must_use]
pub fn centring_stiffness(force_n: f64, room_counts: i64, resolution: f64) -> f64 {
    let reach = (room_counts as f64 * CENTRING_SHARE).max(1.0) * resolution;
    force_n.abs() / reach
}

/// How far from the wall a release or impact test at stiffness `k` and speed `v_ticks`
/// (counts per tick) reaches, counts: the impact's launch distance (the larger of 20 ticks and
/// one natural period of motion, plus two) or the release's deflection v·√(m/K)/Δ, whichever
/// is larger, times 1.5 for the overshoot of a wall that rings.
#[must_use]
pub fn test_reach_counts(v_ticks: f64, mass: f64, k: f64, period_s: f64) -> f64 {
    let natural_ticks = core::f64::consts::TAU * (mass / k).sqrt() / period_s;
    let launch = v_ticks.abs() * (natural_ticks.max(20.0) + 2.0);
    let deflection = v_ticks.abs() * natural_ticks / core::f64::consts::TAU;
    1.5 * launch.max(deflection)
}
