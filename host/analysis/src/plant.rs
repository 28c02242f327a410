//! The plant of `hostctl analyze`, `hostctl replay` and `hostctl map --k-b` as given on the
//! command line ([`PlantSpec`]): a device preset and the friction model's m, b, c overriding
//! its fields, resolved into a [`Friction`].
//!
//! Units: SI; for a linear device m in kg, b in N·s/m, c in N; for a rotational one m in kg·m²,
//! b in N·m·s/rad, c in N·m. Invariants: the ranges are the plausible ranges of
//! `stiffwall_sim::scene::field_bounds` ([`MASS`], [`VISCOUS`], [`COULOMB`]: the same as the
//! plant file's `device.mass_kg`, `viscous_ns_per_m`, `coulomb_n`, with the same message); a
//! refused value is an error naming the flag, its allowed range and the value. A preset name is
//! matched case-insensitively against [`stiffwall_core::devices`].

use stiffwall_core::devices::{self, Device};
use stiffwall_sim::scene::field_bounds::{FieldBounds, COULOMB, MASS, VISCOUS};

/// A plant as given: a preset and overrides of its m, b, c (each named by its flag in
/// errors, `--mass`, `--viscous`, `--coulomb`, `--device`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlantSpec {
    /// Device preset name (`stiffwall_core::devices`), matched case-insensitively.
    pub device: Option<String>,
    /// Inertia m [kg, or kg·m² for a rotational device], > 0.
    pub mass: Option<f64>,
    /// Viscous friction b [N·s/m, or N·m·s/rad], >= 0.
    pub viscous: Option<f64>,
    /// Coulomb friction c [N, or N·m], >= 0.
    pub coulomb: Option<f64>,
}

/// A plant flag that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlantSpecError {
    /// `--device` names no preset.
    #[error("unknown device {name:?} (--device must be one of: {allowed})")]
    UnknownDevice {
        /// The name given.
        name: String,
        /// The preset names.
        allowed: &'static str,
    },
    /// A value outside its field's plausible range.
    #[error("--{flag} must be {range} (got {value:?})")]
    OutOfRange {
        /// The flag, without dashes (`mass`).
        flag: &'static str,
        /// The value given.
        value: f64,
        /// The allowed range ([`FieldBounds::allowed`]).
        range: &'static str,
    },
    /// Neither a preset nor all of m, b, c.
    #[error(
        "the plant needs m, b and c: give --device NAME or all of --mass, --viscous and --coulomb"
    )]
    Incomplete,
}

/// `--mass`, `--viscous`, `--coulomb` as given (None: not given), checked.
pub type GivenFriction = (Option<f64>, Option<f64>, Option<f64>);

/// The plant's friction model, resolved from a preset and flags.
#[derive(Debug, Clone, PartialEq)]
pub struct Friction {
    /// Inertia m.
    pub mass: f64,
    /// Viscous friction b.
    pub viscous: f64,
    /// Coulomb friction c.
    pub coulomb: f64,
    /// Where the values came from, e.g. `preset omega + --mass`.
    pub source: String,
}

fn checked(
    flag: &'static str,
    value: Option<f64>,
    bounds: &FieldBounds,
) -> Result<Option<f64>, PlantSpecError> {
    // m, b and c have one range for both unit systems.
    value
        .map(|v| {
            bounds
                .check(flag, v, false)
                .map_err(|_| PlantSpecError::OutOfRange {
                    flag,
                    value: v,
                    range: bounds.allowed,
                })
        })
        .transpose()
}

impl PlantSpec {
    /// Whether any plant flag was given.
    #[must_use]
    pub fn any(&self) -> bool {
        self.device.is_some()
            || self.mass.is_some()
            || self.viscous.is_some()
            || self.coulomb.is_some()
    }

    /// The preset named by `--device`, if given.
    ///
    /// # Errors
    /// [`PlantSpecError::UnknownDevice`].
    pub fn preset(&self) -> Result<Option<&'static Device>, PlantSpecError> {
        self.device.as_deref().map(find).transpose()
    }

    /// `--mass`, `--viscous`, `--coulomb` as given, each checked against its field's range.
    ///
    /// # Errors
    /// [`PlantSpecError::OutOfRange`] for the first flag out of range.
    pub fn overrides(&self) -> Result<GivenFriction, PlantSpecError> {
        Ok((
            checked("mass", self.mass, &MASS)?,
            checked("viscous", self.viscous, &VISCOUS)?,
            checked("coulomb", self.coulomb, &COULOMB)?,
        ))
    }

    /// m, b, c from the preset (`--device`, else `fallback_device`), then the flags.
    ///
    /// # Errors
    /// An unknown preset, a flag out of range, or a field given by neither.
    pub fn friction(&self, fallback_device: Option<&str>) -> Result<Friction, PlantSpecError> {
        let (mass, viscous, coulomb) = self.overrides()?;
        let (name, from_recording) = match (&self.device, fallback_device) {
            (Some(n), _) => (Some(n.as_str()), false),
            (None, f) => (f, true),
        };
        let preset = name.map(find).transpose()?;
        let mut source = Vec::new();
        if let (Some(n), Some(_)) = (name, preset) {
            source.push(format!(
                "preset {n}{}",
                if from_recording {
                    " (from the recording)"
                } else {
                    ""
                }
            ));
        }
        for (flag, v) in [
            ("--mass", mass),
            ("--viscous", viscous),
            ("--coulomb", coulomb),
        ] {
            if v.is_some() {
                source.push(flag.to_string());
            }
        }
        let pick = |flag: Option<f64>, field: fn(&Device) -> f64| flag.or(preset.map(field));
        match (
            pick(mass, |d| d.params.mass),
            pick(viscous, |d| d.params.viscous),
            pick(coulomb, |d| d.params.coulomb),
        ) {
            (Some(mass), Some(viscous), Some(coulomb)) => Ok(Friction {
                mass,
                viscous,
                coulomb,
                source: source.join(" + "),
            }),
            _ => Err(PlantSpecError::Incomplete),
        }
    }
}

fn find(name: &str) -> Result<&'static Device, PlantSpecError> {
    devices::find(name).ok_or_else(|| PlantSpecError::UnknownDevice {
        name: name.to_string(),
        allowed: devices::NAMES,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Every value, finite or not, is accepted exactly when it is finite and inside the
        /// field's stated range (written out here), and a refusal names the flag and the value.
        #[test]
        fn flags_accept_exactly_the_fields_range(v in proptest::num::f64::ANY) {
            for (flag, a, in_range) in [
                ("--mass", args(None, Some(v), None, None), (1e-9..=1e3).contains(&v)),
                ("--viscous", args(None, None, Some(v), None), (0.0..=1e4).contains(&v)),
                ("--coulomb", args(None, None, None, Some(v)), (0.0..=1e4).contains(&v)),
            ] {
                match a.overrides() {
                    Ok(_) => prop_assert!(in_range, "{flag} {v} accepted"),
                    Err(e) => {
                        prop_assert!(!in_range, "{flag} {v} refused: {e}");
                        let text = e.to_string();
                        prop_assert!(text.starts_with(flag), "{text}");
                        prop_assert!(text.ends_with(&format!("(got {v:?})")), "{text}");
                    }
                }
            }
        }
    }

    fn args(device: Option<&str>, m: Option<f64>, b: Option<f64>, c: Option<f64>) -> PlantSpec {
        PlantSpec {
            device: device.map(str::to_string),
            mass: m,
            viscous: b,
            coulomb: c,
        }
    }

    #[test]
    fn errors_name_flag_range_and_value_with_one_message_per_field() {
        let mass = "finite and in [1e-9, 1e3] kg (kg·m² on a rotary device)";
        for v in [-1.0, 0.0, 1e300] {
            let e = args(None, Some(v), None, None).overrides().unwrap_err();
            assert_eq!(e.to_string(), format!("--mass must be {mass} (got {v:?})"));
        }
        let e = args(None, None, Some(-0.1), None).overrides().unwrap_err();
        assert_eq!(
            e.to_string(),
            "--viscous must be finite and in [0, 1e4] N·s/m (N·m·s/rad on a rotary device) \
             (got -0.1)"
        );
        let e = args(None, None, None, Some(f64::NAN))
            .overrides()
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "--coulomb must be finite and in [0, 1e4] N (N·m on a rotary device) (got NaN)"
        );
        // Zero friction is allowed, zero mass is not; the bounds themselves are.
        assert!(args(None, Some(0.0), None, None).overrides().is_err());
        assert!(args(None, Some(1e-9), Some(0.0), Some(0.0))
            .overrides()
            .is_ok());
        assert!(args(None, Some(1e3), Some(1e4), Some(1e4))
            .overrides()
            .is_ok());
    }

    #[test]
    fn preset_then_flags_with_their_source() {
        let omega = devices::find("omega").unwrap().params;
        let f = args(Some("OMEGA"), Some(2.0), None, None)
            .friction(None)
            .unwrap();
        assert_eq!(
            (f.mass, f.viscous, f.coulomb),
            (2.0, omega.viscous, omega.coulomb)
        );
        assert_eq!(f.source, "preset OMEGA + --mass");
        let f = args(None, None, None, Some(0.5))
            .friction(Some("omega"))
            .unwrap();
        assert_eq!((f.mass, f.coulomb), (omega.mass, 0.5));
        assert_eq!(f.source, "preset omega (from the recording) + --coulomb");
        let f = args(None, Some(1.0), Some(0.0), Some(0.0))
            .friction(None)
            .unwrap();
        assert_eq!(f.source, "--mass + --viscous + --coulomb");
    }

    #[test]
    fn unknown_or_incomplete_is_refused() {
        let e = args(Some("nope"), None, None, None)
            .friction(None)
            .unwrap_err();
        assert!(e.to_string().starts_with("unknown device \"nope\""), "{e}");
        assert!(e.to_string().contains("phantom-1.0"), "{e}");
        assert!(matches!(
            args(None, Some(1.0), Some(0.0), None).friction(None),
            Err(PlantSpecError::Incomplete)
        ));
        assert!(!PlantSpec::default().any());
        assert!(args(None, None, None, Some(0.0)).any());
    }
}
