//! The pure data of what travels between `hostctl ui` and its page (the command parsing, the
//! server and the configuration command stay in `hostctl`'s `cmd::ui::wire`): the page's
//! release test and tune arguments ([`ReleaseTest`], [`TuneTest`]) and the binary telemetry
//! frame.
//!
//! Telemetry (server → page, binary, little-endian): `u32` magic [`FRAME_MAGIC`], `u32` chunk
//! count; per chunk `u32` seq of its first sample, `u32` n, then n samples of [`SAMPLE_BYTES`]
//! bytes: `u32` tick, `i32` count, `i32` force_code, `u16` flags, `u32` energy (the units of
//! [`stiffwall_proto::Sample`]). Every sample the device sent is in exactly one frame.

use stiffwall_proto::{fault, Sample};

/// First word of every binary telemetry frame ("SWT1").
pub const FRAME_MAGIC: u32 = 0x3154_5753;
/// Bytes per sample in a telemetry frame.
pub const SAMPLE_BYTES: usize = 18;

/// The page's release test: `experiment release`'s test flags.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub struct ReleaseTest {
    /// Initial deflection, effective encoder ticks.
    pub deflection: i32,
    /// Servo ticks recorded after the release.
    #[serde(default = "default_ticks")]
    pub ticks: u32,
    /// Wall stiffness for the test (default: the configured K).
    #[serde(default)]
    pub stiffness: Option<f64>,
}

fn default_ticks() -> u32 {
    crate::release::DEFAULT_RELEASE_TICKS
}

/// The page's tune: `tune`'s flags that the page may give (the others choose the device, the
/// output or the plot).
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub struct TuneTest {
    /// Expected maximum velocity (default: 5 ticks per period).
    pub max_velocity: Option<f64>,
    /// Fraction of the largest resting K that is set.
    pub margin: Option<f64>,
    /// Ticks per release test.
    pub release_ticks: Option<u32>,
    /// Duration of the identification excitation, s.
    pub excite_seconds: Option<f64>,
    /// Find and report K, but leave the device's config as it was.
    #[serde(default)]
    pub dry_run: bool,
}

/// Appends one chunk (consecutive samples from `seq`) to a frame body.
pub fn push_chunk(body: &mut Vec<u8>, seq: u32, samples: &[Sample]) {
    body.extend_from_slice(&seq.to_le_bytes());
    body.extend_from_slice(&(samples.len() as u32).to_le_bytes());
    for s in samples {
        body.extend_from_slice(&s.tick.to_le_bytes());
        body.extend_from_slice(&s.count.to_le_bytes());
        body.extend_from_slice(&s.force_code.to_le_bytes());
        body.extend_from_slice(&s.flags.to_le_bytes());
        body.extend_from_slice(&s.energy.to_le_bytes());
    }
}

/// A whole frame: header and `chunks` chunks of `body`.
#[must_use]
pub fn frame(chunks: u32, body: &[u8]) -> Vec<u8> {
    let mut v = Vec::with_capacity(8 + body.len());
    v.extend_from_slice(&FRAME_MAGIC.to_le_bytes());
    v.extend_from_slice(&chunks.to_le_bytes());
    v.extend_from_slice(body);
    v
}

/// Names of the latched fault bits.
#[must_use]
pub fn fault_names(bits: u32) -> Vec<&'static str> {
    fault::NAMES
        .into_iter()
        .filter(|(b, _, _)| bits & b != 0)
        .map(|(_, _, label)| label)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_layout() {
        let s = Sample {
            tick: 7,
            count: -3,
            force_code: 120,
            flags: 5,
            energy: 26,
        };
        let mut body = Vec::new();
        push_chunk(&mut body, 1200, &[s, s]);
        let f = frame(1, &body);
        assert_eq!(f.len(), 8 + 8 + 2 * SAMPLE_BYTES);
        assert_eq!(&f[0..4], b"SWT1");
        assert_eq!(u32::from_le_bytes(f[8..12].try_into().unwrap()), 1200);
        assert_eq!(i32::from_le_bytes(f[20..24].try_into().unwrap()), -3);
        assert_eq!(u16::from_le_bytes(f[28..30].try_into().unwrap()), 5);
        assert_eq!(u32::from_le_bytes(f[30..34].try_into().unwrap()), 26);
    }

    #[test]
    fn fault_bits_are_named() {
        assert_eq!(
            fault_names(fault::BUZZ | fault::ENERGY_GROWTH),
            ["energy growth", "buzz"]
        );
        assert!(fault_names(0).is_empty());
    }
}
