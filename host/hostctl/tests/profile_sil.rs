//! The proof of issue 43 (item 4), software in the loop: every example profile in `profiles/`
//! runs on every device it was checked for (`[profile] checked_for`), rendered by the
//! firmware's own servo (`stiffwall_analysis::profile_run`) against the virtual device's plant,
//! from a release and an impact at each element; by the simulator alone every run comes to rest
//! (the project's rest rule) without a fault, a run that ends inside a detent train rests
//! within one count of one of its minima (or against a wall at the train's end), and a release beside a detent rests at that detent.
//! The profile the check refuses (`too-strong-detent.toml`) does not rest at its minima: the
//! check's refusal is not merely conservative.

use std::path::{Path, PathBuf};
use stiffwall_analysis::profile_run::{detent_minima, run, starts, within_one_count, Run, Start};
use stiffwall_client::{ConnectSpec, Pace, VirtualSpec};
use stiffwall_proto::{Profile, ProfileElement};
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

/// The element's stiffest local slope, N/m (N·m/rad): K, or a detent's 2π·A/pitch; 0 for a
/// viscous zone.
fn local_k(e: &ProfileElement, resolution: f64) -> f64 {
    match *e {
        ProfileElement::Wall { stiffness, .. } | ProfileElement::Spring { stiffness, .. } => {
            f64::from(stiffness)
        }
        ProfileElement::Detents {
            strength,
            pitch_counts,
            ..
        } => std::f64::consts::TAU * f64::from(strength) / (pitch_counts * resolution),
        ProfileElement::Viscous { .. } => 0.0,
    }
}

/// Every start of `profile` on `spec`, run for at least 60 natural periods of its element
/// (and 20 000 ticks; a viscous zone, which has none, 20 000), with the impact speed tune's default: 5 counts per servo period.
fn run_all(spec: &VirtualSpec, profile: &Profile) -> Vec<(Start, Run, f64)> {
    let p = &spec.plant;
    let v = 5.0 * p.resolution / p.period_s;
    starts(profile, p.resolution, v, 10)
        .into_iter()
        .map(|st| {
            let k = local_k(&profile.elements[st.element], p.resolution);
            let natural = std::f64::consts::TAU * (p.mass / k).sqrt() / p.period_s;
            let ticks = if natural.is_finite() {
                ((60.0 * natural).ceil() as usize).max(20_000)
            } else {
                20_000
            };
            let r = run(spec, profile, &st, ticks, natural).unwrap();
            (st, r, natural)
        })
        .collect()
}

/// The detent train (its minima) whose active range holds raw count `n`, if any.
fn train_at(profile: &Profile, n: i64) -> Option<Vec<f64>> {
    profile.elements.iter().find_map(|e| match *e {
        ProfileElement::Detents { pitch_counts, .. } => {
            let m = detent_minima(e);
            let lo = m.first()? - pitch_counts / 2.0;
            let hi = m.last()? + pitch_counts / 2.0;
            (lo <= n as f64 + 0.5 && n as f64 + 0.5 < hi).then_some(m)
        }
        _ => None,
    })
}

/// True when raw count `n` is within one count of a wall's surface (a wall's first count in
/// contact, or the free count beside it): at rest against that wall.
fn against_a_wall(profile: &Profile, n: i64) -> bool {
    profile.elements.iter().any(|e| match *e {
        // Either side: counts P − 1 and P hold the surface at P.
        ProfileElement::Wall { position, .. } => {
            (i64::from(position) - 1..=i64::from(position)).contains(&n)
        }
        _ => false,
    })
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
                if let Some(minima) = train_at(&profile, n) {
                    assert!(
                        minima.iter().any(|&m| within_one_count(n, m))
                            || against_a_wall(&profile, n),
                        "{at}: rests at count {n} inside a detent train, not within one count of a minimum"
                    );
                }
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
            let n = r.final_count();
            r.rests
                && train_at(&profile, n).is_some_and(|m| m.iter().any(|&m| within_one_count(n, m)))
        })
        .count();
    assert_eq!(
        at_rest_at_a_minimum,
        0,
        "{at_rest_at_a_minimum} of {} runs of the refused detent rest at a minimum",
        all.len()
    );
}
