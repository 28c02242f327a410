//! [`RichPlant`]: the stepping plant of a [`PlantModel`] for the virtual device and the sampled
//! scene loop, exact where the model is piecewise closed-form, a reference integrator otherwise.
//!
//! Units: SI at this API (m, m/s, N, s; rotary: rad, rad/s, N·m). State y = [x₁, v₁, x₂, v₂, p,
//! ṗ]: motor position and velocity (the encoder side), link position and velocity (= motor
//! without a transmission), amplifier filter output p (N) and its rate.
//!
//! Equations (each term only when its effect is on):
//! - motor: m₁ v̇₁ = F_A + F_cog(x₁) + F_stop + k_t(x₂ − x₁) + d_t(v₂ − v₁) − b v₁ − F_fric,
//!   with F_cog = A·sin(2π x₁/P), F_A = clip(p) (filter) or the shaped command (no filter),
//!   F_stop the end stops' one-sided contact ([`crate::rich::Travel::contact_force_n`]);
//! - link: m₂ v̇₂ = −k_t(x₂ − x₁) − d_t(v₂ − v₁) + F_H, F_H = −k_h x₂ − b_h v₂ (hand anchored at
//!   x = 0; its mass adds to m₂; without a transmission the hand acts on the motor);
//! - amplifier: p̈ + 2ζω ṗ + ω² p = ω² u', u' = the command after dead band and saturation
//!   ([`PlantModel::shape_command`]);
//! - friction: the stick rule of [`crate::rich::friction`] (sliding −F(|v₁|)·sgn v₁, stuck
//!   while |f_ext| ≤ F_s, events located).
//!
//! Engines: [`PlantModel::is_exact`] models step in closed form: rigid ones without travel by
//! [`crate::rich::friction::advance_switch`], those with a transmission, hand, filter or end
//! stops by the matrix exponential of [`crate::rich::linear`] (a stop's contact and release are
//! located as events there); the others (cogging, Stribeck decay) with
//! Dormand–Prince 5(4) of [`crate::dopri`] (rtol 1e-9,
//! atol 1e-6 in units of Δ, Δ/ms, max(F_s, 1 mN), per ms) or the method given to
//! [`RichPlant::with_method`].
//!
//! Invariants: `advance` never allocates, never panics, and ends (at most [`MAX_EVENTS`] mode
//! switches per call, then the rest of the interval is skipped: a Zeno guard); non-finite
//! commands count as 0 N.

use super::friction::{advance_switch, sliding_n, stick_rule};
use super::linear::{Linear, LinearPlant};
use super::model::{ModelError, PlantModel};
use crate::dopri::{Field, OdeMethod, OdeStats, Stepper};
use crate::plant::{Body, Motion};

/// Dimension of the state (motor x, v; link x, v; amplifier p, ṗ).
pub const NS: usize = 6;
/// A state vector [x₁, v₁, x₂, v₂, p, ṗ].
pub type State = [f64; NS];

/// Mode switches handled by one [`RichPlant::advance`] call at most.
pub const MAX_EVENTS: u32 = 10_000;

/// Constants derived once from the model.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Derived {
    inv_m1: f64,
    inv_m2: f64,
    b: f64,
    c: f64,
    fs: f64,
    vs: f64,
    cog_a: f64,
    cog_w: f64,
    kt: f64,
    dt: f64,
    trans: bool,
    kh: f64,
    bh: f64,
    hand_on_link: bool,
    amp_w: f64,
    amp_z: f64,
    filter: bool,
    limit: f64,
    /// The same constants for the linear engine (and the one `f_ext`).
    lin: LinearPlant,
}

impl Derived {
    fn new(m: &PlantModel) -> Self {
        let hand = m.hand.unwrap_or(super::model::HandSi {
            mass_kg: 0.0,
            damping_ns_per_m: 0.0,
            stiffness_n_per_m: 0.0,
        });
        let trans = m.transmission;
        let (m1, m2) = match trans {
            Some(t) => (m.mass_kg, t.link_mass_kg + hand.mass_kg),
            None => (m.mass_kg + hand.mass_kg, 1.0),
        };
        let (amp_w, amp_z) = match m
            .amplifier
            .and_then(|a| a.cutoff_hz.map(|f| (f, a.damping_ratio)))
        {
            Some((f, z)) => (2.0 * core::f64::consts::PI * f, z),
            None => (0.0, 0.0),
        };
        let (cog_a, cog_w) = m.cogging.map_or((0.0, 0.0), |c| {
            (c.amplitude_n, 2.0 * core::f64::consts::PI / c.period_m)
        });
        let lin = LinearPlant {
            inv_m1: 1.0 / m1,
            inv_m2: 1.0 / m2,
            b: m.viscous_ns_per_m,
            c: m.coulomb_n,
            fs: m.static_friction_n(),
            kt: trans.map_or(0.0, |t| t.stiffness_n_per_m),
            dt: trans.map_or(0.0, |t| t.damping_ns_per_m),
            trans: trans.is_some(),
            kh: hand.stiffness_n_per_m,
            bh: hand.damping_ns_per_m,
            amp_w,
            amp_z,
            limit: m.force_limit_n().unwrap_or(f64::INFINITY),
            pos_scale: m.resolution_m,
            force_scale: m.static_friction_n().max(1e-3),
            stop_lo: m.travel.map_or(f64::NEG_INFINITY, |t| t.min_m),
            stop_hi: m.travel.map_or(f64::INFINITY, |t| t.max_m),
            stop_k: m.travel.map_or(0.0, |t| t.stop_stiffness_n_per_m),
            stop_d: m.travel.map_or(0.0, |t| t.stop_damping_ns_per_m),
        };
        Self {
            inv_m1: lin.inv_m1,
            inv_m2: lin.inv_m2,
            b: lin.b,
            c: lin.c,
            fs: lin.fs,
            vs: m.stiction.map_or(0.0, |s| s.stribeck_m_per_s),
            cog_a,
            cog_w,
            kt: lin.kt,
            dt: lin.dt,
            trans: lin.trans,
            kh: lin.kh,
            bh: lin.bh,
            hand_on_link: lin.trans,
            amp_w,
            amp_z,
            filter: amp_w > 0.0,
            limit: lin.limit,
            lin,
        }
    }

    /// Force of the amplifier on the motor for state y and shaped command u.
    #[inline]
    fn actuator(&self, y: &State, u: f64) -> f64 {
        if self.filter {
            y[4].clamp(-self.limit, self.limit)
        } else {
            u
        }
    }

    /// Net non-friction, non-viscous force on the motor.
    #[inline]
    fn f_ext(&self, y: &State, u: f64) -> f64 {
        let cog = if self.cog_a != 0.0 {
            self.cog_a * libm::sin(self.cog_w * y[0])
        } else {
            0.0
        };
        self.lin.f_ext(y, u, cog)
    }
}

/// The vector field for one mode (`slide` = ±1 sliding, 0 stuck) and one held command.
struct Dyn<'a> {
    d: &'a Derived,
    u: f64,
    slide: f64,
}

impl Field<NS> for Dyn<'_> {
    fn rhs(&self, y: &State, dy: &mut State) {
        let d = self.d;
        *dy = [0.0; NS];
        if self.slide != 0.0 {
            let fric = self.slide * sliding_n(d.c, d.fs, d.vs, y[1].abs());
            dy[0] = y[1];
            dy[1] = (d.f_ext(y, self.u) - d.b * y[1] - fric) * d.inv_m1;
        }
        if d.trans {
            let v1 = if self.slide != 0.0 { y[1] } else { 0.0 };
            let fl = -d.kt * (y[2] - y[0]) - d.dt * (y[3] - v1) - d.kh * y[2] - d.bh * y[3];
            dy[2] = y[3];
            dy[3] = fl * d.inv_m2;
        }
        if d.filter {
            let w = d.amp_w;
            dy[4] = y[5];
            dy[5] = w * w * (self.u - y[4]) - 2.0 * d.amp_z * w * y[5];
        }
    }

    fn fired(&self, y: &State) -> bool {
        if self.slide != 0.0 {
            self.slide * y[1] <= 0.0
        } else {
            self.d.f_ext(y, self.u).abs() > self.d.fs
        }
    }
}

// The linear engine carries its transition-matrix cache inline (about 1.9 KB): the no_std
// build has no allocator to box it, and a plant is copied only when a trial starts.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
enum Engine {
    /// Rigid mass with friction: [`advance_switch`].
    Exact(Body),
    /// Linear between events (transmission, hand, filter): [`Linear`].
    Linear(Linear),
    /// Reference integrator.
    Ode(Stepper<NS>),
}

/// The plant of a scene, stepped one held command at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RichPlant {
    model: PlantModel,
    d: Derived,
    engine: Engine,
    y: State,
    /// ±1 sliding, 0 stuck.
    slide: f64,
    /// Last shaped command (N).
    u: f64,
}

impl RichPlant {
    /// The plant at rest at x = 0: exact when [`PlantModel::is_exact`], otherwise
    /// Dormand–Prince 5(4) at rtol 1e-9, atol 1e-6 (module header).
    pub fn new(model: &PlantModel) -> Result<Self, ModelError> {
        let method = if model.is_exact() {
            None
        } else {
            Some(OdeMethod::Dopri {
                rtol: 1e-9,
                atol: 1e-6,
            })
        };
        Self::with_method(model, method)
    }

    /// The plant with a chosen engine: `None` = exact (an error naming `run.solver` when the
    /// model is not piecewise closed-form), `Some(method)` = that reference integrator.
    pub fn with_method(model: &PlantModel, method: Option<OdeMethod>) -> Result<Self, ModelError> {
        model.validate()?;
        let d = Derived::new(model);
        let engine = match method {
            None if model.is_exact() && model.is_rigid() => Engine::Exact(Body::new(
                model.mass_kg + model.hand.map_or(0.0, |h| h.mass_kg),
                model.viscous_ns_per_m,
                model.coulomb_n,
            )),
            None if model.is_exact() => Engine::Linear(Linear::new(d.lin)),
            None => {
                return Err(ModelError {
                    key: "run.solver",
                    allowed: "rk4 or dopri: kind = \"exact\" needs a plant without cogging or \
                              Stribeck decay",
                })
            }
            Some(m) => {
                let dx = model.resolution_m;
                let f = model.static_friction_n().max(1e-3);
                Engine::Ode(Stepper::new(m, [dx, dx * 1e3, dx, dx * 1e3, f, f * 1e3]))
            }
        };
        Ok(Self {
            model: *model,
            d,
            engine,
            y: [0.0; NS],
            slide: 0.0,
            u: 0.0,
        })
    }

    /// Measures the integrator's absolute error in Δ, Δ/T, max(F_s, 1 mN), per T for the
    /// sampling period T = `period_s` (the default is T = 1 ms); no effect on the exact engine.
    pub fn set_tolerance_period(&mut self, period_s: f64) {
        if let Engine::Ode(s) = &mut self.engine {
            if period_s > 0.0 && period_s.is_finite() {
                let dx = self.model.resolution_m;
                let f = self.model.static_friction_n().max(1e-3);
                s.scale = [dx, dx / period_s, dx, dx / period_s, f, f / period_s];
            }
        }
    }

    /// Sets the whole plant to position `position_m` and velocity `velocity_m_per_s` (link =
    /// motor, spring relaxed, amplifier output 0).
    pub fn set_state(&mut self, position_m: f64, velocity_m_per_s: f64) {
        let x = if position_m.is_finite() {
            position_m
        } else {
            0.0
        };
        let v = if velocity_m_per_s.is_finite() {
            velocity_m_per_s
        } else {
            0.0
        };
        self.y = [x, v, x, v, 0.0, 0.0];
        self.slide = if v > 0.0 {
            1.0
        } else if v < 0.0 {
            -1.0
        } else {
            0.0
        };
    }

    /// Held at rest with the motor (encoder side) at `position_m`, as a hold (the paper's Fig. 8
    /// release test) leaves it just before the release: everything at rest in static
    /// equilibrium, friction aside. With a transmission the link sits where the transmission
    /// balances the hand's spring, x₂ = k_t·x₁/(k_t + k_h), so the link is not at x₁ when a
    /// hand holds it; with an amplifier filter its output is the holding force, which balances
    /// the transmission (or the hand's spring without one) and the cogging force at x₁. Without
    /// a hand spring this is [`RichPlant::set_state`] at rest (plus the filter's cogging hold).
    pub fn set_held(&mut self, position_m: f64) {
        self.set_state(position_m, 0.0);
        let x1 = self.y[0];
        if self.d.trans && self.d.kt + self.d.kh > 0.0 {
            self.y[2] = self.d.kt * x1 / (self.d.kt + self.d.kh);
        }
        if self.d.filter {
            // f_ext with p = 0 is the force on the motor besides the actuator's; the hold
            // cancels it.
            let hold = -self.d.f_ext(&self.y, 0.0);
            self.set_amplifier_output(hold);
        }
    }

    /// Sets the amplifier filter to a steady output `force_n` (N): p = force, ṗ = 0. No effect
    /// without a filter.
    pub fn set_amplifier_output(&mut self, force_n: f64) {
        if self.d.filter && force_n.is_finite() {
            self.y[4] = force_n;
            self.y[5] = 0.0;
        }
    }

    /// Applies the command `force_cmd_n` (held over the interval) for `dt_s` seconds; the
    /// amplifier's dead band, saturation and filter act inside. A non-positive or non-finite
    /// duration is a no-op.
    pub fn advance(&mut self, force_cmd_n: f64, dt_s: f64) {
        if !(dt_s > 0.0 && dt_s.is_finite()) {
            return;
        }
        let u = self.model.shape_command(force_cmd_n);
        self.u = u;
        // The stick rule at zero velocity, with the new command (the rigid closed form applies
        // it itself).
        if !matches!(self.engine, Engine::Exact(_)) && (self.slide == 0.0 || self.y[1] == 0.0) {
            self.y[1] = 0.0;
            self.slide = stick_rule(self.d.f_ext(&self.y, u), self.d.fs);
        }
        match &mut self.engine {
            Engine::Exact(body) => {
                let mut m = Motion {
                    x: self.y[0],
                    v: self.y[1],
                };
                let stuck = advance_switch(body, self.d.fs, &mut m, u, dt_s);
                self.y = [m.x, m.v, m.x, m.v, 0.0, 0.0];
                self.slide = if stuck || m.v == 0.0 {
                    0.0
                } else if m.v > 0.0 {
                    1.0
                } else {
                    -1.0
                };
            }
            Engine::Linear(lin) => {
                lin.advance(&mut self.y, &mut self.slide, u, dt_s, MAX_EVENTS);
            }
            Engine::Ode(stepper) => {
                let d = self.d;
                // Each interval is integrated afresh: its result is a function of the state
                // and the command alone, not of how many intervals came before (the virtual
                // device's idle time between commands varies with the host in `--fast`).
                stepper.reset_step();
                let mut rem = dt_s;
                let mut events = 0;
                while rem > 0.0 && events < MAX_EVENTS {
                    let field = Dyn {
                        d: &d,
                        u,
                        slide: self.slide,
                    };
                    let (t, ev) = stepper.run(&field, &mut self.y, rem);
                    rem -= t;
                    if !ev {
                        break;
                    }
                    events += 1;
                    if self.slide != 0.0 {
                        self.y[1] = 0.0;
                    }
                    self.slide = stick_rule(d.f_ext(&self.y, u), d.fs);
                }
            }
        }
    }

    /// Encoder count ⌊x₁/Δ⌋ (saturating at the i64 range).
    #[must_use]
    pub fn encoder_count(&self) -> i64 {
        crate::math::floor_i64(self.y[0] / self.model.resolution_m)
    }

    /// Motor (encoder-side) position, m (rad).
    #[must_use]
    pub fn position_m(&self) -> f64 {
        self.y[0]
    }

    /// Motor velocity, m/s (rad/s).
    #[must_use]
    pub fn velocity_m_per_s(&self) -> f64 {
        self.y[1]
    }

    /// Link (hand-side) position, m (rad); the motor position without a transmission.
    #[must_use]
    pub fn link_position_m(&self) -> f64 {
        if self.d.trans {
            self.y[2]
        } else {
            self.y[0]
        }
    }

    /// Link velocity, m/s (rad/s).
    #[must_use]
    pub fn link_velocity_m_per_s(&self) -> f64 {
        if self.d.trans {
            self.y[3]
        } else {
            self.y[1]
        }
    }

    /// The end stops' contact force on the motor now, N (N·m): 0 inside the travel or without
    /// one ([`crate::rich::Travel::contact_force_n`]).
    #[must_use]
    pub fn stop_force_n(&self) -> f64 {
        self.d.lin.stop_force(self.y[0], self.y[1])
    }

    /// Force the amplifier applies now, N (N·m).
    #[must_use]
    pub fn actuator_force_n(&self) -> f64 {
        self.d.actuator(&self.y, self.u)
    }

    /// Whether the motor is stuck (static friction holds it).
    #[must_use]
    pub fn is_stuck(&self) -> bool {
        self.slide == 0.0 && self.y[1] == 0.0
    }

    /// Whether the closed-form engine runs this plant.
    #[must_use]
    pub fn is_exact(&self) -> bool {
        matches!(self.engine, Engine::Exact(_) | Engine::Linear(_))
    }

    /// The whole state [x₁, v₁, x₂, v₂, p, ṗ].
    #[must_use]
    pub fn state(&self) -> State {
        self.y
    }

    /// Integrator work (zeros for the exact engine).
    #[must_use]
    pub fn stats(&self) -> OdeStats {
        match self.engine {
            Engine::Exact(_) | Engine::Linear(_) => OdeStats::default(),
            Engine::Ode(s) => s.stats,
        }
    }

    /// The model.
    #[must_use]
    pub fn model(&self) -> &PlantModel {
        &self.model
    }
}
