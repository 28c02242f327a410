//! The independent watchdog (IWDG), clocked by the LSI (32 kHz): once started it resets the
//! board unless the image reloads it within (RLR + 1) × 4·2^PR LSI periods.
//!
//! Models: KR (the keys `KEY_START`, `KEY_RELOAD` and `KEY_ACCESS`; any other value locks PR
//! and RLR again), PR and RLR (need `KEY_ACCESS` first; a new value counts from the next
//! reload, as on the chip), SR (reads 0: updates are instant). Refuses: PR or RLR written
//! without the access key, a write to SR. Units: time in 1/720 MHz units (one LSI period is
//! 22 500). Invariant: the deadline is the last reload plus the period latched at that reload;
//! `Periph::advance` turns a deadline passed into `ResetCause::Watchdog`.

use super::state::{Iwdg, Periph};
use crate::plant::UNITS_PER_S;
use crate::trace;

/// IWDG base address.
pub const BASE: u32 = 0x4000_3000;
/// Last word address (SR).
pub const LAST: u32 = 0x4000_300F;

/// IWDG_KR address.
const KR: u32 = BASE;
/// IWDG_PR address.
const PR: u32 = BASE + 0x04;
/// IWDG_RLR address.
const RLR: u32 = BASE + 0x08;
/// IWDG_PR register index.
const PR_I: usize = 1;
/// IWDG_RLR register index.
const RLR_I: usize = 2;

/// KR key: starts the watchdog (and reloads it).
pub const KEY_START: u32 = 0xCCCC;
/// KR key: reloads the counter (a feed).
pub const KEY_RELOAD: u32 = 0xAAAA;
/// KR key: unlocks PR and RLR for writing.
pub const KEY_ACCESS: u32 = 0x5555;

/// LSI frequency, Hz.
const LSI_HZ: u64 = 32_000;
/// RLR's reload field.
const RLR_MASK: u32 = 0xFFF;

impl Iwdg {
    /// The watchdog at reset: stopped, PR 0, RLR 0xFFF, locked (the feed count survives).
    pub(super) fn reset(&mut self) {
        self.r = [0, 0, 0xFFF, 0];
        self.on = false;
        self.unlocked = false;
    }

    /// The LSI period times the prescaler, units.
    fn step(&self) -> u64 {
        (UNITS_PER_S / LSI_HZ) * (4u64 << self.r[PR_I].min(6))
    }

    /// The counter restarts at `now` with the period of the current PR and RLR.
    fn reload(&mut self, now: u64) {
        self.reload_at = now;
        self.period = (u64::from(self.r[RLR_I] & RLR_MASK) + 1) * self.step();
    }

    /// When the watchdog runs out, if it runs.
    pub fn deadline(&self) -> Option<u64> {
        self.on.then(|| self.reload_at + self.period)
    }
}

/// A word read of an IWDG register (the latched value).
pub(super) fn read(p: &mut Periph, a: u32) -> u32 {
    p.iwdg.r[((a - BASE) / 4) as usize]
}

/// A word write of an IWDG register.
pub(super) fn write(p: &mut Periph, a: u32, v: u32, raw: u64) {
    match a {
        KR => write_key(p, v),
        PR | RLR => write_guarded(p, a, v),
        _ => p.unmodelled(a, Some(raw)),
    }
}

/// IWDG_KR: start, reload, unlock, or (any other value) lock.
fn write_key(p: &mut Periph, v: u32) {
    let now = p.now;
    let w = &mut p.iwdg;
    match v & 0xFFFF {
        KEY_START => {
            w.on = true;
            w.reload(now);
        }
        KEY_RELOAD => {
            w.reload(now);
            w.feeds += 1;
            w.unlocked = false;
        }
        KEY_ACCESS => w.unlocked = true,
        _ => w.unlocked = false,
    }
}

/// IWDG_PR or IWDG_RLR: written after `KEY_ACCESS`.
fn write_guarded(p: &mut Periph, a: u32, v: u32) {
    let name = if a == PR { "PR" } else { "RLR" };
    if !p.iwdg.unlocked {
        p.fail(format!(
            "IWDG_{name}: written without the {KEY_ACCESS:#x} access key first (the write is \
             ignored by the chip)"
        ));
    }
    p.iwdg.r[((a - BASE) / 4) as usize] = v;
    if trace::enabled() {
        eprintln!(
            "iwdg: {name} = {v} at {:.6} s",
            p.now as f64 / UNITS_PER_S as f64
        );
    }
}

impl Periph {
    /// When the watchdog runs out, if it runs.
    pub fn iwdg_deadline(&self) -> Option<u64> {
        self.iwdg.deadline()
    }
}

#[cfg(test)]
mod tests {
    use super::{KEY_ACCESS, KEY_RELOAD, KEY_START};
    use crate::periph::state::{Periph, ResetCause};
    use crate::plant::Coupling;
    use crate::plant::UNITS_PER_S;

    #[test]
    fn the_watchdog_needs_the_access_key_and_runs_out_without_a_reload() {
        let mut p = Periph::new(Coupling::new(None));
        p.write(0x4000_3008, 4, 100);
        let why = p.stop.take().expect("RLR without the access key");
        assert!(
            why.contains("IWDG_RLR: written without the 0x5555 access key"),
            "{why}"
        );
        p.write(0x4000_3000, 4, u64::from(KEY_ACCESS));
        p.write(0x4000_3004, 4, 0); // PR: LSI / 4
        p.write(0x4000_3008, 4, 99); // RLR: 100 steps
        assert!(p.stop.is_none(), "{:?}", p.stop);
        assert_eq!(p.iwdg_deadline(), None, "not started");
        p.write(0x4000_3000, 4, u64::from(KEY_START));
        let period = 100 * 4 * (UNITS_PER_S / 32_000);
        assert_eq!(p.iwdg_deadline(), Some(period));
        p.now = period / 2;
        p.write(0x4000_3000, 4, u64::from(KEY_RELOAD));
        assert_eq!(p.iwdg_deadline(), Some(period / 2 + period));
        assert_eq!(p.iwdg.feeds, 1);
        p.now = period / 2 + period;
        p.advance();
        assert_eq!(p.reset, Some(ResetCause::Watchdog));
        p.write(0x4000_300C, 4, 0);
        let why = p.stop.take().expect("SR is read-only");
        assert!(why.contains("IWDG+0x00c"), "{why}");
    }
}
