//! `hostctl experiment release`: the paper's Fig. 8 test on a device. The device is held at a
//! deflection (effective encoder ticks from the wall) with zero velocity, released, and
//! recorded; the outcome is classified (settles / locally stable / limit cycle below one tick /
//! persistent / growing, see `stiffwall_tune::classify`) and plotted: x(t) with the ±1-tick lines,
//! beside the (β, σ) operating point and its critical line for the equivalent velocity (all
//! spring energy turned into kinetic energy, as in Sec. V).

use crate::analysis;
use crate::device::connect::ConnectArgs;
use crate::figure;
use crate::output::{emit, emit_json, fault_name_list, fault_names};
use anyhow::{bail, Result};
use std::fmt::Write as _;
use std::path::PathBuf;
use stiffwall_analysis::release;
use stiffwall_core::params::PhysicalParams;
use stiffwall_figures::release as release_figure;
use stiffwall_proto::{flags, Sample};
use stiffwall_tune::{classify, Verdict};

/// Arguments of `hostctl experiment`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    pub kind: Kind,
}

/// Experiments.
#[derive(Debug, clap::Subcommand)]
pub enum Kind {
    /// Release test (Fig. 8): hold at a deflection, release into the wall, classify.
    Release(ReleaseArgs),
}

pub use stiffwall_analysis::release::DEFAULT_RELEASE_TICKS;

/// Arguments of `hostctl experiment release`.
#[derive(Debug, clap::Args)]
pub struct ReleaseArgs {
    #[command(flatten)]
    pub connect: ConnectArgs,
    /// Initial deflection, effective encoder ticks from the wall (non-zero, |d| ≤ 1048576).
    #[arg(long, allow_hyphen_values = true)]
    pub deflection: i32,
    /// Servo ticks to record after the release (100–10000000).
    #[arg(long, default_value_t = DEFAULT_RELEASE_TICKS, allow_hyphen_values = true)]
    pub ticks: u32,
    /// Wall stiffness for the test, N/m (N·m/rad); default: the device's configured K
    /// (needed when the device's wall is off, K = 0, as on a fresh virtual device).
    #[arg(long, allow_hyphen_values = true)]
    pub stiffness: Option<f64>,
    /// Device model for the (β, σ) panel: mass, viscous and Coulomb friction (SI); default:
    /// the `--device` preset of the virtual device.
    #[arg(long, num_args = 3, value_names = ["M", "B", "C"], allow_hyphen_values = true)]
    pub model: Option<Vec<f64>>,
    /// Write the figure (.svg or .png).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `hostctl experiment`.
pub fn run(a: &Args) -> Result<()> {
    match &a.kind {
        Kind::Release(r) => release(r),
    }
}

/// Checks the numbers of a release test (`--deflection`, `--ticks`, `--stiffness`) before any
/// device is touched; shared with `hostctl ui`.
///
/// # Errors
/// The first argument out of range, named with its range.
pub fn check_release(a: &ReleaseArgs) -> Result<()> {
    check_release_values(a.deflection, a.ticks, a.stiffness)
}

/// [`check_release`] on the values themselves (shared with `hostctl ui`'s release command;
/// `stiffwall_analysis::release::check_values`).
///
/// # Errors
/// As [`check_release`].
pub fn check_release_values(deflection: i32, ticks: u32, stiffness: Option<f64>) -> Result<()> {
    Ok(release::check_values(deflection, ticks, stiffness)?)
}

fn release(a: &ReleaseArgs) -> Result<()> {
    check_release(a)?;
    if let Some(p) = &a.plot {
        figure::prepare(p)?;
    }
    let model = release_model(a)?;
    let mut c = a.connect.connect()?;
    let original = c.get_config()?;
    let cfg = release::config(&original, a.stiffness, c.info.limits.max_stiffness)?;
    c.clear_faults().ok();
    c.set_config(&cfg)?;
    let rec = c.release(a.deflection, a.ticks);
    // The experiment's stiffness is not kept.
    c.set_config(&original)?;
    let rec = rec?;
    let released: Vec<Sample> = rec
        .samples
        .iter()
        .copied()
        .filter(|s| s.flags & flags::RELEASED != 0)
        .collect();
    let counts = stiffwall_tune::released_counts(&released, cfg.coarsen_shift);
    let verdict = classify(&counts, rec.faults != 0);
    let rate = f64::from(c.info.servo_rate_hz);
    let delta = f64::from(c.info.resolution) * f64::from(1u32 << cfg.coarsen_shift);
    let params = model.map(|(m, b, cc)| PhysicalParams {
        mass: m,
        viscous: b,
        coulomb: cc,
        resolution: delta,
        period_s: 1.0 / rate,
        stiffness: f64::from(cfg.stiffness),
        delay_s: f64::from(cfg.extra_delay_ticks) / rate,
        rotational: c.info.counts_per_rev > 0,
    });
    // Equivalent maximum velocity: ½K(dΔ)² = ½mv² (Sec. V).
    let start = counts.first().copied().unwrap_or(i64::from(a.deflection));
    let v_eq = params.map(|p| (start as f64 + 0.5).abs() * delta * (p.stiffness / p.mass).sqrt());
    let report = match (params, v_eq) {
        (Some(p), Some(v)) => Some(analysis::analyze(None, &p, Some(v), None)?),
        _ => None,
    };
    if let Some(path) = &a.plot {
        let trip = released
            .iter()
            .position(|s| s.flags & flags::SAFE_MODE != 0)
            .or_else(|| (rec.faults != 0).then(|| counts.len().saturating_sub(1)));
        let name = a.connect.describe();
        let fig = release_figure::Release {
            counts: &counts,
            rate,
            verdict: verdict.describe(),
            name: &name,
            stiffness: f64::from(cfg.stiffness),
            damping: f64::from(cfg.damping),
            rotary: c.info.counts_per_rev > 0,
            trip,
            plane: report
                .as_ref()
                .map(|r| release_plane(r, &name, f64::from(cfg.damping))),
        };
        figure::write(path, release_figure::SIZE_PX, &fig)?;
    }
    let done = ReleaseDone {
        rotary: c.info.counts_per_rev > 0,
        stiffness: cfg.stiffness,
        start,
        counts: &counts,
        verdict,
        rec: &rec,
        v_eq,
        report: report.as_ref(),
    };
    if a.json {
        emit_json(&done.json(a))?;
    } else {
        emit(&done.text(a))?;
    }
    Ok(())
}

/// The (β, σ) plane beside a release: the device, the release's equivalent velocity, and the
/// config's damper B [N·s/m or N·m·s/rad] (0: none) drawn apart from the spring.
fn release_plane<'a>(
    r: &'a analysis::Report,
    name: &str,
    b: f64,
) -> stiffwall_figures::plane::Plane<'a> {
    let p = &r.params;
    stiffwall_figures::plane::Plane {
        report: r,
        name: name.to_owned(),
        velocity_source: "the release's equivalent velocity, ½K(dΔ)² = ½mv²".to_owned(),
        damper: (b > 0.0).then(|| stiffwall_figures::plane::Damper {
            b,
            beta_v: b / (p.stiffness * p.period_s),
            k_max: stiffwall_core::criteria::k_max_exact_linear(p, b).ok(),
        }),
    }
}

/// The plant model of `--model M B C`, else the virtual device's own plant (None on a real
/// device: no (β, σ) for the release).
fn release_model(a: &ReleaseArgs) -> Result<Option<(f64, f64, f64)>> {
    Ok(match &a.model {
        Some(v) if v.iter().all(|x| x.is_finite() && *x >= 0.0) && v[0] > 0.0 => {
            Some((v[0], v[1], v[2]))
        }
        Some(v) => bail!(
            "--model M B C must be finite, M > 0 kg, B ≥ 0 N·s/m, C ≥ 0 N (got {} {} {})",
            v[0],
            v[1],
            v[2]
        ),
        None => a
            .connect
            .virtual_spec()?
            .map(|s| (s.plant.mass, s.plant.viscous, s.plant.coulomb)),
    })
}

/// A finished release test, as reported.
struct ReleaseDone<'a> {
    /// A rotary device (N·m/rad, rad/s), else linear (N/m, m/s).
    rotary: bool,
    /// The test's stiffness.
    stiffness: f32,
    /// Where the device was released, effective ticks.
    start: i64,
    /// Counts after the release.
    counts: &'a [i64],
    verdict: Verdict,
    rec: &'a stiffwall_client::Record,
    /// Equivalent maximum velocity of the release (with a model).
    v_eq: Option<f64>,
    /// The analysis at that velocity (with a model).
    report: Option<&'a analysis::Report>,
}

impl ReleaseDone<'_> {
    /// The largest |x| (ticks, from the middle of the count) over the last quarter.
    fn peak_tail(&self) -> f64 {
        self.counts
            .iter()
            .rev()
            .take(self.counts.len() / 4)
            .map(|n| (*n as f64 + 0.5).abs())
            .fold(0.0, f64::max)
    }

    fn json(&self, a: &ReleaseArgs) -> serde_json::Value {
        let r = self.report;
        serde_json::json!({
            "verdict": self.verdict,
            "deflection_ticks": a.deflection,
            "start_ticks": self.start,
            "ticks": self.counts.len(),
            "completed": self.rec.completed,
            "faults": self.rec.faults,
            "fault_names": fault_name_list(self.rec.faults),
            "tail_peak_ticks": self.peak_tail(),
            "stiffness": self.stiffness,
            "equivalent_velocity": self.v_eq,
            "mu": r.map(|r| r.mu),
            "beta": r.map(|r| r.beta),
            "sigma": r.map(|r| r.sigma),
            "region": r.map(|r| r.region),
            "gaps": self.rec.gaps,
        })
    }

    fn text(&self, a: &ReleaseArgs) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "release test on the {}", a.connect.describe());
        let (k_unit, v_unit) = if self.rotary {
            ("N·m/rad", "rad/s")
        } else {
            ("N/m", "m/s")
        };
        // `start` is the first count recorded after the release, where the hold left the
        // device: it need not be the count asked for.
        let asked = if self.start == i64::from(a.deflection) {
            String::new()
        } else {
            format!(
                " (the first count recorded after the release; {} asked)",
                a.deflection
            )
        };
        let _ = writeln!(
            s,
            "  K = {} {k_unit}, released from {} ticks{asked}, {} ticks recorded",
            self.stiffness,
            self.start,
            self.counts.len()
        );
        let _ = writeln!(s, "  verdict: {}", self.verdict.describe());
        let _ = writeln!(
            s,
            "  peak |x| over the last quarter: {:.1} ticks; faults: {}",
            self.peak_tail(),
            fault_names(self.rec.faults)
        );
        if let Some(r) = self.report {
            let _ = writeln!(
                s,
                "  (β, σ) = ({:.4}, {:.4}), μ = {:.3}; region {:?} for the equivalent velocity {:.4} \
                 {v_unit}",
                r.beta, r.sigma, r.mu, r.region, self.v_eq.unwrap_or(0.0)
            );
        }
        if let Some(p) = &a.plot {
            let _ = writeln!(s, "  plot: {}", p.display());
        }
        s
    }
}
