//! One module per `hostctl` subcommand: each exposes a clap `Args` struct and a `run` function.

pub mod analyze;
pub mod simulate;
pub mod map;
pub mod info;
pub mod config;
pub mod stream;
pub mod record;
pub mod replay;
pub mod experiment;
pub mod tune;
