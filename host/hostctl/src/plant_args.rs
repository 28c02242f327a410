//! The plant flags shared by `hostctl analyze` and `hostctl replay`: a device preset and the
//! friction model's m, b, c overriding its fields.
//!
//! Units: SI; for a linear device m [kg], b [N·s/m], c [N]; for a rotational one m [kg·m²],
//! b [N·m·s/rad], c [N·m]. Invariants: the ranges are `stiffwall-core`'s
//! ([`stiffwall_core::params::check_positive`], [`stiffwall_core::params::check_non_negative`]):
//! m finite and > 0, b and c finite and >= 0; a refused value is an error naming the flag, its
//! allowed range and the value. A preset name is matched case-insensitively against
//! [`stiffwall_core::devices`]. The flags are resolved by `stiffwall_analysis::plant`
//! ([`PlantSpec`]); the methods here hand them over.

pub use stiffwall_analysis::plant::{Friction, GivenFriction, PlantSpec, PlantSpecError};
use stiffwall_core::devices::Device;

/// Plant flags: a preset and overrides of its m, b, c.
#[derive(Debug, Clone, Default, PartialEq, clap::Args)]
pub struct PlantArgs {
    /// Device preset (see `hostctl analyze --list-devices`); the other plant flags override
    /// its fields.
    #[arg(long = "device", value_name = "NAME")]
    pub device: Option<String>,
    /// Inertia m [kg, or kg·m² for a rotational device], > 0.
    #[arg(long, allow_negative_numbers = true)]
    pub mass: Option<f64>,
    /// Viscous friction b [N·s/m, or N·m·s/rad], >= 0.
    #[arg(long, allow_negative_numbers = true)]
    pub viscous: Option<f64>,
    /// Coulomb friction c [N, or N·m], >= 0.
    #[arg(long, allow_negative_numbers = true)]
    pub coulomb: Option<f64>,
}

impl PlantArgs {
    /// The plant as given, for `stiffwall_analysis::plant`.
    #[must_use]
    pub fn spec(&self) -> PlantSpec {
        PlantSpec {
            device: self.device.clone(),
            mass: self.mass,
            viscous: self.viscous,
            coulomb: self.coulomb,
        }
    }

    /// Whether any plant flag was given.
    #[must_use]
    pub fn any(&self) -> bool {
        self.spec().any()
    }

    /// The preset named by `--device`, if given.
    ///
    /// # Errors
    /// [`PlantSpecError::UnknownDevice`].
    pub fn preset(&self) -> Result<Option<&'static Device>, PlantSpecError> {
        self.spec().preset()
    }

    /// `--mass`, `--viscous`, `--coulomb` as given, each checked against core's range.
    ///
    /// # Errors
    /// [`PlantSpecError::OutOfRange`] for the first flag out of range.
    pub fn overrides(&self) -> Result<GivenFriction, PlantSpecError> {
        self.spec().overrides()
    }

    /// m, b, c from the preset (`--device`, else `fallback_device`), then the flags.
    ///
    /// # Errors
    /// An unknown preset, a flag out of range, or a field given by neither.
    pub fn friction(&self, fallback_device: Option<&str>) -> Result<Friction, PlantSpecError> {
        self.spec().friction(fallback_device)
    }
}
