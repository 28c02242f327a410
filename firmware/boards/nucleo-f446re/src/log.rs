//! Optional logging: defmt over RTT with the `defmt` feature, nothing without it.
//!
//! Units: none (log text only). Invariants: these macros are called from thread mode, boot and
//! the fault handlers only, never from the servo interrupt (TIM7) or the serial interrupt, so
//! logging can't add time to the servo path. Without the feature they expand to code that only
//! borrows their arguments (no unused-variable warnings, no code in the image). With it, the
//! RTT buffer is written in a short critical section; `probe-rs run` reads and decodes it.

#[cfg(feature = "defmt")]
use defmt_rtt as _;

/// Logs at defmt level `$level` (`info`, `warn`, `error`) through defmt, or does nothing.
macro_rules! log_at {
    ($level:ident, $fmt:literal $(, $arg:expr)* $(,)?) => {{
        #[cfg(feature = "defmt")]
        defmt::$level!($fmt $(, $arg)*);
        #[cfg(not(feature = "defmt"))]
        {
            $(let _ = &$arg;)*
        }
    }};
}

/// An informational message (boot, config saves).
macro_rules! info {
    ($($t:tt)*) => { $crate::log::log_at!(info, $($t)*) };
}

/// A fault latched by the servo's supervisor (defmt's `warn`; only the `defmt` build watches the
/// fault bits, so only it has this macro).
#[cfg(feature = "defmt")]
macro_rules! warning {
    ($($t:tt)*) => { $crate::log::log_at!(warn, $($t)*) };
}

/// A failure (flash errors, hard faults, panics).
macro_rules! error {
    ($($t:tt)*) => { $crate::log::log_at!(error, $($t)*) };
}

#[cfg(feature = "defmt")]
pub(crate) use warning;
pub(crate) use {error, info, log_at};
