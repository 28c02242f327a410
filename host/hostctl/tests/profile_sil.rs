//! The proof of issue 43 (item 4), software in the loop: every example profile in `profiles/`
//! runs on every device it was checked for (`[profile] checked_for`), rendered by the
//! firmware's own servo (`stiffwall_analysis::profile_run`) against the virtual device's plant,
//! from a release and an impact at each element; by the simulator alone every run comes to rest
//! (the project's rest rule) without a fault, a run that ends inside a detent train rests
//! within one count of one of its minima (or against a wall at the train's end), and a release beside a detent rests at that detent.
//! The profile the check refuses (`too-strong-detent.toml`) does not rest at its minima: the
//! check's refusal is not merely conservative.

#[path = "support/cli.rs"]
mod cli;

use std::path::{Path, PathBuf};
use stiffwall_analysis::profile_run::{
    detent_minima, rest_place, run_start, starts, within_one_count, RestPlace, Run, Start,
};
use stiffwall_client::{ConnectSpec, Pace, VirtualSpec};
use stiffwall_proto::Profile;
use stiffwall_tune::profile::{lower, Device, ProfileFile};

/// The repository's root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The example profiles, by file name.
fn examples() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("profiles"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    v.sort();
    assert!(v.len() >= 4, "{v:?}");
    v
}

/// The virtual device of a `checked_for` entry: a preset's name or a plant file's path.
fn device(entry: &str) -> VirtualSpec {
    let spec = if entry.ends_with(".toml") {
        ConnectSpec::plant_file(root().join(entry), Pace::Fast)
    } else {
        ConnectSpec::preset(entry, Pace::Fast)
    };
    spec.virtual_spec().unwrap().unwrap()
}

/// The file's profile lowered for `spec`'s device.
fn lowered(path: &Path, spec: &VirtualSpec) -> (ProfileFile, Profile) {
    let file = ProfileFile::from_toml(&std::fs::read_to_string(path).unwrap()).unwrap();
    let dev = Device {
        rotational: spec.plant.rotational,
        resolution: spec.plant.resolution,
    };
    let wire = lower(&file, &dev).unwrap().wire();
    (file, wire)
}

/// Every start of `profile` on `spec` (`run_start`: at least 60 natural periods of its
/// element), with the impact speed tune's default: 5 counts per servo period.
fn run_all(spec: &VirtualSpec, profile: &Profile) -> Vec<(Start, Run, f64)> {
    let p = &spec.plant;
    let v = 5.0 * p.resolution / p.period_s;
    starts(profile, p.resolution, v, 10)
        .into_iter()
        .map(|st| {
            let (r, natural) = run_start(spec, profile, &st).unwrap();
            (st, r, natural)
        })
        .collect()
}

/// The detent a start named "release … detent J" was released beside, and its minimum.
fn released_beside(st: &Start, profile: &Profile) -> Option<f64> {
    let j: usize = st
        .label
        .strip_prefix("element ")?
        .rsplit("detent ")
        .next()?
        .parse()
        .ok()?;
    detent_minima(&profile.elements[st.element]).get(j).copied()
}

#[test]
fn every_example_comes_to_rest_at_every_element_on_every_device_it_was_checked_for() {
    let mut runs = 0;
    for path in examples() {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name == "too-strong-detent.toml" {
            continue;
        }
        let file = ProfileFile::from_toml(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert!(
            !file.header.checked_for.is_empty(),
            "{name}: checked_for names no device"
        );
        for entry in &file.header.checked_for {
            let spec = device(entry);
            let (_, profile) = lowered(&path, &spec);
            for (st, r, natural) in run_all(&spec, &profile) {
                let at = format!("{name} on {entry}: {}", st.label);
                assert_eq!(r.faults, 0, "{at}: fault {:#x}", r.faults);
                assert!(
                    r.rests,
                    "{at}: does not come to rest (last counts span {})",
                    r.final_span(natural)
                );
                let n = r.final_count();
                assert!(
                    !matches!(rest_place(&profile, n), RestPlace::OffDetent { .. }),
                    "{at}: rests at count {n} inside a detent train, not within one count of a minimum"
                );
                if let Some(m) = released_beside(&st, &profile) {
                    assert!(
                        within_one_count(n, m),
                        "{at}: rests at count {n}, not at its detent's minimum {m:.2}"
                    );
                }
                runs += 1;
            }
        }
    }
    assert!(runs >= 40, "only {runs} runs");
}

#[test]
fn the_refused_detent_does_not_rest_at_its_minima() {
    let path = root().join("profiles/too-strong-detent.toml");
    let spec = device("maxon-re35");
    let (_, profile) = lowered(&path, &spec);
    let all = run_all(&spec, &profile);
    let at_rest_at_a_minimum = all
        .iter()
        .filter(|(_, r, _)| {
            r.rests
                && matches!(
                    rest_place(&profile, r.final_count()),
                    RestPlace::Detent { .. }
                )
        })
        .count();
    assert_eq!(
        at_rest_at_a_minimum,
        0,
        "{at_rest_at_a_minimum} of {} runs of the refused detent rest at a minimum",
        all.len()
    );
}

/// `hostctl profile simulate` is the same proof from the command line: the knob's 32 starts
/// (13 detents × 2 releases, 2 impacts across the train, 2 starts at each of its 2 end stops)
/// all rest where it holds the device (exit 0); the refused detent's rest nowhere (exit 1).
#[test]
fn profile_simulate_prints_where_each_run_rests() {
    let knob = root().join("profiles/knob-24-detents.toml");
    let out = cli::ok(&[
        "profile",
        "simulate",
        &knob.display().to_string(),
        "--device",
        "maxon-re35",
    ]);
    assert!(
        out.contains("32 of 32 runs come to rest where the profile holds the device"),
        "{out}"
    );
    assert!(out.contains("element 1 (detents): release ¼ pitch above detent 3: rests at count"));
    let strong = root().join("profiles/too-strong-detent.toml");
    let o = cli::hostctl(&[
        "profile",
        "simulate",
        &strong.display().to_string(),
        "--device",
        "maxon-re35",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("0 of 10 runs"), "{out}");
}
