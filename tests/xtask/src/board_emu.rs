//! `cargo xtask board-emu [--build] [--bench]`: the Nucleo-F446RE images on the board emulator
//! (host/board-emu, its own GPL-2.0-or-later workspace around unicorn).
//!
//! Steps: installs `cmake` and `libclang-dev` when missing (root on Debian, as QEMU is
//! installed); builds the `dac` and `pwm` images exactly as `cargo xtask firmware` and `cargo
//! xtask flash` do, the `dac` image with the linear rig of feature `rig-phantom`
//! (`nucleo-f446re-dac-phantom-1.0`), plus the QEMU image (for the other-board refusal) and the five mutants
//! (features `mutant-*` of the board crate: encoder polarity, DAC alignment, TIM7 prescaler,
//! USART2 BRR, NVIC priorities), and copies each ELF to `target/board-emu/NAME.elf` (`nucleo-f446re-dac`,
//! `nucleo-f446re-pwm`, `qemu-an386`, `mutant-…`); builds the emulator
//! (release). `--build` stops there (what `hostctl --board-emulator` needs). Otherwise it builds
//! hostctl and runs the emulated-board tests (`host/board-emu/tests/board.rs`, `#[ignore]`d,
//! all must run): boot and clock tree, info over the pty, tune against the virtual device,
//! release counts, config across a power cycle, the watchdog, refusals, and the mutation checks
//! (each mutant must fail its test); then the seven QEMU scenarios of `host/hostctl/tests/qemu.rs`
//! on each image (`STIFFWALL_SCENARIO_BOARD`), against the transcripts in
//! `firmware/boards/nucleo-f446re/scenarios/{dac,pwm}/`. `--bench` measures the cycles per servo tick and the CPU
//! load at 1, 5, 10 and 20 kHz (a rate above the board's `max_rate_hz` reported refused), with
//! the config's wall and with a 16-element profile loaded over the protocol, and writes the
//! table into docs/BENCHMARKS.md (`board-emu` section). The 20 kHz rows run on measurement
//! images built only by `--bench`: the `dac` and `pwm` images with feature `bench-20khz`
//! (`nucleo-f446re-dac-bench-20khz`, `nucleo-f446re-pwm-bench-20khz`; `max_rate_hz` 20 kHz,
//! nothing else changed), recorded at decimation 2 (the link carries every second sample, as
//! every sample at 10 kHz); the other rates run on the normal images at decimation 1.

use crate::firmware::{self, root, Image, IMAGES};
use crate::process::{run, run_counting};
use crate::toolchain;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The mutation features of the board crate (each must make an emulated-board test fail).
pub const MUTANTS: &[&str] = &[
    "mutant-encoder-polarity",
    "mutant-dac-alignment",
    "mutant-tim7-prescaler",
    "mutant-usart-brr",
    "mutant-nvic-priority",
];

/// Tests in host/board-emu/tests/board.rs (all must run).
const TESTS: usize = 17;

fn image(name: &str) -> &'static Image {
    IMAGES
        .iter()
        .find(|i| i.name == name)
        .expect("the image is in the image table")
}

fn copy(elf: &Path, out: &Path, name: &str) -> Result<PathBuf> {
    let to = out.join(format!("{name}.elf"));
    std::fs::copy(elf, &to)
        .with_context(|| format!("copying {} to {}", elf.display(), to.display()))?;
    Ok(to)
}

/// The emulator's cargo command (its own workspace, never the host's target dir).
fn emu_cargo(args: &[&str]) -> Command {
    let mut c = Command::new("cargo");
    c.env_remove("CARGO_TARGET_DIR")
        .args(args)
        .current_dir(root().join("host/board-emu"));
    c
}

/// Builds the images (with mutants if `mutants`, with the `bench-20khz` measurement images if
/// `bench`) and the emulator.
fn build(mutants: bool, bench: bool) -> Result<PathBuf> {
    toolchain::ensure_board_emu_deps()?;
    let cross = toolchain::ensure_cross()?;
    let out = root().join("target/board-emu");
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let qemu = firmware::build(cross, image("qemu-an386"), &[])?;
    copy(&qemu, &out, "qemu-an386")?;
    if mutants {
        for m in MUTANTS {
            let elf = firmware::build(cross, image("nucleo-f446re-dac"), &[m])?;
            copy(&elf, &out, m)?;
        }
    }
    // The worked example of a linear rig (src/rig.rs, feature rig-phantom): the image
    // `hostctl --board-emulator --device phantom-1.0` picks.
    let phantom = firmware::build(cross, image("nucleo-f446re-dac"), &["rig-phantom"])?;
    copy(&phantom, &out, "nucleo-f446re-dac-phantom-1.0")?;
    if bench {
        // The 20 kHz measurement images (feature bench-20khz: `max_rate_hz` 20 kHz only).
        for output in ["dac", "pwm"] {
            let name = format!("nucleo-f446re-{output}");
            let elf = firmware::build(cross, image(&name), &[BENCH_FEATURE])?;
            copy(&elf, &out, &format!("{name}-{BENCH_FEATURE}"))?;
        }
    }
    let pwm = firmware::build(cross, image("nucleo-f446re-pwm"), &[])?;
    copy(&pwm, &out, "nucleo-f446re-pwm")?;
    // The dac image last: the board crate's own output path keeps the default build.
    let dac = firmware::build(cross, image("nucleo-f446re-dac"), &[])?;
    copy(&dac, &out, "nucleo-f446re-dac")?;
    run(&mut emu_cargo(&["build", "--release", "--locked"]))?;
    Ok(out)
}

/// Runs the subcommand.
pub fn board_emu(args: &[String]) -> Result<()> {
    let build_only = args.iter().any(|a| a == "--build");
    let bench = args.iter().any(|a| a == "--bench");
    if let Some(bad) = args.iter().find(|a| *a != "--build" && *a != "--bench") {
        bail!("unknown argument {bad:?} for `cargo xtask board-emu` (allowed: --build, --bench)");
    }
    let out = build(!build_only && !bench, bench && !build_only)?;
    if build_only {
        eprintln!(
            "xtask: images in {}, emulator in host/board-emu/target/release; try \
             `hostctl tune --board-emulator --fast`",
            out.display()
        );
        return Ok(());
    }
    run(crate::process::cargo().args(["build", "-p", "stiffwall-host", "--bin", "hostctl"]))?;
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root().join("target"), PathBuf::from);
    if bench {
        return figures(&out, &target.join("debug/hostctl"));
    }
    // The emulator's own unit tests (register models, image checks, output stage).
    run(&mut emu_cargo(&[
        "test",
        "--release",
        "--locked",
        "--bin",
        "stiffwall-board-emu",
    ]))?;
    let mut test = emu_cargo(&[
        "test",
        "--release",
        "--locked",
        "--test",
        "board",
        "--",
        "--ignored",
        "--test-threads=1",
    ]);
    test.env("STIFFWALL_HOSTCTL", target.join("debug/hostctl"));
    run_counting(&mut test, TESTS)?;
    scenarios()
}

/// The seven QEMU scenarios (`host/hostctl/tests/qemu.rs`) on each Nucleo image, against
/// `firmware/boards/nucleo-f446re/scenarios/{dac,pwm}/`.
fn scenarios() -> Result<()> {
    for output in ["dac", "pwm"] {
        eprintln!("xtask: the QEMU scenarios on the emulated board, {output} image");
        let mut cmd = crate::qemu::scenarios_command();
        cmd.env(
            "STIFFWALL_SCENARIO_BOARD",
            format!("nucleo-f446re-{output}"),
        )
        .env(
            "STIFFWALL_BOARD_EMU",
            root().join("host/board-emu/target/release/stiffwall-board-emu"),
        )
        .env_remove("STIFFWALL_NUCLEO_ELF");
        run_counting(&mut cmd, crate::qemu::QEMU_SCENARIOS)?;
    }
    Ok(())
}

/// The rates of `--bench`, Hz (a rate above the board's `max_rate_hz` is reported refused).
const BENCH_RATES: [u32; 4] = [1000, 5000, 10_000, 20_000];
/// The board crate's feature of the measurement images (`max_rate_hz` 20 kHz), built only by
/// `--bench`, for the rates above [`PRODUCT_MAX_HZ`].
const BENCH_FEATURE: &str = "bench-20khz";
/// The normal images' `max_rate_hz` (firmware/boards/nucleo-f446re/src/rig.rs): the highest
/// rate at which the link streams every sample.
const PRODUCT_MAX_HZ: u32 = 10_000;

/// The image file (in `target/board-emu`, without `.elf`) and the telemetry decimation of a
/// `--bench` run of output `name` at `hz`: above [`PRODUCT_MAX_HZ`], the `bench-20khz` image,
/// recording every `hz / PRODUCT_MAX_HZ`-th sample (the link's share of samples at the normal
/// images' limit); else the normal image, every sample.
fn bench_image(name: &str, hz: u32) -> (String, u32) {
    if hz > PRODUCT_MAX_HZ {
        (
            format!("nucleo-f446re-{name}-{BENCH_FEATURE}"),
            hz.div_ceil(PRODUCT_MAX_HZ),
        )
    } else {
        (format!("nucleo-f446re-{name}"), 1)
    }
}
/// The rate set before each run's own (the statistics restart at a rate change: every run's
/// window then starts at the change to its rate, the profile already loaded).
const PRE_RATE_HZ: u32 = 2000;

/// What a `--bench` run renders: the config's wall, or a profile loaded over the protocol.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Load {
    Wall,
    Profile,
}

/// The profile of `--bench` in the JSON form of `stiffwall_proto::profile::Profile` (the
/// client's `set_profile` names the type; this crate does not depend on the protocol crate):
/// the QEMU bench's worst case on the Nucleo's rig (8192 counts per turn, 0.1 N·m full
/// scale), sixteen detent trains each spanning ±3000 counts around the start, 0.002 N·m each
/// (their sum passes the 0.025 N·m force limit in places), each with a damper (1e-4
/// N·m·s/rad, the default law, a dead band of one count).
fn bench_profile() -> serde_json::Value {
    let elements: Vec<serde_json::Value> = (0..16)
        .map(|i| {
            let pitch = 40.0 + 3.0 * f64::from(i);
            serde_json::json!({ "Detents": {
                "first": -3000 - i,
                "pitch_counts": pitch,
                "count": (6000.0 / pitch) as u32 + 2,
                "strength": 0.002,
                "damping": 1.0e-4,
                "damper": { "DeadBand": { "counts": 1 } },
            }})
        })
        .collect();
    serde_json::json!({ "elements": elements })
}

/// Over the protocol, as a host: reads the board's highest rate; for [`Load::Profile`] sets
/// [`PRE_RATE_HZ`] and loads [`bench_profile`] (`HostMsg::SetProfile`), else sets
/// [`PRE_RATE_HZ`] only. Returns the board's `max_rate_hz`.
fn prepare(pty: &str, load: Load) -> Result<u32> {
    let port = stiffwall_client::open_port(pty, stiffwall_client::DEFAULT_BAUD)?;
    let mut c = stiffwall_client::Client::connect(port, None)?;
    let max = c.info.limits.max_rate_hz;
    let mut cfg = c.get_config()?;
    cfg.servo_rate_hz = PRE_RATE_HZ;
    c.set_config(&cfg)?;
    if load == Load::Profile {
        let p = serde_json::from_value(bench_profile()).context("the bench profile")?;
        c.set_profile(&p)?;
        let back = c.get_profile()?;
        if back.elements.len() != 16 {
            bail!(
                "the board holds {} profile elements, not 16",
                back.elements.len()
            );
        }
    }
    Ok(max)
}

/// One run's figures, from the emulator's report: (mean cycles, longest tick, CPU load).
fn run_figures(report: &str) -> (String, String, String) {
    let line = |p: &str| report.lines().find(|l| l.starts_with(p)).unwrap_or("");
    let tick = line("servo tick:");
    let after = |key: &str| {
        tick.split_once(key)
            .map(|(_, r)| r.split_whitespace().next().unwrap_or("").to_string())
            .unwrap_or_default()
    };
    let load = line("CPU load:")
        .trim_start_matches("CPU load: ")
        .split(" awake")
        .next()
        .unwrap_or("")
        .to_string();
    (after("mean "), after("max "), load)
}

/// Measures cycles per servo tick and CPU load at [`BENCH_RATES`], with the wall and with
/// [`bench_profile`], each on the image and at the decimation of [`bench_image`]: the emulator
/// serves its pty; the client reads the board's highest rate
/// (a rate above it is reported refused, not forced), sets [`PRE_RATE_HZ`] and for the profile
/// loads it over the protocol; then hostctl sets the rate and a wall (K = 1 N·m/rad: the
/// config's wall, or the profile compiled again for the new rate) and records 2 s of telemetry
/// (the telemetry stream is part of the load); the emulator's statistics start at the rate
/// change. Prints the table and writes it into docs/BENCHMARKS.md (`board-emu` section).
fn figures(out: &Path, hostctl: &Path) -> Result<()> {
    let mut t = String::from(
        "| image | servo rate | telemetry recorded | renders | servo tick: mean cycles | longest tick, cycles | CPU load (telemetry streaming) |\n\
         |---|---:|---|---|---:|---:|---:|\n",
    );
    for name in ["dac", "pwm"] {
        for hz in BENCH_RATES {
            for load in [Load::Wall, Load::Profile] {
                let what = match load {
                    Load::Wall => "the wall",
                    Load::Profile => "16 detent trains",
                };
                let (file, decimation) = bench_image(name, hz);
                let row = bench_run(out, hostctl, &file, hz, decimation, load)?;
                let recorded = if decimation == 1 {
                    "every sample (decimation 1)".to_string()
                } else {
                    format!("1 sample in {decimation} (decimation {decimation})")
                };
                let line = format!(
                    "| {file} | {} kHz | {recorded} | {what} | {row} |",
                    hz / 1000
                );
                println!("{line}");
                t.push_str(&line);
                t.push('\n');
            }
        }
    }
    crate::process::update_section(
        &root().join("docs/BENCHMARKS.md"),
        "board-emu",
        t.trim_end(),
    )
}

/// One `--bench` run of image file `file` (in `out`, without `.elf`), recording every
/// `decimation`-th sample: the table's last three cells.
fn bench_run(
    out: &Path,
    hostctl: &Path,
    file: &str,
    hz: u32,
    decimation: u32,
    load: Load,
) -> Result<String> {
    use std::io::BufRead;
    let exe = root().join("host/board-emu/target/release/stiffwall-board-emu");
    let csv = std::env::temp_dir().join(format!("board-emu-bench-{}.csv", std::process::id()));
    let mut child = Command::new(&exe)
        .arg("--elf")
        .arg(out.join(format!("{file}.elf")))
        .args(["--pty", "--fast"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .with_context(|| format!("starting {}", exe.display()))?;
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().context("emulator stdout")?)
        .read_line(&mut line)?;
    let pty = line.trim().trim_start_matches("pty: ").to_string();
    let max = prepare(&pty, load)?;
    let refused = hz > max;
    if !refused {
        let rate = hz.to_string();
        run(Command::new(hostctl).args([
            "config",
            "set",
            "--rate",
            &rate,
            "--stiffness",
            "1",
            "--port",
            &pty,
        ]))?;
        let decimation = decimation.to_string();
        run(Command::new(hostctl)
            .args(["record", "--seconds", "2", "--decimation", &decimation])
            .args(["--port", &pty])
            .arg(&csv))?;
    }
    drop(child.stdin.take());
    let o = child.wait_with_output()?;
    let e = String::from_utf8_lossy(&o.stderr);
    if !o.status.success() {
        bail!("the emulator failed:\n{e}");
    }
    let _ = std::fs::remove_file(&csv);
    if refused {
        return Ok(format!(
            "refused: above the board's max_rate_hz, {max} Hz | – | –"
        ));
    }
    let (mean, max_tick, cpu) = run_figures(&e);
    Ok(format!("{mean} | {max_tick} | {cpu}"))
}
