//! End-to-end tests of `hostctl info`, `config`, `stream`, `record` and `replay` against the
//! built-in virtual device over a pseudo-terminal (no hardware). The CLI tests run the real
//! `hostctl` binary; the disconnect and overflow tests drive the library so they can cut the
//! link or stall the reader at a chosen moment.

use std::path::PathBuf;
use std::process::{Command, Output};
use std::time::{Duration, Instant};
use stiffwall_client::Client;
use stiffwall_client::{spawn_virtual_device as spawn, Pace, VirtualSpec as Spec};
use stiffwall_host::cmd::record::{header, record, End, Plan};

fn hostctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .args(args)
        .output()
        .expect("run hostctl")
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn ok(args: &[&str]) -> String {
    let o = hostctl(args);
    let (out, err) = text(&o);
    assert!(o.status.success(), "hostctl {args:?} failed:\n{out}\n{err}");
    out
}

/// Runs a command that must fail cleanly (exit 1, no panic); returns stderr.
fn fails(args: &[&str]) -> String {
    let o = hostctl(args);
    let (out, err) = text(&o);
    assert!(!o.status.success(), "hostctl {args:?} succeeded:\n{out}");
    assert!(
        !err.contains("panicked"),
        "hostctl {args:?} panicked:\n{err}"
    );
    err
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("stiffwall-device-cmds-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn maxon(fast: bool) -> Spec {
    Spec {
        plant: stiffwall_core::devices::find("maxon-re35").unwrap().params,
        counts_per_rev: 8192,
        pace: Pace::fast_if(fast),
        initial_position: 0.0,
        output_range: None,
        scene: None,
        travel: None,
        trace: None,
    }
}

#[test]
fn info_text_and_json() {
    let out = ok(&["info", "--fast"]);
    assert!(out.contains("board:       virtual"), "{out}");
    assert!(out.contains("8192 counts/rev"), "{out}");
    assert!(out.contains("faults:      none"), "{out}");
    let v: serde_json::Value = serde_json::from_str(&ok(&["info", "--fast", "--json"])).unwrap();
    assert_eq!(v["device"]["board"], "virtual");
    assert_eq!(
        v["device"]["protocol_version"],
        u64::from(stiffwall_proto::PROTOCOL_VERSION)
    );
    assert_eq!(v["faults"]["latched"], 0);
}

#[test]
fn config_get_set_save_defaults() {
    let get: serde_json::Value =
        serde_json::from_str(&ok(&["config", "get", "--fast", "--json"])).unwrap();
    assert_eq!(get["stiffness"], 0.0);
    let set: serde_json::Value = serde_json::from_str(&ok(&[
        "config",
        "set",
        "--stiffness",
        "2.5",
        "--delay-ticks",
        "1",
        "--rate",
        "5000",
        "--wall",
        "one-sided",
        "--energy-monitor",
        "off",
        "--fast",
        "--json",
    ]))
    .unwrap();
    assert_eq!(set["stiffness"], 2.5);
    assert_eq!(set["extra_delay_ticks"], 1);
    assert_eq!(set["servo_rate_hz"], 5000);
    assert_eq!(set["wall"], "OneSided");
    assert_eq!(set["energy_monitor"], false);
    // Fields not given keep their value.
    assert_eq!(set["force_limit"], get["force_limit"]);
    assert_eq!(set["damping"], get["damping"]);
    let out = ok(&["config", "save", "--fast"]);
    assert!(out.contains("# saved"), "{out}");
    let out = ok(&["config", "defaults", "--fast"]);
    assert!(out.contains("firmware defaults"), "{out}");
}

#[test]
fn config_refusals_name_the_field() {
    // Refused by the device: its message names the field and the range.
    let e = fails(&["config", "set", "--stiffness", "1e6", "--fast"]);
    assert!(e.contains("--stiffness must be within [0, "), "{e}");
    let e = fails(&["config", "set", "--rate", "50", "--fast"]);
    assert!(e.contains("--rate must be within [100, 20000]"), "{e}");
    // Refused on the host before sending.
    let e = fails(&["config", "set", "--stiffness", "NaN"]);
    assert!(
        e.contains("--stiffness must be a finite number >= 0 (got NaN)"),
        "{e}"
    );
    let e = fails(&["config", "set", "--damping", "-1"]);
    assert!(e.contains("--damping must be a finite number >= 0"), "{e}");
    let e = fails(&["config", "set", "--delay-ticks", "40"]);
    assert!(e.contains("--delay-ticks must be within [0, 31]"), "{e}");
    let e = fails(&["config", "set", "--force-limit", "0"]);
    assert!(
        e.contains("--force-limit must be a finite number > 0"),
        "{e}"
    );
    let e = fails(&["config", "set", "--fast"]);
    assert!(e.contains("at least one field"), "{e}");
}

#[test]
fn wrong_port_is_a_clear_error() {
    for cmd in [
        vec!["info"],
        vec!["config", "get"],
        vec!["stream", "--seconds", "1"],
    ] {
        let mut args = cmd.clone();
        args.extend(["--port", "/dev/stiffwall-no-such-port"]);
        let e = fails(&args);
        assert!(
            e.contains("serial port /dev/stiffwall-no-such-port does not exist"),
            "{args:?}: {e}"
        );
    }
    let f = tmp("never.csv");
    let e = fails(&[
        "record",
        f.to_str().unwrap(),
        "--port",
        "/dev/stiffwall-no-such-port",
    ]);
    assert!(e.contains("does not exist"), "{e}");
    assert!(!f.exists(), "no file for a failed connection");
}

#[test]
fn silent_or_non_serial_port_is_a_clear_error() {
    use serialport::SerialPort as _;
    // A pty nobody answers on: the handshake gives up with a clear message.
    let (_master, mut slave) = serialport::TTYPort::pair().unwrap();
    slave.set_exclusive(false).unwrap();
    let path = slave.name().unwrap();
    let _keep = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&path)
        .unwrap();
    drop(slave);
    let e = fails(&["info", "--port", &path]);
    assert!(e.contains("the device never answered the handshake"), "{e}");
    // Not a serial port at all.
    let e = fails(&["config", "get", "--port", "/dev/null"]);
    assert!(e.contains("cannot open serial port /dev/null"), "{e}");
}

#[test]
fn stream_shows_a_summary_without_gaps() {
    let out = ok(&["stream", "--seconds", "1", "--rate", "2000", "--fast"]);
    assert!(
        out.contains("stream (2000 Hz / decimation 1): received 2000, missing 0"),
        "{out}"
    );
    assert!(out.contains("last: tick"), "{out}");
    let e = fails(&["stream", "--decimation", "0"]);
    assert!(e.contains("--decimation must be within [1, 65535]"), "{e}");
}

#[test]
fn ten_seconds_at_5khz_has_zero_gaps() {
    let f = tmp("ten-seconds.csv");
    let t = Instant::now();
    let out = ok(&[
        "record",
        f.to_str().unwrap(),
        "--seconds",
        "10",
        "--rate",
        "5000",
        "--decimation",
        "1",
        "--stiffness",
        "2",
        "--fast",
    ]);
    let wall = t.elapsed();
    eprintln!(
        "record 10 s at 5 kHz (--fast): {:.2} s wall; {out}",
        wall.as_secs_f64()
    );
    let rec = stiffwall_client::read_recording(&f).unwrap();
    assert_eq!(rec.rows.len(), 50_000);
    assert_eq!(rec.missing(), 0);
    assert_eq!(rec.segments().len(), 1);
    assert_eq!(rec.segments()[0], 0..50_000);
    assert_eq!(rec.header.config.servo_rate_hz, 5000);
    assert_eq!(rec.header.config.stiffness, 2.0);
    assert_eq!(rec.header.decimation, 1);
    assert_eq!(rec.header.device.board.as_str(), "virtual");
    let text = std::fs::read_to_string(&f).unwrap();
    assert!(!text.contains("# gap:"));
    assert!(text.contains("# end: received 50000, missing 0"), "trailer");
    assert!(out.contains("missing 0 in 0 gap(s)"), "{out}");
}

/// Paced (real-time) virtual device at 5 and 10 kHz, every sample: the figure of the issue.
#[test]
fn real_time_streaming_5_and_10_khz() {
    for rate in [5000u32, 10_000] {
        let mut c = {
            let (vd, port) = spawn(maxon(false)).unwrap();
            Client::connect(port, Some(Box::new(vd))).unwrap()
        };
        let mut cfg = c.get_config().unwrap();
        cfg.servo_rate_hz = rate;
        c.set_config(&cfg).unwrap();
        let plan = Plan::new(1, Some(2.0), rate).unwrap();
        let h = header(&c, cfg, 1, None);
        let t = Instant::now();
        let o = record(&mut c, &plan, &h, Vec::new(), |_| {}).unwrap();
        eprintln!(
            "paced {rate} Hz, decimation 1, 2 s: {:.3} s wall, {}",
            t.elapsed().as_secs_f64(),
            o.stats.summary()
        );
        assert_eq!(o.end, End::Complete);
        assert_eq!(o.rows + o.stats.missing, u64::from(rate) * 2);
        assert_eq!(o.stats.missing, 0, "{rate} Hz: {}", o.stats.summary());
    }
}

#[test]
fn disconnect_keeps_what_was_received() {
    // Paced, so the recording is still running when the device goes away.
    let (vd, port) = spawn(maxon(false)).unwrap();
    let mut c = Client::connect(port, None).unwrap();
    let cfg = c.get_config().unwrap();
    let plan = Plan::new(1, Some(5.0), cfg.servo_rate_hz).unwrap();
    let h = header(&c, cfg, 1, None);
    let killer = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(700));
        drop(vd); // stops the device thread and closes its side of the pty
    });
    let f = tmp("disconnect.csv");
    let file = std::fs::File::create(&f).unwrap();
    let t = Instant::now();
    let o = record(&mut c, &plan, &h, std::io::BufWriter::new(file), |_| {}).unwrap();
    killer.join().unwrap();
    eprintln!(
        "disconnect after 0.7 s: {:?} after {:.2} s, {}",
        o.end,
        t.elapsed().as_secs_f64(),
        o.stats.summary()
    );
    assert!(
        matches!(&o.end, End::Disconnected(_) | End::Silent(_)),
        "{:?}",
        o.end
    );
    assert!(o.rows > 100, "kept what was received: {}", o.rows);
    assert!(o.rows < 5000, "stopped at the disconnect: {}", o.rows);
    let rec = stiffwall_client::read_recording(&f).unwrap();
    assert_eq!(
        rec.rows.len() as u64,
        o.rows,
        "every received sample is in the file"
    );
    let text = std::fs::read_to_string(&f).unwrap();
    let end = text.lines().last().unwrap();
    assert!(
        end.starts_with("# end:") && (end.contains("DISCONNECTED") || end.contains("SILENT")),
        "{end}"
    );
}

/// A link the test controls: a paced virtual device, relayed byte for byte to a second pty
/// that `hostctl --port` opens by path. The relay throws away `lose` bytes once `lose_at`
/// bytes have passed (a burst of line noise), and hangs up after `cut_after`.
fn relay(
    lose_at: usize,
    lose: usize,
    cut_after: Duration,
) -> (String, std::thread::JoinHandle<()>) {
    use serialport::SerialPort as _;
    use std::io::{Read, Write};
    let (vd, mut dev) = spawn(maxon(false)).unwrap();
    let (mut master, mut slave) = serialport::TTYPort::pair().unwrap();
    // Keep the pty open with a plain file (no flock), so that hostctl's exclusive open works
    // and the master never sees a hang-up before hostctl has opened the port.
    slave.set_exclusive(false).unwrap();
    let path = slave.name().unwrap();
    let keep_open = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&path)
        .unwrap();
    drop(slave);
    master.set_timeout(Duration::from_millis(1)).unwrap();
    let t = std::thread::spawn(move || {
        let _keep_open = keep_open;
        let start = Instant::now();
        let (mut passed, mut lost) = (0usize, 0usize);
        let mut buf = [0u8; 4096];
        while start.elapsed() < cut_after {
            if let Ok(n) = master.bytes_to_read() {
                if n > 0 {
                    if let Ok(n) = master.read(&mut buf) {
                        let _ = dev.write_all(&buf[..n]);
                    }
                }
            }
            match dev.read(&mut buf) {
                Ok(n) if n > 0 => {
                    let mut out = &buf[..n];
                    if passed >= lose_at && lost < lose {
                        let k = (lose - lost).min(out.len());
                        lost += k;
                        out = &out[k..];
                    }
                    passed += n;
                    let _ = master.write_all(out);
                }
                _ => {}
            }
        }
        drop(vd);
        drop(master); // hang up
    });
    (path, t)
}

#[test]
fn cli_recording_reports_link_loss_and_disconnect_and_keeps_data() {
    // hostctl is started (through sh, after a short sleep) *before* the ptys exist, so that it
    // cannot inherit the relay's master descriptor and the hang-up reaches it.
    let link = tmp("relay-port");
    let _ = std::fs::remove_file(&link);
    let f = tmp("cli-disconnect.csv");
    let child = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "sleep 0.5; exec '{}' record '{}' --port '{}' --seconds 10",
            env!("CARGO_BIN_EXE_hostctl"),
            f.display(),
            link.display()
        ))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let (pty, t) = relay(5_000, 300, Duration::from_millis(2500));
    std::os::unix::fs::symlink(&pty, &link).unwrap();
    let o = child.wait_with_output().unwrap();
    t.join().unwrap();
    let (out, err) = text(&o);
    eprintln!("{out}{err}");
    assert!(!o.status.success());
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("the device disconnected during the recording"),
        "{err}"
    );
    let rec = stiffwall_client::read_recording(&f).unwrap();
    assert!(rec.rows.len() > 500, "kept {} rows", rec.rows.len());
    assert!(
        err.contains(&format!("kept the {} samples received", rec.rows.len())),
        "{err}"
    );
    // The burst of lost bytes is a link-lost gap, noted where it happened.
    let text = std::fs::read_to_string(&f).unwrap();
    let gap = text
        .lines()
        .find(|l| l.starts_with("# gap:"))
        .expect("gap noted");
    assert!(gap.contains("(device-dropped 0, link-lost"), "{gap}");
    assert!(rec.missing() > 0);
    let end = text.lines().last().unwrap();
    assert!(
        end.starts_with("# end:") && end.contains("DISCONNECTED"),
        "{end}"
    );
    assert!(
        end.contains(&format!(
            "missing {} in 1 gap(s) (device-dropped 0, link-lost {})",
            rec.missing(),
            rec.missing()
        )),
        "{end}"
    );
}

#[test]
fn stalled_reader_gaps_are_noted_and_attributed() {
    // Paced 20 kHz and a reader that stalls once for 1.5 s: the device's queue overflows and
    // the lost samples must show up as device-dropped gaps, in the file and in the stats.
    let (vd, port) = spawn(maxon(false)).unwrap();
    let mut c = Client::connect(port, Some(Box::new(vd))).unwrap();
    let mut cfg = c.get_config().unwrap();
    cfg.servo_rate_hz = 20_000;
    c.set_config(&cfg).unwrap();
    let plan = Plan::new(1, Some(3.0), 20_000).unwrap();
    let h = header(&c, cfg, 1, None);
    let mut stalled = false;
    let o = record(&mut c, &plan, &h, Vec::new(), |_| {
        if !stalled {
            stalled = true;
            std::thread::sleep(Duration::from_millis(1500));
        }
    })
    .unwrap();
    eprintln!("stalled reader: {}", o.stats.summary());
    assert_eq!(o.end, End::Complete);
    assert!(o.stats.missing > 0, "{}", o.stats.summary());
    assert_eq!(
        o.stats.missing,
        o.stats.device_dropped + o.stats.link_lost,
        "every missing sample attributed"
    );
    assert_eq!(o.rows + o.stats.missing, 60_000, "{}", o.stats.summary());
}

#[test]
fn replay_reproduces_force_codes_bit_for_bit() {
    let f = tmp("release.csv");
    // A release test with a non-trivial config: stiffness, damping, 2 ticks of extra delay.
    let out = ok(&[
        "record",
        f.to_str().unwrap(),
        "--seconds",
        "3",
        "--stiffness",
        "0.5",
        "--damping",
        "0.0002",
        "--delay-ticks",
        "2",
        "--energy-monitor",
        "off",
        "--release",
        "30",
        "--fast",
    ]);
    eprintln!("{out}");
    let plot = tmp("replay.svg");
    let json = ok(&[
        "replay",
        f.to_str().unwrap(),
        "--json",
        "--plot",
        plot.to_str().unwrap(),
    ]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    eprintln!("{json}");
    let servo = &v["servo"];
    assert_eq!(servo["mismatch_count"], 0, "{json}");
    assert!(servo["compared"].as_u64().unwrap() > 500, "{json}");
    assert_eq!(servo["matched"], servo["compared"]);
    assert!(
        servo["excluded_experiment"].as_u64().unwrap() > 0,
        "hold phase excluded"
    );
    let plant = &v["plant"];
    assert!(plant["rms_ticks"].as_f64().unwrap() <= 1.0, "{json}");
    assert!(plant["max_ticks"].as_i64().unwrap() <= 2, "{json}");
    assert!(std::fs::metadata(&plot).unwrap().len() > 1000);

    // Negative control: one comparable force code changed → a reported mismatch, exit 1.
    let text = std::fs::read_to_string(&f).unwrap();
    let rec = stiffwall_client::parse_recording(&text).unwrap();
    let victim = rec
        .rows
        .iter()
        .rev()
        .find(|r| r.sample.flags & stiffwall_proto::flags::RELEASED != 0)
        .unwrap();
    let s = victim.sample;
    let line = format!(
        "{},{},{},{},{},{}\n",
        victim.seq, s.tick, s.count, s.force_code, s.flags, s.energy
    );
    let changed = format!(
        "{},{},{},{},{},{}\n",
        victim.seq,
        s.tick,
        s.count,
        s.force_code + 1,
        s.flags,
        s.energy
    );
    let bad = tmp("tampered.csv");
    std::fs::write(&bad, text.replacen(&line, &changed, 1)).unwrap();
    let e = fails(&["replay", bad.to_str().unwrap()]);
    assert!(
        e.contains("1 of ") && e.contains(&format!("first at seq {}", victim.seq)),
        "{e}"
    );
}

#[test]
fn replay_of_a_plain_recording_and_wrong_plant() {
    let f = tmp("plain.csv");
    ok(&[
        "record",
        f.to_str().unwrap(),
        "--seconds",
        "1",
        "--rate",
        "4000",
        "--stiffness",
        "1",
        "--fast",
    ]);
    let out = ok(&["replay", f.to_str().unwrap()]);
    assert!(
        out.contains("(b) servo replay: 3999/3999 force codes reproduced bit for bit"),
        "{out}"
    );
    assert!(out.contains("(a) plant replay"), "{out}");
    // Explicit parameters override the recorded preset; bad ones are refused.
    let out = ok(&[
        "replay",
        f.to_str().unwrap(),
        "--mass",
        "1e-5",
        "--viscous",
        "0",
        "--coulomb",
        "0.002",
    ]);
    assert!(out.contains("--mass"), "{out}");
    let e = fails(&["replay", f.to_str().unwrap(), "--mass", "-1"]);
    assert!(
        e.contains("--mass must be finite and in [1e-9, 1e3] kg"),
        "{e}"
    );
    let e = fails(&["replay", f.to_str().unwrap(), "--device", "nope"]);
    assert!(e.contains("unknown device \"nope\""), "{e}");
    // Decimated recordings: replays that need every tick say why they cannot run.
    let d = tmp("decimated.csv");
    ok(&[
        "record",
        d.to_str().unwrap(),
        "--seconds",
        "1",
        "--decimation",
        "10",
        "--fast",
    ]);
    let out = ok(&["replay", d.to_str().unwrap()]);
    assert!(
        out.contains("skipped: servo replay needs every servo tick (decimation 1)"),
        "{out}"
    );
}

#[test]
fn corrupted_csv_is_a_clear_error() {
    let f = tmp("to-corrupt.csv");
    ok(&["record", f.to_str().unwrap(), "--seconds", "0.2", "--fast"]);
    let text = std::fs::read_to_string(&f).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let header_at = lines
        .iter()
        .position(|l| *l == stiffwall_client::RECORDING_COLUMNS)
        .unwrap();
    let row_line = header_at + 5; // 0-based index of some data row
    let mut bad_lines: Vec<String> = lines.iter().map(|l| (*l).to_string()).collect();
    let fields: Vec<&str> = lines[row_line].split(',').collect();
    bad_lines[row_line] = format!(
        "{},{},{},12x,{},{}",
        fields[0], fields[1], fields[2], fields[4], fields[5]
    );
    let bad = tmp("corrupt-field.csv");
    std::fs::write(&bad, bad_lines.join("\n")).unwrap();
    let e = fails(&["replay", bad.to_str().unwrap()]);
    assert!(
        e.contains(&format!("line {}, column 4 (force_code)", row_line + 1)),
        "{e}"
    );
    // Truncated mid-header, binary garbage, missing file.
    let cut = tmp("cut.csv");
    std::fs::write(&cut, &text[..text.find("# config").unwrap()]).unwrap();
    let e = fails(&["replay", cut.to_str().unwrap()]);
    assert!(e.contains("no column header"), "{e}");
    let junk = tmp("junk.csv");
    std::fs::write(&junk, [0xffu8, 0, 1, 2, 0x80]).unwrap();
    let e = fails(&["replay", junk.to_str().unwrap()]);
    assert!(e.contains("junk.csv"), "{e}");
    let e = fails(&["replay", tmp("missing.csv").to_str().unwrap()]);
    assert!(e.contains("reading recording"), "{e}");
}

/// The real Cortex-M firmware image under QEMU (16-bit counter, Impulse Engine plant): a
/// release recording replays bit for bit through the host build of the servo core, and the
/// plant replay with the board's preset stays within a tick.
#[test]
#[ignore = "needs qemu-system-arm and the board image: run `cargo xtask qemu`"]
fn qemu_recording_replays_bit_for_bit() {
    let f = tmp("qemu.csv");
    ok(&[
        "record",
        f.to_str().unwrap(),
        "--qemu",
        "--seconds",
        "3",
        "--stiffness",
        "2000",
        "--delay-ticks",
        "1",
        "--energy-monitor",
        "off",
        "--release",
        "20",
    ]);
    let v: serde_json::Value = serde_json::from_str(&ok(&[
        "replay",
        f.to_str().unwrap(),
        "--device",
        "impulse-engine",
        "--json",
    ]))
    .unwrap();
    assert_eq!(v["servo"]["mismatch_count"], 0, "{v}");
    assert!(v["servo"]["compared"].as_u64().unwrap() > 500, "{v}");
    assert!(v["plant"]["max_ticks"].as_i64().unwrap() <= 2, "{v}");
}
