//! The emulated-board tests: the Nucleo-F446RE images (`dac` and `pwm`) run on the board
//! emulator, driven through `hostctl` as a user would drive a real board, compared with the
//! virtual device; and the mutation checks (each flipped hardware setting must fail a test).
//!
//! Opt-in (`#[ignore]`): `cargo xtask board-emu` builds the images (and the mutants) into
//! `target/board-emu/`, builds hostctl, and runs these with `--ignored`. Units: stiffness in
//! N·m/rad (the default rig is rotary; N/m on the phantom-1.0 rig), time in emulated seconds. Invariants: every test starts its own
//! emulator process(es) and ends them; nothing depends on test order.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn emulator() -> &'static str {
    env!("CARGO_BIN_EXE_stiffwall-board-emu")
}

/// An image built by `cargo xtask board-emu` (`nucleo-f446re-dac`, `nucleo-f446re-pwm`,
/// `nucleo-f446re-dac-phantom-1.0`, `qemu-an386`, `mutant-…`).
fn image(name: &str) -> PathBuf {
    let p = root().join("target/board-emu").join(format!("{name}.elf"));
    assert!(
        p.is_file(),
        "{} is missing: run `cargo xtask board-emu`",
        p.display()
    );
    p
}

fn hostctl() -> Command {
    let exe = std::env::var_os("STIFFWALL_HOSTCTL")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target/debug/hostctl"));
    let mut c = Command::new(exe);
    c.env("STIFFWALL_BOARD_EMU", emulator())
        .env_remove("STIFFWALL_NUCLEO_ELF")
        .current_dir(root());
    c
}

/// Runs `cmd`; returns (success, stdout, stderr).
fn run(cmd: &mut Command) -> (bool, String, String) {
    let out = cmd.output().expect("spawning");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn run_ok(cmd: &mut Command) -> (String, String) {
    let (ok, o, e) = run(cmd);
    assert!(ok, "{cmd:?} failed:\n{o}\n{e}");
    (o, e)
}

fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("not JSON ({e}): {text}"))
}

/// The emulator serving a pty, with a config-store file.
struct Served {
    child: Child,
    pty: String,
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts the emulator on `elf` serving a pty, with `args` after `--pty`; returns the child
/// (stdin and stderr as given by the caller's `stderr`) and the pty's path.
fn spawn_pty(elf: &Path, args: &[&std::ffi::OsStr], stderr: Stdio) -> (Child, String) {
    let mut child = Command::new(emulator())
        .arg("--elf")
        .arg(elf)
        .arg("--pty")
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(stderr)
        .spawn()
        .expect("starting the emulator");
    let mut line = String::new();
    BufReader::new(child.stdout.take().expect("stdout"))
        .read_line(&mut line)
        .expect("reading the pty line");
    let pty = line
        .trim()
        .strip_prefix("pty: ")
        .expect("pty line")
        .to_string();
    (child, pty)
}

fn serve(elf: &Path, store: &Path) -> Served {
    let (child, pty) = spawn_pty(
        elf,
        &["--fast".as_ref(), "--store".as_ref(), store.as_os_str()],
        Stdio::inherit(),
    );
    Served { child, pty }
}

const OUTPUTS: [&str; 2] = ["dac", "pwm"];

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn boots_at_180_mhz_with_a_1_khz_servo_tick_on_both_outputs() {
    for out in OUTPUTS {
        let (_, e) = run_ok(
            Command::new(emulator())
                .arg("--elf")
                .arg(image(&format!("nucleo-f446re-{out}")))
                .args([
                    "--output",
                    out,
                    "--seconds",
                    "1",
                    "--expect-servo-hz",
                    "1000",
                ]),
        );
        for want in [
            "SYSCLK 180.000 MHz",
            "PCLK1 45.000 MHz",
            "PCLK2 90.000 MHz",
            "APB1 timers 90.000 MHz",
            "flash 5 wait states",
            "TIM7: ",
            "(PSC 1, ARR 44999)",
        ] {
            assert!(e.contains(want), "{out}: no {want:?} in\n{e}");
        }
        assert!(!e.contains("reset at"), "{out}: an unexpected reset\n{e}");
    }
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn info_over_the_emulated_usart2_on_both_outputs() {
    for out in OUTPUTS {
        let (o, _) = run_ok(hostctl().args(["info", "--board-emulator", "--features", out]));
        assert!(
            o.contains(&format!("board:       nucleo-f446re-{out}")),
            "{o}"
        );
        assert!(o.contains("8192 counts/rev"), "{o}");
        assert!(o.contains("faults:      none"), "{o}");
    }
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn refuses_other_boards_and_corrupt_files_before_running() {
    let (ok, _, e) = run(Command::new(emulator())
        .arg("--elf")
        .arg(image("qemu-an386"))
        .args(["--seconds", "0.01"]));
    assert!(!ok && e.contains("outside the image flash"), "{e}");
    let bytes = std::fs::read(image("nucleo-f446re-dac")).unwrap();
    let dir = std::env::temp_dir().join(format!("board-emu-refuse-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cut = dir.join("truncated.elf");
    std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
    let (ok, _, e) = run(Command::new(emulator())
        .arg("--elf")
        .arg(&cut)
        .args(["--seconds", "0.01"]));
    assert!(!ok && e.contains("refusing"), "{e}");
    let mut bad = bytes.clone();
    bad[..4].copy_from_slice(b"JUNK");
    let junk = dir.join("corrupt.elf");
    std::fs::write(&junk, &bad).unwrap();
    let (ok, _, e) = run(Command::new(emulator())
        .arg("--elf")
        .arg(&junk)
        .args(["--seconds", "0.01"]));
    assert!(!ok && e.contains("truncated or corrupt"), "{e}");
    let (ok, _, e) = run(Command::new(emulator())
        .arg("--elf")
        .arg(image("nucleo-f446re-dac"))
        .args(["--sha256", "00", "--seconds", "0.01"]));
    assert!(!ok && e.contains("SHA-256"), "{e}");
    let (ok, _, e) = run(Command::new(emulator())
        .arg("--elf")
        .arg(image("nucleo-f446re-dac"))
        .args(["--output", "pwm", "--seconds", "0.01"]));
    assert!(!ok && e.contains("it is the dac build"), "{e}");
    // A plant the image's rig (rotary, 8192 counts/rev) does not describe, and the other way.
    let (ok, _, e) = run(Command::new(emulator())
        .arg("--elf")
        .arg(image("nucleo-f446re-dac"))
        .args(["--device", "phantom-1.0", "--seconds", "0.01"]));
    assert!(
        !ok && e.contains("is linear") && e.contains("8192 counts/rev"),
        "{e}"
    );
    let (ok, _, e) = run(Command::new(emulator())
        .arg("--elf")
        .arg(image("nucleo-f446re-dac-phantom-1.0"))
        .args(["--device", "maxon-re35", "--seconds", "0.01"]));
    assert!(
        !ok && e.contains("is rotary with 8192 counts/rev")
            && e.contains("rig (src/rig.rs) is linear"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `hostctl tune --json` on `target` (not a dry run: the wall is set and saved): (set K, every
/// set wall rests, the largest resting K its release search found). Every tune must pass its
/// own final check (issue 46: at rest, no fault, and within 2 counts of where it started or
/// where the set wall holds it against static friction), and on the presets (`--device`)
/// within 2 counts outright.
fn tune(target: &[&str]) -> (f64, bool, f64) {
    let (o, _) = run_ok(hostctl().args(["tune", "--fast", "--json"]).args(target));
    let t = &json(&o)["tune"];
    let left = &t["device_left"];
    let moved = left["count"].as_i64().expect("device_left.count")
        - left["start"].as_i64().expect("device_left.start");
    assert!(
        left["ok"].as_bool() == Some(true)
            && left["at_rest"].as_bool() == Some(true)
            && left["faults"].as_array().is_some_and(Vec::is_empty)
            && (moved.abs() <= 2 || !target.contains(&"--device")),
        "tune {target:?} left the device {moved} counts from its start: {left}"
    );
    assert_eq!(
        t["saved"].as_bool(),
        Some(true),
        "tune {target:?}: not saved"
    );
    (
        t["k_set"].as_f64().expect("k_set"),
        t["rests"].as_bool().expect("rests"),
        t["search"]["k_pass"].as_f64().expect("search.k_pass"),
    )
}

/// The spring-only tune (`--damping 0`, the paper's wall) on the board and on the virtual
/// device: the same verdict (every set wall rests), and the largest resting K the release search
/// finds within 10 %. The set K is that K × 0.9, backed off ×0.95 for each verification test
/// that fails; the verification's impact tests are marginal near that K and come out either
/// way from run to run, on the virtual device as on the board (seen on maxon-re35: virtual 1.072
/// and 1.188, board 1.070 and 1.185, with the searched K within 0.3 %), so the set K is held to
/// 25 %, two back-off steps. The default tune (spring + damper) is checked to set a wall that
/// rests, stiffer than the spring alone; its frontier sits at the quiet ceiling 2c/Δ, where one
/// release verdict turns on a fraction of an output code, and the board's codes are 18× (DAC)
/// or 3.7× (PWM) coarser than the virtual device's 16-bit ones (the board README).
fn tune_matches(plant: &[&str], out: &str) {
    let spring = |t: &[&str]| {
        let mut a = t.to_vec();
        a.extend(["--damping", "0"]);
        tune(&a)
    };
    let mut board = plant.to_vec();
    board.extend(["--board-emulator", "--features", out]);
    let (k_virtual, rests_virtual, pass_virtual) = spring(plant);
    let (k_board, rests_board, pass_board) = spring(&board);
    eprintln!(
        "tune --damping 0 {plant:?} {out}: virtual K = {k_virtual} (search {pass_virtual}), \
         board K = {k_board} (search {pass_board})"
    );
    assert!(
        rests_board && rests_virtual,
        "verdicts: virtual {rests_virtual}, board {rests_board}"
    );
    assert!(
        (pass_board / pass_virtual - 1.0).abs() <= 0.10,
        "{plant:?} {out}: searched K: board {pass_board} vs virtual {pass_virtual}, more than 10 % apart"
    );
    assert!(
        (k_board / k_virtual - 1.0).abs() <= 0.25,
        "{plant:?} {out}: set K: board {k_board} vs virtual {k_virtual}, more than 25 % apart"
    );
    let (k_damped, rests_damped, _) = tune(&board);
    eprintln!("tune {plant:?} {out}: board K = {k_damped} (spring + damper)");
    assert!(
        rests_damped && k_damped > k_board,
        "{plant:?} {out}: damped K {k_damped}"
    );
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn tune_sets_the_virtual_devices_wall_maxon_re35_dac() {
    tune_matches(&["--device", "maxon-re35"], "dac");
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn tune_sets_the_virtual_devices_wall_maxon_re35_pwm() {
    tune_matches(&["--device", "maxon-re35"], "pwm");
}

/// phantom-1.0 (linear, Table II) on the `dac` image built with that rig (src/rig.rs, feature
/// `rig-phantom`), which `--board-emulator --device phantom-1.0` picks by itself.
#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn tune_sets_the_virtual_devices_wall_phantom_1_0() {
    tune_matches(&["--device", "phantom-1.0"], "dac");
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn tune_sets_the_virtual_devices_wall_rotary_plant_file() {
    tune_matches(&["--plant", "sim/plants/rotary-belt-60hz.toml"], "dac");
}

/// Runs of the default tune per image in [`tune_is_repeatable_on_the_board`].
const REPEATS: usize = 5;

/// Issue 42: `tune` as a repeatable measurement. The default tune (spring + damper, `--fast`,
/// the wall set and saved) [`REPEATS`] times on the board emulator per image and device beside
/// the virtual device's (deterministic in fast mode), run concurrently (one thread per image;
/// the device ends each test itself, so the host's speed changes no verdict). Every run must
/// pass its own final check ([`tune`]) and set a wall that rests; the set K is printed with its
/// deviation from the virtual device's, which must be within [`AGREEMENT`]. A damped
/// maxon-re35 wall is set below the first K at which the identified model keeps a small swing
/// (`stiffwall_tune::small_swing`); while that screen scanned K by 2 % from the wall asked
/// for, its answer stepped over or into a band of swinging K 0.5 % wide depending on where it
/// started, and the set K was −5.4 to +15.5 % from the virtual device's over 30 board tunes;
/// on its grid of 0.5 % fixed in K the models of the three images (within 0.6 % of each
/// other) find the same band: −1.4 to 0.0 % over 30 board tunes (two runs of this test;
/// maxon-re35 3.3107 on both images but once 3.3056, phantom-1.0 −1.4 to 0.0 %).
const AGREEMENT: f64 = 0.10;

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn tune_is_repeatable_on_the_board() {
    let targets: [(&[&str], &str); 3] = [
        (&["--device", "maxon-re35"], "dac"),
        (&["--device", "maxon-re35"], "pwm"),
        (&["--device", "phantom-1.0"], "dac"),
    ];
    let results: Vec<(String, f64, Vec<f64>)> = std::thread::scope(|scope| {
        let runs: Vec<_> = targets
            .iter()
            .map(|&(plant, out)| {
                scope.spawn(move || {
                    let (k_virtual, rests, _) = tune(plant);
                    assert!(rests, "{plant:?}: the virtual device's wall does not rest");
                    let mut board = plant.to_vec();
                    board.extend(["--board-emulator", "--features", out]);
                    let ks: Vec<f64> = (0..REPEATS)
                        .map(|_| {
                            let (k, rests, _) = tune(&board);
                            assert!(rests, "{board:?}: set K {k} does not rest");
                            k
                        })
                        .collect();
                    (format!("{} {out}", plant.join(" ")), k_virtual, ks)
                })
            })
            .collect();
        runs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let mut worst: f64 = 0.0;
    for (name, k_virtual, ks) in &results {
        let dev: Vec<String> = ks
            .iter()
            .map(|k| format!("{k:.4} ({:+.1} %)", 100.0 * (k / k_virtual - 1.0)))
            .collect();
        eprintln!(
            "tune repeatability {name}: virtual K = {k_virtual:.4}; board: {}",
            dev.join(", ")
        );
        for k in ks {
            worst = worst.max((k / k_virtual - 1.0).abs());
        }
    }
    eprintln!(
        "tune repeatability: largest deviation from the virtual device {:.1} %",
        100.0 * worst
    );
    assert!(
        worst <= AGREEMENT,
        "a board tune set K {:.1} % from the virtual device's (allowed {:.0} %)",
        100.0 * worst,
        100.0 * AGREEMENT
    );
}

/// `hostctl experiment release --json` fields that describe the counts.
fn release(target: &[&str], k: &str, deflection: &str) -> serde_json::Value {
    let (o, _) = run_ok(
        hostctl()
            .args([
                "experiment",
                "release",
                "--fast",
                "--json",
                "--ticks",
                "2000",
            ])
            .args(["--stiffness", k, "--deflection", deflection])
            .args(target),
    );
    json(&o)
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn release_counts_match_the_virtual_device() {
    // Region A-ish (settles) and region D (grows until the supervisor trips).
    for (k, d) in [("0.5", "10"), ("1.2", "10"), ("1.0", "20")] {
        let v = release(&[], k, d);
        for out in OUTPUTS {
            let b = release(&["--board-emulator", "--features", out], k, d);
            eprintln!("release K={k} d={d} {out}: virtual {v}\nboard {b}");
            for field in ["verdict", "completed", "faults", "start_ticks"] {
                assert_eq!(v[field], b[field], "K={k} d={d} {out}: {field}");
            }
            // Within the output quantization: one DAC LSB is 1/1800 and one PWM count 1/8820
            // of full scale against the virtual device's 1/32767, a force difference of at most
            // half a code, so a settling release's tail peak stays within one count. A growing
            // one (region D) is stopped by the supervisor at a size that amplifies any such
            // difference (seen: 39.5 vs 43.5 counts, one tick later); there only the verdict,
            // the start and the fault are compared.
            if v["verdict"] == "settles" {
                let pv = v["tail_peak_ticks"].as_f64().unwrap();
                let pb = b["tail_peak_ticks"].as_f64().unwrap();
                assert!(
                    (pv - pb).abs() <= 1.0,
                    "K={k} d={d} {out}: tail peak {pv} vs {pb}"
                );
            }
        }
    }
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn a_saved_config_comes_back_after_a_power_cycle() {
    let dir = std::env::temp_dir().join(format!("board-emu-store-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let store = dir.join("store.bin");
    let _ = std::fs::remove_file(&store);
    {
        let s = serve(&image("nucleo-f446re-dac"), &store);
        run_ok(hostctl().args(["config", "set", "--stiffness", "0.75", "--port", &s.pty]));
        run_ok(hostctl().args(["config", "save", "--port", &s.pty]));
        // A second save rewrites the other slot (an erase of a written sector comes later).
        run_ok(hostctl().args(["config", "set", "--stiffness", "0.8", "--port", &s.pty]));
        run_ok(hostctl().args(["config", "save", "--port", &s.pty]));
        run_ok(hostctl().args(["config", "set", "--stiffness", "0.85", "--port", &s.pty]));
        run_ok(hostctl().args(["config", "save", "--port", &s.pty]));
    }
    let s = serve(&image("nucleo-f446re-dac"), &store);
    let (o, _) = run_ok(hostctl().args(["config", "get", "--json", "--port", &s.pty]));
    let k = json(&o)["stiffness"].as_f64().expect("stiffness");
    assert!(
        (k - 0.85).abs() < 1e-6,
        "after the power cycle K = {k}\n{o}"
    );
    drop(s);
    let fresh = dir.join("fresh.bin");
    let s = serve(&image("nucleo-f446re-dac"), &fresh);
    let (o, _) = run_ok(hostctl().args(["config", "get", "--json", "--port", &s.pty]));
    assert_eq!(
        json(&o)["stiffness"].as_f64(),
        Some(0.0),
        "a blank store boots the defaults"
    );
    drop(s);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn the_watchdog_resets_a_board_whose_main_loop_stops() {
    let (ok, _, e) = run(Command::new(emulator())
        .arg("--elf")
        .arg(image("nucleo-f446re-dac"))
        .args(["--seconds", "1", "--hang-main-after", "0.3"]));
    assert!(ok, "{e}");
    // IWDG: /64 prescaler, reload 50 → (50 + 1) × 2 ms = 102 ms after the last feed.
    let line = e
        .lines()
        .find(|l| l.starts_with("reset at"))
        .unwrap_or_else(|| panic!("no reset\n{e}"));
    assert!(line.ends_with("Watchdog"), "{line}");
    let at: f64 = line.split_whitespace().nth(2).unwrap().parse().unwrap();
    assert!((0.39..0.41).contains(&at), "reset at {at} s");
}

fn mutant(name: &str) -> PathBuf {
    image(&format!("mutant-{name}"))
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn mutant_tim7_prescaler_fails_the_servo_rate_check() {
    let (ok, _, e) = run(Command::new(emulator())
        .arg("--elf")
        .arg(mutant("tim7-prescaler"))
        .args(["--seconds", "0.5", "--expect-servo-hz", "1000"]));
    assert!(
        !ok && e.contains("TIM7 (servo tick) runs at 500.000 Hz"),
        "{e}"
    );
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn mutant_usart_brr_stops_the_board() {
    let (ok, _, e) = run(Command::new(emulator())
        .arg("--elf")
        .arg(mutant("usart-brr"))
        .args(["--seconds", "0.5"]));
    assert!(!ok && e.contains("USART2_BRR = 0x62"), "{e}");
}

fn mutant_fails_tune(name: &str) -> String {
    let (ok, o, e) = run(hostctl().env("STIFFWALL_NUCLEO_ELF", mutant(name)).args([
        "tune",
        "--fast",
        "--board-emulator",
    ]));
    assert!(!ok, "tune passed on mutant {name}:\n{o}\n{e}");
    e
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn mutant_encoder_polarity_fails_tune() {
    let e = mutant_fails_tune("encoder-polarity");
    assert!(e.contains("tune failed"), "{e}");
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn mutant_dac_alignment_fails_tune() {
    let e = mutant_fails_tune("dac-alignment");
    assert!(e.contains("tune failed"), "{e}");
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn a_malformed_burst_leaves_the_link_and_the_servo_rate_intact() {
    // The QEMU scenario `malformed_burst` on the emulated board: 4 KiB of junk (frame delimiters
    // included) into USART2, then the handshake and a config read still work, no byte was
    // overrun, and TIM7 kept its 1 kHz.
    let (mut child, pty) = spawn_pty(&image("nucleo-f446re-dac"), &[], Stdio::piped());
    // After the boot (bytes that arrive before main unmasks USART2 overrun, as on the chip).
    std::thread::sleep(std::time::Duration::from_millis(200));
    let mut junk = Vec::with_capacity(4096);
    let mut x: u32 = 12345;
    for i in 0..4096 {
        x = x.wrapping_mul(1_103_515_245).wrapping_add(12345);
        junk.push(if i % 97 == 0 { 0 } else { (x >> 16) as u8 });
    }
    {
        use std::io::Write;
        let mut port = std::fs::OpenOptions::new().write(true).open(&pty).unwrap();
        port.write_all(&junk).unwrap();
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    let (o, _) = run_ok(hostctl().args(["info", "--port", &pty]));
    assert!(o.contains("board:       nucleo-f446re-dac"), "{o}");
    run_ok(hostctl().args(["config", "get", "--port", &pty]));
    drop(child.stdin.take());
    let out = child.wait_with_output().unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{e}");
    assert!(e.contains(", 1000.000 Hz (PSC 1, ARR 44999)"), "{e}");
    assert!(e.contains(" 0 overruns"), "{e}");
}

/// Serves `elf` on a pty, writes a steady stream of bytes (48 KiB at 921 600 baud, about
/// 0.5 s) into USART2, and returns how often USART2 preempted the servo tick (TIM7), how often
/// TIM7 preempted USART2, and the emulator's report.
fn preemptions(elf: &Path) -> (u64, u64, String) {
    let (mut child, pty) = spawn_pty(elf, &[], Stdio::piped());
    std::thread::sleep(std::time::Duration::from_millis(200));
    {
        use std::io::Write;
        let mut port = std::fs::OpenOptions::new().write(true).open(&pty).unwrap();
        // Frame delimiters every 64 bytes: the firmware answers bad frames, never a hang.
        let junk: Vec<u8> = (0..48 * 1024)
            .map(|i: u32| if i % 64 == 63 { 0 } else { 0x55 })
            .collect();
        port.write_all(&junk).unwrap();
    }
    std::thread::sleep(std::time::Duration::from_millis(800));
    drop(child.stdin.take());
    let out = child.wait_with_output().unwrap();
    let e = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{e}");
    let times = |prefix: &str| -> u64 {
        e.lines()
            .find_map(|l| l.strip_prefix(prefix))
            .and_then(|rest| rest.trim().strip_suffix("times"))
            .map_or(0, |n| n.trim().parse().unwrap())
    };
    (
        times("preemption: USART2 preempted TIM7 "),
        times("preemption: TIM7 preempted USART2 "),
        e,
    )
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn usart2_preempts_the_servo_tick_and_never_the_other_way() {
    // The NVIC priorities of main.rs: USART2 0x00 above TIM7 0x10. Some RXNE interrupts land
    // inside servo ticks: each must preempt the tick (else a byte could wait a whole tick, and
    // at 10 kHz be overrun), and no tick may ever preempt the USART2 handler.
    let (over_tick, under_tick, e) = preemptions(&image("nucleo-f446re-dac"));
    eprintln!("USART2 preempted TIM7 {over_tick} times, TIM7 preempted USART2 {under_tick} times");
    assert!(over_tick > 0, "USART2 never preempted a servo tick\n{e}");
    assert_eq!(under_tick, 0, "a servo tick preempted USART2\n{e}");
    assert!(e.contains(" 0 overruns"), "{e}");
}

#[test]
#[ignore = "needs the images: run `cargo xtask board-emu`"]
fn mutant_nvic_priority_fails_the_preemption_check() {
    // USART2 at 0x20, below the servo tick: the bytes now wait for the tick to end.
    let (over_tick, under_tick, e) = preemptions(&mutant("nvic-priority"));
    assert!(
        over_tick == 0 && under_tick > 0,
        "USART2 over TIM7 {over_tick}, TIM7 over USART2 {under_tick}\n{e}"
    );
}
