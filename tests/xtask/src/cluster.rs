//! `cargo xtask cluster-test`: a Fig. 6 panel as a Slurm job array on a throw-away single-node
//! cluster on this machine (also the last step of `cargo xtask ci`: about 140 s with the install
//! on 2 cores).
//!
//! Steps: install Debian's `slurm-wlm` and `munge` when missing ([`toolchain::apt_install`]:
//! `--no-remove`, never removes anything); build `hostctl` (release); start `munged` with a
//! fresh key, `slurmctld` and `slurmd` with a generated `slurm.conf`, all state, sockets, logs
//! and pid files in one temporary directory and on free TCP ports, so the machine's own
//! configuration (/etc/slurm, /etc/munge) is neither read nor changed; submit
//! `docs/cluster/submit.sh` (the array of `map-array.sbatch` tasks, `--shard
//! $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`, and the `afterok` merge job); wait; submit
//! the array again (must be a no-op), an array numbered 1..n (must be refused), and a long
//! shard cancelled while it runs (must leave nothing merge accepts, and complete when
//! re-submitted; without cycle detection, its horizon sized from a measurement on this machine
//! to run about 30 s, so that it cannot finish within the second before the cancel however fast
//! the solver is); and check that the merged map equals the single-process map point for point. The daemons are stopped
//! (`scontrol shutdown`, `munged --stop`, then only the recorded pids) however the run ends.
//!
//! Units: seconds of wall time. Needs root (slurmd and munged run as the invoking user, which
//! Slurm requires to be root to launch jobs) and Debian (for the install).

use crate::process::run;
use crate::{firmware, toolchain};
use anyhow::{bail, ensure, Context, Result};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The sweep: the Fig. 6(b) panel (μ = 100, τ_D = 0, ξ̇₀ = 5, 34 × 21 points, 5×10⁴ periods).
const MAP_ARGS: &str = "--mu 100 --tau-d 0 --xidot0 5 --beta 0:1:34 --sigma 0:2:21 --periods 50000";

/// Number of shards (array tasks).
const SHARDS: usize = 8;

/// Longest wait for the cluster to come up, and for the jobs.
const UP_TIMEOUT: Duration = Duration::from_secs(60);
const JOBS_TIMEOUT: Duration = Duration::from_secs(900);

fn have(cmd: &str) -> bool {
    ["/usr/sbin", "/usr/bin", "/sbin", "/bin"]
        .iter()
        .any(|d| Path::new(d).join(cmd).exists())
}

fn output(cmd: &mut Command) -> Result<String> {
    let o = cmd
        .stderr(Stdio::piped())
        .output()
        .with_context(|| format!("starting {cmd:?}"))?;
    ensure!(
        o.status.success(),
        "{cmd:?} failed: {}",
        String::from_utf8_lossy(&o.stderr).trim()
    );
    Ok(String::from_utf8_lossy(&o.stdout).trim().to_owned())
}

fn free_port() -> Result<u16> {
    Ok(std::net::TcpListener::bind("127.0.0.1:0")?
        .local_addr()?
        .port())
}

/// The running cluster; dropping it stops every daemon it started.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    socket: PathBuf,
}

impl Cluster {
    fn slurm(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    fn pid(&self, name: &str) -> Option<i32> {
        std::fs::read_to_string(self.dir.join(name))
            .ok()?
            .trim()
            .parse()
            .ok()
    }

    /// Starts `munged`, `slurmctld` and `slurmd` with all their state in `dir`, and waits for
    /// the node to be idle.
    fn start(dir: &Path) -> Result<Self> {
        let munge_dir = dir.join("munge");
        let key = make_dirs_and_key(dir, &munge_dir)?;
        let socket = munge_dir.join("munge.socket");
        let conf = dir.join("slurm.conf");
        let cluster = Self {
            dir: dir.to_path_buf(),
            conf: conf.clone(),
            socket: socket.clone(),
        };
        run(Command::new("munged")
            .arg("--force")
            .arg(format!("--key-file={}", key.display()))
            .arg(format!("--socket={}", socket.display()))
            .arg(format!("--pid-file={}", dir.join("munged.pid").display()))
            .arg(format!("--log-file={}", dir.join("munged.log").display()))
            .arg(format!("--seed-file={}", munge_dir.join("seed").display())))?;
        let host = output(Command::new("hostname").arg("-s"))?;
        cluster.write_conf(&host)?;
        run(cluster.slurm("slurmctld").arg("-f").arg(&conf).arg("-c"))?;
        run(cluster.slurm("slurmd").arg("-f").arg(&conf))?;
        cluster.wait_idle(&host)
    }

    /// Writes `slurm.conf` for one node `host` with this machine's CPUs, on two free TCP ports.
    fn write_conf(&self, host: &str) -> Result<()> {
        let cpus = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
        let (ctld_port, d_port) = (free_port()?, free_port()?);
        ensure!(ctld_port != d_port, "no two free TCP ports");
        let d = self.dir.display();
        let text = format!(
            "# Generated by cargo xtask cluster-test: a throw-away single-node cluster.\n\
             ClusterName=stiffwall-test\n\
             SlurmctldHost={host}(127.0.0.1)\n\
             SlurmUser=root\nSlurmdUser=root\n\
             SlurmctldPort={ctld_port}\nSlurmdPort={d_port}\n\
             AuthType=auth/munge\nCredType=cred/munge\nAuthInfo=socket={sock}\n\
             StateSaveLocation={d}/state\nSlurmdSpoolDir={d}/spool\n\
             SlurmctldPidFile={d}/slurmctld.pid\nSlurmdPidFile={d}/slurmd.pid\n\
             SlurmctldLogFile={d}/slurmctld.log\nSlurmdLogFile={d}/slurmd.log\n\
             ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n\
             SelectType=select/cons_tres\nSelectTypeParameters=CR_Core\n\
             SchedulerType=sched/backfill\nJobCompType=jobcomp/none\n\
             AccountingStorageType=accounting_storage/none\nJobAcctGatherType=jobacct_gather/none\n\
             MpiDefault=none\nReturnToService=2\n\
             NodeName={host} NodeAddr=127.0.0.1 CPUs={cpus} State=UNKNOWN\n\
             PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n",
            sock = self.socket.display(),
        );
        std::fs::write(&self.conf, text)?;
        eprintln!(
            "xtask: slurm.conf in {} ({host}, {cpus} CPUs, ports {ctld_port}/{d_port})",
            self.conf.display()
        );
        Ok(())
    }

    /// Polls `sinfo` every 0.5 s until the node `host` is idle, for at most [`UP_TIMEOUT`].
    fn wait_idle(self, host: &str) -> Result<Self> {
        let t0 = Instant::now();
        loop {
            let state = output(self.slurm("sinfo").args(["-h", "-o", "%T"])).unwrap_or_default();
            if state == "idle" {
                eprintln!(
                    "xtask: cluster up in {:.1} s (node {host} idle)",
                    t0.elapsed().as_secs_f64()
                );
                return Ok(self);
            }
            if t0.elapsed() > UP_TIMEOUT {
                let d = self.dir.display();
                bail!(
                    "the node is {state:?}, not idle, after {} s; see {d}/slurmctld.log, {d}/slurmd.log",
                    UP_TIMEOUT.as_secs()
                );
            }
            std::thread::sleep(Duration::from_millis(500));
        }
    }
}

/// Sets the Unix permission bits of `p`.
fn set_mode(p: &Path, mode: u32) -> std::io::Result<()> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(p, std::fs::Permissions::from_mode(mode))
}

/// Creates the cluster's state, spool and munge directories under `dir` and a fresh 1024-byte
/// munge key (mode 0600) in `munge_dir`; returns the key's path.
fn make_dirs_and_key(dir: &Path, munge_dir: &Path) -> Result<PathBuf> {
    for d in [munge_dir, &dir.join("state"), &dir.join("spool")] {
        std::fs::create_dir_all(d)?;
    }
    set_mode(dir, 0o755)?;
    set_mode(munge_dir, 0o700)?;
    let key = munge_dir.join("munge.key");
    let mut bytes = vec![0u8; 1024];
    use std::io::Read;
    std::fs::File::open("/dev/urandom")?.read_exact(&mut bytes)?;
    std::fs::write(&key, &bytes)?;
    set_mode(&key, 0o600)?;
    Ok(key)
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = self
            .slurm("scontrol")
            .arg("shutdown")
            .stderr(Stdio::null())
            .status();
        let _ = Command::new("munged")
            .arg("--stop")
            .arg(format!("--socket={}", self.socket.display()))
            .stderr(Stdio::null())
            .status();
        // Whatever did not stop within 10 s: only the pids this run recorded.
        let t0 = Instant::now();
        for name in ["slurmd.pid", "slurmctld.pid", "munged.pid"] {
            if let Some(pid) = self.pid(name) {
                let proc = PathBuf::from(format!("/proc/{pid}"));
                while proc.exists() && t0.elapsed() < Duration::from_secs(10) {
                    std::thread::sleep(Duration::from_millis(200));
                }
                if proc.exists() {
                    let _ = Command::new("kill").arg(pid.to_string()).status();
                }
            }
        }
        eprintln!("xtask: cluster stopped");
    }
}

/// The jobs still in the queue, as `id state reason` lines.
fn queue(c: &Cluster, jobs: &str) -> String {
    output(c.slurm("squeue").args(["-h", "-j", jobs, "-o", "%i %T %r"])).unwrap_or_default()
}

/// Waits until `jobs` (comma-separated ids) have left the queue; returns the seconds waited.
fn wait_for(c: &Cluster, jobs: &str) -> Result<f64> {
    let t0 = Instant::now();
    let mut last = String::new();
    loop {
        let q = queue(c, jobs);
        if q != last {
            let pending = q.lines().count();
            eprintln!(
                "xtask: {:5.1} s: {pending} job(s) queued or running",
                t0.elapsed().as_secs_f64()
            );
            last = q.clone();
        }
        if q.is_empty() {
            return Ok(t0.elapsed().as_secs_f64());
        }
        if q.contains("DependencyNeverSatisfied") {
            bail!(
                "a shard failed, so the merge can never run:\n{q}\nlogs in {}",
                c.dir.display()
            );
        }
        if t0.elapsed() > JOBS_TIMEOUT {
            bail!("jobs still queued after {} s:\n{q}", JOBS_TIMEOUT.as_secs());
        }
        std::thread::sleep(Duration::from_millis(500));
    }
}

/// The scripts' behaviour on a second submission: the whole array again is a no-op (complete
/// shards are kept byte for byte), and an array not numbered 0..n-1 is refused by every task.
fn resubmissions(c: &Cluster, dir: &Path, sweep: &Path, hostctl: &Path) -> Result<()> {
    let script = firmware::root().join("docs/cluster/map-array.sbatch");
    let shard_files: Vec<PathBuf> = (0..SHARDS)
        .map(|k| sweep.join(format!("shard-{k}-of-{SHARDS}.json")))
        .collect();
    let before: Vec<Vec<u8>> = shard_files
        .iter()
        .map(std::fs::read)
        .collect::<std::io::Result<_>>()?;
    let submit_to = |sweep: &Path, map_args: &str, array: &str, shards: Option<usize>| {
        let mut cmd = c.slurm("sbatch");
        cmd.args(["--parsable", &format!("--array={array}")])
            .arg(&script)
            .current_dir(dir)
            .env("HOSTCTL", hostctl)
            .env("SWEEP_DIR", sweep)
            .env("MAP_ARGS", map_args)
            .env_remove("SHARDS");
        if let Some(n) = shards {
            cmd.env("SHARDS", n.to_string());
        }
        Ok::<_, anyhow::Error>(output(&mut cmd)?.split(';').next().unwrap_or("").to_owned())
    };
    let submit = |array: &str, shards: Option<usize>| submit_to(sweep, MAP_ARGS, array, shards);
    let again = submit(&format!("0-{}", SHARDS - 1), Some(SHARDS))?;
    let s = wait_for(c, &again)?;
    let after: Vec<Vec<u8>> = shard_files
        .iter()
        .map(std::fs::read)
        .collect::<std::io::Result<_>>()?;
    ensure!(
        before == after,
        "re-running the array changed a complete shard file"
    );
    let log = std::fs::read_to_string(dir.join(format!("stiffwall-map-{again}_0.out")))?;
    ensure!(log.contains("nothing to do"), "re-run log of task 0: {log}");
    eprintln!("xtask: re-submitted array {again}: all {SHARDS} complete shards kept as they were, in {s:.1} s");
    let wrong = submit(&format!("1-{SHARDS}"), None)?;
    wait_for(c, &wrong)?;
    let log = std::fs::read_to_string(dir.join(format!("stiffwall-map-{wrong}_1.out")))?;
    ensure!(
        log.contains(&format!("the array must be 0-{}", SHARDS - 1)),
        "an array 1-{SHARDS} was not refused: {log}"
    );
    eprintln!(
        "xtask: array 1-{SHARDS} refused by its tasks: {}",
        log.trim()
    );
    preempted_shard(c, dir, hostctl, &submit_to)
}

/// Submits `map-array.sbatch`: (sweep directory, MAP_ARGS, array, SHARDS) → job id.
type Submit<'a> = dyn Fn(&Path, &str, &str, Option<usize>) -> Result<String> + 'a;

/// How long the pre-empted shard is planned to run, s: far beyond the 1 s after which it must
/// still be running, short enough to complete when submitted again.
const LONG_SHARD_S: f64 = 30.0;

/// The `hostctl map` flags of the pre-emption step's long sweep: the panel without cycle
/// detection (its persistent points run every period of the horizon, however fast the solver
/// finds their cycle), with a horizon sized from a measurement on this machine so that its
/// shard 0 of [`SHARDS`] runs about [`LONG_SHARD_S`] on one thread (as the array task does);
/// where even the largest horizon would be quicker, a finer β axis adds points. Returns the
/// flags and the planned seconds.
fn long_sweep(hostctl: &Path, dir: &Path) -> Result<(String, f64)> {
    let base = MAP_ARGS.replace("--periods 50000", "");
    let time = |args: &str, periods: u64| -> Result<f64> {
        let t0 = Instant::now();
        output(
            Command::new(hostctl)
                .arg("map")
                .args(args.split_whitespace())
                .args(["--periods", &periods.to_string(), "--no-cycle-detection"])
                .args(["--quiet", "--threads", "1", "--force"])
                .args(["--shard", &format!("0/{SHARDS}")])
                .arg("--out")
                .arg(dir.join("long-sweep-probe.json")),
        )?;
        Ok(t0.elapsed().as_secs_f64())
    };
    // t(P) = a + b·P: the persistent points cost b per period, the rest end early.
    let (p1, p2) = (200_000u64, 1_000_000u64);
    let (t1, t2) = (time(&base, p1)?, time(&base, p2)?);
    let b = ((t2 - t1) / (p2 - p1) as f64).max(1e-12);
    let a = (t1 - b * p1 as f64).max(0.0);
    let max = 100_000_000u64; // stiffwall_sim::map::MAX_PERIODS
    let fine = ((LONG_SHARD_S / (a + b * max as f64)).ceil() as usize).max(1);
    let args = if fine > 1 {
        base.replace("--beta 0:1:34", &format!("--beta 0:1:{}", 34 * fine))
    } else {
        base
    };
    let b = b * fine as f64;
    let periods = ((LONG_SHARD_S - a).max(1.0) / b).clamp(p2 as f64, max as f64) as u64;
    let planned = a + b * periods as f64;
    eprintln!(
        "xtask: long sweep for pre-emption: shard 0/{SHARDS} measured {t1:.2} s at {p1} periods and {t2:.2} s at {p2}, without cycle detection: {periods} periods{} planned {planned:.0} s",
        if fine > 1 { format!(", β axis × {fine},") } else { ",".into() }
    );
    Ok((
        format!("{args} --periods {periods} --no-cycle-detection"),
        planned,
    ))
}

/// A shard cancelled while it runs (as pre-emption does) leaves no shard file that merge
/// accepts; submitted again, it completes.
fn preempted_shard(c: &Cluster, dir: &Path, hostctl: &Path, submit_to: &Submit) -> Result<()> {
    let sweep = dir.join("sweep-preempted");
    let (long, planned) = long_sweep(hostctl, dir)?;
    let shard = sweep.join(format!("shard-0-of-{SHARDS}.json"));
    let job = submit_to(&sweep, &long, "0", Some(SHARDS))?;
    let t0 = Instant::now();
    while !queue(c, &job).contains("RUNNING") {
        ensure!(t0.elapsed() < UP_TIMEOUT, "job {job} did not start");
        std::thread::sleep(Duration::from_millis(200));
    }
    std::thread::sleep(Duration::from_secs(1));
    ensure!(
        !shard.exists(),
        "the long shard (planned {planned:.0} s) finished before it could be cancelled"
    );
    output(c.slurm("scancel").arg(&job))?;
    wait_for(c, &job)?;
    ensure!(
        !shard.exists(),
        "a cancelled shard left {}",
        shard.display()
    );
    let left: Vec<String> = std::fs::read_dir(&sweep)?
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
        .collect();
    for name in &left {
        let o = Command::new(hostctl)
            .args(["map", "merge"])
            .arg(sweep.join(name))
            .arg("--out")
            .arg(dir.join("preempted-merge.json"))
            .output()?;
        ensure!(!o.status.success(), "merge accepted the leftover {name}");
    }
    eprintln!(
        "xtask: shard 0/{SHARDS} (planned {planned:.0} s) cancelled while running: no shard file; merge refuses what it left ({left:?})"
    );
    let t1 = Instant::now();
    let again = submit_to(&sweep, &long, "0", Some(SHARDS))?;
    wait_for(c, &again)?;
    ensure!(shard.exists(), "the re-submitted shard left no file");
    eprintln!(
        "xtask: the same shard submitted again completed in {:.1} s",
        t1.elapsed().as_secs_f64()
    );
    Ok(())
}

fn json(p: &Path) -> Result<serde_json::Value> {
    let text = std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))
}

/// Installs Slurm and munge when a program is missing, and checks that this runs as root.
fn ensure_tools_and_root() -> Result<()> {
    if !["munged", "slurmctld", "slurmd", "sbatch"]
        .iter()
        .all(|c| have(c))
    {
        toolchain::apt_install(&["slurm-wlm", "munge"], "Slurm and munge (cluster-test)")?;
    }
    let uid = output(Command::new("id").arg("-u"))?;
    ensure!(
        uid == "0",
        "cluster-test starts slurmd, which must run as root to launch jobs (uid is {uid})"
    );
    Ok(())
}

/// Submits `docs/cluster/submit.sh` (the array and its merge job) and waits for both; returns
/// the merged map's path and the seconds waited.
fn run_panel(c: &Cluster, dir: &Path, sweep: &Path, hostctl: &Path) -> Result<(PathBuf, f64)> {
    let submit = firmware::root().join("docs/cluster/submit.sh");
    let ids = output(
        c.slurm("bash")
            .arg(&submit)
            .current_dir(dir)
            .env("SHARDS", SHARDS.to_string())
            .env("HOSTCTL", hostctl)
            .env("SWEEP_DIR", sweep)
            .env("MAP_ARGS", MAP_ARGS),
    )?;
    let (array, merge) = ids
        .split_once(' ')
        .with_context(|| format!("submit.sh printed {ids:?}, expected two job ids"))?;
    eprintln!("xtask: submitted array job {array} ({SHARDS} tasks) and merge job {merge} (afterok:{array})");
    let jobs_s = wait_for(c, &format!("{array},{merge}"))?;
    let merged_path = sweep.join("map.json");
    ensure!(
        merged_path.exists(),
        "the merge job left no {}; its log: {}",
        merged_path.display(),
        std::fs::read_to_string(dir.join(format!("stiffwall-merge-{merge}.out")))
            .unwrap_or_default()
    );
    Ok((merged_path, jobs_s))
}

/// Prints each shard file's points, periods and cost.
fn report_shards(sweep: &Path) -> Result<()> {
    for k in 0..SHARDS {
        let s = json(&sweep.join(format!("shard-{k}-of-{SHARDS}.json")))?;
        eprintln!(
            "xtask: shard {k}/{SHARDS}: {} points, {} periods in {:.2} s ({:.1} ns/period thread wall time, {:.2} s CPU)",
            s["panels"][0]["points"].as_array().map_or(0, Vec::len),
            s["cost"]["periods_total"],
            s["seconds"].as_f64().unwrap_or(f64::NAN),
            s["cost"]["ns_per_period_mean"].as_f64().unwrap_or(f64::NAN),
            s["cost"]["cpu_seconds"].as_f64().unwrap_or(f64::NAN)
        );
    }
    Ok(())
}

/// Checks that the merged map equals the single-process map (spec, no shard left, all 714
/// points); returns the number of points and the count of each class.
fn compare_maps(
    merged_path: &Path,
    single_path: &Path,
) -> Result<(usize, std::collections::BTreeMap<String, usize>)> {
    let (merged, single) = (json(merged_path)?, json(single_path)?);
    ensure!(
        merged["spec"] == single["spec"],
        "the merged spec differs from the single run's"
    );
    ensure!(merged["shard"].is_null(), "the merged map is still a shard");
    let (mp, sp) = (&merged["panels"], &single["panels"]);
    let (mpts, spts) = (
        mp[0]["points"].as_array().map_or(&[][..], Vec::as_slice),
        sp[0]["points"].as_array().map_or(&[][..], Vec::as_slice),
    );
    ensure!(
        mpts.len() == spts.len() && mpts.len() == 714,
        "{} merged points, {} single-process points, expected 714",
        mpts.len(),
        spts.len()
    );
    let differ = mpts.iter().zip(spts).filter(|(a, b)| a != b).count();
    ensure!(
        differ == 0 && mp == sp,
        "{differ} of {} points differ between the merged and the single-process map",
        mpts.len()
    );
    let mut classes = std::collections::BTreeMap::new();
    for p in mpts {
        *classes
            .entry(p["class"].as_str().unwrap_or("?").to_owned())
            .or_insert(0) += 1;
    }
    Ok((mpts.len(), classes))
}

/// Runs `cargo xtask cluster-test`.
///
/// # Errors
/// A missing package that cannot be installed, a cluster that does not come up, a failed or
/// stuck job, or a merged map that differs from the single-process one.
pub fn cluster_test(args: &[String]) -> Result<()> {
    ensure!(
        args.is_empty(),
        "cluster-test takes no arguments (got {args:?})"
    );
    let t0 = Instant::now();
    ensure_tools_and_root()?;
    let hostctl = crate::process::build_hostctl()?;
    let dir = std::env::temp_dir().join(format!("stiffwall-cluster-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir)?;
    let cluster = Cluster::start(&dir)?;

    let sweep = dir.join("sweep");
    let (merged_path, jobs_s) = run_panel(&cluster, &dir, &sweep, &hostctl)?;
    report_shards(&sweep)?;
    resubmissions(&cluster, &dir, &sweep, &hostctl)?;
    drop(cluster);

    let single_path = dir.join("single.json");
    run(Command::new(&hostctl)
        .arg("map")
        .args(MAP_ARGS.split_whitespace())
        .args(["--quiet", "--out"])
        .arg(&single_path))?;
    let (points, classes) = compare_maps(&merged_path, &single_path)?;
    eprintln!(
        "xtask: cluster-test passed: {SHARDS} array tasks + merge in {jobs_s:.1} s on Slurm; the merged map \
         equals the single-process map at all {} points ({classes:?}); total {:.1} s; files in {}",
        points,
        t0.elapsed().as_secs_f64(),
        dir.display()
    );
    Ok(())
}
