//! QEMU scenarios: the real Cortex-M firmware image under `qemu-system-arm -serial pty`,
//! driven through hostctl's own serial client. Opt-in (`#[ignore]`): `cargo xtask qemu` builds
//! the image, sets `STIFFWALL_QEMU_IMAGE` and runs them; `STIFFWALL_BLESS=1` (`--bless`)
//! rewrites the expected transcripts in `firmware/boards/qemu-an386/scenarios/`.

use std::fmt::Write as _;
use std::path::PathBuf;
use stiffwall_host::device::client::Client;
use stiffwall_host::device::{qemu, transport};

fn boot() -> (qemu::Qemu, Client) {
    let image = qemu::find_image(None).expect("QEMU image (run `cargo xtask qemu`)");
    let q = qemu::boot(&image).expect("boot QEMU");
    let port = transport::open_port(&q.pty, transport::DEFAULT_BAUD).expect("open QEMU pty");
    let client = Client::connect(port, None).expect("handshake with the QEMU image");
    (q, client)
}

/// Compares a transcript with its expected file (or writes it when blessing).
fn check(name: &str, transcript: &str) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../firmware/boards/qemu-an386/scenarios")
        .join(format!("{name}.expected"));
    if std::env::var_os("STIFFWALL_BLESS").is_some() {
        std::fs::write(&path, transcript).expect("write expected transcript");
        return;
    }
    let expected = std::fs::read_to_string(&path)
        .unwrap_or_else(|_| panic!("missing {}; run `cargo xtask qemu --bless`", path.display()));
    assert_eq!(
        transcript,
        expected,
        "scenario {name} differs from {}",
        path.display()
    );
}

#[test]
#[ignore = "needs qemu-system-arm and the board image: run `cargo xtask qemu`"]
fn boot_and_handshake() {
    let (_q, mut c) = boot();
    let i = c.info.clone();
    let mut t = String::new();
    writeln!(t, "protocol {}", i.protocol_version).unwrap();
    writeln!(t, "firmware {} {}", i.firmware_name, i.firmware_version).unwrap();
    writeln!(t, "board {}", i.board).unwrap();
    writeln!(t, "servo_rate_hz {}", i.servo_rate_hz).unwrap();
    writeln!(
        t,
        "counts_per_rev {} encoder_bits {}",
        i.counts_per_rev, i.encoder_bits
    )
    .unwrap();
    writeln!(t, "max_code {}", i.max_code).unwrap();
    let cfg = c.get_config().expect("GetConfig");
    writeln!(
        t,
        "stiffness {} force_limit {:.4}",
        cfg.stiffness, cfg.force_limit
    )
    .unwrap();
    check("boot_and_handshake", &t);
}

/// One release test on the QEMU image; returns a transcript line set.
fn release_transcript(c: &mut Client, k: f32, deflection: i32, ticks: u32) -> String {
    use stiffwall_host::tune::release::classify;
    let mut cfg = c.get_config().expect("GetConfig");
    cfg.stiffness = k;
    c.clear_faults().expect("ClearFaults");
    c.set_config(&cfg).expect("SetConfig");
    let rec = c.release(deflection, ticks).expect("release");
    let counts: Vec<i64> = rec
        .samples
        .iter()
        .filter(|s| s.flags & stiffwall_proto::flags::RELEASED != 0)
        .map(|s| i64::from(s.count))
        .collect();
    let verdict = classify(&counts, rec.faults != 0);
    let mut t = String::new();
    writeln!(t, "stiffness {k} deflection {deflection} ticks {ticks}").unwrap();
    writeln!(t, "completed {} faults {:#x}", rec.completed, rec.faults).unwrap();
    writeln!(t, "verdict {verdict:?}").unwrap();
    writeln!(t, "telemetry gaps {}", rec.gaps.missing).unwrap();
    t
}

#[test]
#[ignore = "needs qemu-system-arm and the board image: run `cargo xtask qemu`"]
fn release_in_region_a_settles() {
    let (_q, mut c) = boot();
    // Impulse Engine at 1 kHz, K = 20 N/m: β = 1.0, σ = 38 (region A).
    let t = release_transcript(&mut c, 20.0, 20, 2000);
    check("release_in_region_a_settles", &t);
}

#[test]
#[ignore = "needs qemu-system-arm and the board image: run `cargo xtask qemu`"]
fn release_in_region_c_trips_the_supervisor() {
    let (_q, mut c) = boot();
    // K = 3000 N/m: β = 0.0067, σ = 0.25 (region C): the energy monitor must trip.
    let t = release_transcript(&mut c, 3000.0, 10, 2000);
    let faults = c.faults().expect("GetFaults");
    let mut t = t;
    writeln!(
        t,
        "latched {:#x} safe_mode {}",
        faults.latched, faults.safe_mode
    )
    .unwrap();
    check("release_in_region_c_trips_the_supervisor", &t);
}
