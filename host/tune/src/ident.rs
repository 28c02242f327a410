//! Identification of mass m, viscous friction b and Coulomb friction c from an open-loop
//! excitation recorded with the wall off.
//!
//! Model (eq. (1) with F_H = 0): m ẍ + b ẋ + c sgn(ẋ) = F_A. Quantized positions are never
//! differentiated twice: the equation is integrated over windows [t_a, t_b],
//!
//! m (v_b − v_a) + b (x_b − x_a) + c ∫ sgn(v) dt = ∫ F_A dt,
//!
//! where x is the mid-tick position (n + ½)Δ, the integrals are sums over held (ZOH) periods, and
//! the end-point velocities v_a, v_b come from a local least-squares line through ±`half_window`
//! positions (one differentiation, smoothed). Windows in which the device may be sticking
//! (smoothed speed below `stick_speed_ticks` ticks per period anywhere in the window) are left
//! out, since there the friction is static and not c·sgn(v). Least squares over all windows gives
//! (m, b, c) with standard errors from the residual variance.
//!
//! **Position-dependent force.** A hand holding the handle, a cable or a gravity-compensation
//! spring adds a force k·x + f₀ that the rigid model lacks; fitted without it, a 3 Hz hand
//! resonance inside the chirp band turns into a negative mass. So the fit is also run with two
//! more columns, ∫x dt and ∫dt (k and f₀), and that extended fit is kept when k is clearly
//! resolved (k > [`SPRING_SIGNIFICANCE`] standard errors above zero) and it explains the force
//! clearly better (relative residual below [`SPRING_RESIDUAL_GAIN`] × the rigid fit's). m, b and
//! c are then those of the extended fit (m includes whatever moves with the handle, e.g. the
//! hand's mass), and [`Identified::spring`] reports k for the model check.
//!
//! Units: SI (kg, N·s/m, N; or kg·m², N·m·s/rad, N·m for rotary devices with Δ in rad).

use super::error::{bail, Result, StepError};
use nalgebra::{DMatrix, DVector};

/// The extended fit's k must exceed this many of its standard errors to be kept.
pub const SPRING_SIGNIFICANCE: f64 = 4.0;
/// The extended fit is kept only when its relative residual is below this × the rigid fit's.
pub const SPRING_RESIDUAL_GAIN: f64 = 0.8;

/// One servo sample of an excitation record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Encoder count at the sample instant.
    pub count: i64,
    /// Force applied (held) from this sample instant to the next, in N (or N·m).
    pub force: f64,
}

/// Settings of the identification.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// Servo period T in seconds.
    pub period_s: f64,
    /// Encoder resolution Δ in m (or rad).
    pub resolution: f64,
    /// Half-width, in samples, of the line fit that estimates velocity.
    pub half_window: usize,
    /// Window length, in samples, of one integrated equation.
    pub window: usize,
    /// Windows whose smoothed speed drops below this many ticks per period are left out.
    pub stick_speed_ticks: f64,
    /// Delay between the force sample and its application, in whole periods (≥ 0).
    pub delay_periods: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            period_s: 1e-3,
            resolution: 1e-5,
            half_window: 8,
            window: 40,
            stick_speed_ticks: 0.05,
            delay_periods: 0,
        }
    }
}

/// Identified parameters with one-sigma standard errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Identified {
    /// Mass (or inertia).
    pub mass: f64,
    /// Standard error of `mass`.
    pub mass_se: f64,
    /// Viscous friction.
    pub viscous: f64,
    /// Standard error of `viscous`.
    pub viscous_se: f64,
    /// Coulomb friction.
    pub coulomb: f64,
    /// Standard error of `coulomb`.
    pub coulomb_se: f64,
    /// Number of integrated equations used.
    pub equations: usize,
    /// RMS of the fit residual relative to the RMS of the force integrals (0 = exact fit).
    pub residual_rel: f64,
    /// A position-dependent force k·x + f₀ found beside the rigid model (None: none resolved).
    pub spring: Option<Spring>,
}

/// A spring-like force k·x + f₀ on the device (x the mid-tick position of the record's counts).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spring {
    /// Stiffness k, N/m (N·m/rad).
    pub stiffness: f64,
    /// Standard error of `stiffness`.
    pub stiffness_se: f64,
    /// Force at x = 0, N (N·m).
    pub offset: f64,
    /// Relative residual of the rigid fit without the spring, for the report.
    pub rigid_residual_rel: f64,
}

impl Identified {
    /// True when b is not distinguishable from zero (within two standard errors): then only the
    /// upper bound [`Identified::viscous_upper_bound`] is meaningful, as for most devices in
    /// the paper's Table II.
    #[must_use]
    pub fn viscous_only_bounded(&self) -> bool {
        self.viscous.abs() < 2.0 * self.viscous_se
    }

    /// Upper bound on b: estimate plus two standard errors, at least zero.
    #[must_use]
    pub fn viscous_upper_bound(&self) -> f64 {
        (self.viscous + 2.0 * self.viscous_se).max(0.0)
    }
}

/// Identifies m, b, c from an excitation record.
pub fn identify(samples: &[Sample], s: &Settings) -> Result<Identified> {
    check(s, samples.len())?;
    let x = positions(samples, s.resolution);
    let v = velocities(&x, s.half_window, s.period_s);
    let rows = window_rows(samples, &x, &v, s);
    if rows.len() < 6 {
        bail!(
            "only {} usable windows (the device stuck or barely moved); excite harder",
            rows.len()
        );
    }
    let (fit, spring) = rigid_or_extended(&rows)?;
    Ok(Identified {
        mass: fit.p[0],
        mass_se: fit.se[0],
        viscous: fit.p[1],
        viscous_se: fit.se[1],
        coulomb: fit.p[2],
        coulomb_se: fit.se[2],
        equations: rows.len(),
        residual_rel: fit.residual_rel,
        spring,
    })
}

/// Checks the settings and that `n` samples hold at least one window with its velocity
/// estimates and delay.
fn check(s: &Settings, n: usize) -> Result<()> {
    if !(s.period_s.is_finite() && s.period_s > 0.0) {
        bail!("period_s must be finite and > 0 (got {})", s.period_s);
    }
    if !(s.resolution.is_finite() && s.resolution > 0.0) {
        bail!("resolution must be finite and > 0 (got {})", s.resolution);
    }
    if s.half_window == 0 || s.window < 2 {
        bail!("half_window must be ≥ 1 and window ≥ 2");
    }
    let h = s.half_window;
    if n < 2 * h + s.window + s.delay_periods + 1 {
        bail!(
            "excitation too short: {n} samples, need at least {}",
            2 * h + s.window + s.delay_periods + 1
        );
    }
    Ok(())
}

/// The mid-tick positions (n + ½)Δ of the samples' counts, m (rad), for `resolution` Δ.
fn positions(samples: &[Sample], resolution: f64) -> Vec<f64> {
    samples
        .iter()
        .map(|p| (p.count as f64 + 0.5) * resolution)
        .collect()
}

/// Velocity by least-squares line over ±`h` samples (central, so no lag), m/s (rad/s) for a
/// period `t` s; NaN within `h` samples of either end.
fn velocities(x: &[f64], h: usize, t: f64) -> Vec<f64> {
    let n = x.len();
    let denom: f64 = (1..=h).map(|j| 2.0 * (j * j) as f64).sum::<f64>() * t;
    let mut v = vec![f64::NAN; n];
    for k in h..n - h {
        let num: f64 = (1..=h).map(|j| j as f64 * (x[k + j] - x[k - j])).sum();
        v[k] = num / denom;
    }
    v
}

/// One integrated equation per window that never sticks: [Δv, Δx, ∫sgn(v) dt, ∫x dt, ∫dt] ·
/// (m, b, c, k, f₀) = ∫F_A dt, windows of `s.window` samples advancing by half a window.
fn window_rows(samples: &[Sample], x: &[f64], v: &[f64], s: &Settings) -> Vec<([f64; 5], f64)> {
    let (n, h, t) = (samples.len(), s.half_window, s.period_s);
    let stick_speed = s.stick_speed_ticks * s.resolution / t;
    let mut rows: Vec<([f64; 5], f64)> = Vec::new();
    let mut a = h;
    while a + s.window < n - h {
        let b = a + s.window;
        if (a..=b).all(|k| v[k].abs() >= stick_speed) {
            let sgn_int: f64 = (a..b).map(|k| v[k].signum() * t).sum();
            let x_int: f64 = (a..b).map(|k| 0.5 * (x[k] + x[k + 1]) * t).sum();
            // Force applied during period k was commanded `delay` periods earlier.
            let f_int: f64 = (a..b)
                .map(|k| {
                    k.checked_sub(s.delay_periods)
                        .map_or(0.0, |j| samples[j].force)
                        * t
                })
                .sum();
            rows.push((
                [v[b] - v[a], x[b] - x[a], sgn_int, x_int, (b - a) as f64 * t],
                f_int,
            ));
        }
        a += s.window / 2;
    }
    rows
}

/// The rigid fit (m, b, c), or the extended one (m, b, c, k, f₀) with its spring when k is
/// resolved and the residual clearly smaller ([`SPRING_SIGNIFICANCE`], [`SPRING_RESIDUAL_GAIN`]).
fn rigid_or_extended(rows: &[([f64; 5], f64)]) -> Result<(Fit, Option<Spring>)> {
    let rigid = least_squares(rows, 3).ok_or_else(|| {
        StepError::Failed("excitation does not separate m, b and c (singular fit)".into())
    })?;
    let extended = least_squares(rows, 5).filter(|e| {
        e.p[3] > SPRING_SIGNIFICANCE * e.se[3]
            && e.residual_rel < SPRING_RESIDUAL_GAIN * rigid.residual_rel
    });
    let spring = extended.as_ref().map(|e| Spring {
        stiffness: e.p[3],
        stiffness_se: e.se[3],
        offset: e.p[4],
        rigid_residual_rel: rigid.residual_rel,
    });
    Ok((extended.unwrap_or(rigid), spring))
}

/// A least-squares fit: parameters, their standard errors and the relative residual.
struct Fit {
    p: Vec<f64>,
    se: Vec<f64>,
    residual_rel: f64,
}

/// Least squares over the first `cols` columns of `rows`, by QR-free normal equations with
/// columns scaled to unit norm (the columns differ by many orders of magnitude), solved with
/// nalgebra's Cholesky. None when the columns are (nearly) dependent.
fn least_squares(rows: &[([f64; 5], f64)], cols: usize) -> Option<Fit> {
    let a = DMatrix::from_fn(rows.len(), cols, |i, j| rows[i].0[j]);
    let y = DVector::from_iterator(rows.len(), rows.iter().map(|r| r.1));
    let norms: Vec<f64> = (0..cols).map(|j| a.column(j).norm()).collect();
    if norms.iter().any(|&s| !(s.is_finite() && s > 0.0)) {
        return None;
    }
    let scaled = DMatrix::from_fn(rows.len(), cols, |i, j| a[(i, j)] / norms[j]);
    let ata = scaled.transpose() * &scaled;
    // Condition guard: a scaled Gram matrix with a tiny eigenvalue means dependent columns.
    let eig = ata.clone().symmetric_eigenvalues();
    if eig.min() <= 1e-10 * eig.max() {
        return None;
    }
    let chol = ata.cholesky()?;
    let q = chol.solve(&(scaled.transpose() * &y));
    let inv = chol.inverse();
    let resid = &y - &scaled * &q;
    let rss = resid.norm_squared();
    let y2 = y.norm_squared();
    let dof = (rows.len() - cols) as f64;
    let s2 = rss / dof;
    Some(Fit {
        p: (0..cols).map(|j| q[j] / norms[j]).collect(),
        se: (0..cols)
            .map(|j| (s2 * inv[(j, j)]).max(0.0).sqrt() / norms[j])
            .collect(),
        residual_rel: if y2 > 0.0 { (rss / y2).sqrt() } else { 0.0 },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A finely sub-stepped plant, independent of the solver under test elsewhere: semi-implicit
    /// Euler with 200 sub-steps per period, Coulomb friction with a stick band.
    fn simulate(m: f64, b: f64, c: f64, delta: f64, t: f64, forces: &[f64]) -> Vec<Sample> {
        simulate_held([m, b, c], [0.0; 3], delta, t, forces)
    }

    #[test]
    fn recovers_mass_and_coulomb_of_a_simulated_device() {
        let (m, b, c, delta, t) = (0.072, 0.005, 0.038, 29.1e-6, 1e-3);
        let forces: Vec<f64> = (0..4000)
            .map(|k| 0.3 * (2.0 * std::f64::consts::PI * 2.0 * k as f64 * t).sin())
            .collect();
        let samples = simulate(m, b, c, delta, t, &forces);
        let s = Settings {
            period_s: t,
            resolution: delta,
            ..Settings::default()
        };
        let id = identify(&samples, &s).unwrap();
        assert!((id.mass / m - 1.0).abs() < 0.05, "{id:?}");
        assert!((id.coulomb / c - 1.0).abs() < 0.10, "{id:?}");
        assert!(id.viscous_upper_bound() >= b * 0.5, "{id:?}");
    }

    #[test]
    fn a_device_that_never_moves_is_an_error() {
        let samples = vec![
            Sample {
                count: 3,
                force: 0.0
            };
            500
        ];
        let e = identify(&samples, &Settings::default()).unwrap_err();
        assert!(e.to_string().contains("usable windows"), "{e}");
    }

    #[test]
    fn bad_settings_name_the_field() {
        let samples = vec![
            Sample {
                count: 3,
                force: 0.0
            };
            500
        ];
        let s = Settings {
            period_s: 0.0,
            ..Settings::default()
        };
        assert!(identify(&samples, &s)
            .unwrap_err()
            .to_string()
            .contains("period_s"));
    }

    #[test]
    fn least_squares_solves_a_known_system_and_refuses_dependent_columns() {
        // y = 2·a − 3·b + 0.5·c exactly, columns of very different scales.
        let rows: Vec<([f64; 5], f64)> = (0..20)
            .map(|i| {
                let (a, b, c) = (
                    1e-3 * f64::from(i).sin(),
                    1e-6 * f64::from(i),
                    1.0 + f64::from(i % 3),
                );
                ([a, b, c, 0.0, 0.0], 2.0 * a - 3.0 * b + 0.5 * c)
            })
            .collect();
        let f = least_squares(&rows, 3).unwrap();
        for (got, want) in f.p.iter().zip([2.0, -3.0, 0.5]) {
            assert!((got - want).abs() < 1e-6 * want.abs().max(1.0), "{:?}", f.p);
        }
        assert!(f.residual_rel < 1e-9);
        let dependent: Vec<([f64; 5], f64)> = rows
            .iter()
            .map(|(r, y)| ([r[0], 2.0 * r[0], r[2], 0.0, 0.0], *y))
            .collect();
        assert!(least_squares(&dependent, 3).is_none());
    }

    /// The device of [`simulate`] held by a hand: m_h moves with it, a spring k_h pulls it back
    /// to x = 0 with damping b_h (all zero: the free device). Semi-implicit Euler, 200
    /// sub-steps per period, Coulomb friction with a stick band.
    fn simulate_held(
        p: [f64; 3],
        hand: [f64; 3],
        delta: f64,
        t: f64,
        forces: &[f64],
    ) -> Vec<Sample> {
        let [m, b, c] = p;
        let [mh, bh, kh] = hand;
        let (mut x, mut v) = (0.0f64, 0.0f64);
        let sub = 200;
        let dt = t / f64::from(sub);
        let mut out = Vec::new();
        for &f in forces {
            out.push(Sample {
                count: (x / delta).floor() as i64,
                force: f,
            });
            for _ in 0..sub {
                let fs = f - kh * x;
                if v == 0.0 && fs.abs() <= c {
                    continue;
                }
                let fr = if v != 0.0 {
                    c * v.signum()
                } else {
                    c * fs.signum()
                };
                let vn = v + dt * (fs - (b + bh) * v - fr) / (m + mh);
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

    #[test]
    fn a_hand_spring_is_found_and_the_mass_includes_the_hand() {
        let (delta, t) = (29.1e-6, 1e-3);
        // Phantom held loosely (0.05 kg, 0.5 N·s/m, 50 N/m): resonance at 3.2 Hz, inside a
        // 0.5–4 Hz chirp, where the rigid fit's mass goes negative.
        let forces: Vec<f64> = (0..6000)
            .map(|k| {
                let tk = k as f64 * t;
                let phase = std::f64::consts::TAU * (0.5 * tk + 0.5 * (3.5 / 6.0) * tk * tk);
                0.4 * phase.sin()
            })
            .collect();
        let samples = simulate_held([0.072, 0.005, 0.038], [0.05, 0.5, 50.0], delta, t, &forces);
        let s = Settings {
            period_s: t,
            resolution: delta,
            ..Settings::default()
        };
        let id = identify(&samples, &s).unwrap();
        let spring = id.spring.expect("spring found");
        assert!((spring.stiffness / 50.0 - 1.0).abs() < 0.15, "{id:?}");
        assert!((id.mass / 0.122 - 1.0).abs() < 0.1, "{id:?}");
        assert!((id.coulomb / 0.038 - 1.0).abs() < 0.2, "{id:?}");
        // The same chirp on the free device finds no spring.
        let free = simulate_held([0.072, 0.005, 0.038], [0.0, 0.0, 0.0], delta, t, &forces);
        let id = identify(&free, &s).unwrap();
        assert!(id.spring.is_none(), "{id:?}");
        assert!((id.mass / 0.072 - 1.0).abs() < 0.05, "{id:?}");
    }
}
