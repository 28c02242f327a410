//! `hostctl tune` on plants beyond its model (issue 10, item 5; with the damper, issue 19; the
//! quiet wall, issue 33): on every plant of `sim/plants/`, the (K, B) that `tune --plant FILE
//! --fast --dry-run` sets is quiet (every trial of the K* criterion comes to rest at that
//! (K, B), simulated by `stiffwall_tests::kstar` from the simulator alone with the firmware's
//! damper law: no chatter, no buzz, no growth) and near optimal (0.7 K*(B) ≤ K ≤ K*(B), the
//! true largest quiet K at the B and law it set, lowered as docs/TUNE.md's where one of tune's
//! small-swing states keeps swinging on the plant: `stiffwall_tests::swings`); over all of `sim/plants/` the median K set /
//! K*(0) is at least 2.
//!
//! The tune runs the same code as `hostctl tune --plant FILE --fast --dry-run`: the client
//! connects to the same target (`ConnectSpec::plant_file(FILE, fast)`, what `--plant FILE
//! --fast` converts into) and `tune::procedure::tune` runs on it.
//! Default run: the plants of [`DEFAULT_PLANTS`] and the presets; `-- --ignored` runs six random
//! plants of the launch family (in `cargo xtask ci`). Every plant of `sim/plants/` and the
//! holdout plants of `sim/plants-holdout/` (written after tune was built and never tuned
//! against) are checked by `cargo xtask tune-table --check` in `cargo xtask ci`.

use stiffwall_client::ConnectSpec;
use stiffwall_tests::family::PlantCase;
use stiffwall_tests::kstar;
use stiffwall_tests::swings;
use stiffwall_tune::{Outcome, Settings};

/// The plants of the default run (quick K*): stiction, amplifier filter, compliant
/// transmission, cogging, a hand (the spring-like force tune's identification fits beside m,
/// b, c), the launch family (stiction, a slow amplifier with a tight limit, delay), a damped
/// wall behind a fast amplifier whose stable K has a narrow failing band below K*(B)
/// (`maxon-re35-amp-3khz`: the brute force's confirmation scan finds it), and a light stage
/// with a fine encoder whose damped release hold trips the encoder-jump limit when re-aimed
/// farther (`fine-encoder-stage`: the first attempt's outcome stands), and a lighter rotor
/// behind two ticks of delay whose release hold rings far past its target above K* and, re-aimed
/// nearer, sticks at the wall (`rotary-light-stiction-delay2`: the failure from farther stands;
/// tune set 0.62–0.69 = 1.7 K* before). The every-plant test below runs all of `sim/plants/`.
pub const DEFAULT_PLANTS: [&str; 9] = [
    "phantom-stiction",
    "phantom-amp-300hz",
    "phantom-cable-150hz",
    "rotary-ironcore-cogging",
    "phantom-light-grip",
    "maxon-re35-stiction-amp1k-delay",
    "maxon-re35-amp-3khz",
    "fine-encoder-stage",
    "rotary-light-stiction-delay2",
];

/// Lower bound of K set / K*_quiet(B set) (docs/TUNE.md states the same bound).
const NEAR_OPTIMAL: f64 = 0.7;

/// One plant's tune against the truth.
struct Checked {
    line: String,
    /// K set / K*(0).
    gain: f64,
}

/// K*_quiet(0) and K*_quiet(B set) and the K (B, law) set by tune; an error message when tune
/// fails, when any trial of the criterion at the set wall does not come to rest (chatter, buzz
/// or growth), or when K is outside [0.7, 1] × K*_quiet(B set).
fn check(case: &PlantCase) -> Result<Checked, String> {
    let ks0 = kstar::k_star(&case.proto, &case.rig, case.k_start(), 1e12)
        .map_err(|e| format!("{}: K*: {e}", case.name))?;
    let t0 = std::time::Instant::now();
    let o = tune_dry_run(&ConnectSpec::plant_file(
        &case.path,
        stiffwall_client::Pace::Fast,
    ))
    .map_err(|e| format!("{}: {e}", case.name))?;
    let tune_s = t0.elapsed().as_secs_f64();
    // The truth at the set damping and law (the same brute force with the firmware's damper).
    let at_set = at_set_wall(&case.rig, &o).map_err(|e| format!("{}: {e}", case.name))?;
    // Lowered where a small state keeps swinging on the plant, as docs/TUNE.md's K*(B set):
    // tune screens its damped wall for those states, the criterion's trials never start there.
    let ks = if o.b_set > 0.0 {
        let ks = kstar::k_star(&case.proto, &at_set, ks0.k_star * 0.5, 1e12)
            .map_err(|e| format!("{}: K*(B = {:.4e}): {e}", case.name, o.b_set))?;
        let starts: Vec<(f64, f64)> = stiffwall_tune::small_swing::small_starts()
            .map(|st| (st.x_counts, st.v_counts_per_tick))
            .collect();
        let trials = swings::moving_trials(&at_set, &starts);
        swings::lowered_where_swinging(&case.proto, &at_set, ks, &trials)
    } else {
        ks0.clone()
    };
    let runs = kstar::run_all(&case.proto, &at_set, o.k_set);
    let not_resting: Vec<String> = runs
        .iter()
        .filter(|(_, r)| !r.rests())
        .map(
            |(t, r)| match r.chatter(case.rig.period_s, case.model.coulomb_n) {
                Some(ch) => format!(
                    "{t:?} chatters ({:.0} toggles/s, {:.1} c)",
                    ch.toggles_per_s, ch.force_pp_c
                ),
                None => format!("{t:?} buzzes or grows"),
            },
        )
        .collect();
    let ratio = o.k_set / ks.k_star;
    let gain = o.k_set / ks0.k_star;
    let line = format!(
        "{}: K*(0) = {:.5}, B set = {:.4e} ({}), K*(B) = {:.5} (first failure {:?}), K set = \
         {:.5}, K/K*(B) = {ratio:.3}, K/K*(0) = {gain:.3}, rests in {} of {} runs, tune \
         {tune_s:.1} s",
        case.name,
        ks0.k_star,
        o.b_set,
        o.damper,
        ks.k_star,
        ks.failing,
        o.k_set,
        runs.len() - not_resting.len(),
        runs.len(),
    );
    eprintln!("{line}");
    if !not_resting.is_empty() {
        return Err(format!(
            "DOES NOT REST at the set wall: {}; {line}",
            not_resting.join("; ")
        ));
    }
    if !o.rests {
        return Err(format!("tune says its wall does not rest: {line}"));
    }
    // Above K*(B) is allowed only because every run at the set wall came to rest (checked
    // above): with a damper the quiet K need not form one interval (maxon-re35-amp-3khz at
    // B = 4.8e-3: a release from 7 counts chatters at 3.19, every run rests at 3.90).
    if ratio < NEAR_OPTIMAL {
        return Err(format!("below {NEAR_OPTIMAL} K*(B): {line}"));
    }
    Ok(Checked { line, gain })
}

/// `tune --dry-run` (the default settings) on the device of `spec`.
fn tune_dry_run(spec: &ConnectSpec) -> Result<Outcome, String> {
    let mut client = stiffwall_client::connect(spec).map_err(|e| format!("connect: {e:#}"))?;
    stiffwall_tune::tune(
        &mut client,
        &Settings {
            dry_run: true,
            ..Settings::default()
        },
        &stiffwall_client::Cancel::default(),
        &mut |_| {},
    )
    .map_err(|e| format!("tune failed: {e:#}"))
}

/// The K* rig `rig` with the damping and the damper law tune set.
fn at_set_wall(rig: &kstar::Rig, o: &Outcome) -> Result<kstar::Rig, String> {
    let law: stiffwall_proto::DamperLaw = o
        .damper
        .parse()
        .map_err(|e| format!("tune.damper {:?}: {e}", o.damper))?;
    Ok(kstar::Rig {
        damping: o.b_set,
        deadband_counts: i64::from(law.dead_band()),
        ..rig.clone()
    })
}

/// Checks every case; returns the gains K set / K*(0).
fn check_all(cases: &[PlantCase]) -> Vec<f64> {
    let results: Vec<Result<Checked, String>> = cases.iter().map(check).collect();
    let failures: Vec<&String> = results.iter().filter_map(|r| r.as_ref().err()).collect();
    assert!(
        failures.is_empty(),
        "{} of {} plants fail:\n{}",
        failures.len(),
        cases.len(),
        failures
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>()
            .join("\n")
    );
    results
        .into_iter()
        .filter_map(Result::ok)
        .map(|c| {
            eprintln!("ok {}", c.line);
            c.gain
        })
        .collect()
}

#[test]
fn tune_is_safe_and_near_optimal_on_the_default_plants() {
    let cases: Vec<PlantCase> = DEFAULT_PLANTS
        .iter()
        .map(|n| PlantCase::named(n).unwrap_or_else(|e| panic!("{e}")))
        .collect();
    let _ = check_all(&cases);
}

// Every plant of `sim/plants/` and of `sim/plants-holdout/`: `cargo xtask ci` checks
// docs/TUNE.md and docs/TUNE-holdout.md against a fresh run (`cargo xtask tune-table --check`),
// which fails on a set wall that does not rest in every run, K below 0.7 K*(B), a supervisor
// that does not stop, or a median gain below 2 over `sim/plants/`: the same assertions as
// `check` above, on every plant.

/// A rotary plant of the launch family of issue 21 (static friction above Coulomb, a current
/// amplifier of finite bandwidth with a force limit a few times the wall's peak force, extra
/// delay, light rotors), drawn from `rng`: the scene file's text.
fn random_launch_plant(rng: &mut proptest::test_runner::TestRng) -> String {
    use proptest::prelude::RngExt;
    let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.random::<f64>();
    let mass = u(1.5e-6, 8e-6);
    let coulomb = u(0.8e-3, 2.5e-3);
    let cpr = [2048u32, 4096, 8192][(u(0.0, 3.0) as usize).min(2)];
    let stiction = coulomb * u(1.2, 2.0);
    let stribeck = u(0.01, 0.1);
    let cutoff = u(600.0, 2000.0);
    let limit = coulomb * u(8.0, 20.0);
    let delay_ticks = (u(0.0, 3.0) as u32).min(2);
    let v_max = 5.0 * std::f64::consts::TAU / f64::from(cpr) / 1e-3;
    format!(
        "[device]\nmass_kg = {mass:e}\nviscous_ns_per_m = {:e}\ncoulomb_n = {coulomb:e}\n\
         counts_per_rev = {cpr}\n\n[controller]\nstiffness_n_per_m = 0.2\nperiod_s = 0.001\n\
         extra_delay_s = {:e}\n\n[effects]\nzoh = true\nquantization = true\ncoulomb = true\n\
         viscous = true\ndelay = {}\none_sided_wall = false\namplifier = {{ kind = \
         \"second_order\", cutoff_hz = {cutoff}, damping = 0.7, force_limit_n = {limit:e} }}\n\
         hand = {{ kind = \"none\" }}\nstiction = {{ static_n = {stiction:e}, stribeck_m_per_s = \
         {stribeck} }}\n\n[initial]\nposition_m = 0.0\nvelocity_m_per_s = {v_max}\n\n[run]\n\
         periods = 3000\nsolver = {{ kind = \"dopri\", rtol = 1e-9, atol = 1e-12 }}\n",
        1.5 * mass,
        f64::from(delay_ticks) * 1e-3,
        delay_ticks > 0,
    )
}

#[test]
#[ignore = "six random plants of the launch family (stiction, amplifier limit, delay): minutes"]
fn tune_is_safe_and_near_optimal_on_random_launch_plants() {
    let mut rng = proptest::test_runner::TestRng::deterministic_rng(
        proptest::test_runner::RngAlgorithm::ChaCha,
    );
    let dir = std::env::temp_dir().join(format!("stiffwall-launch-plants-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cases: Vec<PlantCase> = (0..6)
        .map(|i| {
            let path = dir.join(format!("random-launch-{i}.toml"));
            std::fs::write(&path, random_launch_plant(&mut rng)).unwrap();
            PlantCase::load(&path).unwrap_or_else(|e| panic!("{e}"))
        })
        .collect();
    let _ = check_all(&cases);
}

/// The README's first command (the default `maxon-re35`) and phantom-1.0: the wall tune sets
/// comes to rest in every run of the K* criterion by the simulator alone (ten impact speeds
/// up to v_max from both sides, releases from four deflections, 60 natural periods each), and
/// lies in [0.7, 1] × K*_quiet(B set).
#[test]
fn the_presets_walls_come_to_rest_in_every_run() {
    for name in ["maxon-re35", "phantom-1.0"] {
        let (plant, rig) = kstar::preset(name).expect("a preset");
        let o = tune_dry_run(&ConnectSpec::preset(name, stiffwall_client::Pace::Fast))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let at_set = at_set_wall(&rig, &o).unwrap();
        let k0 = kstar::k_star(&plant, &rig, 1e-3 * o.k_set, 1e12).unwrap();
        let ks = kstar::k_star(&plant, &at_set, k0.k_star * 0.5, 1e12).unwrap();
        let runs = kstar::run_all(&plant, &at_set, o.k_set);
        let c = stiffwall_core::devices::find(name).unwrap().params.coulomb;
        let loud: Vec<String> = runs
            .iter()
            .filter(|(_, r)| !r.rests())
            .map(|(t, r)| format!("{t:?}: {:?}", r.chatter(rig.period_s, c)))
            .collect();
        let ratio = o.k_set / ks.k_star;
        eprintln!(
            "{name}: K set {:.5}, B set {:.4e} ({}), K*(0) {:.5}, K*(B set) {:.5}, K/K*(B) \
             {ratio:.3}, K/K*(0) {:.3}, {} of {} runs rest",
            o.k_set,
            o.b_set,
            o.damper,
            k0.k_star,
            ks.k_star,
            o.k_set / k0.k_star,
            runs.len() - loud.len(),
            runs.len()
        );
        assert!(loud.is_empty(), "{name}: runs that do not rest: {loud:#?}");
        assert!(o.rests, "{name}: tune reports a wall that does not rest");
        assert!(
            (NEAR_OPTIMAL..=1.0).contains(&ratio),
            "{name}: K set / K*(B set) = {ratio:.3}"
        );
    }
}

/// The wall `tune` set on the default device before walls had to come to rest (K = 4.0776
/// N·m/rad, B = 5.2791e-3 N·m·s/rad, README): with the plain backward difference most runs of
/// the criterion chatter (an independent simulator found 20 of its 22 runs toggling at up to
/// 500 per second); with a dead band of one count the same (K, B) rests in every run.
#[test]
fn the_former_default_wall_chatters_with_the_plain_difference_and_rests_with_the_dead_band() {
    let (plant, rig) = kstar::preset("maxon-re35").expect("a preset");
    let c = stiffwall_core::devices::find("maxon-re35")
        .unwrap()
        .params
        .coulomb;
    let at = |deadband_counts| kstar::Rig {
        damping: 5.2791e-3,
        deadband_counts,
        ..rig.clone()
    };
    let plain = kstar::run_all(&plant, &at(0), 4.0776);
    let chatter: Vec<_> = plain
        .iter()
        .filter_map(|(_, r)| r.chatter(rig.period_s, c))
        .collect();
    let worst = chatter.iter().fold(0.0f64, |a, ch| a.max(ch.toggles_per_s));
    eprintln!(
        "difference: {} of {} runs chatter, up to {worst:.0} toggles/s",
        chatter.len(),
        plain.len()
    );
    assert!(chatter.len() >= 20 && worst >= 400.0, "{chatter:?}");
    let dead_band = kstar::run_all(&plant, &at(1), 4.0776);
    assert!(dead_band.iter().all(|(_, r)| r.rests()));
}
