//! `hostctl map atlas`: a complete map compared, panel by panel, with the paper's analytic
//! growth boundaries.
//!
//! Units: dimensionless (Table I); fractions in [0, 1]. For each panel (μ, τ_D, ξ̇₀) every grid
//! point's simulated outcome is reduced to "growing" (class `growing`) or not, and each analytic
//! line is read as a predictor of growth:
//! - `worst_case`: the regions of (12) (τ_D = 0) / (19) (τ_D > 0), growth in C or D
//!   (`stiffwall_core::regions::classify_delayed`), with ξ̇_max = |ξ̇₀| and the harmonic
//!   ξ̈_max = ξ̇_max/√μ (as `hostctl map --overlay` draws them);
//! - `df_72`: growth below the describing-function line (72), σ < (πM/4)(sin(τ_Lω) − βω) with ω
//!   from (71) and M = |ξ̇₀|/ω (so ξ̇_max = Mω), τ_L = ½ + τ_D
//!   (`stiffwall_core::describing::large_cycle_sigma`);
//! - `df_74`: the same with the low-frequency approximation (73)/(74);
//! - `linear_exact`: growth where the sampled linear loop (no quantization, no Coulomb friction)
//!   is unstable (`stiffwall_core::criteria::gil_avello_rubio_stable`); defined for
//!   τ_D ≤ 60 periods, `null` beyond.
//!
//! A line's agreement is the fraction of the panel's grid points on which its prediction
//! equals the simulation. Invariant: the atlas is computed only from a complete, validated map.
//!
//! Layout: the lines, the atlas document and its computation are `stiffwall_analysis::atlas`
//! with its Markdown (re-exported here); `atlas_plot` (`stiffwall_figures::atlas`) draws them;
//! this module runs the command, on top of both.

use anyhow::{Context, Result};
use std::path::PathBuf;
pub use stiffwall_analysis::atlas::{
    compute, markdown, pct, Agreement, Atlas, AtlasPanel, FigureLinks, Line, Slice,
};
use stiffwall_analysis::map_file as file;
use stiffwall_figures::atlas as atlas_plot;

/// Arguments of `hostctl map atlas`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A complete map JSON (from `hostctl map` or `hostctl map merge`).
    pub input: PathBuf,
    /// Atlas JSON output (stdout when neither --out, --plots nor --markdown is given).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Directory for one image per panel and `atlas-summary.<ext>`.
    #[arg(long)]
    pub plots: Option<PathBuf>,
    /// Image format of --plots: png or svg.
    #[arg(long, default_value = "png")]
    pub format: String,
    /// Markdown table of the agreement fractions.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// Command line recorded in the --markdown header (how the table was generated).
    #[arg(long)]
    pub generated_by: Option<String>,
}

///
/// # Errors
/// An invalid or incomplete map, an unwritable output, or a drawing error.
pub fn run(a: &Args) -> Result<()> {
    let ext = match a.format.to_ascii_lowercase().as_str() {
        f @ ("png" | "svg") => f.to_owned(),
        other => anyhow::bail!("--format {other}: allowed values are png, svg"),
    };
    if let Some(d) = &a.plots {
        std::fs::create_dir_all(d).with_context(|| format!("--plots {}", d.display()))?;
    }
    for p in a.out.iter().chain(&a.markdown) {
        crate::figure::check_writable(p).with_context(|| format!("{}", p.display()))?;
    }
    let m = file::read(&a.input)?;
    let atlas = compute(&m)?;
    for p in &atlas.panels {
        eprintln!(
            "mu = {:.4}, tau_d = {}, xidot0 = {}: {} growing of {}; agreement: {}",
            p.mu,
            p.tau_d,
            p.xidot0,
            p.growing,
            p.points,
            Line::ALL
                .iter()
                .map(|&l| format!("{} {}", l.name(), pct(p.fraction(l))))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let json = serde_json::to_string_pretty(&atlas)? + "\n";
    if let Some(out) = &a.out {
        std::fs::write(out, &json).with_context(|| format!("writing {}", out.display()))?;
    }
    if let Some(md) = &a.markdown {
        // Link the figures when they sit below the Markdown file's directory.
        let parent = md
            .parent()
            .map(std::path::Path::to_path_buf)
            .unwrap_or_default();
        let rel = a.plots.as_ref().and_then(|d| {
            let rel = d.strip_prefix(&parent).ok()?;
            let parts: Option<Vec<&str>> = rel.iter().map(|c| c.to_str()).collect();
            Some(parts?.join("/"))
        });
        let links = rel.as_deref().map(|dir| FigureLinks { dir, ext: &ext });
        std::fs::write(md, markdown(&atlas, a.generated_by.as_deref(), links))
            .with_context(|| format!("writing {}", md.display()))?;
    }
    if let Some(dir) = &a.plots {
        atlas_plot::plot_all(&m, &atlas, dir, &ext)?;
    }
    if a.out.is_none() && a.plots.is_none() && a.markdown.is_none() {
        print!("{json}");
    }
    Ok(())
}
