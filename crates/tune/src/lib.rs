//! `hostctl tune` and `hostctl experiment`: identification, release-test verdicts, the stiffness
//! search, and the procedure that runs them on a device.

pub mod excite;
pub mod frontier;
pub mod ident;
pub mod judged;
pub mod launch;
pub mod model_check;
pub mod outcome;
pub mod procedure;
pub mod release;
pub mod search;
pub mod settings;
pub mod steps;
pub mod verdict;
pub mod verify;
