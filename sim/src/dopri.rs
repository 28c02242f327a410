//! The one Dormand–Prince 5(4) stepper of the crate (and the classical RK4 step beside it),
//! generic over the state dimension `N` (`[f64; N]`), with event location on re-taken partial
//! steps. Users: [`crate::reference`] (the dimensionless reference integrator, N = 7) and
//! [`crate::rich`] (the rich plant, N = 6).
//!
//! Units: whatever the vector field uses (the reference: sampling periods; the rich plant: SI,
//! s, m, m/s, N). The error of a Dormand–Prince step is max_i |err_i| / (atol·scale_i +
//! rtol·max(|y_i|, |y1_i|)) ([`dopri_step`]; the reference passes scale_i = 1, so its `atol` is
//! absolute; the rich plant passes the encoder resolution and force units, so its `atol` is
//! dimensionless), a non-finite error counting as +∞. The step-size factor after a step is
//! [`step_factor`]: 0.9·err^(−1/5) clamped to [0.2, 5] (5 for a zero error).
//!
//! Layers: [`dopri_step`], [`rk4_step`] and [`step_factor`] are the shared kernel (tableau,
//! stages, error norm, controller law). [`Stepper::run`] is the driver for a [`Field`] whose
//! event is a yes/no predicate (bisection on the step length, the rich plant); the reference
//! keeps its own segment driver on the same kernel (its event is a signed function located by
//! Illinois regula falsi, with sticking modes and a step cap after an unbracketable event).
//! Both drivers are exactly the arithmetic they had before they shared this module: results
//! are bit-for-bit those of the two former steppers. The only surviving difference is the
//! rounding of RK4's weighted sum ([`Rk4Form`]), kept because plant and scene results depend
//! on it to the last bit.
//!
//! Invariants: no allocation; every call of [`Stepper::run`] ends (at most [`MAX_STEPS`]
//! accepted or rejected steps, 60 bisections per event, a minimum step of 1e-12 of the
//! requested interval below which a step is accepted whatever its error); the state stays
//! finite when the field is finite.

/// Maximum number of steps of one [`Stepper::run`] call.
pub const MAX_STEPS: u32 = 1_000_000;

// Dormand–Prince 5(4) tableau (the nodes c_i are not needed: both users' fields are
// autonomous between events, the held input being constant).
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

/// y + h·Σ c_j k_j (the sum accumulated from 0 in the order given; fully unrolled).
#[inline(always)]
pub fn comb<const N: usize, const K: usize>(
    y: &[f64; N],
    h: f64,
    c: [f64; K],
    k: [&[f64; N]; K],
) -> [f64; N] {
    let mut out = *y;
    for i in 0..N {
        let mut s = 0.0;
        for j in 0..K {
            s += c[j] * k[j][i];
        }
        out[i] += h * s;
    }
    out
}

/// Error-control tolerances of a Dormand–Prince step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance<const N: usize> {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance, in units of `scale`.
    pub atol: f64,
    /// Unit of the absolute tolerance per component (> 0).
    pub scale: [f64; N],
}

/// One Dormand–Prince 5(4) step of length h from y: the 5th-order solution and, with `tol`,
/// the error norm of the module header (0 without `tol`, which saves the 7th evaluation).
#[inline]
pub fn dopri_step<const N: usize>(
    f: &mut impl FnMut(&[f64; N]) -> [f64; N],
    y: &[f64; N],
    h: f64,
    tol: Option<&Tolerance<N>>,
) -> ([f64; N], f64) {
    let k1 = f(y);
    let k2 = f(&comb(y, h, [A21], [&k1]));
    let k3 = f(&comb(y, h, [A31, A32], [&k1, &k2]));
    let k4 = f(&comb(y, h, [A41, A42, A43], [&k1, &k2, &k3]));
    let k5 = f(&comb(y, h, [A51, A52, A53, A54], [&k1, &k2, &k3, &k4]));
    let k6 = f(&comb(
        y,
        h,
        [A61, A62, A63, A64, A65],
        [&k1, &k2, &k3, &k4, &k5],
    ));
    let y1 = comb(y, h, [B1, B3, B4, B5, B6], [&k1, &k3, &k4, &k5, &k6]);
    let Some(tol) = tol else {
        return (y1, 0.0);
    };
    let k7 = f(&y1);
    let mut err: f64 = 0.0;
    for i in 0..N {
        let e = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
        let sc = tol.atol * tol.scale[i] + tol.rtol * y[i].abs().max(y1[i].abs());
        err = err.max(e.abs() / sc);
    }
    (y1, if err.is_finite() { err } else { f64::INFINITY })
}

/// The rounding of RK4's stages and weighted sum (the same method; results differ in the
/// last bits, and each user keeps the one its results were produced with).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rk4Form {
    /// Stages y + h·(½k), sum y + h·(k₁/6 + k₂/3 + k₃/3 + k₄/6) (the reference).
    Fractions,
    /// Stages y + (h/2)·k, sum y + (h/6)·(k₁ + 2k₂ + 2k₃ + k₄) (the rich plant).
    Integers,
}

/// One classical RK4 step of length h from y.
#[inline]
pub fn rk4_step<const N: usize>(
    f: &mut impl FnMut(&[f64; N]) -> [f64; N],
    y: &[f64; N],
    h: f64,
    form: Rk4Form,
) -> [f64; N] {
    let k1 = f(y);
    match form {
        Rk4Form::Fractions => {
            let k2 = f(&comb(y, h, [0.5], [&k1]));
            let k3 = f(&comb(y, h, [0.5], [&k2]));
            let k4 = f(&comb(y, h, [1.0], [&k3]));
            let w = [1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0];
            comb(y, h, w, [&k1, &k2, &k3, &k4])
        }
        Rk4Form::Integers => {
            let k2 = f(&comb(y, 0.5 * h, [1.0], [&k1]));
            let k3 = f(&comb(y, 0.5 * h, [1.0], [&k2]));
            let k4 = f(&comb(y, h, [1.0], [&k3]));
            comb(y, h / 6.0, [1.0, 2.0, 2.0, 1.0], [&k1, &k2, &k3, &k4])
        }
    }
}

/// Step-size factor after a step of error norm `err`: 0.9·err^(−1/5) in [0.2, 5], 5 for 0.
#[inline]
#[must_use]
pub fn step_factor(err: f64) -> f64 {
    if err == 0.0 {
        5.0
    } else {
        (0.9 * libm::pow(err, -0.2)).clamp(0.2, 5.0)
    }
}

/// A vector field with a mode-switching event (the driver of [`Stepper::run`]).
pub trait Field<const N: usize> {
    /// dy/dt at y.
    fn rhs(&self, y: &[f64; N], dy: &mut [f64; N]);
    /// Whether the event has happened at y (the current mode no longer holds).
    fn fired(&self, y: &[f64; N]) -> bool;
}

/// Integration method of a [`Stepper`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OdeMethod {
    /// Classical RK4 with steps of at most `step_s`.
    Rk4 {
        /// Step length in the field's time unit (s for the rich plant), > 0.
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
pub struct Stepper<const N: usize> {
    method: OdeMethod,
    /// Absolute-tolerance scale per component.
    pub scale: [f64; N],
    h: f64,
    /// Work counters.
    pub stats: OdeStats,
}

impl<const N: usize> Stepper<N> {
    /// A stepper; `scale` is the absolute-tolerance unit of each component (> 0).
    #[must_use]
    pub fn new(method: OdeMethod, scale: [f64; N]) -> Self {
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
    fn step<F: Field<N>>(&mut self, f: &F, y: &[f64; N], h: f64) -> ([f64; N], f64) {
        let mut rhs = |y: &[f64; N]| {
            let mut dy = [0.0; N];
            f.rhs(y, &mut dy);
            dy
        };
        match self.method {
            OdeMethod::Rk4 { .. } => {
                self.stats.rhs_evals += 4;
                (rk4_step(&mut rhs, y, h, Rk4Form::Integers), 0.0)
            }
            OdeMethod::Dopri { rtol, atol } => {
                self.stats.rhs_evals += 7;
                let tol = Tolerance {
                    rtol,
                    atol,
                    scale: self.scale,
                };
                dopri_step(&mut rhs, y, h, Some(&tol))
            }
        }
    }

    /// Integrates `y` over `dt` or until the field's event fires, whichever comes first.
    /// Returns the time advanced and whether it stopped at an event (then `y` is the first
    /// state found where the event has fired, within 2⁻⁶⁰ of the step of its exact instant).
    pub fn run<F: Field<N>>(&mut self, f: &F, y: &mut [f64; N], dt: f64) -> (f64, bool) {
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
            let h = match self.method {
                OdeMethod::Rk4 { step_s } => step_s.min(rem),
                OdeMethod::Dopri { .. } => self.h.min(rem),
            };
            let h = if rem - h < h_min { rem } else { h };
            let (y1, err) = self.step(f, y, h);
            if !fixed {
                let fac = step_factor(err);
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
                let (hi, yh) = self.bisect(f, y, h, y1);
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

    /// Bisects on the step length from y (not fired at 0, fired at h with state y_h): the
    /// first fired length found and its state.
    fn bisect<F: Field<N>>(
        &mut self,
        f: &F,
        y: &[f64; N],
        h: f64,
        y_h: [f64; N],
    ) -> (f64, [f64; N]) {
        let (mut lo, mut hi, mut yh) = (0.0, h, y_h);
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
        (hi, yh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ẋ = v, v̇ = −x: a harmonic oscillator; event when x < 0.
    struct Osc;
    impl Field<6> for Osc {
        fn rhs(&self, y: &[f64; 6], dy: &mut [f64; 6]) {
            *dy = [y[1], -y[0], 0.0, 0.0, 0.0, 0.0];
        }
        fn fired(&self, y: &[f64; 6]) -> bool {
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
            let mut s = Stepper::new(m, [1.0; 6]);
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

    #[test]
    fn the_two_rk4_roundings_agree_to_rounding_and_the_error_norm_is_scaled() {
        let mut f = |y: &[f64; 2]| [y[1], -y[0]];
        let y = [1.0, 0.0];
        let a = rk4_step(&mut f, &y, 0.1, Rk4Form::Fractions);
        let b = rk4_step(&mut f, &y, 0.1, Rk4Form::Integers);
        assert!((a[0] - b[0]).abs() < 1e-15 && (a[1] - b[1]).abs() < 1e-15);
        let tol = |s: f64| Tolerance {
            rtol: 0.0,
            atol: 1e-9,
            scale: [s; 2],
        };
        let (_, e1) = dopri_step(&mut f, &y, 0.5, Some(&tol(1.0)));
        let (_, e2) = dopri_step(&mut f, &y, 0.5, Some(&tol(2.0)));
        assert!(e1 > 0.0 && (e1 / e2 - 2.0).abs() < 1e-12);
        assert_eq!(dopri_step(&mut f, &y, 0.5, None).1, 0.0);
    }
}
