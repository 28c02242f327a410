//! `hostctl analyze`: the paper's analysis of one device (Diolaiti et al. 2006, Sec. III, VII).
//!
//! Units: command-line values are SI (kg, N·s/m, N, m, s, N/m, m/s, m/s²; with `--rotational`
//! kg·m², N·m·s/rad, N·m, rad, N·m/rad, rad/s, rad/s²). The report gives the dimensionless
//! values of Table I, the region of Fig. 3/5, the velocity limit (15), the stiffness limits of
//! `stiffwall_core::limits` and the classic criteria of `stiffwall_core::criteria` side by side.
//!
//! Invariants: every number from the command line is validated by `stiffwall-core`; bad input
//! is an error naming the field and its allowed range, and nothing is written.

pub mod plot;

use anyhow::{anyhow, bail, Context};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;
use stiffwall_core::params::{check_non_negative, check_positive, resolution_from_counts_per_rev};
use stiffwall_core::{criteria, describing, devices, limits, regions, PhysicalParams, Region};

/// Arguments of `hostctl analyze`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  hostctl analyze --device phantom-1.0\n  hostctl analyze --device omega --stiffness 8000 --velocity 0.05 --json\n  hostctl analyze --mass 0.1 --viscous 0.01 --coulomb 0.05 --resolution 2e-5 --period 1e-3 --stiffness 2000 --plot wall.svg"
)]
pub struct Args {
    /// Start from a preset (see --list-devices); other flags override its fields.
    #[arg(long, value_name = "NAME")]
    pub device: Option<String>,
    /// List the presets and exit.
    #[arg(long)]
    pub list_devices: bool,
    /// Inertia m [kg, or kg·m² with --rotational], > 0.
    #[arg(long, allow_negative_numbers = true)]
    pub mass: Option<f64>,
    /// Viscous friction b [N·s/m, or N·m·s/rad], >= 0.
    #[arg(long, allow_negative_numbers = true)]
    pub viscous: Option<f64>,
    /// Coulomb friction c [N, or N·m], >= 0.
    #[arg(long, allow_negative_numbers = true)]
    pub coulomb: Option<f64>,
    /// Encoder resolution Δ [m, or rad], > 0.
    #[arg(long, allow_negative_numbers = true, conflicts_with = "counts_per_rev")]
    pub resolution: Option<f64>,
    /// Rotary encoder counts per revolution (Δ = 2π/N rad); rotational devices only.
    #[arg(long, allow_negative_numbers = true)]
    pub counts_per_rev: Option<f64>,
    /// Sampling period T [s], > 0.
    #[arg(long, allow_negative_numbers = true)]
    pub period: Option<f64>,
    /// Virtual wall stiffness K [N/m, or N·m/rad], > 0.
    #[arg(long, allow_negative_numbers = true)]
    pub stiffness: Option<f64>,
    /// Extra loop delay T_D (amplifier + computation, excluding the ZOH) [s], >= 0.
    #[arg(long, allow_negative_numbers = true)]
    pub delay: Option<f64>,
    /// Maximum velocity |ẋ| the user reaches [m/s, or rad/s], >= 0.
    #[arg(long, allow_negative_numbers = true)]
    pub velocity: Option<f64>,
    /// Maximum acceleration |ẍ| [m/s², or rad/s²], >= 0 (delayed criterion (19)).
    #[arg(long, allow_negative_numbers = true)]
    pub acceleration: Option<f64>,
    /// Rotational device: angles, torques and inertia instead of positions, forces and mass.
    #[arg(long)]
    pub rotational: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Write the (β, σ) plane with regions, operating point and K path (.svg or .png).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
}

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
}

/// Runs `hostctl analyze`.
///
/// # Errors
/// Bad or missing input (message names the field and allowed range), or a plot write error.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.list_devices {
        return emit(&list_devices());
    }
    let (name, p) = resolve_params(args)?;
    let report = analyze(name, &p, args.velocity, args.acceleration)?;
    if let Some(path) = &args.plot {
        plot::write(path, &report).with_context(|| format!("writing plot {}", path.display()))?;
    }
    if args.json {
        emit(&(serde_json::to_string_pretty(&report)? + "\n"))
    } else {
        let mut s = render_table(&report);
        if let Some(path) = &args.plot {
            let _ = writeln!(s, "plot written to {}", path.display());
        }
        emit(&s)
    }
}

/// Writes `s` to stdout; a closed pipe (e.g. `| head`) is not an error.
fn emit(s: &str) -> anyhow::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(s.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

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

fn missing(flag: &str, unit: &str, range: &str) -> anyhow::Error {
    anyhow!(
        "missing --{flag} [{unit}] (must be {range}); give it or start from --device NAME ({})",
        devices::NAMES
    )
}

/// Builds the physical parameters from a preset and/or flags, and validates them.
///
/// # Errors
/// Unknown device, missing field, or a field out of range (named, with its allowed range).
pub fn resolve_params(args: &Args) -> anyhow::Result<(Option<String>, PhysicalParams)> {
    let preset = match &args.device {
        Some(n) => Some(devices::find(n).ok_or_else(|| {
            anyhow!(
                "unknown device '{n}' (--device must be one of: {})",
                devices::NAMES
            )
        })?),
        None => None,
    };
    let rotational = args.rotational || preset.is_some_and(|d| d.params.rotational);
    let resolution = match (args.resolution, args.counts_per_rev) {
        (Some(r), _) => Some(r),
        (None, Some(n)) => {
            if !rotational {
                bail!("--counts-per-rev applies to rotational devices only; add --rotational or give --resolution [m]");
            }
            Some(resolution_from_counts_per_rev(n)?)
        }
        (None, None) => preset.map(|d| d.params.resolution),
    };
    let pick = |flag: Option<f64>, preset_val: Option<f64>| flag.or(preset_val);
    let pp = preset.map(|d| d.params);
    let unit = |l: &'static str, r: &'static str| if rotational { r } else { l };
    let p = PhysicalParams {
        mass: pick(args.mass, pp.map(|p| p.mass))
            .ok_or_else(|| missing("mass", unit("kg", "kg·m²"), "finite and > 0"))?,
        viscous: pick(args.viscous, pp.map(|p| p.viscous))
            .ok_or_else(|| missing("viscous", unit("N·s/m", "N·m·s/rad"), "finite and >= 0"))?,
        coulomb: pick(args.coulomb, pp.map(|p| p.coulomb))
            .ok_or_else(|| missing("coulomb", unit("N", "N·m"), "finite and >= 0"))?,
        resolution: resolution
            .ok_or_else(|| missing("resolution", unit("m", "rad"), "finite and > 0"))?,
        period_s: pick(args.period, pp.map(|p| p.period_s))
            .ok_or_else(|| missing("period", "s", "finite and > 0"))?,
        stiffness: pick(args.stiffness, pp.map(|p| p.stiffness))
            .ok_or_else(|| missing("stiffness", unit("N/m", "N·m/rad"), "finite and > 0"))?,
        delay_s: pick(args.delay, pp.map(|p| p.delay_s)).unwrap_or(0.0),
        rotational,
    };
    let p = p.validate()?;
    Ok((args.device.clone(), p))
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
) -> anyhow::Result<Report> {
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
    let (region, assumption) = match xidot {
        Some(x) => (
            regions::classify_delayed(d.beta, d.sigma, d.tau_d, Some(x), Some(xiddot))?,
            if delayed {
                format!("velocity bound ξ̇_max = {x:.4} ticks/period, acceleration bound ξ̈_max = {xiddot:.4} ticks/period²{}", if acceleration.is_none() { " (harmonic: ξ̇_max/√μ)" } else { "" })
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
    };
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
            entry(km, if acceleration.is_some() { "K <= min((c + bv)/(Δ/2 + a(T_D² + T T_D) + v(T/2 + T_D)), c/(Δ/2 + a(T_D² + T T_D)))  (eq. 19)" } else { "eq. 19 with a = v·sqrt(K/m) (harmonic), bisection" }, "Diolaiti et al. 2006, eq. (19)"),
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
    })
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
    s
}
