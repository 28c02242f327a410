//! The TOML layout of a scene, as read by serde: every table and key of the format, unchecked.
//!
//! Units are in the key names (`mass_kg`, `period_s`, …); dimensionless keys (`mu`, `beta`,
//! `sigma`, `tau_d`, `xi`, `xidot`) are in Table I units; the plant-effect tables of issue 10
//! (`stiction`, `cogging`, `transmission`) are SI. Invariant: unknown keys are rejected
//! (`deny_unknown_fields`); ranges and unit-system consistency are checked in `resolve`.

use crate::exact::History;
use serde::Deserialize;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScene {
    pub device: RawDevice,
    #[serde(default)]
    pub controller: RawController,
    pub effects: RawEffects,
    pub initial: RawInitial,
    pub run: RawRun,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawDevice {
    pub mu: Option<f64>,
    pub beta: Option<f64>,
    pub sigma: Option<f64>,
    pub mass_kg: Option<f64>,
    pub viscous_ns_per_m: Option<f64>,
    pub coulomb_n: Option<f64>,
    pub resolution_m: Option<f64>,
    /// Rotary device (issue 10): Δ = 2π/counts_per_rev rad.
    pub counts_per_rev: Option<u32>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawController {
    pub stiffness_n_per_m: Option<f64>,
    /// Virtual damping B of the wall, N·s/m (N·m·s/rad for rotary files); default 0.
    pub virtual_damping_ns_per_m: Option<f64>,
    /// The wall damper's law on the virtual device, `"difference"` or `"dead-band-N"`; default
    /// the firmware's (a dead band of one count).
    pub damper: Option<String>,
    pub period_s: Option<f64>,
    pub extra_delay_s: Option<f64>,
    pub tau_d: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawEffects {
    pub zoh: bool,
    pub quantization: bool,
    pub coulomb: bool,
    pub viscous: bool,
    pub delay: bool,
    pub one_sided_wall: bool,
    pub amplifier: RawAmp,
    pub hand: RawHand,
    pub stiction: Option<RawStiction>,
    pub cogging: Option<RawCogging>,
    pub transmission: Option<RawTransmission>,
    pub travel: Option<RawTravel>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
pub(super) enum RawAmp {
    /// Ideal amplifier (optionally with a force limit and a dead band).
    None {
        force_limit_n: Option<f64>,
        deadband_n: Option<f64>,
    },
    /// Pure delay of eq. (5): T_A = 2δ_A/ω_A.
    Delay {
        omega: Option<f64>,
        zeta: Option<f64>,
        cutoff_hz: Option<f64>,
        damping: Option<f64>,
        force_limit_n: Option<f64>,
        deadband_n: Option<f64>,
    },
    /// Second-order low-pass filter.
    SecondOrder {
        omega: Option<f64>,
        zeta: Option<f64>,
        cutoff_hz: Option<f64>,
        damping: Option<f64>,
        force_limit_n: Option<f64>,
        deadband_n: Option<f64>,
    },
}

impl RawAmp {
    /// The amplifier limits of issue 10 (force limit, dead band), on every kind.
    pub fn limits(&self) -> (Option<f64>, Option<f64>) {
        match *self {
            Self::None {
                force_limit_n,
                deadband_n,
            }
            | Self::Delay {
                force_limit_n,
                deadband_n,
                ..
            }
            | Self::SecondOrder {
                force_limit_n,
                deadband_n,
                ..
            } => (force_limit_n, deadband_n),
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
pub(super) enum RawHand {
    None,
    Dimensionless {
        mu: f64,
        beta: f64,
        kappa: f64,
    },
    Physical {
        mass_kg: f64,
        damping_ns_per_m: f64,
        stiffness_n_per_m: f64,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawInitial {
    pub xi: Option<f64>,
    pub xidot: Option<f64>,
    pub position_m: Option<f64>,
    pub velocity_m_per_s: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRun {
    pub periods: u64,
    pub solver: RawSolver,
    #[serde(default)]
    pub history: History,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
pub(super) enum RawSolver {
    Exact,
    Rk4 { steps_per_period: u32 },
    Dopri { rtol: f64, atol: f64 },
}

/// `effects.stiction` as written.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStiction {
    /// Breakaway force, N.
    pub static_n: f64,
    /// Stribeck velocity, m/s.
    pub stribeck_m_per_s: f64,
}

/// `effects.cogging` as written.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCogging {
    /// Amplitude, N.
    pub amplitude_n: f64,
    /// Period, m.
    pub period_m: f64,
}

/// `effects.transmission` as written.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTransmission {
    /// Link-side mass, kg.
    pub link_mass_kg: f64,
    /// Spring, N/m.
    pub stiffness_n_per_m: f64,
    /// Damper, N·s/m.
    pub damping_ns_per_m: f64,
}

/// `effects.travel` as written: the end stops (m, N/m, N·s/m; rad, N·m/rad, N·m·s/rad on a
/// rotary device), the stop's stiffness and damping optional (a hard stop by default).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTravel {
    /// Lower end stop, m.
    pub min_m: f64,
    /// Upper end stop, m.
    pub max_m: f64,
    /// Stop stiffness, N/m.
    pub stop_stiffness_n_per_m: Option<f64>,
    /// Stop damping, N·s/m.
    pub stop_damping_ns_per_m: Option<f64>,
}
