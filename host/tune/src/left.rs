//! What tune leaves the device as (issue 46): the final check's record, the `device left`
//! line of the report and the JSON (a leaf of the crate, so that the error type can carry it).
//!
//! Units: raw encoder counts (the frame of `ServoConfig::wall_position`).

use stiffwall_proto::fault;

/// What the device was left as: the report's `device left` line and the JSON's.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DeviceLeft {
    /// Raw count where it came to rest (or was last seen).
    pub count: i64,
    /// Raw count where it started.
    pub start: i64,
    /// Whether it was at rest.
    pub at_rest: bool,
    /// Faults latched after the final config was set, by name.
    pub faults: Vec<String>,
    /// Whether the final check passed: at rest, no fault, within [`LEFT_TOLERANCE_COUNTS`] of
    /// the start (or where the set wall holds it, when that wall pulls it elsewhere).
    pub ok: bool,
    /// Why it failed, when it did.
    pub problem: Option<String>,
    /// Why a device resting farther than [`LEFT_TOLERANCE_COUNTS`] from its start passed (the
    /// band static friction leaves the way back's stiffest spring), when it did.
    #[serde(default)]
    pub note: Option<String>,
}

/// The final check's tolerance on the position, counts.
pub const LEFT_TOLERANCE_COUNTS: i64 = 2;

impl core::fmt::Display for DeviceLeft {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "device left: count {} (started at {}), {}, {}",
            self.count,
            self.start,
            if self.at_rest { "at rest" } else { "moving" },
            if self.faults.is_empty() {
                "no fault".to_string()
            } else {
                format!("faults latched: {}", self.faults.join(", "))
            }
        )?;
        if let Some(p) = &self.problem {
            write!(f, ": {p}")?;
        }
        if let Some(n) = &self.note {
            write!(f, " ({n})")?;
        }
        Ok(())
    }
}

/// Names of the fault bits in `latched`.
#[must_use]
pub fn fault_names(latched: u32) -> Vec<String> {
    fault::NAMES
        .iter()
        .filter(|(bit, _, _)| latched & bit != 0)
        .map(|(_, name, _)| (*name).to_string())
        .collect()
}
