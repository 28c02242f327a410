//! Haptic profiles (issue 43): the profile file (TOML, `profiles/README.md`), its validation
//! and lowering to the wire [`stiffwall_proto::Profile`] for one device, and the check of a
//! profile against what a tune verified on that device.
//!
//! - [`file`](mod@file): the file's layout as written ([`ProfileFile::from_toml`]; unknown keys, tables
//!   and kinds refused).
//! - [`lower`](mod@lower): every field checked (finite, in its plausible range, `stiffwall_sim`'s
//!   `field_bounds` where the field has one), positions rounded to counts, `end-stops` as two
//!   walls, at most 16 wire elements, no nonsensical overlap ([`overlap`]);
//!   [`Lowered::wire`] is the profile sent to the device.
//! - [`envelope`]: a tune's [`crate::Outcome`] as limits, K_limit(B) = min(margin × K*(B),
//!   quiet ceiling).
//! - [`check`](check()): each element's local K and B against its limit, detent centring,
//!   the verdict; [`render`](fn@render) writes it as text, serde as JSON.
//!
//! Units: a profile's axis fixes them: linear m, N/m, N·s/m, N; rotary rad, N·m/rad,
//! N·m·s/rad, N·m; positions on the wire are raw encoder counts (position 0 = count 0).
//!
//! Invariants: nothing is produced from a file with an error ([`ProfileError`] names the
//! element by number and kind, the key and the allowed range); a [`Lowered`] profile is one
//! the device's validation accepts (every number finite and in range, ≤ 16 elements).
//!
//! ```
//! use stiffwall_tune::profile::{check, lower, render, Device, Envelope, Point, ProfileFile};
//! use stiffwall_proto::DamperLaw;
//!
//! let file = ProfileFile::from_toml(
//!     "[profile]\nname = \"wall\"\naxis = \"linear\"\n\n[[element]]\nkind = \"wall\"\n\
//!      at = 0.01\nside = \"upper\"\nstiffness = 400\n",
//! )?;
//! let device = Device { rotational: false, resolution: 1e-5 };
//! let envelope = Envelope {
//!     source: "by hand".into(),
//!     device,
//!     frontier: vec![Point { b: 0.0, k: Some(600.0), damper: DamperLaw::default() }],
//!     margin: 0.8,
//!     quiet_ceiling: 2000.0,
//!     coulomb: 0.01,
//!     static_friction: 0.01,
//!     force_limit: None,
//! };
//! let report = check(&lower(&file, &device)?, &envelope);
//! assert!(report.pass); // 400 N/m ≤ 0.8 × 600 = 480 N/m
//! print!("{}", render(&report));
//! # Ok::<(), stiffwall_tune::profile::ProfileError>(())
//! ```

pub mod check;
pub mod envelope;
pub mod error;
pub mod file;
pub mod lower;
pub mod overlap;
pub mod placed;
pub mod render;
pub mod units;

pub use check::{check, Centring, ElementCheck, Report, Strongest};
pub use envelope::{Envelope, Point, Verified, B_MATCH};
pub use error::{Place, ProfileError};
pub use file::{Axis, ElementSpec, Positions, ProfileFile};
pub use lower::lower;
pub use placed::{Lowered, Origin, Placed};
pub use render::{render, render_wire};
pub use units::{Device, Units};

#[cfg(test)]
mod tests;
