//! `cargo run --release -p stiffwall-tests --bin damper_laws [-- NAME...]`: the measurement
//! behind the firmware's default damper law. For every plant of `sim/plants/` (or the named
//! ones), the brute-force K*_quiet (every trial of the K* criterion comes to rest, simulated
//! from the plant file alone: `stiffwall_tests::kstar`) at B = 0 and, for each damper law, the
//! best K*_quiet(B) over B = [`kstar::FRONTIER_BETA`] × K*(0)·T with that B. Prints a Markdown
//! table of K*_quiet(B)/K*(0) per law and the median per law.
//!
//! Laws: `difference` (v = n − n_prev, dead band 0) and `dead-band-N` (v = 0 when |n − n_prev|
//! ≤ N counts), as the firmware's `DamperLaw`.

use rayon::prelude::*;
use stiffwall_tests::family::{plant_files, plants_dir, PlantCase};
use stiffwall_tests::kstar::{self, Rig};

/// The laws compared, as dead bands in counts (0: the plain difference).
const DEADBANDS: [i64; 3] = [0, 1, 2];

fn law_name(deadband: i64) -> String {
    if deadband == 0 {
        "difference".into()
    } else {
        format!("dead-band-{deadband}")
    }
}

/// The best (B, K*_quiet(B)) over the β grid with dead band `db`.
fn best(case: &PlantCase, k0: f64, db: i64) -> Option<(f64, f64)> {
    kstar::FRONTIER_BETA
        .par_iter()
        .filter(|&&beta| beta > 0.0)
        .filter_map(|beta| {
            let rig = Rig {
                damping: beta * k0 * case.rig.period_s,
                deadband_counts: db,
                ..case.rig.clone()
            };
            kstar::k_star(&case.proto, &rig, k0 * 0.5, 1e12)
                .ok()
                .map(|k| (rig.damping, k.k_star))
        })
        .collect::<Vec<_>>()
        .into_iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

fn main() {
    let names: Vec<String> = std::env::args().skip(1).collect();
    let cases: Vec<PlantCase> = plant_files(&plants_dir())
        .unwrap_or_else(|e| panic!("{e}"))
        .iter()
        .map(|p| PlantCase::load(p).unwrap_or_else(|e| panic!("{e}")))
        .filter(|c| names.is_empty() || names.contains(&c.name))
        .collect();
    let header: Vec<String> = DEADBANDS.iter().map(|&d| law_name(d)).collect();
    println!("| plant | K*_quiet(0) | {} |", header.join(" | "));
    println!("|---|---:|{}", "---:|".repeat(DEADBANDS.len()));
    let mut ratios: Vec<Vec<f64>> = vec![Vec::new(); DEADBANDS.len()];
    for case in &cases {
        let Ok(k0) = kstar::k_star(&case.proto, &case.rig, case.k_start(), 1e12) else {
            println!("| {} | none | |", case.name);
            continue;
        };
        let k0 = k0.k_star;
        let mut cells = Vec::new();
        for (i, &db) in DEADBANDS.iter().enumerate() {
            let (cell, r) = match best(case, k0, db) {
                Some((b, k)) if k > k0 => (format!("{:.2} (B {b:.3e})", k / k0), k / k0),
                _ => ("1.00 (B 0)".to_string(), 1.0),
            };
            ratios[i].push(r);
            cells.push(cell);
        }
        println!("| {} | {k0:.5} | {} |", case.name, cells.join(" | "));
    }
    let medians: Vec<String> = ratios
        .iter_mut()
        .map(|r| {
            r.sort_by(f64::total_cmp);
            r.get(r.len() / 2).map_or("-".into(), |m| format!("{m:.2}"))
        })
        .collect();
    println!("| **median** | | {} |", medians.join(" | "));
}
