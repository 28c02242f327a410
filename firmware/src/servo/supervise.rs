//! The supervisor's fault path: the heartbeat watchdog, the halted tick (safe mode: force 0 or
//! the safe damper, the delay line bypassed), the first reading that primes the loop, and the
//! latching of new fault bits (published to the main loop, ending any experiment). The tick's
//! own tests (encoder jump, the travel window on the raw count, over-velocity, the energy
//! monitor) run in `Servo::step`, which hands the bits they raise to this path.
//!
//! Units: ticks (`now`), fault bits of `stiffwall_proto::fault`. Invariants: a latched fault
//! stays until cleared by a command; no allocation, blocking or panic.

use super::{Servo, UNPRIMED};
use crate::config::VEL_WINDOW;
use crate::numeric::Numeric;
use core::sync::atomic::Ordering;
use stiffwall_proto::{fault, flags};

impl<N: Numeric> Servo<'_, N> {
    /// The heartbeat watchdog (experiments only): [`fault::HEARTBEAT`] when the host's heartbeat
    /// counter has not changed for more than `heartbeat_ticks` ticks, else 0. Inlined into
    /// [`Self::step`], where it was written out (same code).
    #[inline(always)]
    pub(super) fn heartbeat(&mut self, now: u32) -> u32 {
        let hb = self.port.shared.heartbeat.load(Ordering::Relaxed);
        if hb != self.hb_seen {
            self.hb_seen = hb;
            self.hb_tick = now;
            0
        } else if now.wrapping_sub(self.hb_tick) > self.g.heartbeat_ticks {
            fault::HEARTBEAT
        } else {
            0
        }
    }

    /// The tick's force when `halt` or `new_faults` is set: the first reading (seeded, then as
    /// any tick), or faults. Returns the code, its flags and the count difference dn the tick
    /// counts (0 on the first reading).
    #[cold]
    #[inline(never)]
    pub(super) fn halted<const WALL: bool>(
        &mut self,
        now: u32,
        new_faults: u32,
        d: i32,
        n: i32,
        free: bool,
    ) -> (i32, u16, i32) {
        let dn = n.saturating_sub(self.prev_n);
        let (new_faults, d, dn) = if self.halt & UNPRIMED != 0 {
            self.prime(n);
            // With the history seeded the first reading moved 0: neither the jump test (d = 0)
            // nor the velocity window (every entry the position) can trip; the monitor's and
            // the heartbeat's bits stand.
            (
                new_faults & !(fault::ENCODER_JUMP | fault::OVER_VELOCITY),
                0,
                0,
            )
        } else {
            (new_faults, d, dn)
        };
        if (self.faults | new_faults) == 0 {
            let (c, f) = if WALL {
                self.wall_force(n, dn, free)
            } else {
                self.force(n, dn)
            };
            (self.delay(c), f, dn)
        } else {
            let (c, f) = self.faulted(now, new_faults, d);
            (c, f, dn)
        }
    }

    /// The first reading, at effective count `n`: seeds the supervisor's history (the damper's
    /// last count, the velocity window).
    pub(super) fn prime(&mut self, n: i32) {
        self.halt &= !UNPRIMED;
        self.prev_n = n;
        self.vel_hist = [self.pos; VEL_WINDOW];
    }

    /// A tick with fault bits latched or new: latches the new ones, then the safe-mode output
    /// and its flag (safe mode bypasses the delay line).
    pub(super) fn faulted(&mut self, now: u32, new_faults: u32, d: i32) -> (i32, u16) {
        if new_faults & !self.faults != 0 {
            self.latch(now, new_faults);
        }
        (self.safe_code(d), flags::SAFE_MODE)
    }

    pub(super) fn latch(&mut self, now: u32, bits: u32) {
        if self.faults == 0 {
            self.port
                .shared
                .first_fault_tick
                .store(now, Ordering::Relaxed);
        }
        self.set_faults(self.faults | bits);
        self.port
            .shared
            .faults
            .store(self.faults, Ordering::Relaxed);
        self.end_experiment(false);
    }
}
