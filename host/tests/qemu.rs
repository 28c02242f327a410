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
