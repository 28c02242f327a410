//! The stability map over the (K, B) plane of one physical device (`hostctl map --k-b`): the
//! device ([`Plant`]), its JSON document ([`KbFile`]) and the computation ([`compute`]).
//!
//! Model: every (K, B) is mapped by Table I to μ = m/(KT²), β = b/(KT), σ = c/(KΔ),
//! τ_D = T_D/T and β_v = B/(KT), then simulated by the same exact solver, horizon and classes
//! as the (β, σ) map; a plant file's effects beyond the paper's rigid plant are listed in
//! [`Plant::ignored`], not simulated. The predicted boundary is core's exact sampled linear
//! K_max(B) (`criteria::k_max_exact_linear`). The damper's law is the sweep's
//! ([`KbSpec::damper`]): the plain difference or the firmware's `dead-band-N` (its default,
//! `dead-band-1`), simulated exactly. The result is deterministic and independent of the thread
//! count.
//!
//! Units: SI. K in N/m and B in N·s/m for a linear device, N·m/rad and N·m·s/rad for a
//! rotational one ([`Units`]); ξ̇₀ in counts per period. Invariant: points are stored by index
//! (K outer), the boundary on [`BOUNDARY_POINTS`] B values spanning the B axis.

pub use crate::frontier::Units;
use rayon::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
use stiffwall_core::{criteria, ParamError, PhysicalParams};
use stiffwall_sim::classify::Class;
use stiffwall_sim::exact::History;
use stiffwall_sim::map::{self as smap, Axis};
use stiffwall_sim::params::{Params, MAX_TAU_D};
use stiffwall_sim::rich::{PlantModel, WallDamper};
use stiffwall_sim::scene::SceneError;

/// Why a (K, B) point is out of the solver's range.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum KbError {
    /// A physical parameter out of core's range (named, with its range).
    #[error(transparent)]
    Param(#[from] ParamError),
    /// τ_D = T_D/T beyond the solver's delay line.
    #[error("tau_d = T_D/T = {tau_d}: allowed range is [0, {MAX_TAU_D}]")]
    TauD {
        /// T_D/T.
        tau_d: f64,
    },
}

/// Number of B values of the predicted boundary curve.
pub const BOUNDARY_POINTS: usize = 101;

/// What the (K, B) map simulates (stated in the JSON `model` key).
pub const MODEL_NOTE: &str = "rigid plant m, b, c, resolution, T, T_D of the device mapped by \
Table I to (mu, beta, sigma, tau_d, beta_v = B/(K*T)) and simulated by the exact solver of the \
(beta, sigma) map (quantization, Coulomb, viscous, delay, two-sided wall; the damper is the \
firmware's law named in spec.damper: `difference`, or `dead-band-N`, off while the count moves \
by at most N per period); a plant file's stiction, cogging, transmission, amplifier, hand and \
one-sided wall are not simulated; boundary: exact sampled linear K_max(B) (no quantization, no \
Coulomb, the plain difference)";

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
    /// The damper's law (JSON: `"difference"` or `"dead-band-N"`).
    #[serde(serialize_with = "as_text")]
    pub damper: WallDamper,
}

fn as_text<S: serde::Serializer>(d: &WallDamper, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(d)
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

/// The device of a (K, B) map (its K is the sweep's).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Plant {
    /// Where it came from (`plant file …`, `preset …`, `flags`).
    pub source: String,
    /// m [kg or kg·m²].
    pub mass: f64,
    /// b [N·s/m or N·m·s/rad].
    pub viscous: f64,
    /// c [N or N·m].
    pub coulomb: f64,
    /// Δ [m or rad].
    pub resolution: f64,
    /// T, s.
    pub period_s: f64,
    /// T_D, s.
    pub delay_s: f64,
    /// Rotational units.
    pub rotational: bool,
    /// Effects of the plant file that the map does not simulate.
    pub ignored: Vec<String>,
    /// The plant file's damper law (`controller.damper`), if it names one: the map's default
    /// (in the JSON as the sweep's `spec.damper`).
    #[serde(skip)]
    pub damper: Option<WallDamper>,
}

impl Plant {
    /// Core's physical parameters at stiffness `k`.
    #[must_use]
    pub fn physical(&self, k: f64) -> PhysicalParams {
        PhysicalParams {
            mass: self.mass,
            viscous: self.viscous,
            coulomb: self.coulomb,
            resolution: self.resolution,
            period_s: self.period_s,
            stiffness: k,
            delay_s: self.delay_s,
            rotational: self.rotational,
        }
    }

    /// Table I at (K, B): (μ, β, σ, τ_D) and β_v = B/(KT).
    ///
    /// # Errors
    /// A value out of the solver's range (μ underflow, τ_D > 250), naming the quantity.
    pub fn at(&self, k: f64, b: f64) -> Result<(Params, f64), KbError> {
        let d = self.physical(k).to_dimensionless()?;
        if d.tau_d > MAX_TAU_D {
            return Err(KbError::TauD { tau_d: d.tau_d });
        }
        Ok((d, b / (k * self.period_s)))
    }

    /// The device of a plant file's text (the scene format of `sim/plants/`: `[device]` m, b,
    /// c, Δ and `[controller]` period and extra delay; its stiffness is not used), with the
    /// effects the map does not simulate listed in [`Plant::ignored`].
    ///
    /// # Errors
    /// The scene's own error (naming the key and its range).
    pub fn from_scene_toml(source: String, text: &str) -> Result<Self, SceneError> {
        let (m, ctl) = PlantModel::from_scene_toml(text)?;
        Ok(Plant {
            source,
            mass: m.mass_kg,
            viscous: m.viscous_ns_per_m,
            coulomb: m.coulomb_n,
            resolution: m.resolution_m,
            period_s: ctl.period_s,
            delay_s: ctl.extra_delay_s,
            rotational: m.counts_per_rev.is_some(),
            ignored: ignored_effects(&m, ctl.one_sided),
            damper: ctl.damper,
        })
    }
}

fn ignored_effects(m: &PlantModel, one_sided: bool) -> Vec<String> {
    let mut v = Vec::new();
    let mut add = |on: bool, name: &str| {
        if on {
            v.push(name.to_owned());
        }
    };
    add(m.stiction.is_some(), "stiction");
    add(m.cogging.is_some(), "cogging");
    add(m.transmission.is_some(), "transmission");
    let amp = m.amplifier;
    add(
        amp.is_some_and(|a| a.cutoff_hz.is_some()),
        "amplifier filter",
    );
    add(
        amp.is_some_and(|a| a.force_limit_n.is_some()),
        "amplifier saturation",
    );
    add(
        amp.is_some_and(|a| a.deadband_n.is_some()),
        "amplifier dead band",
    );
    add(m.hand.is_some(), "hand");
    add(one_sided, "one-sided wall");
    v
}

fn point(plant: &Plant, spec: &KbSpec, index: usize) -> KbPoint {
    let k = spec.k.at(index / spec.b.n);
    let b = spec.b.at(index % spec.b.n);
    // In range at both ends of the K axis (checked by the caller, see `compute`), hence
    // everywhere.
    let (d, beta_v) = plant
        .at(k, b)
        .unwrap_or((stiffwall_sim::Params::BASE, f64::NAN));
    let law = (beta_v, spec.damper.dead_band());
    let o = smap::simulate_point_law(d, spec.xidot0, spec.periods, spec.history, law);
    let phys = plant.physical(k);
    KbPoint {
        index,
        k,
        b,
        mu: d.mu,
        beta: d.beta,
        sigma: d.sigma,
        beta_v,
        class: o.class,
        periods_run: o.periods_run,
        h0: o.h0,
        h_end: o.h_end,
        tail_amplitude: o.tail_amplitude,
        chatter: is_chatter(o.class, o.tail_amplitude),
        linear_stable: criteria::exact_linear_stable(&phys, b).unwrap_or(false),
    }
}

/// K_max(B) on [`BOUNDARY_POINTS`] values spanning the B axis.
#[must_use]
pub fn boundary(plant: &Plant, b: &Axis) -> Vec<BoundaryPoint> {
    let n = if b.hi > b.lo { BOUNDARY_POINTS } else { 1 };
    let axis = Axis { n, ..*b };
    let p = plant.physical(1.0);
    (0..n)
        .map(|i| {
            let b = axis.at(i);
            BoundaryPoint {
                b,
                k_max: criteria::k_max_exact_linear(&p, b).unwrap_or(f64::NAN),
            }
        })
        .collect()
}

/// Simulates every point of `spec` in parallel (rayon), calling `progress` once per point.
///
/// `spec` is checked by the caller first (`hostctl map --k-b` does it once, naming its flags):
/// K lo > 0, B lo >= 0, at most `MAX_GRID_POINTS` points, B/(K·T) <= 1000 at the smallest K,
/// [`Plant::at`] in range at both ends of the K axis. Unchecked, a point out of range falls
/// back to `Params::BASE` with β_v = NaN instead of panicking.
#[must_use]
pub fn compute(plant: &Plant, spec: &KbSpec, progress: &(dyn Fn() + Sync)) -> KbFile {
    let t0 = std::time::Instant::now();
    let points: Vec<KbPoint> = (0..spec.k.n * spec.b.n)
        .into_par_iter()
        .with_max_len(1)
        .map(|i| {
            let p = point(plant, spec, i);
            progress();
            p
        })
        .collect();
    KbFile {
        kind: "k-b",
        model: MODEL_NOTE,
        units: Units::of(plant.rotational),
        plant: plant.clone(),
        spec: spec.clone(),
        points,
        boundary: boundary(plant, &spec.b),
        seconds: t0.elapsed().as_secs_f64(),
    }
}

fn class_char(c: Class, chatter: bool) -> char {
    match c {
        Class::Persistent if chatter => 'c',
        Class::Growing => '#',
        Class::Persistent => 'o',
        Class::NonMonotoneDecay => '~',
        Class::MonotoneDecay => '.',
    }
}

/// The text report: class counts, the class grid (K rows from the top, B columns) and K_max(B).
#[must_use]
pub fn render(m: &KbFile) -> String {
    let (s, u) = (&m.spec, m.units);
    let mut out = String::new();
    let _ = writeln!(
        out,
        "(K, B) map of {} with the damper law {}: {}",
        m.plant.source, s.damper, MODEL_NOTE
    );
    if !m.plant.ignored.is_empty() {
        let _ = writeln!(out, "not simulated: {}", m.plant.ignored.join(", "));
    }
    let count = |c: Class| m.points.iter().filter(|p| p.class == c).count();
    let chatter = m.points.iter().filter(|p| p.chatter).count();
    let _ = writeln!(
        out,
        "{} points: growing {} (#), persistent {} (o), chatter within one count {chatter} (c), non-monotone decay {} (~), monotone decay {} (.); linear-stable {}",
        m.points.len(),
        count(Class::Growing),
        count(Class::Persistent) - chatter,
        count(Class::NonMonotoneDecay),
        count(Class::MonotoneDecay),
        m.points.iter().filter(|p| p.linear_stable).count()
    );
    let _ = writeln!(
        out,
        "rows K [{}] from {:e} (top) down, columns B [{}] {:e}..{:e}:",
        u.k, s.k.hi, u.b, s.b.lo, s.b.hi
    );
    for row in m.points.chunks(s.b.n).rev() {
        let cells: String = row.iter().map(|p| class_char(p.class, p.chatter)).collect();
        let _ = writeln!(out, "{:>12.4e} {cells}", row[0].k);
    }
    let _ = writeln!(out, "predicted exact linear K_max(B):");
    let step = (m.boundary.len() / 10).max(1);
    for bp in m.boundary.iter().step_by(step) {
        let _ = writeln!(
            out,
            "  B = {:>11.4e} {}: K_max = {:.4e} {}",
            bp.b, u.b, bp.k_max, u.k
        );
    }
    out
}
