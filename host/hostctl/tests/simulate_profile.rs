//! A haptic profile in `hostctl simulate SCENE --profile` and `hostctl virtual --profile` (the
//! real binary): a physical scene's plant renders the profile with the firmware's servo and
//! comes to rest at the spring's centre (computed from the profile file); a dimensionless scene,
//! a profile of the other axis and a run the profile does not hold are refused or fail; the
//! served virtual device starts with the profile loaded (its `GetProfile`, read back by `hostctl
//! profile show`), and one that fails its check against a tune serves nothing.

#[path = "support/cli.rs"]
mod cli;
#[path = "support/served.rs"]
mod served;
use cli::{fails, hostctl, ok};
use served::Served;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use stiffwall_proto::ProfileElement;
use stiffwall_tune::profile::{self, Device, ProfileFile};

fn repo(path: &str) -> String {
    format!("{}/../../{path}", env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("stiffwall-simulate-profile-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Phantom 1.0 of Table II in SI units (the exact solver), released 5 mm from the origin at
/// 2 cm/s, for `PERIODS` servo ticks.
const RESOLUTION_M: f64 = 29.1e-6;
const COULOMB_N: f64 = 0.038;
const START_M: f64 = 0.005;
const PERIODS: usize = 3000;

fn scene() -> String {
    let text = format!(
        "[device]\nmass_kg = 0.072\nviscous_ns_per_m = 0.005\ncoulomb_n = {COULOMB_N}\n\
         resolution_m = {RESOLUTION_M:e}\n\n[controller]\nstiffness_n_per_m = 1015.0\n\
         period_s = 1e-3\nextra_delay_s = 0.0\n\n[effects]\nzoh = true\nquantization = true\n\
         coulomb = true\nviscous = true\ndelay = true\none_sided_wall = false\n\
         amplifier = {{ kind = \"none\" }}\nhand = {{ kind = \"none\" }}\n\n[initial]\n\
         position_m = {START_M}\nvelocity_m_per_s = 0.02\n\n[run]\nperiods = {PERIODS}\n\
         solver = {{ kind = \"exact\" }}\n"
    );
    let path = temp_dir().join("phantom-release.toml");
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

/// The profile file at `path` lowered for `device` (as the commands lower it).
fn lowered(path: &str, device: &Device) -> stiffwall_proto::Profile {
    let file = ProfileFile::from_toml(&std::fs::read_to_string(path).unwrap()).unwrap();
    profile::lower(&file, device).unwrap().wire()
}

#[test]
fn a_centring_profile_on_a_physical_scene_rests_at_its_centre() {
    let file = repo("profiles/centring-viscous-linear.toml");
    let wire = lowered(
        &file,
        &Device {
            rotational: false,
            resolution: RESOLUTION_M,
        },
    );
    let (centre, k) = wire
        .elements
        .iter()
        .find_map(|e| match *e {
            ProfileElement::Spring {
                center, stiffness, ..
            } => Some((i64::from(center), f64::from(stiffness))),
            _ => None,
        })
        .expect("the profile has a spring");
    let o = hostctl(&["simulate", &scene(), "--profile", &file]);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{err}");
    let mut lines = out.lines();
    assert_eq!(lines.next(), Some("tick,t_s,count,position,velocity,force"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|f| f.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), PERIODS, "one row per tick");
    let count = |r: &[f64]| r[2] as i64;
    // It starts where the scene says, far from the centre, and the count is the position's.
    let first = count(&rows[0]);
    assert_eq!(first, (START_M / RESOLUTION_M).floor() as i64);
    for r in &rows {
        assert_eq!(count(r), (r[3] / RESOLUTION_M).floor() as i64, "{r:?}");
    }
    // The spring F = −KΔ(n − c + ½) is held by Coulomb friction within c/(KΔ) counts of c − ½.
    let band = (COULOMB_N / (k * RESOLUTION_M)).ceil() as i64 + 1;
    assert!((first - centre).abs() > 10 * band);
    let last = count(rows.last().unwrap());
    assert!(
        (last - centre).abs() <= band,
        "rests at count {last}, the spring's centre is {centre} (±{band})"
    );
    // At rest over the last quarter, as the summary says.
    assert!(rows[PERIODS * 3 / 4..].iter().all(|r| count(r) == last));
    assert!(err.contains(&format!("rests at count {last}")), "{err}");
    assert!(err.contains("faults: none"), "{err}");
}

#[test]
fn a_run_the_profile_does_not_hold_fails_after_its_rows() {
    // A spring far above the plant's quiet ceiling 2c/Δ ≈ 2600 N/m: the count never settles.
    let stiff = temp_dir().join("stiff-spring.toml");
    std::fs::write(
        &stiff,
        "[profile]\nname = \"stiff\"\naxis = \"linear\"\n\n[[element]]\nkind = \"spring\"\n\
         center = 0.0\nstiffness = 20000\n",
    )
    .unwrap();
    let o = hostctl(&["simulate", &scene(), "--profile", stiff.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("does not come to rest"), "{err}");
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).lines().count(),
        PERIODS + 1
    );
}

#[test]
fn a_dimensionless_scene_or_a_profile_of_the_other_axis_is_refused() {
    let linear = repo("profiles/centring-viscous-linear.toml");
    let err = fails(&[
        "simulate",
        &repo("sim/scenes/base.toml"),
        "--profile",
        &linear,
    ]);
    assert!(
        err.contains("is dimensionless") && err.contains("physical"),
        "{err}"
    );
    let rotary = repo("profiles/knob-24-detents.toml");
    let err = fails(&["simulate", &scene(), "--profile", &rotary]);
    assert!(err.contains("`axis` must be `linear`"), "{err}");
    let err = fails(&[
        "simulate",
        &scene(),
        "--profile",
        &linear,
        "--plot",
        "x.svg",
    ]);
    assert!(err.contains("--plot"), "{err}");
}

/// `hostctl virtual ARGS` that must be refused before serving: exit code 2 and nothing on
/// standard output (no `pty:` line), within a deadline (a served device never exits itself).
fn refused_to_serve(args: &[&str]) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .arg("virtual")
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("hostctl virtual {args:?} is serving");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(String::from_utf8_lossy(&o.stdout), "", "{err}");
    err
}

#[test]
fn the_virtual_device_serves_with_the_profile_loaded() {
    let file = repo("profiles/knob-24-detents.toml");
    let d = Served::with(&["--device", "maxon-re35", "--fast", "--profile", &file]);
    let re35 = stiffwall_core::devices::find("maxon-re35").unwrap();
    let cpr = (core::f64::consts::TAU / re35.params.resolution).round();
    let wire = lowered(
        &file,
        &Device {
            rotational: true,
            resolution: core::f64::consts::TAU / cpr,
        },
    );
    let shown = ok(&d.args(&["profile", "show"]));
    assert!(
        shown.starts_with(&format!("profile: {} elements", wire.elements.len())),
        "{shown}"
    );
    assert!(shown.contains("13 detents from count 0"), "{shown}");
    assert!(
        shown.contains("lower wall at count") && shown.contains("upper wall at count"),
        "{shown}"
    );
    let f = cli::json(&ok(&d.args(&["faults", "--json"])));
    assert_eq!(f["latched"], 0, "{f}");
}

#[test]
fn a_profile_failing_its_check_serves_nothing() {
    let tune = temp_dir().join("re35-tune.json");
    let t = ok(&[
        "tune",
        "--dry-run",
        "--json",
        "--fast",
        "--device",
        "maxon-re35",
    ]);
    std::fs::write(&tune, t).unwrap();
    let tune = tune.to_str().unwrap();
    let strong = repo("profiles/too-strong-detent.toml");
    let base = ["--device", "maxon-re35", "--fast", "--profile", &strong];
    let err = refused_to_serve(&[&base[..], &["--tune-json", tune]].concat());
    assert!(
        err.contains("fails the check") && err.contains("element 1 (detents)"),
        "{err}"
    );
    assert!(err.contains("nothing was loaded"), "{err}");
    // A profile of the other axis is refused as the file is read, with or without a tune.
    let linear = repo("profiles/centring-viscous-linear.toml");
    let err = refused_to_serve(&["--device", "maxon-re35", "--fast", "--profile", &linear]);
    assert!(err.contains("`axis` must be `rotary`"), "{err}");
    // --force-profile serves it.
    let d = Served::with(&[&base[..], &["--tune-json", tune, "--force-profile"]].concat());
    assert!(ok(&d.args(&["profile", "show"])).contains("4 detents"));
}
