//! The JSON document of `hostctl map --k-b` ([`KbFile`]) and its parts, as plain data shared
//! by the (K, B) computation and its figure.
//!
//! Units: SI. K in N/m and B in N·s/m for a linear device, N·m/rad and N·m·s/rad for a
//! rotational one ([`Units`]); ξ̇₀ in counts per period. Invariant: points are stored by index
//! (K outer), the boundary on [`BOUNDARY_POINTS`] B values spanning the B axis.

use super::kb_args::Plant;
pub use crate::analysis::kb_plot::Units;
use serde::Serialize;
use stiffwall_sim::classify::Class;
use stiffwall_sim::exact::History;
use stiffwall_sim::map::Axis;

/// Number of B values of the predicted boundary curve.
pub const BOUNDARY_POINTS: usize = 101;

/// What the (K, B) map simulates (stated in the JSON `model` key).
pub const MODEL_NOTE: &str = "rigid plant m, b, c, resolution, T, T_D of the device mapped by \
Table I to (mu, beta, sigma, tau_d, beta_v = B/(K*T)) and simulated by the exact solver of the \
(beta, sigma) map (quantization, Coulomb, viscous, delay, two-sided wall; the damper is the \
plain backward difference, the firmware's `difference` law); a plant file's \
stiction, cogging, transmission, amplifier, hand and one-sided wall are not simulated; boundary: \
exact sampled linear K_max(B) (no quantization, no Coulomb)";

/// The (K, B) sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct KbSpec {
    /// K axis [N/m or N·m/rad], lo > 0.
    pub k: Axis,
    /// B axis [N·s/m or N·m·s/rad], lo ≥ 0.
    pub b: Axis,
    /// ξ̇₀ [counts per period], ξ₀ = 0.
    pub xidot0: f64,
    /// ξ̇₀ as a physical velocity ξ̇₀·Δ/T [m/s or rad/s].
    pub velocity: f64,
    /// Horizon in periods.
    pub periods: u64,
    /// Delay-line history before τ = 0.
    pub history: History,
}

/// One classified (K, B) point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct KbPoint {
    /// Index, row-major (K outer, B inner).
    pub index: usize,
    /// K.
    pub k: f64,
    /// B.
    pub b: f64,
    /// μ = m/(KT²).
    pub mu: f64,
    /// β = b/(KT).
    pub beta: f64,
    /// σ = c/(KΔ).
    pub sigma: f64,
    /// β_v = B/(KT).
    pub beta_v: f64,
    /// Class of the simulation.
    pub class: Class,
    /// Periods simulated.
    pub periods_run: u64,
    /// H_T(0).
    pub h0: f64,
    /// H_T at the end.
    pub h_end: f64,
    /// Largest |ξ| over the tail.
    pub tail_amplitude: f64,
    /// Chatter: a persistent run whose tail stays within the two counts around the wall (|ξ| ≤
    /// 1): it never comes to rest (`stiffwall_core::rest`), and never grows or buzzes wider; a
    /// class of its own in the text grid (`c`) and the figure (purple).
    pub chatter: bool,
    /// Stable by core's exact sampled linear test (`criteria::exact_linear_stable`).
    pub linear_stable: bool,
}

/// Whether a run of class `class` with tail amplitude `tail_amplitude` (|ξ|, counts) is
/// chatter: persistent within the two counts either side of the wall.
#[must_use]
pub fn is_chatter(class: Class, tail_amplitude: f64) -> bool {
    class == Class::Persistent && tail_amplitude <= 1.0
}

/// One point of the predicted boundary.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BoundaryPoint {
    /// B.
    pub b: f64,
    /// Exact linear K_max(B) (0: no stable K).
    pub k_max: f64,
}

/// The JSON document of `hostctl map --k-b`.
#[derive(Debug, Clone, Serialize)]
pub struct KbFile {
    /// Always `"k-b"`.
    pub kind: &'static str,
    /// [`MODEL_NOTE`].
    pub model: &'static str,
    /// Units of K and B.
    pub units: Units,
    /// The device.
    pub plant: Plant,
    /// The sweep.
    pub spec: KbSpec,
    /// Points, by index.
    pub points: Vec<KbPoint>,
    /// K_max(B) on [`BOUNDARY_POINTS`] B values spanning the B axis.
    pub boundary: Vec<BoundaryPoint>,
    /// Wall time of the computation, s.
    pub seconds: f64,
}
