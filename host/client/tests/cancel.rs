//! Cancelling an experiment from another thread (a page's Abort, a user's timer): the running
//! release ends soon after, the client reports `Cancelled`, the device is idle and keeps its
//! config, and the next experiment on a fresh token runs normally.

use std::time::{Duration, Instant};
use stiffwall_client::{connect, Cancel, ClientError, ConnectSpec};

#[test]
fn a_cancelled_release_stops_the_device_and_the_client_stays_usable() {
    let mut c = connect(&ConnectSpec::preset(
        "maxon-re35",
        stiffwall_client::Pace::Fast,
    ))
    .unwrap();
    let cfg = stiffwall_proto::ServoConfig {
        stiffness: 0.5,
        ..c.get_config().unwrap()
    };
    c.set_config(&cfg).unwrap();
    let cancel = Cancel::detached();
    c.set_cancel(cancel.clone());
    let timer = {
        let cancel = cancel.clone();
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(300));
            cancel.cancel();
            Instant::now()
        })
    };
    // 10⁷ ticks: minutes even on the fast virtual device, unless cancelled.
    let r = c.release(20, 10_000_000);
    let cancelled_at = timer.join().unwrap();
    assert!(matches!(r, Err(ClientError::Cancelled)), "{r:?}");
    assert!(
        cancelled_at.elapsed() < Duration::from_secs(3),
        "ended {:?} after the cancel",
        cancelled_at.elapsed()
    );
    // Requests still work and the config is the one set before.
    assert_eq!(c.get_config().unwrap(), cfg);
    // The token stays cancelled: a new experiment on it is refused before it starts.
    assert!(matches!(c.release(20, 500), Err(ClientError::Cancelled)));
    // On a fresh token the device runs the next test to its end.
    c.set_cancel(Cancel::detached());
    let rec = c.release(20, 500).unwrap();
    assert!(rec.completed, "{rec:?}");
    assert!(rec.samples.len() >= 500);
}

#[test]
fn a_child_token_follows_the_ctrl_c_root() {
    let op = stiffwall_client::ctrl_c().child();
    assert!(!op.is_cancelled());
    op.cancel();
    assert!(op.is_cancelled());
    assert!(!stiffwall_client::ctrl_c().is_cancelled());
}
