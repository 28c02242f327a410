//! One module per `hostctl` subcommand: each exposes a clap `Args` struct and a `run` function.

pub mod analyze;
pub mod config;
pub mod experiment;
pub mod faults;
pub mod info;
pub mod map;
pub mod profile;
pub mod record;
pub mod replay;
pub mod simulate;
pub mod stream;
pub mod tune;
#[cfg(feature = "ui")]
pub mod ui;
pub mod r#virtual;
