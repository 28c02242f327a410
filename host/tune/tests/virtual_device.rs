//! End-to-end tests against the built-in virtual device over a pseudo-terminal (release
//! verdicts: they need the tune's classifier, so they live with it).

use stiffwall_client::{spawn_virtual_device as spawn, Client, Pace, VirtualSpec as Spec};
use stiffwall_tune::{classify, released_counts, Verdict};

fn maxon(fast: bool) -> Spec {
    let d = stiffwall_core::devices::find("maxon-re35").expect("preset");
    Spec {
        plant: d.params,
        counts_per_rev: 8192,
        pace: Pace::fast_if(fast),
        initial_position: 0.0,
        output_range: None,
        scene: None,
        travel: None,
        trace: None,
    }
}

fn connect(spec: Spec) -> Client {
    let (vd, port) = spawn(spec).expect("spawn virtual device");
    Client::connect(port, Some(Box::new(vd))).expect("handshake")
}

fn release_verdict(c: &mut Client, k: f32, deflection: i32) -> Verdict {
    let mut cfg = c.get_config().unwrap();
    cfg.stiffness = k;
    c.set_config(&cfg).unwrap();
    let rec = c.release(deflection, 3000).unwrap();
    assert!(rec.completed || rec.faults != 0, "{rec:?}");
    assert_eq!(
        rec.gaps.missing,
        0,
        "no sample lost in fast mode: {:?} first {:?} n {}",
        rec.gaps,
        rec.samples.first(),
        rec.samples.len()
    );
    let counts = released_counts(&rec.samples, 0);
    eprintln!(
        "K={k} faults={:#x} completed={} n={} head={:?} tail={:?}",
        rec.faults,
        rec.completed,
        counts.len(),
        &counts[..counts.len().min(40)],
        &counts[counts.len().saturating_sub(20)..]
    );
    classify(&counts, rec.faults != 0)
}

#[test]
fn handshake_reports_the_virtual_board() {
    let c = connect(maxon(true));
    assert_eq!(c.info.board.as_str(), "virtual");
    assert_eq!(c.info.protocol_version, stiffwall_proto::PROTOCOL_VERSION);
    assert_eq!(c.info.counts_per_rev, 8192);
}

#[test]
fn soft_wall_settles_and_stiff_wall_does_not() {
    let mut c = connect(maxon(true));
    let soft = release_verdict(&mut c, 0.5, 20);
    assert!(soft.settled(), "K=0.5 N·m/rad: {soft:?}");
    c.clear_faults().unwrap();
    let stiff = release_verdict(&mut c, 40.0, 20);
    assert!(!stiff.settled(), "K=40 N·m/rad: {stiff:?}");
}

/// A fake device on a pty that answers the handshake claiming another protocol version.
#[test]
fn a_device_speaking_another_protocol_version_is_refused_clearly() {
    use std::io::{Read, Write};
    use stiffwall_proto::{encode, DeviceMsg, FrameDecoder, HostMsg, MAX_FRAME};
    let (mut master, host, _name) = stiffwall_client::pty_pair().unwrap();
    let fake = std::thread::spawn(move || {
        let mut dec = FrameDecoder::new();
        let mut byte = [0u8; 1];
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(5);
        while std::time::Instant::now() < deadline {
            if master.read(&mut byte).unwrap_or(0) == 0 {
                continue;
            }
            if let Some(Ok(HostMsg::Hello { .. })) = dec.feed::<HostMsg>(byte[0]) {
                let mut info = stiffwall_firmware::BoardInfo::default().device_info(1000);
                info.protocol_version = stiffwall_proto::PROTOCOL_VERSION + 1;
                let mut buf = [0u8; MAX_FRAME];
                let frame = encode(&DeviceMsg::HelloReply(info), &mut buf).unwrap();
                master.write_all(frame).unwrap();
                std::thread::sleep(std::time::Duration::from_millis(300));
                return;
            }
        }
    });
    let err = Client::connect(host, None).unwrap_err();
    let msg = format!("{err:#}");
    assert!(
        msg.contains(&format!(
            "protocol version {}",
            stiffwall_proto::PROTOCOL_VERSION + 1
        )) && msg.contains("update the host"),
        "{msg}"
    );
    fake.join().unwrap();
}
