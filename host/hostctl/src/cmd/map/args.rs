//! The command line of `hostctl map` ([`Args`], its sub-commands [`Sub`] and `--history`), as
//! plain clap data shared by the (β, σ) map in `mod.rs` and the (K, B) map in `kb`.
//!
//! Units: dimensionless (Table I) for the (β, σ) flags (μ, τ_D in periods, ξ̇₀ in ticks per
//! period, β_v = B/(K·T)); the (K, B) flags of [`kb_args::KbArgs`] are SI. Invariant: nothing
//! here checks a value; every flag is checked where it is used, before anything is computed.

use super::atlas;
use super::kb_args;
use std::path::PathBuf;
use stiffwall_sim::exact::History;

/// Arguments of `hostctl map`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Sub-commands (`merge`).
    #[command(subcommand)]
    pub cmd: Option<Sub>,
    /// Dimensionless mass μ: a value, a list v1,v2,… or a range lo:hi:n[:log] (one slice each).
    #[arg(long, default_value = "100", allow_hyphen_values = true)]
    pub mu: String,
    /// Delay τ_D in sampling periods: a value, a list or a range lo:hi:n[:log] (one slice each).
    #[arg(long, default_value = "0", allow_hyphen_values = true)]
    pub tau_d: String,
    /// Initial velocities ξ̇₀ (comma separated, one panel each).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "5",
        allow_hyphen_values = true
    )]
    pub xidot0: Vec<f64>,
    /// β axis lo:hi:n.
    #[arg(long, default_value = "0:1:34", allow_hyphen_values = true)]
    pub beta: String,
    /// σ axis lo:hi:n.
    #[arg(long, default_value = "0:2:21", allow_hyphen_values = true)]
    pub sigma: String,
    /// Horizon in sampling periods.
    #[arg(long, default_value_t = 50_000)]
    pub periods: u64,
    /// JSON output file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Image of the map (.svg or .png).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Draw the analytic region boundaries of Fig. 3/5 over the map.
    #[arg(long)]
    pub overlay: bool,
    /// Compute only shard k of n (k/n, 0-based).
    #[arg(long)]
    pub shard: Option<String>,
    /// Worker threads (default: all cores; at most 4 per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Recompute even when `--out` already holds this sweep's complete result.
    #[arg(long)]
    pub force: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Simulate every period even where a point's state repeats (same result, slower; for
    /// checking and timing).
    #[arg(long)]
    pub no_cycle_detection: bool,
    /// Delay-line history before tau = 0: the spring force of the initial position, or zero.
    #[arg(long, value_enum, default_value = "hold-initial")]
    pub history: HistoryArg,
    /// Virtual damping beta_v = B/(K*T) of the wall at every point, dimensionless, in [0, 1000]
    /// (0: the paper's spring-only wall; the JSON records it only when nonzero).
    #[arg(long = "beta-v", default_value_t = 0.0, allow_hyphen_values = true)]
    pub beta_v: f64,
    /// The old spelling of `--beta-v`, refused with a hint (`--damping` is the physical
    /// damper B on `tune`, `analyze` and `config`).
    #[arg(long = "damping", hide = true, allow_hyphen_values = true)]
    pub damping_renamed: Option<String>,
    /// The (K, B) map of one device (`--k-b`, [`kb`]).
    #[command(flatten)]
    pub kb: kb_args::KbArgs,
}

/// `--history` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum HistoryArg {
    /// phi_A = phi_C(xi0) before the first delayed sample.
    HoldInitial,
    /// phi_A = 0 before the first delayed sample.
    Zero,
}

/// `hostctl map merge`.
#[derive(Debug, clap::Subcommand)]
pub enum Sub {
    /// Merge shard JSON files of one sweep into one complete map.
    Merge {
        /// Shard files.
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
        /// Merged JSON output.
        #[arg(long)]
        out: PathBuf,
        /// Image of the merged map (.svg or .png).
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Draw the analytic region boundaries.
        #[arg(long)]
        overlay: bool,
    },
    /// Compare a complete map with the analytic growth boundaries, slice by slice.
    Atlas(atlas::Args),
}

/// The delay-line history of `--history`.
#[must_use]
pub fn history_of(h: HistoryArg) -> History {
    match h {
        HistoryArg::HoldInitial => History::HoldInitial,
        HistoryArg::Zero => History::Zero,
    }
}
