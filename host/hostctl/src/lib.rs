//! `stiffwall-host`: the library behind `hostctl`. Each subcommand lives in its own module under
//! [`cmd`], exposing a clap `Args` struct and a `run` function, so the binary is a thin dispatcher
//! and the end-to-end tests can call the same code. [`device`] adds the connection options of every device
//! command to the protocol client of `stiffwall-client` (they convert into a `stiffwall_client::ConnectSpec`); [`cli_error`] prints errors
//! in the command line's words (refused fields as `--flag`s).
//!
//! Commands never import each other: what several of them share lives beside them —
//! [`output`] (tables and JSON on stdout), [`figure`] (SVG/PNG files by extension),
//! [`plant_args`] (the plant flags, checked by `stiffwall-core`), [`config_flags`] (servo
//! configuration changes), [`session`] (the telemetry stream and recorder), [`analysis`] (the
//! paper's analysis of one device, its (β, σ) figure and the (K, B) frontier figure). The device libraries are used directly, not re-exported:
//! `stiffwall-client` (client, transports, virtual device, sessions, recordings) and
//! `stiffwall-tune` (the tune procedure).
//!
//! Units: as documented per module (SI on the command line, device integers on the wire).
//! Errors: library modules return `thiserror` enums naming the field and its range; the
//! commands' `run` functions add context with `anyhow` at the edge.

pub mod analysis;
pub mod cli_error;
pub mod cmd;
pub mod config_flags;
pub mod device;
pub mod figure;
pub mod monitor_report;
pub mod output;
pub mod plant_args;
pub mod session;
