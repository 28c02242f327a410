//! `stiffwall-analysis`: the library logic behind `hostctl` that is neither argument parsing,
//! figures nor the live view's server:
//! - maps: the `hostctl map` file format, its computation, validation and shard merging
//!   ([`map_file`], [`values`]), the atlas of the paper's analytic lines against a map
//!   ([`atlas`]) and the (K, B) map of one physical device ([`kb`]);
//! - one device: the paper's analysis ([`device_report`], with its text `render_table` and
//!   `list_devices`), its spring + damper part ([`damping`], its text `damping::render`) and
//!   the data of its (K, B) frontier figure ([`frontier`]); the plant as given, a preset and
//!   m, b, c ([`plant`]);
//! - haptic profiles: a profile rendered by the firmware's own servo against the virtual
//!   device's plant from releases and impacts at each element ([`profile_run`]);
//! - scenes: the one-screen summary of a simulated scene, verdict and energy audit
//!   ([`scene_summary`]);
//! - recordings: the replay engines ([`replay`]) and the energy-monitor replay
//!   ([`monitor_report`], its text `monitor_report::render`); the checks of a release test
//!   ([`release`]) and of a servo configuration change ([`config_check`]);
//! - the live view's data ([`live`]): the (β, σ) plane and (B, K) frontier panels, a release
//!   test's decimated trace, the page's test arguments and the telemetry frame, as the page
//!   receives them (its server is `hostctl`'s).
//!
//! Units: as documented per module (dimensionless Table I quantities in map files, SI for a
//! device's physical parameters, raw counts and servo ticks for recordings). Errors: `thiserror`
//! enums whose messages name the field (as the command line spells it) and its allowed range;
//! the command line adds its own context at the edge. Invariants: nothing here parses a command
//! line, draws, prints or serves; a file or value is checked (here, or once by the caller where
//! a function says so, e.g. the (K, B) sweep) before anything is computed from it. Layer 3 of docs/ARCHITECTURE.md: depends
//! on core, proto, sim, the firmware and the client, never on tune or `hostctl`.

#![warn(missing_docs)]

pub mod atlas;
pub mod config_check;
pub mod damping;
pub mod device_report;
pub mod frontier;
pub mod kb;
pub mod live;
pub mod map_file;
pub mod monitor_report;
pub mod plant;
pub mod profile_run;
pub mod release;
pub mod replay;
pub mod scene_summary;
pub mod values;
