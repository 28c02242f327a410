//! `stiffwall-core`: the dimensionless model of Diolaiti et al., "Stability of Haptic Rendering:
//! Discretization, Quantization, Time Delay, and Coulomb Effects" (IEEE T-RO 22(2), 2006).
//!
//! no_std, no allocation. Physical quantities are SI; dimensionless quantities are named as in
//! the paper's Table I (`mu`, `beta`, `sigma`, `tau_d`, `xi`, `xidot`, `phi`).
#![no_std]
#![cfg_attr(not(test), warn(missing_docs))]

pub mod energy;
