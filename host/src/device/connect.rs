//! `--port/--baud/--device/--plant/--fast/--qemu` options shared by every device command, and
//! the connection they describe: a real serial port, QEMU, or (default) the built-in virtual
//! device running a preset (`--device NAME`) or a scene file's plant (`--plant FILE.toml`).

use super::client::Client;
use super::{qemu, transport, virtual_device};
use anyhow::{anyhow, bail, Result};
use std::path::PathBuf;

/// The virtual device's plant when `--device` is not given: the paper's own rig (Sec. V).
pub const DEFAULT_VIRTUAL_DEVICE: &str = "maxon-re35";

/// How to reach the device.
#[derive(Debug, Clone, clap::Args)]
pub struct ConnectArgs {
    /// Serial port of a real board (e.g. /dev/ttyACM0). Without it, the built-in virtual device
    /// is used.
    #[arg(long, global = true, conflicts_with = "qemu")]
    pub port: Option<String>,
    /// Baud rate of --port.
    #[arg(long, global = true, default_value_t = transport::DEFAULT_BAUD)]
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
    /// Boot the QEMU board image and talk to it over `-serial pty`.
    #[arg(long, global = true)]
    pub qemu: bool,
    /// QEMU image (default: $STIFFWALL_QEMU_IMAGE or the `cargo xtask firmware` output).
    #[arg(long, global = true, value_name = "ELF")]
    pub qemu_image: Option<PathBuf>,
}

impl ConnectArgs {
    /// A short description of the target, for reports.
    #[must_use]
    pub fn describe(&self) -> String {
        if let Some(p) = &self.port {
            format!("serial port {p} at {} baud", self.baud)
        } else if self.qemu {
            "QEMU board image (mps2-an386)".into()
        } else {
            format!(
                "virtual device ({}{})",
                self.virtual_plant_name(),
                if self.fast { ", fast" } else { "" }
            )
        }
    }

    /// The virtual device's plant as written in recordings: the preset name, or `plant:FILE`.
    #[must_use]
    pub fn virtual_plant_name(&self) -> String {
        match &self.plant {
            Some(p) => format!("plant:{}", p.display()),
            None => self
                .device
                .clone()
                .unwrap_or_else(|| DEFAULT_VIRTUAL_DEVICE.to_string()),
        }
    }

    /// The virtual device's specification, when the target is the virtual device.
    pub fn virtual_spec(&self) -> Result<Option<virtual_device::Spec>> {
        if self.port.is_some() || self.qemu {
            if self.device.is_some() || self.plant.is_some() {
                bail!("--device and --plant pick the virtual device's plant; they cannot be combined with --port or --qemu");
            }
            return Ok(None);
        }
        if let Some(path) = &self.plant {
            if self.device.is_some() {
                bail!("--device and --plant both pick the virtual device's plant; give one");
            }
            return virtual_device::Spec::from_plant_file(path, self.fast).map(Some);
        }
        let name = self.device.as_deref().unwrap_or(DEFAULT_VIRTUAL_DEVICE);
        let d = stiffwall_core::devices::find(name).ok_or_else(|| {
            anyhow!(
                "unknown device {name:?} for --device (allowed: {})",
                stiffwall_core::devices::NAMES
            )
        })?;
        let counts_per_rev = if d.params.rotational {
            (std::f64::consts::TAU / d.params.resolution).round() as u32
        } else {
            0
        };
        Ok(Some(virtual_device::Spec {
            plant: d.params,
            counts_per_rev,
            fast: self.fast,
            initial_position: 0.0,
            output_range: Some(d.force_limit),
            scene: None,
        }))
    }

    /// Connects and performs the handshake.
    pub fn connect(&self) -> Result<Client> {
        // Refuses --device with --port or --qemu (instead of ignoring it).
        let spec = self.virtual_spec()?;
        if let Some(port) = &self.port {
            let p = transport::open_port(port, self.baud)?;
            let mut c = Client::connect(p, None)?;
            c.set_field_label(crate::config_flags::flag_name);
            return Ok(c);
        }
        if self.qemu {
            let image = qemu::find_image(self.qemu_image.as_deref())?;
            let q = qemu::boot(&image)?;
            let p = transport::open_port(&q.pty, transport::DEFAULT_BAUD)?;
            let mut c = Client::connect(p, Some(Box::new(q)))?;
            c.set_field_label(crate::config_flags::flag_name);
            return Ok(c);
        }
        let spec = spec.expect("virtual target");
        let (vd, p) = virtual_device::spawn(spec)?;
        let mut c = Client::connect(p, Some(Box::new(vd)))?;
        c.set_field_label(crate::config_flags::flag_name);
        Ok(c)
    }
}
