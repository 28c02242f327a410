//! `--port/--baud/--device/--plant/--fast/--qemu/--board-emulator` options shared by every
//! device command, and the connection they describe ([`ConnectSpec`] of `stiffwall-client`): a
//! real serial port, QEMU, the board emulator (the Nucleo image on an emulated STM32F446), or
//! (default) the built-in virtual device running a preset (`--device NAME`) or a scene
//! file's plant (`--plant FILE.toml`). The options only convert into a [`ConnectSpec`]
//! ([`ConnectArgs::spec`]); `stiffwall_client::connect` does the rest.

use anyhow::{anyhow, bail, Result};
use std::path::PathBuf;
use stiffwall_client::Client;
pub use stiffwall_client::DEFAULT_VIRTUAL_DEVICE;
use stiffwall_client::{Cancel, ConnectSpec, Pace, VirtualPlant};

/// How to reach the device.
#[derive(Debug, Clone, clap::Args)]
pub struct ConnectArgs {
    /// Serial port of a real board (e.g. /dev/ttyACM0). Without it, the built-in virtual device
    /// is used.
    #[arg(long, global = true, conflicts_with = "qemu")]
    pub port: Option<String>,
    /// Baud rate of --port.
    #[arg(long, global = true, default_value_t = stiffwall_client::DEFAULT_BAUD)]
    pub baud: u32,
    /// Plant of the virtual device: a preset name (see `hostctl analyze --list-devices`).
    #[arg(
        long = "device",
        global = true,
        value_name = "NAME",
        conflicts_with = "plant"
    )]
    pub device: Option<String>,
    /// Plant of the virtual device: a scene file (sim/plants/*.toml, sim/scenes/*.toml, physical
    /// units); its [device] and [effects] are the plant, its [controller] the boot
    /// configuration. Not with --device.
    #[arg(long = "plant", global = true, value_name = "FILE.toml")]
    pub plant: Option<PathBuf>,
    /// Run the virtual device as fast as the host reads, not in real time.
    #[arg(long, global = true)]
    pub fast: bool,
    /// The built-in virtual device writes its plant's true state every servo tick to this CSV
    /// file: time [s], position [m or rad], velocity [m/s or rad/s], end-stop contact force
    /// [N or N·m], encoder count and commanded force. Only with the virtual device.
    #[arg(long, global = true, value_name = "FILE.csv", conflicts_with_all = ["qemu", "port", "board_emulator"])]
    pub trace: Option<PathBuf>,
    /// Boot the QEMU board image and talk to it over `-serial pty`.
    #[arg(long, global = true)]
    pub qemu: bool,
    /// QEMU image (default: $STIFFWALL_QEMU_IMAGE or the `cargo xtask firmware` output).
    #[arg(long, global = true, value_name = "ELF")]
    pub qemu_image: Option<PathBuf>,
    /// Run the Nucleo-F446RE image on the board emulator (a separate process, host/board-emu,
    /// built by `cargo xtask board-emu --build`) with the plant of --device/--plant.
    #[arg(long, global = true, conflicts_with_all = ["qemu", "port"])]
    pub board_emulator: bool,
    /// The board emulator's image: its force output, `dac` (default) or `pwm`.
    #[arg(
        long,
        global = true,
        value_name = "dac|pwm",
        requires = "board_emulator"
    )]
    pub features: Option<String>,
}

impl ConnectArgs {
    /// A short description of the target, for reports.
    #[must_use]
    pub fn describe(&self) -> String {
        self.target().describe()
    }

    /// The virtual device's plant as written in recordings: the preset name, or `plant:FILE`.
    #[must_use]
    pub fn virtual_plant_name(&self) -> String {
        self.virtual_target()
            .virtual_plant_name()
            .unwrap_or_default()
    }

    /// The target these options name, unchecked (for descriptions).
    fn target(&self) -> ConnectSpec {
        if let Some(p) = &self.port {
            ConnectSpec::Serial {
                path: p.clone(),
                baud: self.baud,
            }
        } else if self.qemu {
            ConnectSpec::Qemu {
                image: self.qemu_image.clone(),
            }
        } else if self.board_emulator {
            ConnectSpec::BoardEmulator(stiffwall_client::BoardEmulatorSpec {
                output: self.features.clone(),
                device: self.device.clone(),
                plant_file: self.plant.clone(),
                pace: Pace::fast_if(self.fast),
            })
        } else {
            self.virtual_target()
        }
    }

    /// The virtual device these options name (`--plant` before `--device`).
    fn virtual_target(&self) -> ConnectSpec {
        let plant = match (&self.plant, &self.device) {
            (Some(p), _) => VirtualPlant::File(p.clone()),
            (None, Some(d)) => VirtualPlant::Preset(d.clone()),
            (None, None) => VirtualPlant::default(),
        };
        ConnectSpec::Virtual {
            plant,
            pace: Pace::fast_if(self.fast),
            trace: self.trace.clone(),
        }
    }

    /// The connection these options describe, refusing combinations that contradict each
    /// other and unknown `--device` presets (messages name the flags).
    pub fn spec(&self) -> Result<ConnectSpec> {
        if self.port.is_some() || self.qemu {
            if self.device.is_some() || self.plant.is_some() {
                bail!("--device and --plant pick the virtual device's plant; they cannot be combined with --port or --qemu");
            }
            if let (true, Some(image)) = (self.qemu, &self.qemu_image) {
                if !image.is_file() {
                    bail!("--qemu-image {} does not exist", image.display());
                }
            }
            return Ok(self.target());
        }
        if self.plant.is_some() && self.device.is_some() {
            bail!("--device and --plant both pick the virtual device's plant; give one");
        }
        if let Some(f) = self.features.as_deref() {
            if !stiffwall_client::BOARD_EMULATOR_OUTPUTS.contains(&f) {
                bail!("--features {f}: allowed dac or pwm (the board emulator's force output)");
            }
        }
        if self.plant.is_none() {
            let name = self.device.as_deref().unwrap_or(DEFAULT_VIRTUAL_DEVICE);
            if stiffwall_core::devices::find(name).is_none() {
                return Err(anyhow!(
                    "unknown device {name:?} for --device (allowed: {})",
                    stiffwall_core::devices::NAMES
                ));
            }
        }
        Ok(self.target())
    }

    /// The virtual device's specification, when the target is the virtual device.
    pub fn virtual_spec(&self) -> Result<Option<stiffwall_client::VirtualSpec>> {
        Ok(self.spec()?.virtual_spec()?)
    }

    /// Connects and performs the handshake. The client's experiments check a token Ctrl-C
    /// cancels ([`Cancel::on_ctrl_c`]; the command installs the handler,
    /// [`crate::session::stop_on_ctrl_c`]).
    pub fn connect(&self) -> Result<Client> {
        let mut client = stiffwall_client::connect(&self.spec()?)?;
        client.set_cancel(Cancel::on_ctrl_c());
        Ok(client)
    }
}

impl TryFrom<&ConnectArgs> for ConnectSpec {
    type Error = anyhow::Error;

    fn try_from(a: &ConnectArgs) -> Result<Self> {
        a.spec()
    }
}
