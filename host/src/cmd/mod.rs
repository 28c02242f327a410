//! One module per `hostctl` subcommand.

pub mod analyze;
