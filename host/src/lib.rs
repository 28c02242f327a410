//! `stiffwall-host`: the library behind `hostctl`. Each subcommand lives in its own module under
//! [`cmd`], exposing a clap `Args` struct and a `run` function, so the binary is a thin dispatcher
//! and the end-to-end tests can call the same code. [`device`] holds the transports and the
//! protocol client shared by every device command.

pub mod cmd;
pub mod device;
pub mod monitor_report;
pub mod recording;
pub mod tune;
