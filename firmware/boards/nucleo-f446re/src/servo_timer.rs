//! The servo tick: TIM7 (basic timer, no pins) update interrupt at the configured servo rate.
//!
//! Units: rate in Hz; TIM7 runs from the APB1 timer clock (90 MHz at the 180 MHz system clock).
//! 1 kHz is exact (prescaler 2 × reload 45 000, zero drift); 2, 5 and 10 kHz are exact too, and
//! any other rate is within 3·10⁻⁵ of the request. Invariants: the timer is free running and
//! auto-reloading, so ticks are periodic no matter how long the handler takes (a tick that
//! overran its period merges the next update: one tick is skipped, never run twice); the handler
//! calls `ack` exactly once per entry. Rate changes happen inside the handler (`request_rate` →
//! `apply_rate_request`), so thread mode never touches TIM7. Priority: below USART2 (serial
//! bytes are never lost), above thread mode.

use core::sync::atomic::{AtomicU32, Ordering};
use stm32f4xx_hal::{
    pac::TIM7,
    prelude::*,
    rcc::Rcc,
    timer::{CounterHz, Event, Flag},
};

static TICKS: AtomicU32 = AtomicU32::new(0);
/// A servo rate requested by thread mode (Hz), 0 = none pending.
static RATE_REQUEST: AtomicU32 = AtomicU32::new(0);

/// Asks the servo interrupt to reprogram TIM7 to `rate_hz` at its next tick (thread mode).
pub fn request_rate(rate_hz: u32) {
    RATE_REQUEST.store(rate_hz, Ordering::Relaxed);
}

/// TIM7 programmed as the servo clock. Owned by the `TIM7` interrupt handler.
pub struct ServoTimer {
    counter: CounterHz<TIM7>,
    rate_hz: u32,
}

/// Highest rate the timer is asked for, Hz.
const MAX_RATE_HZ: u32 = 100_000;

impl ServoTimer {
    /// Starts TIM7 at `rate_hz` with its update interrupt enabled (the NVIC line stays masked
    /// until `main` unmasks it). `None` if the rate is 0 or not reachable from the timer clock.
    pub fn new(tim: TIM7, rate_hz: u32, rcc: &mut Rcc) -> Option<Self> {
        if rate_hz == 0 || rate_hz > MAX_RATE_HZ {
            return None;
        }
        let mut counter = tim.counter_hz(rcc);
        counter.start(rate_hz.Hz()).ok()?;
        // Mutation check (board emulator): the prescaler doubled, so the tick runs at half rate.
        #[cfg(feature = "mutant-tim7-prescaler")]
        // SAFETY: TIM7 is owned by `counter`; one prescaler write and an update event.
        unsafe {
            let t = &*TIM7::ptr();
            let psc = t.psc().read().bits();
            t.psc().write(|w| w.bits(2 * psc + 1));
            t.egr().write(|w| w.ug().set_bit());
        }
        counter.listen(Event::Update);
        Some(Self { counter, rate_hz })
    }

    /// Clears the update flag and counts the tick; call once at the start of every TIM7
    /// interrupt. Returns the new tick number.
    #[inline(always)]
    pub fn ack(&mut self) -> u32 {
        self.counter.clear_flags(Flag::Update);
        TICKS.fetch_add(1, Ordering::Relaxed).wrapping_add(1)
    }

    /// Applies a rate change requested with `request_rate`, if any (from the TIM7 handler).
    /// An unreachable rate leaves the timer at its old rate.
    #[inline]
    pub fn apply_rate_request(&mut self) {
        let hz = RATE_REQUEST.swap(0, Ordering::Relaxed);
        if hz == 0 || hz == self.rate_hz {
            return;
        }
        if hz <= MAX_RATE_HZ && self.counter.start(hz.Hz()).is_ok() {
            self.rate_hz = hz;
        } else {
            // `start` stops the counter first: restart it at the old, known-good rate.
            let _ = self.counter.start(self.rate_hz.Hz());
        }
    }
}

/// Servo ticks since boot (wraps after 2³² ticks, 49.7 days at 1 kHz).
pub fn ticks() -> u32 {
    TICKS.load(Ordering::Relaxed)
}
