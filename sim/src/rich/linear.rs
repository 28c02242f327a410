//! The exact engine of a plant that is linear between events: a compliant transmission, a
//! hand, an amplifier filter (with its output clamp), viscous and Coulomb friction with a
//! static/dynamic switch — everything of [`crate::rich`] except cogging and Stribeck decay.
//!
//! Units: SI (m, m/s, N, s; rotary: rad, rad/s, N·m), the state y = [x₁, v₁, x₂, v₂, p, ṗ] of
//! [`crate::rich::plant`].
//!
//! **Why it is exact.** In each mode — motor sliding forward, backward or stuck (`slide` = ±1,
//! 0), amplifier output inside its range or clamped at ±limit (`clamp` = 0, ±1) — and for a
//! held command u, the field of [`crate::rich::plant`] is affine, ẏ = A y + g. With the
//! augmented state z = [y, 1, u] it is ż = M z, so z(t) = e^{Mt} z(0): the matrix exponential of
//! the augmented M is the closed-form solution (computed by scaling and squaring of its Taylor
//! series on a balanced M, accurate to a few ulps of the state). Events end a mode: the motor
//! velocity reaching zero while sliding, |f_ext| exceeding the breakaway force F_s while stuck,
//! the filter output crossing ±limit (either way). They are linear functionals of z, so each is
//! located on the closed form itself: the interval is cut into sub-steps no longer than half
//! the fastest time constant (1/ρ, ρ the largest natural frequency or damping rate), an event
//! is detected at a sub-step end, and its instant found by the Illinois variant of regula falsi
//! on the closed form inside the sub-step (its Taylor series in τ, which converges at least as
//! 2^{-k}/k! there) to the last bits of τ. The stick rule is [`crate::rich::friction::stick_rule`].
//! The one approximation left: two zero crossings of an event function inside one sub-step
//! (a graze) go unseen, as with any sampled event detector.
//!
//! Invariants: no allocation, no panic, at most [`crate::rich::plant::MAX_EVENTS`] mode switches
//! per call (the caller's Zeno guard); a non-finite state is never produced from finite inputs.

// Dense 7×7 matrix arithmetic reads as its index formulas; iterator chains would hide them.
#![allow(clippy::needless_range_loop)]

/// Augmented dimension: the six states, the constant 1 and the held command u (constant over
/// an interval), so that a mode's transition matrix does not depend on u and is cached.
const N: usize = 8;
/// An 8×8 matrix, row-major.
type Mat = [[f64; N]; N];

/// The plant's constants the engine needs (from the model).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearPlant {
    /// 1/m₁ (motor side; with the hand's mass without a transmission), 1/kg.
    pub inv_m1: f64,
    /// 1/m₂ (link with the hand's mass), 1/kg.
    pub inv_m2: f64,
    /// Viscous friction of the motor, N·s/m.
    pub b: f64,
    /// Dynamic (sliding) Coulomb friction, N.
    pub c: f64,
    /// Breakaway force F_s ≥ c, N.
    pub fs: f64,
    /// Transmission stiffness and damping (0 without one), N/m, N·s/m.
    pub kt: f64,
    /// Transmission damping, N·s/m.
    pub dt: f64,
    /// Whether there is a transmission.
    pub trans: bool,
    /// Hand spring and damper (anchored at 0), N/m, N·s/m.
    pub kh: f64,
    /// Hand damping, N·s/m.
    pub bh: f64,
    /// Filter natural frequency ω, rad/s, and damping ζ (ω = 0: no filter).
    pub amp_w: f64,
    /// Filter damping ζ.
    pub amp_z: f64,
    /// Output clamp of the filter, N (∞ without a limit).
    pub limit: f64,
    /// Position scale for balancing (the encoder resolution), m.
    pub pos_scale: f64,
    /// Force scale for balancing (max(F_s, 1 mN)), N.
    pub force_scale: f64,
    /// Lower end stop, m (−∞ without travel).
    pub stop_lo: f64,
    /// Upper end stop, m (+∞ without travel).
    pub stop_hi: f64,
    /// End-stop stiffness (0 without travel), N/m.
    pub stop_k: f64,
    /// End-stop damping, N·s/m.
    pub stop_d: f64,
}

impl LinearPlant {
    /// Net non-friction, non-viscous force on the motor at y for the shaped command u: the
    /// actuator's force, then `extra` (the rich plant's cogging; 0 here), then the spring and
    /// damper of the transmission, or of the hand without one. The one definition of `f_ext`
    /// for every engine of [`crate::rich::RichPlant`].
    #[inline]
    #[must_use]
    pub fn f_ext(&self, y: &[f64; 6], u: f64, extra: f64) -> f64 {
        let mut f = if self.amp_w > 0.0 {
            y[4].clamp(-self.limit, self.limit)
        } else {
            u
        };
        f += extra + self.stop_force(y[0], y[1]);
        if self.trans {
            f += self.kt * (y[2] - y[0]) + self.dt * (y[3] - y[1]);
        } else {
            f -= self.kh * y[0] + self.bh * y[1];
        }
        f
    }

    /// The end stops' contact force at motor position x and velocity v (0 inside the travel;
    /// only pushing back: [`crate::rich::Travel::contact_force_n`]).
    #[inline]
    #[must_use]
    pub fn stop_force(&self, x: f64, v: f64) -> f64 {
        if x > self.stop_hi {
            -(self.stop_k * (x - self.stop_hi) + self.stop_d * v).max(0.0)
        } else if x < self.stop_lo {
            (self.stop_k * (self.stop_lo - x) - self.stop_d * v).max(0.0)
        } else {
            0.0
        }
    }

    /// The contact functions of the two stops at (x, v): g > 0 exactly while that stop pushes
    /// (past it and its spring and damper pushing back), continuous in (x, v).
    #[inline]
    fn contact_g(&self, x: f64, v: f64) -> (f64, f64) {
        let hi = (x - self.stop_hi).min(self.stop_k * (x - self.stop_hi) + self.stop_d * v);
        let lo = (self.stop_lo - x).min(self.stop_k * (self.stop_lo - x) - self.stop_d * v);
        (lo, hi)
    }

    /// The contact mode at (x, v): +1 the upper stop pushes, −1 the lower one, 0 none.
    #[inline]
    #[must_use]
    pub fn contact_of(&self, x: f64, v: f64) -> f64 {
        if self.stop_k <= 0.0 {
            return 0.0;
        }
        let (lo, hi) = self.contact_g(x, v);
        if hi > 0.0 {
            1.0
        } else if lo > 0.0 {
            -1.0
        } else {
            0.0
        }
    }
}

/// A mode of the piecewise-affine field: the motor sliding forward, backward or stuck
/// (`slide` ±1, 0), the filter output inside its range or clamped (`clamp` 0, ±1), the motor
/// free or against the upper or lower end stop (`contact` 0, ±1).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Mode {
    slide: f64,
    clamp: f64,
    contact: f64,
}

/// One cached transition matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Cached {
    slide: f64,
    clamp: f64,
    contact: f64,
    h: f64,
    e: Mat,
}

/// The engine: the plant's constants and a small cache of sub-step transition matrices.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Linear {
    p: LinearPlant,
    /// Fastest rate ρ, 1/s.
    rho: f64,
    cache: [Option<Cached>; 6],
    next: usize,
}

fn mat_mul(a: &Mat, b: &Mat) -> Mat {
    let mut o = [[0.0; N]; N];
    for i in 0..N {
        for k in 0..N {
            let aik = a[i][k];
            if aik != 0.0 {
                for j in 0..N {
                    o[i][j] += aik * b[k][j];
                }
            }
        }
    }
    o
}

fn mat_vec(a: &Mat, z: &[f64; N]) -> [f64; N] {
    let mut o = [0.0; N];
    for i in 0..N {
        let mut s = 0.0;
        for j in 0..N {
            s += a[i][j] * z[j];
        }
        o[i] = s;
    }
    o
}

// Written here rather than taken from a crate: this crate is no_std without an allocator and
// is checked for the Cortex-M target; nalgebra's matrix exponential (the host uses nalgebra for
// least squares) would bring a large dependency into the simulator for one fixed 8×8 case.
/// e^{A} by scaling and squaring of the Taylor series (the scaled norm ≤ ½, 18 terms: the
/// truncation error is below 2⁻¹⁹/19! of the scaled norm).
fn expm(a: &Mat) -> Mat {
    let mut norm: f64 = 0.0;
    for j in 0..N {
        let col: f64 = (0..N).map(|i| a[i][j].abs()).sum();
        norm = norm.max(col);
    }
    let mut s = 0u32;
    let mut scale = 1.0;
    while norm * scale > 0.5 && s < 1100 {
        scale *= 0.5;
        s += 1;
    }
    let mut x = *a;
    for row in &mut x {
        for v in row.iter_mut() {
            *v *= scale;
        }
    }
    let mut e = [[0.0; N]; N];
    let mut term = [[0.0; N]; N];
    for i in 0..N {
        e[i][i] = 1.0;
        term[i][i] = 1.0;
    }
    for k in 1..=18 {
        term = mat_mul(&term, &x);
        let inv = 1.0 / f64::from(k);
        for row in &mut term {
            for v in row.iter_mut() {
                *v *= inv;
            }
        }
        for i in 0..N {
            for j in 0..N {
                e[i][j] += term[i][j];
            }
        }
    }
    for _ in 0..s {
        e = mat_mul(&e, &e);
    }
    e
}

/// Terms of the Taylor series of the closed form over a sub-step:
/// z(s·len) = Σ_k s^k w_k, w_k = (M·len)^k z₀ / k!. A sub-step is at most ½/ρ, so the terms
/// fall at least as 2^{-k}/k!: [`TAYLOR_TERMS`] of them are exact to rounding.
fn taylor_terms(m: &Mat, z0: &[f64; N], len: f64) -> [[f64; N]; TAYLOR_TERMS] {
    let mut w = [[0.0; N]; TAYLOR_TERMS];
    w[0] = *z0;
    for k in 1..TAYLOR_TERMS {
        let mut next = mat_vec(m, &w[k - 1]);
        let f = len / k as f64;
        for v in &mut next {
            *v *= f;
        }
        w[k] = next;
    }
    w
}

/// The series of [`taylor_terms`] at s ∈ [0, 1] (Horner).
fn taylor_at(w: &[[f64; N]; TAYLOR_TERMS], s: f64) -> [f64; N] {
    let mut z = w[TAYLOR_TERMS - 1];
    for k in (0..TAYLOR_TERMS - 1).rev() {
        for i in 0..N {
            z[i] = z[i] * s + w[k][i];
        }
    }
    z
}

/// Terms of the in-sub-step Taylor series.
const TAYLOR_TERMS: usize = 26;

impl Linear {
    /// The engine for a plant's constants.
    #[must_use]
    pub fn new(p: LinearPlant) -> Self {
        let m_hand = if p.trans { p.inv_m2 } else { p.inv_m1 };
        let rates = [
            libm::sqrt(p.kt * (p.inv_m1 + p.inv_m2)),
            libm::sqrt(p.kh * m_hand),
            p.amp_w,
            (p.b + p.dt + if p.trans { 0.0 } else { p.bh }) * p.inv_m1,
            (p.dt + p.bh) * p.inv_m2,
            2.0 * p.amp_z * p.amp_w,
            libm::sqrt(p.stop_k * p.inv_m1),
            p.stop_d * p.inv_m1,
        ];
        let rho = rates
            .iter()
            .copied()
            .filter(|r| r.is_finite())
            .fold(0.0, f64::max);
        Self {
            p,
            rho,
            cache: [None; 6],
            next: 0,
        }
    }

    /// Balancing scales of the state: Δ, Δρ, Δ, Δρ, F, Fρ, 1, F.
    fn scales(&self) -> [f64; N] {
        let r = self.rho.max(1.0);
        let (x, f) = (self.p.pos_scale, self.p.force_scale);
        [x, x * r, x, x * r, f, f * r, 1.0, f]
    }

    /// The augmented matrix M of a mode (column 6: constant terms; column 7: the command's);
    /// `contact` ±1: the upper (lower) end stop's spring and damper act on the motor.
    fn matrix(&self, slide: f64, clamp: f64, contact: f64) -> Mat {
        let p = &self.p;
        let mut m = [[0.0; N]; N];
        let filter = p.amp_w > 0.0;
        if slide != 0.0 {
            m[0][1] = 1.0;
            let k = p.inv_m1;
            if filter {
                if clamp == 0.0 {
                    m[1][4] += k;
                } else {
                    m[1][6] += clamp * p.limit * k;
                }
            } else {
                m[1][7] += k;
            }
            if p.trans {
                m[1][0] -= p.kt * k;
                m[1][2] += p.kt * k;
                m[1][1] -= p.dt * k;
                m[1][3] += p.dt * k;
            } else {
                m[1][0] -= p.kh * k;
                m[1][1] -= p.bh * k;
            }
            m[1][1] -= p.b * k;
            m[1][6] -= slide * p.c * k;
            if contact != 0.0 {
                let bound = if contact > 0.0 { p.stop_hi } else { p.stop_lo };
                m[1][0] -= p.stop_k * k;
                m[1][1] -= p.stop_d * k;
                m[1][6] += p.stop_k * bound * k;
            }
        }
        if p.trans {
            let k = p.inv_m2;
            m[2][3] = 1.0;
            m[3][0] += p.kt * k;
            m[3][2] -= (p.kt + p.kh) * k;
            m[3][3] -= (p.dt + p.bh) * k;
            if slide != 0.0 {
                m[3][1] += p.dt * k;
            }
        }
        if filter {
            let w = p.amp_w;
            m[4][5] = 1.0;
            m[5][4] = -w * w;
            m[5][5] = -2.0 * p.amp_z * w;
            m[5][7] = w * w;
        }
        m
    }

    /// e^{Mh} of a mode, balanced (D⁻¹ M D with the state scales) for accuracy, cached.
    fn transition(&mut self, slide: f64, clamp: f64, contact: f64, h: f64) -> Mat {
        for c in self.cache.iter().flatten() {
            if c.slide == slide && c.clamp == clamp && c.contact == contact && c.h == h {
                return c.e;
            }
        }
        let m = self.matrix(slide, clamp, contact);
        let d = self.scales();
        let mut a = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                a[i][j] = m[i][j] * h * d[j] / d[i];
            }
        }
        let eb = expm(&a);
        let mut e = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                e[i][j] = eb[i][j] * d[i] / d[j];
            }
        }
        self.cache[self.next] = Some(Cached {
            slide,
            clamp,
            contact,
            h,
            e,
        });
        self.next = (self.next + 1) % self.cache.len();
        e
    }

    /// The clamp mode of a filter output p.
    fn clamp_of(&self, p4: f64) -> f64 {
        if self.p.amp_w > 0.0 && p4 > self.p.limit {
            1.0
        } else if self.p.amp_w > 0.0 && p4 < -self.p.limit {
            -1.0
        } else {
            0.0
        }
    }

    /// The event function of a mode at z: fired when > 0 (≥ 0 for the slide's zero crossing
    /// and a stop's release).
    fn event(&self, m: Mode, u: f64, z: &[f64; N]) -> (f64, bool) {
        let Mode {
            slide,
            clamp,
            contact,
        } = m;
        let mut worst = f64::NEG_INFINITY;
        let mut fired = false;
        if self.p.stop_k > 0.0 && slide != 0.0 {
            let (lo, hi) = self.p.contact_g(z[0], z[1]);
            let phi = if contact > 0.0 {
                -hi
            } else if contact < 0.0 {
                -lo
            } else {
                lo.max(hi)
            };
            worst = worst.max(phi);
            fired |= if contact == 0.0 {
                phi > 0.0
            } else {
                phi >= 0.0
            };
        }
        if slide != 0.0 {
            let phi = -slide * z[1];
            worst = worst.max(phi);
            fired |= phi >= 0.0;
        } else {
            let mut y = [0.0; 6];
            y.copy_from_slice(&z[..6]);
            let f = self.p.f_ext(&y, u, 0.0);
            let phi = f.abs() - self.p.fs;
            worst = worst.max(phi);
            fired |= phi > 0.0;
        }
        if self.p.amp_w > 0.0 && self.p.limit.is_finite() {
            let phi = if clamp == 0.0 {
                z[4].abs() - self.p.limit
            } else {
                self.p.limit - clamp * z[4]
            };
            worst = worst.max(phi);
            fired |= phi > 0.0;
        }
        (worst, fired)
    }

    /// Advances y over `dt_s` with the shaped command u from the mode `slide`; returns the
    /// mode at the end. At most `max_events` mode switches, then the rest is skipped.
    pub fn advance(
        &mut self,
        y: &mut [f64; 6],
        slide: &mut f64,
        u: f64,
        dt_s: f64,
        max_events: u32,
    ) {
        let subs = self.substeps(dt_s);
        let h = dt_s / subs;
        let mut z = self.augmented(y, u);
        let mut mode = Mode {
            slide: *slide,
            clamp: self.clamp_of(z[4]),
            contact: self.p.contact_of(z[0], z[1]),
        };
        let mut t = 0.0;
        let mut events = 0;
        // The sub-step grid is fixed from the start of the interval; after an event the step
        // to the next grid point is taken with its own length.
        let mut k = 0.0;
        // On the grid (no event since the last grid point) a sub-step is exactly h, so its
        // cached transition matrix applies; after an event the rest of the sub-step is taken
        // with the Taylor series of the closed form (shorter than ½/ρ, so it converges).
        let mut aligned = true;
        while k < subs && events <= max_events {
            let t_next = if k + 1.0 >= subs { dt_s } else { (k + 1.0) * h };
            let step = if aligned { h } else { t_next - t };
            if step <= 0.0 {
                k += 1.0;
                aligned = true;
                continue;
            }
            let z1 = if aligned {
                let e = self.transition(mode.slide, mode.clamp, mode.contact, step);
                mat_vec(&e, &z)
            } else {
                let w = taylor_terms(&self.matrix(mode.slide, mode.clamp, mode.contact), &z, step);
                taylor_at(&w, 1.0)
            };
            let (_, fired) = self.event(mode, u, &z1);
            if !fired {
                z = z1;
                t = t_next;
                k += 1.0;
                aligned = true;
                continue;
            }
            aligned = false;
            // Locate the event on the closed form: lo not fired, hi fired.
            let (tau, zh) = self.locate(mode, u, &z, step, &z1);
            z = zh;
            t += tau;
            events += 1;
            self.switch_slide(&mut z, &mut mode.slide, u);
            mode.clamp = self.clamp_of(z[4]);
            mode.contact = self.p.contact_of(z[0], z[1]);
            if t >= t_next {
                k += 1.0;
                aligned = true;
            }
        }
        *slide = mode.slide;
        self.store(z, y);
    }

    /// Sub-steps of an interval of `dt_s`: none longer than ½/ρ (at least 1, at most 10⁶).
    #[inline]
    fn substeps(&self, dt_s: f64) -> f64 {
        if self.rho > 0.0 {
            libm::ceil(dt_s * self.rho / 0.5).clamp(1.0, 1e6)
        } else {
            1.0
        }
    }

    /// The augmented state z = [y, 1, u] (without a transmission the link follows the motor).
    #[inline]
    fn augmented(&self, y: &[f64; 6], u: f64) -> [f64; N] {
        let mut z = [y[0], y[1], y[2], y[3], y[4], y[5], 1.0, u];
        if !self.p.trans {
            z[2] = z[0];
            z[3] = z[1];
        }
        z
    }

    /// The motor's mode after an event at z: a slide whose velocity reached zero stops there
    /// and sticks or slides on by the stick rule, as does a stuck motor.
    #[inline]
    fn switch_slide(&self, z: &mut [f64; N], slide: &mut f64, u: f64) {
        let fs = self.p.fs;
        let mut yy = [0.0; 6];
        yy.copy_from_slice(&z[..6]);
        if *slide != 0.0 && *slide * z[1] <= 0.0 {
            z[1] = 0.0;
            yy[1] = 0.0;
            *slide = super::friction::stick_rule(self.p.f_ext(&yy, u, 0.0), fs);
        } else if *slide == 0.0 {
            *slide = super::friction::stick_rule(self.p.f_ext(&yy, u, 0.0), fs);
        }
    }

    /// Writes z's state back to y (without a transmission the link follows the motor), unless
    /// it is not finite.
    #[inline]
    fn store(&self, mut z: [f64; N], y: &mut [f64; 6]) {
        if !self.p.trans {
            z[2] = z[0];
            z[3] = z[1];
        }
        if z[..6].iter().all(|v| v.is_finite()) {
            y.copy_from_slice(&z[..6]);
        }
    }

    /// The first instant in (0, step] where the mode's event fires from z0, and the state
    /// there (on the fired side): Illinois regula falsi on the closed form, bisection when the
    /// secant is of no use.
    fn locate(
        &mut self,
        mode: Mode,
        u: f64,
        z0: &[f64; N],
        step: f64,
        z_hi: &[f64; N],
    ) -> (f64, [f64; N]) {
        // The closed form inside the sub-step as its Taylor series (no matrix exponential per
        // iteration).
        let w = taylor_terms(&self.matrix(mode.slide, mode.clamp, mode.contact), z0, step);
        let at = |tau: f64| taylor_at(&w, tau / step);
        let (f_lo, _) = self.event(mode, u, z0);
        let (f_hi, _) = self.event(mode, u, z_hi);
        let this = &*self;
        crate::math::illinois(
            0.0,
            step,
            f_lo,
            f_hi,
            *z_hi,
            4.0 * f64::EPSILON * step,
            |tau| {
                let z = at(tau);
                let (f, fired) = this.event(mode, u, &z);
                (f, fired, z)
            },
        )
    }
}
