//! The firmware's supervisor on the plant family (issue 10, item 6): with the stiffness forced to
//! 1.5 × the true largest stable K* (`stiffwall_tests::kstar`, computed here from the simulator
//! alone), the firmware core driving the plant (software in the loop, the virtual device's board
//! and boot config) latches a fault and zeroes the force, on every plant of `sim/plants/`:
//! - after an impact at v_max from each side, whenever that impact does not settle without the
//!   firmware (the same sampled spring of eq. (2), no supervisor);
//! - in every other trial of the K* criterion that does not settle without the firmware at
//!   1.5 K* (releases, slower impacts), so that no unstable motion of the criterion is missed.
//!
//! The one exception, asserted as such: a one-sided wall without a hand spring that throws the
//! plant out once, faster than it came (nothing brings it back, so there is no motion left to
//! stop); then the firmware must apply no force after the plant left, and the run is reported.

use stiffwall_tests::family::{plant_files, plants_dir, PlantCase};
use stiffwall_tests::kstar;

/// The plants of the default run: the buzz of a firm grip and of a slow servo, a one-sided wall,
/// a transmission, cogging and the paper's rig with its amplifier.
pub const DEFAULT_PLANTS: [&str; 6] = [
    "freedom6-firm-grip",
    "maxon-re35-slow-servo",
    "omega-one-sided-delay",
    "phantom-cable-150hz",
    "rotary-ironcore-cogging",
    "maxon-re35-amp-3khz",
];

fn check_all(cases: &[PlantCase]) {
    let mut failures = Vec::new();
    for case in cases {
        let ks = kstar::k_star(&case.proto, &case.rig, case.k_start(), 1e12)
            .unwrap_or_else(|e| panic!("{}: K*: {e}", case.name));
        let rep = case.supervisor_report(1.5 * ks.k_star);
        assert_eq!(
            rep.v_max_impacts.len(),
            if case.rig.one_sided { 1 } else { 2 },
            "{}: the impacts at v_max are always run",
            case.name
        );
        for s in rep.v_max_impacts.iter().chain(&rep.other_unstable) {
            let line = format!(
                "{} at 1.5 K* = {:.5}: {:?}: unsupervised {} (peak {:.1} counts, left the wall at {:?} × the passive speed); supervised: trip at tick {:?}, faults {:#x}, nonzero codes after the trip {}, left and released {}",
                case.name,
                rep.k,
                s.trial,
                if s.unsupervised_settles { "settles" } else { "does not settle" },
                s.unsupervised_peak,
                s.left_faster,
                s.run.trip_tick,
                s.run.faults,
                s.run.nonzero_after_trip,
                s.left_and_released(),
            );
            eprintln!("{line}");
            if !s.safe() {
                failures.push(format!("NOT STOPPED: {line}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} unstable runs not stopped:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn the_supervisor_stops_six_plants_at_one_and_a_half_k_star() {
    let cases: Vec<PlantCase> = DEFAULT_PLANTS
        .iter()
        .map(|n| PlantCase::named(n).unwrap_or_else(|e| panic!("{e}")))
        .collect();
    check_all(&cases);
}

#[test]
#[ignore = "every plant of sim/plants: minutes in a debug build; run with --ignored"]
fn the_supervisor_stops_every_plant_at_one_and_a_half_k_star() {
    let cases: Vec<PlantCase> = plant_files(&plants_dir())
        .unwrap()
        .iter()
        .map(|p| PlantCase::load(p).unwrap_or_else(|e| panic!("{e}")))
        .collect();
    check_all(&cases);
}
