//! Reference integrators: fixed-step classical RK4 and adaptive Dormand–Prince 5(4), with event
//! location by a bracketing root finder (Illinois regula falsi on re-taken partial steps). The
//! steps, the error norm (scale 1: `atol` is absolute) and the step-size law are those of
//! [`crate::dopri`]; this module keeps the segment driver (modes, events, step cap).
//!
//! Units: dimensionless (Table I). State y = [ξ, ξ̇, p, q, E_d, W_A, W_H]: position, velocity,
//! amplifier filter output p = φ_A and its derivative q, and three energy quadratures (dissipated
//! energy (28), work of the actuator ∫φ_A ξ̇, work of the hand ∫φ_H ξ̇).
//!
//! Honest about sgn(0): the friction sign is a *mode* fixed between events, never sgn of a stage
//! value. Modes: moving with s = ±1, or stuck. Events: the velocity crosses zero while moving
//! (then the stick–slip rule of [`crate::plant`] picks the next mode), the net force |φ_A + φ_H|
//! exceeds σ while stuck (only possible with the amplifier filter), and the segment ends (sample
//! instants and delayed force switches, where the rule is re-applied to a mass at rest).
//!
//! Extra effects beyond the exact solver: a second-order amplifier filter
//! p̈ + 2ζω ṗ + ω² p = ω² u, a hand (added mass μ_h, damping β_h, stiffness κ_h: φ_H = −κ_h ξ − β_h
//! ξ̇), and a continuous spring without sampling (`zoh = false`, no delay allowed).
//!
//! Invariants: every step is finite-length (≥ 1e-14 periods or the segment end), the root
//! finder is bounded to 100 iterations, so the run always terminates; no allocation.

use crate::dopri::{dopri_step, rk4_step, step_factor, Rk4Form, Tolerance};
use crate::exact::{potential, ExactSim, History, PeriodAudit};
use crate::math::floor_fast;
use crate::params::{validate, Effects, ParamError, Params};
use crate::plant::Motion;
use stiffwall_core::params::{check_non_negative, check_positive, check_range};

const N: usize = 7;
type Y = [f64; N];
const LINE: usize = 256;
const MASK: u64 = LINE as u64 - 1;

/// Integration method.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "std", serde(rename_all = "snake_case", tag = "kind"))]
pub enum Method {
    /// Classical RK4 with a fixed number of steps per sampling period.
    Rk4 {
        /// Steps per period (≥ 1).
        steps_per_period: u32,
    },
    /// Dormand–Prince 5(4) with error control.
    Dopri {
        /// Relative tolerance.
        rtol: f64,
        /// Absolute tolerance.
        atol: f64,
    },
}

/// Human hand in contact (dimensionless, Table I scaling).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct Hand {
    /// Added mass μ_h = m_h/(K T²).
    pub mu: f64,
    /// Damping β_h = b_h/(K T).
    pub beta: f64,
    /// Stiffness κ_h = k_h/K (spring to the anchor at ξ = 0).
    pub kappa: f64,
}

/// Second-order amplifier low-pass filter.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
pub struct AmpFilter {
    /// Cut-off ω_A·T (radians per period), > 0.
    pub omega: f64,
    /// Damping ratio δ_A, > 0.
    pub zeta: f64,
}

/// Model seen by the reference integrators.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefModel {
    /// μ, β, σ, τ_D.
    pub params: Params,
    /// Effects shared with the exact solver.
    pub effects: Effects,
    /// Sample-and-hold of the spring (otherwise the spring acts continuously, no delay).
    pub zoh: bool,
    /// Optional hand.
    pub hand: Option<Hand>,
    /// Optional amplifier filter.
    pub amp: Option<AmpFilter>,
    /// Delay-line history.
    pub history: History,
}

impl RefModel {
    /// The paper's model (7)–(9) with every effect of `effects`, no hand, no filter.
    #[must_use]
    pub fn paper(params: Params, effects: Effects) -> Self {
        Self {
            params,
            effects,
            zoh: true,
            hand: None,
            amp: None,
            history: History::HoldInitial,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Mode {
    Moving(f64),
    Stuck,
}

/// Work counters.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps (Dormand–Prince only).
    pub rejected: u64,
    /// Located events.
    pub events: u64,
}

/// A reference simulation (implements [`ExactSim`] so it plugs into the same tools).
#[derive(Debug, Clone)]
pub struct RefSim {
    m: RefModel,
    method: Method,
    y: Y,
    mode: Mode,
    mass: f64,
    beta: f64,
    own_beta: f64,
    sigma: f64,
    tau_d: f64,
    n: u64,
    frac: f64,
    line: [f64; LINE],
    h: u64,
    u: f64,
    dt: f64,
    stats: Stats,
    audit: PeriodAudit,
    rest_periods: u64,
    /// Dimensionless virtual damping β_v = B/(K·T) (0: no damper).
    beta_v: f64,
    /// Sampled count of the previous sample, n_(h−1).
    n_prev: f64,
}

/// The method's parameters: RK4 steps ≥ 1, Dormand–Prince tolerances > 0.
fn check_method(method: Method) -> Result<(), ParamError> {
    match method {
        Method::Rk4 { steps_per_period } => {
            check_range(
                "steps_per_period",
                f64::from(steps_per_period),
                1.0,
                false,
                f64::from(u32::MAX),
                ">= 1",
            )?;
        }
        Method::Dopri { rtol, atol } => {
            check_positive("rtol", rtol)?;
            check_positive("atol", atol)?;
        }
    }
    Ok(())
}

/// The effects beyond the exact solver, in this order: no delay without the sample-and-hold,
/// hand coefficients ≥ 0, amplifier filter cut-off and damping > 0.
fn check_model(model: &RefModel, tau_d: f64) -> Result<(), ParamError> {
    if !model.zoh {
        check_range(
            "tau_d",
            tau_d,
            0.0,
            false,
            0.0,
            "0 without the sample-and-hold (zoh = false)",
        )?;
    }
    if let Some(hand) = model.hand {
        check_non_negative("hand.mu", hand.mu)?;
        check_non_negative("hand.beta", hand.beta)?;
        check_non_negative("hand.kappa", hand.kappa)?;
    }
    if let Some(a) = model.amp {
        check_positive("amplifier.omega", a.omega)?;
        check_positive("amplifier.zeta", a.zeta)?;
    }
    Ok(())
}

impl RefSim {
    /// A reference simulation starting at τ = 0 in `init`.
    pub fn new(model: RefModel, method: Method, init: Motion) -> Result<Self, ParamError> {
        let p = model.params;
        validate(&p)?;
        check_method(method)?;
        let e = model.effects;
        let tau_d = if e.delay { p.tau_d } else { 0.0 };
        check_model(&model, tau_d)?;
        let mut mass = p.mu;
        let mut beta = if e.viscous { p.beta } else { 0.0 };
        if let Some(hand) = model.hand {
            mass += hand.mu;
            beta += hand.beta;
        }
        let n = libm::floor(tau_d);
        let mut s = Self {
            m: model,
            method,
            y: [0.0; N],
            mode: Mode::Stuck,
            mass,
            beta,
            own_beta: if e.viscous { p.beta } else { 0.0 },
            sigma: if e.coulomb { p.sigma } else { 0.0 },
            tau_d,
            n: n as u64,
            frac: tau_d - n,
            line: [0.0; LINE],
            h: 0,
            u: 0.0,
            dt: 0.1,
            stats: Stats::default(),
            audit: PeriodAudit::default(),
            rest_periods: 0,
            beta_v: 0.0,
            n_prev: 0.0,
        };
        s.n_prev = s.count(init.x);
        let hist = match model.history {
            History::HoldInitial => s.spring(init.x),
            History::Zero => 0.0,
        };
        s.line = [hist; LINE];
        s.u = hist;
        s.y[0] = init.x;
        s.y[1] = init.v;
        // The filter starts in steady state with the history force.
        s.y[2] = hist;
        s.mode = if init.v > 0.0 {
            Mode::Moving(1.0)
        } else if init.v < 0.0 {
            Mode::Moving(-1.0)
        } else {
            Mode::Stuck
        };
        Ok(s)
    }

    /// Work counters so far.
    #[must_use]
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Adds the virtual damper −β_v·(n_h − n_(h−1)) of the exact solver
    /// ([`crate::exact::Exact::with_beta_v`]: same law, n_(−1) = n_0, one-sided only in contact).
    ///
    /// # Errors
    /// [`ParamError`] naming `beta_v` unless β_v is finite and in [0, 1000].
    pub fn with_beta_v(mut self, beta_v: f64) -> Result<Self, ParamError> {
        self.beta_v = stiffwall_core::params::check_range(
            "beta_v",
            beta_v,
            0.0,
            false,
            crate::exact::MAX_BETA_V,
            "finite and in [0, 1000] (dimensionless B/(K*T))",
        )?;
        Ok(self)
    }

    /// Sampled count ⌊ξ⌋ (ξ without quantization).
    fn count(&self, xi: f64) -> f64 {
        if self.m.effects.quantization {
            floor_fast(xi)
        } else {
            xi
        }
    }

    /// Sampled law: spring plus damper (the spring alone when β_v = 0).
    fn law(&self, xi: f64) -> f64 {
        if self.beta_v == 0.0 {
            return self.spring(xi);
        }
        let n = self.count(xi);
        let spring = if self.m.effects.quantization {
            -n - 0.5
        } else {
            -n
        };
        if self.m.effects.one_sided && n < 0.0 {
            0.0
        } else {
            spring - self.beta_v * (n - self.n_prev)
        }
    }

    fn spring(&self, xi: f64) -> f64 {
        let e = self.m.effects;
        let f = if e.quantization {
            -floor_fast(xi) - 0.5
        } else {
            -xi
        };
        if e.one_sided {
            f.min(0.0)
        } else {
            f
        }
    }

    /// Force input u to the amplifier (held spring force, or continuous spring).
    #[inline]
    fn input(&self, y: &Y) -> f64 {
        if self.m.zoh {
            self.u
        } else {
            self.spring(y[0])
        }
    }

    #[inline]
    fn phi_a(&self, y: &Y) -> f64 {
        if self.m.amp.is_some() {
            y[2]
        } else {
            self.input(y)
        }
    }

    #[inline]
    fn phi_h(&self, y: &Y) -> f64 {
        match self.m.hand {
            Some(h) => -h.kappa * y[0] - h.beta * y[1],
            None => 0.0,
        }
    }

    #[inline]
    fn rhs(&self, y: &Y, mode: Mode) -> Y {
        let fa = self.phi_a(y);
        let fh = self.phi_h(y);
        let mut d = [0.0; N];
        if let Mode::Moving(s) = mode {
            let v = y[1];
            // The hand's damping is part of φ_H, so the device's own β is used for E_d.
            let own_beta = self.own_beta;
            d[0] = v;
            d[1] = (fa + fh - own_beta * v - self.sigma * s) / self.mass;
            d[4] = own_beta * v * v + self.sigma * s * v;
            d[5] = fa * v;
            d[6] = fh * v;
        }
        if let Some(a) = self.m.amp {
            let u = self.input(y);
            d[2] = y[3];
            d[3] = a.omega * a.omega * (u - y[2]) - 2.0 * a.zeta * a.omega * y[3];
        }
        d
    }

    /// One explicit step of size h from y ([`crate::dopri`]); returns (y1, error norm or 0).
    fn step(&mut self, y: &Y, h: f64, mode: Mode, want_err: bool) -> (Y, f64) {
        let mut evals = 0;
        let me = &*self;
        let mut f = |y: &Y| {
            evals += 1;
            me.rhs(y, mode)
        };
        let out = match self.method {
            Method::Rk4 { .. } => (rk4_step(&mut f, y, h, Rk4Form::Fractions), 0.0),
            Method::Dopri { rtol, atol } => {
                let tol = Tolerance {
                    rtol,
                    atol,
                    scale: [1.0; N],
                };
                dopri_step(&mut f, y, h, want_err.then_some(&tol))
            }
        };
        self.stats.rhs_evals += evals;
        out
    }

    /// Event function: ≤ 0 (moving) / > 0 (stuck) means the event happened.
    fn event(&self, y: &Y, mode: Mode) -> f64 {
        match mode {
            Mode::Moving(s) => y[1] * s,
            Mode::Stuck => (self.phi_a(y) + self.phi_h(y)).abs() - self.sigma,
        }
    }

    fn triggered(&self, y: &Y, mode: Mode) -> bool {
        let g = self.event(y, mode);
        match mode {
            Mode::Moving(_) => g <= 0.0,
            Mode::Stuck => g > 0.0,
        }
    }

    /// Mode for a mass at rest under the current net force (the stick–slip rule).
    fn rest_mode(&self, y: &Y) -> Mode {
        let f = self.phi_a(y) + self.phi_h(y);
        if f.abs() <= self.sigma {
            Mode::Stuck
        } else if f > 0.0 {
            Mode::Moving(1.0)
        } else {
            Mode::Moving(-1.0)
        }
    }

    /// Locates the event inside a step of size h (the event is triggered at h).
    fn locate(&mut self, y: &Y, h: f64, mode: Mode) -> (f64, Y) {
        let sign_ok = |sim: &Self, g: f64| match mode {
            Mode::Moving(_) => g > 0.0,
            Mode::Stuck => g <= 0.0,
        } && sim.event(y, mode).is_finite();
        let (a, fa) = (0.0, self.event(y, mode));
        let (y_h, _) = self.step(y, h, mode, false);
        let (b, fb) = (h, self.event(&y_h, mode));
        let yb = y_h;
        if !sign_ok(self, fa) {
            return (0.0, *y);
        }
        crate::math::illinois(a, b, fa, fb, yb, 1e-15 * (1.0 + h), |c| {
            let (yc, _) = self.step(y, c, mode, false);
            let fc = self.event(&yc, mode);
            (fc, !sign_ok(self, fc), yc)
        })
    }

    /// One accepted step at most `rem` (and `cap`) long: its length and end state (RK4: the
    /// fixed steps evenly spread over the rest; Dormand–Prince: rejected and shrunk until the
    /// error norm is ≤ 1 or the step ≤ 1e-12, then the step-size memory `dt` updated).
    fn trial_step(&mut self, rem: f64, cap: f64, fixed: Option<f64>) -> (f64, Y) {
        let y0 = self.y;
        if let Some(hf) = fixed {
            let n = libm::ceil(rem / hf - 1e-9).max(1.0);
            let h = (rem / n).min(cap);
            let (y1, _) = self.step(&y0, h, self.mode, false);
            return (h, y1);
        }
        let mut h = self.dt.min(rem).min(cap);
        loop {
            let (y1, err) = self.step(&y0, h, self.mode, true);
            if err <= 1.0 || h <= 1e-12 {
                let fac = step_factor(err);
                if h < rem {
                    self.dt = h * fac;
                } else {
                    self.dt = self.dt.max(h * fac);
                }
                return (h, y1);
            }
            self.stats.rejected += 1;
            // err > 1: the factor is below 0.9.
            h *= step_factor(err);
        }
    }

    /// Integrates one segment of length `len` with constant held input.
    fn segment(&mut self, len: f64) {
        let mut t = 0.0;
        if self.mode == Mode::Stuck || self.y[1] == 0.0 {
            self.y[1] = 0.0;
            self.mode = self.rest_mode(&self.y);
        }
        let fixed = match self.method {
            Method::Rk4 { steps_per_period } => Some(1.0 / f64::from(steps_per_period)),
            Method::Dopri { .. } => None,
        };
        let mut guard = 0u64;
        // Step cap after an event that could not be bracketed (a mass leaving rest whose force
        // reverses within the step): halve until the step is tiny, then hold the mass for it.
        let mut cap = f64::INFINITY;
        while t < len {
            guard += 1;
            if guard > 10_000_000 {
                break;
            }
            // Nothing moves while stuck without a filter: skip the segment.
            if self.mode == Mode::Stuck && self.m.amp.is_none() {
                break;
            }
            let (h, y1) = self.trial_step(len - t, cap, fixed);
            self.stats.steps += 1;
            if self.triggered(&y1, self.mode) {
                let y0 = self.y;
                let (tc, yc) = self.locate(&y0, h, self.mode);
                self.stats.events += 1;
                if tc <= 0.0 {
                    if h > 1e-13 {
                        cap = 0.5 * h;
                    } else {
                        // The mass cannot leave rest within 1e-13 periods: hold it that long.
                        let (ys, _) = self.step(&y0, h, Mode::Stuck, false);
                        self.y = ys;
                        self.y[1] = 0.0;
                        self.mode = Mode::Stuck;
                        t += h;
                        cap = f64::INFINITY;
                    }
                    continue;
                }
                cap = f64::INFINITY;
                self.y = yc;
                t += tc;
                if let Mode::Moving(_) = self.mode {
                    self.y[1] = 0.0;
                    self.mode = self.rest_mode(&self.y);
                } else {
                    self.mode = self.rest_mode(&self.y);
                    if self.mode == Mode::Stuck {
                        // Root found on the stuck side: nudge by the bracket width.
                        t += 1e-15 * (1.0 + len);
                    }
                }
                continue;
            }
            cap = f64::INFINITY;
            self.y = y1;
            t += h;
        }
    }
}

impl ExactSim for RefSim {
    fn step_period(&mut self) {
        let start = self.y;
        if self.diverged() {
            self.h += 1;
            return;
        }
        let fc = self.law(self.y[0]);
        self.n_prev = self.count(self.y[0]);
        let h = self.h;
        self.line[(h & MASK) as usize] = fc;
        let at = |back: u64| self.line[(h.wrapping_sub(back) & MASK) as usize];
        let f2 = at(self.n);
        let f1 = at(self.n + 1);
        if self.frac > 0.0 {
            self.u = f1;
            self.segment(self.frac);
            self.u = f2;
            self.segment(1.0 - self.frac);
        } else {
            self.u = f2;
            self.segment(1.0);
        }
        let end = self.y;
        let m = self.mass;
        // H_T (35) with the hand's mass added; kinetic term first, as the audit always summed it
        // (core's `storage_energy` associates the other way, which moves the last bit).
        let h0 = 0.5 * m * start[1] * start[1] + potential(start[0]);
        let h1 = 0.5 * m * end[1] * end[1] + potential(end[0]);
        let e_d = end[4] - start[4];
        let e_g = (end[5] - start[5]) + potential(end[0]) - potential(start[0]);
        let w_h = end[6] - start[6];
        self.audit = PeriodAudit {
            h_start: h0,
            h_end: h1,
            e_d,
            e_g,
            residual: (h1 - h0) + e_d - e_g - w_h,
        };
        let still = start[1] == 0.0 && end[1] == 0.0 && start[0] == end[0] && f1 == f2;
        let settled_filter = self.m.amp.is_none() && self.m.zoh;
        self.rest_periods = if still && settled_filter {
            self.rest_periods + 1
        } else {
            0
        };
        self.h += 1;
    }
    fn state(&self) -> Motion {
        Motion {
            x: self.y[0],
            v: self.y[1],
        }
    }
    fn period(&self) -> u64 {
        self.h
    }
    fn audit(&self) -> PeriodAudit {
        self.audit
    }
    fn at_rest(&self) -> bool {
        self.rest_periods > self.n + 2
    }
    fn diverged(&self) -> bool {
        !(self.y[0].abs() <= 1e150 && self.y[1].abs() <= 1e150)
    }
    fn params(&self) -> Params {
        Params {
            mu: self.mass,
            beta: self.beta,
            sigma: self.sigma,
            tau_d: self.tau_d,
        }
    }
    /// Always false: the reference integrators are never cut short by cycle detection (their
    /// adaptive step-size controller carries state across periods), so they classify by brute
    /// force.
    fn same_state(&self, _other: &Self) -> bool {
        false
    }
    /// Always false (see [`Self::same_state`]).
    fn same_but_position(&self, _other: &Self) -> bool {
        false
    }
    /// No trace: steps and leaves `tr` empty.
    fn step_period_traced(&mut self, tr: &mut crate::plant::Increments) {
        tr.len = 0;
        self.step_period();
    }
    fn count_at(&self, x: f64) -> f64 {
        self.count(x)
    }
    fn set_position(&mut self, x: f64) {
        self.y[0] = x;
    }
    fn applied_force(&self) -> f64 {
        // Same convention as the exact solver: the force at the start of the next period.
        if self.m.amp.is_some() || !self.m.zoh {
            return self.phi_a(&self.y);
        }
        let h = self.h;
        let at = |back: u64| self.line[(h.wrapping_sub(back) & MASK) as usize];
        if self.frac > 0.0 {
            at(self.n + 1)
        } else if self.n > 0 {
            at(self.n)
        } else {
            self.law(self.y[0])
        }
    }
}
