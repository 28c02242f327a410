//! The SCB (system control block) with the FPU and debug control words the image writes:
//! CPUID, ICSR, VTOR, AIRCR, SCR, CCR, SHPR1–3, SHCSR, CPACR, FPCCR, FPCAR, FPDSCR, DEMCR.
//!
//! Models: CPUID (read-only Cortex-M4 r0p1), ICSR (reads 0; nothing pends PendSV or SysTick),
//! AIRCR (needs VECTKEY 0x05FA; SYSRESETREQ resets the board with `ResetCause::Software`;
//! PRIGROUP latched; reads VECTKEYSTAT 0xFA05), and the others latched by address (the
//! harness in `emu` reads VTOR at exception entry). Refuses: an AIRCR write without VECTKEY,
//! writes to CPUID and ICSR, every other address in the block (CFSR, HFSR, MMFAR, BFAR, the
//! debug registers but DEMCR, …). Units: none. Invariant: FPCCR reads 0xC000_0000 after reset
//! (ASPEN, LSPEN set), though the harness does no lazy stacking (see `emu`).

use super::state::{Periph, ResetCause};

/// SCB_CPUID address (the block's first word).
pub const BASE: u32 = 0xE000_ED00;
/// FPU_FPDSCR address (the last modelled word).
pub const LAST: u32 = 0xE000_EF3C;
/// SCB_CPUID.
const CPUID: u32 = BASE;
/// SCB_ICSR.
const ICSR: u32 = 0xE000_ED04;
/// SCB_VTOR.
pub const VTOR: u32 = 0xE000_ED08;
/// SCB_AIRCR.
const AIRCR: u32 = 0xE000_ED0C;
/// FPU_FPCCR.
const FPCCR: u32 = 0xE000_EF34;
/// The latched words: VTOR, SCR, CCR, SHPR1–3, SHCSR, CPACR, FPCCR, FPCAR, FPDSCR, DEMCR.
const LATCHED: [u32; 12] = [
    VTOR,
    0xE000_ED10,
    0xE000_ED14,
    0xE000_ED18,
    0xE000_ED1C,
    0xE000_ED20,
    0xE000_ED24,
    0xE000_ED88,
    FPCCR,
    0xE000_EF38,
    0xE000_EF3C,
    0xE000_EDFC,
];
/// CPUID's value: ARM Cortex-M4 r0p1.
const CPUID_VALUE: u32 = 0x410F_C241;
/// AIRCR's VECTKEY (written in the upper half).
const VECTKEY: u32 = 0x05FA;
/// AIRCR as read: VECTKEYSTAT.
const VECTKEYSTAT: u32 = 0xFA05_0000;
/// AIRCR.SYSRESETREQ.
const SYSRESETREQ: u32 = 1 << 2;
/// AIRCR.PRIGROUP.
const PRIGROUP: u32 = 0x700;
/// FPCCR at reset: ASPEN and LSPEN.
const FPCCR_RESET: u32 = 0xC000_0000;

/// The SCB at reset: every latched word 0 but FPCCR.
pub(super) fn reset(p: &mut Periph) {
    p.scb.clear();
    p.scb.insert(FPCCR, FPCCR_RESET);
}

/// A word read in the SCB block.
pub(super) fn read(p: &mut Periph, a: u32) -> u32 {
    match a {
        CPUID => CPUID_VALUE,
        ICSR => 0,
        AIRCR => p.scb.get(&a).copied().unwrap_or(VECTKEYSTAT),
        _ if LATCHED.contains(&a) => p.scb.get(&a).copied().unwrap_or(0),
        _ => {
            p.unmodelled(a, None);
            0
        }
    }
}

/// A word write in the SCB block.
pub(super) fn write(p: &mut Periph, a: u32, v: u32, raw: u64) {
    match a {
        AIRCR => write_aircr(p, v),
        _ if LATCHED.contains(&a) => {
            p.scb.insert(a, v);
        }
        _ => p.unmodelled(a, Some(raw)),
    }
}

/// AIRCR: VECTKEY required; SYSRESETREQ resets the board, PRIGROUP is latched.
fn write_aircr(p: &mut Periph, v: u32) {
    if v >> 16 != VECTKEY {
        p.fail(format!(
            "SCB_AIRCR: written without VECTKEY 0x05FA ({v:#010x})"
        ));
    } else if v & SYSRESETREQ != 0 {
        p.reset = Some(ResetCause::Software);
    } else {
        p.scb.insert(AIRCR, VECTKEYSTAT | (v & PRIGROUP));
    }
}

impl Periph {
    /// SCB_VTOR: where the vector table is (0 at reset).
    pub fn vtor(&self) -> u32 {
        self.scb.get(&VTOR).copied().unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use crate::periph::state::{Periph, ResetCause};
    use crate::plant::Coupling;

    #[test]
    fn aircr_needs_its_key_and_sysresetreq_resets_the_board() {
        let mut p = Periph::new(Coupling::new(None));
        assert_eq!(p.read(0xE000_ED0C, 4), 0xFA05_0000);
        assert_eq!(p.read(0xE000_EF34, 4), 0xC000_0000, "FPCCR: ASPEN, LSPEN");
        p.write(0xE000_ED0C, 4, 0x0000_0300);
        let why = p.stop.take().expect("AIRCR without VECTKEY");
        assert!(why.contains("without VECTKEY"), "{why}");
        p.write(0xE000_ED0C, 4, 0x05FA_0300);
        assert_eq!(p.read(0xE000_ED0C, 4), 0xFA05_0300, "PRIGROUP latched");
        p.write(0xE000_ED08, 4, 0x0800_4000);
        assert_eq!(p.vtor(), 0x0800_4000);
        assert_eq!(p.reset, None);
        p.write(0xE000_ED0C, 4, 0x05FA_0004);
        assert_eq!(p.reset, Some(ResetCause::Software));
        p.write(0xE000_ED04, 4, 1 << 28); // ICSR.PENDSVSET
        let why = p.stop.take().expect("ICSR writes are not modelled");
        assert!(why.contains("SCB_ICSR"), "{why}");
    }
}
