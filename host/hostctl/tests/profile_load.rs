//! End-to-end: `hostctl profile load | show | clear` on a device that outlives each run (the
//! virtual device served by `hostctl virtual`), and a tune on a device with a profile active.
//! The device's state is read back after every command: the profile the device renders (its
//! `GetProfile`), its faults, and, after a tune, that the profile is back.

#[path = "support/cli.rs"]
mod cli;
#[path = "support/served.rs"]
mod served;
use cli::{hostctl, ok};
use served::Served;

fn profile(name: &str) -> String {
    format!("{}/../../profiles/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn no_faults(d: &Served) {
    let f = cli::json(&ok(&d.args(&["faults", "--json"])));
    assert_eq!(f["latched"], 0, "{f}");
}

#[test]
fn load_show_clear_and_a_tune_over_a_loaded_profile() {
    let d = Served::with(&["--device", "maxon-re35", "--fast"]);
    assert!(ok(&d.args(&["profile", "show"])).contains("none (the config's wall)"));

    // A failing profile is refused and changes nothing.
    let strong = profile("too-strong-detent.toml");
    let o = hostctl(&d.args(&["profile", "load", &strong]));
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not loaded"));
    assert!(ok(&d.args(&["profile", "show"])).contains("none (the config's wall)"));

    // The knob loads, saved: the device renders its three wire elements (13 detents, two walls).
    ok(&d.args(&[
        "profile",
        "load",
        &profile("knob-24-detents.toml"),
        "--save",
    ]));
    let shown = ok(&d.args(&["profile", "show"]));
    assert!(shown.starts_with("profile: 3 elements"), "{shown}");
    assert!(shown.contains("13 detents from count 0"), "{shown}");
    assert!(
        shown.contains("lower wall at count -171") && shown.contains("upper wall at count 4267"),
        "{shown}"
    );
    no_faults(&d);

    // A tune with the profile active turns it off for its tests and puts it back.
    let tune = hostctl(&d.args(&["tune", "--dry-run"]));
    let err = String::from_utf8_lossy(&tune.stderr);
    assert!(tune.status.success(), "{err}");
    assert!(
        err.contains("a haptic profile of 3 elements is active"),
        "{err}"
    );
    assert_eq!(ok(&d.args(&["profile", "show"])), shown);
    no_faults(&d);

    // --force loads a failing profile, naming what will chatter.
    let o = hostctl(&d.args(&["profile", "load", &strong, "--force"]));
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("element 1 (detents) is expected to chatter or grow"),
        "{err}"
    );
    assert!(ok(&d.args(&["profile", "show"])).contains("4 detents"));

    ok(&d.args(&["profile", "clear"]));
    assert!(ok(&d.args(&["profile", "show"])).contains("none (the config's wall)"));
    no_faults(&d);
}
