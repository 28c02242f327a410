//! Support code for the cross-crate software-in-the-loop tests in `tests/tests/`.
//!
//! Units: SI at the plant (m, m/s, N, s), raw encoder counts and output codes at the firmware.
//! One servo tick: read the plant's count → `Servo::tick` → apply the written force code
//! (× `force_per_code`) to the plant for one period T (zero-order hold, no extra plant delay:
//! τ_D = T_V/T). The host side talks to the [`Device`] through an in-memory byte pipe.
//!
//! The plant sits behind the [`Plant`] trait: [`SimPlant`] is `stiffwall_sim::PhysicalPlant`
//! (closed-form, exact stick–slip), [`EulerPlant`] an independent sub-stepped semi-implicit
//! integrator kept as a cross-check.
//!
//! Plants beyond the paper's model (issue 10): [`kstar`] (the brute-force true largest stable
//! stiffness K* of a plant, simulator only), [`family`] (the plant files of `sim/plants/`),
//! [`supervise`] (the firmware servo driving any plant, for the supervisor at 1.5 K*); the
//! `tune_table` binary writes docs/TUNE.md from them (`cargo xtask tune-table`).

pub mod family;
pub mod kstar;
pub mod supervise;
pub mod swings;

use std::collections::VecDeque;
use stiffwall_firmware::{BoardInfo, ByteLink, ConfigStore, Device, Encoder, MemStorage, Servo};
use stiffwall_proto::{
    encode, DeviceMsg, FrameDecoder, FrameError, HostMsg, ServoConfig, MAX_FRAME,
};

/// A 1-DOF device: m ẍ + b ẋ + c sgn(ẋ) = F.
pub trait Plant {
    /// Position x, m.
    fn position(&self) -> f64;
    /// Velocity, m/s.
    fn velocity(&self) -> f64;
    /// Sets the state.
    fn set(&mut self, x: f64, v: f64);
    /// Applies `force` N for `dt` s.
    fn apply(&mut self, force: f64, dt: f64);
}

/// The simulator's exact plant.
#[derive(Debug, Clone)]
pub struct SimPlant(pub stiffwall_sim::PhysicalPlant);

impl Plant for SimPlant {
    fn position(&self) -> f64 {
        self.0.position_m()
    }
    fn velocity(&self) -> f64 {
        self.0.velocity_m_per_s()
    }
    fn set(&mut self, x: f64, v: f64) {
        self.0.set_state(x, v);
    }
    fn apply(&mut self, force: f64, dt: f64) {
        self.0.advance(force, dt);
    }
}

/// Sub-stepped semi-implicit Euler with a stick rule (|F| ≤ c at zero velocity sticks).
#[derive(Debug, Clone)]
pub struct EulerPlant {
    /// Mass, kg.
    pub m: f64,
    /// Viscous friction, N·s/m.
    pub b: f64,
    /// Coulomb friction, N.
    pub c: f64,
    /// Position, m.
    pub x: f64,
    /// Velocity, m/s.
    pub v: f64,
    /// Sub-steps per call.
    pub substeps: u32,
}

impl Plant for EulerPlant {
    fn position(&self) -> f64 {
        self.x
    }
    fn velocity(&self) -> f64 {
        self.v
    }
    fn set(&mut self, x: f64, v: f64) {
        self.x = x;
        self.v = v;
    }
    fn apply(&mut self, f: f64, dt: f64) {
        let h = dt / f64::from(self.substeps);
        for _ in 0..self.substeps {
            if self.v == 0.0 && f.abs() <= self.c {
                continue;
            }
            let dir = if self.v != 0.0 {
                self.v.signum()
            } else {
                f.signum()
            };
            let v1 = (self.v + h * (f - self.c * dir) / self.m) / (1.0 + h * self.b / self.m);
            // Friction cannot reverse the motion within a sub-step: stop at zero.
            self.v = if v1 * dir < 0.0 { 0.0 } else { v1 };
            self.x += h * self.v;
        }
    }
}

/// Dimensionless operating point (Table I) and the SI rig built from it.
#[derive(Debug, Clone, Copy)]
pub struct Point {
    /// μ = m/(K T²).
    pub mu: f64,
    /// β = b/(K T).
    pub beta: f64,
    /// σ = c/(K Δ).
    pub sigma: f64,
}

/// The test rig's board: Δ = 10 µm, 0.1 mN per code (±3.2767 N), 16-bit counter.
#[must_use]
pub fn board() -> BoardInfo {
    BoardInfo {
        name: "sil",
        resolution: 1.0e-5,
        counts_per_rev: 0,
        encoder_bits: 16,
        force_per_code: 1.0e-4,
        max_code: 32767,
        min_rate_hz: 100,
        max_rate_hz: 20_000,
    }
}

/// Wall stiffness of the rig, N/m: K·Δ = 0.01 N = 100 codes, k_half = 50 codes.
pub const K: f64 = 1000.0;
/// Servo rate, Hz.
pub const RATE: u32 = 1000;

/// The servo config of the rig (energy monitor as given).
#[must_use]
pub fn config(energy_monitor: bool) -> ServoConfig {
    ServoConfig {
        stiffness: K as f32,
        force_limit: 3.0,
        servo_rate_hz: RATE,
        energy_monitor,
        energy_limit: 10.0,
        encoder_jump_counts: 10_000,
        ..ServoConfig::default()
    }
}

impl Point {
    /// The SI plant parameters (m, b, c) for K, T = 1/RATE and Δ of [`board`].
    #[must_use]
    pub fn si(&self) -> (f64, f64, f64) {
        let t = 1.0 / f64::from(RATE);
        let d = f64::from(board().resolution);
        (self.mu * K * t * t, self.beta * K * t, self.sigma * K * d)
    }

    /// The exact simulated plant at rest at 0.
    #[must_use]
    pub fn sim_plant(&self) -> SimPlant {
        let (m, b, c) = self.si();
        SimPlant(
            stiffwall_sim::PhysicalPlant::new(m, b, c, f64::from(board().resolution))
                .expect("valid plant"),
        )
    }

    /// The Euler plant at rest at 0.
    #[must_use]
    pub fn euler_plant(&self) -> EulerPlant {
        let (m, b, c) = self.si();
        EulerPlant {
            m,
            b,
            c,
            x: 0.0,
            v: 0.0,
            substeps: 64,
        }
    }
}

/// The encoder view of a plant position: ⌊x/Δ⌋ as a wrapping hardware counter.
#[derive(Debug, Clone, Copy)]
pub struct PlantEncoder {
    /// Count to return.
    pub count: i64,
}

impl Encoder for PlantEncoder {
    fn count(&mut self) -> u32 {
        self.count as u32 // low bits: the firmware uses `encoder_bits` of them
    }
}

/// Encoder count of a plant.
#[must_use]
pub fn count_of(p: &impl Plant) -> i64 {
    (p.position() / f64::from(board().resolution)).floor() as i64
}

/// One servo tick of firmware + plant; returns the code written.
pub fn tick<P: Plant>(servo: &mut Servo<'_>, plant: &mut P, now: u32) -> i32 {
    tick_offset(servo, plant, now, 0)
}

/// [`tick`] with the hardware counter reading `offset` more than ⌊x/Δ⌋ (wrapping), e.g. to
/// put the counter wrap inside the motion.
pub fn tick_offset<P: Plant>(servo: &mut Servo<'_>, plant: &mut P, now: u32, offset: i64) -> i32 {
    let mut enc = PlantEncoder {
        count: count_of(plant).wrapping_add(offset),
    };
    let mut out = stiffwall_firmware::HeldCode::default();
    servo.tick(now, &mut enc, &mut out);
    plant.apply(
        f64::from(out.0) * f64::from(board().force_per_code),
        1.0 / f64::from(RATE),
    );
    out.0
}

/// The in-memory byte pipe between host and device.
#[derive(Debug, Default)]
pub struct Pipe {
    /// Host → device bytes.
    pub to_device: VecDeque<u8>,
    /// Device → host bytes.
    pub to_host: VecDeque<u8>,
    /// Bytes the device may write per poll (None = unlimited).
    pub device_tx_budget: Option<usize>,
    /// Bytes the device has written in total.
    pub bytes_to_host: u64,
}

/// The device's end of a [`Pipe`].
#[derive(Debug)]
pub struct DeviceEnd<'p>(pub &'p mut Pipe);

impl ByteLink for DeviceEnd<'_> {
    fn read(&mut self) -> Option<u8> {
        self.0.to_device.pop_front()
    }
    fn write(&mut self, b: u8) -> bool {
        if let Some(n) = &mut self.0.device_tx_budget {
            if *n == 0 {
                return false;
            }
            *n -= 1;
        }
        self.0.to_host.push_back(b);
        self.0.bytes_to_host += 1;
        true
    }
}

/// A minimal host-side protocol client.
#[derive(Debug, Default)]
pub struct Host {
    decoder: FrameDecoder,
}

impl Host {
    /// Queues `msg` to the device.
    pub fn send(&mut self, pipe: &mut Pipe, msg: &HostMsg) {
        let mut buf = [0u8; MAX_FRAME];
        pipe.to_device
            .extend(encode(msg, &mut buf).expect("encodes"));
    }

    /// Decodes everything the device sent.
    pub fn receive(&mut self, pipe: &mut Pipe) -> Vec<Result<DeviceMsg, FrameError>> {
        let mut out = Vec::new();
        while let Some(b) = pipe.to_host.pop_front() {
            if let Some(r) = self.decoder.feed::<DeviceMsg>(b) {
                out.push(r);
            }
        }
        out
    }
}

/// A new device over in-memory storage.
#[must_use]
pub fn device<'a>(
    port: stiffwall_firmware::HostPort<'a>,
    cfg: ServoConfig,
) -> Device<'a, MemStorage> {
    Device::new(board(), ConfigStore::new(MemStorage::default()), port, cfg)
}

/// Peak |x|/Δ over a slice of positions (ticks).
#[must_use]
pub fn peak_ticks(xs: &[f64]) -> f64 {
    let d = f64::from(board().resolution);
    xs.iter().fold(0.0f64, |a, x| a.max((x / d).abs()))
}
