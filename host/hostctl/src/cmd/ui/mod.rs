//! `hostctl ui`: a live view of the device in the browser — telemetry traces, the (β, σ)
//! plane with the live operating point, release tests, tune, faults, recording and a map
//! viewer — served on a local address with a per-run token.
//!
//! Parts: [`security`] (who may talk to the server), [`conn`] (connections and their limits),
//! [`server`] (HTTP routes, the embedded page from `host/ui/`), [`ws`] (the WebSocket
//! session), [`device`] (the thread that owns the device connection),
//! [`wire`] (commands, events and the binary telemetry frames), [`plane`] (the (β, σ) plane
//! and the map overlay, computed with the same code as the figures), [`frontier`] (the (B, K)
//! frontier K_max(B) beside it, with the configured (B, K)), [`profile`] (`--profile`, checked
//! and loaded at start, and the device's active profile drawn over the position trace), [`record`] (recording
//! from the page in `hostctl record`'s format), [`trace`] (a release test's trace, decimated
//! for the page).
//!
//! Unlike the other commands, this one imports its siblings' argument definitions and checks
//! (config set, experiment release, tune, map files, profile files): it is a front end over them, so that the
//! page behaves exactly as the terminal (docs/ARCHITECTURE.md).
//!
//! Units: as in the other device commands (SI on the command line and on the page, device
//! integers in telemetry). Invariants: the device is reached exactly as by every device
//! command ([`ConnectArgs`]); configuration flags given here are applied before serving, with
//! `config set`'s checks; the server binds to 127.0.0.1 unless `--listen` says otherwise (with
//! a warning); the URL with the token is printed on stdout before anything is served.

pub mod app;
pub mod conn;
pub mod control;
pub mod device;
pub mod profile;
pub mod record;
pub mod security;
pub mod server;
pub mod wire;
pub mod ws;
/// The live view's data (`stiffwall_analysis::live`), re-exported under its old paths.
pub use stiffwall_analysis::live::{frontier, plane, trace};

use crate::config_flags::Overrides;
use crate::device::connect::ConnectArgs;
use anyhow::{bail, Context, Result};
use std::io::Write as _;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::{mpsc, Arc, Mutex};
use std::time::Duration;
use stiffwall_proto::ServoConfig;

/// Default address: loopback only.
pub const DEFAULT_LISTEN: &str = "127.0.0.1:8737";

/// Arguments of `hostctl ui`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  hostctl ui\n  hostctl ui --device phantom-1.0 --rate 5000\n  hostctl ui --port /dev/ttyACM0 --model 6.28e-6 9e-6 2e-3\n  hostctl ui --listen 127.0.0.1:0 --fast\n  hostctl ui --device maxon-re35 --profile profiles/knob-24-detents.toml --tune-json tune.json\n\nOpen the printed URL (it carries the run's token). Recordings started from the page are\nwritten to --record-dir in the format of `hostctl record`."
)]
pub struct Args {
    /// Address to serve on. Anything but a loopback address exposes the device's controls to
    /// the network (a warning is printed); the token is still required.
    #[arg(long, default_value = DEFAULT_LISTEN, value_name = "ADDR")]
    pub listen: SocketAddr,
    /// Device model for the (β, σ) plane: mass, viscous and Coulomb friction (SI); default:
    /// the `--device` preset of the virtual device (tune from the page replaces it with the
    /// identified one).
    #[arg(long, num_args = 3, value_names = ["M", "B", "C"], allow_hyphen_values = true)]
    pub model: Option<Vec<f64>>,
    /// Directory that recordings started from the page are written to.
    #[arg(long, default_value = ".", value_name = "DIR")]
    pub record_dir: PathBuf,
    /// A haptic profile file (TOML, profiles/README.md): lowered for the connected device and
    /// loaded onto it (`SetProfile`) before serving, drawn over the position trace. Refused,
    /// with nothing loaded, when it does not lower or fails the check against --tune-json.
    #[arg(long, value_name = "FILE")]
    pub profile: Option<PathBuf>,
    /// A tune result (the output of `hostctl tune --json`) to check --profile against: each
    /// element's margin (limit / local K) is shown and one that fails refuses the profile.
    #[arg(long, value_name = "TUNE.json", requires = "profile")]
    pub tune_json: Option<PathBuf>,
    /// Load a --profile that fails the check anyway (what fails is printed and marked).
    #[arg(long, requires = "tune_json")]
    pub force_profile: bool,
    /// Configuration changes applied before serving (not saved).
    #[command(flatten)]
    pub set: Overrides,
    /// How to reach the device.
    #[command(flatten)]
    pub connect: ConnectArgs,
}

/// The model of `--model`, checked as `experiment release --model`.
fn model(a: &Args) -> Result<Option<plane::Model>> {
    Ok(match &a.model {
        Some(v) if v.iter().all(|x| x.is_finite() && *x >= 0.0) && v[0] > 0.0 => {
            Some(plane::Model {
                mass: v[0],
                viscous: v[1],
                coulomb: v[2],
                source: "--model",
            })
        }
        Some(v) => bail!(
            "--model M B C must be finite, M > 0 kg, B ≥ 0 N·s/m, C ≥ 0 N (got {} {} {})",
            v[0],
            v[1],
            v[2]
        ),
        None => a.connect.virtual_spec()?.map(|s| plane::Model {
            mass: s.plant.mass,
            viscous: s.plant.viscous,
            coulomb: s.plant.coulomb,
            source: "the virtual device's plant",
        }),
    })
}

/// `--profile`: prepared (lowered, checked against `--tune-json`) and loaded onto the device.
fn load_profile(
    a: &Args,
    client: &mut stiffwall_client::Client,
) -> Result<Option<profile::Loaded>> {
    let Some(file) = &a.profile else {
        return Ok(None);
    };
    let l = profile::prepare(file, a.tune_json.as_deref(), a.force_profile, &client.info)?;
    client
        .set_profile(&l.lowered.wire())
        .with_context(|| format!("--profile {}: loading it onto the device", file.display()))?;
    Ok(Some(l))
}

/// Runs `hostctl ui` until Ctrl-C (or until the device disconnects).
pub fn run(a: &Args) -> Result<()> {
    a.set.apply(&ServoConfig::default())?;
    let model = model(a)?;
    if !a.record_dir.is_dir() {
        bail!("--record-dir {} is not a directory", a.record_dir.display());
    }
    if !a.listen.ip().is_loopback() {
        eprintln!(
            "warning: --listen {} is not a loopback address: anyone who can reach it and has the \
             token can change this device's stiffness; prefer 127.0.0.1 and an SSH tunnel",
            a.listen
        );
    }
    crate::session::stop_on_ctrl_c();
    let (mut client, _cfg) = a.set.connect_and_apply(&a.connect)?;
    let loaded = load_profile(a, &mut client)?;
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    let listener = rt
        .block_on(tokio::net::TcpListener::bind(a.listen))
        .with_context(|| format!("binding {}", a.listen))?;
    let bound = listener.local_addr()?;
    let guard = security::Guard::new(bound, security::new_token()?);
    let url = format!("http://{bound}/?token={}", guard.token());
    let shared = Arc::new(device::Shared::new(512));
    let (tx, rx) = mpsc::channel();
    let setup = device::Setup {
        connect: a.connect.clone(),
        model,
        record_dir: a.record_dir.clone(),
        pace: a.connect.fast && a.connect.port.is_none() && !a.connect.qemu,
        profile: loaded,
    };
    let dev_shared = Arc::clone(&shared);
    let dev = std::thread::Builder::new()
        .name("ui-device".into())
        .spawn(move || {
            let r = device::run(client, setup, Arc::clone(&dev_shared), rx);
            dev_shared.stop.store(true, Ordering::Relaxed);
            r
        })
        .context("starting the device thread")?;
    {
        let mut out = std::io::stdout().lock();
        writeln!(out, "hostctl ui: {} at {url}", a.connect.describe())?;
        writeln!(out, "hostctl ui: open the URL above; Ctrl-C stops")?;
        out.flush()?;
    }
    let app = app::App {
        guard: Arc::new(guard),
        shared: Arc::clone(&shared),
        commands: Arc::new(Mutex::new(tx)),
    };
    let stop = Arc::clone(&shared);
    let served = rt.block_on(async move {
        conn::serve(listener, server::router(app), async move {
            while !stop.stop.load(Ordering::Relaxed) && !stiffwall_client::interrupted() {
                tokio::time::sleep(Duration::from_millis(100)).await;
            }
        })
        .await
    });
    shared.stop.store(true, Ordering::Relaxed);
    let dev = dev
        .join()
        .map_err(|_| anyhow::anyhow!("the device thread panicked"))?;
    rt.shutdown_timeout(Duration::from_secs(1));
    served.context("serving")?;
    dev
}
