//! The built-in virtual device: the firmware core (`stiffwall-firmware`: `Device` + `Servo`)
//! driving a simulated plant of `stiffwall-sim` (`rich::RichPlant`: the exact rigid plant of a
//! `--device` preset, or any plant a scene file describes with `--plant FILE.toml`), served on
//! a pseudo-terminal so that hostctl reaches it through the same serial code path as a real
//! board.
//!
//! Timing: the servo ticks at the configured rate against the wall clock (`paced`), or as fast
//! as the host reads telemetry (`fast`): in fast mode the servo only runs while fewer than
//! [`FAST_BACKLOG`] bytes wait for the host, so no telemetry sample is ever dropped.
//! Units: SI at this API; the plant is read at each sample instant and the written code is held
//! (ZOH) for one period, as on hardware. The amplifier is ideal unless the plant file gives a
//! filter, dead band or force limit; extra delay comes from the firmware's own delay line
//! (`ServoConfig::extra_delay_ticks`; a plant file's `controller.extra_delay_s`, plus an
//! amplifier of kind "delay", rounded to whole ticks in the boot configuration).
//! Output range: 16-bit codes; full scale = the plant's `amplifier.force_limit_n` when set,
//! else a preset's published peak force (`--device NAME`: `stiffwall_core::devices`, e.g.
//! 8.5 N for the Phantom 1.0), otherwise 32.767 × `coulomb_n` (at least 1 mN).

use crate::error::{ClientError, Result};
use crate::transport;
use serialport::SerialPort as _;
use std::collections::VecDeque;
use std::io::{ErrorKind, Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use stiffwall_core::params::PhysicalParams;
use stiffwall_firmware::{
    BoardInfo, ByteLink, Channels, ConfigStore, Device, HeldCode, MemStorage, SampledCount, Servo,
};
use stiffwall_proto::ServoConfig;
use stiffwall_proto::{DamperLaw, WallMode};
use stiffwall_sim::rich::{Controller, PlantModel, RichPlant, Travel, WallDamper};

// A plant file's `controller.damper` takes the firmware's dead bands.
const _: () =
    assert!(stiffwall_sim::rich::MAX_DAMPER_DEAD_BAND == stiffwall_proto::MAX_DEADBAND_COUNTS);

/// Bytes waiting for the host above which the fast virtual device pauses its servo.
pub const FAST_BACKLOG: usize = 2048;
/// Bytes from the host held at most before the firmware reads them; beyond this the virtual
/// device stops reading its pty, so a writer faster than the firmware is back-pressured by
/// the kernel (as a UART's FIFO would) instead of growing memory.
pub const RX_LIMIT: usize = 64 * 1024;
/// Output codes of the virtual amplifier (16-bit bipolar).
pub const MAX_CODE: i32 = 32_767;

/// What to simulate.
#[derive(Debug, Clone)]
pub struct Spec {
    /// The device: m, b, c, Δ (T and K come from the firmware's config; `stiffness` and
    /// `period_s` here set the boot config).
    pub plant: PhysicalParams,
    /// Encoder counts per revolution for rotary devices (0 for linear).
    pub counts_per_rev: u32,
    /// In real time, or as fast as the host reads.
    pub pace: crate::pace::Pace,
    /// Initial position of the plant, m (rad).
    pub initial_position: f64,
    /// The amplifier's output range, N (N·m), when known (a preset's published peak force);
    /// a scene's `amplifier.force_limit_n` takes precedence. `None`: 32.767 × c, ≥ 1 mN.
    pub output_range: Option<f64>,
    /// The plant and controller of a scene file (`--plant`). `None`: the rigid plant of
    /// `plant` (with `travel`), wall off at boot. The firmware always quantises, so
    /// `controller.quantization`, the scene's `[initial]` velocity and `[run]` are not used by
    /// the device (it starts at rest at `initial_position`).
    pub scene: Option<ScenePlant>,
    /// The travel of a preset's rigid plant, [min, max] m (rad) (`None`: unbounded); a scene
    /// file's `effects.travel` is in its model.
    pub travel: Option<[f64; 2]>,
    /// Where to write the plant's true state every tick (`--trace FILE`): CSV of time,
    /// position, velocity, end-stop contact force, encoder count and commanded force
    /// ([`TRACE_HEADER`]). `None`: no trace.
    pub trace: Option<std::path::PathBuf>,
}

/// The trace's header line (SI units; rotary devices: rad, rad/s, N·m in the same columns).
pub const TRACE_HEADER: &str = "t_s,position_m,velocity_m_per_s,stop_force_n,count,force_cmd_n";

/// What a scene file gives the virtual device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScenePlant {
    /// `[device]` and `[effects]`: the plant behind the firmware core.
    pub model: PlantModel,
    /// `[controller]`: the boot configuration.
    pub controller: Controller,
}

/// A plant file's `controller.damper` as the firmware's law.
fn damper_law(d: WallDamper) -> DamperLaw {
    match d {
        WallDamper::Difference => DamperLaw::Difference,
        WallDamper::DeadBand(counts) => DamperLaw::DeadBand { counts },
    }
}

impl Spec {
    /// The virtual device of a scene file: `[device]` and `[effects]` are the plant,
    /// `[controller]` the boot configuration. Errors name the key and its allowed range.
    pub fn from_plant_file(path: &std::path::Path, pace: crate::pace::Pace) -> Result<Self> {
        let plant_error = |message: String| ClientError::Plant {
            path: Some(path.to_path_buf()),
            message,
        };
        let text = std::fs::read_to_string(path).map_err(|e| plant_error(e.to_string()))?;
        let (model, ctl, start_m) = PlantModel::from_scene_toml_with_start(&text)
            .map_err(|e| plant_error(e.to_string()))?;
        let spec = Self {
            plant: PhysicalParams {
                mass: model.mass_kg,
                viscous: model.viscous_ns_per_m,
                coulomb: model.coulomb_n,
                resolution: model.resolution_m,
                period_s: ctl.period_s,
                stiffness: ctl.stiffness_n_per_m,
                delay_s: ctl.extra_delay_s,
                rotational: model.counts_per_rev.is_some(),
            },
            counts_per_rev: model.counts_per_rev.unwrap_or(0),
            pace,
            initial_position: start_m,
            output_range: None,
            scene: Some(ScenePlant {
                model,
                controller: ctl,
            }),
            travel: None,
            trace: None,
        };
        if let Err(e) = stiffwall_firmware::validate(&spec.defaults(), &spec.board()) {
            use stiffwall_proto::ConfigField as F;
            let ctl = spec.scene.map(|s| s.controller);
            let t = ctl.map_or(1e-3, |c| c.period_s);
            let (key, lo, hi, unit) = match e.field {
                F::Stiffness => ("controller.stiffness_n_per_m", e.min, e.max, "N/m"),
                F::Damping => (
                    "controller.virtual_damping_ns_per_m",
                    e.min,
                    e.max,
                    "N s/m (N m s/rad on a rotary device)",
                ),
                F::ServoRateHz => ("controller.period_s", 1.0 / e.max, 1.0 / e.min, "s"),
                F::ExtraDelayTicks => ("controller.extra_delay_s", e.min * t, e.max * t, "s"),
                F::Damper => ("controller.damper's dead band", e.min, e.max, "counts"),
                _ => ("the boot configuration", e.min, e.max, ""),
            };
            return Err(plant_error(format!(
                "{key} is outside the virtual board's range [{lo}, {hi}] {unit} \
                 ({:?} of the boot configuration; the output range is amplifier.force_limit_n, \
                 or 32.767 x device.coulomb_n)",
                e.field
            )));
        }
        Ok(spec)
    }

    /// The plant's output full scale, N (N·m): `amplifier.force_limit_n` when the plant sets
    /// one, else the preset's [`Spec::output_range`], otherwise 32.767 × the Coulomb friction
    /// (at least 1 mN).
    #[must_use]
    pub fn full_scale(&self) -> f64 {
        self.scene
            .and_then(|s| s.model.force_limit_n())
            .or(self.output_range)
            .unwrap_or_else(|| (self.plant.coulomb * 32.767).max(1e-3))
    }

    /// The board facts the firmware is built with for this plant: a 32-bit encoder counter
    /// and a 16-bit amplifier of [`Spec::full_scale`].
    #[must_use]
    pub fn board(&self) -> BoardInfo {
        let full_scale = self.full_scale();
        BoardInfo {
            name: "virtual",
            resolution: self.plant.resolution as f32,
            counts_per_rev: self.counts_per_rev,
            encoder_bits: 32,
            force_per_code: (full_scale / f64::from(MAX_CODE)) as f32,
            max_code: MAX_CODE,
            min_rate_hz: 100,
            max_rate_hz: 20_000,
        }
    }

    /// Boot configuration: the plant's travel (when it has one) as the firmware's travel
    /// window; wall off (a plant file: its controller's stiffness, virtual damping
    /// `controller.virtual_damping_ns_per_m`, damper law `controller.damper` (when given; else
    /// the firmware's default), extra delay in
    /// whole ticks and wall mode), the spec's servo rate, force limit at full scale. In fast
    /// mode the heartbeat watchdog is off: device time then runs many times faster than the
    /// host's clock, so a heartbeat timeout counted in servo ticks would trip spuriously.
    #[must_use]
    pub fn defaults(&self) -> ServoConfig {
        let b = self.board();
        // The plant's travel as the firmware's travel window: the counts wholly inside it, as a
        // user configures a board's (`hostctl config set`).
        let res = self.plant.resolution;
        let (travel_min, travel_max) = match self.travel_m() {
            Some([lo, hi]) => (
                i32::try_from((lo / res).ceil() as i64).ok(),
                i32::try_from((hi / res).floor() as i64 - 1).ok(),
            ),
            None => (None, None),
        };
        let base = ServoConfig {
            heartbeat_timeout_ms: if self.pace.is_fast() { 0 } else { 500 },
            stiffness: 0.0,
            servo_rate_hz: (1.0 / self.plant.period_s).round().clamp(100.0, 20_000.0) as u32,
            force_limit: b.force_per_code * b.max_code as f32,
            energy_limit: 1.0e3,
            travel_min,
            travel_max,
            ..ServoConfig::default()
        };
        match self.scene.map(|s| s.controller) {
            None => base,
            Some(c) => ServoConfig {
                stiffness: c.stiffness_n_per_m as f32,
                damping: c.virtual_damping_ns_per_m as f32,
                damper: c.damper.map_or(base.damper, damper_law),
                extra_delay_ticks: (c.extra_delay_s / c.period_s).round().clamp(0.0, 255.0) as u8,
                wall: if c.one_sided {
                    WallMode::OneSided
                } else {
                    WallMode::Bidirectional
                },
                ..base
            },
        }
    }

    /// The plant model the device runs: the file's, or the rigid plant of `plant` with the
    /// preset's `travel` (hard stops).
    pub fn plant_model(&self) -> Result<PlantModel> {
        let plant_error = |e: stiffwall_sim::rich::ModelError| ClientError::Plant {
            path: None,
            message: format!("virtual device plant: {e}"),
        };
        match self.scene {
            Some(s) => Ok(s.model),
            None => {
                let p = &self.plant;
                let rigid = PlantModel::rigid(p.mass, p.viscous, p.coulomb, p.resolution)
                    .map_err(plant_error)?;
                let model = PlantModel {
                    travel: self
                        .travel
                        .map(|[lo, hi]| Travel::with_defaults(lo, hi, None, None, p.mass)),
                    ..rigid
                };
                model.validate().map_err(plant_error)?;
                Ok(model)
            }
        }
    }

    /// The travel of the plant the device runs, [min, max] m (rad), when it has one.
    pub fn travel_m(&self) -> Option<[f64; 2]> {
        match self.scene {
            Some(s) => s.model.travel.map(|t| [t.min_m, t.max_m]),
            None => self.travel,
        }
    }
}

/// A running virtual device; stopped when dropped.
#[derive(Debug)]
pub struct VirtualDevice {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    /// Path of the host side of its pseudo-terminal.
    pub pty: String,
}

impl Drop for VirtualDevice {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// In-memory byte link between the firmware's `Device` and the pty.
#[derive(Debug, Default)]
struct MemLink {
    rx: VecDeque<u8>,
    tx: VecDeque<u8>,
}

impl ByteLink for MemLink {
    fn read(&mut self) -> Option<u8> {
        self.rx.pop_front()
    }
    fn write(&mut self, byte: u8) -> bool {
        if self.tx.len() >= 1 << 16 {
            return false;
        }
        self.tx.push_back(byte);
        true
    }
}

/// Starts the virtual device; returns it and the host side of its pty, opened by path.
pub fn spawn(spec: Spec) -> Result<(VirtualDevice, Box<dyn serialport::SerialPort>)> {
    let mut plant = match RichPlant::new(&spec.plant_model()?) {
        Ok(pl) => pl,
        Err(e) => {
            return Err(ClientError::Plant {
                path: None,
                message: format!("virtual device plant: {e}"),
            })
        }
    };
    plant.set_state(spec.initial_position, 0.0);
    let trace = match &spec.trace {
        Some(path) => Some(Trace::create(path)?),
        None => None,
    };
    let (mut master, host, pty) = transport::pty_pair()?;
    master
        .set_timeout(Duration::from_millis(1))
        .map_err(|e| ClientError::Port(format!("virtual device pty: {e}")))?;
    let stop = Arc::new(AtomicBool::new(false));
    let stop2 = Arc::clone(&stop);
    let thread = std::thread::Builder::new()
        .name("virtual-device".into())
        .spawn(move || run(&spec, plant, trace, &mut master, &stop2))
        .map_err(|e| ClientError::Io {
            op: "starting the virtual device for",
            source: e,
        })?;
    Ok((
        VirtualDevice {
            stop,
            thread: Some(thread),
            pty,
        },
        host,
    ))
}

/// The virtual device's loop until `stop` or the host hangs up: bytes from the host, the
/// firmware's `Device`, the servo ticks due (each against `plant`), bytes to the host.
fn run(
    spec: &Spec,
    mut plant: RichPlant,
    mut trace: Option<Trace>,
    pty: &mut serialport::TTYPort,
    stop: &AtomicBool,
) {
    let board = spec.board();
    let mut channels = Box::new(Channels::new());
    let (servo_port, host_port) = channels.split();
    let mut device = Device::new(
        board,
        ConfigStore::new(MemStorage::default()),
        host_port,
        spec.defaults(),
    );
    let mut servo: Servo<'_> = Servo::new(board, device.config(), servo_port);
    let mut period_s = 1.0 / f64::from(device.servo_rate_hz().max(1));
    let mut link = MemLink::default();
    let mut tick: u32 = 0;
    let mut ticks_since_epoch: u64 = 0;
    let mut epoch = Instant::now();
    let mut buf = [0u8; 4096];
    let mask = encoder_mask(board.encoder_bits);
    while !stop.load(Ordering::Relaxed) {
        // Host → device, while the receive buffer has room.
        let Some(room) = receive(pty, &mut link, &mut buf) else {
            break; // the host hung up
        };
        device.poll(tick, &mut link);
        if let Some(hz) = device.take_rate_change() {
            period_s = 1.0 / f64::from(hz.max(1));
            epoch = Instant::now();
            ticks_since_epoch = 0;
        }
        // Servo ticks due now.
        let due = ticks_due(
            spec.pace.is_fast(),
            &link,
            epoch,
            period_s,
            ticks_since_epoch,
        );
        for _ in 0..due {
            tick = tick.wrapping_add(1);
            ticks_since_epoch += 1;
            let raw = (plant.encoder_count() as u64 & mask) as u32;
            let mut out = HeldCode(0);
            servo.tick(tick, &mut SampledCount(raw), &mut out);
            let force = f64::from(out.0) * f64::from(board.force_per_code);
            if let Some(t) = &mut trace {
                t.sample(&plant, force, period_s);
            }
            plant.advance(force, period_s);
            // Let the main loop drain telemetry before the servo's queue fills.
            device.poll(tick, &mut link);
        }
        // Device → host.
        if !transmit(pty, &mut link) {
            break;
        }
        if due == 0
            && (link.rx.is_empty() || room == 0)
            && link.tx.is_empty()
            && !spec.pace.is_fast()
        {
            std::thread::sleep(Duration::from_micros(200));
        }
    }
}

/// The plant's true state, one CSV line per servo tick ([`TRACE_HEADER`]): at each sample
/// instant, before the tick's force is applied. Written through a buffer, flushed when the
/// device stops; a write error ends the trace (reported once on stderr), never the device.
struct Trace {
    out: Option<std::io::BufWriter<std::fs::File>>,
    path: std::path::PathBuf,
    t_s: f64,
}

impl Trace {
    fn create(path: &std::path::Path) -> Result<Self> {
        let file = std::fs::File::create(path).map_err(|e| ClientError::Io {
            op: "creating the trace file",
            source: e,
        })?;
        let mut out = std::io::BufWriter::new(file);
        writeln!(out, "{TRACE_HEADER}").map_err(|e| ClientError::Io {
            op: "writing the trace file",
            source: e,
        })?;
        Ok(Self {
            out: Some(out),
            path: path.to_path_buf(),
            t_s: 0.0,
        })
    }

    fn sample(&mut self, plant: &RichPlant, force_n: f64, period_s: f64) {
        let Some(out) = &mut self.out else { return };
        let r = writeln!(
            out,
            "{:.9},{:e},{:e},{:e},{},{:e}",
            self.t_s,
            plant.position_m(),
            plant.velocity_m_per_s(),
            plant.stop_force_n(),
            plant.encoder_count(),
            force_n
        );
        self.t_s += period_s;
        if let Err(e) = r {
            eprintln!("trace {}: {e}; the trace stops here", self.path.display());
            self.out = None;
        }
    }
}

impl Drop for Trace {
    fn drop(&mut self) {
        if let Some(out) = &mut self.out {
            if let Err(e) = out.flush() {
                eprintln!("trace {}: {e}", self.path.display());
            }
        }
    }
}

/// The mask of an encoder of `bits` bits (all 32 bits from 32 up).
fn encoder_mask(bits: u8) -> u64 {
    if bits >= 32 {
        u64::from(u32::MAX)
    } else {
        (1u64 << bits) - 1
    }
}

/// Whether a pty error is only a timeout or an interruption (the host is still there).
fn transient(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
    )
}

/// Reads what the host sent into `link.rx`, at most up to [`RX_LIMIT`] bytes held; returns
/// the room there was (0: nothing read), or None when the host hung up.
fn receive(pty: &mut serialport::TTYPort, link: &mut MemLink, buf: &mut [u8]) -> Option<usize> {
    let room = RX_LIMIT.saturating_sub(link.rx.len()).min(buf.len());
    let got = if room == 0 {
        Ok(0)
    } else {
        pty.read(&mut buf[..room])
    };
    match got {
        Ok(n) => link.rx.extend(&buf[..n]),
        Err(e) if transient(&e) => {}
        Err(_) => return None,
    }
    Some(room)
}

/// Servo ticks to run now: `fast`, 32 while fewer than [`FAST_BACKLOG`] bytes wait for the
/// host (else 0); paced, those the wall clock is ahead of since `epoch` (at most 64).
fn ticks_due(
    fast: bool,
    link: &MemLink,
    epoch: Instant,
    period_s: f64,
    ticks_since_epoch: u64,
) -> u64 {
    if fast {
        if link.tx.len() < FAST_BACKLOG {
            32
        } else {
            0
        }
    } else {
        let target = (epoch.elapsed().as_secs_f64() / period_s) as u64;
        target.saturating_sub(ticks_since_epoch).min(64)
    }
}

/// Writes what waits in `link.tx` to the host (as much as the pty takes); false when the host
/// hung up.
fn transmit(pty: &mut serialport::TTYPort, link: &mut MemLink) -> bool {
    if !link.tx.is_empty() {
        let (a, _) = link.tx.as_slices();
        match pty.write(a) {
            Ok(n) => {
                link.tx.drain(..n);
            }
            Err(e) if transient(&e) => {}
            Err(_) => return false,
        }
    }
    true
}
