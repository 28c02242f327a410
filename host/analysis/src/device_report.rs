//! The paper's analysis of one device (Diolaiti et al. 2006, Sec. III, VII), behind `hostctl
//! analyze` and reused by `tune` and `experiment` for their reports and (β, σ) figures; the
//! spring + damper part is [`crate::damping`]; the device's limits without a wall ("how stiff
//! can it go", `analyze` without `--stiffness`) are [`stiffest`]. Rendering of figures is the
//! caller's.
//!
//! Units: inputs are SI (kg, N·s/m, N, m, s, N/m, m/s, m/s²; with `--rotational`
//! kg·m², N·m·s/rad, N·m, rad, N·m/rad, rad/s, rad/s²). The report gives the dimensionless
//! values of Table I, the region of Fig. 3/5, the velocity limit (15), the stiffness limits of
//! `stiffwall_core::limits` and the classic criteria of `stiffwall_core::criteria` side by side.
//!
//! Invariants: every number is validated by `stiffwall-core`; bad input is an error naming the
//! field and its allowed range.

pub mod stiffest;

use crate::damping;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use stiffwall_core::params::{check_non_negative, check_positive};
use stiffwall_core::{
    criteria, describing, devices, limits, regions, ParamError, PhysicalParams, Region,
};

/// One stiffness limit of a criterion.
#[derive(Debug, Clone, Serialize)]
pub struct CriterionLimit {
    /// Largest stiffness allowed [N/m or N·m/rad] (null if not finite).
    pub k_max: Option<f64>,
    /// Current stiffness divided by `k_max` (> 1: the criterion is violated).
    pub k_ratio: Option<f64>,
    /// The formula used.
    pub formula: &'static str,
    /// Bibliographic source.
    pub source: &'static str,
}

/// Predicted small-amplitude limit cycle (68)–(70).
#[derive(Debug, Clone, Serialize)]
pub struct LimitCycleReport {
    /// Amplitude M in encoder ticks.
    pub amplitude_ticks: f64,
    /// Frequency in Hz.
    pub frequency_hz: f64,
    /// Frequency ω in rad per sampling period.
    pub omega: f64,
}

/// The full analysis of one device; serialised as the `--json` output.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Preset name, if any.
    pub device: Option<String>,
    /// Physical parameters analysed (SI).
    pub params: PhysicalParams,
    /// μ = m/(KT²).
    pub mu: f64,
    /// β = b/(KT).
    pub beta: f64,
    /// σ = c/(KΔ).
    pub sigma: f64,
    /// τ_D = T_D/T.
    pub tau_d: f64,
    /// Region label, "A"…"E", "F1", "F2".
    pub region: Region,
    /// One-line meaning of the region.
    pub region_meaning: &'static str,
    /// The velocity/acceleration bounds the region was classified with.
    pub region_assumption: String,
    /// Dimensionless ξ̇ of `--velocity` (ticks/period), if given.
    pub xidot: Option<f64>,
    /// Dimensionless ξ̈ used for (19) (ticks/period²), when τ_D > 0.
    pub xiddot: Option<f64>,
    /// Velocity limit (15) (or its delayed form), dimensionless; null when unbounded.
    pub xidot_max: Option<f64>,
    /// The same in m/s (rad/s for rotational); null when unbounded.
    pub velocity_limit_m_s: Option<f64>,
    /// Largest K of region A (passive), eq. (17)–(18).
    pub k_max_passive: f64,
    /// Largest K satisfying (12) at `--velocity` (τ_D = 0 criterion).
    pub k_max_at_velocity: Option<f64>,
    /// Largest K satisfying (19) at `--velocity` and the acceleration bound, with the delay.
    pub k_max_delayed: Option<f64>,
    /// Classic and paper criteria, keyed by name.
    pub criteria: BTreeMap<&'static str, CriterionLimit>,
    /// Predicted small-amplitude limit cycle, or null (σ ≥ ½).
    pub limit_cycle: Option<LimitCycleReport>,
    /// Minimum σ for stability against large oscillations, eq. (75).
    pub sigma_min_large_amplitude: f64,
    /// Whether μ ≫ 1/π² of (11) holds (we test μ ≥ 10/π²).
    pub mu_sampling_ok: bool,
    /// The spring + damper analysis of `--damping B`; absent (no JSON key) without it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<damping::DampingReport>,
}

/// Computes the whole report for `p`, with optional physical velocity and acceleration bounds.
///
/// # Errors
/// A parameter, velocity or acceleration out of range (named, with its allowed range).
pub fn analyze(
    device: Option<String>,
    p: &PhysicalParams,
    velocity: Option<f64>,
    acceleration: Option<f64>,
) -> Result<Report, ParamError> {
    let d = p.to_dimensionless()?;
    if let Some(v) = velocity {
        check_non_negative("velocity", v)?;
    }
    if let Some(a) = acceleration {
        check_non_negative("acceleration", a)?;
    }
    let xidot = velocity.map(|v| p.xidot_from_velocity(v));
    let delayed = d.tau_d > 0.0;
    // ξ̈ bound for (19): the given acceleration, else harmonic motion at the wall's natural
    // frequency (ξ̈ = ξ̇/√μ), else 0 (the low-speed limit).
    let xiddot = match (acceleration, xidot) {
        (Some(a), _) => p.xiddot_from_acceleration(a),
        (None, Some(x)) => x / d.mu.sqrt(),
        (None, None) => 0.0,
    };
    let (region, assumption) = classify(&d, xidot, xiddot, acceleration.is_some())?;
    let xidot_max = match (delayed, acceleration) {
        (false, _) => regions::velocity_limit(d.beta, d.sigma)?,
        (true, Some(_)) => regions::velocity_limit_delayed(d.beta, d.sigma, d.tau_d, xiddot)?,
        (true, None) => regions::velocity_limit_harmonic(d.mu, d.beta, d.sigma, d.tau_d)?,
    };
    let velocity_limit_m_s = xidot_max.map(|x| p.velocity_from_xidot(x));
    let k_max_passive = limits::k_max_passive(p)?;
    let k_max_at_velocity = velocity
        .map(|v| limits::k_max_at_velocity(p, v))
        .transpose()?;
    let k_max_delayed = match (velocity, acceleration) {
        (Some(v), Some(a)) => Some(limits::k_max_delayed(p, v, a)?),
        (Some(v), None) => Some(limits::k_max_delayed_harmonic(p, v)?),
        _ => None,
    };
    let crit = criteria_table(
        p,
        k_max_passive,
        k_max_at_velocity,
        k_max_delayed,
        acceleration.is_some(),
    )?;
    let tau_l = 0.5 + d.tau_d;
    let limit_cycle =
        describing::small_limit_cycle(d.mu, d.beta, d.sigma, tau_l)?.map(|lc| LimitCycleReport {
            amplitude_ticks: lc.amplitude,
            frequency_hz: lc.frequency_hz(p.period_s),
            omega: lc.omega,
        });
    let sigma_min_large_amplitude = describing::sigma_min_large(d.mu, d.beta, tau_l)?;
    check_positive("mu", d.mu)?;
    Ok(Report {
        device,
        params: *p,
        mu: d.mu,
        beta: d.beta,
        sigma: d.sigma,
        tau_d: d.tau_d,
        region,
        region_meaning: region.meaning(),
        region_assumption: assumption,
        xidot,
        xiddot: delayed.then_some(xiddot),
        xidot_max,
        velocity_limit_m_s,
        k_max_passive,
        k_max_at_velocity,
        k_max_delayed,
        criteria: crit,
        limit_cycle,
        sigma_min_large_amplitude,
        mu_sampling_ok: d.mu >= 10.0 / (std::f64::consts::PI * std::f64::consts::PI),
        damping: None,
    })
}

/// The region of the operating point under the velocity bound (or the low-speed limit), and
/// the assumption it was classified under, in words.
fn classify(
    d: &stiffwall_core::params::Dimensionless,
    xidot: Option<f64>,
    xiddot: f64,
    acceleration_given: bool,
) -> Result<(Region, String), ParamError> {
    let delayed = d.tau_d > 0.0;
    Ok(match xidot {
        Some(x) => (
            regions::classify_delayed(d.beta, d.sigma, d.tau_d, Some(x), Some(xiddot))?,
            if delayed {
                format!("velocity bound ξ̇_max = {x:.4} ticks/period, acceleration bound ξ̈_max = {xiddot:.4} ticks/period²{}", if acceleration_given { "" } else { " (harmonic: ξ̇_max/√μ)" })
            } else {
                format!("velocity bound ξ̇_max = {x:.4} ticks/period")
            },
        ),
        None => (
            regions::classify_delayed(d.beta, d.sigma, d.tau_d, Some(0.0), Some(xiddot))?,
            format!(
                "low-speed limit ξ̇_max → 0{} (give --velocity for a velocity bound)",
                if delayed {
                    ", ξ̈_max as given or 0"
                } else {
                    ""
                }
            ),
        ),
    })
}

/// Every criterion's stiffness limit at the device's K, keyed by name.
fn criteria_table(
    p: &PhysicalParams,
    k_max_passive: f64,
    k_max_at_velocity: Option<f64>,
    k_max_delayed: Option<f64>,
    acceleration_given: bool,
) -> Result<BTreeMap<&'static str, CriterionLimit>, ParamError> {
    let k = p.stiffness;
    let entry = |k_max: f64, formula, source| CriterionLimit {
        k_max: k_max.is_finite().then_some(k_max),
        k_ratio: (k_max.is_finite() && k_max > 0.0).then(|| k / k_max),
        formula,
        source,
    };
    let mut crit = BTreeMap::new();
    crit.insert(
        "diolaiti_region_a",
        entry(
            k_max_passive,
            "K <= min(2b/T, 2c/Δ)  (β >= 1/2, σ >= 1/2; eq. 17-18)",
            "Diolaiti et al. 2006, Sec. III-B/C",
        ),
    );
    if let Some(km) = k_max_at_velocity {
        crit.insert(
            "diolaiti_eq12_at_velocity",
            entry(
                km,
                "K <= min(2(bv + c)/(vT + Δ), 2c/Δ)  (eq. 12 with ξ̇_max = vT/Δ)",
                "Diolaiti et al. 2006, eq. (12)",
            ),
        );
    }
    if let Some(km) = k_max_delayed {
        crit.insert(
            "diolaiti_eq19_delayed",
            entry(km, if acceleration_given { "K <= min((c + bv)/(Δ/2 + a(T_D² + T T_D) + v(T/2 + T_D)), c/(Δ/2 + a(T_D² + T T_D)))  (eq. 19)" } else { "eq. 19 with a = v·sqrt(K/m) (harmonic), bisection" }, "Diolaiti et al. 2006, eq. (19)"),
        );
    }
    crit.insert(
        "colgate_schenkel",
        entry(
            criteria::k_max_colgate_schenkel(p)?,
            "K < 2b/T  (b > KT/2 + |B|, B = 0)",
            "Colgate & Schenkel, ACC 1994",
        ),
    );
    crit.insert(
        "abbott_okamura",
        entry(
            criteria::k_max_abbott_okamura(p)?,
            "K < min(2b/T, 2c/Δ)",
            "Abbott & Okamura, IEEE T-RO 21(5), 2005",
        ),
    );
    crit.insert(
        "gil_avello_rubio",
        entry(
            criteria::k_max_gil_avello_rubio(p)?,
            "exact: sampled linear loop 1/(ms²+bs), ZOH, delay T_D, Schur-Cohn-Jury + bisection",
            "Gil, Avello & Rubio, IEEE TCST 12(4), 2004",
        ),
    );
    crit.insert(
        "hulin",
        entry(
            criteria::k_max_hulin(p)?,
            "K ≈ b/(T/2 + T_D)  (small-damping linear approximation)",
            "Hulin, Preusche & Hirzinger, IROS 2006",
        ),
    );
    Ok(crit)
}

// The text of `hostctl analyze` (its default output), rendered from a report.

/// The `--list-devices` text.
#[must_use]
pub fn list_devices() -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<16} {:>10} {:>10} {:>9} {:>11} {:>8} {:>9}  description",
        "name", "m", "b", "c", "Δ", "T [ms]", "K"
    );
    for d in &devices::DEVICES {
        let p = d.params;
        let _ = writeln!(
            s,
            "{:<16} {:>10.4e} {:>10.3e} {:>9.3e} {:>11.4e} {:>8.3} {:>9.4}  {}",
            d.name,
            p.mass,
            p.viscous,
            p.coulomb,
            p.resolution,
            p.period_s * 1e3,
            p.stiffness,
            d.description
        );
    }
    s
}

fn opt(v: Option<f64>, unbounded: &str) -> String {
    v.map_or_else(|| unbounded.to_string(), |v| format!("{v:.4}"))
}

/// The default, human-readable output.
#[must_use]
pub fn render_table(r: &Report) -> String {
    let p = &r.params;
    let (mu_u, b_u, c_u, x_u, k_u, v_u) = if p.rotational {
        ("kg·m²", "N·m·s/rad", "N·m", "rad", "N·m/rad", "rad/s")
    } else {
        ("kg", "N·s/m", "N", "m", "N/m", "m/s")
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Device: {}",
        r.device.as_deref().unwrap_or("(from flags)")
    );
    let _ = writeln!(s, "\nPhysical parameters");
    let _ = writeln!(s, "  mass m           {:>12.5e} {mu_u}", p.mass);
    let _ = writeln!(s, "  viscous b        {:>12.5e} {b_u}", p.viscous);
    let _ = writeln!(s, "  Coulomb c        {:>12.5e} {c_u}", p.coulomb);
    let _ = writeln!(s, "  resolution Δ     {:>12.5e} {x_u}", p.resolution);
    let _ = writeln!(s, "  period T         {:>12.5e} s", p.period_s);
    let _ = writeln!(s, "  stiffness K      {:>12.5e} {k_u}", p.stiffness);
    let _ = writeln!(s, "  delay T_D        {:>12.5e} s", p.delay_s);
    render_dimensionless(&mut s, r, v_u);
    render_limits(&mut s, r, k_u);
    render_describing(&mut s, r);
    if let Some(d) = &r.damping {
        s.push_str(&damping::render(d, p));
    }
    s
}

/// Table I's numbers, the region and the velocity limit (15).
fn render_dimensionless(s: &mut String, r: &Report, v_u: &str) {
    let _ = writeln!(s, "\nDimensionless (Table I)");
    let _ = writeln!(
        s,
        "  μ = m/(KT²)      {:>12.4}{}",
        r.mu,
        if r.mu_sampling_ok {
            ""
        } else {
            "   (warning: μ ≫ 1/π² of (11) not met)"
        }
    );
    let _ = writeln!(s, "  β = b/(KT)       {:>12.5}", r.beta);
    let _ = writeln!(s, "  σ = c/(KΔ)       {:>12.4}", r.sigma);
    let _ = writeln!(s, "  τ_D = T_D/T      {:>12.4}", r.tau_d);
    let _ = writeln!(s, "\nRegion {} — {}", r.region, r.region_meaning);
    let _ = writeln!(s, "  classified at: {}", r.region_assumption);
    let _ = writeln!(
        s,
        "  velocity limit (15): ξ̇_max = {} ticks/period = {} {v_u}",
        opt(r.xidot_max, "unbounded"),
        r.velocity_limit_m_s
            .map_or_else(|| "unbounded".to_string(), |v| format!("{v:.4e}"))
    );
}

/// Every criterion's stiffness limit against the current K.
fn render_limits(s: &mut String, r: &Report, k_u: &str) {
    let p = &r.params;
    let _ = writeln!(
        s,
        "\nStiffness limits [{k_u}]  (current K = {:.5e})",
        p.stiffness
    );
    let _ = writeln!(
        s,
        "  {:<28} {:>12} {:>8}  formula",
        "criterion", "K_max", "K/K_max"
    );
    for (name, c) in &r.criteria {
        let _ = writeln!(
            s,
            "  {:<28} {:>12} {:>8}  {}",
            name,
            c.k_max
                .map_or_else(|| "inf".to_string(), |k| format!("{k:.5e}")),
            c.k_ratio
                .map_or_else(|| "-".to_string(), |x| format!("{x:.3}")),
            c.formula
        );
    }
}

/// The describing-function predictions of Sec. VII.
fn render_describing(s: &mut String, r: &Report) {
    let _ = writeln!(s, "\nDescribing function (Sec. VII)");
    match &r.limit_cycle {
        Some(lc) => {
            let _ = writeln!(
                s,
                "  small limit cycle (68)-(70): amplitude {:.4} ticks, {:.1} Hz{}",
                lc.amplitude_ticks,
                lc.frequency_hz,
                if lc.amplitude_ticks < 1.0 {
                    ""
                } else {
                    "  (M >= 1: outside the small-amplitude approximation)"
                }
            );
        }
        None => {
            let _ = writeln!(
                s,
                "  small limit cycle (68)-(70): none predicted (σ >= 1/2)"
            );
        }
    }
    let _ = writeln!(
        s,
        "  large-amplitude bound (75): stable only if σ >= {:.4} (σ = {:.4})",
        r.sigma_min_large_amplitude, r.sigma
    );
}
