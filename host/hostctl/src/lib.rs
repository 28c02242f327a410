//! `stiffwall-host`: the library behind `hostctl`. Each subcommand lives in its own module under
//! [`cmd`], exposing a clap `Args` struct and a `run` function, so the binary is a thin dispatcher
//! and the end-to-end tests can call the same code. [`device`] adds the connection options of every device
//! command to the protocol client of `stiffwall-client` (they convert into a `stiffwall_client::ConnectSpec`); [`cli_error`] prints errors
//! in the command line's words (refused fields as `--flag`s).
//!
//! The library logic (map files, atlas, (K, B) maps, the device report, replay and monitor
//! engines, the plant as given, release checks) is the `stiffwall-analysis` crate; this crate
//! parses arguments, renders text (the figures are drawn by `stiffwall-figures`, re-exported
//! under the old paths) and serves the live view (`cmd::ui`).
//!
//! Commands never import each other: what several of them share lives beside them —
//! [`output`] (tables and JSON on stdout), [`figure`] (SVG/PNG files by extension, from
//! `stiffwall-figures`),
//! [`plant_args`] (the plant flags, resolved by `stiffwall_analysis::plant`), [`config_flags`] (servo
//! configuration changes), [`session`] (the telemetry stream and recorder), [`analysis`] (the
//! paper's analysis of one device with its text, its (β, σ) figure and the (K, B) frontier
//! figure). The live view (`cmd::ui`) is a command too: it shares the release test's
//! configuration with `experiment release` through `stiffwall_analysis::release` and the
//! configuration table with `config get` through [`output`]. The libraries are used directly:
//! `stiffwall-client` (client, transports, virtual device, sessions, recordings) and
//! `stiffwall-tune` (the tune procedure) are not re-exported; of `stiffwall-analysis`
//! (computation and text) and `stiffwall-figures` (pictures), [`monitor_report`] and [`figure`]
//! are re-exported under the paths they had when they lived here.
//!
//! Units: as documented per module (SI on the command line, device integers on the wire).
//! Errors: library modules return `thiserror` enums naming the field and its range; the
//! commands' `run` functions add context with `anyhow` at the edge.

pub mod analysis;
pub mod cli_error;
pub mod cmd;
pub mod config_flags;
pub mod device;
/// The energy-monitor replay and its text (`stiffwall-analysis`), re-exported under its old path.
pub use stiffwall_analysis::monitor_report;
/// The figure writer (the `stiffwall-figures` crate's), re-exported under its old path.
pub use stiffwall_figures::figure;
pub mod output;
pub mod plant_args;
pub mod session;
