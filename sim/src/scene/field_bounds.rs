//! One table of plausible ranges per physical field of a device and its loop (issue 47): the
//! same bounds and the same message whether the value comes from a command-line flag
//! (`hostctl analyze --mass`, `--period`, …, `hostctl replay`, `map --k-b`) or from a plant or
//! scene file key (`device.mass_kg`, `controller.period_s`, …). std only, with the scene module.
//!
//! Units: SI; each field states its linear and its rotary unit (kg or kg·m², N·s/m or N·m·s/rad,
//! N or N·m, m or rad, s, N/m or N·m/rad, m/s or rad/s). The bounds cover every preset of
//! `stiffwall_core::devices`, every file of `sim/plants/`, `sim/plants-holdout/` and
//! `sim/scenes/` and the README's examples with room to spare (a test checks the presets and
//! files), and refuse what no haptic device is: a mass of 1e300 kg, a period of a year, a
//! resolution of 1 m. The model notes (`docs/model-notes-sim.md`) list them.
//!
//! Invariants: a value is accepted exactly when it is finite and within `[lo, hi]` of its unit
//! system; [`FieldBounds::allowed`] is one static text per field naming both units and every
//! bound that applies (the virtual damping's β_v = B/(K T) ≤ 1000, the delay's 60 sampling
//! periods), the same whatever the value or where it was given.

use stiffwall_core::params::{check_range, ParamError};

/// The plausible range of one physical field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldBounds {
    /// The field, in words (`mass`).
    pub field: &'static str,
    /// `[lo, hi]` of a linear device, in the linear unit.
    pub linear: (f64, f64),
    /// `[lo, hi]` of a rotary device, in the rotary unit.
    pub rotary: (f64, f64),
    /// The range in words, both units and every bound (the message of every refusal).
    pub allowed: &'static str,
}

/// Inertia m: kg, or kg·m² on a rotary device.
pub const MASS: FieldBounds = FieldBounds {
    field: "mass",
    linear: (1e-9, 1e3),
    rotary: (1e-9, 1e3),
    allowed: "finite and in [1e-9, 1e3] kg (kg·m² on a rotary device)",
};

/// Viscous friction b: N·s/m, or N·m·s/rad.
pub const VISCOUS: FieldBounds = FieldBounds {
    field: "viscous friction",
    linear: (0.0, 1e4),
    rotary: (0.0, 1e4),
    allowed: "finite and in [0, 1e4] N·s/m (N·m·s/rad on a rotary device)",
};

/// Coulomb friction c: N, or N·m.
pub const COULOMB: FieldBounds = FieldBounds {
    field: "Coulomb friction",
    linear: (0.0, 1e4),
    rotary: (0.0, 1e4),
    allowed: "finite and in [0, 1e4] N (N·m on a rotary device)",
};

/// Encoder resolution Δ: m, or rad (2π / counts per revolution).
pub const RESOLUTION: FieldBounds = FieldBounds {
    field: "resolution",
    linear: (1e-10, 1e-2),
    rotary: (
        core::f64::consts::TAU / COUNTS_PER_REV_MAX,
        core::f64::consts::TAU / COUNTS_PER_REV_MIN,
    ),
    allowed: "finite and in [1e-10, 0.01] m, or [6.3e-9, 0.393] rad on a rotary device (16 to \
              1e9 counts per revolution)",
};

/// Fewest counts per revolution of a rotary encoder.
pub const COUNTS_PER_REV_MIN: f64 = 16.0;
/// Most counts per revolution of a rotary encoder.
pub const COUNTS_PER_REV_MAX: f64 = 1e9;

/// Counts per revolution N of a rotary encoder (Δ = 2π/N rad).
pub const COUNTS_PER_REV: FieldBounds = FieldBounds {
    field: "counts per revolution",
    linear: (COUNTS_PER_REV_MIN, COUNTS_PER_REV_MAX),
    rotary: (COUNTS_PER_REV_MIN, COUNTS_PER_REV_MAX),
    allowed: "finite and in [16, 1e9] counts per revolution (a resolution of [6.3e-9, 0.393] rad)",
};

/// Sampling period T: s.
pub const PERIOD: FieldBounds = FieldBounds {
    field: "period",
    linear: (1e-6, 0.1),
    rotary: (1e-6, 0.1),
    allowed: "finite and in [1e-6, 0.1] s (a 10 Hz to 1 MHz servo)",
};

/// Most sampling periods of extra loop delay ([`DELAY`]): the exact sampled linear test's
/// ([`stiffwall_core::criteria::MAX_DELAY_PERIODS`]).
#[allow(clippy::cast_precision_loss)]
pub const DELAY_MAX_PERIODS: f64 = stiffwall_core::criteria::MAX_DELAY_PERIODS as f64;

/// Extra loop delay T_D (amplifier + computation, excluding the ZOH): s; also at most
/// [`DELAY_MAX_PERIODS`] sampling periods (checked by [`FieldBounds::check_delay`]).
pub const DELAY: FieldBounds = FieldBounds {
    field: "delay",
    linear: (0.0, 0.1),
    rotary: (0.0, 0.1),
    allowed: "finite, in [0, 0.1] s and at most 60 sampling periods (60 T)",
};

/// Wall stiffness K: N/m, or N·m/rad.
pub const STIFFNESS: FieldBounds = FieldBounds {
    field: "stiffness",
    linear: (1e-6, 1e8),
    rotary: (1e-6, 1e8),
    allowed: "finite and in [1e-6, 1e8] N/m (N·m/rad on a rotary device)",
};

/// Largest β_v = B/(K T) of the virtual damping ([`DAMPING`]): the solvers' bound.
pub const DAMPING_MAX_BETA_V: f64 = crate::exact::MAX_BETA_V;

/// Virtual damping B of the wall: N·s/m, or N·m·s/rad; also at most
/// [`DAMPING_MAX_BETA_V`]·K·T where the wall's K is known (checked by
/// [`FieldBounds::check_damping`]).
pub const DAMPING: FieldBounds = FieldBounds {
    field: "virtual damping",
    linear: (0.0, 1e4),
    rotary: (0.0, 1e4),
    allowed: "finite, in [0, 1e4] N·s/m (N·m·s/rad on a rotary device) and, with the wall's K, \
              at most 1000 K T (β_v = B/(K T) ≤ 1000)",
};

/// Largest velocity the user reaches: m/s, or rad/s.
pub const VELOCITY: FieldBounds = FieldBounds {
    field: "velocity",
    linear: (0.0, 100.0),
    rotary: (0.0, 1e4),
    allowed: "finite and in [0, 100] m/s, or [0, 1e4] rad/s on a rotary device",
};

/// Every field of the table, in the order above.
pub const ALL: [FieldBounds; 10] = [
    MASS,
    VISCOUS,
    COULOMB,
    RESOLUTION,
    COUNTS_PER_REV,
    PERIOD,
    DELAY,
    STIFFNESS,
    DAMPING,
    VELOCITY,
];

impl FieldBounds {
    /// `[lo, hi]` of the unit system.
    #[must_use]
    pub fn range(&self, rotational: bool) -> (f64, f64) {
        if rotational {
            self.rotary
        } else {
            self.linear
        }
    }

    /// Checks `value` given as `name` (a flag or a TOML key) against the field's range.
    ///
    /// # Errors
    /// [`ParamError`] naming `name`, with the value and [`Self::allowed`].
    pub fn check(
        &self,
        name: &'static str,
        value: f64,
        rotational: bool,
    ) -> Result<f64, ParamError> {
        let (lo, hi) = self.range(rotational);
        check_range(name, value, lo, false, hi, self.allowed)
    }

    /// [`Self::check`] of [`DELAY`] and, with the period T [s], T_D ≤ 60·T: one message for
    /// both.
    ///
    /// # Errors
    /// [`ParamError`] naming `name`, with [`DELAY`]'s text.
    pub fn check_delay(
        name: &'static str,
        value: f64,
        period_s: Option<f64>,
    ) -> Result<f64, ParamError> {
        let v = DELAY.check(name, value, false)?;
        let hi = period_s.map_or(f64::INFINITY, |t| DELAY_MAX_PERIODS * t);
        check_range(name, v, 0.0, false, hi, DELAY.allowed)
    }

    /// [`Self::check`] of [`DAMPING`] and, with the wall's K·T [N·s/m], B ≤ 1000·K·T: one
    /// message for both.
    ///
    /// # Errors
    /// [`ParamError`] naming `name`, with [`DAMPING`]'s text.
    pub fn check_damping(
        name: &'static str,
        value: f64,
        rotational: bool,
        k_times_t: Option<f64>,
    ) -> Result<f64, ParamError> {
        let v = DAMPING.check(name, value, rotational)?;
        let hi = k_times_t.map_or(f64::INFINITY, |kt| DAMPING_MAX_BETA_V * kt);
        check_range(name, v, 0.0, false, hi, DAMPING.allowed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each bound is refused just outside and accepted on it, in both unit systems, and every
    /// refusal carries the field's one text.
    #[test]
    fn bounds_are_inclusive_and_the_text_is_the_fields() {
        for f in ALL {
            for rot in [false, true] {
                let (lo, hi) = f.range(rot);
                assert!(f.check("x", lo, rot).is_ok(), "{} lo", f.field);
                assert!(f.check("x", hi, rot).is_ok(), "{} hi", f.field);
                for bad in [
                    hi * (1.0 + 1e-9),
                    if lo > 0.0 { lo * (1.0 - 1e-9) } else { -1e-300 },
                    f64::NAN,
                    f64::INFINITY,
                ] {
                    let e = f.check("x", bad, rot).unwrap_err();
                    assert_eq!(e.allowed(), f.allowed, "{} {bad}", f.field);
                    assert_eq!(e.name(), "x");
                }
            }
        }
    }

    /// The stated numbers are the checked ones (the text is written by hand): `[lo, hi]` of
    /// the linear range, and of the rotary one where it differs, each number in its shorter
    /// spelling (`1e-9`, `0.1`, `100`).
    #[test]
    fn the_text_states_the_checked_numbers() {
        let num = |x: f64| {
            let (plain, sci) = (format!("{x}"), format!("{x:e}"));
            if sci.len() < plain.len() {
                sci
            } else {
                plain
            }
        };
        let pair = |(lo, hi): (f64, f64)| format!("[{}, {}]", num(lo), num(hi));
        for f in ALL {
            assert!(
                f.allowed.contains(&pair(f.linear)),
                "{}: {}",
                f.field,
                f.allowed
            );
            if f.rotary != f.linear && f.field != "resolution" {
                assert!(
                    f.allowed.contains(&pair(f.rotary)),
                    "{}: {}",
                    f.field,
                    f.allowed
                );
            }
        }
        // 2π/1e9 and 2π/16 rad, stated to 2 and 3 digits.
        assert!(RESOLUTION.allowed.contains("[6.3e-9, 0.393] rad"));
        assert!((RESOLUTION.rotary.0 - 6.283e-9).abs() < 1e-12);
        assert_eq!(RESOLUTION.rotary.1, core::f64::consts::FRAC_PI_8, "2π/16");
    }

    /// The second bounds are the ones the text states.
    #[test]
    fn second_bounds_are_stated() {
        assert_eq!(DELAY_MAX_PERIODS, 60.0);
        assert!(DELAY.allowed.contains("at most 60 sampling periods"));
        assert_eq!(DAMPING_MAX_BETA_V, 1000.0);
        assert!(DAMPING.allowed.contains("at most 1000 K T"));
    }

    /// Two bounds, one message: the delay in s and in periods, the damping in N·s/m and β_v.
    #[test]
    fn second_bounds_share_the_message() {
        let e1 = FieldBounds::check_delay("d", -1.0, Some(1e-3)).unwrap_err();
        let e2 = FieldBounds::check_delay("d", 0.061, Some(1e-3)).unwrap_err();
        assert_eq!(e1.allowed(), e2.allowed());
        assert!(FieldBounds::check_delay("d", 0.06, Some(1e-3)).is_ok());
        assert!(FieldBounds::check_delay("d", 0.061, None).is_ok());
        let e1 = FieldBounds::check_damping("b", -1.0, false, Some(2.4)).unwrap_err();
        let e2 = FieldBounds::check_damping("b", 2401.0, false, Some(2.4)).unwrap_err();
        let e3 = FieldBounds::check_damping("b", 2e4, false, None).unwrap_err();
        assert_eq!(e1.allowed(), e2.allowed());
        assert_eq!(e1.allowed(), e3.allowed());
        assert!(FieldBounds::check_damping("b", 2400.0, false, Some(2.4)).is_ok());
    }
}
