//! The validated physical plant of a scene: a rigid (or two-mass) device with every optional
//! effect of issue 10, in SI units.
//!
//! Units: linear devices in m, m/s, kg, N, N·s/m, N/m; rotary devices (`counts_per_rev` set)
//! use the same fields in rad, rad/s, kg·m², N·m, N·m·s/rad, N·m/rad. Every field named `_n`
//! is then a torque, `_m` an angle, `_kg` an inertia.
//!
//! Invariants (checked by [`PlantModel::validate`], which every constructor in this module
//! calls): masses > 0, damping and friction ≥ 0, `static_n ≥ coulomb_n`, resolution > 0, every
//! value finite; optional effects are `None` when off.

/// Static friction with a Stribeck decay to the dynamic level `coulomb_n` of the plant.
///
/// Sliding friction magnitude at speed |v|: `c + (static_n − c)·exp(−(v/stribeck_m_per_s)²)`;
/// with `stribeck_m_per_s = 0` it is `c` at every non-zero speed (a pure static/dynamic switch).
/// At rest the friction holds any net force up to `static_n` (the stick rule of
/// [`crate::rich::friction`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stiction {
    /// Breakaway force F_s, N (N·m), ≥ `coulomb_n`.
    pub static_n: f64,
    /// Stribeck velocity v_s, m/s (rad/s), ≥ 0; 0 = no decay (switch).
    pub stribeck_m_per_s: f64,
}

/// Position-periodic cogging force `F = amplitude_n · sin(2π x / period_m)` on the motor side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cogging {
    /// Amplitude, N (N·m), ≥ 0.
    pub amplitude_n: f64,
    /// Spatial period, m (rad), > 0.
    pub period_m: f64,
}

/// Compliant transmission: the encoder, actuator, friction and cogging act on the motor mass,
/// the user (hand) on the link mass; the two are joined by a spring and a damper.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transmission {
    /// Link-side mass m₂, kg (kg·m²), > 0.
    pub link_mass_kg: f64,
    /// Spring k_t, N/m (N·m/rad), > 0.
    pub stiffness_n_per_m: f64,
    /// Damper d_t, N·s/m (N·m·s/rad), ≥ 0.
    pub damping_ns_per_m: f64,
}

/// The current amplifier: optional second-order low-pass filter, dead band and saturation.
///
/// The held command u is first shaped by the dead band (`|u| ≤ d → 0`, otherwise
/// `u − d·sgn(u)`), then clipped to ±`force_limit_n`, then filtered
/// (p̈ + 2ζω ṗ + ω² p = ω² u'); the filter output is clipped to ±`force_limit_n` again (an
/// under-damped filter cannot overshoot the current limit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Amplifier {
    /// Filter cut-off ω/2π, Hz; `None` = ideal (no filter).
    pub cutoff_hz: Option<f64>,
    /// Filter damping ratio ζ (> 0; unused without a filter).
    pub damping_ratio: f64,
    /// Output saturation, N (N·m), > 0.
    pub force_limit_n: Option<f64>,
    /// Dead band, N (N·m), ≥ 0.
    pub deadband_n: Option<f64>,
}

/// A hand: mass added to the body it holds, damping and a spring to the anchor at x = 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandSi {
    /// Mass, kg (kg·m²), ≥ 0.
    pub mass_kg: f64,
    /// Damping, N·s/m, ≥ 0.
    pub damping_ns_per_m: f64,
    /// Stiffness to the anchor, N/m, ≥ 0.
    pub stiffness_n_per_m: f64,
}

/// Contact frequency of a default (hard) end stop with the motor-side mass, Hz: the stop's
/// stiffness defaults to m·(2π·[`HARD_STOP_HZ`])², far above any wall a servo at 1–20 kHz
/// renders on the same mass.
pub const HARD_STOP_HZ: f64 = 1000.0;
/// Damping ratio of a default end stop with the motor-side mass (a rubber bumper: the
/// contact rebounds little); its damping defaults to 2·ζ·√(k·m).
pub const HARD_STOP_DAMPING_RATIO: f64 = 0.7;

/// The device's travel: mechanical end stops at `min_m` and `max_m` on the motor (encoder)
/// side, each a one-sided spring and damper that acts only while the motor is past it and
/// only pushes (the contact force is −max(0, k·δ + d·v) at the upper stop, δ = x₁ − max_m,
/// and mirrored at the lower one), so a motor leaving a stop separates without being held.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Travel {
    /// Lower end stop, m (rad).
    pub min_m: f64,
    /// Upper end stop, m (rad), > `min_m`.
    pub max_m: f64,
    /// Stop stiffness, N/m (N·m/rad), > 0.
    pub stop_stiffness_n_per_m: f64,
    /// Stop damping, N·s/m (N·m·s/rad), ≥ 0.
    pub stop_damping_ns_per_m: f64,
}

impl Travel {
    /// End stops at `min_m` and `max_m` with the given stiffness and damping, or the defaults
    /// of a hard stop for the motor-side mass `mass_kg` ([`HARD_STOP_HZ`],
    /// [`HARD_STOP_DAMPING_RATIO`]) where `None`.
    #[must_use]
    pub fn with_defaults(
        min_m: f64,
        max_m: f64,
        stiffness: Option<f64>,
        damping: Option<f64>,
        mass_kg: f64,
    ) -> Self {
        let w = 2.0 * core::f64::consts::PI * HARD_STOP_HZ;
        let k = stiffness.unwrap_or(mass_kg * w * w);
        let d = damping.unwrap_or(2.0 * HARD_STOP_DAMPING_RATIO * libm::sqrt(k * mass_kg));
        Self {
            min_m,
            max_m,
            stop_stiffness_n_per_m: k,
            stop_damping_ns_per_m: d,
        }
    }

    /// Whether `x_m` lies inside the travel (stops included).
    #[must_use]
    pub fn contains(&self, x_m: f64) -> bool {
        x_m >= self.min_m && x_m <= self.max_m
    }

    /// The contact force of the stops at motor position `x_m` and velocity `v_m_per_s`, N
    /// (N·m): 0 inside the travel, and only pushing back inside.
    #[must_use]
    pub fn contact_force_n(&self, x_m: f64, v_m_per_s: f64) -> f64 {
        let (k, d) = (self.stop_stiffness_n_per_m, self.stop_damping_ns_per_m);
        if x_m > self.max_m {
            -(k * (x_m - self.max_m) + d * v_m_per_s).max(0.0)
        } else if x_m < self.min_m {
            (k * (self.min_m - x_m) - d * v_m_per_s).max(0.0)
        } else {
            0.0
        }
    }
}

/// Largest dead band of [`WallDamper::DeadBand`], counts per tick (the firmware's
/// `stiffwall_proto::MAX_DEADBAND_COUNTS`).
pub const MAX_DAMPER_DEAD_BAND: u8 = crate::exact::MAX_DEAD_BAND;

/// How the virtual device's wall damper turns the count difference dn = n_h − n_(h−1) into a
/// velocity (`controller.damper`; the firmware's `DamperLaw`). Part of the boot configuration
/// only: this crate's simulators damp the plain difference.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WallDamper {
    /// `"difference"`: v = dn.
    Difference,
    /// `"dead-band-N"`: v = 0 when |dn| ≤ N counts, else v = dn (N in
    /// 1..=[`MAX_DAMPER_DEAD_BAND`]).
    DeadBand(u8),
}

impl WallDamper {
    /// The dead band in counts per tick: 0 for the plain difference (the exact solver's
    /// `Exact::with_dead_band` argument).
    #[must_use]
    pub fn dead_band(self) -> u8 {
        match self {
            Self::Difference => 0,
            Self::DeadBand(n) => n,
        }
    }

    /// Parses `"difference"` or `"dead-band-N"` (N decimal without sign or leading zeros, in
    /// 1..=[`MAX_DAMPER_DEAD_BAND`]); `None` for anything else.
    #[must_use]
    pub fn parse(s: &str) -> Option<Self> {
        if s == "difference" {
            return Some(Self::Difference);
        }
        let digits = s.strip_prefix("dead-band-")?;
        if digits.is_empty() || digits.len() > 3 || digits.starts_with('0') {
            return None;
        }
        if !digits.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        let n: u8 = digits.parse().ok()?;
        (1..=MAX_DAMPER_DEAD_BAND)
            .contains(&n)
            .then_some(Self::DeadBand(n))
    }
}

impl core::fmt::Display for WallDamper {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Difference => f.write_str("difference"),
            Self::DeadBand(n) => write!(f, "dead-band-{n}"),
        }
    }
}

/// The controller of a scene (boot configuration of the virtual device).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Controller {
    /// Wall stiffness K, N/m (N·m/rad).
    pub stiffness_n_per_m: f64,
    /// Virtual damping B of the wall law's backward difference, N·s/m (N·m·s/rad), ≥ 0
    /// (`controller.virtual_damping_ns_per_m`; 0: a spring-only wall).
    pub virtual_damping_ns_per_m: f64,
    /// Sampling period T, s.
    pub period_s: f64,
    /// Total extra delay, s: `controller.extra_delay_s` plus an amplifier of kind `"delay"`
    /// (2ζ/ω), as in the scene's τ_D.
    pub extra_delay_s: f64,
    /// One-sided wall (force only for x < 0).
    pub one_sided: bool,
    /// Quantised position in the spring law (eq. (8)); `false`: the ideal spring.
    pub quantization: bool,
    /// The wall damper's law on the virtual device (`controller.damper`; `None`: not given,
    /// the firmware's default). The simulators here damp the plain difference.
    pub damper: Option<WallDamper>,
}

/// The validated physical plant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlantModel {
    /// Motor-side mass m, kg (kg·m²).
    pub mass_kg: f64,
    /// Viscous friction b, N·s/m.
    pub viscous_ns_per_m: f64,
    /// Dynamic Coulomb friction c, N.
    pub coulomb_n: f64,
    /// Encoder resolution Δ, m (rad).
    pub resolution_m: f64,
    /// Counts per revolution of a rotary device (`None`: linear).
    pub counts_per_rev: Option<u32>,
    /// Static friction and Stribeck decay.
    pub stiction: Option<Stiction>,
    /// Cogging.
    pub cogging: Option<Cogging>,
    /// Compliant transmission.
    pub transmission: Option<Transmission>,
    /// Amplifier filter, dead band, saturation.
    pub amplifier: Option<Amplifier>,
    /// Hand (on the link side when there is a transmission).
    pub hand: Option<HandSi>,
    /// End stops (`None`: unbounded travel, the paper's plant).
    pub travel: Option<Travel>,
}

/// An invalid model value (names the field and the allowed range): the rich physics' own
/// error. With `std` it is a `thiserror` error; the no_std build formats the same message.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "std", derive(thiserror::Error))]
#[cfg_attr(feature = "std", error("{key}: allowed range is {allowed}"))]
pub struct ModelError {
    /// Field, as the scene key (e.g. `effects.stiction.static_n`).
    pub key: &'static str,
    /// Allowed range.
    pub allowed: &'static str,
}

#[cfg(not(feature = "std"))]
impl core::fmt::Display for ModelError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}: allowed range is {}", self.key, self.allowed)
    }
}

fn chk(ok: bool, key: &'static str, allowed: &'static str) -> Result<(), ModelError> {
    if ok {
        Ok(())
    } else {
        Err(ModelError { key, allowed })
    }
}

fn pos(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

fn nonneg(v: f64) -> bool {
    v.is_finite() && v >= 0.0
}

/// The amplifier's filter, saturation and dead band (part of [`PlantModel::validate`]).
fn validate_amplifier(a: &Amplifier) -> Result<(), ModelError> {
    if let Some(f) = a.cutoff_hz {
        chk(
            pos(f) && f <= 1e7,
            "effects.amplifier.cutoff_hz",
            "(0, 1e7] Hz",
        )?;
        chk(
            pos(a.damping_ratio) && a.damping_ratio <= 100.0,
            "effects.amplifier.damping",
            "(0, 100]",
        )?;
    }
    if let Some(l) = a.force_limit_n {
        chk(
            pos(l) && l <= 1e9,
            "effects.amplifier.force_limit_n",
            "(0, 1e9] N",
        )?;
    }
    if let Some(d) = a.deadband_n {
        chk(
            nonneg(d) && d <= 1e9,
            "effects.amplifier.deadband_n",
            "[0, 1e9] N",
        )?;
    }
    Ok(())
}

/// The end stops (part of [`PlantModel::validate`]).
fn validate_travel(t: &Travel) -> Result<(), ModelError> {
    chk(
        t.min_m.is_finite() && t.min_m.abs() <= 1e3,
        "effects.travel.min_m",
        "[-1e3, 1e3] m (rad), below effects.travel.max_m",
    )?;
    chk(
        t.max_m.is_finite() && t.max_m.abs() <= 1e3 && t.max_m > t.min_m,
        "effects.travel.max_m",
        "(effects.travel.min_m, 1e3] m (rad)",
    )?;
    chk(
        pos(t.stop_stiffness_n_per_m) && t.stop_stiffness_n_per_m <= 1e12,
        "effects.travel.stop_stiffness_n_per_m",
        "(0, 1e12] N/m (N m/rad)",
    )?;
    chk(
        nonneg(t.stop_damping_ns_per_m) && t.stop_damping_ns_per_m <= 1e9,
        "effects.travel.stop_damping_ns_per_m",
        "[0, 1e9] N s/m (N m s/rad)",
    )
}

impl PlantModel {
    /// The paper's plant: rigid mass, viscous and dynamic Coulomb friction, no optional effect.
    pub fn rigid(
        mass_kg: f64,
        viscous_ns_per_m: f64,
        coulomb_n: f64,
        resolution_m: f64,
    ) -> Result<Self, ModelError> {
        let m = Self {
            mass_kg,
            viscous_ns_per_m,
            coulomb_n,
            resolution_m,
            counts_per_rev: None,
            stiction: None,
            cogging: None,
            transmission: None,
            amplifier: None,
            hand: None,
            travel: None,
        };
        m.validate()?;
        Ok(m)
    }

    /// Checks every invariant of the module header.
    pub fn validate(&self) -> Result<(), ModelError> {
        chk(pos(self.mass_kg), "device.mass_kg", "(0, 1e6] kg")?;
        chk(
            nonneg(self.viscous_ns_per_m),
            "device.viscous_ns_per_m",
            "[0, 1e9] N s/m",
        )?;
        chk(nonneg(self.coulomb_n), "device.coulomb_n", "[0, 1e9] N")?;
        chk(pos(self.resolution_m), "device.resolution_m", "(0, 1] m")?;
        if let Some(s) = self.stiction {
            chk(
                s.static_n.is_finite() && s.static_n >= self.coulomb_n && s.static_n <= 1e9,
                "effects.stiction.static_n",
                "[device.coulomb_n, 1e9] N",
            )?;
            chk(
                nonneg(s.stribeck_m_per_s) && s.stribeck_m_per_s <= 1e3,
                "effects.stiction.stribeck_m_per_s",
                "[0, 1e3] m/s",
            )?;
        }
        if let Some(c) = self.cogging {
            chk(
                nonneg(c.amplitude_n) && c.amplitude_n <= 1e9,
                "effects.cogging.amplitude_n",
                "[0, 1e9] N",
            )?;
            chk(
                pos(c.period_m) && c.period_m <= 1e3,
                "effects.cogging.period_m",
                "(0, 1e3] m",
            )?;
        }
        if let Some(t) = self.transmission {
            chk(
                pos(t.link_mass_kg) && t.link_mass_kg <= 1e6,
                "effects.transmission.link_mass_kg",
                "(0, 1e6] kg",
            )?;
            chk(
                pos(t.stiffness_n_per_m) && t.stiffness_n_per_m <= 1e12,
                "effects.transmission.stiffness_n_per_m",
                "(0, 1e12] N/m",
            )?;
            chk(
                nonneg(t.damping_ns_per_m) && t.damping_ns_per_m <= 1e9,
                "effects.transmission.damping_ns_per_m",
                "[0, 1e9] N s/m",
            )?;
        }
        if let Some(a) = self.amplifier {
            validate_amplifier(&a)?;
        }
        if let Some(t) = self.travel {
            validate_travel(&t)?;
        }
        if let Some(h) = self.hand {
            chk(nonneg(h.mass_kg), "effects.hand.mass_kg", "[0, 1e6] kg")?;
            chk(
                nonneg(h.damping_ns_per_m),
                "effects.hand.damping_ns_per_m",
                "[0, 1e9] N s/m",
            )?;
            chk(
                nonneg(h.stiffness_n_per_m),
                "effects.hand.stiffness_n_per_m",
                "[0, 1e12] N/m",
            )?;
        }
        Ok(())
    }

    /// The amplifier's saturation, when the plant sets one (N or N·m).
    #[must_use]
    pub fn force_limit_n(&self) -> Option<f64> {
        self.amplifier.and_then(|a| a.force_limit_n)
    }

    /// Breakaway friction F_s (= `coulomb_n` without stiction).
    #[must_use]
    pub fn static_friction_n(&self) -> f64 {
        self.stiction.map_or(self.coulomb_n, |s| s.static_n)
    }

    /// Whether the motion is piecewise closed-form ([`crate::rich::RichPlant`] then steps it
    /// exactly): no cogging and no Stribeck decay. A rigid plant without hand or filter is
    /// stepped by [`crate::rich::friction::advance_switch`]; one with a transmission, a hand or
    /// an amplifier filter is linear between events and stepped by [`crate::rich::linear`].
    #[must_use]
    pub fn is_exact(&self) -> bool {
        self.cogging.is_none() && self.stiction.is_none_or(|s| s.stribeck_m_per_s == 0.0)
    }

    /// Whether the plant is a rigid mass with friction alone (no transmission, hand or
    /// amplifier filter): the closed form of [`crate::rich::friction::advance_switch`].
    #[must_use]
    pub fn is_rigid(&self) -> bool {
        self.travel.is_none()
            && self.transmission.is_none()
            && self.hand.is_none()
            && self.amplifier.and_then(|a| a.cutoff_hz).is_none()
    }

    /// Whether any effect beyond the paper's plant (and the existing hand and filter) is on:
    /// stiction, cogging, transmission, force limit, dead band or end stops.
    #[must_use]
    pub fn has_new_effects(&self) -> bool {
        self.travel.is_some()
            || self.stiction.is_some()
            || self.cogging.is_some()
            || self.transmission.is_some()
            || self
                .amplifier
                .is_some_and(|a| a.force_limit_n.is_some() || a.deadband_n.is_some())
    }

    /// The amplifier's static map: dead band then saturation of the held command (N).
    #[must_use]
    pub fn shape_command(&self, u: f64) -> f64 {
        let u = if u.is_finite() { u } else { 0.0 };
        let Some(a) = self.amplifier else {
            return u;
        };
        let mut u = u;
        if let Some(d) = a.deadband_n {
            u = if u.abs() <= d {
                0.0
            } else {
                u - if u > 0.0 { d } else { -d }
            };
        }
        if let Some(l) = a.force_limit_n {
            u = u.clamp(-l, l);
        }
        u
    }
}
