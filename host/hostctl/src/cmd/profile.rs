//! `hostctl profile check FILE`: checks a haptic profile file (`profiles/README.md`) against
//! what a tune verified on a device: a tune result (`--tune-json`, the output of `hostctl tune
//! --json`) or a fresh dry-run tune on the device the connection flags name (the built-in
//! virtual device runs fast). `hostctl profile load FILE` checks it the same way on the
//! connected device and loads it (`SetProfile`; `--save` persists it with the config), refusing
//! a failing profile unless `--force`; `profile show` prints the device's active profile and
//! `profile clear` returns it to the config's single wall. The file format, the lowering and
//! the check are `stiffwall_tune::profile`'s; this parses flags and prints.
//!
//! Exit codes: 0 every element passes (and, for `load`, the profile is loaded), 1 the check
//! fails (nothing loaded without `--force`), 2 the file, the flags, the tune or the device
//! refused (as every hostctl command's errors).
//!
//! Shared with the commands that take a profile file: [`prepare`] (read, lowered for a
//! connected device and checked against `--tune-json`: `hostctl ui --profile` and `hostctl
//! virtual --profile`) and [`lower_for_spec`] (lowered for a virtual device's plant: `profile
//! simulate` and `hostctl simulate SCENE --profile`).

use crate::device::connect::ConnectArgs;
use crate::output::{emit, emit_json};
use anyhow::{anyhow, bail, Context as _, Result};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use stiffwall_proto::DeviceInfo;
use stiffwall_tune::profile::{
    self, units::sig, Device, ElementCheck, Envelope, Lowered, ProfileFile, Report,
};
use stiffwall_tune::{Outcome, Settings, TuneError};

/// Arguments of `hostctl profile`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    pub command: Command,
}

/// `hostctl profile` subcommands.
#[derive(Debug, clap::Subcommand)]
pub enum Command {
    /// Check a profile file against a device's verified stiffness (a tune's result).
    Check(CheckArgs),
    /// Check a profile file on the connected device and load it (refused when it fails,
    /// unless --force).
    Load(LoadArgs),
    /// Simulate the profile on the built-in virtual device (--device or --plant): the
    /// firmware's servo against the plant, a release and an impact at every element.
    Simulate(SimulateArgs),
    /// Print the device's active profile.
    Show(ConnectArgs),
    /// Return the device to the config's single wall (an empty profile; --save persists it).
    Clear(ClearArgs),
}

/// Arguments of `hostctl profile load`.
#[derive(Debug, clap::Args)]
pub struct LoadArgs {
    #[command(flatten)]
    pub check: CheckArgs,
    /// Load a profile that fails the check, listing the elements expected to chatter or grow.
    #[arg(long)]
    pub force: bool,
    /// Also save the config and the profile on the device (SaveConfig), so it renders the
    /// profile after a reboot.
    #[arg(long)]
    pub save: bool,
}

/// Arguments of `hostctl profile simulate`.
#[derive(Debug, clap::Args)]
pub struct SimulateArgs {
    /// The profile file (TOML; profiles/README.md).
    pub file: PathBuf,
    #[command(flatten)]
    pub connect: ConnectArgs,
    /// Impact speed, m/s (rad/s), > 0 (default: 5 counts per servo period, tune's default).
    #[arg(long, value_name = "V")]
    pub velocity: Option<f64>,
    /// Write every run's counts as CSV (`start,tick,count`).
    #[arg(long, value_name = "FILE.csv")]
    pub out: Option<PathBuf>,
}

/// Arguments of `hostctl profile clear`.
#[derive(Debug, clap::Args)]
pub struct ClearArgs {
    #[command(flatten)]
    pub connect: ConnectArgs,
    /// Also save (SaveConfig), so the device boots with its config's wall.
    #[arg(long)]
    pub save: bool,
}

/// Arguments of `hostctl profile check`.
#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// The profile file (TOML; profiles/README.md).
    pub file: PathBuf,
    /// A tune result: the output of `hostctl tune --json` (its `tune` object), or the bare
    /// object. Without it, a dry-run tune runs on the device first.
    #[arg(long, value_name = "TUNE.json", conflicts_with_all = ["port", "device", "plant", "qemu", "board_emulator"])]
    pub tune_json: Option<PathBuf>,
    #[command(flatten)]
    pub connect: ConnectArgs,
    /// Print the report as JSON (with a fresh tune, its result under `tune`).
    #[arg(long)]
    pub json: bool,
}

/// Runs `hostctl profile`, with its own exit codes (module header).
pub fn main(a: &Args) -> ExitCode {
    let result = match a.command {
        Command::Check(ref c) => check(c),
        Command::Load(ref l) => load(l),
        Command::Simulate(ref a) => simulate(a),
        Command::Show(ref c) => show(c).map(|()| true),
        Command::Clear(ref c) => clear(c).map(|()| true),
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {}", crate::cli_error::message(&e));
            ExitCode::from(2)
        }
    }
}

/// `profile load`: the check on the connected device, then `SetProfile` (and `SaveConfig`
/// with `--save`); whether the check passed.
///
/// # Errors
/// The file refused, the tune failed, the device refused the profile or the save.
pub fn load(a: &LoadArgs) -> Result<bool> {
    let c = &a.check;
    let file = read_file(&c.file)?;
    let mut client = connect_for(c)?;
    let device = Device::of_info(&client.info);
    let lowered =
        profile::lower(&file, &device).map_err(|e| anyhow!("{}: {e}", c.file.display()))?;
    let envelope = match &c.tune_json {
        Some(path) => envelope_of_file(path)?.with_force_limit(force_limit(&client.info)),
        None => tune_on(&mut client, c.connect.describe())?.0,
    };
    let report = profile::check(&lowered, &envelope);
    emit(&profile::render(&report))?;
    if !report.pass && !a.force {
        eprintln!(
            "not loaded: the profile fails the check (the device renders what it had);              --force loads it anyway"
        );
        return Ok(false);
    }
    if !report.pass {
        for e in report.elements.iter().filter(|e| !e.pass) {
            eprintln!(
                "loading anyway (--force): element {} ({}) is expected to chatter or grow",
                e.index, e.kind
            );
        }
    }
    let wire = lowered.wire();
    client.set_profile(&wire)?;
    anyhow::ensure!(
        client.get_profile()? == wire,
        "the device's active profile differs from the one sent"
    );
    if a.save {
        client.save_config()?;
    }
    let saved = if a.save {
        ", saved"
    } else {
        " (not saved: --save keeps it over a reboot)"
    };
    eprintln!(
        "profile {} loaded on {}{saved}",
        lowered.name,
        c.connect.describe()
    );
    Ok(report.pass)
}

/// `profile simulate`: every start's run and where it came to rest; whether every run rests
/// where the profile holds the device (at a detent's minimum, against a wall, or outside any
/// detent train).
///
/// # Errors
/// Not the built-in virtual device, a bad file or velocity, the device refused the profile,
/// the CSV unwritable.
pub fn simulate(a: &SimulateArgs) -> Result<bool> {
    use stiffwall_analysis::profile_run::{run_start, starts};
    let file = read_file(&a.file)?;
    let spec = a.connect.spec()?.virtual_spec()?.ok_or_else(|| {
        anyhow!("profile simulate runs the built-in virtual device: give --device NAME or --plant FILE.toml")
    })?;
    let p = &spec.plant;
    let (wire, device) = lower_for_spec(&file, &a.file, &spec)?;
    let v = a.velocity.unwrap_or(5.0 * p.resolution / p.period_s);
    anyhow::ensure!(
        v.is_finite() && v > 0.0,
        "--velocity {v}: allowed range is > 0"
    );
    let mut csv = String::from("start,tick,count\n");
    let (mut good, all) = (0, starts(&wire, p.resolution, v, 10));
    for (i, st) in all.iter().enumerate() {
        let (r, natural) = run_start(&spec, &wire, st)?;
        let (verdict, holds) = rest_verdict(&wire, &r, natural, &device);
        good += usize::from(holds);
        println!("{}: {verdict}", st.label);
        for (t, c) in r.counts.iter().enumerate() {
            csv.push_str(&format!("{i},{t},{c}\n"));
        }
    }
    println!(
        "{good} of {} runs come to rest where the profile holds the device",
        all.len()
    );
    if let Some(out) = &a.out {
        std::fs::write(out, csv).with_context(|| format!("writing {}", out.display()))?;
    }
    Ok(good == all.len())
}

/// How run `r` of `wire` on `device` ended, in words ("rests at count n (x m): minimum j of
/// element i", "does not come to rest (last counts span s)", "fault 0x…"; `natural` is the
/// rest rule's natural period, ticks), and whether it rests where the profile holds the device:
/// no fault, at rest, and not inside a detent train at no minimum.
pub(crate) fn rest_verdict(
    wire: &stiffwall_proto::Profile,
    r: &stiffwall_analysis::profile_run::Run,
    natural: f64,
    device: &Device,
) -> (String, bool) {
    use stiffwall_analysis::profile_run::{rest_place, RestPlace};
    let n = r.final_count();
    let place = rest_place(wire, n);
    let at = format!(
        "count {n} ({} {})",
        sig(n as f64 * device.resolution),
        device.units().position
    );
    let verdict = match (r.faults, r.rests, place) {
        (f, _, _) if f != 0 => format!("fault {f:#x}"),
        (_, false, _) => format!(
            "does not come to rest (last counts span {})",
            r.final_span(natural)
        ),
        (_, true, RestPlace::OffDetent { element }) => format!(
            "rests at {at}, inside detent train {} at no minimum",
            element + 1
        ),
        (_, true, RestPlace::Detent { element, minimum }) => format!(
            "rests at {at}: minimum {minimum} of element {}",
            element + 1
        ),
        (_, true, RestPlace::Wall { element }) => {
            format!("rests at {at}: against the wall, element {}", element + 1)
        }
        (_, true, RestPlace::Elsewhere) => format!("rests at {at}"),
    };
    let holds = r.faults == 0 && r.rests && !matches!(place, RestPlace::OffDetent { .. });
    (verdict, holds)
}

/// `profile show`: the device's active profile.
///
/// # Errors
/// The connection or the request failed.
pub fn show(c: &ConnectArgs) -> Result<()> {
    let mut client = c.connect()?;
    let device = Device::of_info(&client.info);
    let p = client.get_profile()?;
    Ok(emit(&profile::render_wire(&p, &device))?)
}

/// `profile clear`: an empty profile (the config's wall), saved with `--save`.
///
/// # Errors
/// The connection, the request or the save failed.
pub fn clear(c: &ClearArgs) -> Result<()> {
    let mut client = c.connect.connect()?;
    client.set_profile(&stiffwall_proto::Profile::default())?;
    if c.save {
        client.save_config()?;
    }
    eprintln!("profile cleared: the device renders its config's wall");
    Ok(())
}

/// `profile check`: whether every element passes.
///
/// # Errors
/// The file unreadable or refused, the tune JSON unreadable, the tune failed.
pub fn check(a: &CheckArgs) -> Result<bool> {
    let named = |e: profile::ProfileError| anyhow!("{}: {e}", a.file.display());
    let file = read_file(&a.file)?;
    let (envelope, outcome) = match &a.tune_json {
        Some(path) => (envelope_of_file(path)?, None),
        None => {
            let (envelope, o) = fresh_tune(a, &file)?;
            (envelope, Some(o))
        }
    };
    let lowered = profile::lower(&file, &envelope.device).map_err(named)?;
    let report = profile::check(&lowered, &envelope);
    if a.json {
        let mut j = serde_json::json!({
            "file": a.file,
            "target": envelope.source,
            "check": report,
        });
        if let Some(o) = outcome {
            j["tune"] = serde_json::to_value(o)?;
        }
        emit_json(&j)?;
    } else {
        emit(&profile::render(&report))?;
    }
    Ok(report.pass)
}

/// `file` (read from `path`) lowered for the virtual device of `spec` (its axis and
/// resolution), as `profile simulate` and `simulate SCENE --profile` run it; the device it was
/// lowered for. A file of the other axis is refused with the library's message.
///
/// # Errors
/// The library's refusal (element, key, range), with the file's name.
pub(crate) fn lower_for_spec(
    file: &ProfileFile,
    path: &Path,
    spec: &stiffwall_client::VirtualSpec,
) -> Result<(stiffwall_proto::Profile, Device)> {
    let device = Device {
        rotational: spec.plant.rotational,
        resolution: spec.plant.resolution,
    };
    let wire = profile::lower(file, &device)
        .map_err(|e| anyhow!("{}: {e}", path.display()))?
        .wire();
    Ok((wire, device))
}

/// The profile file at `path`, parsed (its name in the error).
pub(crate) fn read_file(path: &Path) -> Result<ProfileFile> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    ProfileFile::from_toml(&text).map_err(|e| anyhow!("{}: {e}", path.display()))
}

/// The envelope of a saved tune result (the live view's `--tune-json` too).
pub(crate) fn envelope_of_file(path: &Path) -> Result<Envelope> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut v: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("--tune-json {}: not JSON", path.display()))?;
    let target = v["target"].as_str().map(str::to_owned);
    let tune = match v.get_mut("tune") {
        Some(t) => t.take(),
        None => v,
    };
    let o: Outcome = serde_json::from_value(tune).with_context(|| {
        format!(
            "--tune-json {}: not a tune result (the output of `hostctl tune --json`, or its \
             `tune` object)",
            path.display()
        )
    })?;
    Ok(Envelope::from_outcome(
        &o,
        target.unwrap_or_else(|| path.display().to_string()),
    ))
}

/// The device of the connection flags (the built-in virtual device fast).
fn connect_for(a: &CheckArgs) -> Result<stiffwall_client::Client> {
    let mut connect = a.connect.clone();
    if connect.port.is_none() && !connect.qemu && !connect.board_emulator {
        connect.fast = true;
    }
    connect.connect()
}

/// A dry-run tune on the device of the connection flags (the virtual device fast), as
/// `hostctl tune --dry-run` runs it; the file is lowered for the device first, so a bad file
/// is refused before any test.
fn fresh_tune(a: &CheckArgs, file: &ProfileFile) -> Result<(Envelope, Outcome)> {
    let mut client = connect_for(a)?;
    let device = Device::of_info(&client.info);
    profile::lower(file, &device).map_err(|e| anyhow!("{}: {e}", a.file.display()))?;
    tune_on(&mut client, a.connect.describe())
}

/// A dry-run tune on `client` (its summary on stderr) and its envelope, named `name`.
fn tune_on(client: &mut stiffwall_client::Client, name: String) -> Result<(Envelope, Outcome)> {
    crate::session::stop_on_ctrl_c();
    let cancel = stiffwall_client::Cancel::on_ctrl_c();
    let settings = Settings {
        dry_run: true,
        ..Settings::default()
    };
    let o = stiffwall_tune::tune(client, &settings, &cancel, &mut |e| {
        eprintln!("tune: {e}");
    })
    .map_err(|e| match e {
        TuneError::Cancelled => anyhow!("interrupted; the device's config was left as it was"),
        e => anyhow!("tune failed: {e}"),
    })?;
    let u = profile::Units::of(o.params.rotational);
    let sig = profile::units::sig;
    eprintln!(
        "tune (dry run) on {name}: K = {} {} at B = {} {} ({}), margin ×{}, quiet ceiling {} {}",
        sig(o.k_set),
        u.stiffness,
        sig(o.b_set),
        u.damping,
        o.damper,
        sig(o.margin_used),
        sig(o.quiet_ceiling),
        u.stiffness
    );
    let envelope = Envelope::from_outcome(&o, name).with_force_limit(force_limit(&client.info));
    Ok((envelope, o))
}

/// The device's largest force, N (N·m): its largest output code × force per code (the most a
/// detent's strength may be; the firmware refuses more).
pub(crate) fn force_limit(info: &stiffwall_proto::DeviceInfo) -> f64 {
    f64::from(info.max_code) * f64::from(info.force_per_code)
}

/// A profile file loaded at start (`hostctl ui --profile`, `hostctl virtual --profile`), with
/// its check.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The file, as given.
    pub file: PathBuf,
    /// Lowered for the connected device.
    pub lowered: Lowered,
    /// The check against `--tune-json`, when given.
    pub report: Option<Report>,
}

/// Where an element of a check is, as the profile library's errors name it.
fn place(e: &ElementCheck) -> String {
    match e.part {
        Some(p) => format!("element {} ({}, {p} wall)", e.index, e.kind),
        None => format!("element {} ({})", e.index, e.kind),
    }
}

/// What fails in `report`, one line per failing element.
#[must_use]
pub fn failures(report: &Report) -> Vec<String> {
    report
        .elements
        .iter()
        .filter(|e| !e.pass)
        .map(|e| format!("{} at {}: {}", place(e), e.at, e.problems.join("; ")))
        .collect()
}

/// Reads `file`, lowers it for `info`'s device and checks it against `tune_json` (when given).
///
/// # Errors
/// The file unreadable or refused (the library's message: element, field, range), the tune
/// result unreadable or of another device, or the check fails and `force` is not set. Nothing
/// has been loaded onto the device then.
pub fn prepare(
    file: &Path,
    tune_json: Option<&Path>,
    force: bool,
    info: &DeviceInfo,
) -> Result<Loaded> {
    let text = std::fs::read_to_string(file)
        .with_context(|| format!("--profile: reading {}", file.display()))?;
    let named = |e: profile::ProfileError| {
        anyhow!(
            "--profile {}: {e}; nothing was loaded onto the device",
            file.display()
        )
    };
    let parsed = ProfileFile::from_toml(&text).map_err(named)?;
    let device = Device::of_info(info);
    let lowered = profile::lower(&parsed, &device).map_err(named)?;
    let report = match tune_json {
        None => None,
        Some(path) => {
            let envelope = envelope_of_file(path)?.with_force_limit(force_limit(info));
            same_device(path, &envelope.device, &device)?;
            let report = profile::check(&lowered, &envelope);
            if !report.pass {
                let what = failures(&report).join("\n  ");
                if force {
                    eprintln!(
                        "warning: --profile {} fails the check against {}; loaded anyway \
                         (--force-profile):\n  {what}",
                        file.display(),
                        envelope.source
                    );
                } else {
                    bail!(
                        "--profile {} fails the check against {}:\n  {what}\nnothing was loaded \
                         onto the device (--force-profile loads it anyway)",
                        file.display(),
                        envelope.source
                    );
                }
            }
            Some(report)
        }
    };
    Ok(Loaded {
        file: file.to_path_buf(),
        lowered,
        report,
    })
}

/// Refuses a tune result (`--tune-json path`, measured on `tuned`) of another device than
/// `device` (axis, or resolution beyond 1 ppm).
fn same_device(path: &Path, tuned: &Device, device: &Device) -> Result<()> {
    let axis = |d: &Device| if d.rotational { "rotary" } else { "linear" };
    let same = tuned.rotational == device.rotational
        && (tuned.resolution - device.resolution).abs() <= 1e-6 * device.resolution;
    if !same {
        bail!(
            "--tune-json {} was measured on another device ({}, Δ = {} {}) than the one \
             connected ({}, Δ = {} {}); nothing was loaded onto the device",
            path.display(),
            axis(tuned),
            sig(tuned.resolution),
            tuned.units().position,
            axis(device),
            sig(device.resolution),
            device.units().position,
        );
    }
    Ok(())
}
