//! The pieces of `hostctl tune` that need no device: identification and release-test verdicts.

pub mod ident;
pub mod release;
