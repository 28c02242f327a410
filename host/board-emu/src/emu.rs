//! The emulated STM32F446: unicorn's Cortex-M4 core (Thumb, M-class) running the image, with
//! the peripheral models of `periph` on its bus and exception entry and return done here.
//!
//! Units: time in 1/720 MHz units (`periph::UNITS_PER_S`); one instruction costs one CPU cycle
//! at the configured HCLK (a CPI-1 model: no flash wait states, no pipeline refills, so cycle
//! figures are a lower bound of the real core's; see the board README). Invariants:
//!
//! - Exceptions are entered and left by this harness, not by unicorn's M-profile model (its
//!   exception return after a host-driven entry was broken in older releases): entry pushes the
//!   8-word basic frame on the main stack (8-byte aligned, xPSR bit 9 records the padding),
//!   sets LR to EXC_RETURN 0xFFFFFFF9 (to thread mode) or 0xFFFFFFF1 (to a handler) and jumps
//!   to the vector; IPSR stays 0 in unicorn, so a branch to 0xFFFFFFxx is a plain branch whose
//!   fetch from unmapped memory this harness catches and turns into the return (pop the frame).
//! - FPU: the image is eabihf and both thread mode and the servo handler use S registers. The
//!   harness treats FPCCR.ASPEN as off (no lazy stacking, no extended frames, so EXC_RETURN is
//!   never 0xFFFFFFE1/E9/ED) and instead saves S0–S31 and FPSCR on its own stack at entry and
//!   restores them at return. Observable state is the same as the hardware's extended frame;
//!   only the stack memory below SP differs (nothing reads it).
//! - Preemption follows NVIC priorities (upper nibble, lower = more urgent), PRIMASK and
//!   BASEPRI; an interrupt is taken between instructions, never inside an IT block.
//! - WFI/WFE: a code hook on each sleep instruction stops before it; the harness then jumps
//!   time to the next event (timer update, UART byte, watchdog) instead of running idle loops.

use crate::image::{Image, FLASH_BASE, IMAGE_END, RAM_BASE, RAM_LEN};
use crate::periph::{reg_name, Periph, ResetCause, IRQS, IRQ_TIM7};
use anyhow::{anyhow, bail, Result};
use unicorn_engine::{Arch, ArmCpuModel, HookType, MemType, Mode, Prot, RegisterARM, Unicorn};

/// What the hooks share with the harness (unicorn's per-engine data).
#[derive(Debug)]
pub struct State {
    /// The peripherals and the clock.
    pub p: Periph,
    /// Instructions executed since power-on.
    pub insns: u64,
    /// Stop running at this time.
    deadline: u64,
    /// The sleep instruction the core stopped before.
    sleep_at: Option<u32>,
    /// Address of an exception return (a fetch from 0xFFFFFFxx).
    exc_return: Option<u32>,
    /// An unmapped access.
    fault: Option<String>,
    /// Stop before the next instruction (set by the mmio callbacks).
    attention: bool,
    /// Addresses of the image's WFI/WFE instructions (sorted).
    sleep_insns: Vec<u32>,
}

/// Servo-tick statistics (TIM7 handler runs).
#[derive(Debug, Clone, Default)]
pub struct TickStats {
    /// Handler runs completed.
    pub count: u64,
    /// Total instructions in the handler (including what preempted it).
    pub insns: u64,
    /// Longest run.
    pub max: u64,
}

/// The running board.
pub struct Machine<'a> {
    uc: Unicorn<'a, State>,
    image: Image,
    /// Active exceptions: (exception number, priority, instructions at entry).
    active: Vec<(usize, u8, u64)>,
    /// S0–S31 and FPSCR saved at each exception entry.
    fp_saved: Vec<[u64; 33]>,
    sleeping: bool,
    /// Time spent asleep since `stats_since`, units.
    pub asleep: u64,
    /// Start of the statistics window, units.
    pub stats_since: u64,
    /// Resets so far and why.
    pub resets: Vec<(u64, ResetCause)>,
    /// Servo tick statistics.
    pub ticks: TickStats,
    /// Nested exception entries: (the exception taken, the one it preempted) → how often.
    pub preemptions: std::collections::BTreeMap<(usize, usize), u64>,
    /// From this time on, thread mode makes no progress (a hung main loop; the watchdog
    /// test): interrupts are still taken.
    pub hang_main_at: Option<u64>,
}

impl std::fmt::Debug for Machine<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Machine")
            .field("active", &self.active)
            .finish_non_exhaustive()
    }
}

const FP_REGS: [RegisterARM; 32] = [
    RegisterARM::S0,
    RegisterARM::S1,
    RegisterARM::S2,
    RegisterARM::S3,
    RegisterARM::S4,
    RegisterARM::S5,
    RegisterARM::S6,
    RegisterARM::S7,
    RegisterARM::S8,
    RegisterARM::S9,
    RegisterARM::S10,
    RegisterARM::S11,
    RegisterARM::S12,
    RegisterARM::S13,
    RegisterARM::S14,
    RegisterARM::S15,
    RegisterARM::S16,
    RegisterARM::S17,
    RegisterARM::S18,
    RegisterARM::S19,
    RegisterARM::S20,
    RegisterARM::S21,
    RegisterARM::S22,
    RegisterARM::S23,
    RegisterARM::S24,
    RegisterARM::S25,
    RegisterARM::S26,
    RegisterARM::S27,
    RegisterARM::S28,
    RegisterARM::S29,
    RegisterARM::S30,
    RegisterARM::S31,
];

fn uc_err(what: &str) -> impl Fn(unicorn_engine::uc_error) -> anyhow::Error + '_ {
    move |e| anyhow!("unicorn: {what}: {e:?}")
}

/// Asks the code hook to stop before the next instruction (stopping from inside an mmio
/// callback would abandon the access and re-execute it).
fn attention(uc: &mut Unicorn<'_, State>) {
    uc.get_data_mut().attention = true;
}

/// The word address and bit number a bit-band alias offset stands for.
fn bit_band(off: u64) -> (u32, u32) {
    let byte = 0x4000_0000 + (off / 32) as u32;
    let bit = ((off % 32) / 4) as u32 + 8 * (byte & 3);
    (byte & !3, bit)
}

impl State {
    /// The hooks' state at power-on, around the peripherals `p`, for `image`.
    fn new(p: Periph, image: &Image) -> Self {
        Self {
            p,
            insns: 0,
            deadline: 0,
            sleep_at: None,
            exc_return: None,
            fault: None,
            attention: false,
            sleep_insns: image.sleep_insns.clone(),
        }
    }
}

/// Opens unicorn's Cortex-M4 (Thumb, M-class) around `state`.
fn open_core<'a>(state: State) -> Result<Unicorn<'a, State>> {
    let mut uc = Unicorn::new_with_data(Arch::ARM, Mode::THUMB | Mode::MCLASS, state)
        .map_err(uc_err("opening the Cortex-M engine"))?;
    uc.ctl_set_cpu_model(ArmCpuModel::CORTEX_M4 as i32)
        .map_err(uc_err("selecting the Cortex-M4"))?;
    Ok(uc)
}

/// Maps the image flash (sectors 0–5, read and execute) with `image` in it, and the SRAM.
fn map_memory(uc: &mut Unicorn<'_, State>, image: &Image) -> Result<()> {
    let image_len = u64::from(IMAGE_END - FLASH_BASE);
    uc.mem_map(u64::from(FLASH_BASE), image_len, Prot::READ | Prot::EXEC)
        .map_err(uc_err("mapping the flash"))?;
    uc.mem_write(u64::from(FLASH_BASE), &image.flash)
        .map_err(uc_err("loading the image"))?;
    uc.mem_map(u64::from(RAM_BASE), u64::from(RAM_LEN), Prot::ALL)
        .map_err(uc_err("mapping the SRAM"))
}

/// Maps flash sectors 6–7: the config store, NOR semantics (`Periph::store_write`).
fn map_config_store(uc: &mut Unicorn<'_, State>) -> Result<()> {
    uc.mmio_map(
        u64::from(IMAGE_END),
        0x4_0000,
        Some(|uc: &mut Unicorn<'_, State>, off: u64, size: usize| {
            uc.get_data().p.store_read(off as u32, size)
        }),
        Some(
            |uc: &mut Unicorn<'_, State>, off: u64, size: usize, v: u64| {
                let p = &mut uc.get_data_mut().p;
                p.store_write(off as u32, size, v);
                p.now += std::mem::take(&mut p.stall);
                attention(uc);
            },
        ),
    )
    .map_err(uc_err("mapping the config store"))
}

/// Maps the peripheral space (0x4000_0000..0x4008_0000) and the system space
/// (0xE000_0000..0xE010_0000) onto `Periph::read` and `Periph::write`.
fn map_peripherals(uc: &mut Unicorn<'_, State>) -> Result<()> {
    for (base, len) in [(0x4000_0000u64, 0x8_0000u64), (0xE000_0000, 0x10_0000)] {
        uc.mmio_map(
            base,
            len,
            Some(move |uc: &mut Unicorn<'_, State>, off: u64, size: usize| {
                let s = uc.get_data_mut();
                let v = s.p.read((base + off) as u32, size);
                if s.p.stop.is_some() || s.p.reset.is_some() {
                    s.attention = true;
                }
                v
            }),
            Some(
                move |uc: &mut Unicorn<'_, State>, off: u64, size: usize, v: u64| {
                    let p = &mut uc.get_data_mut().p;
                    p.write((base + off) as u32, size, v);
                    p.now += std::mem::take(&mut p.stall);
                    // An interrupt may have become pending (NVIC pend/enable, a flag set).
                    attention(uc);
                },
            ),
        )
        .map_err(uc_err("mapping the peripherals"))?;
    }
    Ok(())
}

/// Maps the peripheral bit-band alias (RM0390 §2.3.2): one word per bit of 0x4000_0000..
fn map_bit_band(uc: &mut Unicorn<'_, State>) -> Result<()> {
    uc.mmio_map(
        0x4200_0000,
        0x200_0000,
        Some(|uc: &mut Unicorn<'_, State>, off: u64, _size: usize| {
            let (addr, bit) = bit_band(off);
            let s = uc.get_data_mut();
            let v = s.p.read(addr, 4);
            if s.p.stop.is_some() {
                s.attention = true;
            }
            (v >> bit) & 1
        }),
        Some(
            |uc: &mut Unicorn<'_, State>, off: u64, _size: usize, v: u64| {
                let (addr, bit) = bit_band(off);
                let p = &mut uc.get_data_mut().p;
                let old = p.read(addr, 4);
                let new = (old & !(1 << bit)) | ((v & 1) << bit);
                p.write(addr, 4, new);
                attention(uc);
            },
        ),
    )
    .map_err(uc_err("mapping the bit-band alias"))
}

/// Every instruction: count it, charge its cycle, stop at the deadline or before WFI.
fn add_code_hook(uc: &mut Unicorn<'_, State>) -> Result<()> {
    uc.add_code_hook(
        1,
        0,
        |uc: &mut Unicorn<'_, State>, addr: u64, _size: u32| {
            let s = uc.get_data_mut();
            if s.sleep_insns.binary_search(&(addr as u32)).is_ok() {
                s.sleep_at = Some(addr as u32);
                let _ = uc.emu_stop();
                return;
            }
            if s.attention {
                s.attention = false;
                let _ = uc.emu_stop();
                return;
            }
            s.insns += 1;
            s.p.now += s.p.cpu_units;
            if s.p.now >= s.deadline {
                let _ = uc.emu_stop();
            }
        },
    )
    .map_err(uc_err("adding the code hook"))?;
    Ok(())
}

/// Unmapped and protected accesses: an exception return (a fetch from 0xFFFFFFxx) or a fault.
fn add_fault_hook(uc: &mut Unicorn<'_, State>) -> Result<()> {
    uc.add_mem_hook(
        HookType::MEM_UNMAPPED | HookType::MEM_PROT,
        1,
        0,
        |uc: &mut Unicorn<'_, State>, kind: MemType, addr: u64, _size: usize, v: i64| {
            let s = uc.get_data_mut();
            let a = addr as u32;
            match kind {
                MemType::FETCH_UNMAPPED if a >= 0xFFFF_FF00 => s.exc_return = Some(a),
                MemType::WRITE_PROT if (FLASH_BASE..IMAGE_END).contains(&a) => {
                    s.fault = Some(format!(
                        "write of {v:#x} to the image flash at {a:#010x} (only sectors 6-7 \
                         are written)"
                    ));
                }
                MemType::WRITE_UNMAPPED => {
                    s.fault = Some(format!("write of {v:#x} to {}", reg_name(a)));
                }
                _ => s.fault = Some(format!("{kind:?} at {}", reg_name(a))),
            }
            false
        },
    )
    .map_err(uc_err("adding the fault hook"))?;
    Ok(())
}

impl<'a> Machine<'a> {
    /// Builds the board around `image` and `p`, at the reset vector.
    pub fn new(image: Image, p: Periph) -> Result<Self> {
        let mut uc = open_core(State::new(p, &image))?;
        map_memory(&mut uc, &image)?;
        map_config_store(&mut uc)?;
        map_peripherals(&mut uc)?;
        map_bit_band(&mut uc)?;
        add_code_hook(&mut uc)?;
        add_fault_hook(&mut uc)?;
        let mut m = Self {
            uc,
            image,
            active: Vec::new(),
            fp_saved: Vec::new(),
            sleeping: false,
            asleep: 0,
            stats_since: 0,
            resets: Vec::new(),
            ticks: TickStats::default(),
            preemptions: std::collections::BTreeMap::new(),
            hang_main_at: None,
        };
        m.cpu_reset()?;
        Ok(m)
    }

    /// The peripherals.
    pub fn periph(&mut self) -> &mut Periph {
        &mut self.uc.get_data_mut().p
    }

    /// Instructions executed since power-on.
    pub fn insns(&self) -> u64 {
        self.uc.get_data().insns
    }

    /// Restarts the statistics (servo ticks, time asleep) from now.
    pub fn reset_stats(&mut self) {
        self.ticks = TickStats::default();
        self.asleep = 0;
        self.stats_since = self.now();
    }

    /// The program counter.
    pub fn pc(&self) -> u32 {
        self.reg(RegisterARM::PC).unwrap_or(0)
    }

    /// Time now, units.
    pub fn now(&self) -> u64 {
        self.uc.get_data().p.now
    }

    fn reg(&self, r: RegisterARM) -> Result<u32> {
        Ok(self.uc.reg_read(r).map_err(uc_err("reading a register"))? as u32)
    }

    fn set(&mut self, r: RegisterARM, v: u32) -> Result<()> {
        self.uc
            .reg_write(r, u64::from(v))
            .map_err(uc_err("writing a register"))
    }

    fn cpu_reset(&mut self) -> Result<()> {
        for r in [
            RegisterARM::R0,
            RegisterARM::R1,
            RegisterARM::R2,
            RegisterARM::R3,
            RegisterARM::R4,
            RegisterARM::R5,
            RegisterARM::R6,
            RegisterARM::R7,
            RegisterARM::R8,
            RegisterARM::R9,
            RegisterARM::R10,
            RegisterARM::R11,
            RegisterARM::R12,
        ] {
            self.set(r, 0)?;
        }
        self.set(RegisterARM::PRIMASK, 0)?;
        self.set(RegisterARM::BASEPRI, 0)?;
        self.set(RegisterARM::CONTROL, 0)?;
        self.set(RegisterARM::SP, self.image.initial_sp)?;
        self.set(RegisterARM::LR, 0xFFFF_FFFF)?;
        self.set(RegisterARM::XPSR, 0x0100_0000)?;
        self.set(RegisterARM::PC, self.image.reset & !1)?;
        self.active.clear();
        self.fp_saved.clear();
        self.sleeping = false;
        Ok(())
    }

    /// Current execution priority (256: thread mode, nothing masked).
    fn exec_priority(&self) -> Result<u16> {
        let mut prio = self
            .active
            .iter()
            .map(|a| u16::from(a.1))
            .min()
            .unwrap_or(256);
        if self.reg(RegisterARM::PRIMASK)? & 1 != 0 {
            prio = 0;
        }
        let basepri = self.reg(RegisterARM::BASEPRI)? & 0xF0;
        if basepri != 0 {
            prio = prio.min(basepri as u16);
        }
        Ok(prio)
    }

    /// The most urgent pending, enabled interrupt: (irq, priority).
    fn pending(&self) -> Option<(usize, u8)> {
        let p = &self.uc.get_data().p;
        (0..IRQS)
            .filter(|&i| {
                p.nvic_en[i] && p.irq_pending(i) && !self.active.iter().any(|a| a.0 == 16 + i)
            })
            .map(|i| (i, p.nvic_prio[i]))
            .min_by_key(|&(i, pr)| (pr, i))
    }

    fn enter(&mut self, irq: usize, prio: u8) -> Result<()> {
        let exc = 16 + irq;
        if self.reg(RegisterARM::CONTROL)? & 2 != 0 {
            bail!("CONTROL.SPSEL = 1 (process stack): not modelled; the image runs on MSP only");
        }
        let mut sp = self.reg(RegisterARM::SP)?;
        let pad = sp & 4 != 0;
        if pad {
            sp -= 4;
        }
        sp -= 32;
        let xpsr = self.reg(RegisterARM::XPSR)? | (u32::from(pad) << 9);
        let frame = [
            self.reg(RegisterARM::R0)?,
            self.reg(RegisterARM::R1)?,
            self.reg(RegisterARM::R2)?,
            self.reg(RegisterARM::R3)?,
            self.reg(RegisterARM::R12)?,
            self.reg(RegisterARM::LR)?,
            self.reg(RegisterARM::PC)?,
            xpsr,
        ];
        let bytes: Vec<u8> = frame.iter().flat_map(|w| w.to_le_bytes()).collect();
        self.uc.mem_write(u64::from(sp), &bytes).map_err(|e| {
            anyhow!("stack overflow: pushing an exception frame at {sp:#010x}: {e:?}")
        })?;
        let mut fp = [0u64; 33];
        for (i, r) in FP_REGS.iter().enumerate() {
            fp[i] = self
                .uc
                .reg_read(*r)
                .map_err(uc_err("reading S registers"))?;
        }
        fp[32] = self
            .uc
            .reg_read(RegisterARM::FPSCR)
            .map_err(uc_err("reading FPSCR"))?;
        self.fp_saved.push(fp);
        let exc_return = if self.active.is_empty() {
            0xFFFF_FFF9
        } else {
            0xFFFF_FFF1
        };
        let vtor = self.uc.get_data().p.vtor();
        let vtor = if vtor == 0 { FLASH_BASE } else { vtor };
        let mut vec = [0u8; 4];
        self.uc
            .mem_read(u64::from(vtor) + 4 * exc as u64, &mut vec)
            .map_err(|e| anyhow!("reading vector {exc} at VTOR {vtor:#010x}: {e:?}"))?;
        let handler = u32::from_le_bytes(vec);
        self.set(RegisterARM::SP, sp)?;
        self.set(RegisterARM::LR, exc_return)?;
        self.set(RegisterARM::XPSR, 0x0100_0000)?;
        self.set(RegisterARM::PC, handler & !1)?;
        if let Some(&(below, _, _)) = self.active.last() {
            *self.preemptions.entry((exc, below)).or_default() += 1;
        }
        let insns = self.insns();
        let s = self.uc.get_data_mut();
        s.p.nvic_pend[irq] = false;
        // Exception entry takes 12 cycles on the Cortex-M4.
        s.p.now += 12 * s.p.cpu_units;
        self.active.push((exc, prio, insns));
        self.sleeping = false;
        Ok(())
    }

    fn exception_return(&mut self, at: u32) -> Result<()> {
        let exc_return = at | 1;
        let Some((exc, _, started)) = self.active.pop() else {
            bail!("branch to {at:#010x} (EXC_RETURN) in thread mode");
        };
        if exc_return != 0xFFFF_FFF9 && exc_return != 0xFFFF_FFF1 {
            bail!(
                "EXC_RETURN {exc_return:#010x}: only 0xFFFFFFF9/0xFFFFFFF1 are produced by this \
                 harness (basic frames, MSP)"
            );
        }
        let sp = self.reg(RegisterARM::SP)?;
        let mut bytes = [0u8; 32];
        self.uc
            .mem_read(u64::from(sp), &mut bytes)
            .map_err(|e| anyhow!("popping the exception frame at {sp:#010x}: {e:?}"))?;
        let w = |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().expect("4"));
        let regs = [
            RegisterARM::R0,
            RegisterARM::R1,
            RegisterARM::R2,
            RegisterARM::R3,
            RegisterARM::R12,
            RegisterARM::LR,
            RegisterARM::PC,
        ];
        for (i, r) in regs.iter().enumerate() {
            self.set(*r, w(i))?;
        }
        let xpsr = w(7);
        let new_sp = sp + 32 + if xpsr & (1 << 9) != 0 { 4 } else { 0 };
        self.set(RegisterARM::XPSR, xpsr & !(0x1FF | (1 << 9)))?;
        self.set(RegisterARM::SP, new_sp)?;
        if let Some(fp) = self.fp_saved.pop() {
            for (i, r) in FP_REGS.iter().enumerate() {
                self.uc
                    .reg_write(*r, fp[i])
                    .map_err(uc_err("restoring S registers"))?;
            }
            self.uc
                .reg_write(RegisterARM::FPSCR, fp[32])
                .map_err(uc_err("restoring FPSCR"))?;
        }
        let insns = self.insns();
        if exc == 16 + IRQ_TIM7 {
            let n = insns - started;
            self.ticks.count += 1;
            self.ticks.insns += n;
            self.ticks.max = self.ticks.max.max(n);
        }
        let s = self.uc.get_data_mut();
        s.p.now += 12 * s.p.cpu_units;
        Ok(())
    }

    fn board_reset(&mut self, cause: ResetCause) -> Result<()> {
        let now = self.now();
        self.resets.push((now, cause));
        self.periph().reset_registers();
        self.cpu_reset()
    }

    /// Runs the board until emulated time `t_end` (units). Errors: the firmware touched an
    /// unmodelled register, broke a hardware rule, or faulted.
    pub fn run_until(&mut self, t_end: u64) -> Result<()> {
        loop {
            if self.stop_or_reset()? {
                continue;
            }
            let now = self.now();
            let exec = self.exec_priority()?;
            let pending = self.pending();
            if let Some((irq, prio)) = pending {
                if u16::from(prio) < exec {
                    self.enter(irq, prio)?;
                    continue;
                }
            }
            if now >= t_end {
                return Ok(());
            }
            let next = self.uc.get_data().p.next_event().unwrap_or(u64::MAX);
            let deadline = next.min(t_end).max(now + 1);
            if self.sleeping {
                self.sleep(pending, now, deadline);
            } else if self.active.is_empty() && self.hang_main_at.is_some_and(|h| now >= h) {
                // A hung main loop: thread mode spins in place until the next event.
                self.idle_to(deadline);
            } else if pending.is_some() {
                // Masked (PRIMASK/BASEPRI): look again soon.
                let u = self.uc.get_data().p.cpu_units;
                self.execute(deadline.min(now + 32 * u))?;
            } else {
                self.execute(deadline)?;
            }
        }
    }

    /// Stops the run on a broken rule (`Periph::stop`), brings the peripherals up to now and
    /// performs a reset they ask for. `Ok(true)`: the board was reset.
    fn stop_or_reset(&mut self) -> Result<bool> {
        if let Some(why) = self.uc.get_data_mut().p.stop.take() {
            let pc = self.reg(RegisterARM::PC)?;
            bail!("{why} (pc {pc:#010x})");
        }
        self.periph().advance();
        if let Some(cause) = self.uc.get_data_mut().p.reset.take() {
            self.board_reset(cause)?;
            return Ok(true);
        }
        Ok(false)
    }

    /// Asleep in WFI: wakes on any pending interrupt above the handler's priority, even a
    /// masked one; else time jumps to `deadline`.
    fn sleep(&mut self, pending: Option<(usize, u8)>, now: u64, deadline: u64) {
        let wakes = pending.is_some_and(|(_, pr)| {
            u16::from(pr)
                < self
                    .active
                    .iter()
                    .map(|a| u16::from(a.1))
                    .min()
                    .unwrap_or(256)
        });
        if wakes {
            self.sleeping = false;
        } else {
            self.asleep += deadline - now;
            self.idle_to(deadline);
        }
    }

    /// Time jumps to `deadline` with the core idle; the plant follows.
    fn idle_to(&mut self, deadline: u64) {
        let p = self.periph();
        p.now = deadline;
        p.plant.advance_to(deadline);
    }

    /// Runs the core from the PC until `deadline` (or an earlier stop by a hook), then handles
    /// why it stopped: a sleep instruction, an exception return, a fault.
    fn execute(&mut self, deadline: u64) -> Result<()> {
        self.uc.get_data_mut().deadline = deadline;
        let pc = self.reg(RegisterARM::PC)?;
        let result = self.uc.emu_start(u64::from(pc | 1), u64::MAX, 0, 0);
        let s = self.uc.get_data_mut();
        if let Some(at) = s.sleep_at.take() {
            self.set(RegisterARM::PC, at + 2)?;
            self.sleeping = true;
            return Ok(());
        }
        let exc_return = s.exc_return.take();
        let fault = s.fault.take();
        if let Some(at) = exc_return {
            return self.exception_return(at);
        }
        // The M-profile system region (0xE000_0000 and up) is execute-never: a branch to
        // EXC_RETURN raises a prefetch abort in unicorn rather than an unmapped fetch.
        let pc = self.reg(RegisterARM::PC)?;
        if result.is_err() && pc >= 0xFFFF_FF00 {
            return self.exception_return(pc);
        }
        if let Some(f) = fault {
            bail!("the firmware faulted: {f} (pc {pc:#010x})");
        }
        if let Err(e) = result {
            let pc = self.reg(RegisterARM::PC)?;
            bail!("the core stopped: {e:?} at pc {pc:#010x}");
        }
        Ok(())
    }
}
