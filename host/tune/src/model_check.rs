//! Checks of the identified model against the device's own data: where the rigid mass with
//! viscous and Coulomb friction (eq. (1)) does not describe what was measured, `tune` reports a
//! plain-language finding (`tune.model_mismatch`) and verifies more cautiously.
//!
//! Checks (pure functions; the procedure supplies the records):
//! - **fit residual**: the RMS residual of the integrated equations relative to the RMS of the
//!   force integrals ([`super::ident::Identified::residual_rel`]) above [`RESIDUAL_LIMIT`];
//! - **breakaway vs sliding friction**: a slow force ramp from rest, wall off, in each
//!   direction; the force at which the device has moved [`BREAKAWAY_COUNTS`] counts is compared
//!   with the force at which the identified model, simulated on the same ramp, moves as far.
//!   A measured breakaway more than [`BREAKAWAY_EXCESS`] × c above the model's is static
//!   friction (stick–slip) the model does not have;
//! - **resonance**: the oscillation frequency of a release at stiffness K against the rigid
//!   model's √(K/m)/2π; a ratio outside [1/[`FREQUENCY_RATIO`], [`FREQUENCY_RATIO`]] means
//!   another mode (a compliant transmission, an amplifier lag) shapes the wall's response;
//! - **verified vs predicted**: the largest verified K below [`PREDICTION_RATIO`] × the
//!   expected limit means the model overestimates the device.
//!
//! Units: SI (N, kg, s) or rotary (N·m, kg·m², rad); counts are encoder counts.

use super::ident::Identified;

/// Relative fit residual above which the rigid model is reported as not fitting.
pub const RESIDUAL_LIMIT: f64 = 0.08;
/// Counts of motion that mark breakaway on a force ramp.
pub const BREAKAWAY_COUNTS: i64 = 2;
/// Breakaway force above the model's by more than this fraction of c is reported.
pub const BREAKAWAY_EXCESS: f64 = 0.15;
/// Largest accepted ratio between measured and predicted release frequency (and its inverse).
pub const FREQUENCY_RATIO: f64 = 1.3;
/// Verified K below this fraction of the expected limit is reported.
pub const PREDICTION_RATIO: f64 = 0.6;

/// The force at which a ramp moved the device [`BREAKAWAY_COUNTS`] counts from rest.
///
/// `counts[k]` is the count at sample k and `force[k]` the force held from sample k to k+1.
/// Returns the force (signed) of the sample before the one that first reached the distance,
/// or None when the device never moved that far.
#[must_use]
pub fn breakaway_force(counts: &[i64], force: &[f64]) -> Option<f64> {
    let start = *counts.first()?;
    counts
        .iter()
        .zip(force)
        .position(|(&n, _)| (n - start).abs() >= BREAKAWAY_COUNTS)
        .and_then(|k| k.checked_sub(1))
        .map(|k| force[k])
}

/// The identified model (Coulomb friction, no static friction) on a force sequence from rest
/// in the middle of a cell: the counts it would produce (semi-implicit Euler, 50 sub-steps per
/// period, sticking while |F| ≤ c). An identified spring k pulls back towards the start, where
/// it already pushes with `preload` (the spring force at the start position, which static
/// friction holds: clamped to ±c).
#[must_use]
pub fn model_counts(
    id: &Identified,
    force: &[f64],
    preload: f64,
    period_s: f64,
    resolution: f64,
) -> Vec<i64> {
    let (m, b, c) = (id.mass.max(1e-12), id.viscous.max(0.0), id.coulomb.max(0.0));
    let k_spring = id.spring.map_or(0.0, |s| s.stiffness.max(0.0));
    let x0 = 0.5 * resolution;
    let (mut x, mut v) = (x0, 0.0f64);
    let sub = 50;
    let dt = period_s / f64::from(sub);
    let mut out = Vec::with_capacity(force.len());
    for &f in force {
        out.push((x / resolution).floor() as i64);
        for _ in 0..sub {
            let f = f + preload.clamp(-c, c) - k_spring * (x - x0);
            if v == 0.0 && f.abs() <= c {
                continue;
            }
            let fr = if v == 0.0 {
                c * f.signum()
            } else {
                c * v.signum()
            };
            let vn = v + dt * (f - b * v - fr) / m;
            v = if v != 0.0 && vn.signum() != v.signum() {
                0.0
            } else {
                vn
            };
            x += dt * v;
        }
    }
    out
}

/// Dominant oscillation frequency of a release about the wall origin, Hz: from the mean
/// interval between sign changes of the offset n + ½ over the first `max_crossings` crossings.
/// None with fewer than three crossings.
#[must_use]
pub fn release_frequency_hz(counts: &[i64], period_s: f64, max_crossings: usize) -> Option<f64> {
    let mut crossings = Vec::new();
    let mut side = counts.first().map(|&n| n >= 0)?;
    for (k, &n) in counts.iter().enumerate() {
        let s = n >= 0;
        if s != side {
            crossings.push(k);
            side = s;
            if crossings.len() >= max_crossings {
                break;
            }
        }
    }
    if crossings.len() < 3 {
        return None;
    }
    let span = (crossings[crossings.len() - 1] - crossings[0]) as f64;
    let half_periods = (crossings.len() - 1) as f64;
    Some(half_periods / (2.0 * span * period_s))
}

/// What the checks measured, for the report.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Evidence {
    /// Relative fit residual of the identification.
    pub residual_rel: f64,
    /// Measured breakaway force in the + and − direction (None: did not move).
    pub breakaway_measured: [Option<f64>; 2],
    /// The identified model's breakaway on the same ramps.
    pub breakaway_model: [Option<f64>; 2],
    /// Release oscillation frequency measured at `release_k`, Hz.
    pub release_hz: Option<f64>,
    /// The rigid model's frequency at `release_k`, Hz.
    pub model_hz: Option<f64>,
    /// Stiffness of the release used for the frequency check.
    pub release_k: Option<f64>,
}

/// Plain-language findings where the model does not fit the evidence (empty when it does).
#[must_use]
pub fn findings(id: &Identified, e: &Evidence, units: (&str, &str)) -> Vec<String> {
    let (force_unit, k_unit) = units;
    let mut out = Vec::new();
    if let Some(sp) = id.spring {
        out.push(format!(
            "a position-dependent force acts on the device like a spring of {:.3e} {k_unit} \
             (a hand holding the handle, a cable or a balancing spring); without it the rigid \
             model left {:.0} % of the excitation force unexplained. m = {:.3e} includes what \
             moves with the handle, and the wall's stiffness acts on top of this spring",
            sp.stiffness,
            100.0 * sp.rigid_residual_rel,
            id.mass
        ));
    }
    if e.residual_rel > RESIDUAL_LIMIT {
        out.push(format!(
            "the rigid-mass model with viscous and Coulomb friction leaves {:.0} % of the \
             excitation force unexplained (more than {:.0} %): the device has dynamics the model \
             lacks",
            100.0 * e.residual_rel,
            100.0 * RESIDUAL_LIMIT
        ));
    }
    for (i, dir) in ["positive", "negative"].iter().enumerate() {
        match (e.breakaway_measured[i], e.breakaway_model[i]) {
            (Some(meas), Some(model))
                if meas.abs() - model.abs() > BREAKAWAY_EXCESS * id.coulomb.max(0.0) =>
            {
                out.push(format!(
                    "breakaway in the {dir} direction needs {:.3e} {force_unit}, {:.2} × the \
                     sliding friction c = {:.3e} {force_unit}: static friction (stick–slip) \
                     or an amplifier dead band, which the model does not include",
                    meas.abs(),
                    meas.abs() / id.coulomb.max(1e-30),
                    id.coulomb
                ));
            }
            (None, Some(_)) => out.push(format!(
                "the device did not break away in the {dir} direction on a ramp that moves the \
                 identified model: static friction above the sliding friction"
            )),
            _ => {}
        }
    }
    if let (Some((meas, model)), Some(k)) = (resonance(e), e.release_k) {
        out.push(format!(
            "a release at K = {k:.4} oscillates at {meas:.1} Hz where the rigid model \
             predicts {model:.1} Hz: a resonance or lag (compliant transmission, amplifier) \
             shapes the wall's response"
        ));
    }
    out
}

/// The measured and the rigid model's release frequency, Hz, when their ratio is outside
/// [1/[`FREQUENCY_RATIO`], [`FREQUENCY_RATIO`]].
fn resonance(e: &Evidence) -> Option<(f64, f64)> {
    let (meas, model) = (e.release_hz?, e.model_hz?);
    let r = meas / model;
    (!(1.0 / FREQUENCY_RATIO..=FREQUENCY_RATIO).contains(&r)).then_some((meas, model))
}

/// Whether the identified dynamics (mass, the wall's frequency) fit the device: no spring-like
/// force, a fit residual within [`RESIDUAL_LIMIT`], no resonance. Then the only findings can
/// be about friction (breakaway above sliding) or the verified K against the prediction, and
/// the test energies, computed from the identified mass, are the ones asked for.
#[must_use]
pub fn dynamics_fit(id: &Identified, e: &Evidence) -> bool {
    id.spring.is_none() && e.residual_rel <= RESIDUAL_LIMIT && resonance(e).is_none()
}

/// Finding when the verified K is far below the prediction, if it is.
#[must_use]
pub fn prediction_finding(k_verified: f64, k_expected: f64) -> Option<String> {
    (k_verified < PREDICTION_RATIO * k_expected).then(|| {
        format!(
            "the largest verified stiffness {k_verified:.4} is {:.0} % of the model's expected \
             limit {k_expected:.4}: the device is less stable than its identified model",
            100.0 * k_verified / k_expected
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn id(m: f64, b: f64, c: f64) -> Identified {
        Identified {
            mass: m,
            mass_se: 0.0,
            viscous: b,
            viscous_se: 0.0,
            coulomb: c,
            coulomb_se: 0.0,
            equations: 100,
            residual_rel: 0.01,
            spring: None,
        }
    }

    fn ramp(peak: f64, n: usize) -> Vec<f64> {
        (0..n).map(|k| peak * k as f64 / n as f64).collect()
    }

    #[test]
    fn the_model_breaks_away_just_above_c_and_a_sticky_device_later() {
        let (m, c, delta, t) = (0.07, 0.04, 2.9e-5, 1e-3);
        let f = ramp(3.0 * c, 600);
        let model = id(m, 0.0, c);
        let counts = model_counts(&model, &f, 0.0, t, delta);
        let fb = breakaway_force(&counts, &f).unwrap();
        // The model itself needs a little more than c to move two counts on a ramp (inertia).
        assert!(fb > c && fb < 1.3 * c, "{fb}");
        // A device whose static friction is 1.5 c: it cannot move before |F| > 1.5 c.
        let sticky: Vec<i64> = f
            .iter()
            .scan((0.5 * delta, 0.0f64, false), |(x, v, moving), &ff| {
                let n = (*x / delta).floor() as i64;
                if !*moving && ff > 1.5 * c {
                    *moving = true;
                }
                if *moving {
                    *v += t * (ff - c) / m;
                    *x += t * *v;
                }
                Some(n)
            })
            .collect();
        let fs = breakaway_force(&sticky, &f).unwrap();
        let e = Evidence {
            breakaway_measured: [Some(fs), None],
            breakaway_model: [Some(fb), None],
            ..Evidence::default()
        };
        let found = findings(&model, &e, ("N", "N/m"));
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(found[0].contains("static friction"), "{found:?}");
        let e = Evidence {
            breakaway_measured: [Some(fb), None],
            breakaway_model: [Some(fb), None],
            ..Evidence::default()
        };
        assert!(findings(&model, &e, ("N", "N/m")).is_empty());
    }

    #[test]
    fn release_frequency_of_a_sampled_cosine() {
        let t = 1e-3;
        let counts: Vec<i64> = (0..2000)
            .map(|k| (30.0 * (std::f64::consts::TAU * 12.5 * k as f64 * t).cos()).floor() as i64)
            .collect();
        let f = release_frequency_hz(&counts, t, 12).unwrap();
        assert!((f / 12.5 - 1.0).abs() < 0.02, "{f}");
        assert_eq!(release_frequency_hz(&[3, 3, 3, -1, -1], t, 12), None);
    }

    #[test]
    fn residual_and_frequency_and_prediction_findings() {
        let model = id(0.07, 0.0, 0.04);
        let e = Evidence {
            residual_rel: 0.2,
            release_hz: Some(40.0),
            model_hz: Some(10.0),
            release_k: Some(100.0),
            ..Evidence::default()
        };
        let found = findings(&model, &e, ("N", "N/m"));
        assert_eq!(found.len(), 2, "{found:?}");
        assert!(found[0].contains("unexplained"));
        assert!(found[1].contains("40.0 Hz"));
        assert!(prediction_finding(0.5, 1.0).is_some());
        assert!(prediction_finding(0.9, 1.0).is_none());
    }

    #[test]
    fn the_dynamics_fit_unless_a_spring_a_residual_or_a_resonance_says_otherwise() {
        let model = id(0.07, 0.0, 0.04);
        // Static friction alone (a breakaway finding) leaves the dynamics fitting.
        let sticky = Evidence {
            residual_rel: 0.02,
            breakaway_measured: [Some(0.08), Some(-0.08)],
            breakaway_model: [Some(0.045), Some(-0.045)],
            release_hz: Some(11.0),
            model_hz: Some(10.0),
            release_k: Some(100.0),
        };
        assert_eq!(findings(&model, &sticky, ("N", "N/m")).len(), 2);
        assert!(dynamics_fit(&model, &sticky));
        let resonant = Evidence {
            release_hz: Some(14.0),
            ..sticky.clone()
        };
        assert!(!dynamics_fit(&model, &resonant));
        let residual = Evidence {
            residual_rel: 0.1,
            ..sticky.clone()
        };
        assert!(!dynamics_fit(&model, &residual));
        let held = Identified {
            spring: Some(super::super::ident::Spring {
                stiffness: 250.0,
                stiffness_se: 1.0,
                offset: 0.0,
                rigid_residual_rel: 0.5,
            }),
            ..model
        };
        assert!(!dynamics_fit(&held, &sticky));
    }
}
