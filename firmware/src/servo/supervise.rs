//! The supervisor's fault path: the heartbeat watchdog, the halted tick (safe mode: force 0 or
//! the safe damper, the delay line bypassed), the first reading that primes the loop, and the
//! latching of new fault bits (published to the main loop, ending any experiment). The tick's
//! own tests (encoder jump, the travel window on the raw count, over-velocity, the energy
//! monitor, the heartbeat) are `Servo::tick_checks`, inlined into `Servo::step`, which hands the
//! bits they raise to this path.
//!
//! Units: ticks (`now`), fault bits of `stiffwall_proto::fault`. Invariants: a latched fault
//! stays until cleared by a command; no allocation, blocking or panic.

use super::{Servo, UNPRIMED, VEL_MASK};
use crate::config::VEL_WINDOW;
use crate::experiment::Mode;
use crate::numeric::Numeric;
use core::sync::atomic::Ordering;
use stiffwall_core::monitor;
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

    /// The tick's own tests, before the force: encoder jump (`d`, the raw delta), over-velocity
    /// (the raw count against the one `VEL_WINDOW` ticks ago), the energy monitor at effective
    /// count `n` (reset while `free`, outside a one-sided wall) and, during experiments, the
    /// heartbeat. Returns the new fault bits and the flags they set (`TURN`). Inlined into
    /// [`Self::step`], where it was written out (same code).
    #[inline(always)]
    pub(super) fn tick_checks<const WALL: bool>(
        &mut self,
        now: u32,
        d: i32,
        n: i32,
        free: bool,
    ) -> (u32, u16) {
        let mut new_faults = 0u32;
        if self.g.jump_bound.exceeded(d) {
            new_faults |= fault::ENCODER_JUMP;
        }
        let vi = (now & VEL_MASK) as usize;
        let old = core::mem::replace(&mut self.vel_hist[vi], self.pos);
        if self.g.vel_bound.exceeded(self.pos.saturating_sub(old)) {
            new_faults |= fault::OVER_VELOCITY;
        }
        let mut fl = 0u16;
        // The monitor watches the config wall's storage function: on the wall and a release
        // test's released phase, not while holding, exciting or rendering a profile.
        let monitoring = self.g.energy_monitor && (WALL || self.mode == Mode::Released);
        if monitoring {
            if free {
                // Outside a one-sided wall the spring stores nothing: free motion (the user
                // moving the device around) must not count; start afresh on the next contact.
                self.monitor.reset();
            } else {
                // `update`, its two parts written out (the limit test then compiles to one
                // conditional or).
                if monitor::odd_abs(n) > self.g.energy_limit_m {
                    new_faults |= fault::ENERGY_LIMIT;
                }
                let (f, turn) = self.monitor.track(n, self.g.growth_trip);
                new_faults |= f;
                if turn {
                    fl |= flags::TURN;
                    // A prepared test (`PrepareTest`) is judged by the host from its counts
                    // over the test's length, as the stability criterion judges a trial: a
                    // transient that rings for more than the buzz window and then decays is
                    // not a buzz there (rotary-belt-60hz at 0.93 K*(B): 8 of 40 releases after
                    // the hold tripped the detector, all 40 settle with it off). The test's
                    // own end rule bounds a persistent buzz; growth and the energy limit
                    // still trip.
                    if WALL || self.end.is_none() {
                        new_faults |= self.monitor.buzz_turn(now, self.g.buzz_window_ticks);
                    }
                }
            }
        }
        // The heartbeat watchdog guards experiments only (not the wall, not a profile).
        if !WALL && self.mode != Mode::Profile && self.g.heartbeat_ticks > 0 {
            new_faults |= self.heartbeat(now);
        }
        (new_faults, fl)
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
        self.prev_pos = self.pos;
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
