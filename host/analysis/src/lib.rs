//! `stiffwall-analysis`: the library logic behind `hostctl` that is neither argument parsing,
//! rendering nor the live view: the `hostctl map` file format and its validation and merging
//! ([`map_file`], [`values`]); the paper's analysis of one device ([`device_report`],
//! [`damping`]) and the data of its (K, B) frontier figure ([`frontier`]).
//!
//! Units: as documented per module (dimensionless Table I quantities in map files, SI for a
//! device's physical parameters). Errors: `thiserror` enums whose messages name the field and
//! its allowed range; the command line adds its own context at the edge.

#![warn(missing_docs)]

pub mod atlas;
pub mod damping;
pub mod device_report;
pub mod frontier;
pub mod kb;
pub mod map_file;
pub mod monitor_report;
pub mod plant;
pub mod replay;
pub mod values;
