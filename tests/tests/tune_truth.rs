//! `tune` on the virtual device with known plant parameters (issue 6 acceptance; issue 34
//! item 5: the truth independent of the code under test): the spring-only tune of the default
//! device identifies its m and c and sets K within 80–100 % of the true largest quiet K*(0),
//! found by the brute force of [`stiffwall_tests::kstar`] (the simulator's exact plant and the
//! sampled spring of eq. (2) written out there: impacts up to v_max from both sides, releases
//! from four deflections, every trial must come to rest). Nothing of tune (its release verdict,
//! its deflection rule) computes the truth.
//!
//! Units: the preset's (maxon-re35: rotary, kg·m², N·m, N·m/rad).

use stiffwall_client::{Cancel, ConnectSpec};
use stiffwall_tests::kstar;
use stiffwall_tune::{Damping, Settings};

#[test]
fn the_spring_only_tune_identifies_the_rig_and_sets_k_within_80_to_100_percent_of_k_star() {
    let name = "maxon-re35";
    let truth = stiffwall_core::devices::find(name).unwrap().params;
    let mut c = stiffwall_client::connect(&ConnectSpec::preset(name, stiffwall_client::Pace::Fast))
        .unwrap();
    let before = c.get_config().unwrap();
    // The spring-only tune (`--damping 0`), against the spring-only truth.
    let o = stiffwall_tune::tune(
        &mut c,
        &Settings {
            dry_run: true,
            damping: Damping::Fixed(0.0),
            ..Settings::default()
        },
        &Cancel::default(),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(o.b_set, 0.0);
    let m_err = o.identified.mass[0] / truth.mass - 1.0;
    let c_err = o.identified.coulomb[0] / truth.coulomb - 1.0;
    assert!(m_err.abs() < 0.05, "mass off by {:.1} %", 100.0 * m_err);
    assert!(
        c_err.abs() < 0.10,
        "Coulomb friction off by {:.1} %",
        100.0 * c_err
    );
    let (plant, rig) = kstar::preset(name).expect("a preset");
    let ks = kstar::k_star(&plant, &rig, 1e-3 * o.k_set, 1e12).unwrap();
    let ratio = o.k_set / ks.k_star;
    eprintln!(
        "{name}: K set {:.5}, K*(0) {:.5} (first failure {:?}), ratio {ratio:.3}",
        o.k_set, ks.k_star, ks.failing
    );
    assert!(
        (0.8..=1.0).contains(&ratio),
        "K set {:.5} vs K*(0) {:.5} (ratio {ratio:.3})",
        o.k_set,
        ks.k_star
    );
    assert_eq!(
        c.get_config().unwrap(),
        before,
        "dry run leaves the config untouched"
    );
}
