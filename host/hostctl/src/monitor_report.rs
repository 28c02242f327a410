//! The text of the firmware's energy monitor run over a recording (`hostctl replay`, part (c)),
//! computed by [`stiffwall_analysis::monitor_report`] (re-exported here).
//!
//! Units: `count` raw encoder counts relative to the wall, energies `e8` in units of
//! K·Δ_eff²/8, ticks the device's servo ticks.

use std::fmt::Write as _;
pub use stiffwall_analysis::monitor_report::*;

/// Text lines of the monitor replay.
#[must_use]
pub fn render(r: &MonitorReplay) -> String {
    let mut s = String::new();
    let _ = write!(
        s,
        "(c) energy monitor{} (trip score {}, limit e8 {}): {} ticks, {} turning points",
        if r.device_monitor_on {
            ""
        } else {
            " [off on the device: what would have latched]"
        },
        r.trip,
        r.limit_e8,
        r.monitored,
        r.turning_points
    );
    if let Some((e8, tick)) = r.max_e8 {
        let _ = write!(s, ", max energy e8 {e8} at tick {tick}");
    }
    let _ = write!(
        s,
        "; {} event(s){}",
        r.events.len(),
        if r.events.is_empty() { "" } else { ":" }
    );
    for e in &r.events {
        let _ = write!(
            s,
            "\n    tick {} (seq {}): {} at count {}, score {}, peak n {} e8 {} ({:.3e} J){}",
            e.tick,
            e.seq,
            e.fault,
            e.count,
            e.score,
            e.peak_n,
            e.peak_e8,
            e.peak_energy_j,
            if e.device_latched_here {
                "; the device latched a fault here"
            } else {
                ""
            }
        );
    }
    s
}
