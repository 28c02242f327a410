//! Regression tests of issue 11 point 8 (messages) and point 10 (`hostctl virtual`): negative
//! numbers reach the range checks that name their flag, readable numbers in device refusals,
//! `experiment release` on a fresh virtual device, `simulate` divergence and `--every`,
//! `--device` with `--qemu`, unwritable output paths refused before the run, `record
//! --release 0`, and the virtual device served on a pty to another `hostctl`.

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};
use stiffwall_client::{describe_error, readable};
use stiffwall_proto::{ConfigField, ErrorCode, ErrorDetail};

fn hostctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .args(args)
        .output()
        .expect("run hostctl")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("stiffwall-cli-messages-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// A clean refusal (exit 2, no panic, not clap's usage error) whose message contains `want`.
fn refused(args: &[&str], want: &str) -> String {
    let o = hostctl(args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "hostctl {args:?}: {err}");
    assert!(
        !err.contains("unexpected argument"),
        "hostctl {args:?}: {err}"
    );
    assert!(
        err.contains(want),
        "hostctl {args:?}: want {want:?} in {err}"
    );
    err
}

#[test]
fn negative_numbers_reach_the_range_check_of_their_flag() {
    refused(
        &["analyze", "--device", "phantom-1.0", "--period", "-1e-3"],
        "--period must be finite and in [1e-6, 0.1] s (a 10 Hz to 1 MHz servo) (got -0.001)",
    );
    refused(&["map", "--mu", "-1", "--periods", "10"], "--mu -1");
    refused(
        &[
            "experiment",
            "release",
            "--deflection",
            "12",
            "--model",
            "-1",
            "0",
            "0",
        ],
        "--model M B C must be finite, M > 0 kg",
    );
    refused(
        &[
            "experiment",
            "release",
            "--deflection",
            "12",
            "--stiffness",
            "-3",
        ],
        "--stiffness must be finite and > 0 (got -3)",
    );
}

#[test]
fn device_range_errors_print_readable_numbers() {
    let e = describe_error(
        ErrorCode::InvalidConfig,
        &ErrorDetail::Field {
            field: ConfigField::Stiffness,
            min: f64::from(f32::MIN_POSITIVE),
            max: f64::from(85.445_656_f32),
        },
    );
    assert!(e.contains("must be > 0 and ≤ 85.4457"), "{e}");
    assert!(!e.contains("0.0000"), "{e}");
    for (x, want) in [
        (1.175_494_350_822_287_5e-38, "1.18e-38"),
        (85.445_655_822_753_9, "85.4457"),
        (1_048_576.0, "1048576"),
        (0.5, "0.5"),
        (0.0, "0"),
        (-2.5e9, "-2.50e9"),
    ] {
        assert_eq!(readable(x), want);
    }
}

#[test]
fn release_on_a_fresh_virtual_device_says_what_to_do_or_works_with_stiffness() {
    let err = refused(
        &["experiment", "release", "--deflection", "12", "--fast"],
        "wall is off (K = 0)",
    );
    assert!(err.contains("--stiffness"), "{err}");
    let o = hostctl(&[
        "experiment",
        "release",
        "--deflection",
        "12",
        "--stiffness",
        "2",
        "--fast",
        "--json",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(!v["verdict"].is_null(), "{v}");
}

#[test]
fn device_with_qemu_is_an_error_not_ignored() {
    refused(
        &["info", "--qemu", "--device", "phantom-1.0"],
        "cannot be combined with --port or --qemu",
    );
}

#[test]
fn record_release_zero_is_refused_like_experiment_release() {
    let f = tmp("r0.csv");
    let f = f.to_str().unwrap();
    refused(
        &["record", f, "--seconds", "0.1", "--release", "0", "--fast"],
        "--release must be non-zero",
    );
    refused(
        &["experiment", "release", "--deflection", "0", "--fast"],
        "--deflection must be non-zero",
    );
}

const DIVERGING: &str = "[device]\nmu = 0.01\nbeta = 0.0\nsigma = 0.0\n[effects]\nzoh = true\n\
    quantization = false\ncoulomb = false\nviscous = false\ndelay = false\n\
    one_sided_wall = false\namplifier = { kind = \"none\" }\nhand = { kind = \"none\" }\n\
    [initial]\nxi = 0.0\nxidot = 5.0\n[run]\nperiods = 100000\nsolver = { kind = \"exact\" }\n";

#[test]
fn simulate_reports_divergence_and_every_keeps_the_last_row() {
    let scene = tmp("diverging.toml");
    std::fs::write(&scene, DIVERGING).unwrap();
    let csv = tmp("diverging.csv");
    let o = hostctl(&[
        "simulate",
        scene.to_str().unwrap(),
        "--out",
        csv.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("diverged at period"), "{err}");
    assert!(std::fs::read_to_string(&csv).unwrap().lines().count() > 2);

    // --every 7 on a 100-period run: rows 0, 7, ..., 98 and the last one, 100.
    let base = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../sim/scenes/base.toml");
    let text = std::fs::read_to_string(&base).unwrap();
    let short = tmp("short.toml");
    std::fs::write(
        &short,
        text.replace(
            &text[text.find("periods = ").unwrap()..]
                .lines()
                .next()
                .unwrap()
                .to_string(),
            "periods = 100",
        ),
    )
    .unwrap();
    let o = hostctl(&["simulate", short.to_str().unwrap(), "--every", "7"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    let periods: Vec<u64> = out
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(periods.first(), Some(&0));
    assert_eq!(periods.last(), Some(&100), "{periods:?}");
    assert_eq!(periods.len(), 16);
}

#[test]
fn unwritable_plot_is_refused_before_the_run() {
    let bad = tmp("no/such/dir/f.svg");
    let bad = bad.to_str().unwrap();
    let base = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../sim/scenes/base.toml");
    let out = tmp("never.csv");
    let err = refused(
        &[
            "simulate",
            base.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--plot",
            bad,
        ],
        "no/such/dir/f.svg",
    );
    assert!(!out.exists(), "the run must not start: {err}");
    refused(
        &["analyze", "--device", "phantom-1.0", "--plot", bad],
        "no/such/dir/f.svg",
    );
    refused(
        &[
            "experiment",
            "release",
            "--deflection",
            "12",
            "--stiffness",
            "2",
            "--fast",
            "--plot",
            bad,
        ],
        "no/such/dir/f.svg",
    );
}

#[test]
fn virtual_serves_the_device_on_a_pty_for_other_clients() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .args(["virtual", "--device", "phantom-1.0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let pty = line.trim().strip_prefix("pty: ").expect(&line).to_string();
    assert!(pty.starts_with("/dev/"), "{pty}");
    // Two clients in turn: the pty survives the first one's close.
    for _ in 0..2 {
        let o = hostctl(&["info", "--port", &pty, "--json"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert!(v.to_string().contains("servo_rate_hz"), "{v}");
    }
    // Ctrl-C stops it cleanly.
    let pid = child.id().to_string();
    assert!(Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .unwrap()
        .success());
    let t0 = Instant::now();
    loop {
        if let Some(st) = child.try_wait().unwrap() {
            assert!(st.success(), "{st}");
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "did not stop on SIGINT"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let o = hostctl(&["virtual", "--qemu"]);
    assert_eq!(o.status.code(), Some(2));
}
