//! The dry-run tune of one plant, as `hostctl tune --plant FILE --fast --dry-run` runs it, in
//! this process with the plant's true state traced ([`run_tune`]).
use super::row::Tuned;
use anyhow::{bail, Context, Result};
use std::path::Path;
use std::time::Instant;
use stiffwall_tests::family::PlantCase;
use stiffwall_tests::kstar;

/// Half-width of the travel the table declares for a plant without end stops whose tune in
/// the default window lowered the maximum velocity, m (linear): such a plant is unbounded,
/// and its user says so (`--travel`); K*'s impacts run at the full velocity (a 0.1 mm encoder
/// at 5 counts per tick needs about 0.22 m each side).
const UNBOUNDED_TRAVEL: f64 = 10.0;
/// The same for a rotary plant, rad (about 160 turns).
const UNBOUNDED_TRAVEL_RAD: f64 = 1000.0;

/// A dry-run tune of the fast virtual device running the plant of `case` (what `hostctl tune
/// --plant FILE --fast --dry-run` runs), in this process, with the plant's true state traced.
/// A plant with end stops is tuned inside them (the device's travel window); one without in
/// tune's default window, and again with ±[`UNBOUNDED_TRAVEL`] given when that window made
/// tune lower the maximum velocity below K*'s ([`kstar::DEFAULT_XIDOT`] counts per period).
pub(super) fn run_tune(case: &PlantCase) -> Result<Tuned> {
    let first = tune_once(case, None)?;
    if case.model.travel.is_some() || first.xidot >= kstar::DEFAULT_XIDOT * (1.0 - 1e-6) {
        return Ok(first);
    }
    let half = if case.model.counts_per_rev.is_some() {
        UNBOUNDED_TRAVEL_RAD
    } else {
        UNBOUNDED_TRAVEL
    };
    tune_once(case, Some([-half, half]))
}

/// One traced dry-run tune of `case` with `travel` given (None: the device's or the default).
fn tune_once(case: &PlantCase, travel: Option<[f64; 2]>) -> Result<Tuned> {
    use stiffwall_client::{connect, Cancel, ConnectSpec, Pace};
    let t0 = Instant::now();
    let trace = std::env::temp_dir().join(format!(
        "stiffwall-tune-table-{}-{}.csv",
        std::process::id(),
        case.name
    ));
    let spec = ConnectSpec::plant_file(&case.path, Pace::Fast).with_trace(Some(trace.clone()));
    let mut client = connect(&spec).with_context(|| {
        format!(
            "connecting to the virtual device of {}",
            case.path.display()
        )
    })?;
    let settings = stiffwall_tune::Settings {
        dry_run: true,
        travel,
        ..stiffwall_tune::Settings::default()
    };
    let o = stiffwall_tune::tune(&mut client, &settings, &Cancel::default(), &mut |_| {});
    drop(client);
    let used = traced_range(&trace);
    let _ = std::fs::remove_file(&trace);
    let o = o.context("tune failed")?;
    let seconds = t0.elapsed().as_secs_f64();
    let window = o.workspace.map(|w| {
        let [lo, hi] = w.ends_si();
        (lo, hi, w.source)
    });
    Ok(Tuned {
        k_set: o.k_set,
        b_set: o.b_set,
        deadband_counts: deadband_of(&o.damper)?,
        damper: o.damper,
        rests: o.rests,
        quiet_ceiling: o.quiet_ceiling,
        mass: o.identified.mass[0],
        viscous: o.identified.viscous[0],
        coulomb: o.identified.coulomb[0],
        mismatch: Some(o.model_mismatch),
        seconds,
        travel_used: used?,
        xidot: o.xidot,
        window,
    })
}

/// The least and largest position of a `--trace` file (`t_s,position_m,…`), m (rad), and
/// whether any tick had an end-stop force.
fn traced_range(path: &Path) -> Result<([f64; 2], bool)> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading the trace {}", path.display()))?;
    let mut range = [f64::INFINITY, f64::NEG_INFINITY];
    let mut contact = false;
    for line in text.lines().skip(1) {
        let mut cells = line.split(',');
        let x: f64 = cells
            .nth(1)
            .and_then(|v| v.parse().ok())
            .unwrap_or(f64::NAN);
        let stop: f64 = cells.nth(1).and_then(|v| v.parse().ok()).unwrap_or(0.0);
        range = [range[0].min(x), range[1].max(x)];
        contact |= stop != 0.0;
    }
    if !range[0].is_finite() {
        bail!("the trace {} has no rows", path.display());
    }
    Ok((range, contact))
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
