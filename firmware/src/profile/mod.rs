//! The haptic profile the servo renders in place of the config's wall (protocol 5,
//! `stiffwall_proto::profile`, whose module header is the normative force law of each element):
//! [`validate`] checks a wire [`Profile`] against the active config and board, [`compile`]
//! turns a valid one into a [`ProfileTable`] of integer and fixed-point gains, and
//! [`ProfileTable::code`] is the servo's per-tick sum of the elements' codes.
//!
//! Units: positions (anchors) are raw encoder counts; every element is evaluated on its own
//! effective count n = ⌊(count − anchor)/2^shift⌋ (saturating, as the config's wall), with dn
//! the backward difference of that effective count; codes are output codes; gains are in the
//! [`Numeric`] back-end's forms, exactly as [`crate::Gains`] derives the config wall's.
//!
//! Invariants: a table compiled from a profile that passed [`validate`] renders every count
//! and every dn without overflow, allocation or panic: each element's code is below 2^31 in
//! magnitude before the saturating sum (the spring part is clamped at its saturation count as
//! the config's wall is, the damper's velocity is clamped to [`crate::config::DAMPER_V_MAX`], a
//! detent's code is at most its strength, ≤ [`crate::config::MAX_LIMIT_CODES`]); the sum of
//! the elements' codes saturates. A one-element `Wall`/`Spring` profile with the config's K, B
//! and damper law at the config's wall position gives bit for bit the codes of the config's
//! one-sided (`Upper`) or two-sided wall. Compiling costs f64 arithmetic and is done in the
//! main loop ([`crate::Device`]), never in a servo tick.
//!
//! Layout: `validate` (the ranges, refusing with a [`ProfileError`]), `compile` (the table),
//! `table` ([`ProfileTable`] and its sum),
//! `element` (one element's code), `detent` (the detents' fixed-point phase and sine).

mod compile;
mod detent;
mod element;
mod table;
mod validate;

#[cfg(test)]
mod tests;

pub use compile::compile;
pub use element::Element;
pub use table::ProfileTable;
pub use validate::{validate, ProfileError};
