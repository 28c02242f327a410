//! What a tune found: predictions, the identified device, the wall set and the frontier tried
//! (plain data, serialised as `hostctl tune --json`'s `tune` object).
//!
//! Units: SI (N/m, N·s/m, kg, N; rotary devices N·m/rad, N·m·s/rad, kg·m², N·m).

use super::model_check::Evidence;
use super::release::Verdict;
use super::search::Found;
use super::verdict::Criterion;
use super::verify::TestResult;
use stiffwall_core::params::PhysicalParams;

/// Predicted stiffness limits, N/m (N·m/rad).
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct Predicted {
    /// Region A (passive) limit, (17)–(18).
    pub passive: f64,
    /// Worst-case guaranteed limit at v: (12), or (19) with delay.
    pub guaranteed: f64,
    /// Expected limit: exact sampled linear boundary with Coulomb as DF damping at v.
    pub expected: f64,
    /// The paper's describing-function approximation (74) at v (ZOH as a ½-period delay).
    pub expected_paper_74: f64,
}

/// Everything `tune` found.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Outcome {
    /// Identified parameters.
    pub identified: IdentifiedReport,
    /// Device model used for predictions (K = the set value).
    pub params: PhysicalParams,
    /// Maximum velocity used, m/s (rad/s).
    pub max_velocity: f64,
    /// Same, ticks per period.
    pub xidot: f64,
    /// Predictions.
    pub predicted: Predicted,
    /// The release-test search.
    pub search: Found,
    /// The stiffness set.
    pub k_set: f64,
    /// The virtual damping set, N·s/m (N·m·s/rad).
    pub b_set: f64,
    /// The spring-only stiffness of the same run: verified when it is the one set, otherwise
    /// the one it would set (largest resting K at B = 0 × the margin).
    pub k_spring_only: f64,
    /// The B values tried with their largest verified (settling) K (None: none at or above
    /// the best K so far), B = 0 first.
    pub frontier: Vec<FrontierPoint>,
    /// Verdicts of the verification set at `k_set` (in the order of `verification`).
    pub confirmation: Vec<Verdict>,
    /// The verification set at `k_set`, test by test.
    pub verification: Vec<TestResult>,
    /// Every test of the verification set at the set wall came to rest (or left a one-sided
    /// wall): the wall is quiet. False only where no wall rests ([`Outcome::no_rest`]) or
    /// under [`Criterion::AcceptChatter`].
    pub rests: bool,
    /// What a passing test had to do.
    pub criterion: Criterion,
    /// The virtual damper's law (`difference`, `dead-band-N`; the firmware's `DamperLaw`),
    /// set with `b_set` (the law is set even when B is 0, where it does nothing).
    pub damper: String,
    /// The quiet ceiling 2·max(c, F_s)/Δ of the identified device, N/m (N·m/rad): above it no
    /// count can hold the wall's force KΔ/2 and every wall chatters (0: no friction).
    pub quiet_ceiling: f64,
    /// Why no wall comes to rest on this device (None when the set wall rests or chatter was
    /// accepted): the wall set is then the one with the least chatter.
    pub no_rest: Option<String>,
    /// Where the identified model does not describe the device (plain language; empty when
    /// it does).
    pub model_mismatch: Vec<String>,
    /// What the model checks measured.
    pub model_evidence: Evidence,
    /// Margin applied to the set wall's largest resting K (the requested one, times
    /// [`crate::settings::MISMATCH_MARGIN`] on a mismatch; at most `crate::settings::DAMPED_MARGIN` with a damper).
    pub margin_used: f64,
    /// The small-swing screen (`small_swing`), when it lowered the damped wall below the
    /// margin's K: on the identified model that K keeps a swing of a few counts from a small,
    /// slow start, which the damper's dead band leaves undamped.
    #[serde(default)]
    pub small_swing: Option<crate::small_swing::Screened>,
    /// How repeatable the set wall's frontier K was.
    #[serde(default)]
    pub repeatability: Option<Repeatability>,
    /// Whether the config was saved.
    pub saved: bool,
    /// The travel the experiments kept to (issue 46).
    #[serde(default)]
    pub workspace: Option<crate::travel::Workspace>,
    /// The final check: where the device was left, at rest, without a fault (issue 46).
    #[serde(default)]
    pub device_left: Option<crate::left::DeviceLeft>,
}

/// One point of the verified frontier.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrontierPoint {
    /// Virtual damping B, N·s/m (N·m·s/rad).
    pub b: f64,
    /// Largest resting K found at B, N/m (N·m/rad).
    pub k_verified: Option<f64>,
    /// The damper's law at this B (`difference`, `dead-band-N`).
    #[serde(serialize_with = "law_name", deserialize_with = "law_from_name")]
    pub damper: stiffwall_proto::DamperLaw,
    /// The search's K at B run again from a new start ([`crate::repeat`]); None where no K
    /// was found at B.
    #[serde(default)]
    pub repeat: Option<crate::repeat::Repeat>,
}

/// How repeatable the set wall's frontier K was (issue 42): its repeat's spread and the margin
/// that spread leaves.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Repeatability {
    /// Damping of the set wall's frontier point, N·s/m (N·m·s/rad).
    pub b: f64,
    /// The search's largest resting K there (one run), N/m (N·m/rad).
    pub k_searched: f64,
    /// The largest K whose every run rested (None: no K within the repeat's steps).
    pub k_repeated: Option<f64>,
    /// The smallest K above it that failed (None: the search stopped at its cap resting).
    pub k_failed: Option<f64>,
    /// The frontier's bracket by this run's tests, k_failed / k_repeated − 1
    /// ([`crate::repeat::Repeat::spread`]).
    pub spread: f64,
    /// The margin applied to k_repeated.
    pub margin: f64,
    /// The spread that margin leaves room for ([`crate::repeat::spread_room`]): a larger
    /// measured spread lowers the margin to 1/(1 + 2·spread).
    pub spread_room: f64,
    /// The set K is the small-swing screen's (below the first K at which the identified model
    /// keeps a swing, [`crate::small_swing`]), below margin × the frontier's K: the frontier's
    /// spread does not move it, the identified model does.
    #[serde(default)]
    pub set_by_screen: bool,
}

fn law_name<S: serde::Serializer>(
    law: &stiffwall_proto::DamperLaw,
    s: S,
) -> Result<S::Ok, S::Error> {
    s.collect_str(law)
}

fn law_from_name<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<stiffwall_proto::DamperLaw, D::Error> {
    let name = <String as serde::Deserialize>::deserialize(d)?;
    name.parse().map_err(serde::de::Error::custom)
}

/// Identified parameters as reported.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct IdentifiedReport {
    /// m and its standard error.
    pub mass: [f64; 2],
    /// b and its standard error.
    pub viscous: [f64; 2],
    /// Upper bound on b (estimate + 2 s.e.), meaningful when b is only bounded.
    pub viscous_upper_bound: f64,
    /// Whether b is indistinguishable from 0.
    pub viscous_only_bounded: bool,
    /// c and its standard error.
    pub coulomb: [f64; 2],
    /// Integrated equations used.
    pub equations: usize,
    /// Chirp amplitude used, output codes.
    pub excite_amplitude_codes: i32,
    /// Stiffness of a spring-like force beside the rigid model (a hand, a cable) and its
    /// standard error, N/m (N·m/rad); None when none was resolved.
    pub spring: Option<[f64; 2]>,
}
