//! The servo tick: encoder → eq. (2) in fixed point → extra delay → clamp → output, with the
//! safety supervisor and telemetry in the same tick.
//!
//! Units: raw counts (hardware counter, unwrapped to a saturating `i32`), effective counts
//! n = ⌊(pos − wall) / 2^shift⌋ (the paper's ⌊ξ⌋ with Δ_eff = 2^shift·Δ), output codes, ticks.
//!
//! Spring (eq. (2)): the force code for effective count n is exactly
//! `code(n) = clamp(⌊−(2n+1) · k_half + ½⌋, −limit, limit)` where `k_half` =
//! K·Δ_eff/(2·force_per_code) is an `I32F32` gain ([`crate::numeric`]), the product computed
//! exactly (`Numeric::spring`). For n outside (−n_sat−1, n_sat), where the force already
//! exceeds the limit, the code at the bound (precomputed in `Gains`) is used instead, as if n
//! were clamped first, so the output is exact for every n and the product never overflows; a
//! one-sided wall moves the lower bound to −1 with code 0. Positions are saturating `i32`
//! counts: a count far outside the wall (or a counter that wrapped many times) gives the
//! clamped force, never a wrapped one. Shift amounts are [`Shift`]s (0..=31 by type), so the
//! unwrap and the coarsening shift need no `& 31` masks.
//!
//! Invariants: `tick*` never allocates, blocks or panics (no indexing that can fail: the ring
//! buffers are indexed with a power-of-two mask); it does at most one command per tick and
//! bounded work. Time is only the `now` argument. It is the single producer of the telemetry
//! and event queues and the single consumer of the command queue ([`Channels`](crate::Channels)).
//!
//! Profile mode (protocol 5, [`crate::profile`]): while a non-empty profile is active and no
//! experiment runs, the mode is `Mode::Profile` and the commanded code is the profile's (the
//! saturating sum of its elements' codes, each on its own effective count), then the same delay
//! line, clamp and output; the wall's own tick (`step::<_, true>`, `Mode::Wall`) is unchanged,
//! the profile taking the experiments' out-of-line path. It is no experiment
//! (`experiment_running()` stays false). Experiments (release, impact, excitation) run on the
//! config's wall as before, and the profile renders again on the tick they end. In profile mode
//! the energy monitor (about the config wall's storage function, which is not what renders)
//! and the heartbeat watchdog (which guards experiments) are off; the encoder-jump,
//! over-velocity and travel checks stay. A profile arrives as one `ServoCmd::Profile` (its
//! table in the channels' profile queue), applied whole between two ticks; the delay line
//! restarts empty and the monitor afresh, as for a config; an empty profile is the wall again.
//!
//! Layout: the channels are [`crate::channels`], the experiments (hold/release, excitation
//! generators) [`crate::experiment`], the energy monitor `stiffwall_core::monitor` (the
//! dissipation check shared with `hostctl replay`); this module is the tick that uses them.
//! Its children split the tick by concern: `wall` (the spring, the damper law, the clamp),
//! `supervise` (heartbeat, halted ticks, fault latching), `drive` (a running experiment's
//! forces, advance and end) and `commands` (the one command taken per tick).

use crate::channels::{DecidedEnd, ServoCmd, ServoEvent, ServoPort, TelemetryItem};
use crate::config::{BoardInfo, Gains, VEL_WINDOW};
use crate::experiment::{EndWatch, Excitation, Experiment, Hold, Launch, Mode};
use crate::hal::{Encoder, ForceOutput};
use crate::numeric::{Fx64, Numeric, Shift};
use crate::profile::ProfileTable;
use core::sync::atomic::Ordering;
use stiffwall_core::monitor::{self, energy_e8_u32, EnergyMonitor};
use stiffwall_proto::{fault, flags, ExperimentKind, Sample, ServoConfig, MAX_TABLE};

mod commands;
mod drive;
mod supervise;
mod wall;

#[cfg(test)]
mod damper_monitor_tests;
#[cfg(test)]
mod excite_tests;
#[cfg(test)]
mod experiment_tests;
#[cfg(test)]
mod fault_tests;
#[cfg(test)]
mod fixture;
#[cfg(test)]
mod profile_tests;
#[cfg(test)]
mod spring_tests;
#[cfg(test)]
mod travel_tests;
#[cfg(test)]
mod wall_law_tests;

// The monitor's bits are the protocol's fault bits, so the servo latches them unchanged.
const _: () =
    assert!(monitor::GROWTH == fault::ENERGY_GROWTH && monitor::LIMIT == fault::ENERGY_LIMIT);
const _: () = assert!(monitor::BUZZ == fault::BUZZ);

/// The bit of [`Servo`]'s `halt` word that marks "no reading yet" (above every fault bit).
const UNPRIMED: u32 = 1 << 31;
const _: () = assert!(UNPRIMED & fault::ALL == 0);

const RING: usize = 32;
const RING_MASK: u32 = RING as u32 - 1;
const VEL_MASK: u32 = VEL_WINDOW as u32 - 1;

/// The servo: owns the loop state; call one `tick*` per servo period.
///
/// `repr(C)`, hot fields first: the spring stage's loads then use small immediate offsets
/// whatever the sizes of the cold fields (the big excitation table is last). Letting the
/// compiler order the fields cost the spring stage 7 instructions per tick (44 vs 37, measured
/// with `cargo xtask bench-firmware`) once the experiment state moved into its own module.
#[derive(Debug)]
#[repr(C)]
pub struct Servo<'a, N: Numeric = Fx64> {
    g: Gains<N>,
    last_raw: u32,
    pos: i32,
    sign_shift: Shift,
    mode: Mode,
    prev_n: i32,
    head: u32,
    /// `faults` | [`UNPRIMED`] before the first reading: the tick's one test of "anything out
    /// of the ordinary" (latched faults, or the first reading). Kept with `faults` by
    /// `set_faults`.
    halt: u32,
    faults: u32,
    ring: [i32; RING],
    vel_hist: [i32; VEL_WINDOW],
    monitor: EnergyMonitor,
    hb_seen: u32,
    hb_tick: u32,
    decimation: u16,
    user_decimation: u16,
    /// Ticks to the next telemetry push, counting down (1: this tick), set to `decimation`
    /// whenever it changes and after each push. With `decimation` 0 it keeps counting (down
    /// from 0, wrapping) and the tick it reaches 0 pushes nothing.
    decim_left: u32,
    seq: u32,
    port: ServoPort<'a, N>,
    exp: Experiment,
    /// The running test's end rule (`HostMsg::PrepareTest`), if it has one.
    end: Option<DecidedEnd>,
    /// Its end watch, from the release on.
    settle: Option<EndWatch>,
    board: BoardInfo,
    /// The raw count of the previous tick, kept on every tick but the wall's (`step`'s
    /// `WALL` path), and set when a profile arrives: the profile's elements take their
    /// backward differences from it.
    prev_pos: i32,
    /// The active haptic profile (empty: the config's wall).
    profile: ProfileTable<N>,
    table: [i16; MAX_TABLE],
}

impl<'a, N: Numeric> Servo<'a, N> {
    /// A servo for `board` with the (validated) config `cfg`, talking through `port`.
    pub fn new(board: BoardInfo, cfg: &ServoConfig, port: ServoPort<'a, N>) -> Self {
        let bits = u32::from(board.encoder_bits.clamp(1, 32));
        Self {
            board,
            g: Gains::from_config(cfg, &board),
            port,
            sign_shift: Shift::new(32 - bits),
            halt: UNPRIMED,
            last_raw: 0,
            pos: 0,
            prev_n: 0,
            ring: [0; RING],
            head: 0,
            vel_hist: [0; VEL_WINDOW],
            faults: 0,
            monitor: EnergyMonitor::default(),
            hb_seen: 0,
            hb_tick: 0,
            exp: Experiment::None,
            end: None,
            settle: None,
            mode: Mode::Wall,
            prev_pos: 0,
            profile: ProfileTable::empty(),
            table: [0; MAX_TABLE],
            decimation: 0,
            user_decimation: 0,
            decim_left: 0,
            seq: 0,
        }
    }

    /// Applies a config directly (equivalent to a `ServoCmd::Config`); for tests and boot.
    pub fn apply_config(&mut self, cfg: &ServoConfig) {
        self.g = Gains::from_config(cfg, &self.board);
        self.ring = [0; RING];
        self.monitor.reset();
        // The backward difference is of the count from the wall: a new wall position (or
        // coarsening) is not a motion, and must not kick the damper on the next tick.
        if self.halt & UNPRIMED == 0 {
            self.prev_n = self.pos.saturating_sub(self.g.wall) >> self.g.coarsen.get();
        }
    }

    /// The derived gains in use.
    pub fn gains(&self) -> &Gains<N> {
        &self.g
    }

    /// Latched fault bits.
    #[must_use]
    pub fn faults(&self) -> u32 {
        self.faults
    }

    /// Sets the latched fault bits (and the tick's `halt` word with them).
    fn set_faults(&mut self, faults: u32) {
        self.faults = faults;
        self.halt = faults | (self.halt & UNPRIMED);
    }

    /// The energy monitor state.
    #[must_use]
    pub fn monitor(&self) -> &EnergyMonitor {
        &self.monitor
    }

    /// Unwrapped raw position (counts since the first reading, sign-extended; saturates at
    /// the `i32` range instead of wrapping).
    #[must_use]
    pub fn position(&self) -> i32 {
        self.pos
    }

    /// An experiment is running (the wall and the profile are no experiments).
    #[must_use]
    pub fn experiment_running(&self) -> bool {
        !matches!(self.mode, Mode::Wall | Mode::Profile)
    }

    /// The active haptic profile (empty: the config's wall renders).
    #[must_use]
    pub fn profile(&self) -> &ProfileTable<N> {
        &self.profile
    }

    /// Renders `table` from the next tick on (an empty one: the config's wall), as a
    /// `ServoCmd::Profile` does; for tests and boot. The delay line restarts empty and the
    /// energy monitor afresh, as for a config; a running experiment keeps running, and the
    /// profile renders when it ends.
    pub fn set_profile(&mut self, table: ProfileTable<N>) {
        self.profile = table;
        self.profile_changed();
    }

    /// Takes the profile queue's next table, as announced by a `ServoCmd::Profile`: its
    /// elements are copied in place from the queue's slot (only as many as it holds, not the
    /// whole 16-slot table, and not through the stack), then the slot is released.
    pub(crate) fn take_profile(&mut self) {
        let Some(t) = self.port.profiles.peek() else {
            return;
        };
        self.profile.copy_from(t);
        // The slot's value is not needed: its elements are `Copy`, nothing to drop.
        let _ = self.port.profiles.dequeue();
        self.profile_changed();
    }

    /// What a new profile resets: the delay line restarts empty, the energy monitor afresh,
    /// and the mode follows the profile unless an experiment runs.
    fn profile_changed(&mut self) {
        self.prev_pos = self.pos;
        self.ring = [0; RING];
        self.monitor.reset();
        if !self.experiment_running() {
            self.mode = self.idle_mode();
        }
    }

    /// The mode without an experiment: the profile when one is active, else the wall.
    fn idle_mode(&self) -> Mode {
        if self.profile.is_empty() {
            Mode::Wall
        } else {
            Mode::Profile
        }
    }

    /// Reads and unwraps the encoder; returns the raw count delta.
    ///
    /// No first-reading branch: `last_raw` and `pos` start at 0, so the first delta is the
    /// sign-extended raw count and `pos` becomes exactly that. Only the supervisor needs to know
    /// that it was the first reading (see `step`: the `halt` word's [`UNPRIMED`] bit), so the
    /// spring path stays branch-free.
    #[inline]
    fn read(&mut self, enc: &mut impl Encoder) -> i32 {
        let raw = enc.count();
        let sh = self.sign_shift.get();
        let d = (raw.wrapping_sub(self.last_raw).wrapping_shl(sh) as i32).wrapping_shr(sh);
        self.last_raw = raw;
        self.pos = self.pos.saturating_add(d);
        d
    }

    #[inline]
    fn delay(&mut self, code: i32) -> i32 {
        let h = self.head;
        self.head = h.wrapping_add(1);
        self.ring[(h & RING_MASK) as usize] = code;
        self.ring[(h.wrapping_sub(self.g.delay) & RING_MASK) as usize]
    }

    /// Spring alone: read, unwrap, coarsen, eq. (2), clamp, write. (Instruction budget stage 1.)
    pub fn tick_spring(&mut self, enc: &mut impl Encoder, out: &mut impl ForceOutput) -> i32 {
        self.read(enc);
        let n = self.pos.saturating_sub(self.g.wall) >> self.g.coarsen.get();
        let (c, _) = self.clamp(self.spring_code(n));
        out.write(c);
        c
    }

    /// Spring + extra delay line. (Stage 2.)
    pub fn tick_spring_delay(&mut self, enc: &mut impl Encoder, out: &mut impl ForceOutput) -> i32 {
        self.read(enc);
        let n = self.pos.saturating_sub(self.g.wall) >> self.g.coarsen.get();
        let d = self.delay(self.spring_code(n));
        let (c, _) = self.clamp(d);
        out.write(c);
        c
    }

    /// Spring + damping + delay + supervisor + experiments, no telemetry, no commands. (Stage 3.)
    pub fn tick_supervised(
        &mut self,
        now: u32,
        enc: &mut impl Encoder,
        out: &mut impl ForceOutput,
    ) -> i32 {
        if self.mode == Mode::Wall {
            self.step::<false, true>(now, enc, out)
        } else {
            self.step_experiment::<false>(now, enc, out)
        }
    }

    /// The full servo tick: one pending command, spring, damping, delay, supervisor,
    /// experiments, clamp, output, telemetry push. (Stage 4; what the board calls.)
    pub fn tick(&mut self, now: u32, enc: &mut impl Encoder, out: &mut impl ForceOutput) -> i32 {
        // Commands are rare: only the emptiness test (two relaxed loads) is on the tick's path;
        // the dequeue and the handler are out of line, so their stack frame and registers do
        // not weigh on the tick.
        if self.port.commands.ready() {
            self.next_command(now);
        }
        if self.mode == Mode::Wall {
            self.step::<true, true>(now, enc, out)
        } else {
            self.step_experiment::<true>(now, enc, out)
        }
    }

    /// Dequeues and handles one pending command (out of the tick's hot path).
    #[cold]
    #[inline(never)]
    fn next_command(&mut self, now: u32) {
        if let Some(cmd) = self.port.commands.dequeue() {
            self.command(now, cmd);
        }
    }

    /// One tick. `WALL`: the mode is [`Mode::Wall`] (the caller tested it; no experiment runs,
    /// so nothing in the tick changes the mode), which leaves out the experiments' tests.
    #[inline(always)]
    fn step<const TEL: bool, const WALL: bool>(
        &mut self,
        now: u32,
        enc: &mut impl Encoder,
        out: &mut impl ForceOutput,
    ) -> i32 {
        // The first reading is absolute, not a motion: its tick takes the `halt` path below,
        // which seeds the supervisor's history as if before it and drops what the jump and
        // velocity tests made of it (with that history they see no motion).
        let d = self.read(enc);
        let rel = self.pos.saturating_sub(self.g.wall);
        let n = rel >> self.g.coarsen.get();
        // Outside a one-sided wall (one test for the monitor and the force).
        let free = n < self.g.contact_n;

        // Supervisor.
        let (new_faults, mut fl) = self.tick_checks::<WALL>(now, d, n, free);
        // The count's backward difference (for the dampers), taken here, where the force
        // needs it, so it is not held through the supervisor.
        let dn = n.saturating_sub(self.prev_n);
        self.prev_n = n;

        // Force. One test of the latched and the new fault bits (and of the first reading)
        // keeps the fault handling (the latch, safe mode) out of the normal path.
        // The flags gather in `fl` on the path that sets them (the wall's usual path sets
        // none), not merged from each stage.
        // The raw count outside the travel window: one compare, a window that is off being
        // the whole `i32` range, never left. Tested here, as a branch to the fault path
        // (which adds its bit), not or-ed into `new_faults` with the supervisor's other bits:
        // that cost the full tick three instructions more (`cargo xtask bench-firmware`). It
        // stands on the first reading too: a device that boots outside its window is outside.
        let travel = self.g.travel.outside(self.pos);
        let (code, dn) = if (self.halt | new_faults) == 0 && !travel {
            let c = if WALL {
                self.wall_force_into(n, dn, free, &mut fl)
            } else {
                let (c, f) = self.force(n, dn);
                fl |= f;
                c
            };
            (self.delay(c), dn)
        } else {
            let new_faults = new_faults | if travel { fault::TRAVEL } else { 0 };
            let (c, f, dn) = self.halted::<WALL>(now, new_faults, d, n, free);
            fl |= f;
            (c, dn)
        };
        let code = self.clamp_into(code, &mut fl);
        out.write(code);

        if TEL {
            self.telemetry(now, rel, n, code, fl);
            self.port.shared.tick.store(now, Ordering::Relaxed);
        }
        if !WALL {
            self.advance(n, dn);
        }
        code
    }

    /// The commanded code (before delay and clamp) and its flags, outside safe mode.
    #[inline(always)]
    fn force(&mut self, n: i32, dn: i32) -> (i32, u16) {
        match self.mode {
            Mode::Wall => self.wall_force(n, dn, n < self.g.contact_n),
            Mode::Released => (self.wall_code(n, dn), flags::RELEASED),
            Mode::Other => self.experiment_force(n, dn),
            Mode::Profile => (self.profile.code(self.pos, self.prev_pos), 0),
        }
    }

    #[inline]
    fn telemetry(&mut self, now: u32, rel: i32, n: i32, code: i32, fl: u16) {
        let left = self.decim_left.wrapping_sub(1);
        if left != 0 {
            self.decim_left = left;
            return;
        }
        // A push, or a stopped stream's count passing 0 (once every 2^32 ticks).
        self.decim_left = u32::from(self.decimation);
        if self.decimation == 0 {
            return;
        }
        let item = TelemetryItem {
            seq: self.seq,
            sample: Sample {
                tick: now,
                count: rel,
                force_code: code,
                flags: fl,
                energy: energy_e8_u32(n),
            },
        };
        self.seq = self.seq.wrapping_add(1);
        if self.port.telemetry.enqueue(item).is_err() {
            self.port.shared.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
}
