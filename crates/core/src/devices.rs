//! Device presets: the six rows of Table II and the experimental rig of Sec. V.
//!
//! Units: SI, as in [`PhysicalParams`] (Table II prints Δ in µm and T in ms; converted here).
//! Invariants: every preset validates; the Table II inputs are the printed values, unchanged —
//! the printed dimensionless outputs are kept alongside so that discrepancies stay visible
//! (see `docs/model-notes-core.md`).

use crate::params::PhysicalParams;

/// A named device preset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Device {
    /// CLI name, e.g. `"phantom-1.0"`.
    pub name: &'static str,
    /// Human-readable description and source.
    pub description: &'static str,
    /// Physical parameters at the preset stiffness.
    pub params: PhysicalParams,
    /// Dimensionless (μ, β, σ) as printed in Table II, if the preset is a Table II row.
    pub printed: Option<PrintedDimensionless>,
    /// Peak output of the device's amplifier, N (N·m for rotary devices): the virtual
    /// device's full scale. Not in the paper: the manufacturers' published peak forces
    /// (see `docs/model-notes-core.md`).
    pub force_limit: f64,
    /// The device's travel along the rendered axis, [min, max] m (rad) around the position it
    /// starts at, where the manufacturer publishes a workspace (`None`: unbounded, as the
    /// paper's model). Not in the paper: see `docs/model-notes-core.md` for each source.
    pub travel: Option<[f64; 2]>,
}

/// Dimensionless values as printed in Table II, with the number of decimals printed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrintedDimensionless {
    /// Printed μ.
    pub mu: f64,
    /// Decimals printed for μ.
    pub mu_decimals: u8,
    /// Printed β.
    pub beta: f64,
    /// Decimals printed for β.
    pub beta_decimals: u8,
    /// Printed σ.
    pub sigma: f64,
    /// Decimals printed for σ.
    pub sigma_decimals: u8,
}

const fn linear(m: f64, b: f64, c: f64, delta_um: f64, t_ms: f64, k: f64) -> PhysicalParams {
    PhysicalParams {
        mass: m,
        viscous: b,
        coulomb: c,
        resolution: delta_um * 1e-6,
        period_s: t_ms * 1e-3,
        stiffness: k,
        delay_s: 0.0,
        rotational: false,
    }
}

const fn printed(
    mu: f64,
    mu_d: u8,
    beta: f64,
    beta_d: u8,
    sigma: f64,
    sigma_d: u8,
) -> Option<PrintedDimensionless> {
    Some(PrintedDimensionless {
        mu,
        mu_decimals: mu_d,
        beta,
        beta_decimals: beta_d,
        sigma,
        sigma_decimals: sigma_d,
    })
}

/// Counts per revolution of the Sec. V encoder.
pub const MAXON_COUNTS_PER_REV: f64 = 8192.0;

/// All presets: Table II (delta, freedom6, impulse-engine, mit-toolhandle, omega, phantom-1.0)
/// and `maxon-re35` (Sec. V: rotational, 8192 counts/rev, c = 2e-3 N·m, b = 9e-6 N·m·s/rad,
/// m = 6.28e-6 kg·m²; T = 1 ms, the fastest servo rate of Sec. V; K = 2 N·m/rad, our choice,
/// which puts it in region E with σ ≈ 1.30, β ≈ 0.0045, μ ≈ 3.1, like the Table II devices).
///
/// Travel (issue 46), centred on the start: phantom-1.0 ±65 mm (the smallest side of the
/// Phantom 1.0's published 13 × 18 × 25 cm workspace), omega ±55 mm (the 110 mm height of the
/// omega.3's published Ø160 × 110 mm workspace), impulse-engine ±76.2 mm (the Impulse Engine
/// 2000's published 6 × 6 in workspace); delta, freedom6 and mit-toolhandle unbounded (no
/// single-axis figure at hand), maxon-re35 unbounded (the paper's bare motor turns freely).
pub const DEVICES: [Device; 7] = [
    Device {
        name: "delta",
        description: "Force Dimension Delta (Table II)",
        params: linear(0.250, 0.01, 0.883, 30.0, 0.33, 14500.0),
        printed: printed(155.2, 1, 0.002, 3, 2.03, 2),
        force_limit: 20.0,
        travel: None,
    },
    Device {
        name: "freedom6",
        description: "MPB Freedom6 (Table II)",
        params: linear(0.250, 0.01, 0.06, 20.0, 1.0, 2400.0),
        printed: printed(104.2, 1, 0.025, 3, 1.25, 2),
        force_limit: 2.5,
        travel: None,
    },
    Device {
        name: "impulse-engine",
        description: "Immersion Impulse Engine 2000 (Table II)",
        params: linear(0.032, 0.02, 0.024, 31.4, 0.2, 800.0),
        printed: printed(1007.8, 1, 0.13, 2, 0.97, 2),
        force_limit: 8.9,
        travel: Some([-0.0762, 0.0762]),
    },
    Device {
        name: "mit-toolhandle",
        description: "MIT Toolhandle (Table II)",
        params: linear(0.119, 0.001, 0.034, 20.1, 1.0, 3125.0),
        printed: printed(38.19, 2, 0.0003, 4, 0.54, 2),
        force_limit: 8.5,
        travel: None,
    },
    Device {
        name: "omega",
        description: "Force Dimension Omega (Table II)",
        params: linear(0.220, 0.01, 0.147, 10.0, 0.33, 14500.0),
        printed: printed(136.6, 1, 0.002, 3, 1.01, 2),
        force_limit: 12.0,
        travel: Some([-0.055, 0.055]),
    },
    Device {
        name: "phantom-1.0",
        description: "SensAble Phantom 1.0 (Table II)",
        params: linear(0.072, 0.005, 0.038, 29.1, 1.0, 1015.0),
        printed: printed(70.55, 2, 0.004, 3, 1.29, 2),
        force_limit: 8.5,
        travel: Some([-0.065, 0.065]),
    },
    Device {
        name: "maxon-re35",
        description: "Maxon RE35 + 8192-count encoder, Sec. V rig (T = 1 ms, K = 2 N·m/rad chosen)",
        params: PhysicalParams {
            mass: 6.28e-6,
            viscous: 9e-6,
            coulomb: 2e-3,
            resolution: core::f64::consts::TAU / MAXON_COUNTS_PER_REV,
            period_s: 1e-3,
            stiffness: 2.0,
            delay_s: 0.0,
            rotational: true,
        },
        printed: None,
        force_limit: 0.1,
        travel: None,
    },
];

/// Looks a preset up by name (ASCII case-insensitive).
#[must_use]
pub fn find(name: &str) -> Option<&'static Device> {
    DEVICES.iter().find(|d| d.name.eq_ignore_ascii_case(name))
}

/// Names of all presets, comma-separated (for error messages).
pub const NAMES: &str =
    "delta, freedom6, impulse-engine, mit-toolhandle, omega, phantom-1.0, maxon-re35";
