//! Tune settings and the constants of the procedure (a leaf module: it imports no other module
//! of the crate but the error type and the verdict's criterion).
//!
//! Units: velocities m/s (rad/s for rotary devices), damping N·s/m (N·m·s/rad), seconds, ticks.
//! Invariant: [`Settings::validate`] is the one place the settings are checked; the CLI and the
//! live view call it before touching a device.

use stiffwall_sim::scene::field_bounds::{DAMPING, VELOCITY};

pub use super::error::SettingsError;
pub use super::verdict::Criterion;

/// Default maximum velocity, in encoder ticks per servo period (ξ̇ of Table I; independent of K).
pub const DEFAULT_XIDOT: f64 = 5.0;

/// Factor applied to K when a test of the verification set fails.
pub const CONFIRM_BACKOFF: f64 = 0.95;

/// Factor applied to the margin when the model does not fit the device.
pub const MISMATCH_MARGIN: f64 = 0.85;
/// Factor applied to the margin instead of [`MISMATCH_MARGIN`] when the only mismatch is the
/// friction (breakaway above sliding: static friction or a dead band) or the verified K below
/// the prediction, the identified dynamics fitting (`crate::model_check::dynamics_fit`) and every
/// impact launched: static friction dissipates, and the release tests run at the energy asked
/// for (re-aimed where the hold stuck off target), so the verified K is the device's own.
pub const FRICTION_MISMATCH_MARGIN: f64 = 0.9;

/// Duration of each breakaway ramp, s.
pub const RAMP_SECONDS: f64 = 0.3;

/// Tune settings.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Expected maximum velocity, m/s (rad/s); None = [`DEFAULT_XIDOT`] ticks per period.
    pub max_velocity: Option<f64>,
    /// Fraction of the largest resting K that is set, in (0, 1].
    pub margin: f64,
    /// Ticks per release test; None = 60 natural periods (at least 1500, at most 30000).
    pub release_ticks: Option<u32>,
    /// Duration of the identification chirp, s.
    pub excite_seconds: f64,
    /// Relative tolerance of the K bisection.
    pub rel_tol: f64,
    /// Virtual damping B of the wall: searched (default) or fixed.
    pub damping: Damping,
    /// Find and report the wall but leave the device's config as it was (default false: the
    /// wall found is set and saved).
    pub dry_run: bool,
    /// What a passing test must do: come to rest (default), or also chatter within one count
    /// ([`Criterion::AcceptChatter`], reported).
    pub criterion: Criterion,
    /// The law of the virtual damper tried and set. None (default): a dead band of one count
    /// ([`DamperLaw::default`](stiffwall_proto::DamperLaw), stiffest over `sim/plants/` by
    /// docs/DAMPER-LAWS.md), and the plain difference where that buys no stiffness.
    pub damper: Option<stiffwall_proto::DamperLaw>,
    /// The device's travel [min, max], m (rad), as positions of the encoder's frame (count ×
    /// Δ): every experiment stays inside it with a margin. None (default): the device config's
    /// travel window when it has one, else a default window around the start
    /// (`crate::travel`).
    pub travel: Option<[f64; 2]>,
}

/// How `tune` chooses the virtual damping B.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Damping {
    /// Search the (K, B) frontier (`DAMPING_BETAS`) for the stiffest verified pair.
    Search,
    /// Fixed B, N·s/m (N·m·s/rad), ≥ 0; 0 is the spring-only tune.
    Fixed(f64),
}

/// Damping levels of the predicted frontier, as β = B/(K₀·T) with K₀ the spring-only largest
/// settling K (the model's, where the two agree: `frontier::damping_scale_k`): the brute-force frontiers of the repository's plants rise up to β ≈ 2–6
/// (3–8 × K*(0)) where the damper itself stays stable, and fall where it does not.
pub const DAMPING_BETAS: [f64; 5] = [1.0, 2.0, 3.0, 4.0, 6.0];

/// Damping levels searched on the device, in the order of their predicted K: the second is
/// searched only when the first held no K above the spring-only one.
pub const FRONTIER_TRIES: usize = 2;

/// Relative gain in verified K that a damping must bring over the spring alone to be kept:
/// less is within the bisection's resolution.
pub const DAMPING_MIN_GAIN: f64 = 0.1;

/// How near the spring-only search's K must be to the model's for the damping levels to be
/// scaled by the model's (`frontier::damping_scale_k`), as a share of the model's.
pub const DAMPING_SCALE_AGREEMENT: f64 = 0.25;

/// The damped search starts at this fraction of the predicted K (the prediction is the exact
/// linear boundary with Coulomb friction as describing-function damping, scaled by what the
/// spring-only search measured against its own prediction).
pub const FRONTIER_START: f64 = 0.85;

/// Bracketing factor of the damped search (finer than the spring-only one: it starts near the
/// predicted limit).
pub const FRONTIER_STEP: f64 = 1.2;

/// Largest fraction of the damped search's largest resting K that is set (the smaller of it
/// and the margin in use): near its edge a damped wall's stable K are speckled with persistent
/// limit cycles that only some starts reach (maxon-re35-amp-3khz at B = 4.4e-3 N·m·s/rad: a
/// release from 4 counts buzzes at 0.96 K*(B), one from 6 at 0.90, none below 0.89), which a
/// verification set of a few tests cannot rule out.
pub const DAMPED_MARGIN: f64 = 0.8;

/// Relative tolerance of the bisections at B > 0 (coarser than the spring-only one: the
/// chosen pair is confirmed with the whole set). The K set is a margin times the largest
/// settling K found, so the search's own shortfall (up to this tolerance below the first
/// failure) comes off the wall too: 2.5 % costs about one more step than 5 %.
pub const FRONTIER_REL_TOL: f64 = 0.025;

/// Natural periods per test (at least [`TEST_TICKS`].0, at most .1 ticks).
pub const TEST_NATURAL_PERIODS: f64 = 60.0;
/// Fewest / most ticks per test when `release_ticks` is not given.
pub const TEST_TICKS: (f64, f64) = (1500.0, 30_000.0);
/// Fewest ticks per test of a damped wall (when `release_ticks` is not given): its damper ends
/// a transient within a few natural periods, so 60 natural periods suffice down to this floor;
/// a persistent oscillation is judged (and fails) sooner.
pub const DAMPED_TEST_MIN_TICKS: f64 = 400.0;
/// Confirmation attempts, each [`CONFIRM_BACKOFF`] below the last.
pub const CONFIRM_TRIES: usize = 8;

impl Default for Settings {
    fn default() -> Self {
        Self {
            max_velocity: None,
            margin: 0.9,
            release_ticks: None,
            excite_seconds: 3.0,
            rel_tol: 0.02,
            damping: Damping::Search,
            dry_run: false,
            criterion: Criterion::Rest,
            damper: None,
            travel: None,
        }
    }
}

/// `--max-velocity` out of its plausible range ([`VELOCITY`]'s one message, and > 0: tune needs
/// a velocity to test at).
pub(crate) fn velocity_error(v: f64) -> SettingsError {
    SettingsError {
        field: "max_velocity",
        range: format!("{}, and > 0", VELOCITY.allowed),
        got: short(v),
    }
}

/// A refused number as a person reads it: `1e300`, not 301 digits.
fn short(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && a.is_finite() && !(1e-4..1e6).contains(&a) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}

impl Settings {
    /// Checks every field, naming it (its Rust name, see [`SettingsError`]) and its allowed
    /// range.
    ///
    /// # Errors
    /// The first field out of range.
    pub fn validate(&self) -> Result<(), SettingsError> {
        let bad = |field: &'static str, range: &str, got: String| {
            Err(SettingsError {
                field,
                range: range.to_string(),
                got,
            })
        };
        if !(self.margin.is_finite() && self.margin > 0.0 && self.margin <= 1.0) {
            return bad("margin", "in (0, 1]", self.margin.to_string());
        }
        if let Some(v) = self.max_velocity {
            // The device's kind is not known here: the wider (rotary) bound, and the linear
            // one once the device is connected (`tune`), both with the field's one message.
            let (_, hi) = VELOCITY.range(true);
            if !(v.is_finite() && v > 0.0 && v <= hi) {
                return Err(velocity_error(v));
            }
        }
        if let Some([lo, hi]) = self.travel {
            if !(lo.is_finite() && hi.is_finite() && lo < hi && lo.abs() <= 1e3 && hi.abs() <= 1e3)
            {
                return bad(
                    "travel",
                    "MIN:MAX finite within [-1000, 1000] m (rad) with MIN < MAX",
                    format!("{lo}:{hi}"),
                );
            }
        }
        if let Damping::Fixed(b) = self.damping {
            if DAMPING.check("damping", b, false).is_err() {
                return bad("damping", DAMPING.allowed, short(b));
            }
        }
        if !(self.excite_seconds.is_finite() && (0.5..=1000.0).contains(&self.excite_seconds)) {
            return bad(
                "excite_seconds",
                "within [0.5, 1000]",
                self.excite_seconds.to_string(),
            );
        }
        if let Some(t) = self.release_ticks {
            if !(100..=10_000_000).contains(&t) {
                return bad("release_ticks", "within [100, 10000000]", t.to_string());
            }
        }
        if !(self.rel_tol.is_finite() && self.rel_tol > 0.0 && self.rel_tol < 1.0) {
            return bad("rel_tol", "in (0, 1)", self.rel_tol.to_string());
        }
        if let Some(law @ stiffwall_proto::DamperLaw::DeadBand { counts }) = self.damper {
            if !(1..=stiffwall_proto::MAX_DEADBAND_COUNTS).contains(&counts) {
                return bad(
                    "damper",
                    &format!(
                        "`difference` or `dead-band-N` with N in 1..={}",
                        stiffwall_proto::MAX_DEADBAND_COUNTS
                    ),
                    law.to_string(),
                );
            }
        }
        Ok(())
    }
}

/// Fails with [`stiffwall_client::ClientError::Cancelled`] once the client's cancel token
/// (the caller's, for a tune) was cancelled.
pub(crate) fn check_cancel(c: &stiffwall_client::Client) -> super::error::Result<()> {
    if c.cancel_token().is_cancelled() {
        return Err(stiffwall_client::ClientError::Cancelled.into());
    }
    Ok(())
}
