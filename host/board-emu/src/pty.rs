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
    let (mut master, slave) = serialport::TTYPort::pair().context("creating the pty")?;
    let name = slave.name().context("the pty has no name")?;
    master
        .set_timeout(Duration::from_millis(0))
        .context("pty timeout")?;
    println!("pty: {name}");
    std::io::stdout().flush().ok();
    // Keep the slave open: the master never sees a hang-up while the host (re)opens the path.
    let _slave = slave;
    if let Some(h) = hang_after {
        m.hang_main_at = Some((h * UNITS_PER_S as f64) as u64);
    }
    let slice = (SLICE_S * UNITS_PER_S as f64) as u64;
    let lead = (FAST_LEAD_S * UNITS_PER_S as f64) as u64;
    let start = Instant::now();
    let t0 = m.now();
    let mut last_host = t0;
    let mut stall_at_last_host = m.periph().stalled_total;
    let mut buf = [0u8; 1024];
    let trace = crate::trace::enabled();
    let mut last_trace = Instant::now();
    let mut flash_ops = (m.periph().erases, m.periph().programs);
    let mut servo_timer = (m.periph().tim7.r[10], m.periph().tim7.r[11]);
    loop {
        if STOP.load(std::sync::atomic::Ordering::Relaxed) {
            return Ok(());
        }
        // Statistics start afresh whenever the servo rate changes (TIM7 PSC/ARR).
        let t7 = (m.periph().tim7.r[10], m.periph().tim7.r[11]);
        if t7 != servo_timer {
            servo_timer = t7;
            m.reset_stats();
        }
        if let Some(path) = store {
            let ops = (m.periph().erases, m.periph().programs);
            if ops != flash_ops {
                flash_ops = ops;
                std::fs::write(path, &m.periph().store)
                    .with_context(|| format!("saving the config store to {}", path.display()))?;
            }
        }
        // Host → UART.
        let held = m.periph().usart.rx_fifo.len();
        if held < RX_HELD {
            let room = (RX_HELD - held).min(buf.len());
            match master.read(&mut buf[..room]) {
                Ok(n) if n > 0 => {
                    if trace {
                        eprintln!(
                            "pty: {n} bytes in at {:.6} s",
                            m.now() as f64 / UNITS_PER_S as f64
                        );
                    }
                    m.periph().usart.rx_fifo.extend(&buf[..n]);
                    last_host = m.now();
                    stall_at_last_host = m.periph().stalled_total;
                }
                Ok(_) => {}
                Err(e) if transient(&e) => {}
                Err(e) => return Err(e).context("reading the pty"),
            }
        }
        // UART → host.
        let out = &mut m.periph().usart.tx_out;
        if !out.is_empty() {
            let (a, _) = out.as_slices();
            match master.write(a) {
                Ok(n) => {
                    out.drain(..n);
                    if trace {
                        eprintln!("pty: {n} bytes out");
                    }
                }
                Err(e) if transient(&e) => {}
                Err(e) => return Err(e).context("writing the pty"),
            }
        }
        if trace && last_trace.elapsed() > Duration::from_millis(300) {
            last_trace = Instant::now();
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
        let backlog = m.periph().usart.tx_out.len();
        let wall = t0 + (start.elapsed().as_secs_f64() * UNITS_PER_S as f64) as u64;
        let now = m.now();
        let allowed = if fast {
            // Flash stalls (a 1 s sector erase) are not held against the host.
            let stalled = m.periph().stalled_total;
            (wall + stalled).max(last_host + lead + (stalled - stall_at_last_host))
        } else {
            wall
        };
        if backlog > TX_BACKLOG || now >= allowed {
            std::thread::sleep(Duration::from_micros(200));
            continue;
        }
        m.run_until((now + slice).min(allowed.max(now + 1)))?;
    }
}

fn transient(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
    )
}
