//! `stiffwall-board-emu`: runs the Nucleo-F446RE firmware ELF on an emulated STM32F446 whose
//! encoder (TIM2), force output (DAC1 or TIM1 PWM + DIR), servo timer (TIM7), UART (USART2),
//! flash config store and watchdog are coupled to the simulated plant of `stiffwall-sim`.
//!
//! Units: emulated time in seconds at the CLI, 1/720 MHz units inside (`periph::UNITS_PER_S`);
//! the plant in SI (rad and N·m for a rotary rig, m and N for a linear one). Invariants: the image is checked before
//! anything runs (`image`); runs are deterministic for a given image, plant and host byte
//! stream timing; a register the emulator does not model stops the run with its name.
//!
//! Modes: `--seconds S` runs S emulated seconds with no host and prints a report (clock tree,
//! servo rate, cycles per tick, CPU load); `--pty` serves USART2 on a pseudo-terminal (its path
//! printed on stdout as `pty: PATH`), paced to the wall clock, or as fast as the host keeps up
//! with `--fast`. `STIFFWALL_EMU_TRACE=1` logs pty traffic, output changes, IWDG and flash
//! operations on stderr. License: GPL-2.0-or-later (it links unicorn, GPL-2.0).

mod emu;
mod image;
mod periph;
mod plant;
mod pty;
mod trace;

use anyhow::{bail, Context, Result};
use clap::Parser;
use periph::{Periph, UNITS_PER_S};
use std::path::PathBuf;

#[derive(Debug, Parser)]
#[command(
    name = "stiffwall-board-emu",
    about = "Runs the Nucleo-F446RE image on an emulated STM32F446 coupled to the simulated plant"
)]
struct Args {
    /// The firmware ELF (`cargo xtask firmware` output for nucleo-f446re).
    #[arg(long)]
    elf: PathBuf,
    /// Refuse the ELF unless its SHA-256 (hex) is this.
    #[arg(long)]
    sha256: Option<String>,
    /// The force output the image must be built for: `dac` or `pwm` (refused otherwise).
    #[arg(long, value_parser = ["dac", "pwm"])]
    output: Option<String>,
    /// With --seconds: fail unless TIM7 (the servo tick) ran at this rate, Hz (±0.01 %).
    #[arg(long)]
    expect_servo_hz: Option<f64>,
    /// Device preset for the plant (see `stiffwall_core::devices`).
    #[arg(long, conflicts_with = "plant")]
    device: Option<String>,
    /// Scene / plant file (its [device] and [effects]).
    #[arg(long)]
    plant: Option<PathBuf>,
    /// Run this many emulated seconds without a host and print a report.
    #[arg(long)]
    seconds: Option<f64>,
    /// Serve USART2 on a pseudo-terminal.
    #[arg(long)]
    pty: bool,
    /// With --pty: run ahead of the wall clock while the host keeps up.
    #[arg(long)]
    fast: bool,
    /// Stop the main loop (thread mode) after this many emulated seconds: for the watchdog test.
    #[arg(long)]
    hang_main_after: Option<f64>,
    /// Load the config store (sectors 6-7, 256 KiB) from this file and save it back on exit.
    #[arg(long)]
    store: Option<PathBuf>,
}

fn build_plant(args: &Args, rig: &image::Rig) -> Result<stiffwall_sim::rich::RichPlant> {
    use stiffwall_sim::rich::{PlantModel, RichPlant};
    // (the model, whether the device is rotary)
    let (model, rotary) = if let Some(path) = &args.plant {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("reading plant file {}", path.display()))?;
        let m = PlantModel::from_scene_toml(&text)
            .map(|(m, _)| m)
            .map_err(|e| anyhow::anyhow!("plant file {}: {e}", path.display()))?;
        let rotary = m.counts_per_rev.is_some();
        (m, rotary)
    } else {
        let name = args.device.as_deref().unwrap_or("maxon-re35");
        let d = stiffwall_core::devices::find(name).with_context(|| {
            format!(
                "unknown device {name:?} (allowed: {})",
                stiffwall_core::devices::NAMES
            )
        })?;
        let p = d.params;
        let m = PlantModel::rigid(p.mass, p.viscous, p.coulomb, p.resolution)
            .map_err(|e| anyhow::anyhow!("device {name}: {e}"))?;
        (m, p.rotational)
    };
    // The image reports the rig of its src/rig.rs to the host; a plant with another encoder
    // would be read through the wrong resolution.
    let what = args.plant.as_ref().map_or_else(
        || format!("device {}", args.device.as_deref().unwrap_or("maxon-re35")),
        |p| format!("plant file {}", p.display()),
    );
    let same_encoder =
        rotary == rig.rotary() && (model.resolution_m / rig.resolution - 1.0).abs() < 1e-6;
    if !same_encoder {
        let plant = if rotary {
            format!(
                "rotary with {} counts/rev",
                (std::f64::consts::TAU / model.resolution_m).round()
            )
        } else {
            format!("linear with {:.4e} m per count", model.resolution_m)
        };
        bail!(
            "{what} is {plant}, but the image's rig (src/rig.rs) is {}: allowed only plants \
             with the rig's encoder (a device of its own needs its rig.rs constants and a \
             rebuilt image; the board crate's feature rig-phantom is the worked example for \
             phantom-1.0, built by `cargo xtask board-emu --build`)",
            rig.describe()
        );
    }
    RichPlant::new(&model).map_err(|e| anyhow::anyhow!("plant: {e}"))
}

fn main() {
    if let Err(e) = run() {
        eprintln!("stiffwall-board-emu: error: {e:#}");
        std::process::exit(1);
    }
}

fn run() -> Result<()> {
    let args = Args::parse();
    let img = load_image(&args)?;
    let plant = build_plant(&args, &img.rig)?;
    let mut p = Periph::new(plant::Coupling::new(Some(plant)).with_rig(img.rig));
    load_store(&args, &mut p)?;
    let mut m = emu::Machine::new(img, p)?;
    let result = if args.pty {
        serve_pty(&args, &mut m)
    } else {
        let end = seconds_end(&args)?;
        run_seconds(&args, &mut m, end)
    };
    save_store(&args, &mut m)?;
    result
}

/// Loads the ELF and refuses it unless it has the SHA-256 and the output asked for.
fn load_image(args: &Args) -> Result<image::Image> {
    let img = image::load(&args.elf)?;
    if let Some(want) = &args.sha256 {
        if !want.eq_ignore_ascii_case(&img.sha256) {
            bail!(
                "refusing {}: SHA-256 {} is not the expected {want}",
                args.elf.display(),
                img.sha256
            );
        }
    }
    if let Some(want) = args.output.as_deref() {
        let have = match img.output {
            image::Output::Dac => "dac",
            image::Output::Pwm => "pwm",
        };
        if want != have {
            bail!(
                "refusing {}: it is the {have} build, --output asks for {want}",
                args.elf.display()
            );
        }
    }
    eprintln!(
        "stiffwall-board-emu: {} ({:?} output, rig {}), sha256 {}",
        args.elf.display(),
        img.output,
        img.rig.describe(),
        img.sha256
    );
    Ok(img)
}

/// With --store: the config store from that file, if it exists (it must be exactly the
/// store's size).
fn load_store(args: &Args, p: &mut Periph) -> Result<()> {
    if let Some(path) = &args.store {
        if let Ok(bytes) = std::fs::read(path) {
            if bytes.len() != p.store.len() {
                bail!(
                    "--store {}: {} bytes, allowed exactly {} (sectors 6-7)",
                    path.display(),
                    bytes.len(),
                    p.store.len()
                );
            }
            p.store = bytes;
        }
    }
    Ok(())
}

/// With --store: the config store back to that file.
fn save_store(args: &Args, m: &mut emu::Machine<'_>) -> Result<()> {
    if let Some(path) = &args.store {
        std::fs::write(path, &m.periph().store)
            .with_context(|| format!("saving the config store to {}", path.display()))?;
    }
    Ok(())
}

/// --pty: serves USART2 until the host is gone, then reports.
fn serve_pty(args: &Args, m: &mut emu::Machine<'_>) -> Result<()> {
    // The host holds our stdin: when it goes away (even killed), stdin closes and the run
    // ends with a report.
    std::thread::spawn(|| {
        let mut sink = Vec::new();
        let _ = std::io::Read::read_to_end(&mut std::io::stdin(), &mut sink);
        pty::STOP.store(true, std::sync::atomic::Ordering::Relaxed);
    });
    let r = pty::serve(m, args.fast, args.hang_main_after, args.store.as_deref());
    report(m);
    r
}

/// The end of a --seconds run (1 s by default), units; refused outside 0 < S <= 3600.
fn seconds_end(args: &Args) -> Result<u64> {
    let secs = args.seconds.unwrap_or(1.0);
    if !(secs > 0.0 && secs <= 3600.0) {
        bail!("--seconds {secs}: allowed 0 < S <= 3600");
    }
    Ok((secs * UNITS_PER_S as f64) as u64)
}

/// Runs without a host until `end`, reports, and checks the servo rate if asked to.
fn run_seconds(args: &Args, m: &mut emu::Machine<'_>, end: u64) -> Result<()> {
    if let Some(h) = args.hang_main_after {
        m.hang_main_at = Some((h * UNITS_PER_S as f64) as u64);
    }
    let r = m.run_until(end);
    report(m);
    r.and_then(|()| check_servo_rate(m, args.expect_servo_hz))
}

/// The TIM7 update rate over the run, Hz.
fn servo_rate(m: &mut emu::Machine<'_>) -> Option<f64> {
    let t = &m.periph().tim7;
    let first = t.first_update?;
    (t.updates > 1)
        .then(|| (t.updates - 1) as f64 / ((t.last_update - first) as f64 / UNITS_PER_S as f64))
}

fn check_servo_rate(m: &mut emu::Machine<'_>, want: Option<f64>) -> Result<()> {
    let Some(want) = want else { return Ok(()) };
    let have = servo_rate(m).unwrap_or(0.0);
    if (have / want - 1.0).abs() > 1e-4 {
        let (psc, arr) = (m.periph().tim7.r[10], m.periph().tim7.r[11]);
        bail!(
            "TIM7 (servo tick) runs at {have:.3} Hz, expected {want} Hz +/- 0.01 % \
             (TIM7_PSC = {psc}, TIM7_ARR = {arr}, APB1 timer clock {:.3} MHz)",
            m.periph().clocks().tim1clk_apb1 / 1e6
        );
    }
    Ok(())
}

/// The name of exception number `exc` (16 + IRQ for interrupts) among those the image enables.
fn exception_name(exc: usize) -> String {
    match exc.checked_sub(16) {
        Some(periph::IRQ_TIM2) => "TIM2".into(),
        Some(periph::IRQ_USART2) => "USART2".into(),
        Some(periph::IRQ_TIM7) => "TIM7".into(),
        Some(irq) => format!("IRQ {irq}"),
        None => format!("exception {exc}"),
    }
}

/// Prints what the run measured: clocks, servo rate, cycles per tick, CPU load, resets.
pub fn report(m: &mut emu::Machine<'_>) {
    let now = m.now();
    let asleep = m.asleep;
    let since = m.stats_since;
    let insns = m.insns();
    let ticks = m.ticks.clone();
    let resets = m.resets.clone();
    let preemptions = m.preemptions.clone();
    let pc = m.pc();
    let p = m.periph();
    let c = p.clocks();
    let t = now as f64 / UNITS_PER_S as f64;
    eprintln!("emulated time: {t:.6} s, {insns} instructions, pc {pc:#010x}");
    eprintln!(
        "clocks: SYSCLK {:.3} MHz, HCLK {:.3} MHz, PCLK1 {:.3} MHz, PCLK2 {:.3} MHz, APB1 timers {:.3} MHz, APB2 timers {:.3} MHz, flash {} wait states",
        c.sysclk / 1e6,
        c.hclk / 1e6,
        c.pclk1 / 1e6,
        c.pclk2 / 1e6,
        c.tim1clk_apb1 / 1e6,
        c.timclk_apb2 / 1e6,
        p.flash[0] & 0xF
    );
    let tim7 = &p.tim7;
    if let (Some(first), true) = (tim7.first_update, tim7.updates > 1) {
        let span = (tim7.last_update - first) as f64 / UNITS_PER_S as f64;
        eprintln!(
            "TIM7: {} update events, {:.3} Hz (PSC {}, ARR {})",
            tim7.updates,
            (tim7.updates - 1) as f64 / span,
            tim7.r[10],
            tim7.r[11]
        );
    }
    if ticks.count > 0 {
        eprintln!(
            "servo tick: {} handler runs, mean {:.0} cycles, max {} cycles (instructions, CPI 1, plus 24 cycles entry/exit)",
            ticks.count,
            ticks.insns as f64 / ticks.count as f64,
            ticks.max
        );
    }
    let window = now.saturating_sub(since).max(1);
    eprintln!(
        "CPU load: {:.2} % awake over {:.3} s",
        100.0 * (1.0 - asleep as f64 / window as f64),
        window as f64 / UNITS_PER_S as f64
    );
    eprintln!(
        "USART2: {} bytes sent, {} overruns; IWDG: {} feeds; flash: {} erases, {} words programmed",
        p.usart.sent, p.usart.overruns, p.iwdg.feeds, p.erases, p.programs
    );
    for ((taken, below), n) in &preemptions {
        eprintln!(
            "preemption: {} preempted {} {n} times",
            exception_name(*taken),
            exception_name(*below)
        );
    }
    let (length, force) = if p.plant.rig().rotary() {
        ("rad", "N·m")
    } else {
        ("m", "N")
    };
    eprintln!(
        "plant: position {:.6} {length}, force {:.6} {force}, {} output changes",
        p.plant.position(),
        p.plant.force(),
        p.plant.changes
    );
    for (at, cause) in resets {
        eprintln!(
            "reset at {:.6} s: {cause:?}",
            at as f64 / UNITS_PER_S as f64
        );
    }
}
