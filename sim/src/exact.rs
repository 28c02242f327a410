//! Exact event-driven solver of μξ̈ + βξ̇ + σ·sgn(ξ̇) = φ_A with the digital spring (8) held
//! over each period and the delay (9).
//!
//! Units: dimensionless (Table I). τ counts sampling periods, ξ encoder ticks, ξ̇ ticks per
//! period, forces K·Δ, energies K·Δ².
//!
//! Between events the applied force and the friction sign are constant, so the motion is the
//! closed form of [`crate::math`]. Events: sample instants (integer τ), delayed force switches
//! (τ = h + frac(τ_D)), velocity zero crossings (located analytically, one `log1p` each) and
//! stick/slip ([`crate::plant`]'s rule). No step size, no tolerance: only floating-point error.
//!
//! Hot path: the exponentials of the two possible segment lengths (a full period, or frac(τ_D)
//! and 1 − frac(τ_D)) are precomputed, so a period without a zero crossing costs a few
//! multiplications and one branch; ⌊ξ⌋ uses an integer conversion instead of a libm call.
//!
//! **Delay-line history**: for τ < τ_D the applied force is the spring force of the initial
//! position, φ_C = −⌊ξ₀⌋ − ½ ([`History::HoldInitial`], as if the loop had been sampling ξ₀
//! forever), or zero ([`History::Zero`], amplifier switched on at τ = 0).
//!
//! Effects are compile-time flags (`Q`uantization, `C`oulomb, `V`iscous, `D`elay, one-sided
//! `W`all, energy `A`udit): [`dispatch`] resolves a runtime [`Effects`] once into one of 32
//! monomorphised solvers, so a disabled effect costs nothing per step.
//!
//! **Virtual damper** ([`Exact::with_beta_v`]): the rendered law becomes
//! φ_C(h) = −(n_h + ½) − β_v·(n_h − n_(h−1)) with β_v = B/(K·T) (dimensionless), n_h = ⌊ξ(h)⌋
//! (ξ(h) without quantization): a backward difference of the counts, constant over each period,
//! through the same delay line as the spring. The first sample uses n_(−1) = n_0 (no damper kick
//! at start). On a one-sided wall the whole law (damper included) acts only in contact
//! (n_h ≥ 0) and is 0 otherwise. [`Exact::with_dead_band`] gives the firmware's `dead-band-N`
//! law instead: the difference counts only when |n_h − n_(h−1)| > N (else the damper is 0).
//! The solver stays exact: only the held force changes. The
//! damper's work is part of the applied force's work, so it lands in E_g (29) and (26) still
//! balances. With β_v = 0 the solver is bit-for-bit the undamped one (a branch, not `+ 0·x`).
//!
//! Invariants: at most 2 segments and at most 2 closed-form sub-steps per segment per period (no
//! Zeno); no allocation; the state stays finite unless the caller runs a diverging trajectory
//! past |ξ| ≈ 1e150, which [`ExactSim::diverged`] reports.

use crate::math::{e1, floor_fast, g, g1, g2};
use crate::params::{validate, Effects, ParamError, Params};
use crate::plant::{advance_traced, Body, Increments, Motion};
use stiffwall_core::params::check_range;

/// Capacity of the delay line (a power of two, > MAX_TAU_D + 2).
const LINE: usize = 256;
const MASK: u64 = LINE as u64 - 1;

/// What the delayed force is before the first sample reaches the plant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "std", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "std", serde(rename_all = "snake_case"))]
pub enum History {
    /// φ_A(τ) = φ_C(ξ₀) for τ < τ_D (default).
    #[default]
    HoldInitial,
    /// φ_A(τ) = 0 for τ < τ_D.
    Zero,
}

/// Closed-form coefficients of a segment of fixed length.
#[derive(Debug, Clone, Copy, Default)]
struct Coef {
    len: f64,
    e: f64,
    p1: f64,
    p2: f64,
    i0: f64,
    i1: f64,
    i2: f64,
}

impl Coef {
    fn new(k: f64, len: f64) -> Self {
        let x = k * len;
        let e1x = e1(x);
        Self {
            len,
            e: 1.0 - x * e1x,
            p1: len * e1x,
            p2: len * len * g(x),
            i0: len * e1(2.0 * x),
            i1: len * len * g1(x),
            i2: len * len * len * g2(x),
        }
    }
}

/// Energy audit of one period [h, h+1] (eq. (26)–(29), φ_H = 0).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PeriodAudit {
    /// H_T (35) at the start of the period.
    pub h_start: f64,
    /// H_T at the end of the period.
    pub h_end: f64,
    /// Dissipated energy E_d (28) over the period.
    pub e_d: f64,
    /// Generated energy E_g (29) over the period.
    pub e_g: f64,
    /// Residual of (26): H_end − H_start + E_d − E_g (0 for an exact trajectory).
    pub residual: f64,
}

/// Potential energy of the quantized spring H_e (34): `stiffwall_core::energy::spring_energy`.
pub use stiffwall_core::energy::spring_energy as potential;
/// H_T (35): `stiffwall_core::energy::storage_energy` (inlined, fast floor).
pub use stiffwall_core::energy::storage_energy as storage;

/// Common interface of every monomorphised exact solver (and of the reference solvers).
pub trait ExactSim: Clone {
    /// Advances one sampling period.
    fn step_period(&mut self);
    /// State at the current sample instant.
    fn state(&self) -> Motion;
    /// Current sample index h (τ = h).
    fn period(&self) -> u64;
    /// Audit of the last period (zeros unless built with the audit flag).
    fn audit(&self) -> PeriodAudit;
    /// True once the mass has rested with a constant applied force for longer than the delay
    /// line: the trajectory is then a fixed point forever.
    fn at_rest(&self) -> bool;
    /// True if the state left the finite range (|ξ| or |ξ̇| > 1e150, or NaN).
    fn diverged(&self) -> bool;
    /// Parameters in use.
    fn params(&self) -> Params;
    /// Force applied at the start of the next period's first segment (for CSV output).
    fn applied_force(&self) -> f64;
    /// True if `self` and `other` (the same solver, at any two sample instants) hold the same
    /// state bit for bit: everything the following periods depend on (position, velocity, the
    /// delay line's pending forces, the rest counter and last force of [`Self::at_rest`], the
    /// damper's previous count). Then both continue identically forever, so a trajectory whose
    /// state at sample h equals its state at sample h − L is periodic with period L from h − L
    /// on ([`crate::classify`]'s cycle detection). False whenever unsure (never wrongly true).
    fn same_state(&self, other: &Self) -> bool;
    /// [`Self::same_state`] except for the bits of the position, whose sampled count (what
    /// the law reads, [`Self::count_at`]) must still be equal: true only for a solver whose
    /// future depends on ξ through that count at each sample and through the increments
    /// ξ ← ξ + Δ alone (the quantized exact solver), false otherwise.
    fn same_but_position(&self, other: &Self) -> bool;
    /// [`Self::step_period`], also writing the period's position increments Δ (ξ ← ξ + Δ, in
    /// order) to `tr`; the same arithmetic. A solver without the trace leaves `tr` empty (and
    /// never reports [`Self::same_but_position`]).
    fn step_period_traced(&mut self, tr: &mut Increments);
    /// The sampled count the law reads at position `x` (⌊x⌋ when quantized).
    fn count_at(&self, x: f64) -> f64;
    /// Replaces the position at the current sample instant (for resuming a replayed cycle).
    fn set_position(&mut self, x: f64);
}

/// The exact solver with compile-time effect flags.
#[derive(Debug, Clone)]
pub struct Exact<
    const Q: bool,
    const C: bool,
    const V: bool,
    const D: bool,
    const W: bool,
    const A: bool,
> {
    st: Motion,
    body: Body,
    params: Params,
    full: Coef,
    c1: Coef,
    c2: Coef,
    split: bool,
    n: u64,
    line: [f64; LINE],
    h: u64,
    rest_periods: u64,
    audit: PeriodAudit,
    e_d: f64,
    w_a: f64,
    last_force: f64,
    /// Dimensionless virtual damping β_v = B/(K·T) (0: no damper).
    beta_v: f64,
    /// Count n_(h−1) of the previous sample (ξ(h−1) without quantization).
    n_prev: f64,
    /// Dead band of the damper's count difference, counts per period (0: the plain
    /// difference; N: the firmware's `dead-band-N`, the difference is 0 while |dn| ≤ N).
    dead_band: f64,
}

/// Largest accepted dimensionless virtual damping β_v.
pub const MAX_BETA_V: f64 = 1000.0;

/// Largest accepted damper dead band, counts per period (the firmware's
/// `stiffwall_proto::MAX_DEADBAND_COUNTS`, `rich::MAX_DAMPER_DEAD_BAND`).
pub const MAX_DEAD_BAND: u8 = 8;

impl<const Q: bool, const C: bool, const V: bool, const D: bool, const W: bool, const A: bool>
    Exact<Q, C, V, D, W, A>
{
    /// A solver starting at τ = 0 in `init`. Disabled effects ignore their parameter.
    pub fn new(params: Params, init: Motion, history: History) -> Result<Self, ParamError> {
        validate(&params)?;
        check_range(
            "xi0",
            init.x,
            -1e150,
            false,
            1e150,
            "finite and in [-1e150, 1e150]",
        )?;
        check_range(
            "xidot0",
            init.v,
            -1e150,
            false,
            1e150,
            "finite and in [-1e150, 1e150]",
        )?;
        let beta = if V { params.beta } else { 0.0 };
        let sigma = if C { params.sigma } else { 0.0 };
        let tau_d = if D { params.tau_d } else { 0.0 };
        let body = Body::new(params.mu, beta, sigma);
        let n = libm::floor(tau_d);
        let f = tau_d - n;
        let hist = match history {
            History::HoldInitial => Self::spring(init.x),
            History::Zero => 0.0,
        };
        Ok(Self {
            st: init,
            body,
            params: Params {
                mu: params.mu,
                beta,
                sigma,
                tau_d,
            },
            full: Coef::new(body.rate, 1.0),
            c1: Coef::new(body.rate, f),
            c2: Coef::new(body.rate, 1.0 - f),
            split: f > 0.0,
            n: n as u64,
            line: [hist; LINE],
            h: 0,
            rest_periods: 0,
            audit: PeriodAudit::default(),
            e_d: 0.0,
            w_a: 0.0,
            last_force: hist,
            beta_v: 0.0,
            n_prev: Self::count(init.x),
            dead_band: 0.0,
        })
    }

    /// Adds the virtual damper of dimensionless damping β_v = B/(K·T) (see the module header).
    ///
    /// # Errors
    /// [`ParamError`] naming `beta_v` unless β_v is finite and in [0, [`MAX_BETA_V`]].
    pub fn with_beta_v(mut self, beta_v: f64) -> Result<Self, ParamError> {
        self.beta_v = check_range(
            "beta_v",
            beta_v,
            0.0,
            false,
            MAX_BETA_V,
            "finite and in [0, 1000] (dimensionless B/(K*T))",
        )?;
        Ok(self)
    }

    /// The damper's dead band: the count difference n_h − n_(h−1) is taken as 0 while its
    /// magnitude is at most `counts` (the firmware's `dead-band-N` law; 0 is the plain
    /// difference, the default).
    ///
    /// # Errors
    /// [`ParamError`] naming `dead_band` unless `counts` is in [0, [`MAX_DEAD_BAND`]].
    pub fn with_dead_band(mut self, counts: u8) -> Result<Self, ParamError> {
        self.dead_band = check_range(
            "dead_band",
            f64::from(counts),
            0.0,
            false,
            f64::from(MAX_DEAD_BAND),
            "an integer in [0, 8] counts per period",
        )?;
        Ok(self)
    }

    /// Dimensionless virtual damping β_v in use.
    #[must_use]
    pub fn beta_v(&self) -> f64 {
        self.beta_v
    }

    /// The sampled count n = ⌊ξ⌋ (ξ itself without quantization).
    #[inline(always)]
    fn count(xi: f64) -> f64 {
        if Q {
            floor_fast(xi)
        } else {
            xi
        }
    }

    /// The rendered law at position `xi`: the spring, plus the damper when β_v ≠ 0.
    #[inline(always)]
    fn law(&self, xi: f64) -> f64 {
        if self.beta_v == 0.0 {
            return Self::spring(xi);
        }
        let n = Self::count(xi);
        let dn = n - self.n_prev;
        // With no dead band, |dn| <= 0 only for dn = 0: the plain difference, bit for bit.
        let dn = if dn.abs() <= self.dead_band { 0.0 } else { dn };
        let f = if Q { -n - 0.5 } else { -n } - self.beta_v * dn;
        if W && n < 0.0 {
            0.0
        } else {
            f
        }
    }

    /// The spring force sampled at position `xi` (eq. (8) or (23), one-sided if `W`).
    #[inline(always)]
    #[must_use]
    pub fn spring(xi: f64) -> f64 {
        let f = if Q { -floor_fast(xi) - 0.5 } else { -xi };
        if W {
            f.min(0.0)
        } else {
            f
        }
    }

    /// One segment of constant force `f` with precomputed coefficients.
    #[inline(always)]
    fn seg<const T: bool>(&mut self, f: f64, co: &Coef, tr: &mut Increments) {
        let v = self.st.v;
        let sigma = if C { self.body.coulomb } else { 0.0 };
        let (e, p1, p2) = if V {
            (co.e, co.p1, co.p2)
        } else {
            (1.0, co.len, 0.5 * co.len * co.len)
        };
        if v != 0.0 {
            let s = if v > 0.0 { 1.0 } else { -1.0 };
            let acc = (f - sigma * s) * self.body.inv_mass;
            let v1 = v * e + acc * p1;
            if v1 * s > 0.0 {
                let dx = v * p1 + acc * p2;
                if A {
                    self.account(f, dx, v, acc, co, sigma);
                }
                self.st.x += dx;
                if T {
                    tr.push(dx);
                }
                self.st.v = v1;
                return;
            }
            self.slow::<T>(f, co.len, tr);
        } else if f.abs() > sigma {
            let s = if f > 0.0 { 1.0 } else { -1.0 };
            let acc = (f - sigma * s) * self.body.inv_mass;
            let dx = acc * p2;
            if A {
                self.account(f, dx, 0.0, acc, co, sigma);
            }
            self.st.x += dx;
            if T {
                tr.push(dx);
            }
            self.st.v = acc * p1;
        }
        // else: at rest with |f| ≤ σ, stays.
    }

    #[inline(always)]
    fn account(&mut self, f: f64, dx: f64, v: f64, acc: f64, co: &Coef, sigma: f64) {
        let (i0, i1, i2) = if V {
            (co.i0, co.i1, co.i2)
        } else {
            let l = co.len;
            (l, 0.5 * l * l, l * l * l / 3.0)
        };
        let iv2 = v * v * i0 + 2.0 * v * acc * i1 + acc * acc * i2;
        self.e_d += self.body.viscous * iv2 + sigma * dx.abs();
        self.w_a += f * dx;
    }

    /// Segment with a velocity zero crossing: general closed form (rare).
    #[cold]
    #[inline(never)]
    fn slow<const T: bool>(&mut self, f: f64, len: f64, tr: &mut Increments) {
        let x0 = self.st.x;
        let r = advance_traced::<A, T>(&self.body, &mut self.st, f, len, tr);
        if A {
            self.e_d += self.body.viscous * r.int_v2 + self.body.coulomb * r.int_abs_v;
            self.w_a += f * (self.st.x - x0);
        }
    }

    /// One sampling period; with `T` the position increments go to `tr` (same arithmetic).
    #[inline(always)]
    fn step<const T: bool>(&mut self, tr: &mut Increments) {
        let start = self.st;
        // A diverged trajectory is frozen (never NaN); `diverged()` reports it.
        if !(start.x.abs() <= 1e150 && start.v.abs() <= 1e150) {
            self.h += 1;
            return;
        }
        if A {
            self.e_d = 0.0;
            self.w_a = 0.0;
        }
        let fc = self.law(self.st.x);
        self.n_prev = Self::count(self.st.x);
        let (full, c1, c2) = (self.full, self.c1, self.c2);
        let f_last;
        if D {
            self.line[(self.h & MASK) as usize] = fc;
            let f2 = self.delayed(self.n);
            if self.split {
                let f1 = self.delayed(self.n + 1);
                self.seg::<T>(f1, &c1, tr);
                self.seg::<T>(f2, &c2, tr);
                f_last = if f1 == f2 { f2 } else { f64::NAN };
            } else {
                self.seg::<T>(f2, &full, tr);
                f_last = f2;
            }
        } else {
            self.seg::<T>(fc, &full, tr);
            f_last = fc;
        }
        // Fixed-point detection: at rest over a whole period under one unchanged force.
        if start.v == 0.0 && self.st.v == 0.0 && start.x == self.st.x && f_last == self.last_force {
            self.rest_periods += 1;
        } else {
            self.rest_periods = 0;
        }
        self.last_force = f_last;
        if A {
            let h0 = stiffwall_core::energy::storage_energy(self.params.mu, start.x, start.v);
            let h1 = stiffwall_core::energy::storage_energy(self.params.mu, self.st.x, self.st.v);
            let e_g = self.w_a + potential(self.st.x) - potential(start.x);
            self.audit = PeriodAudit {
                h_start: h0,
                h_end: h1,
                e_d: self.e_d,
                e_g,
                residual: (h1 - h0) + self.e_d - e_g,
            };
        }
        self.h += 1;
    }

    #[inline(always)]
    fn delayed(&self, back: u64) -> f64 {
        self.line[(self.h.wrapping_sub(back) & MASK) as usize]
    }

    /// Everything the following periods depend on apart from ξ and ξ̇. The constants
    /// (parameters, coefficients, β_v) are the same for clones of one solver. The step at sample
    /// h writes slot h and reads slots h − n and h − n − 1: the pending forces are the n + 1
    /// slots before h. The audit fields are outputs of the last period, not state.
    #[inline]
    fn same_but_motion(&self, o: &Self) -> bool {
        self.rest_periods == o.rest_periods
            && self.last_force.to_bits() == o.last_force.to_bits()
            && self.n_prev.to_bits() == o.n_prev.to_bits()
            && self.beta_v.to_bits() == o.beta_v.to_bits()
            && self.dead_band.to_bits() == o.dead_band.to_bits()
            && (!D || (1..=self.n + 1).all(|j| self.delayed(j).to_bits() == o.delayed(j).to_bits()))
    }
}

impl<const Q: bool, const C: bool, const V: bool, const D: bool, const W: bool, const A: bool>
    ExactSim for Exact<Q, C, V, D, W, A>
{
    #[inline]
    fn step_period(&mut self) {
        self.step::<false>(&mut Increments::default());
    }

    fn step_period_traced(&mut self, tr: &mut Increments) {
        tr.len = 0;
        self.step::<true>(tr);
    }

    fn same_but_position(&self, o: &Self) -> bool {
        // Only the quantized law reads ξ through its count alone.
        Q && self.st.v.to_bits() == o.st.v.to_bits()
            && Self::count(self.st.x).to_bits() == Self::count(o.st.x).to_bits()
            && self.same_but_motion(o)
    }

    fn count_at(&self, x: f64) -> f64 {
        Self::count(x)
    }

    fn set_position(&mut self, x: f64) {
        self.st.x = x;
    }

    fn state(&self) -> Motion {
        self.st
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
        !(self.st.x.abs() <= 1e150 && self.st.v.abs() <= 1e150)
    }
    fn params(&self) -> Params {
        self.params
    }
    #[inline]
    fn same_state(&self, o: &Self) -> bool {
        // Position and velocity first: they differ at almost every compare (the cheap filter).
        if self.st.x.to_bits() != o.st.x.to_bits() || self.st.v.to_bits() != o.st.v.to_bits() {
            return false;
        }
        self.same_but_motion(o)
    }

    fn applied_force(&self) -> f64 {
        // The force at the start of the next period; with no delay it is the sample about to
        // be taken (the delay line slot h is written by the next `step_period`).
        if D && (self.split || self.n > 0) {
            self.delayed(self.n + u64::from(self.split))
        } else {
            self.law(self.st.x)
        }
    }
}

/// Receives the monomorphised solver chosen by [`dispatch`].
pub trait Visitor {
    /// Result of the visit.
    type Output;
    /// Called once with the solver.
    fn visit<S: ExactSim>(self, sim: S) -> Self::Output;
}

macro_rules! pick {
    ($vis:ident, $p:ident, $i:ident, $hi:ident, $bv:ident, [$($acc:tt)*]) => {
        $vis.visit(Exact::<$($acc)* AUDIT>::new($p, $i, $hi)?.with_beta_v($bv)?)
    };
    ($vis:ident, $p:ident, $i:ident, $hi:ident, $bv:ident, [$($acc:tt)*] $b:expr $(, $rest:expr)*) => {
        if $b {
            pick!($vis, $p, $i, $hi, $bv, [$($acc)* true,] $($rest),*)
        } else {
            pick!($vis, $p, $i, $hi, $bv, [$($acc)* false,] $($rest),*)
        }
    };
}

/// Builds the exact solver for a runtime effect set once (static dispatch afterwards) and
/// hands it to `vis`. `AUDIT` selects the energy audit.
pub fn dispatch<V: Visitor, const AUDIT: bool>(
    params: Params,
    effects: Effects,
    init: Motion,
    history: History,
    vis: V,
) -> Result<V::Output, ParamError> {
    dispatch_damped::<V, AUDIT>(params, effects, init, history, 0.0, vis)
}

/// [`dispatch`] with the virtual damper of dimensionless damping `beta_v` = B/(K·T)
/// ([`Exact::with_beta_v`]; 0 gives exactly [`dispatch`]).
///
/// # Errors
/// [`ParamError`] naming the offending field (`beta_v` for β_v).
pub fn dispatch_damped<V: Visitor, const AUDIT: bool>(
    params: Params,
    effects: Effects,
    init: Motion,
    history: History,
    beta_v: f64,
    vis: V,
) -> Result<V::Output, ParamError> {
    let e = effects;
    Ok(
        pick!(vis, params, init, history, beta_v, [] e.quantization, e.coulomb, e.viscous, e.delay, e.one_sided),
    )
}

/// The paper's full model (quantization, Coulomb, viscous, delay; no audit).
pub type Full = Exact<true, true, true, true, false, false>;
/// The paper's model without delay (τ_D = 0) and without audit: the fastest map kernel.
pub type NoDelay = Exact<true, true, true, false, false, false>;
/// The paper's full model with the energy audit.
pub type FullAudited = Exact<true, true, true, true, false, true>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn storage_matches_core() {
        for &(x, v) in &[(0.0, 1.0), (-3.7, 0.2), (12.25, -4.0), (-1e-300, 0.0)] {
            assert_eq!(
                storage(100.0, x, v),
                stiffwall_core::energy::storage_energy(100.0, x, v)
            );
        }
    }

    #[test]
    fn dispatch_picks_a_solver() {
        struct Run;
        impl Visitor for Run {
            type Output = Motion;
            fn visit<S: ExactSim>(self, mut s: S) -> Motion {
                for _ in 0..100 {
                    s.step_period();
                }
                s.state()
            }
        }
        let init = Motion { x: 0.0, v: 5.0 };
        let a = dispatch::<_, false>(Params::BASE, Effects::ALL, init, History::HoldInitial, Run)
            .unwrap();
        let mut b = NoDelay::new(Params::BASE, init, History::HoldInitial).unwrap();
        for _ in 0..100 {
            b.step_period();
        }
        assert_eq!(a, b.state());
    }

    #[test]
    fn beta_v_is_validated_by_name() {
        let s = Full::new(
            Params::BASE,
            Motion { x: 0.0, v: 1.0 },
            History::HoldInitial,
        )
        .unwrap();
        for bad in [f64::NAN, -0.1, 1000.5, f64::INFINITY] {
            let e = s.clone().with_beta_v(bad).unwrap_err();
            assert_eq!(e.name(), "beta_v", "{bad}");
        }
        assert_eq!(s.with_beta_v(1000.0).unwrap().beta_v(), 1000.0);
    }

    /// The dead band in the firmware's terms: while the count moves by at most N per period
    /// the damper is off (the run is the spring alone's, bit for bit); a faster motion is
    /// damped as by the plain difference (it decays where the spring alone grows); N = 0 is
    /// the plain difference bit for bit; N above 8 is refused by name.
    #[test]
    fn dead_band_turns_the_damper_off_for_small_count_steps_only() {
        let p = Params {
            mu: 100.0,
            beta: 0.0,
            sigma: 0.2,
            tau_d: 0.0,
        };
        let run = |v0: f64, beta_v: f64, n: u8| {
            let init = Motion { x: 0.0, v: v0 };
            let mut s = NoDelay::new(p, init, History::HoldInitial)
                .unwrap()
                .with_beta_v(beta_v)
                .unwrap()
                .with_dead_band(n)
                .unwrap();
            let mut path = Vec::new();
            for _ in 0..3000 {
                s.step_period();
                path.push(s.state());
            }
            path
        };
        // From 0.3 counts/period the spring alone's speed (so |dn|) stays below 8.
        let spring = run(0.3, 0.0, 0);
        assert!(spring.iter().all(|m| m.v.abs() < 8.0));
        assert_eq!(
            run(0.3, 2.0, 8),
            spring,
            "dead band 8 at |dn| <= 8: the spring alone"
        );
        assert_ne!(run(0.3, 2.0, 0), spring, "the plain difference damps");
        assert_eq!(run(3.0, 2.0, 0), {
            let init = Motion { x: 0.0, v: 3.0 };
            let mut s = NoDelay::new(p, init, History::HoldInitial)
                .unwrap()
                .with_beta_v(2.0)
                .unwrap();
            (0..3000)
                .map(|_| {
                    s.step_period();
                    s.state()
                })
                .collect::<Vec<_>>()
        });
        let fast = |n: u8| {
            let end = *run(20.0, 2.0, n).last().unwrap();
            storage(p.mu, end.x, end.v)
        };
        let h0 = storage(p.mu, 0.0, 20.0);
        let undamped = *run(20.0, 0.0, 0).last().unwrap();
        assert!(
            storage(p.mu, undamped.x, undamped.v) > 0.5 * h0,
            "the spring alone holds on"
        );
        assert!(
            fast(1) < 0.05 * h0,
            "dead band 1 damps a fast motion: {}",
            fast(1)
        );
        assert!(fast(0) < 0.05 * h0);
        let s = NoDelay::new(p, Motion { x: 0.0, v: 1.0 }, History::HoldInitial).unwrap();
        assert_eq!(s.with_dead_band(9).unwrap_err().name(), "dead_band");
    }

    /// Linear sampled spring, no Coulomb, no delay, β = 0: the ZOH spring acts as a negative
    /// damping of about ½ (Colgate), so the oscillation grows; a backward-difference damper
    /// β_v = 2 ≫ ½ (and ≪ μ) makes it decay. Also the energy balance (26) with the damper.
    #[test]
    fn damper_turns_growth_into_decay_and_balances_energy() {
        type Lin = Exact<false, false, true, false, false, true>;
        let p = Params {
            mu: 100.0,
            beta: 0.0,
            sigma: 0.0,
            tau_d: 0.0,
        };
        let init = Motion { x: 0.0, v: 5.0 };
        let h0 = storage(p.mu, init.x, init.v);
        let run = |beta_v: f64| {
            let mut s = Lin::new(p, init, History::HoldInitial)
                .unwrap()
                .with_beta_v(beta_v)
                .unwrap();
            let mut worst: f64 = 0.0;
            for _ in 0..2000 {
                s.step_period();
                let a = s.audit();
                worst = worst.max(a.residual.abs() / a.h_start.max(1.0));
            }
            let st = s.state();
            (storage(p.mu, st.x, st.v), worst)
        };
        let (grown, r0) = run(0.0);
        let (decayed, r2) = run(2.0);
        assert!(grown > 2.0 * h0, "undamped {grown} vs {h0}");
        assert!(decayed < 0.01 * h0, "damped {decayed} vs {h0}");
        assert!(r0 < 1e-9 && r2 < 1e-9, "residuals {r0} {r2}");
    }

    #[test]
    fn applied_force_is_the_force_of_the_next_period() {
        let init = Motion { x: 2.5, v: 0.0 };
        for tau_d in [0.0, 0.5, 1.0, 2.25] {
            let p = Params {
                tau_d,
                ..Params::BASE
            };
            let mut s = Full::new(p, init, History::HoldInitial).unwrap();
            // History: the force of the initial position.
            assert_eq!(s.applied_force(), -2.5, "tau_d {tau_d}");
            for _ in 0..300 {
                s.step_period();
            }
            let st = s.state();
            if tau_d == 0.0 {
                assert_eq!(s.applied_force(), -floor_fast(st.x) - 0.5);
            }
        }
    }
}
