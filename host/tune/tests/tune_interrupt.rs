//! Ctrl-C during `tune` (issue 11): interrupted in each phase — identification, the
//! identified model, the stiffness search, the confirmation — the device is left with the
//! config it had before, unchanged and unsaved. The interrupt is raised as a front end does
//! (cancelling the tune's `Cancel` token: the Ctrl-C handler cancels its root) from the
//! progress callback when the phase starts.

use stiffwall_client::{spawn_virtual_device, Cancel, Client, Pace, VirtualSpec};
use stiffwall_proto::ServoConfig;
use stiffwall_tune::{tune, Settings, TuneError};

fn connect() -> Client {
    let p = stiffwall_core::devices::find("maxon-re35").unwrap().params;
    let (vd, port) = spawn_virtual_device(VirtualSpec {
        plant: p,
        counts_per_rev: (std::f64::consts::TAU / p.resolution).round() as u32,
        pace: Pace::Fast,
        initial_position: 0.0,
        output_range: None,
        scene: None,
        travel: None,
        trace: None,
    })
    .unwrap();
    Client::connect(port, Some(Box::new(vd))).unwrap()
}

#[test]
fn tune_interrupted_in_each_phase_restores_the_previous_config() {
    // The phases of `procedure::tune` by their progress messages ("verifying" is the
    // verification set at the K to be set, formerly "confirming").
    for phase in [
        "identifying",
        "breakaway ramp",
        "identified",
        "release test",
        "verifying",
    ] {
        let mut c = connect();
        let before = ServoConfig {
            stiffness: 0.777,
            damping: 0.000_123,
            wall_position: 17,
            ..c.get_config().unwrap()
        };
        c.set_config(&before).unwrap();
        let cancel = Cancel::default();
        let mut seen = false;
        let r = tune(&mut c, &Settings::default(), &cancel, &mut |m| {
            if m.to_string().starts_with(phase) {
                seen = true;
                cancel.cancel();
            }
        });
        assert!(seen, "phase {phase:?} never started");
        let e = r.expect_err(phase);
        assert!(matches!(e, TuneError::Cancelled), "{phase}: {e:#}");
        assert_eq!(
            c.get_config().unwrap(),
            before,
            "{phase}: config not restored"
        );
    }
}
