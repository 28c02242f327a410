//! Which device to talk to ([`ConnectSpec`]: the virtual device with a preset or a plant
//! file, a serial port, or the QEMU board image) and [`connect`], which reaches it and performs
//! the handshake. No command-line types: a front end builds a [`ConnectSpec`] from its own
//! options.

use crate::client::Client;
use crate::error::Result;
#[cfg(feature = "virtual")]
use crate::pace::Pace;
use crate::transport;
use std::path::PathBuf;

/// The virtual device's plant when none is named: the paper's own rig (Sec. V).
pub const DEFAULT_VIRTUAL_DEVICE: &str = "maxon-re35";

/// The plant behind the virtual device.
#[derive(Debug, Clone, PartialEq)]
pub enum VirtualPlant {
    /// A preset of [`stiffwall_core::devices`] by name (e.g. `"maxon-re35"`).
    Preset(String),
    /// A scene file (`sim/plants/*.toml`, `sim/scenes/*.toml`): its `[device]` and `[effects]`
    /// are the plant, its `[controller]` the boot configuration.
    File(PathBuf),
}

impl Default for VirtualPlant {
    fn default() -> Self {
        Self::Preset(DEFAULT_VIRTUAL_DEVICE.into())
    }
}

/// How to reach a device.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum ConnectSpec {
    /// The built-in virtual device (firmware core + simulated plant) on a pseudo-terminal.
    #[cfg(feature = "virtual")]
    Virtual {
        /// Its plant.
        plant: VirtualPlant,
        /// In real time, or as fast as the host reads.
        pace: Pace,
        /// Where to write the plant's true state every tick (`--trace FILE`;
        /// [`crate::virtual_device::TRACE_HEADER`]). `None`: no trace.
        trace: Option<PathBuf>,
    },
    /// A real board on a serial port.
    Serial {
        /// Port path (e.g. `/dev/ttyACM0`).
        path: String,
        /// Baud rate ([`transport::DEFAULT_BAUD`] for the Nucleo's ST-LINK port).
        baud: u32,
    },
    /// The QEMU board image (mps2-an386) over `-serial pty`.
    #[cfg(feature = "qemu")]
    Qemu {
        /// The image (None: `$STIFFWALL_QEMU_IMAGE` or the `cargo xtask firmware` output).
        image: Option<PathBuf>,
    },
    /// The Nucleo-F446RE image on the board emulator (host/board-emu, a separate process).
    #[cfg(feature = "qemu")]
    BoardEmulator(crate::board_emu::Spec),
}

impl ConnectSpec {
    /// The virtual device running the plant of a scene file.
    #[cfg(feature = "virtual")]
    #[must_use]
    pub fn plant_file(path: impl Into<PathBuf>, pace: Pace) -> Self {
        Self::Virtual {
            plant: VirtualPlant::File(path.into()),
            pace,
            trace: None,
        }
    }

    /// The same target, with the virtual device writing its plant's true state every tick to
    /// `path` (no effect on other targets).
    #[must_use]
    pub fn with_trace(self, path: Option<PathBuf>) -> Self {
        match self {
            #[cfg(feature = "virtual")]
            Self::Virtual { plant, pace, .. } => Self::Virtual {
                plant,
                pace,
                trace: path,
            },
            other => other,
        }
    }

    /// The virtual device running a preset.
    #[cfg(feature = "virtual")]
    #[must_use]
    pub fn preset(name: impl Into<String>, pace: Pace) -> Self {
        Self::Virtual {
            plant: VirtualPlant::Preset(name.into()),
            pace,
            trace: None,
        }
    }

    /// A short description of the target, for reports.
    #[must_use]
    pub fn describe(&self) -> String {
        match self {
            #[cfg(feature = "virtual")]
            Self::Virtual { pace, .. } => format!(
                "virtual device ({}{})",
                self.virtual_plant_name().unwrap_or_default(),
                if pace.is_fast() { ", fast" } else { "" }
            ),
            Self::Serial { path, baud } => format!("serial port {path} at {baud} baud"),
            #[cfg(feature = "qemu")]
            Self::Qemu { .. } => "QEMU board image (mps2-an386)".into(),
            #[cfg(feature = "qemu")]
            Self::BoardEmulator(s) => format!(
                "board emulator (nucleo-f446re-{}{})",
                s.output.as_deref().unwrap_or("dac"),
                if s.pace.is_fast() { ", fast" } else { "" }
            ),
        }
    }

    /// The virtual device's plant as written in recordings (the preset name, or
    /// `plant:FILE`); None for other targets.
    #[must_use]
    pub fn virtual_plant_name(&self) -> Option<String> {
        match self {
            #[cfg(feature = "virtual")]
            Self::Virtual { plant, .. } => Some(match plant {
                VirtualPlant::Preset(name) => name.clone(),
                VirtualPlant::File(p) => format!("plant:{}", p.display()),
            }),
            _ => None,
        }
    }

    /// The virtual device's specification (None for other targets). Errors name the unknown
    /// preset or the plant file's bad key and its range.
    #[cfg(feature = "virtual")]
    pub fn virtual_spec(&self) -> Result<Option<crate::virtual_device::Spec>> {
        let Self::Virtual { plant, pace, trace } = self else {
            return Ok(None);
        };
        let name = match plant {
            VirtualPlant::File(path) => {
                let spec = crate::virtual_device::Spec::from_plant_file(path, *pace)?;
                return Ok(Some(crate::virtual_device::Spec {
                    trace: trace.clone(),
                    ..spec
                }));
            }
            VirtualPlant::Preset(name) => name,
        };
        let d = stiffwall_core::devices::find(name).ok_or_else(|| {
            crate::error::ClientError::Plant {
                path: None,
                message: format!(
                    "unknown device {name:?} (allowed: {})",
                    stiffwall_core::devices::NAMES
                ),
            }
        })?;
        let counts_per_rev = if d.params.rotational {
            (std::f64::consts::TAU / d.params.resolution).round() as u32
        } else {
            0
        };
        Ok(Some(crate::virtual_device::Spec {
            plant: d.params,
            counts_per_rev,
            pace: *pace,
            initial_position: 0.0,
            output_range: Some(d.force_limit),
            scene: None,
            travel: d.travel,
            trace: trace.clone(),
        }))
    }
}

/// Reaches the device `spec` names (starting the virtual device or QEMU if need be) and
/// performs the handshake.
pub fn connect(spec: &ConnectSpec) -> Result<Client> {
    match spec {
        #[cfg(feature = "virtual")]
        ConnectSpec::Virtual { .. } => {
            let vspec = spec.virtual_spec()?.expect("a virtual target");
            let (vd, port) = crate::virtual_device::spawn(vspec)?;
            Client::connect(port, Some(Box::new(vd)))
        }
        ConnectSpec::Serial { path, baud } => {
            let port = transport::open_port(path, *baud)?;
            Client::connect(port, None)
        }
        #[cfg(feature = "qemu")]
        ConnectSpec::Qemu { image } => {
            let image = crate::qemu::find_image(image.as_deref())?;
            let q = crate::qemu::boot(&image)?;
            let port = transport::open_port(&q.pty, transport::DEFAULT_BAUD)?;
            Client::connect(port, Some(Box::new(q)))
        }
        #[cfg(feature = "qemu")]
        ConnectSpec::BoardEmulator(s) => {
            let e = crate::board_emu::start(s)?;
            let port = transport::open_port(&e.pty, transport::DEFAULT_BAUD)?;
            Client::connect(port, Some(Box::new(e)))
        }
    }
}

#[cfg(all(test, feature = "virtual"))]
mod tests {
    use super::*;
    use crate::error::ClientError;

    #[test]
    fn connects_to_the_virtual_device_of_a_preset_and_names_it() {
        let spec = ConnectSpec::preset("maxon-re35", Pace::Fast);
        assert_eq!(spec.describe(), "virtual device (maxon-re35, fast)");
        let mut c = connect(&spec).unwrap();
        assert_eq!(c.info.board.as_str(), "virtual");
        assert_eq!(c.faults().unwrap().latched, 0);
        let serial = ConnectSpec::Serial {
            path: "/dev/ttyACM0".into(),
            baud: transport::DEFAULT_BAUD,
        };
        assert_eq!(serial.describe(), "serial port /dev/ttyACM0 at 921600 baud");
        assert_eq!(serial.virtual_plant_name(), None);
    }

    #[test]
    fn bad_targets_are_typed_errors() {
        let e = connect(&ConnectSpec::preset("nope", Pace::Fast)).unwrap_err();
        assert!(matches!(e, ClientError::Plant { path: None, .. }), "{e:?}");
        assert!(e.to_string().contains("unknown device \"nope\""), "{e}");
        let e = connect(&ConnectSpec::plant_file(
            "/nonexistent/plant.toml",
            Pace::Fast,
        ))
        .unwrap_err();
        assert!(
            matches!(&e, ClientError::Plant { path: Some(_), .. }),
            "{e:?}"
        );
        let e = connect(&ConnectSpec::Serial {
            path: "/dev/does-not-exist-stiffwall".into(),
            baud: transport::DEFAULT_BAUD,
        })
        .unwrap_err();
        assert!(matches!(e, ClientError::Port(_)), "{e:?}");
    }
}
