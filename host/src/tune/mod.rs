//! The pieces of `hostctl tune` that need no device: identification, release-test verdicts
//! and the stiffness search.

pub mod ident;
pub mod release;
pub mod search;
