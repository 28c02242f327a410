//! `hostctl profile check` (issue 43): every example of `profiles/` passes on each device of
//! its `checked_for` with a fresh `--fast` dry-run tune (`too-strong-detent.toml`, the example
//! of a refusal, fails there naming the element and its limit, exit 1); a saved tune
//! (`--tune-json`) gives the same verdict; bad files are refused before any test, naming the
//! element, the field and the range (exit 2).

#[path = "support/cli.rs"]
mod cli;
use cli::hostctl;
use std::path::PathBuf;

fn profiles() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../profiles")
}

/// The `checked_for` list of a profile file (read as TOML by hand: one line).
fn checked_for(text: &str) -> Vec<String> {
    let line = text
        .lines()
        .find(|l| l.starts_with("checked_for"))
        .expect("checked_for");
    line.split('"')
        .skip(1)
        .step_by(2)
        .map(str::to_owned)
        .collect()
}

/// The connection flags of a `checked_for` entry: a preset or a plant file.
fn target(entry: &str) -> Vec<String> {
    if entry.ends_with(".toml") {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(entry);
        vec!["--plant".into(), path.display().to_string()]
    } else {
        vec!["--device".into(), entry.into()]
    }
}

#[test]
fn every_example_passes_on_its_devices_and_the_strong_detent_fails() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(profiles())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 5, "{files:?}");
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let devices = checked_for(&text);
        assert!(!devices.is_empty(), "{}: checked_for", f.display());
        let refused = f.ends_with("too-strong-detent.toml");
        for d in devices {
            let mut args = vec![
                "profile".to_owned(),
                "check".into(),
                f.display().to_string(),
            ];
            args.extend(target(&d));
            args.push("--json".into());
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let o = hostctl(&args);
            let out = String::from_utf8_lossy(&o.stdout);
            let err = String::from_utf8_lossy(&o.stderr);
            let want = if refused { 1 } else { 0 };
            assert_eq!(o.status.code(), Some(want), "{args:?}\n{out}\n{err}");
            let j = cli::json(&out);
            assert_eq!(j["check"]["pass"], !refused, "{args:?}\n{out}");
            for e in j["check"]["elements"].as_array().unwrap() {
                if !refused {
                    // The margin the examples keep: K at most ~80 % of the limit.
                    let m = e["margin"].as_f64().unwrap_or(f64::INFINITY);
                    assert!(m >= 1.2, "{}: {e}", f.display());
                }
            }
            // A saved tune gives the same verdict.
            let tune = std::env::temp_dir().join(format!(
                "profile-check-{}-{}.json",
                std::process::id(),
                d.replace('/', "_")
            ));
            std::fs::write(&tune, j["tune"].to_string()).unwrap();
            let o = hostctl(&[
                "profile",
                "check",
                &f.display().to_string(),
                "--tune-json",
                &tune.display().to_string(),
            ]);
            assert_eq!(o.status.code(), Some(want), "{}", f.display());
            let _ = std::fs::remove_file(tune);
        }
    }
}

#[test]
fn the_strong_detent_names_its_element_and_limit() {
    let f = profiles().join("too-strong-detent.toml");
    let o = hostctl(&[
        "profile",
        "check",
        &f.display().to_string(),
        "--device",
        "maxon-re35",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("verdict: FAIL (element 1 (detents))"), "{out}");
    assert!(
        out.contains("FAIL: K = 7.680 N·m/rad is above its limit"),
        "{out}"
    );
    assert!(out.contains("strongest that passes: strength = "), "{out}");
}

/// Writes `body` as a profile file and runs the check on maxon-re35 (refused before the tune).
fn refused(name: &str, body: &str) -> String {
    let path = std::env::temp_dir().join(format!("profile-{}-{name}.toml", std::process::id()));
    let text = format!("[profile]\nname = \"{name}\"\naxis = \"rotary\"\n{body}");
    std::fs::write(&path, text).unwrap();
    let err = cli::fails(&[
        "profile",
        "check",
        &path.display().to_string(),
        "--device",
        "maxon-re35",
    ]);
    let _ = std::fs::remove_file(path);
    assert!(
        !err.contains("tune (dry run)"),
        "refused after a tune: {err}"
    );
    err
}

#[test]
fn bad_files_are_refused_with_the_field_and_range() {
    let spring = "[[element]]\nkind = \"spring\"\ncenter = 0\nstiffness = 0.5\n";
    let err = refused("nan", &spring.replace("0.5", "nan"));
    assert!(
        err.contains("element 1 (spring): `stiffness` must be finite and in [1e-6, 1e8] N/m (N·m/rad on a rotary device) (got NaN)"),
        "{err}"
    );
    let err = refused("key", &format!("{spring}stifness = 1\n"));
    assert!(
        err.contains("element 1 (spring): unknown field `stifness`"),
        "{err}"
    );
    let det = |first: f64| {
        format!("[[element]]\nkind = \"detents\"\nfirst = {first}\nper_rev = 24\ncount = 3\nstrength = 0.1\n")
    };
    let err = refused("overlap", &format!("{}{}", det(0.0), det(0.5)));
    assert!(
        err.contains("element 1 (detents) and element 2 (detents): two detent trains overlap"),
        "{err}"
    );
    let walls: String = (0..17)
        .map(|i| {
            format!(
                "[[element]]\nkind = \"viscous\"\nfrom = {i}\nto = {}\ndamping = 0.001\n",
                i + 1
            )
        })
        .collect();
    let err = refused("many", &walls);
    assert!(err.contains("lowers to 17 elements"), "{err}");
    assert!(err.contains("at most 16"), "{err}");
}
