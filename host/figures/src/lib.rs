//! `stiffwall-figures`: the figures of stiffwall's host tools, drawn with plotters from the
//! library types of `stiffwall-analysis` and written as SVG or PNG by the file's extension.
//!
//! - [`figure`]: the writer (format by extension, writability check, [`FigureError`]) and the
//!   [`Figure`] trait every figure implements (draw, and describe its words);
//! - [`describe`]: a figure's words as text ([`Description`]: title, axes, legend, values),
//!   the font-independent record of the figure gallery, and the checks of its units;
//! - [`layout`]: wrapped titles and the legend panel beside the plot (pixels);
//! - [`plane`]: the (β, σ) plane of one device report (dimensionless axes);
//! - [`frontier`]: the (B, K) plane of one device, the frontier figure (B in N·s/m, K in N/m;
//!   rotational: N·m·s/rad, N·m/rad);
//! - [`map`]: the panels of a (β, σ) map file (dimensionless axes);
//! - [`atlas`]: an atlas's panel images and its summary (dimensionless axes, fractions);
//! - [`kb_map`]: a (K, B) map file (B and K in SI units as in [`frontier`]);
//! - [`trajectory`]: a simulated scene's ξ(τ) and its energy terms (τ in servo periods);
//! - [`plant_replay`]: a recording replayed through the plant (t in s, counts in ticks);
//! - [`release`]: a release test beside the device's (β, σ) plane (t in s, x in ticks).
//!
//! Errors: the public writers return [`FigureError`], naming the file; drawing functions
//! return [`figure::DrawResult`] (plotters' error or a message). No command line here: the
//! `hostctl` commands choose the file names and add context.

#![warn(missing_docs)]

pub mod atlas;
pub mod describe;
pub mod figure;
pub mod frontier;
pub mod kb_map;
pub mod layout;
pub mod map;
pub mod plane;
pub mod plant_replay;
pub mod release;
pub mod trajectory;

#[cfg(test)]
mod audit_tests;

pub use describe::Description;
pub use figure::{DrawError, DrawResult, Figure, FigureError};
