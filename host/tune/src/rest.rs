//! The device at rest and its faults cleared: the two waits every experiment of tune starts
//! with (a leaf of the crate: it imports only the error type).
//!
//! Units: counts are effective counts from the configured wall position; times are host
//! seconds (the waits' limits).

use super::error::{bail, Result, StepError};
use stiffwall_client::Client;

/// Host time the device gets to come to rest, s ([`rest_position`]).
pub const REST_WAIT_S: f64 = 20.0;

/// Host time a telemetry batch is waited for before the waits look at their deadline again.
pub const BATCH_WAIT: std::time::Duration = std::time::Duration::from_millis(200);

/// Host time the servo gets to take a fault clear ([`clear_faults`]).
pub const CLEAR_WAIT: std::time::Duration = std::time::Duration::from_secs(2);

/// Host time between two tries of [`clear_faults`].
pub const CLEAR_RETRY: std::time::Duration = std::time::Duration::from_millis(5);

/// Waits until the device (wall off) has stopped; returns its count from the wall position.
///
/// # Errors
/// The device failing, or not at rest within [`REST_WAIT_S`].
pub fn rest_position(c: &mut Client) -> Result<i32> {
    rest_position_within(c, REST_WAIT_S)
}

/// [`rest_position`] with a wait of `seconds` of host time (a long gentle move needs more).
///
/// # Errors
/// The device failing, or not at rest within `seconds`.
pub fn rest_position_within(c: &mut Client, seconds: f64) -> Result<i32> {
    let rate = c.info.servo_rate_hz.max(1);
    // One sample every 2 ms of device time; at rest when 50 consecutive samples agree.
    let decimation = u16::try_from((rate / 500).max(1)).unwrap_or(u16::MAX);
    c.stream_start(decimation)?;
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs_f64(seconds);
    let (mut last, mut same) = (i32::MIN, 0u32);
    let result = loop {
        if std::time::Instant::now() > deadline {
            break Err(StepError::NotAtRest { waited_s: seconds });
        }
        if let Some(b) = c.next_batch(BATCH_WAIT)? {
            for x in &b.samples {
                if x.count == last {
                    same += 1;
                } else {
                    (last, same) = (x.count, 0);
                }
            }
            if same >= 50 {
                break Ok(last);
            }
        }
    };
    c.stream_stop()?;
    result
}

/// Clears the latched faults and waits until the servo has taken the command (the device
/// answers `GetFaults` from state the servo updates on its next tick).
pub fn clear_faults(c: &mut Client) -> Result<()> {
    let deadline = std::time::Instant::now() + CLEAR_WAIT;
    loop {
        c.clear_faults()?;
        let f = c.faults()?;
        if f.latched == 0 {
            return Ok(());
        }
        if std::time::Instant::now() > deadline {
            bail!(
                "faults {} stay latched (first at tick {})",
                super::left::fault_names(f.latched).join(", "),
                f.first_tick
            );
        }
        std::thread::sleep(CLEAR_RETRY);
    }
}
