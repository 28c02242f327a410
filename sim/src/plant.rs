//! Closed-form motion of a mass with viscous and dynamic Coulomb friction under a constant force,
//! with the stick–slip rule; the physical-units plant the firmware drives.
//!
//! The equation is `m·ẍ + b·ẋ + c·sgn(ẋ) = f` with `f` constant over the step. The same code
//! serves the dimensionless model (m = μ, b = β, c = σ, time in sampling periods, force in K·Δ)
//! and SI units (kg, N·s/m, N, s, N).
//!
//! **Stick–slip rule** (documented in `docs/model-notes-sim.md`): while ẋ ≠ 0 the friction is
//! −c·sgn(ẋ). When the velocity reaches zero (located analytically) the mass stays at rest as
//! long as |f| ≤ c (this includes f = 0 when c = 0) and otherwise leaves in the direction of `f`
//! with friction −c·sgn(f). With a constant force a mass can therefore reverse at most once per
//! step, and a mass at rest stays at rest until the force changes: no Zeno behaviour.
//!
//! Invariants: m > 0, b ≥ 0, c ≥ 0, step length t ≥ 0; every call performs at most two
//! closed-form sub-steps, never allocates and never loops.

use crate::math::{e1, g, g1, g2, log1p_over};
use crate::params::{ParamError, Params};
use stiffwall_core::params::{check_non_negative, check_positive};

/// Mass, viscous and Coulomb coefficients with derived constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// Mass m (or μ).
    pub mass: f64,
    /// Viscous coefficient b (or β), ≥ 0 (the device's own friction, not the virtual damper).
    pub viscous: f64,
    /// Dynamic Coulomb force c (or σ), ≥ 0.
    pub coulomb: f64,
    /// 1/m.
    pub inv_mass: f64,
    /// Decay rate k = b/m.
    pub rate: f64,
}

impl Body {
    /// A body; the caller guarantees m > 0, b ≥ 0, c ≥ 0 (validated at the API boundaries).
    #[must_use]
    pub fn new(mass: f64, viscous: f64, coulomb: f64) -> Self {
        Self {
            mass,
            viscous,
            coulomb,
            inv_mass: 1.0 / mass,
            rate: viscous / mass,
        }
    }
}

/// Position and velocity.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Motion {
    /// Position (ξ in ticks, or metres).
    pub x: f64,
    /// Velocity (ξ̇ in ticks per period, or m/s).
    pub v: f64,
}

/// Integrals accumulated over one step, for the energy audit.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepIntegrals {
    /// ∫ ẋ² dt over the step.
    pub int_v2: f64,
    /// ∫ |ẋ| dt over the step.
    pub int_abs_v: f64,
    /// Number of velocity zero crossings (0, 1).
    pub crossings: u32,
    /// Whether the mass is at rest (stuck) at the end of the step.
    pub stuck: bool,
}

/// Free motion without a zero crossing: returns (Δx, v₁, ∫v²) for initial velocity `v0`,
/// constant acceleration term `acc = a/m` and duration `t`.
#[inline]
fn free<const AUDIT: bool>(body: &Body, v0: f64, acc: f64, t: f64) -> (f64, f64, f64) {
    let x = body.rate * t;
    let e1x = e1(x);
    let p1 = t * e1x;
    let p2 = t * t * g(x);
    let e = 1.0 - x * e1x;
    let v1 = v0 * e + acc * p1;
    let dx = v0 * p1 + acc * p2;
    let iv2 = if AUDIT {
        v0 * v0 * t * e1(2.0 * x) + 2.0 * v0 * acc * t * t * g1(x) + acc * acc * t * t * t * g2(x)
    } else {
        0.0
    };
    (dx, v1, iv2)
}

/// Sign as ±1 (`v` must be non-zero).
#[inline]
fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// The position increments Δ of one sampling period, in the order a solver adds them
/// (ξ ← ξ + Δ each): at most two per segment, two segments per period. No allocation.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Increments {
    /// The increments (the first `len`).
    pub dx: [f64; 4],
    /// How many.
    pub len: usize,
}

impl Increments {
    /// Appends Δ (a fifth one is dropped: cannot happen, see the type).
    #[inline]
    pub fn push(&mut self, d: f64) {
        if let Some(slot) = self.dx.get_mut(self.len) {
            *slot = d;
            self.len += 1;
        }
    }

    /// The increments in order.
    #[must_use]
    pub fn as_slice(&self) -> &[f64] {
        self.dx.get(..self.len).unwrap_or(&[])
    }
}

/// Advances `m` by `t` under the constant force `f`, exactly, applying the stick–slip rule.
/// With `AUDIT` the returned integrals hold ∫ẋ² and ∫|ẋ| (otherwise zeros and the flags).
#[inline]
pub fn advance<const AUDIT: bool>(body: &Body, m: &mut Motion, f: f64, t: f64) -> StepIntegrals {
    advance_traced::<AUDIT, false>(body, m, f, t, &mut Increments::default())
}

/// [`advance`]; with `TRACE` it also appends to `trace` each increment Δ it adds to the
/// position (`m.x += Δ`, at most two), in order. The arithmetic is the same either way.
#[inline]
pub fn advance_traced<const AUDIT: bool, const TRACE: bool>(
    body: &Body,
    m: &mut Motion,
    f: f64,
    t: f64,
    trace: &mut Increments,
) -> StepIntegrals {
    let mut out = StepIntegrals::default();
    let mut rem = t;
    let c = body.coulomb;
    if m.v != 0.0 {
        let s = sign(m.v);
        let a = f - c * s;
        let acc = a * body.inv_mass;
        let (dx, v1, iv2) = free::<AUDIT>(body, m.v, acc, rem);
        if v1 * s > 0.0 || a * s >= 0.0 {
            m.x += dx;
            if TRACE {
                trace.push(dx);
            }
            m.v = v1;
            if AUDIT {
                out.int_v2 += iv2;
                out.int_abs_v += dx.abs();
            }
            return out;
        }
        // Velocity reaches zero at t* = (m|v0|/|a|)·ln(1 + y)/y, y = k·m|v0|/|a|.
        let t0 = m.v.abs() / acc.abs();
        let tc = (t0 * log1p_over(body.rate * t0)).min(rem);
        let (dx, _, iv2) = free::<AUDIT>(body, m.v, acc, tc);
        m.x += dx;
        if TRACE {
            trace.push(dx);
        }
        m.v = 0.0;
        rem -= tc;
        out.crossings = 1;
        if AUDIT {
            out.int_v2 += iv2;
            out.int_abs_v += dx.abs();
        }
    }
    // At rest: stick while |f| ≤ c, otherwise slip in the direction of f.
    if f.abs() <= c || rem <= 0.0 {
        out.stuck = f.abs() <= c;
        return out;
    }
    let s = sign(f);
    let acc = (f - c * s) * body.inv_mass;
    let (dx, v1, iv2) = free::<AUDIT>(body, 0.0, acc, rem);
    m.x += dx;
    if TRACE {
        trace.push(dx);
    }
    m.v = v1;
    if AUDIT {
        out.int_v2 += iv2;
        out.int_abs_v += dx.abs();
    }
    out
}

/// The device in SI units, for the firmware servo loop and the virtual device.
///
/// `advance(force_n, dt_s)` applies a constant force for `dt_s` seconds and returns the exact
/// state at the end; `encoder_count()` is ⌊x/Δ⌋. No allocation, no panics, no loops: suitable
/// for the no_std firmware (f64 is software-emulated on the Cortex-M4F, ~2 exp/log per call).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhysicalPlant {
    body: Body,
    resolution_m: f64,
    state: Motion,
}

impl PhysicalPlant {
    /// A plant at rest at x = 0. Mass in kg, viscous friction in N·s/m, dynamic Coulomb friction
    /// in N, encoder resolution Δ in m.
    ///
    /// # Errors
    /// [`ParamError`] naming `mass_kg`, `viscous_ns_per_m`, `coulomb_n` or `resolution_m` and
    /// its allowed range (mass and resolution finite and > 0, frictions finite and ≥ 0).
    pub fn new(
        mass_kg: f64,
        viscous_ns_per_m: f64,
        coulomb_n: f64,
        resolution_m: f64,
    ) -> Result<Self, ParamError> {
        check_positive("mass_kg", mass_kg)?;
        check_non_negative("viscous_ns_per_m", viscous_ns_per_m)?;
        check_non_negative("coulomb_n", coulomb_n)?;
        check_positive("resolution_m", resolution_m)?;
        Ok(Self {
            body: Body::new(mass_kg, viscous_ns_per_m, coulomb_n),
            resolution_m,
            state: Motion::default(),
        })
    }

    /// Sets position (m) and velocity (m/s).
    pub fn set_state(&mut self, position_m: f64, velocity_m_per_s: f64) {
        self.state = Motion {
            x: position_m,
            v: velocity_m_per_s,
        };
    }

    /// Applies `force_n` (N, constant) for `dt_s` seconds and returns the exact state at the
    /// end. A negative or non-finite duration is a no-op; a non-finite force is treated as 0 N.
    pub fn advance(&mut self, force_n: f64, dt_s: f64) -> Motion {
        let f = if force_n.is_finite() { force_n } else { 0.0 };
        if dt_s > 0.0 && dt_s.is_finite() {
            advance::<false>(&self.body, &mut self.state, f, dt_s);
        }
        self.state
    }

    /// Position in m.
    #[must_use]
    pub fn position_m(&self) -> f64 {
        self.state.x
    }

    /// Velocity in m/s.
    #[must_use]
    pub fn velocity_m_per_s(&self) -> f64 {
        self.state.v
    }

    /// Encoder count ⌊x/Δ⌋ (saturating at the i64 range).
    #[must_use]
    pub fn encoder_count(&self) -> i64 {
        crate::math::floor_i64(self.state.x / self.resolution_m)
    }

    /// The body (m, b, c) in SI units.
    #[must_use]
    pub fn body(&self) -> &Body {
        &self.body
    }
}

/// The device in dimensionless units (Table I), stepped one constant-force interval at a time:
/// the firmware-facing twin of [`PhysicalPlant`] for tests written in ticks and periods.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DimensionlessPlant {
    body: Body,
    state: Motion,
}

impl DimensionlessPlant {
    /// A plant with μ, β, σ of `params` (τ_D is the controller's business), at rest at ξ = 0.
    ///
    /// # Errors
    /// [`ParamError`] when μ, β or σ is out of range (core's [`Params::validate`]).
    pub fn new(params: &Params) -> Result<Self, ParamError> {
        params.validate()?;
        Ok(Self {
            body: Body::new(params.mu, params.beta, params.sigma),
            state: Motion::default(),
        })
    }

    /// Sets ξ (ticks) and ξ̇ (ticks per period).
    pub fn set_state(&mut self, xi: f64, xidot: f64) {
        self.state = Motion { x: xi, v: xidot };
    }

    /// Applies the constant force `phi_a` (K·Δ) for `dtau` periods and returns the exact state
    /// at the end. A negative or non-finite duration is a no-op; a non-finite force counts as 0.
    pub fn step(&mut self, phi_a: f64, dtau: f64) -> Motion {
        let f = if phi_a.is_finite() { phi_a } else { 0.0 };
        if dtau > 0.0 && dtau.is_finite() {
            advance::<false>(&self.body, &mut self.state, f, dtau);
        }
        self.state
    }

    /// One full sampling period under `phi_a`: the state at the next sample instant.
    pub fn step_period(&mut self, phi_a: f64) -> Motion {
        self.step(phi_a, 1.0)
    }

    /// Current state.
    #[must_use]
    pub fn state(&self) -> Motion {
        self.state
    }

    /// Encoder count ⌊ξ⌋.
    #[must_use]
    pub fn encoder_count(&self) -> i64 {
        crate::math::floor_i64(self.state.x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn beta_zero_is_the_parabola() {
        let b = Body::new(2.0, 0.0, 0.0);
        let mut m = Motion { x: 1.0, v: 3.0 };
        advance::<false>(&b, &mut m, 4.0, 0.5);
        assert_eq!(m.v, 3.0 + 2.0 * 0.5);
        assert!((m.x - (1.0 + 1.5 + 0.25)).abs() < 1e-15);
    }

    #[test]
    fn sticks_when_force_within_coulomb() {
        let b = Body::new(1.0, 0.1, 1.0);
        let mut m = Motion { x: 0.0, v: 0.1 };
        let r = advance::<true>(&b, &mut m, -0.5, 1.0);
        assert_eq!(r.crossings, 1);
        assert!(r.stuck);
        assert_eq!(m.v, 0.0);
        // Stays stuck.
        let before = m;
        advance::<false>(&b, &mut m, 0.9, 10.0);
        assert_eq!(m, before);
    }

    #[test]
    fn reverses_when_force_exceeds_coulomb() {
        let b = Body::new(1.0, 0.0, 0.5);
        let mut m = Motion { x: 0.0, v: 1.0 };
        // a = -2 - 0.5 = -2.5: stops at t = 0.4, x = 0.2; then a = -1.5 for 0.6.
        advance::<false>(&b, &mut m, -2.0, 1.0);
        assert!((m.v + 1.5 * 0.6).abs() < 1e-15);
        assert!((m.x - (0.2 - 0.75 * 0.36)).abs() < 1e-15);
    }

    /// The SI plant and the dimensionless plant agree through Table I (Freedom 6 of Table II).
    #[test]
    fn physical_and_dimensionless_agree() {
        let (m, b, c, delta, k, t) = (0.25, 0.01, 0.06, 20e-6, 2400.0, 1e-3);
        let mut phys = PhysicalPlant::new(m, b, c, delta).unwrap();
        let p = Params {
            mu: m / (k * t * t),
            beta: b / (k * t),
            sigma: c / (k * delta),
            tau_d: 0.0,
        };
        let mut dim = DimensionlessPlant::new(&p).unwrap();
        phys.set_state(0.0, 3.0 * delta / t);
        dim.set_state(0.0, 3.0);
        for _ in 0..500 {
            assert_eq!(phys.encoder_count(), dim.encoder_count());
            let n = phys.encoder_count() as f64;
            phys.advance(-k * delta * (n + 0.5), t);
            let s = dim.step_period(-(n + 0.5));
            assert!((phys.position_m() / delta - s.x).abs() < 1e-9 * (1.0 + s.x.abs()));
            assert!((phys.velocity_m_per_s() * t / delta - s.v).abs() < 1e-9 * (1.0 + s.v.abs()));
        }
    }

    #[test]
    fn physical_plant_validates() {
        assert_eq!(
            PhysicalPlant::new(0.0, 0.0, 0.0, 1e-5).map_err(|e| e.name()),
            Err("mass_kg")
        );
        let mut p = PhysicalPlant::new(0.25, 0.01, 0.06, 20e-6).unwrap();
        p.set_state(-1e-6, 0.0);
        assert_eq!(p.encoder_count(), -1);
        let s = p.advance(1.0, 1e-3);
        assert!(s.v > 0.0);
    }
}
