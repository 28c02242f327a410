//! The map JSON file: its computation ([`compute`]), format, full validation, atomic writing
//! and shard merging.
//!
//! Units: dimensionless (Table I), `seconds` of wall time, `ns_per_period` nanoseconds of wall
//! time per simulated period. Panels are ordered slice-major: for each μ (outer), each τ_D,
//! each ξ̇₀ (inner). Invariants: a file is written to a
//! temporary sibling (`<name>.partial-<pid>`) and renamed into place only when complete, so a
//! killed run never leaves a file under the requested name; every file carries
//! `spec_crc64`, the CRC-64/XZ of its spec's compact JSON. A file read from disk is used only
//! after [`validate`]: a valid spec (every field in range, grid size bounded before anything
//! is allocated), the hash, `0 <= k < n`, one panel per (μ, τ_D, ξ̇₀) with those values, and
//! in each panel exactly the points of its shard, in index order, with the β, σ of their index,
//! and one finite, non-negative cost per point. [`merge`] also refuses
//! mismatched sweeps and duplicate or missing shards; its result does not depend on the order
//! of its inputs.

use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};
use stiffwall_sim::exact::History;
use stiffwall_sim::map::{self, Axis, MapPoint, MapSpec};

pub use crate::values::Values;

/// Why a map spec or file is refused; every message names the file (where there is one), the
/// field and what was allowed or expected.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MapFileError {
    /// A spec field outside its allowed range (the message names the field and the range).
    #[error("{0}")]
    Spec(String),
    /// A file whose spec is invalid (the source names the field).
    #[error("{path}: invalid spec")]
    InvalidSpec {
        /// The file.
        path: PathBuf,
        /// What is wrong with the spec.
        #[source]
        source: Box<MapFileError>,
    },
    /// A file whose content contradicts its spec (the message names the file and field).
    #[error("{0}")]
    Content(String),
    /// Files that do not merge into one map (mismatched sweeps, shards twice or missing).
    #[error("{0}")]
    Merge(String),
    /// A file that could not be read.
    #[error("reading {path}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A file whose JSON ends early.
    #[error("{path}: truncated (the JSON ends early: {error}); re-run its shard")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// The parser's error.
        error: serde_json::Error,
    },
    /// A file that is not a map file.
    #[error("{path}: not a map file: {error}")]
    NotAMapFile {
        /// The file.
        path: PathBuf,
        /// The parser's error.
        error: serde_json::Error,
    },
    /// A file that could not be written.
    #[error("writing {path}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
}

/// `Result` of this module.
pub type Result<T, E = MapFileError> = std::result::Result<T, E>;

/// Returns `Err(MapFileError::$kind(format!(...)))` unless `$cond` holds.
macro_rules! ensure {
    ($kind:ident, $cond:expr, $($fmt:tt)*) => {
        if !$cond {
            return Err(MapFileError::$kind(format!($($fmt)*)));
        }
    };
}

/// Largest number of ξ̇₀ values of one map.
pub const MAX_PANELS: usize = 64;

/// Largest number of panels (μ values × τ_D values × ξ̇₀ values) of one map.
pub const MAX_ALL_PANELS: usize = 4096;

/// Largest number of points of one map (all panels).
pub const MAX_ALL_POINTS: usize = 40_000_000;

/// Largest number of shards of one sweep.
pub const MAX_SHARDS: usize = 100_000;

/// The sweep description stored in the JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Spec {
    /// μ: one value or a slice axis.
    pub mu: Values,
    /// τ_D: one value or a slice axis.
    pub tau_d: Values,
    /// Panels' ξ̇₀.
    pub xidot0: Vec<f64>,
    /// β axis.
    pub beta: Axis,
    /// σ axis.
    pub sigma: Axis,
    /// Horizon.
    pub periods: u64,
    /// Delay-line history before tau = 0.
    #[serde(default)]
    pub history: History,
    /// Virtual damping β_v = B/(K·T) of every point, dimensionless, in [0, 1000]; omitted from
    /// the JSON (and so from `spec_crc64`) when 0, so spring-only files are unchanged.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub damping: f64,
}

#[allow(clippy::trivially_copy_pass_by_ref)] // serde's skip_serializing_if passes a reference
fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl Spec {
    /// (μ, τ_D) of every slice, μ outer.
    #[must_use]
    pub fn slices(&self) -> Vec<(f64, f64)> {
        let taus = self.tau_d.values();
        self.mu
            .values()
            .into_iter()
            .flat_map(|mu| taus.iter().map(move |&t| (mu, t)))
            .collect()
    }

    /// The single-panel spec of every panel, in file order (slice outer, ξ̇₀ inner).
    #[must_use]
    pub fn panels(&self) -> Vec<MapSpec> {
        self.slices()
            .into_iter()
            .flat_map(|(mu, tau_d)| {
                self.xidot0
                    .iter()
                    .map(move |&v| self.panel_at(mu, tau_d, v))
            })
            .collect()
    }

    /// The single-panel spec of (μ, τ_D, ξ̇₀).
    #[must_use]
    pub fn panel_at(&self, mu: f64, tau_d: f64, xidot0: f64) -> MapSpec {
        MapSpec {
            mu,
            tau_d,
            xidot0,
            beta: self.beta,
            sigma: self.sigma,
            periods: self.periods,
            history: self.history,
            damping: self.damping,
        }
    }

    /// Checks every field (see [`MapSpec::validate`]), 1..=[`MAX_PANELS`] ξ̇₀ values, at most
    /// [`MAX_ALL_PANELS`] panels and [`MAX_ALL_POINTS`] points, before anything is allocated.
    ///
    /// # Errors
    /// A message naming the field and its allowed range.
    pub fn validate(&self) -> Result<()> {
        ensure!(
            Spec,
            (1..=MAX_PANELS).contains(&self.xidot0.len()),
            "xidot0: {} values, allowed 1 to {MAX_PANELS}",
            self.xidot0.len()
        );
        self.mu
            .validate()
            .map_err(|e| MapFileError::Spec(format!("mu: {e}")))?;
        self.tau_d
            .validate()
            .map_err(|e| MapFileError::Spec(format!("tau_d: {e}")))?;
        let panels = self.mu.len() * self.tau_d.len() * self.xidot0.len();
        ensure!(
            Spec,
            panels <= MAX_ALL_PANELS,
            "{} mu x {} tau_d x {} xidot0 = {panels} panels: at most {MAX_ALL_PANELS}",
            self.mu.len(),
            self.tau_d.len(),
            self.xidot0.len()
        );
        self.panel_at(self.mu.at(0), self.tau_d.at(0), self.xidot0[0])
            .validate()
            .map_err(MapFileError::Spec)?;
        ensure!(
            Spec,
            panels.saturating_mul(self.len()) <= MAX_ALL_POINTS,
            "{panels} panels x {} points: at most {MAX_ALL_POINTS} points",
            self.len()
        );
        for p in self.panels() {
            p.validate().map_err(MapFileError::Spec)?;
        }
        Ok(())
    }

    /// Number of panels (call after [`Self::validate`]).
    #[must_use]
    pub fn panel_count(&self) -> usize {
        self.mu.len() * self.tau_d.len() * self.xidot0.len()
    }

    /// Number of (β, σ) points per panel (call after [`Self::validate`]).
    #[must_use]
    pub fn len(&self) -> usize {
        self.beta.n * self.sigma.n
    }

    /// True for an empty grid (never, after validation).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// CRC-64/XZ of the spec's compact JSON, as 16 hex digits.
    #[must_use]
    pub fn crc64(&self) -> String {
        let json = serde_json::to_string(self).unwrap_or_default();
        let crc = crc::Crc::<u64>::new(&crc::CRC_64_XZ).checksum(json.as_bytes());
        format!("{crc:016x}")
    }

    /// The first field in which `other` differs, for error messages.
    fn first_difference(&self, other: &Self) -> &'static str {
        if self.mu != other.mu {
            "mu"
        } else if self.tau_d != other.tau_d {
            "tau_d"
        } else if self.xidot0 != other.xidot0 {
            "xidot0"
        } else if self.beta != other.beta {
            "beta"
        } else if self.sigma != other.sigma {
            "sigma"
        } else if self.periods != other.periods {
            "periods"
        } else if self.history != other.history {
            "history"
        } else {
            "damping"
        }
    }
}

/// One panel (one μ, τ_D, ξ̇₀).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Panel {
    /// μ.
    pub mu: f64,
    /// τ_D.
    pub tau_d: f64,
    /// ξ̇₀.
    pub xidot0: f64,
    /// Classified points, sorted by index.
    pub points: Vec<MapPoint>,
}

/// The JSON document.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapFile {
    /// Sweep.
    pub spec: Spec,
    /// [`Spec::crc64`] of `spec` (absent in files of older versions: refused by [`validate`]).
    #[serde(default)]
    pub spec_crc64: String,
    /// Shard (k, n), or None when complete.
    pub shard: Option<(usize, usize)>,
    /// Panels.
    pub panels: Vec<Panel>,
    /// Measured cost, per panel and point (not part of the result: it differs run to run).
    pub cost: Cost,
    /// Wall time of the computation in seconds (sum over shards after a merge).
    pub seconds: f64,
}

/// Measured cost of a map: per point, wall time per simulated period; for the whole run, the
/// CPU time the operating system charged (which, unlike wall time, does not grow when the
/// machine is oversubscribed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cost {
    /// Sum of `periods_run` over all points.
    pub periods_total: u64,
    /// Sum over points of `periods_run × ns_per_period`, in seconds of worker-thread wall time
    /// (each point runs on one thread; this is core time when every thread has a core).
    pub core_seconds: f64,
    /// `core_seconds / periods_total` in nanoseconds (0 for no periods).
    pub ns_per_period_mean: f64,
    /// User + system CPU time of the process during the computation, in seconds (Linux
    /// `/proc/self/stat`, 10 ms resolution; summed over shards by a merge); `None` where it
    /// could not be read.
    #[serde(default)]
    pub cpu_seconds: Option<f64>,
    /// `cpu_seconds / periods_total` in nanoseconds: the figure for sizing a sweep.
    #[serde(default)]
    pub cpu_ns_per_period: Option<f64>,
    /// Per panel (in panel order), the ns per period of each point (in point order).
    pub ns_per_period: Vec<Vec<f64>>,
    /// Number of points that ended by cycle detection (`stiffwall_sim::classify`): their
    /// solver state repeated bit for bit (whole cycles skipped) or up to the position's
    /// rounding drift (the rest replayed from one recorded cycle), with a result identical to
    /// simulating every period. Their `periods_run` still counts every period of the horizon.
    /// 0 in files from before the key.
    #[serde(default)]
    pub cycle_points: u64,
}

impl Cost {
    /// The cost of `panels` with per-point `ns_per_period` (same shape), without CPU time.
    #[must_use]
    pub fn of(panels: &[Panel], ns_per_period: Vec<Vec<f64>>) -> Self {
        let mut periods_total = 0u64;
        let mut core_ns = 0.0;
        for (p, ns) in panels.iter().zip(&ns_per_period) {
            for (pt, &c) in p.points.iter().zip(ns) {
                periods_total += pt.periods_run;
                core_ns += pt.periods_run as f64 * c;
            }
        }
        Self {
            periods_total,
            core_seconds: core_ns * 1e-9,
            ns_per_period_mean: if periods_total == 0 {
                0.0
            } else {
                core_ns / periods_total as f64
            },
            cpu_seconds: None,
            cpu_ns_per_period: None,
            ns_per_period,
            cycle_points: 0,
        }
    }

    /// Sets the number of points that ended by cycle detection.
    #[must_use]
    pub fn with_cycle_points(mut self, cycle_points: u64) -> Self {
        self.cycle_points = cycle_points;
        self
    }

    /// Sets the measured CPU time (and the CPU ns per period derived from it).
    #[must_use]
    pub fn with_cpu_seconds(mut self, cpu_seconds: Option<f64>) -> Self {
        self.cpu_seconds = cpu_seconds;
        self.cpu_ns_per_period = cpu_seconds
            .filter(|_| self.periods_total > 0)
            .map(|s| s * 1e9 / self.periods_total as f64);
        self
    }
}

/// CPU time (user + system) of this process so far in seconds, from Linux `/proc/self/stat`
/// (clock ticks of 1/100 s, the fixed `USER_HZ` of Linux's user interface); `None` elsewhere.
#[must_use]
pub fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which may hold spaces) start at field 3 (state).
    let rest = &stat[stat.rfind(')')? + 1..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: u64 = f.get(11)?.parse().ok()?;
    let stime: u64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) as f64 / 100.0)
}

impl MapFile {
    /// (k, n) of this file, (0, 1) for a complete map.
    #[must_use]
    pub fn shard_or_whole(&self) -> (usize, usize) {
        self.shard.unwrap_or((0, 1))
    }
}

/// Checks a map file read from `path` completely (see the module header) before any use.
///
/// # Errors
/// The first problem found, naming the file, the field and what was expected.
pub fn validate(path: &Path, f: &MapFile) -> Result<()> {
    let name = path.display();
    f.spec.validate().map_err(|e| MapFileError::InvalidSpec {
        path: path.to_path_buf(),
        source: Box::new(e),
    })?;
    let crc = f.spec.crc64();
    ensure!(
        Content,
        f.spec_crc64 == crc,
        "{name}: spec_crc64 is {:?} but the spec hashes to {crc:?}: the file was edited, is \
         corrupt or was written by an older hostctl; re-run its shard",
        f.spec_crc64
    );
    let (k, n) = f.shard_or_whole();
    ensure!(
        Content,
        (1..=MAX_SHARDS).contains(&n) && k < n,
        "{name}: shard [{k}, {n}]: need 0 <= k < n and 1 <= n <= {MAX_SHARDS}"
    );
    let specs = f.spec.panels();
    ensure!(
        Content,
        f.panels.len() == specs.len(),
        "{name}: {} panels, but the spec has {} ({} mu x {} tau_d x {} xidot0 values)",
        f.panels.len(),
        specs.len(),
        f.spec.mu.len(),
        f.spec.tau_d.len(),
        f.spec.xidot0.len()
    );
    ensure!(
        Content,
        f.seconds.is_finite() && f.seconds >= 0.0,
        "{name}: seconds = {}: need a finite value >= 0",
        f.seconds
    );
    ensure!(
        Content,
        f.cost.ns_per_period.len() == specs.len(),
        "{name}: cost.ns_per_period has {} panels, need {}",
        f.cost.ns_per_period.len(),
        specs.len()
    );
    for (pi, (panel, ps)) in f.panels.iter().zip(&specs).enumerate() {
        validate_panel(&name, f, pi, panel, ps, (k, n))?;
    }
    let recount = Cost::of(&f.panels, f.cost.ns_per_period.clone());
    ensure!(
        Content,
        f.cost.periods_total == recount.periods_total,
        "{name}: cost.periods_total = {}, but the points ran {} periods",
        f.cost.periods_total,
        recount.periods_total
    );
    if let Some(c) = f.cost.cpu_seconds {
        ensure!(
            Content,
            c.is_finite() && c >= 0.0,
            "{name}: cost.cpu_seconds = {c}: need a finite value >= 0"
        );
    }
    Ok(())
}

/// Checks panel `pi` of the map file against its spec `ps`: its (mu, tau_d, xidot0), its
/// points of shard (k, n), their costs, indices, (β, σ) and periods run.
fn validate_panel(
    name: &std::path::Display<'_>,
    f: &MapFile,
    pi: usize,
    panel: &Panel,
    ps: &MapSpec,
    (k, n): (usize, usize),
) -> Result<()> {
    let len = f.spec.len();
    let want = map::shard_len(len, k, n);
    for (field, got, want) in [
        ("mu", panel.mu, ps.mu),
        ("tau_d", panel.tau_d, ps.tau_d),
        ("xidot0", panel.xidot0, ps.xidot0),
    ] {
        ensure!(
            Content,
            got.to_bits() == want.to_bits(),
            "{name}: panel {pi} has {field} = {got}, the spec says {want}"
        );
    }
    ensure!(
        Content,
        panel.points.len() == want,
        "{name}: panel {pi} has {} points; shard {k}/{n} of a {len}-point grid has {want}",
        panel.points.len()
    );
    let ns = &f.cost.ns_per_period[pi];
    ensure!(
        Content,
        ns.len() == panel.points.len() && ns.iter().all(|c| c.is_finite() && *c >= 0.0),
        "{name}: cost.ns_per_period[{pi}]: need one finite value >= 0 per point ({})",
        panel.points.len()
    );
    for (j, pt) in panel.points.iter().enumerate() {
        let index = k + j * n;
        ensure!(
            Content,
            pt.index == index,
            "{name}: panel {pi}, point {j}: index {}, expected {index} (shard {k}/{n})",
            pt.index
        );
        let (beta, sigma) = ps.point(index);
        ensure!(
            Content,
            pt.beta.to_bits() == beta.to_bits() && pt.sigma.to_bits() == sigma.to_bits(),
            "{name}: panel {pi}, point {index}: beta = {}, sigma = {} contradict its index \
             (expected beta = {beta}, sigma = {sigma})",
            pt.beta,
            pt.sigma
        );
        ensure!(
            Content,
            pt.periods_run <= f.spec.periods,
            "{name}: panel {pi}, point {index}: periods_run = {} exceeds the horizon {}",
            pt.periods_run,
            f.spec.periods
        );
    }
    Ok(())
}

/// Reads and validates a map file; a truncated file is named as such.
///
/// # Errors
/// An unreadable, truncated, malformed or invalid file.
pub fn read(path: &Path) -> Result<MapFile> {
    let s = std::fs::read_to_string(path).map_err(|source| MapFileError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let f: MapFile = serde_json::from_str(&s).map_err(|error| {
        let path = path.to_path_buf();
        if error.is_eof() {
            MapFileError::Truncated { path, error }
        } else {
            MapFileError::NotAMapFile { path, error }
        }
    })?;
    validate(path, &f)?;
    Ok(f)
}

/// The temporary sibling a file is written to before it is renamed into place.
#[must_use]
pub fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(format!(".partial-{}", std::process::id()));
    path.with_file_name(name)
}

/// Writes `m` (a [`MapFile`], or any JSON document such as the (K, B) map) atomically: to
/// [`partial_path`], flushed to disk, then renamed onto `path`.
///
/// # Errors
/// A file error, naming the path.
pub fn write<T: Serialize>(path: &Path, m: &T) -> Result<()> {
    let tmp = partial_path(path);
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        serde_json::to_writer_pretty(&mut f, m)?;
        f.write_all(b"\n")?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(|source| MapFileError::Write {
        path: path.to_path_buf(),
        source,
    })
}

/// Computes a map (or shard (k, n) of it) with the exact solver, calling `progress` once per
/// point; the cost and CPU time are measured around the computation.
#[must_use]
pub fn compute(
    spec: &Spec,
    shard: Option<(usize, usize)>,
    progress: &(dyn Fn() + Sync),
    opts: map::RunOptions,
) -> MapFile {
    let (k, n) = shard.unwrap_or((0, 1));
    let t0 = std::time::Instant::now();
    let cpu0 = process_cpu_seconds();
    let specs = spec.panels();
    let mut cycle_points = 0;
    let (panels, ns): (Vec<Panel>, Vec<Vec<f64>>) = specs
        .iter()
        .map(|ps| {
            let idx = map::shard(ps, k, n);
            let o = map::run_with(ps, &idx, progress, opts);
            cycle_points += o.cycle_points() as u64;
            let panel = Panel {
                mu: ps.mu,
                tau_d: ps.tau_d,
                xidot0: ps.xidot0,
                points: o.points,
            };
            (panel, o.ns_per_period)
        })
        .unzip();
    MapFile {
        spec: spec.clone(),
        spec_crc64: spec.crc64(),
        shard,
        cost: Cost::of(&panels, ns)
            .with_cpu_seconds(
                cpu0.zip(process_cpu_seconds())
                    .map(|(a, b)| (b - a).max(0.0)),
            )
            .with_cycle_points(cycle_points),
        panels,
        seconds: t0.elapsed().as_secs_f64(),
    }
}

/// Merges validated shard files of one sweep (any order) into a complete map.
///
/// # Errors
/// Mismatched sweeps or shard counts, a shard given twice, or missing shards.
pub fn merge(files: &[(PathBuf, MapFile)]) -> Result<MapFile> {
    let (first_path, first) = files
        .first()
        .ok_or_else(|| MapFileError::Merge("no input files".into()))?;
    let (_, n) = first.shard_or_whole();
    let mut by_k: Vec<Option<usize>> = vec![None; n];
    for (i, (path, f)) in files.iter().enumerate() {
        ensure!(
            Merge,
            f.spec == first.spec,
            "{} and {} belong to different sweeps ({} differs; spec_crc64 {} vs {})",
            first_path.display(),
            path.display(),
            first.spec.first_difference(&f.spec),
            first.spec_crc64,
            f.spec_crc64
        );
        let (k, nf) = f.shard_or_whole();
        ensure!(
            Merge,
            nf == n,
            "{} is shard {k}/{nf} but {} is a shard of {n}: merge shards of one split",
            path.display(),
            first_path.display()
        );
        if let Some(j) = by_k[k] {
            return Err(MapFileError::Merge(format!(
                "shard {k}/{n} given twice: {} and {}",
                files[j].0.display(),
                path.display()
            )));
        }
        by_k[k] = Some(i);
    }
    let missing: Vec<String> = by_k
        .iter()
        .enumerate()
        .filter(|(_, f)| f.is_none())
        .map(|(k, _)| format!("{k}/{n}"))
        .collect();
    ensure!(
        Merge,
        missing.is_empty(),
        "missing shards: {} ({} of {n} given)",
        missing.join(", "),
        n - missing.len()
    );
    let ordered: Vec<&MapFile> = by_k.iter().flatten().map(|&i| &files[i].1).collect();
    let spec = first.spec.clone();
    let specs = spec.panels();
    let mut panels = Vec::with_capacity(specs.len());
    let mut ns = Vec::with_capacity(specs.len());
    for (pi, ps) in specs.iter().enumerate() {
        let mut points: Vec<(MapPoint, f64)> = ordered
            .iter()
            .flat_map(|f| {
                let p = &f.panels[pi].points;
                p.iter()
                    .copied()
                    .zip(f.cost.ns_per_period[pi].iter().copied())
            })
            .collect();
        points.sort_by_key(|(p, _)| p.index);
        let (points, c): (Vec<MapPoint>, Vec<f64>) = points.into_iter().unzip();
        panels.push(Panel {
            mu: ps.mu,
            tau_d: ps.tau_d,
            xidot0: ps.xidot0,
            points,
        });
        ns.push(c);
    }
    let cpu: Option<Vec<f64>> = ordered.iter().map(|f| f.cost.cpu_seconds).collect();
    Ok(MapFile {
        spec_crc64: spec.crc64(),
        spec,
        shard: None,
        cost: Cost::of(&panels, ns)
            .with_cpu_seconds(cpu.map(|c| c.iter().sum()))
            .with_cycle_points(ordered.iter().map(|f| f.cost.cycle_points).sum()),
        panels,
        seconds: ordered.iter().map(|f| f.seconds).sum(),
    })
}
