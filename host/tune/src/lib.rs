//! `stiffwall-tune`: the tune procedure as a library (what `hostctl tune` and `hostctl
//! experiment` run): identification, release and impact test verdicts, the stiffness search,
//! the (K, B) frontier search, and [`tune`], which runs them on a connected device with typed
//! settings ([`Settings`], checked by [`Settings::validate`]), progress events ([`Progress`]),
//! a cancel token ([`stiffwall_client::Cancel`]) and errors ([`TuneError`]).
//!
//! A user's program: tune the virtual device, printing progress, and give up after 2 s (the
//! fast virtual device tunes in a few seconds; a board takes minutes):
//!
//! ```
//! use std::time::{Duration, Instant};
//! use stiffwall_client::{connect, Cancel, ConnectSpec};
//! use stiffwall_tune::{tune, Progress, Settings, TuneError};
//!
//! let mut client = connect(&ConnectSpec::preset("maxon-re35", true))?;
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

pub mod error;
pub mod excite;
pub mod frontier;
pub mod ident;
pub mod judged;
pub mod launch;
pub mod model_check;
pub mod outcome;
pub mod procedure;
pub mod progress;
pub mod release;
pub mod search;
pub mod settings;
pub mod steps;
pub mod verdict;
pub mod verify;

pub use error::{SettingsError, TuneError};
pub use outcome::Outcome;
pub use procedure::tune;
pub use progress::Progress;
pub use settings::{Damping, Settings};
