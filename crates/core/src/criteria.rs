//! Classic stiffness criteria of the field, for side-by-side comparison with the paper's.
//!
//! Units: inputs are [`PhysicalParams`](crate::params::PhysicalParams) (SI; the `stiffness` field is ignored except where a
//! function says it tests stability *at* that stiffness); results are stiffnesses in N/m
//! (N·m/rad for rotational devices). Virtual damping B of the cited papers is 0 in the functions
//! of this file (the wall of eq. (2) is a pure spring); the spring + damper wall
//! F = −K·x − B·(x_k − x_{k−1})/T is analysed in the `damped` submodule, re-exported here
//! ([`k_max_exact_linear`], [`exact_linear_stable`], [`k_max_colgate_schenkel_damped`],
//! [`k_max_small_b`], [`Frontier`]).
//!
//! Invariants: no allocation; the exact linear boundary uses fixed-size coefficient arrays of
//! length [`MAX_DEGREE`] + 1, which limits the delay to [`MAX_DELAY_PERIODS`] periods.

mod damped;
mod sampled;
pub use damped::*;
pub use sampled::*;

#[cfg(test)]
mod tests {
    use super::sampled::*;
    use crate::params::PhysicalParams;

    fn dev(b: f64, td: f64) -> PhysicalParams {
        PhysicalParams {
            mass: 0.072,
            viscous: b,
            coulomb: 0.038,
            resolution: 29.1e-6,
            period_s: 1e-3,
            stiffness: 1.0,
            delay_s: td,
            rotational: false,
        }
    }

    #[test]
    fn gil_no_delay_matches_closed_form() {
        for b in [0.005, 0.5, 20.0, 200.0, 2000.0] {
            let p = dev(b, 0.0);
            let k = k_max_gil_avello_rubio(&p).unwrap();
            let x: f64 = b * 1e-3 / 0.072;
            let e = (-x).exp();
            // (1 - e)/ñ0 with ñ0 = (1 - e - xe)/x², by series for small x (cancellation).
            let n0 = if x < 1e-2 {
                0.5 - x / 3.0 + x * x / 8.0 - x * x * x / 30.0
            } else {
                (1.0 - e - x * e) / (x * x)
            };
            let exact = 0.072 / 1e-6 * (-(-x).exp_m1()) / n0;
            if x < 1.0 {
                assert!((k - exact).abs() < 1e-9 * exact, "b={b}: {k} vs {exact}");
            }
            // The polynomial test agrees with the closed form.
            assert!(gil_avello_rubio_stable(&p.with_stiffness(k * (1.0 - 1e-8))).unwrap());
            assert!(!gil_avello_rubio_stable(&p.with_stiffness(k * (1.0 + 1e-8))).unwrap());
            let colgate = k_max_colgate_schenkel(&p).unwrap();
            if x < 1e-3 {
                assert!((k - colgate).abs() < 1e-3 * colgate);
            }
        }
    }

    #[test]
    fn gil_delay_monotone_and_near_hulin() {
        let mut prev = f64::INFINITY;
        for td in [0.0, 0.25e-3, 0.5e-3, 1.0e-3, 1.25e-3, 2.0e-3, 3.0e-3] {
            let p = dev(0.005, td);
            let k = k_max_gil_avello_rubio(&p).unwrap();
            assert!(k < prev, "td={td}");
            prev = k;
            let h = k_max_hulin(&p).unwrap();
            assert!((k - h).abs() < 0.05 * h, "td={td}: {k} vs {h}");
            // stable just below, unstable just above
            assert!(gil_avello_rubio_stable(&p.with_stiffness(k * (1.0 - 1e-9))).unwrap());
            assert!(!gil_avello_rubio_stable(&p.with_stiffness(k * (1.0 + 1e-9))).unwrap());
        }
    }

    #[test]
    fn undamped_never_stable() {
        assert_eq!(k_max_gil_avello_rubio(&dev(0.0, 0.0)).unwrap(), 0.0);
    }
}
