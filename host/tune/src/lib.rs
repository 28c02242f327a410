//! `stiffwall-tune`: the tune procedure as a library (what `hostctl tune` and `hostctl
//! experiment` run): identification, release and impact test verdicts, the stiffness search,
//! the (K, B) frontier search, and [`tune`], which runs them on a connected device with typed
//! settings ([`Settings`], checked by [`Settings::validate`]), progress events ([`Progress`]),
//! a cancel token ([`stiffwall_client::Cancel`]) and errors ([`TuneError`]). The result is an
//! [`Outcome`] (serializable both ways, as are the progress events).
//!
//! The modules are private; besides [`tune`], the steps a program may run on their own are
//! re-exported here: one wall test ([`run_test`] of a [`Test`], judged as [`Judging`] says),
//! the verdict of a release ([`classify`] of [`released_counts`]), the device at rest
//! ([`rest_position`]), the predicted limits ([`predict`]). They fail with a [`StepError`].
//!
//! A user's program: tune the virtual device, printing progress, and give up after 2 s (the
//! fast virtual device tunes in a few seconds; a board takes minutes):
//!
//! ```
//! use std::time::{Duration, Instant};
//! use stiffwall_client::{connect, Cancel, ConnectSpec, Pace};
//! use stiffwall_tune::{tune, Progress, Settings, TuneError};
//!
//! let mut client = connect(&ConnectSpec::preset("maxon-re35", Pace::Fast))?;
//! let cancel = Cancel::default();
//! let started = Instant::now();
//! let settings = Settings { dry_run: true, ..Settings::default() };
//! let result = tune(&mut client, &settings, &cancel, &mut |event: Progress| {
//!     println!("{event}");
//!     if started.elapsed() > Duration::from_secs(2) {
//!         cancel.cancel(); // the running test stops; the device keeps its config
//!     }
//! });
//! match result {
//!     Ok(o) => println!("K = {:.4}, B = {:.4e}", o.k_set, o.b_set),
//!     Err(TuneError::Cancelled) => println!("cancelled after 2 s"),
//!     Err(e) => return Err(e.into()),
//! }
//! // Cancelled or not, the device has the config it had before (a dry run saves nothing).
//! assert_eq!(client.get_config()?.stiffness, 0.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

mod approach;
mod error;
mod excite;
mod frontier;
mod ident;
mod identification;
mod judged;
mod launch;
mod left;
mod model_check;
mod outcome;
mod procedure;
pub mod profile;
mod progress;
mod reach;
mod reaim;
mod release;
pub mod repeat;
mod rest;
mod search;
mod settings;
pub mod small_swing;
mod steps;
mod test_set;
mod travel;
mod verdict;
mod verify;
mod workspace;

pub use error::{NoWallPassed, SettingsError, StepError, TuneError};
pub use identification::predict;
pub use launch::Delivered;
pub use left::{DeviceLeft, LEFT_TOLERANCE_COUNTS};
pub use model_check::Evidence;
pub use outcome::{FrontierPoint, IdentifiedReport, Outcome, Predicted, Repeatability};
pub use procedure::tune;
pub use progress::Progress;
pub use release::{classify, released_counts, Verdict};
pub use search::{Found, Trial};
pub use settings::{
    Criterion, Damping, Settings, CONFIRM_BACKOFF, DEFAULT_XIDOT, FRICTION_MISMATCH_MARGIN,
    MISMATCH_MARGIN,
};
pub use steps::{deflection_for, df_equivalent};
pub use test_set::{impact, Test, WallSides};
pub use travel::{TravelSource, Workspace, DEFAULT_WINDOW_LINEAR_M, DEFAULT_WINDOW_ROTARY_RAD};
pub use verify::{
    clear_faults, rest_position, run_test, ChatterReport, Judging, TestResult, TestRun,
};
