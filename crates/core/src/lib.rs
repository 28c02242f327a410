//! `stiffwall-core`: the dimensionless model of Diolaiti et al., "Stability of Haptic Rendering:
//! Discretization, Quantization, Time Delay, and Coulomb Effects" (IEEE T-RO 22(2), 2006).
//!
//! no_std, no allocation. Physical quantities are SI; dimensionless quantities are named as in
//! the paper's Table I (`mu`, `beta`, `sigma`, `tau_d`, `xi`, `xidot`, `phi`).
//!
//! Modules: [`params`] (Table I conversions and validation), [`regions`] (regions A–E, F1/F2,
//! criteria (12), (15), (16), (19)), [`limits`] (largest stable K), [`energy`] (H_T (35) and the
//! bounds (40), (47), (58)), [`describing`] (Sec. VII, (62)–(75)), [`criteria`] (classic
//! criteria: Colgate–Schenkel, Abbott–Okamura, Gil–Avello–Rubio, Hulin et al.), [`devices`] (Table II and Sec. V presets) and [`rest`] (when a wall comes to rest: the one
//! rule every check uses, chatter, the quiet ceiling 2c/Δ).
#![no_std]
#![cfg_attr(not(test), warn(missing_docs))]

pub mod criteria;
pub mod describing;
pub mod devices;
pub mod energy;
pub mod limits;
pub mod monitor;
pub mod params;
pub mod regions;
pub mod rest;

pub use params::{Dimensionless, ParamError, PhysicalParams};
pub use regions::Region;
