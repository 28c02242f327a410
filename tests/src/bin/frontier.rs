//! `cargo run --release -p stiffwall-tests --bin frontier -- PLANT.toml… [--beta 0,1,2]`: the
//! brute-force frontier K*(B) of each plant file (the criterion of `kstar`), B on a grid of
//! β = B/(K*(0)·T) (default [`FRONTIER_BETA`]). Prints one line per (plant, B): B in N·s/m
//! (N·m·s/rad), K*(B), K*(B)/K*(0).

use rayon::prelude::*;
use stiffwall_tests::family::PlantCase;
use stiffwall_tests::kstar::{frontier, k_star, FRONTIER_BETA};

fn main() -> Result<(), String> {
    let mut files = Vec::new();
    let mut betas = FRONTIER_BETA.to_vec();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--beta" {
            let list = args.next().ok_or("--beta needs a list, e.g. 0,1,2")?;
            betas = list
                .split(',')
                .map(|s| match s.trim().parse::<f64>() {
                    Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
                    _ => Err(format!("--beta: {s:?} is not a finite number ≥ 0")),
                })
                .collect::<Result<_, _>>()?;
        } else {
            files.push(std::path::PathBuf::from(a));
        }
    }
    let lines: Vec<String> = files
        .par_iter()
        .map(|f| plant_lines(f, &betas))
        .collect::<Result<_, _>>()?;
    for l in lines {
        print!("{l}");
    }
    Ok(())
}

fn plant_lines(file: &std::path::Path, betas: &[f64]) -> Result<String, String> {
    let case = PlantCase::load(file)?;
    let k_cap = case.k_start() * 1e6;
    let k0 = k_star(&case.proto, &case.rig, case.k_start(), k_cap)
        .map_err(|e| format!("{}: K*(0): {e}", case.name))?
        .k_star;
    let grid: Vec<f64> = betas.iter().map(|b| b * k0 * case.rig.period_s).collect();
    let mut out = String::new();
    for p in frontier(&case.proto, &case.rig, &grid, k0 * 0.5, k_cap) {
        let (k, ratio) = match &p.k_star {
            Ok(s) => (format!("{:.6e}", s.k_star), format!("{:.3}", s.k_star / k0)),
            Err(e) => (format!("({e})"), "-".into()),
        };
        out += &format!(
            "{:<32} B={:.4e} beta={:.2} K*={k} ratio={ratio}\n",
            case.name,
            p.b,
            p.b / (k0 * case.rig.period_s),
        );
    }
    Ok(out)
}
