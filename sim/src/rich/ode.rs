//! Reference integrators of the rich plant: fixed-step classical RK4 and adaptive
//! Dormand–Prince 5(4), both with event location by bisection on re-taken partial steps.
//!
//! Units: whatever the [`Field`] uses (SI in this crate: s, m, m/s, N). The error of a
//! Dormand–Prince step is measured per component as |err_i| / (atol·scale_i + rtol·|y_i|),
//! `scale` given by the caller (e.g. the encoder resolution for positions), so `atol` is
//! dimensionless.
//!
//! Invariants: every call of [`Stepper::run`] ends (at most [`MAX_STEPS`] accepted or rejected
//! steps, 60 bisections per event, a minimum step of 1e-12 of the requested interval below
//! which a step is accepted whatever its error); no allocation; the state stays finite when the
//! field is finite.

/// Dimension of the state (motor x, v; link x, v; amplifier p, ṗ).
pub const NS: usize = 6;
/// A state vector.
pub type State = [f64; NS];
/// Maximum number of steps of one [`Stepper::run`] call.
pub const MAX_STEPS: u32 = 1_000_000;

/// A vector field with a mode-switching event.
pub trait Field {
    /// dy/dt at y.
    fn rhs(&self, y: &State, dy: &mut State);
    /// Whether the event has happened at y (the current mode no longer holds).
    fn fired(&self, y: &State) -> bool;
}

/// Integration method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OdeMethod {
    /// Classical RK4 with steps of at most `step_s`.
    Rk4 {
        /// Step length, s (> 0).
        step_s: f64,
    },
    /// Dormand–Prince 5(4) with error control.
    Dopri {
        /// Relative tolerance.
        rtol: f64,
        /// Absolute tolerance (in units of `scale`).
        atol: f64,
    },
}

/// Work counters.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OdeStats {
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Located events.
    pub events: u64,
}

/// An integrator with its step-size memory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stepper {
    method: OdeMethod,
    /// Absolute-tolerance scale per component.
    pub scale: State,
    h: f64,
    /// Work counters.
    pub stats: OdeStats,
}

const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const B1: f64 = 35.0 / 384.0;
const B3: f64 = 500.0 / 1113.0;
const B4: f64 = 125.0 / 192.0;
const B5: f64 = -2187.0 / 6784.0;
const B6: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;

fn comb(y: &State, h: f64, terms: &[(f64, &State)]) -> State {
    let mut o = *y;
    for (i, oi) in o.iter_mut().enumerate() {
        let mut s = 0.0;
        for (c, k) in terms {
            s += c * k[i];
        }
        *oi += h * s;
    }
    o
}

impl Stepper {
    /// A stepper; `scale` is the absolute-tolerance unit of each component (> 0).
    #[must_use]
    pub fn new(method: OdeMethod, scale: State) -> Self {
        let h = match method {
            OdeMethod::Rk4 { step_s } => step_s,
            OdeMethod::Dopri { .. } => 0.0,
        };
        Self {
            method,
            scale,
            h,
            stats: OdeStats::default(),
        }
    }

    /// Forgets the step-size memory: the next [`Stepper::run`] starts from a step of its whole
    /// interval, so its result depends only on its arguments, not on earlier calls.
    pub fn reset_step(&mut self) {
        if matches!(self.method, OdeMethod::Dopri { .. }) {
            self.h = 0.0;
        }
    }

    /// The method.
    #[must_use]
    pub fn method(&self) -> OdeMethod {
        self.method
    }

    /// One step of length h from y: the new state and (Dormand–Prince) the error norm.
    fn step<F: Field>(&mut self, f: &F, y: &State, h: f64) -> (State, f64) {
        let mut k1 = [0.0; NS];
        let mut k2 = [0.0; NS];
        let mut k3 = [0.0; NS];
        let mut k4 = [0.0; NS];
        f.rhs(y, &mut k1);
        match self.method {
            OdeMethod::Rk4 { .. } => {
                self.stats.rhs_evals += 4;
                f.rhs(&comb(y, 0.5 * h, &[(1.0, &k1)]), &mut k2);
                f.rhs(&comb(y, 0.5 * h, &[(1.0, &k2)]), &mut k3);
                f.rhs(&comb(y, h, &[(1.0, &k3)]), &mut k4);
                let y1 = comb(
                    y,
                    h / 6.0,
                    &[(1.0, &k1), (2.0, &k2), (2.0, &k3), (1.0, &k4)],
                );
                (y1, 0.0)
            }
            OdeMethod::Dopri { rtol, atol } => {
                self.stats.rhs_evals += 7;
                let mut k5 = [0.0; NS];
                let mut k6 = [0.0; NS];
                let mut k7 = [0.0; NS];
                f.rhs(&comb(y, h, &[(A21, &k1)]), &mut k2);
                f.rhs(&comb(y, h, &[(A31, &k1), (A32, &k2)]), &mut k3);
                f.rhs(&comb(y, h, &[(A41, &k1), (A42, &k2), (A43, &k3)]), &mut k4);
                f.rhs(
                    &comb(y, h, &[(A51, &k1), (A52, &k2), (A53, &k3), (A54, &k4)]),
                    &mut k5,
                );
                f.rhs(
                    &comb(
                        y,
                        h,
                        &[(A61, &k1), (A62, &k2), (A63, &k3), (A64, &k4), (A65, &k5)],
                    ),
                    &mut k6,
                );
                let y1 = comb(
                    y,
                    h,
                    &[(B1, &k1), (B3, &k3), (B4, &k4), (B5, &k5), (B6, &k6)],
                );
                f.rhs(&y1, &mut k7);
                let mut err: f64 = 0.0;
                for i in 0..NS {
                    let e = h
                        * (E1 * k1[i]
                            + E3 * k3[i]
                            + E4 * k4[i]
                            + E5 * k5[i]
                            + E6 * k6[i]
                            + E7 * k7[i]);
                    let tol = atol * self.scale[i] + rtol * y[i].abs().max(y1[i].abs());
                    err = err.max(e.abs() / tol);
                }
                (y1, if err.is_finite() { err } else { f64::INFINITY })
            }
        }
    }

    /// Integrates `y` over `dt` (s) or until the field's event fires, whichever comes first.
    /// Returns the time advanced and whether it stopped at an event (then `y` is the first
    /// state found where the event has fired, within 2⁻⁶⁰ of the step of its exact instant).
    pub fn run<F: Field>(&mut self, f: &F, y: &mut State, dt: f64) -> (f64, bool) {
        if dt <= 0.0 || dt.is_nan() {
            return (0.0, false);
        }
        let h_min = dt * 1e-12;
        if self.h <= 0.0 || !self.h.is_finite() {
            self.h = dt;
        }
        let fixed = matches!(self.method, OdeMethod::Rk4 { .. });
        let mut t = 0.0;
        let mut n = 0;
        while t < dt && n < MAX_STEPS {
            n += 1;
            let rem = dt - t;
            let h = if fixed {
                match self.method {
                    OdeMethod::Rk4 { step_s } => step_s.min(rem),
                    OdeMethod::Dopri { .. } => rem,
                }
            } else {
                self.h.min(rem)
            };
            let h = if rem - h < h_min { rem } else { h };
            let (y1, err) = self.step(f, y, h);
            if !fixed {
                let fac = if err == 0.0 {
                    5.0
                } else {
                    (0.9 * libm::pow(err, -0.2)).clamp(0.2, 5.0)
                };
                if err > 1.0 && h > h_min {
                    self.stats.rejected += 1;
                    self.h = (h * fac).max(h_min);
                    continue;
                }
                // A step clipped to the end of the interval keeps the step-size memory.
                if !(h < self.h && fac >= 1.0) {
                    self.h = h * fac;
                }
            }
            if f.fired(&y1) {
                // Bisect on the step length: lo not fired, hi fired.
                let (mut lo, mut hi, mut yh) = (0.0, h, y1);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    let (ym, _) = self.step(f, y, mid);
                    if f.fired(&ym) {
                        hi = mid;
                        yh = ym;
                    } else {
                        lo = mid;
                    }
                }
                *y = yh;
                self.stats.steps += 1;
                self.stats.events += 1;
                return (t + hi, true);
            }
            *y = y1;
            self.stats.steps += 1;
            t += h;
        }
        (t, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ẋ = v, v̇ = −x: a harmonic oscillator; event when x < 0.
    struct Osc;
    impl Field for Osc {
        fn rhs(&self, y: &State, dy: &mut State) {
            *dy = [y[1], -y[0], 0.0, 0.0, 0.0, 0.0];
        }
        fn fired(&self, y: &State) -> bool {
            y[0] < 0.0
        }
    }

    #[test]
    fn dopri_and_rk4_follow_the_oscillator_and_locate_the_crossing() {
        for m in [
            OdeMethod::Dopri {
                rtol: 1e-12,
                atol: 1e-12,
            },
            OdeMethod::Rk4 { step_s: 1e-3 },
        ] {
            let mut s = Stepper::new(m, [1.0; NS]);
            let mut y = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
            let (t, ev) = s.run(&Osc, &mut y, 1.0);
            assert!(!ev);
            assert!((t - 1.0).abs() < 1e-12);
            assert!((y[0] - libm::cos(1.0)).abs() < 1e-10, "{m:?} {}", y[0]);
            let (t2, ev) = s.run(&Osc, &mut y, 2.0);
            assert!(ev);
            assert!(
                (1.0 + t2 - core::f64::consts::FRAC_PI_2).abs() < 1e-10,
                "{m:?}"
            );
        }
    }
}
