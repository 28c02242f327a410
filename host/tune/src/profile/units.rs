//! The device a profile is lowered for and checked on (its resolution Δ and whether it turns),
//! the units of its axis, and numbers to about 4 significant digits for the reports.
//!
//! Units: Δ in m, or rad on a rotary device (2π / counts per revolution); a linear axis is in
//! m, N/m, N·s/m, N, a rotary one in rad, N·m/rad, N·m·s/rad, N·m.

use serde::{Deserialize, Serialize};

/// The device a profile is lowered for: position 0 is count 0, count n spans [nΔ, (n+1)Δ).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Device {
    /// A rotary device (positions in rad).
    pub rotational: bool,
    /// Δ, m (rad), > 0.
    pub resolution: f64,
}

impl Device {
    /// A connected device's, from its `HelloReply`: rotary when it reports counts per
    /// revolution (Δ = 2π/counts), else linear with its resolution.
    #[must_use]
    pub fn of_info(info: &stiffwall_proto::DeviceInfo) -> Self {
        if info.counts_per_rev > 0 {
            Self {
                rotational: true,
                resolution: core::f64::consts::TAU / f64::from(info.counts_per_rev),
            }
        } else {
            Self {
                rotational: false,
                resolution: f64::from(info.resolution),
            }
        }
    }

    /// Counts per revolution 2π/Δ (of a rotary device; a linear device's is meaningless).
    #[must_use]
    pub fn counts_per_rev(&self) -> f64 {
        core::f64::consts::TAU / self.resolution
    }

    /// The units of the device's axis.
    #[must_use]
    pub fn units(&self) -> Units {
        Units::of(self.rotational)
    }
}

/// The units of one axis, as the reports write them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Units {
    /// m or rad.
    pub position: &'static str,
    /// N/m or N·m/rad.
    pub stiffness: &'static str,
    /// N·s/m or N·m·s/rad.
    pub damping: &'static str,
    /// N or N·m.
    pub force: &'static str,
}

impl Units {
    /// Linear or rotary units.
    #[must_use]
    pub fn of(rotational: bool) -> Self {
        if rotational {
            Self {
                position: "rad",
                stiffness: "N·m/rad",
                damping: "N·m·s/rad",
                force: "N·m",
            }
        } else {
            Self {
                position: "m",
                stiffness: "N/m",
                damping: "N·s/m",
                force: "N",
            }
        }
    }
}

/// `x` to 4 significant digits: plain between 1e-3 and 1e5 (trailing zeros kept, `2.400`),
/// else in exponent form (`5.462e-3`); 0 as `0`.
#[must_use]
pub fn sig(x: f64) -> String {
    if x == 0.0 {
        return "0".to_owned();
    }
    if !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if (1e-3..1e5).contains(&a) {
        // Digits after the point so that 4 are significant; rounding may carry to 10^(e+1),
        // which then shows one digit more than 4 (9.9996 → 10.000), never fewer.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_significant_digits() {
        assert_eq!(sig(2.4), "2.400");
        assert_eq!(sig(1306.56), "1307");
        assert_eq!(sig(0.0054617), "0.005462");
        assert_eq!(sig(5.4617e-4), "5.462e-4");
        assert_eq!(sig(-0.1309), "-0.1309");
        assert_eq!(sig(2.5e6), "2.500e6");
        assert_eq!(sig(0.0), "0");
    }

    #[test]
    fn counts_per_rev_of_the_paper_rig() {
        let d = Device {
            rotational: true,
            resolution: core::f64::consts::TAU / 8192.0,
        };
        assert!((d.counts_per_rev() - 8192.0).abs() < 1e-9);
        assert_eq!(d.units().stiffness, "N·m/rad");
    }
}
