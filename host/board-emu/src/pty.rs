//! USART2 served on a pseudo-terminal: the host (hostctl, through `--board-emulator`) opens the
//! pty's path, printed on stdout as `pty: PATH`, as it would open the Nucleo's ST-LINK port.
//!
//! Units: emulated time in 1/720 MHz units; host bytes are shifted into USART2 at the
//! configured baud rate (one byte per 10 bit times). Pacing: by default emulated time follows
//! the wall clock (never ahead of it, as a real board); with `fast` it may run ahead of the wall
//! clock, but by at most `FAST_LEAD_S` of emulated time past the last byte the host sent (so
//! the firmware's heartbeat timeout, 500 ms by default, never trips because the host's clock is
//! slower; flash stalls excepted), and never while more than `TX_BACKLOG` bytes wait for the host to read. Invariants:
//! no byte is dropped between the pty and the UART model (the pty is read only while fewer than
//! `RX_HELD` bytes wait); the emulator exits when the host side is gone for good (hang-up after
//! it was opened once) or on a run error.

use crate::emu::Machine;
use crate::periph::UNITS_PER_S;
use anyhow::{Context, Result};
use serialport::SerialPort as _;
use std::io::{ErrorKind, Read, Write};
use std::time::{Duration, Instant};

/// Emulated time run per slice between pty polls, seconds.
const SLICE_S: f64 = 200e-6;
/// How far emulated time may run past the last host byte in fast mode, seconds.
pub const FAST_LEAD_S: f64 = 0.25;
/// Bytes waiting for the host above which emulated time stops.
const TX_BACKLOG: usize = 4096;
/// Host bytes held in the emulator at most.
const RX_HELD: usize = 4096;

/// Set when the host is gone (our stdin closed): `serve` returns.
pub static STOP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Serves USART2 on a new pty until the host hangs up or the run fails. `hang_after`: stop
/// the main loop's progress after that many seconds (watchdog test; see `Machine`).
/// `store`: the file the config store (sectors 6–7) is written to after every flash
/// operation, so a later run (a power cycle) starts from it.
pub fn serve(
    m: &mut Machine<'_>,
    fast: bool,
    hang_after: Option<f64>,
    store: Option<&std::path::Path>,
) -> Result<()> {
    let (master, slave) = open_pty()?;
    // Keep the slave open: the master never sees a hang-up while the host (re)opens the path.
    let _slave = slave;
    if let Some(h) = hang_after {
        m.hang_main_at = Some((h * UNITS_PER_S as f64) as u64);
    }
    let mut link = Link::new(master, m, fast);
    loop {
        if STOP.load(std::sync::atomic::Ordering::Relaxed) {
            return Ok(());
        }
        link.restart_stats_on_new_rate(m);
        link.save_store(m, store)?;
        link.host_to_uart(m)?;
        link.uart_to_host(m)?;
        link.trace_status(m);
        match link.run_end(m) {
            Some(end) => m.run_until(end)?,
            None => std::thread::sleep(Duration::from_micros(200)),
        }
    }
}

/// Opens the pty pair and prints the path the host opens (`pty: PATH` on stdout).
fn open_pty() -> Result<(serialport::TTYPort, serialport::TTYPort)> {
    let (mut master, slave) = serialport::TTYPort::pair().context("creating the pty")?;
    let name = slave.name().context("the pty has no name")?;
    master
        .set_timeout(Duration::from_millis(0))
        .context("pty timeout")?;
    println!("pty: {name}");
    std::io::stdout().flush().ok();
    Ok((master, slave))
}

/// The serving loop's state: the pty, the pacing clocks and what was last seen.
struct Link {
    /// The pty's master side.
    master: serialport::TTYPort,
    /// Run ahead of the wall clock while the host keeps up.
    fast: bool,
    /// Emulated time per slice, units.
    slice: u64,
    /// How far emulated time may run past the last host byte in fast mode, units.
    lead: u64,
    /// Wall-clock start.
    start: Instant,
    /// Emulated time at the start, units.
    t0: u64,
    /// Emulated time of the last byte from the host, units.
    last_host: u64,
    /// `Periph::stalled_total` at the last byte from the host.
    stall_at_last_host: u64,
    /// Receive buffer.
    buf: [u8; 1024],
    /// `STIFFWALL_EMU_TRACE`.
    trace: bool,
    /// When the last status line was traced.
    last_trace: Instant,
    /// Flash erases and programs at the last store save.
    flash_ops: (u64, u64),
    /// TIM7 PSC and ARR at the last statistics restart.
    servo_timer: (u32, u32),
}

impl Link {
    /// The state at the start of serving `m` on `master`.
    fn new(master: serialport::TTYPort, m: &mut Machine<'_>, fast: bool) -> Self {
        let t0 = m.now();
        Self {
            master,
            fast,
            slice: (SLICE_S * UNITS_PER_S as f64) as u64,
            lead: (FAST_LEAD_S * UNITS_PER_S as f64) as u64,
            start: Instant::now(),
            t0,
            last_host: t0,
            stall_at_last_host: m.periph().stalled_total,
            buf: [0u8; 1024],
            trace: crate::trace::enabled(),
            last_trace: Instant::now(),
            flash_ops: (m.periph().erases, m.periph().programs),
            servo_timer: (m.periph().tim7.r[10], m.periph().tim7.r[11]),
        }
    }

    /// Statistics start afresh whenever the servo rate changes (TIM7 PSC/ARR).
    fn restart_stats_on_new_rate(&mut self, m: &mut Machine<'_>) {
        let t7 = (m.periph().tim7.r[10], m.periph().tim7.r[11]);
        if t7 != self.servo_timer {
            self.servo_timer = t7;
            m.reset_stats();
        }
    }

    /// Writes the config store to `store` after a flash operation.
    fn save_store(&mut self, m: &mut Machine<'_>, store: Option<&std::path::Path>) -> Result<()> {
        if let Some(path) = store {
            let ops = (m.periph().erases, m.periph().programs);
            if ops != self.flash_ops {
                self.flash_ops = ops;
                std::fs::write(path, &m.periph().store)
                    .with_context(|| format!("saving the config store to {}", path.display()))?;
            }
        }
        Ok(())
    }

    /// Host → UART: what the host sent, while fewer than `RX_HELD` bytes wait.
    fn host_to_uart(&mut self, m: &mut Machine<'_>) -> Result<()> {
        let held = m.periph().usart.rx_fifo.len();
        if held >= RX_HELD {
            return Ok(());
        }
        let room = (RX_HELD - held).min(self.buf.len());
        match self.master.read(&mut self.buf[..room]) {
            Ok(n) if n > 0 => {
                if self.trace {
                    eprintln!(
                        "pty: {n} bytes in at {:.6} s",
                        m.now() as f64 / UNITS_PER_S as f64
                    );
                }
                m.periph().usart.rx_fifo.extend(&self.buf[..n]);
                self.last_host = m.now();
                self.stall_at_last_host = m.periph().stalled_total;
            }
            Ok(_) => {}
            Err(e) if transient(&e) => {}
            Err(e) => return Err(e).context("reading the pty"),
        }
        Ok(())
    }

    /// UART → host: what the firmware sent, as far as the pty takes it.
    fn uart_to_host(&mut self, m: &mut Machine<'_>) -> Result<()> {
        let out = &mut m.periph().usart.tx_out;
        if out.is_empty() {
            return Ok(());
        }
        let (a, _) = out.as_slices();
        match self.master.write(a) {
            Ok(n) => {
                out.drain(..n);
                if self.trace {
                    eprintln!("pty: {n} bytes out");
                }
            }
            Err(e) if transient(&e) => {}
            Err(e) => return Err(e).context("writing the pty"),
        }
        Ok(())
    }

    /// With tracing, a status line every 300 ms of wall time.
    fn trace_status(&mut self, m: &mut Machine<'_>) {
        if self.trace && self.last_trace.elapsed() > Duration::from_millis(300) {
            self.last_trace = Instant::now();
            let resets = m.resets.clone();
            eprintln!(
                "pty: at {:.6} s, pc {:#010x}, resets {:?}, rx held {}, tx held {}",
                m.now() as f64 / UNITS_PER_S as f64,
                m.pc(),
                resets,
                m.periph().usart.rx_fifo.len(),
                m.periph().usart.tx_out.len()
            );
        }
    }

    /// Where the next slice ends, or None while emulated time must wait (the host is behind
    /// on reading, or emulated time has caught up with what pacing allows).
    fn run_end(&mut self, m: &mut Machine<'_>) -> Option<u64> {
        let backlog = m.periph().usart.tx_out.len();
        let wall = self.t0 + (self.start.elapsed().as_secs_f64() * UNITS_PER_S as f64) as u64;
        let now = m.now();
        let allowed = if self.fast {
            // Flash stalls (a 1 s sector erase) are not held against the host.
            let stalled = m.periph().stalled_total;
            (wall + stalled).max(self.last_host + self.lead + (stalled - self.stall_at_last_host))
        } else {
            wall
        };
        if backlog > TX_BACKLOG || now >= allowed {
            return None;
        }
        Some((now + self.slice).min(allowed.max(now + 1)))
    }
}

fn transient(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
    )
}
