//! `tune_table`: the evidence table of docs/TUNE.md (issue 10, items 5 and 6), run by
//! `cargo xtask tune-table`.
//!
//! For every plant file of `sim/plants/` (or those named with `--only`): the true largest
//! stable stiffness K*(0) of the spring alone ([`stiffwall_tests::kstar`]), the frontier
//! K*(B) over the damper grid [`kstar::FRONTIER_BETA`] × K*(0)·T and its best point, the
//! (K, B) set by `hostctl tune --plant FILE --fast --dry-run --json` (`tune.k_set`,
//! `tune.b_set`, its identified m, b, c, `tune.model_mismatch` when the tune reports it,
//! wall-clock time) with K*(B_set) at the B it set, and the firmware supervisor at
//! 1.5 K*(B_set) with that B after an impact at v_max ([`stiffwall_tests::supervise`]): ticks
//! from the impact to the trip and whether the force was zeroed. Writes docs/TUNE.md.
//!
//! Units: as the plant files (SI; rotary N·m/rad, kg·m², N·m·s/rad, N·m).
//! Options: `--hostctl PATH` (default: target/release/hostctl), `--out FILE`
//! (default docs/TUNE.md), `--only NAME` (repeatable), `--plant FILE` (repeatable: your own
//! plant files instead of `sim/plants/`; printed, written only with `--out`), `--quick` (skip
//! tune: K* and the supervisor only), `--no-write`.

use anyhow::{bail, Context, Result};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;
use stiffwall_tests::family::{self, PlantCase, Supervised, SupervisorReport};
use stiffwall_tests::kstar::{self, KStar, Rig, Trial, TrialKind};

struct Tuned {
    k_set: f64,
    b_set: f64,
    /// The damper law's dead band, counts (0: the plain difference), from `tune.damper`.
    deadband_counts: i64,
    /// The law's name as tune reports it.
    damper: String,
    /// What tune claims: every test of its verification set came to rest.
    rests: bool,
    /// Tune's quiet ceiling 2·max(c, F_s)/Δ of the identified device.
    quiet_ceiling: f64,
    mass: f64,
    viscous: f64,
    coulomb: f64,
    mismatch: Option<Vec<String>>,
    seconds: f64,
}

struct Row {
    case: PlantCase,
    /// K*(0), the spring alone.
    k_star: KStar,
    /// The stiffest point of the frontier grid: (B, K*(B)).
    best: Option<(f64, f64)>,
    /// K*(B_set) at the damping tune set (K*(0) when it set none).
    k_star_set: Option<Result<KStar, String>>,
    /// Every trial of the criterion at (K set, B set), when tune ran.
    at_set: Option<AtSet>,
    k_star_seconds: f64,
    tune: Option<Result<Tuned, String>>,
    /// At 1.5 K*(B_set) with B_set (B = 0 without a tune).
    supervisor: SupervisorReport,
}

/// Every trial of the K* criterion at the set wall, by the simulator alone.
struct AtSet {
    trials: usize,
    /// Trials that come to rest.
    rest: usize,
    /// Trials that chatter within one count (do not rest, do not grow): the worst one's
    /// toggles per second and force swing in units of c.
    chatter: Vec<(Trial, stiffwall_core::rest::Chatter)>,
    /// Trials that buzz over more counts or grow.
    unstable: Vec<Trial>,
}

impl AtSet {
    fn of(case: &PlantCase, k: f64) -> Self {
        let runs = kstar::run_all(&case.proto, &case.rig, k);
        let c = case.model.coulomb_n;
        let mut at = Self {
            trials: runs.len(),
            rest: 0,
            chatter: Vec::new(),
            unstable: Vec::new(),
        };
        for (t, r) in runs {
            if r.rests() {
                at.rest += 1;
            } else if let Some(ch) = r.chatter(case.rig.period_s, c) {
                at.chatter.push((t, ch));
            } else {
                at.unstable.push(t);
            }
        }
        at
    }

    fn all_rest(&self) -> bool {
        self.rest == self.trials
    }

    fn cell(&self) -> String {
        if self.all_rest() {
            return format!("yes ({} of {})", self.rest, self.trials);
        }
        let mut s = format!("NO: {} of {} rest", self.rest, self.trials);
        if let Some((t, ch)) = self
            .chatter
            .iter()
            .max_by(|a, b| a.1.force_pp_c.total_cmp(&b.1.force_pp_c))
        {
            let _ = write!(
                s,
                "; {} chatter (worst {}: {:.0} toggles/s, {:.1} c)",
                self.chatter.len(),
                describe(t),
                ch.toggles_per_s,
                ch.force_pp_c
            );
        }
        if let Some(t) = self.unstable.first() {
            let _ = write!(
                s,
                "; {} UNSTABLE (first {})",
                self.unstable.len(),
                describe(t)
            );
        }
        s
    }
}

/// The dead band of a law named as the firmware's `DamperLaw` prints it (`difference`,
/// `dead-band-N`).
fn deadband_of(law: &str) -> Result<i64> {
    if law == "difference" {
        return Ok(0);
    }
    law.strip_prefix("dead-band-")
        .and_then(|n| n.parse().ok())
        .with_context(|| format!("tune.damper {law:?} is neither `difference` nor `dead-band-N`"))
}

fn run_tune(hostctl: &Path, file: &Path) -> Result<Tuned> {
    let t0 = Instant::now();
    let out = std::process::Command::new(hostctl)
        .arg("tune")
        .arg("--plant")
        .arg(file)
        .args(["--fast", "--dry-run", "--json"])
        .output()
        .with_context(|| format!("starting {}", hostctl.display()))?;
    let seconds = t0.elapsed().as_secs_f64();
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let last = err.lines().last().unwrap_or("").to_string();
        bail!("hostctl tune failed: {last}");
    }
    let j: serde_json::Value =
        serde_json::from_slice(&out.stdout).context("parsing hostctl tune --json")?;
    let t = &j["tune"];
    let num = |v: &serde_json::Value, what: &str| {
        v.as_f64()
            .with_context(|| format!("tune JSON has no number at {what}"))
    };
    let mismatch = t.get("model_mismatch").and_then(|m| m.as_array()).map(|a| {
        a.iter()
            .map(|x| {
                x.as_str()
                    .map_or_else(|| x.to_string(), std::string::ToString::to_string)
            })
            .collect()
    });
    let damper = t["damper"]
        .as_str()
        .context("tune JSON has no string at tune.damper")?
        .to_string();
    Ok(Tuned {
        k_set: num(&t["k_set"], "tune.k_set")?,
        b_set: num(&t["b_set"], "tune.b_set")?,
        deadband_counts: deadband_of(&damper)?,
        damper,
        rests: t["rests"]
            .as_bool()
            .context("tune JSON has no bool at tune.rests")?,
        quiet_ceiling: num(&t["quiet_ceiling"], "tune.quiet_ceiling")?,
        mass: num(&t["identified"]["mass"][0], "tune.identified.mass")?,
        viscous: num(&t["identified"]["viscous"][0], "tune.identified.viscous")?,
        coulomb: num(&t["identified"]["coulomb"][0], "tune.identified.coulomb")?,
        mismatch,
        seconds,
    })
}

fn describe_trial(k: &KStar) -> String {
    describe(&k.failing)
}

fn describe(t: &Trial) -> String {
    let side = if t.side > 0 { "+" } else { "−" };
    let wall = if t.wall == 0 {
        String::new()
    } else {
        format!(", wall +{} counts", t.wall)
    };
    match t.kind {
        TrialKind::Impact { velocity_m_per_s } => {
            format!("impact {side}{velocity_m_per_s:.3}{wall}")
        }
        TrialKind::Release { counts } => format!("release {side}{counts}{wall}"),
    }
}

fn effects(case: &PlantCase) -> String {
    let m = &case.model;
    let mut e = Vec::new();
    if let Some(s) = m.stiction {
        e.push(format!(
            "stiction {:.2}×",
            s.static_n / m.coulomb_n.max(1e-300)
        ));
    }
    if let Some(c) = m.cogging {
        e.push(format!(
            "cogging {:.0} %",
            100.0 * c.amplitude_n / m.coulomb_n.max(1e-300)
        ));
    }
    if let Some(t) = m.transmission {
        let m1 = m.mass_kg;
        let m2 = t.link_mass_kg + m.hand.map_or(0.0, |h| h.mass_kg);
        let f = (t.stiffness_n_per_m * (1.0 / m1 + 1.0 / m2)).sqrt() / std::f64::consts::TAU;
        e.push(format!("transmission {f:.0} Hz"));
    }
    if let Some(a) = m.amplifier {
        if let Some(f) = a.cutoff_hz {
            e.push(format!("amp {f:.0} Hz"));
        }
        if let Some(d) = a.deadband_n {
            e.push(format!("dead band {d:.3}"));
        }
    }
    if let Some(h) = m.hand {
        e.push(format!("hand {:.2e}", h.mass_kg));
    }
    if case.rig.delay_ticks > 0 {
        e.push(format!("delay {}T", case.rig.delay_ticks));
    }
    if case.rig.one_sided {
        e.push("one-sided".into());
    }
    e.push(format!("T {:.2} ms", case.controller.period_s * 1e3));
    e.join(", ")
}

/// The stiffest point (B, K*(B)) of the frontier over B = [`kstar::FRONTIER_BETA`] ×
/// K*(0)·T (the grid's K* searches run in parallel); None when no damped K* was found.
fn best_of_frontier(case: &PlantCase, k0: f64) -> Option<(f64, f64)> {
    let grid: Vec<f64> = kstar::FRONTIER_BETA
        .iter()
        .map(|beta| beta * k0 * case.rig.period_s)
        .collect();
    grid.par_iter()
        .filter_map(|&b| {
            let rig = Rig {
                damping: b,
                deadband_counts: DEFAULT_DEADBAND,
                ..case.rig.clone()
            };
            kstar::k_star(&case.proto, &rig, k0 * 0.5, 1e12)
                .ok()
                .map(|k| (b, k.k_star))
        })
        .collect::<Vec<_>>()
        .into_iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

fn g(v: f64) -> String {
    format!("{v:.4}")
}

/// The supervisor cell of one v_max impact.
fn trip(s: &Supervised) -> String {
    match (s.unsupervised_settles, s.run.trip_tick) {
        (true, None) => "settles".to_string(),
        (true, Some(t)) => format!("settles (trip {t})"),
        (false, Some(t)) if s.run.stopped() => t.to_string(),
        (false, _) if s.left_and_released() => format!(
            "thrown out {:+.1} % faster once, no fault, force 0 after",
            100.0 * (s.left_faster.unwrap_or(1.0) - 1.0)
        ),
        (false, _) if s.safe_by_decay() => "decays under the firmware".to_string(),
        (false, _) => "NOT STOPPED".to_string(),
    }
}

/// The cell of the other unstable trials under the supervisor.
fn others(sup: &SupervisorReport) -> String {
    if sup.other_unstable.is_empty() {
        return "none".to_string();
    }
    let stopped = sup.other_unstable.iter().filter(|s| s.safe()).count();
    let worst = sup
        .other_unstable
        .iter()
        .filter_map(|s| s.run.trip_tick)
        .max()
        .map_or(String::new(), |t| format!(", latest trip {t}"));
    let decays = sup
        .other_unstable
        .iter()
        .filter(|s| s.safe_by_decay())
        .count();
    let decays = if decays > 0 {
        format!(" ({decays} decay under the firmware)")
    } else {
        String::new()
    };
    format!(
        "{stopped} of {} safe{decays}{worst}",
        sup.other_unstable.len()
    )
}

/// The tune's cells: K set, B set, damper law, K*(B set), K/K*(B set), rests at the set
/// point, K/K*(0), seconds, m, b, c, quiet ceiling, mismatch findings.
fn tune_cells(r: &Row, quick: bool) -> [String; 13] {
    let m = &r.case.model;
    let true_m = family::moving_mass_kg(m);
    let true_b = m.viscous_ns_per_m + m.hand.map_or(0.0, |h| h.damping_ns_per_m);
    let dash = || "—".to_string();
    match &r.tune {
        Some(Ok(t)) => {
            let (ks, ratio) = match &r.k_star_set {
                Some(Ok(k)) => (g(k.k_star), format!("{:.3}", t.k_set / k.k_star)),
                Some(Err(e)) => (format!("failed: {}", e.replace('|', "/")), dash()),
                None => (dash(), dash()),
            };
            [
                g(t.k_set),
                format!("{:.4e}", t.b_set),
                if t.b_set > 0.0 {
                    t.damper.clone()
                } else {
                    "—".to_string()
                },
                ks,
                ratio,
                match &r.at_set {
                    Some(a) => format!(
                        "{}{}",
                        a.cell(),
                        if t.rests {
                            ""
                        } else {
                            " (tune: no wall rests)"
                        }
                    ),
                    None => dash(),
                },
                format!("{:.3}", t.k_set / r.k_star.k_star),
                format!("{:.1}", t.seconds),
                format!("{:.3e} / {:.3e}", t.mass, true_m),
                format!("{:.2e} / {:.2e}", t.viscous, true_b),
                format!(
                    "{:.3e} / {:.3e} ({:.3e})",
                    t.coulomb,
                    m.coulomb_n,
                    m.static_friction_n()
                ),
                format!(
                    "{} / {}",
                    g(t.quiet_ceiling),
                    g(stiffwall_core::rest::quiet_ceiling(
                        m.coulomb_n,
                        m.static_friction_n(),
                        r.case.rig.resolution_m
                    ))
                ),
                match &t.mismatch {
                    None => "(not reported)".to_string(),
                    Some(v) if v.is_empty() => "none".to_string(),
                    Some(v) => v.join("; ").replace('|', "/"),
                },
            ]
        }
        other => [
            match other {
                Some(Err(e)) => format!("failed: {}", e.replace('|', "/")),
                _ if quick => "(--quick)".into(),
                _ => dash(),
            },
            dash(),
            dash(),
            dash(),
            dash(),
            dash(),
            dash(),
            dash(),
            format!("— / {true_m:.3e}"),
            format!("— / {true_b:.2e}"),
            format!("— / {:.3e} ({:.3e})", m.coulomb_n, m.static_friction_n()),
            dash(),
            dash(),
        ],
    }
}

fn render(rows: &[Row], quick: bool) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| plant | effects | K*(0) | first failure above K*(0) | best K*(B) of the grid (B) | K set | B set | damper | K*(B set) | K/K*(B set) | rests in every run at (K, B) set | K/K*(0) | tune s | m id / true | b id / true | c id / true (static) | quiet ceiling 2·max(c, F_s)/Δ id / true | mismatch findings | v_max impact at 1.5 K*(B set), B set: ticks to trip (+/−) | other unstable trials there | all safe |"
    );
    let _ = writeln!(
        s,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in rows {
        let sup = &r.supervisor;
        let trips = sup
            .v_max_impacts
            .iter()
            .map(trip)
            .collect::<Vec<_>>()
            .join(" / ");
        let best = r
            .best
            .map_or("—".to_string(), |(b, k)| format!("{} ({b:.3e})", g(k)));
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {best} | {} | {trips} | {} | {} |",
            r.case.name,
            effects(&r.case),
            g(r.k_star.k_star),
            describe_trial(&r.k_star),
            tune_cells(r, quick).join(" | "),
            others(sup),
            if sup.all_safe() { "yes" } else { "NO" },
        );
    }
    if let Some(summary) = summary(rows) {
        let _ = writeln!(s, "\n{summary}");
    }
    s
}

/// The dead band of the firmware's default damper law (`DamperLaw::default()`), counts.
const DEFAULT_DEADBAND: i64 = 1;

/// Lower bound of K set / K*_quiet(B set) (docs/TUNE.md and the every-plant test say the same).
const NEAR_OPTIMAL: f64 = 0.7;
/// Lower bound of the median K set / K*(0) over `sim/plants/`.
const MEDIAN_GAIN: f64 = 2.0;

/// The median of `v` (sorted in place); None when empty.
fn median(v: &mut [f64]) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    (n > 0).then(|| {
        if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        }
    })
}

/// The line under the table: median gain k_set / K*(0), smallest K/K*(B set), rest counts.
fn summary(rows: &[Row]) -> Option<String> {
    let mut gains = Vec::new();
    let mut ratios = Vec::new();
    let (mut not_resting, mut unstable) = (0, 0);
    for r in rows {
        if let (Some(Ok(t)), Some(Ok(k))) = (&r.tune, &r.k_star_set) {
            gains.push(t.k_set / r.k_star.k_star);
            ratios.push(t.k_set / k.k_star);
        }
        if let Some(a) = &r.at_set {
            not_resting += usize::from(!a.all_rest());
            unstable += usize::from(!a.unstable.is_empty());
        }
    }
    let n = gains.len();
    let median = median(&mut gains)?;
    let min_ratio = ratios.iter().copied().fold(f64::INFINITY, f64::min);
    let max_ratio = ratios.iter().copied().fold(0.0, f64::max);
    Some(format!(
        "Over {n} tuned plants: median K set / K*(0) = {median:.2} (the damper's gain, quietly), \
         K set / K*(B set) from {min_ratio:.3} to {max_ratio:.3}; {not_resting} set walls do not \
         come to rest in every run; {unstable} are unstable (buzz or growth) in some run."
    ))
}

/// What makes the table a failure: a tune that failed, a set wall that does not rest in every
/// run or is unstable, K set below 0.7 × K*(B set) (above K*(B set) only where every run at
/// the set wall rests: the quiet K need not form one interval), a supervisor that did not stop a
/// run, and (over all of `sim/plants/`) a median gain below 2. Empty when the table holds.
fn failures(rows: &[Row], whole_family: bool, quick: bool) -> Vec<String> {
    let mut out = Vec::new();
    let mut gains = Vec::new();
    for r in rows {
        let name = &r.case.name;
        if !r.supervisor.all_safe() {
            out.push(format!(
                "{name}: the supervisor did not stop every run at 1.5 K*(B set)"
            ));
        }
        if quick {
            continue;
        }
        let t = match &r.tune {
            Some(Ok(t)) => t,
            Some(Err(e)) => {
                out.push(format!("{name}: tune failed: {e}"));
                continue;
            }
            None => continue,
        };
        gains.push(t.k_set / r.k_star.k_star);
        if let Some(a) = &r.at_set {
            if !a.all_rest() {
                out.push(format!(
                    "{name}: the set wall does not rest in every run: {}",
                    a.cell()
                ));
            }
        }
        match &r.k_star_set {
            // Above K*(B) (the top of the first quiet interval) is allowed only because every
            // run at the set wall came to rest (checked above): with a damper the quiet K need
            // not form one interval.
            Some(Ok(k)) => {
                let q = t.k_set / k.k_star;
                if q < NEAR_OPTIMAL {
                    out.push(format!(
                        "{name}: K set / K*(B set) = {q:.3} < {NEAR_OPTIMAL}"
                    ));
                }
            }
            Some(Err(e)) => out.push(format!("{name}: {e}")),
            None => {}
        }
    }
    if whole_family && !quick {
        if let Some(m) = median(&mut gains) {
            if m < MEDIAN_GAIN {
                out.push(format!("median K set / K*(0) = {m:.2} < {MEDIAN_GAIN}"));
            }
        }
    }
    out
}

fn document(table: &str, command: &str, source: &str) -> String {
    format!(
        "# Tune on plants beyond its model\n\n\
<!-- Generated by `{command}` (tests/xtask/src/tune_table.rs, tests/src/bin/tune_table.rs); do not edit by hand. -->\n\n\
Each plant of {source} (a physical scene with the effects of `stiffwall-sim`'s `rich` module) is\n\
tuned with `hostctl tune --plant FILE --fast --dry-run --json` against the virtual device, whose\n\
firmware core runs that plant; the wall (K, B) it sets, a spring and a virtual damper with its\n\
law (`damper`), is compared with the true largest **quiet** stiffness K*(B) at that damping and law\n\
(every trial comes to rest), computed from the simulator alone, and every trial of the criterion is\n\
run at the set wall: \"rests in every run\" counts those that come to rest; a trial that keeps\n\
toggling within one count is chatter (worst toggles per second and force swing in units of the\n\
Coulomb friction c listed), one that buzzes over more counts or grows is unstable. The generator\n\
exits non-zero when a set wall does not rest in every run, K set lies below 0.7 × K*(B set),\n\
the supervisor does not stop a run, or the median gain over `sim/plants/` is below 2.\n\
K*(0) is the spring alone; the best K*(B) is the stiffest of the frontier (with the law tune set;\n\
dead band 1 when it set no damper) over\n\
B = β·K*(0)·T, β ∈ {{0, 0.5, 1, 2, 3, 4, 6}} (`kstar::FRONTIER_BETA`); K set / K*(0) is what the\n\
damper buys. Units: N/m, kg, N·s/m, N for linear plants; N·m/rad, kg·m²,\n\
N·m·s/rad, N·m for rotary ones (`counts_per_rev`).\n\n\
## How K* is computed (tests/src/kstar.rs)\n\n\
The sampled wall of eq. (2) with the firmware's damper, F = −K·Δ·(n + ½) − B·Δ·v/T on the encoder\n\
count n = ⌊x/Δ⌋ of the motor side, with v = n − n_prev the difference from the previous sample's\n\
count (`difference`), or v = 0 when |n − n_prev| ≤ N (`dead-band-N`) (the whole\n\
law 0 for n < 0 on a one-sided wall; an impact's first n_prev is the count one period before\n\
contact, a release's its own), clamped to the amplifier's range, delayed by the plant's extra\n\
delay in whole periods and held over each period T (ZOH), steps the plant's `RichPlant` (amplifier\n\
filter, dead band and saturation, stiction, cogging, transmission and hand inside). No firmware, no\n\
identification. v_max = 5 counts per period (5Δ/T, the default maximum velocity of `hostctl tune`).\n\
A stiffness K is **quiet** when every trial comes to rest:\n\n\
- impacts at the wall surface moving into the wall at v_max × {{0.1, 0.2, …, 1}}, from both sides\n\
  (one side for a one-sided wall);\n\
- releases from rest at deflections d_max × {{1, 0.6, 0.3}} and 1 count, both sides, where\n\
  ½K(d_max·Δ)² = ½·m·v_max² with m the whole moving mass (motor side, link, hand); a release\n\
  starts as a hold leaves the device (`RichPlant::set_held`): the motor at the deflection, at\n\
  rest in static equilibrium, so a hand's spring behind a transmission deflects the link, and an\n\
  amplifier filter carries the holding force;\n\
- with cogging, all of them again with the wall a quarter cogging period further on.\n\n\
A trial runs 60 natural periods 2π√(m/K) (2000–40000 ticks) and **comes to rest** when the count\n\
changes at most twice over its judged window, the last quarter of the run or from 45 natural\n\
periods on if that is earlier (`stiffwall_core::rest`, the rule tune's verification uses too): chatter\n\
(toggling between two neighbouring counts for ever), a buzz over more counts and growth fail (growth\n\
is also cut short when |n| exceeds 10·(d_max + 2) + 100 counts; on a one-sided wall only the\n\
penetration). On\n\
a one-sided wall without a hand spring nothing brings the plant back once it left the wall\n\
(count < −1, moving away): the trial ends there and settles when the plant leaves no faster than a\n\
passive wall returns it (the impact speed; after a release from count d, the speed of kinetic\n\
energy ½K((d + 1)Δ)²). K is scanned upwards by ×1.25 from\n\
σ = c/(KΔ) = 4 until a trial fails, then bisected to 0.5 %, then K*/1.5625 … K* is tried again\n\
in steps of ×1.05 (a failing band that the coarse scan stepped over is bisected instead): K* is\n\
the largest K below the first failure, resolved to 5 % over the span where a tune's answer\n\
(≥ 0.7 K*) lies. K*(B) at the B tune set is scanned from 0.5 K*(0). The trial that failed just\n\
above K* is listed.\n\n\
## The supervisor at 1.5 K*(B) (tests/src/supervise.rs, tests/tests/supervisor_plants.rs)\n\n\
The firmware core (`stiffwall-firmware`'s `Servo`, the virtual device's boot config: energy monitor\n\
on, growth trip 4, force limit at full scale) with the damping B that tune set and K forced to\n\
1.5 K*(B) drives the same plant\n\
(software in the loop, the virtual device's board: 32-bit counter, ±32767 codes over the\n\
amplifier's range). Runs: the impact at v_max from each side, and every other trial of the K*\n\
criterion that buzzes or grows without the firmware at 1.5 K*(B) (chatter within one count is\n\
not the supervisor's to stop). A number is the ticks from the\n\
impact (first contact) to the latched fault, after which every output code was 0; \"settles\"\n\
means the run is stable without the firmware (nothing to stop). The firmware's monitors are the\n\
turning-point energy monitor (growth score, limit) and the buzz detector added for this family\n\
(`stiffwall_core::monitor::BuzzDetector`, fault `buzz`): 32 consecutive turning points with\n\
swings of two counts or more, at 15 Hz or faster, the largest of the last 8 swings not smaller\n\
than the largest of the first 8 less 1/32 of it (none below 32 counts) —\n\
the persistent oscillation of a firmly held device or a slow servo above K*, whose peaks do not\n\
grow, or one converging onto a limit cycle. \"Decays under the firmware\" is a trial that does\n\
not settle without the firmware but, with no fault, dies away under it (its peak-to-peak motion\n\
over the last sixth of the run at most a quarter of that over the first sixth, or within one\n\
count, and never farther from the wall than the first sixth reached): the firmware's 16-bit,\n\
fixed-point output is not the bare spring's, and near a limit cycle (cogging with a hand) that\n\
is enough to converge; the monitors rightly leave a decaying motion alone. A one-sided wall without a hand spring that throws the plant out faster than it came\n\
(once: nothing brings it back) latches no fault; the table says so, with the speed gained, and\n\
the firmware applies no force after the plant left.\n\n## Table\n\n{table}\n"
    )
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut o = Options::parse(&args, &root)?;
    // `--plant FILE` (repeatable) checks the user's own plant files instead of sim/plants/;
    // the table is then printed, and written only with an explicit `--out`.
    let extra_given = !o.extra.is_empty();
    let root_abs = std::fs::canonicalize(&root).unwrap_or_else(|_| root.clone());
    let files = if extra_given {
        if !o.out_given {
            o.write = false;
        }
        std::mem::take(&mut o.extra)
    } else {
        family::plant_files(&family::plants_dir()).context("listing sim/plants")?
    };
    let mut rows = Vec::new();
    let mut skipped: Vec<String> = Vec::new();
    for f in files {
        let case = match PlantCase::load(&f) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("skipped: {e}");
                skipped.push(e);
                continue;
            }
        };
        if !o.only.is_empty() && !o.only.contains(&case.name) {
            continue;
        }
        match plant_row(case, &f, &o) {
            Ok(row) => rows.push(row),
            Err(e) => {
                eprintln!("skipped: {e}");
                skipped.push(e);
            }
        }
    }
    let table = render(&rows, o.quick);
    print!("{table}");
    let total: f64 = rows.iter().map(|r| r.k_star_seconds).sum();
    eprintln!("K* searches: {total:.1} s in total");
    if !skipped.is_empty() {
        bail!(
            "{} plant(s) without a row (nothing written):\n{}",
            skipped.len(),
            skipped.join("\n")
        );
    }
    if let Some(doc) = &o.check {
        check_against(doc, &table, o.only.is_empty())?;
    }
    if o.write {
        let (cmd, source) = provenance(&rows, extra_given, &root_abs, &o);
        std::fs::write(&o.out, document(&table, &cmd, &source))
            .with_context(|| format!("writing {}", o.out.display()))?;
        eprintln!("wrote {}", o.out.display());
    }
    let whole_family = !extra_given && o.only.is_empty();
    let failed = failures(&rows, whole_family, o.quick);
    if !failed.is_empty() {
        bail!(
            "{} row(s) of the table fail what the docs claim:\n{}",
            failed.len(),
            failed.join("\n")
        );
    }
    Ok(())
}

/// The columns of a table row that a fresh run must reproduce exactly: the plant, its effects,
/// K*(0), the first failure above it and the best K*(B) of the grid (the brute force from the
/// plant file alone, deterministic). Tune's own columns vary from run to run on plants whose
/// state between tests is not reproducible (rotary-belt-60hz) and are checked by the rules of
/// [`failures`] instead.
const STABLE_COLUMNS: [usize; 5] = [1, 2, 3, 4, 5];

/// The table rows of a Markdown document, by plant: the cells of [`STABLE_COLUMNS`].
fn stable_cells(doc: &str) -> Vec<(String, Vec<String>)> {
    doc.lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| plant") && !l.starts_with("|---"))
        .map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            let pick = STABLE_COLUMNS
                .iter()
                .map(|&c| cells.get(c).copied().unwrap_or("").to_string())
                .collect();
            (cells.get(1).copied().unwrap_or("").to_string(), pick)
        })
        .collect()
}

/// Fails when the committed document `doc` is stale: its rows' [`STABLE_COLUMNS`] differ from
/// the fresh `table`'s, or (with `all`: the run covered every plant) the plants differ.
fn check_against(doc: &Path, table: &str, all: bool) -> Result<()> {
    let text =
        std::fs::read_to_string(doc).with_context(|| format!("reading {}", doc.display()))?;
    let (old, new) = (stable_cells(&text), stable_cells(table));
    let mut stale = Vec::new();
    for (plant, cells) in &new {
        match old.iter().find(|(p, _)| p == plant) {
            None => stale.push(format!("{plant}: not in {}", doc.display())),
            Some((_, was)) if was != cells => {
                stale.push(format!(
                    "{plant}: {} says {was:?}, a fresh run {cells:?}",
                    doc.display()
                ));
            }
            Some(_) => {}
        }
    }
    for (plant, _) in old.iter().filter(|_| all) {
        if !new.iter().any(|(p, _)| p == plant) {
            stale.push(format!(
                "{plant}: in {} but not in a fresh run",
                doc.display()
            ));
        }
    }
    if !stale.is_empty() {
        bail!(
            "{} is stale (regenerate it with `cargo xtask tune-table`):\n{}",
            doc.display(),
            stale.join("\n")
        );
    }
    eprintln!("{}: its K* columns match a fresh run", doc.display());
    Ok(())
}

/// The program's options (see `cargo xtask tune-table`).
struct Options {
    /// The hostctl binary that tunes.
    hostctl: PathBuf,
    /// Where the document goes.
    out: PathBuf,
    /// `--out` was given.
    out_given: bool,
    /// Only these plants (file stems), if any.
    only: Vec<String>,
    /// The user's own plant files instead of sim/plants/.
    extra: Vec<PathBuf>,
    /// K* and the supervisor only, no tune runs.
    quick: bool,
    /// Write the document (else print only).
    write: bool,
    /// Compare the fresh table with this document's (`--check FILE`, implies `--no-write`).
    check: Option<PathBuf>,
}

impl Options {
    fn parse(args: &[String], root: &Path) -> Result<Self> {
        let mut o = Self {
            hostctl: root.join("target").join("release").join("hostctl"),
            out: root.join("docs").join("TUNE.md"),
            out_given: false,
            only: Vec::new(),
            extra: Vec::new(),
            quick: false,
            write: true,
            check: None,
        };
        let mut i = 0;
        while i < args.len() {
            let value = |i: usize| {
                args.get(i + 1)
                    .cloned()
                    .with_context(|| format!("{} needs a value", args[i]))
            };
            match args[i].as_str() {
                "--hostctl" => {
                    o.hostctl = PathBuf::from(value(i)?);
                    i += 1;
                }
                "--out" => {
                    o.out = PathBuf::from(value(i)?);
                    o.out_given = true;
                    i += 1;
                }
                "--only" => {
                    o.only.push(value(i)?);
                    i += 1;
                }
                "--plant" => {
                    o.extra.push(PathBuf::from(value(i)?));
                    i += 1;
                }
                "--quick" => o.quick = true,
                "--no-write" => o.write = false,
                "--check" => {
                    o.check = Some(PathBuf::from(value(i)?));
                    o.write = false;
                    i += 1;
                }
                other => bail!(
                    "unknown option {other:?}; available: --hostctl PATH, --out FILE, --only NAME, --plant FILE, --quick, --no-write, --check FILE"
                ),
            }
            i += 1;
        }
        Ok(o)
    }
}

/// One plant's row: K*(0), the frontier's best, tune's (K, B) from `f`, K*(B set), the set
/// point's stability and the supervisor at 1.5 K*(B set). Err (the reason, for the skipped
/// list) when K*(0) has no finite value.
fn plant_row(case: PlantCase, f: &Path, o: &Options) -> Result<Row, String> {
    let t0 = Instant::now();
    let k_star = k_star_or_reason(&case, f, o)?;
    let best = best_of_frontier(&case, k_star.k_star);
    let k_star_seconds = t0.elapsed().as_secs_f64();
    let tune = (!o.quick).then(|| run_tune(&o.hostctl, f).map_err(|e| format!("{e:#}")));
    let (b_set, deadband_counts) = match &tune {
        Some(Ok(t)) => (t.b_set, t.deadband_counts),
        _ => (0.0, 0),
    };
    let damped = PlantCase {
        rig: Rig {
            damping: b_set,
            deadband_counts,
            ..case.rig.clone()
        },
        ..case.clone()
    };
    let k_star_set = tune
        .as_ref()
        .map(|_| k_star_at_set(&damped, &k_star, b_set));
    let at_set = match &tune {
        Some(Ok(t)) => Some(AtSet::of(&damped, t.k_set)),
        _ => None,
    };
    let k_sup = supervised_k_star(&k_star, k_star_set.as_ref());
    let supervisor = damped.supervisor_report(1.5 * k_sup);
    let row = Row {
        case,
        k_star,
        best,
        k_star_set,
        at_set,
        k_star_seconds,
        tune,
        supervisor,
    };
    log_row(&row, k_sup);
    Ok(row)
}

/// K*(0) of `case`, or the reason it has none (with what tune from `f` sets there, unless
/// `--quick`: with no finite K*, it cannot be unsafe).
fn k_star_or_reason(case: &PlantCase, f: &Path, o: &Options) -> Result<KStar, String> {
    match kstar::k_star(&case.proto, &case.rig, case.k_start(), 1e12) {
        Ok(k) => Ok(k),
        Err(e) => {
            // Still say what tune sets there: with no finite K*, it cannot be unsafe.
            let tune = (!o.quick).then(|| run_tune(&o.hostctl, f));
            Err(format!(
                "{}: K*: {e}{}",
                case.name,
                match tune {
                    Some(Ok(t)) => format!("; tune sets K = {:.5} ({:.1} s)", t.k_set, t.seconds),
                    Some(Err(e)) => format!("; tune failed: {e:#}"),
                    None => String::new(),
                }
            ))
        }
    }
}

/// K*(B set) of the `damped` case (the damping tune set, `b_set`), scanned from 0.5 K*(0);
/// K*(0) itself when tune set no damping.
fn k_star_at_set(damped: &PlantCase, k_star: &KStar, b_set: f64) -> Result<KStar, String> {
    if b_set > 0.0 {
        kstar::k_star(&damped.proto, &damped.rig, k_star.k_star * 0.5, 1e12)
            .map_err(|e| format!("K*(B = {b_set:.4e}): {e}"))
    } else {
        Ok(k_star.clone())
    }
}

/// The K* the supervisor's 1.5 K* is taken of: K*(B set) when found, else K*(0).
fn supervised_k_star(k_star: &KStar, k_star_set: Option<&Result<KStar, String>>) -> f64 {
    match k_star_set {
        Some(Ok(k)) => k.k_star,
        _ => k_star.k_star,
    }
}

/// The row's progress line on stderr (`k_sup`: the K* the supervisor ran at 1.5 times).
fn log_row(r: &Row, k_sup: f64) {
    let (best, k_star_seconds, supervisor) = (&r.best, r.k_star_seconds, &r.supervisor);
    eprintln!(
        "{}: K*(0) = {:.5} ({} evaluations), best K*(B) {best:?} ({k_star_seconds:.1} s), tune {}, at 1.5 K*(B set) = {:.5}: v_max impacts trip {:?}, {} other unstable trials, all stopped: {}",
        r.case.name,
        r.k_star.k_star,
        r.k_star.evaluations,
        match &r.tune {
            Some(Ok(t)) => format!("K = {:.5}, B = {:.4e} ({:.3} K*(B set), {:.1} s)", t.k_set, t.b_set, t.k_set / k_sup, t.seconds),
            Some(Err(e)) => format!("failed: {e}"),
            None => "skipped".into(),
        },
        1.5 * k_sup,
        supervisor
            .v_max_impacts
            .iter()
            .map(|s| s.run.trip_tick)
            .collect::<Vec<_>>(),
        supervisor.other_unstable.len(),
        supervisor.all_safe(),
    );
}

/// The command that made the document and the plant directories it covers (relative to the
/// repository when the files are inside it).
fn provenance(rows: &[Row], extra_given: bool, root_abs: &Path, o: &Options) -> (String, String) {
    let mut cmd = String::from(if o.quick {
        "cargo xtask tune-table --quick"
    } else {
        "cargo xtask tune-table"
    });
    if !extra_given {
        return (cmd, "`sim/plants/`".to_string());
    }
    let names: Vec<String> = rows
        .iter()
        .map(|r| {
            let p = r.case.path.strip_prefix(root_abs).unwrap_or(&r.case.path);
            p.display().to_string()
        })
        .collect();
    for n in &names {
        cmd.push_str(&format!(" --plant {n}"));
    }
    let mut dirs: Vec<String> = names
        .iter()
        .map(|n| {
            Path::new(n)
                .parent()
                .map_or_else(String::new, |d| d.display().to_string())
        })
        .collect();
    dirs.dedup();
    cmd.push_str(&format!(
        " --out {}",
        o.out.strip_prefix(root_abs).unwrap_or(&o.out).display()
    ));
    (cmd, format!("`{}/`", dirs.join("/`, `")))
}
