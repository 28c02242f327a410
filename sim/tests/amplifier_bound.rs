//! The amplifier's bandwidth is bounded by what the reference solvers can simulate in
//! reasonable time (issue 11): `cutoff_hz = 1e12` used to be accepted and never finished.
//! Units: Hz for physical scenes, rad per sampling period for dimensionless ones.

use stiffwall_sim::scene::Scene;

const PHANTOM: &str = include_str!("../scenes/phantom-physical.toml");

fn with_cutoff(hz: &str) -> String {
    PHANTOM.replace("cutoff_hz = 3000.0", &format!("cutoff_hz = {hz}"))
}

#[test]
fn cutoff_beyond_the_bound_is_refused_naming_it() {
    for hz in ["1e12", "1e7", "1.6e6"] {
        let e = Scene::from_toml(&with_cutoff(hz)).unwrap_err().to_string();
        assert!(e.contains("effects.amplifier.cutoff_hz"), "{hz}: {e}");
        assert!(e.contains("1e4 rad per sampling period"), "{hz}: {e}");
        assert!(e.contains("1.59 MHz at T = 1 ms"), "{hz}: {e}");
    }
    // Just inside the bound (1e4 / (2 pi 1 ms) = 1.5915 MHz) and the shipped 3 kHz are fine.
    assert!(Scene::from_toml(&with_cutoff("1.59e6")).is_ok());
    assert!(Scene::from_toml(PHANTOM).is_ok());
}

#[test]
fn dimensionless_omega_is_bounded_too() {
    let scene = |omega: &str| {
        format!(
            "[device]\nmu = 100.0\nbeta = 0.1\nsigma = 1.0\n[effects]\nzoh = true\n\
             quantization = true\ncoulomb = true\nviscous = true\ndelay = false\n\
             one_sided_wall = false\namplifier = {{ kind = \"second_order\", omega = {omega}, \
             zeta = 0.7 }}\nhand = {{ kind = \"none\" }}\n[initial]\nxi = 0.0\nxidot = 5.0\n\
             [run]\nperiods = 100\nsolver = {{ kind = \"rk4\", steps_per_period = 8 }}\n"
        )
    };
    let e = Scene::from_toml(&scene("1e9")).unwrap_err().to_string();
    assert!(
        e.contains("effects.amplifier.omega") && e.contains("(0, 1e4]"),
        "{e}"
    );
    assert!(Scene::from_toml(&scene("1e4")).is_ok());
}
