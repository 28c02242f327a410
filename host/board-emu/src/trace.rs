//! `STIFFWALL_EMU_TRACE`: whether the emulator logs its traffic on stderr (pty bytes, force
//! output changes, IWDG and flash operations), read from the environment once per process.
//!
//! Units: none. Invariant: the variable is read at the first question and the answer holds for
//! the rest of the run (any value, even empty, turns tracing on).

use std::sync::OnceLock;

/// Whether `STIFFWALL_EMU_TRACE` is set.
pub fn enabled() -> bool {
    static ENABLED: OnceLock<bool> = OnceLock::new();
    *ENABLED.get_or_init(|| std::env::var_os("STIFFWALL_EMU_TRACE").is_some())
}
