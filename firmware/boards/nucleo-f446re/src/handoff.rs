//! Moves a value, once, from `main` into an interrupt handler that then owns it.
//!
//! `main` builds a driver, `put`s it here, then unmasks the interrupt; the handler `take`s it on
//! its first run into a handler-local `static mut` (which cortex-m-rt turns into a safe `&mut`)
//! and never touches the critical section again. Invariants: `take` returns `Some` at most once
//! per `put`; neither call allocates, blocks or panics (a `Cell` swap inside a critical section: no
//! borrow flag, so no "already borrowed" panic path in the handlers).

use core::cell::Cell;
use cortex_m::interrupt::Mutex;

/// A one-shot mailbox from thread mode to an interrupt handler.
pub struct Handoff<T>(Mutex<Cell<Option<T>>>);

impl<T> Handoff<T> {
    /// An empty mailbox (for a `static`).
    pub const fn new() -> Self {
        Self(Mutex::new(Cell::new(None)))
    }

    /// Stores the value (replacing any value not yet taken).
    pub fn put(&self, value: T) {
        cortex_m::interrupt::free(|cs| {
            self.0.borrow(cs).set(Some(value));
        });
    }

    /// Takes the value out, if one was stored.
    #[inline]
    pub fn take(&self) -> Option<T> {
        cortex_m::interrupt::free(|cs| self.0.borrow(cs).take())
    }
}
