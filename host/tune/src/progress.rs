//! What [`crate::procedure::tune`] reports while it runs: one typed event per step, in order
//! (a leaf module: it imports no other module of the crate).
//!
//! Units: stiffness K in N/m (N·m/rad), damping B in N·s/m (N·m·s/rad), mass kg (kg·m²),
//! viscous N·s/m, Coulomb N (N·m), deflections and starts in effective encoder ticks, ticks
//! servo ticks, amplitudes DAC codes. [`std::fmt::Display`] gives the one-line message the CLI
//! prints (`tune: …`); the JSON form (`serde`) is tagged by `"event"`.

use std::fmt;

/// One step of the tune procedure, as it starts.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "event", rename_all = "snake_case")]
#[non_exhaustive]
pub enum Progress {
    /// Identification: an open-loop chirp with the wall off.
    Chirp {
        /// Chirp amplitude, DAC codes.
        amplitude_codes: i32,
        /// Highest chirp frequency, Hz (the lowest is 0.5 Hz).
        f1_hz: f32,
        /// Chirp length, servo ticks.
        ticks: u32,
    },
    /// A slow force ramp from rest (breakaway against the model's friction).
    BreakawayRamp {
        /// Ramp end, DAC codes (signed: the direction).
        peak_codes: i32,
    },
    /// The model identified and the limits predicted from it.
    Identified {
        /// Mass m.
        mass: f64,
        /// Viscous damping b.
        viscous: f64,
        /// Coulomb friction c.
        coulomb: f64,
        /// The guaranteed K limit.
        k_guaranteed: f64,
        /// The expected K limit.
        k_expected: f64,
    },
    /// A search step: a full-energy release test at K (and B).
    ReleaseStep {
        /// Stiffness tried.
        k: f64,
        /// Damping of the step.
        b: f64,
        /// Release deflection, ticks.
        deflection_ticks: i32,
    },
    /// A search step's impact test.
    ImpactStep {
        /// Stiffness tried.
        k: f64,
        /// The test, in words (`impact at … from …`).
        test: String,
        /// Why the step runs an impact (`force saturates`, `damped wall`).
        reason: String,
    },
    /// The whole verification set at K (and B).
    Verifying {
        /// Stiffness verified.
        k: f64,
        /// Damping verified.
        b: f64,
        /// Largest release deflection of the set, ticks.
        deflection_ticks: i32,
    },
    /// A test of the verification set failed at K; the next K is [`Self::VerifyFailed::backoff`]
    /// lower.
    VerifyFailed {
        /// Stiffness that failed.
        k: f64,
        /// The test, in words.
        test: String,
        /// Its verdict, in words.
        verdict: String,
        /// Factor applied to K for the next try.
        backoff: f64,
    },
    /// The search's largest resting K run again from a new start ([`crate::repeat`]).
    Repeating {
        /// Stiffness re-run.
        k: f64,
        /// Damping, N·s/m (N·m·s/rad).
        b: f64,
    },
    /// The damped search at one damping level of the predicted frontier.
    DampingSearch {
        /// Damping searched.
        b: f64,
        /// Its predicted largest K.
        k_predicted: f64,
        /// Where the search starts.
        k_start: f64,
    },
    /// No K passed the verification set with the damper: the spring-only wall is set.
    DamperDropped {
        /// The damping that failed.
        b: f64,
    },
    /// The small-swing screen lowered the damped wall (`small_swing`): on the identified model
    /// the wall asked for keeps a swing of a few counts from a small, slow start.
    SmallSwing(crate::small_swing::Screened),
    /// Impacts at v failed at every K tried: the set is verified without them.
    ImpactsCapped {
        /// First K tried.
        k_from: f64,
        /// Last K tried.
        k_to: f64,
    },
    /// A finding: the model does not fit the device in some respect (also in the outcome).
    Finding {
        /// The finding, in words.
        text: String,
    },
    /// The travel the experiments keep to, and what it changed (issue 46).
    Travel {
        /// In words: the travel, its source, the window, a lowered velocity.
        text: String,
    },
    /// Bringing the device back to where it started, to raw count `target`.
    Returning {
        /// The start, raw counts.
        target: i64,
    },
    /// The final check of the device (also in the outcome).
    Left(crate::left::DeviceLeft),
}

impl fmt::Display for Progress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Chirp {
                amplitude_codes,
                f1_hz,
                ticks,
            } => write!(
                f,
                "identifying: chirp of {amplitude_codes} codes, 0.5–{f1_hz} Hz, {ticks} ticks"
            ),
            Self::BreakawayRamp { peak_codes } => {
                write!(f, "breakaway ramp to {peak_codes} codes")
            }
            Self::Identified {
                mass,
                viscous,
                coulomb,
                k_guaranteed,
                k_expected,
            } => write!(
                f,
                "identified m={mass:.3e} b={viscous:.3e} c={coulomb:.3e}; K guaranteed \
                 {k_guaranteed:.4} expected {k_expected:.4}"
            ),
            Self::Finding { text } => write!(f, "model mismatch: {text}"),
            Self::Travel { text } => write!(f, "workspace: {text}"),
            Self::Returning { target } => {
                write!(
                    f,
                    "returning the device to count {target}, where it started"
                )
            }
            Self::Left(left) => write!(f, "{left}"),
            search => search.fmt_search(f),
        }
    }
}

impl Progress {
    /// The search and verification events (steps 4a–4b).
    fn fmt_search(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::ReleaseStep {
                k,
                b,
                deflection_ticks,
            } => write!(
                f,
                "release test K={k:.4} B={b:.4} from {deflection_ticks} ticks"
            ),
            Self::ImpactStep { k, test, reason } => write!(f, "{test} test K={k:.4} ({reason})"),
            Self::Verifying {
                k,
                b,
                deflection_ticks,
            } => write!(
                f,
                "verifying K={k:.4} B={b:.4}: releases from ±{deflection_ticks} ticks and \
                     below, impacts"
            ),
            Self::VerifyFailed {
                k,
                test,
                verdict,
                backoff,
            } => write!(
                f,
                "verification at K={k:.4}: {test} {verdict}; backing off ×{backoff}"
            ),
            Self::Repeating { k, b } => write!(
                f,
                "repeating K={k:.4} B={b:.4e} from a new start (it counts only if it rests again)"
            ),
            Self::DampingSearch {
                b,
                k_predicted,
                k_start,
            } => write!(
                f,
                "damping B = {b:.4e}: predicted K {k_predicted:.4}, searching from {k_start:.4}"
            ),
            Self::DamperDropped { b } => write!(
                f,
                "no K above the spring-only wall passed the small-swing screen and the \
                 verification set at B = {b:.4e}; setting the spring-only wall"
            ),
            Self::SmallSwing(s) => match s.swing {
                Some((k, start)) => write!(
                    f,
                    "small-swing screen: on the identified model K = {k:.4} keeps a swing from \
                     {:+.3} counts at {:+.1} counts/tick (the damper's dead band leaves it \
                     undamped); verifying K = {:.4} instead of {:.4}",
                    start.x_counts, start.v_counts_per_tick, s.k, s.k_asked
                ),
                None => write!(
                    f,
                    "small-swing screen: K = {:.4} rests from every small start",
                    s.k
                ),
            },
            Self::ImpactsCapped { k_from, k_to } => write!(
                f,
                "impacts at v failed at every K from {k_from:.4} down to {k_to:.4}; verifying \
                     without them (releases at full energy from both sides, slower impacts)"
            ),
            _ => Ok(()),
        }
    }
}

/// Passes events to the caller's callback from code that holds only a shared reference.
pub(crate) struct Reporter<'a>(std::cell::RefCell<&'a mut dyn FnMut(Progress)>);

impl<'a> Reporter<'a> {
    pub(crate) fn new(f: &'a mut dyn FnMut(Progress)) -> Self {
        Self(std::cell::RefCell::new(f))
    }

    /// Reports one event (a callback that reports from inside itself is not called again).
    pub(crate) fn report(&self, event: Progress) {
        if let Ok(mut f) = self.0.try_borrow_mut() {
            f(event);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cli_lines_and_the_json_tag() {
        let e = Progress::ReleaseStep {
            k: 1.5,
            b: 0.0,
            deflection_ticks: 12,
        };
        assert_eq!(
            e.to_string(),
            "release test K=1.5000 B=0.0000 from 12 ticks"
        );
        assert_eq!(
            serde_json::to_string(&e).unwrap(),
            r#"{"event":"release_step","k":1.5,"b":0.0,"deflection_ticks":12}"#
        );
        assert_eq!(
            Progress::Finding { text: "x".into() }.to_string(),
            "model mismatch: x"
        );
    }
}
