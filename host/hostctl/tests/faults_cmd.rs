//! End-to-end tests of `hostctl faults` and `hostctl faults clear`, and of the travel window
//! (`config set --travel-min/--travel-max`) whose fault they show, running the real `hostctl`
//! binary against the built-in virtual device: served on a pseudo-terminal by `hostctl
//! virtual`, so that one device (and its latched faults) outlives several hostctl runs.

use std::time::{Duration, Instant};
use stiffwall_proto::fault;

#[path = "support/cli.rs"]
mod cli;
#[path = "support/served.rs"]
mod served;
use cli::{fails, json, ok};
use served::Served;

/// The device's fault report (`hostctl faults --json`).
fn faults_json(d: &Served) -> serde_json::Value {
    json(&ok(&d.args(&["faults", "--json"])))
}

/// A travel window the device is outside of trips the `travel` fault: `faults` names it with
/// its first tick (exit 0); `faults clear` refuses while the cause persists (exit 2, naming
/// it), and once the window is off clears it and says what it cleared; `info` names it too.
#[test]
fn faults_name_the_travel_fault_and_clear_it() {
    let d = Served::start();
    let out = ok(&d.args(&["faults"]));
    assert!(out.starts_with("no faults latched on the "), "{out}");
    assert!(out.contains("(safe mode off)"), "{out}");
    let v = faults_json(&d);
    assert_eq!(v["latched"], 0);
    assert_eq!(v["names"], serde_json::json!([]));
    assert_eq!(v["safe_mode"], false);

    // The virtual device rests near count 0: a window far above it.
    let out = ok(&d.args(&[
        "config",
        "set",
        "--travel-min",
        "1000000",
        "--travel-max",
        "2000000",
    ]));
    assert!(
        out.contains("travel-min            1000000 counts"),
        "{out}"
    );
    assert!(
        out.contains("travel-max            2000000 counts"),
        "{out}"
    );
    let t0 = Instant::now();
    let v = loop {
        let v = faults_json(&d);
        if v["latched"] != 0 || t0.elapsed() > Duration::from_secs(5) {
            break v;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(v["latched"], fault::TRAVEL);
    assert_eq!(v["names"], serde_json::json!(["travel"]));
    assert_eq!(v["labels"], serde_json::json!(["outside travel"]));
    assert_eq!(v["safe_mode"], true);
    let first = v["first_tick"].as_u64().unwrap();
    assert!(first > 0, "{v}");

    let out = ok(&d.args(&["faults"]));
    assert!(
        out.contains(&format!(
            ": travel (first at tick {first}, safe mode on)\n  travel         outside travel"
        )),
        "{out}"
    );
    let out = ok(&d.args(&["info"]));
    assert!(
        out.contains(&format!("faults:      travel (first at tick {first}")),
        "{out}"
    );

    // Still outside: cleared, it latches again at once.
    let e = fails(&d.args(&["faults", "clear"]));
    assert!(
        e.contains("the faults latched again at once (travel, at tick"),
        "{e}"
    );
    assert!(e.contains("outside the travel window"), "{e}");
    let v = faults_json(&d);
    assert_eq!(v["latched"], fault::TRAVEL);
    let first = v["first_tick"].as_u64().unwrap();

    // The window off: the fault clears, and `clear` says which.
    let out = ok(&d.args(&[
        "config",
        "set",
        "--travel-min",
        "off",
        "--travel-max",
        "off",
    ]));
    assert!(out.contains("travel-min            off"), "{out}");
    let out = ok(&d.args(&["faults", "clear"]));
    assert!(
        out.starts_with("cleared on the ")
            && out.contains(&format!(
                ": travel (first at tick {first}); safe mode off\n  travel         outside \
                 travel"
            )),
        "{out}"
    );
    let v = faults_json(&d);
    assert_eq!(
        (v["latched"].clone(), v["safe_mode"].clone()),
        (0.into(), false.into())
    );
    let out = ok(&d.args(&["faults"]));
    assert!(out.starts_with("no faults latched"), "{out}");

    // Nothing left: `clear` says so; JSON has the report from before and the one after.
    let out = ok(&d.args(&["faults", "clear"]));
    assert!(out.starts_with("nothing to clear on the "), "{out}");
    let v = json(&ok(&d.args(&["faults", "clear", "--json"])));
    assert_eq!(v["cleared"]["latched"], 0);
    assert_eq!(v["now"]["latched"], 0);
    assert!(v["target"].as_str().unwrap().contains(&d.pty), "{v}");
}

/// The default target (a fresh virtual device per run) and the other device options are
/// accepted as by every device command; a travel window out of order is refused on the host.
#[test]
fn faults_take_the_device_options_and_bad_windows_are_refused() {
    let out = ok(&["faults", "--fast"]);
    assert!(out.starts_with("no faults latched on the "), "{out}");
    let out = ok(&["faults", "clear", "--fast", "--device", "phantom-1.0"]);
    assert!(out.starts_with("nothing to clear on the "), "{out}");
    let v = json(&ok(&["faults", "--json", "--fast"]));
    assert_eq!(v["latched"], 0);
    let e = fails(&["faults", "--port", "/dev/stiffwall-no-such-port"]);
    assert!(e.contains("does not exist"), "{e}");

    let out = ok(&["config", "get", "--fast"]);
    assert!(out.contains("travel-min            off"), "{out}");
    assert!(out.contains("travel-max            off"), "{out}");
    let v = json(&ok(&[
        "config",
        "set",
        "--travel-min",
        "-5000",
        "--travel-max",
        "5000",
        "--fast",
        "--json",
    ]));
    assert_eq!(
        (v["travel_min"].clone(), v["travel_max"].clone()),
        ((-5000).into(), 5000.into())
    );
    let e = fails(&["config", "set", "--travel-min", "10", "--travel-max", "10"]);
    assert!(e.contains("--travel-max must be above --travel-min"), "{e}");
    let e = fails(&["config", "set", "--travel-min", "ten"]);
    assert!(e.contains("nor `off`"), "{e}");
}
