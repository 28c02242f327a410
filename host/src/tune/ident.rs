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
//! Units: SI (kg, N·s/m, N; or kg·m², N·m·s/rad, N·m for rotary devices with Δ in rad).

use anyhow::{bail, Result};

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
    if !(s.period_s.is_finite() && s.period_s > 0.0) {
        bail!("period_s must be finite and > 0 (got {})", s.period_s);
    }
    if !(s.resolution.is_finite() && s.resolution > 0.0) {
        bail!("resolution must be finite and > 0 (got {})", s.resolution);
    }
    if s.half_window == 0 || s.window < 2 {
        bail!("half_window must be ≥ 1 and window ≥ 2");
    }
    let n = samples.len();
    let h = s.half_window;
    if n < 2 * h + s.window + s.delay_periods + 1 {
        bail!(
            "excitation too short: {n} samples, need at least {}",
            2 * h + s.window + s.delay_periods + 1
        );
    }
    let t = s.period_s;
    let x: Vec<f64> = samples
        .iter()
        .map(|p| (p.count as f64 + 0.5) * s.resolution)
        .collect();
    // Velocity by least-squares line over ±h samples (central, so no lag).
    let denom: f64 = (1..=h).map(|j| 2.0 * (j * j) as f64).sum::<f64>() * t;
    let mut v = vec![f64::NAN; n];
    for k in h..n - h {
        let num: f64 = (1..=h).map(|j| j as f64 * (x[k + j] - x[k - j])).sum();
        v[k] = num / denom;
    }
    let stick_speed = s.stick_speed_ticks * s.resolution / t;
    // Normal equations of the 3-parameter least squares, accumulated window by window.
    let mut ata = [[0.0f64; 3]; 3];
    let mut atb = [0.0f64; 3];
    let mut rows: Vec<([f64; 3], f64)> = Vec::new();
    let mut a = h;
    while a + s.window < n - h {
        let b = a + s.window;
        if (a..=b).all(|k| v[k].abs() >= stick_speed) {
            let sgn_int: f64 = (a..b).map(|k| v[k].signum() * t).sum();
            // Force applied during period k was commanded `delay` periods earlier.
            let f_int: f64 = (a..b)
                .map(|k| {
                    k.checked_sub(s.delay_periods)
                        .map_or(0.0, |j| samples[j].force)
                        * t
                })
                .sum();
            let row = [v[b] - v[a], x[b] - x[a], sgn_int];
            for i in 0..3 {
                for j in 0..3 {
                    ata[i][j] += row[i] * row[j];
                }
                atb[i] += row[i] * f_int;
            }
            rows.push((row, f_int));
        }
        a += s.window / 2;
    }
    if rows.len() < 6 {
        bail!(
            "only {} usable windows (the device stuck or barely moved); excite harder",
            rows.len()
        );
    }
    let inv = invert3(&ata)
        .ok_or_else(|| anyhow::anyhow!("excitation does not separate m, b and c (singular fit)"))?;
    let mut p = [0.0; 3];
    for i in 0..3 {
        p[i] = (0..3).map(|j| inv[i][j] * atb[j]).sum();
    }
    let rss: f64 = rows
        .iter()
        .map(|(r, y)| {
            let e = y - (r[0] * p[0] + r[1] * p[1] + r[2] * p[2]);
            e * e
        })
        .sum();
    let y2: f64 = rows.iter().map(|(_, y)| y * y).sum();
    let residual_rel = if y2 > 0.0 { (rss / y2).sqrt() } else { 0.0 };
    let dof = (rows.len() - 3) as f64;
    let s2 = rss / dof;
    let se = |i: usize| (s2 * inv[i][i]).max(0.0).sqrt();
    Ok(Identified {
        mass: p[0],
        mass_se: se(0),
        viscous: p[1],
        viscous_se: se(1),
        coulomb: p[2],
        coulomb_se: se(2),
        equations: rows.len(),
        residual_rel,
    })
}

/// Inverse of a symmetric 3×3 matrix by cofactors, or None when (nearly) singular.
/// Written out because one 3×3 inverse does not justify a linear-algebra dependency.
fn invert3(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c =
        |r0: usize, r1: usize, c0: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    let cof = [
        [c(1, 2, 1, 2), -c(1, 2, 0, 2), c(1, 2, 0, 1)],
        [-c(0, 2, 1, 2), c(0, 2, 0, 2), -c(0, 2, 0, 1)],
        [c(0, 1, 1, 2), -c(0, 1, 0, 2), c(0, 1, 0, 1)],
    ];
    let det = m[0][0] * cof[0][0] + m[0][1] * cof[0][1] + m[0][2] * cof[0][2];
    let scale = m.iter().flatten().fold(0.0f64, |a, &b| a.max(b.abs()));
    if !det.is_finite() || det.abs() <= 1e-14 * scale.powi(3) {
        return None;
    }
    let mut inv = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            inv[i][j] = cof[j][i] / det;
        }
    }
    Some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A finely sub-stepped plant, independent of the solver under test elsewhere: semi-implicit
    /// Euler with 200 sub-steps per period, Coulomb friction with a stick band.
    fn simulate(m: f64, b: f64, c: f64, delta: f64, t: f64, forces: &[f64]) -> Vec<Sample> {
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
                if v == 0.0 && f.abs() <= c {
                    continue;
                }
                let fr = if v != 0.0 {
                    c * v.signum()
                } else {
                    c * f.signum()
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
    #[allow(clippy::needless_range_loop)] // matrix indices read clearer here
    fn invert3_inverts() {
        let m = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let inv = invert3(&m).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let p: f64 = (0..3).map(|k| m[i][k] * inv[k][j]).sum();
                assert!((p - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
        assert!(invert3(&[[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]]).is_none());
    }
}
