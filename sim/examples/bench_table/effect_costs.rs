//! The report's cost of each effect: the exact solver's time per period for each effect set (all,
//! each removed, none), and each compiled-out effect against the same effect compiled in
//! with a neutral parameter.

use super::effect_time;
use std::fmt::Write as _;
use stiffwall_sim::{Effects, Motion, Params};

/// Appends the section's two tables to `md`.
pub fn effect_costs(md: &mut String, min_s: f64) {
    writeln!(md, "## Cost of each effect (exact solver)\n").unwrap();
    let p = Params {
        mu: 100.0,
        beta: 0.1,
        sigma: 1.0,
        tau_d: 1.25,
    };
    let init = Motion { x: 0.0, v: 5.0 };
    writeln!(
        md,
        "Base scene with tau_D = 1.25 (mu 100, beta 0.1, sigma 1, xidot0 5), runs of up to 5e4 periods restarted \
         whenever the trajectory diverges or comes to rest, so every timed period is real work. Removing \
         an effect changes the trajectory (more or fewer zero crossings), so the second table compares \
         each compiled-out effect with the same effect compiled in but made neutral (sigma = 0, \
         beta = 0, tau_D = 0): identical trajectories, so the difference is the cost of the disabled \
         code path. A compiled-out effect is a `const bool` generic parameter, so its code is not in \
         the monomorphised loop at all; differences of either sign up to ~20 % are run-to-run noise \
         (code alignment, the shared machine), not a systematic cost.\n"
    )
    .unwrap();
    writeln!(md, "| effect set | ns/period |\n|---|---:|").unwrap();
    let n = 2_000_000;
    let sets = effect_sets();
    for (name, e) in &sets {
        let ns = effect_time(p, *e, init, n, min_s);
        writeln!(md, "| {name} | {ns:.2} |").unwrap();
    }
    writeln!(
        md,
        "\n| disabled effect | compiled out, ns/period | compiled in, neutral parameter, ns/period |\n|---|---:|---:|"
    )
    .unwrap();
    let pairs = neutral_pairs(p);
    for (name, pn, e) in &pairs {
        // Alternate the two builds and keep the best of 5 each (the machine is shared).
        let (mut off, mut on) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..5 {
            off = off.min(effect_time(*pn, *e, init, n, min_s / 2.0));
            on = on.min(effect_time(*pn, Effects::ALL, init, n, min_s / 2.0));
        }
        writeln!(md, "| {name} | {off:.2} | {on:.2} |").unwrap();
    }
    writeln!(md).unwrap();
}

/// The effect sets timed: all, each removed, the one-sided wall added, and none.
fn effect_sets() -> Vec<(&'static str, Effects)> {
    let all = Effects::ALL;
    vec![
        ("all (quantization, Coulomb, viscous, delay)", all),
        (
            "all without quantization",
            Effects {
                quantization: false,
                ..all
            },
        ),
        (
            "all without Coulomb",
            Effects {
                coulomb: false,
                ..all
            },
        ),
        (
            "all without viscous",
            Effects {
                viscous: false,
                ..all
            },
        ),
        (
            "all without delay",
            Effects {
                delay: false,
                ..all
            },
        ),
        (
            "all + one-sided wall",
            Effects {
                one_sided: true,
                ..all
            },
        ),
        ("none (sampled linear spring only)", Effects::NONE),
    ]
}

/// Each effect compiled out, with the parameter that makes it neutral in `p`.
fn neutral_pairs(p: Params) -> Vec<(&'static str, Params, Effects)> {
    let all = Effects::ALL;
    vec![
        (
            "Coulomb (sigma = 0)",
            Params { sigma: 0.0, ..p },
            Effects {
                coulomb: false,
                ..all
            },
        ),
        (
            "viscous (beta = 0)",
            Params { beta: 0.0, ..p },
            Effects {
                viscous: false,
                ..all
            },
        ),
        (
            "delay (tau_D = 0)",
            Params { tau_d: 0.0, ..p },
            Effects {
                delay: false,
                ..all
            },
        ),
    ]
}
