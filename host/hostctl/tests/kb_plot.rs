//! Issue 19 item 7: the (K, B) frontier figures of `hostctl analyze --damping B --plot` and
//! `hostctl tune --plot` (`<stem>-kb.<ext>` beside the (β, σ) figure): written, non-empty,
//! valid SVG (axis labels and legend text) or PNG (signature and the figure's size), and a bad
//! extension refused before anything is written.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use stiffwall_host::analysis::kb_plot::SIZE_PX;

fn hostctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .args(args)
        .output()
        .expect("run hostctl")
}

fn ok(args: &[&str]) -> String {
    let out = hostctl(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stiffwall-kb-plot-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn svg_with(path: &Path, needles: &[&str]) {
    let svg = std::fs::read_to_string(path).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"),
        "{path:?}"
    );
    // The figure's words as drawn, wrapped lines joined back at their spaces.
    let text = stiffwall_figures::describe::svg_text(&svg);
    for n in needles {
        assert!(text.contains(n), "{path:?} lacks {n:?}");
    }
}

/// PNG signature, IHDR width and height equal to the figure's size, and some KB of data.
fn png_of_figure_size(path: &Path) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "{path:?}: PNG signature");
    assert_eq!(&b[12..16], b"IHDR", "{path:?}");
    let be = |i: usize| u32::from_be_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
    assert_eq!((be(16), be(20)), SIZE_PX, "{path:?}: size");
    assert!(b.len() > 5_000, "{path:?}: {} bytes", b.len());
}

#[test]
fn analyze_damping_plot_writes_the_frontier_beside_the_plane() {
    let dir = temp_dir("analyze");
    let svg = dir.join("a.svg");
    let out = ok(&[
        "analyze",
        "--device",
        "phantom-1.0",
        "--damping",
        "2",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    let kb = dir.join("a-kb.svg");
    assert!(
        out.contains(&format!("written to {}", kb.display())),
        "{out}"
    );
    svg_with(&svg, &["β = b/(KT)"]);
    svg_with(
        &kb,
        &[
            "B, virtual damping of the wall [N·s/m]",
            "K, wall stiffness [N/m]",
            "exact linear K_max(B)",
            "best B = ",
            "operating point B = 2.000 N·s/m",
        ],
    );
    let png = dir.join("r.PNG");
    let rot = [
        "analyze",
        "--device",
        "maxon-re35",
        "--damping",
        "0.01",
        "--plot",
    ];
    ok(&[&rot[..], &[png.to_str().unwrap()]].concat());
    png_of_figure_size(&dir.join("r-kb.PNG"));
    let rot_svg = dir.join("r.svg");
    ok(&[&rot[..], &[rot_svg.to_str().unwrap()]].concat());
    svg_with(
        &dir.join("r-kb.svg"),
        &[
            "B, virtual damping of the wall [N·m·s/rad]",
            "K, wall stiffness [N·m/rad]",
        ],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn analyze_without_damping_writes_no_frontier_and_bad_extensions_are_refused() {
    let dir = temp_dir("analyze-plain");
    let svg = dir.join("p.svg");
    let out = ok(&[
        "analyze",
        "--device",
        "phantom-1.0",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(svg.exists() && !dir.join("p-kb.svg").exists(), "{out}");
    let jpg = dir.join("p.jpg");
    let args = [
        "analyze",
        "--device",
        "phantom-1.0",
        "--damping",
        "2",
        "--plot",
        jpg.to_str().unwrap(),
    ];
    let bad = hostctl(&args);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains(".svg or .png"));
    assert!(!jpg.exists() && !dir.join("p-kb.jpg").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tune_plot_writes_the_frontier_with_verified_points_and_the_set_wall() {
    let dir = temp_dir("tune");
    let svg = dir.join("t.svg");
    let out = ok(&[
        "tune",
        "--fast",
        "--dry-run",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    let kb = dir.join("t-kb.svg");
    assert!(
        out.contains(&format!("(K, B) frontier plot: {}", kb.display())),
        "{out}"
    );
    svg_with(&svg, &["β = b/(KT)"]);
    svg_with(
        &kb,
        &[
            "B, virtual damping of the wall [N·m·s/rad]",
            "K, wall stiffness [N·m/rad]",
            "predicted K_max(B)",
            "verified: the largest resting K",
            "spring-only wall K = ",
            "set wall K = ",
        ],
    );
    let lin = dir.join("l.svg");
    ok(&[
        "tune",
        "--fast",
        "--dry-run",
        "--device",
        "phantom-1.0",
        "--plot",
        lin.to_str().unwrap(),
    ]);
    svg_with(
        &dir.join("l-kb.svg"),
        &[
            "B, virtual damping of the wall [N·s/m]",
            "K, wall stiffness [N/m]",
            "set wall K = ",
        ],
    );
    let png = dir.join("t.png");
    let v = ok(&[
        "tune",
        "--fast",
        "--dry-run",
        "--json",
        "--plot",
        png.to_str().unwrap(),
    ]);
    let v: serde_json::Value = serde_json::from_str(&v).unwrap();
    assert!(v["tune"]["b_set"].as_f64().unwrap() > 0.0, "{v}");
    let kb_png = dir.join("t-kb.png");
    assert_eq!(v["plot_kb"].as_str(), kb_png.to_str());
    png_of_figure_size(&kb_png);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tune_spring_only_writes_no_frontier_and_bad_extension_is_refused_before_connecting() {
    let dir = temp_dir("tune-plain");
    let svg = dir.join("s.svg");
    ok(&[
        "tune",
        "--fast",
        "--dry-run",
        "--damping",
        "0",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(svg.exists() && !dir.join("s-kb.svg").exists());
    let gif = dir.join("s.gif");
    let bad = hostctl(&[
        "tune",
        "--fast",
        "--dry-run",
        "--plot",
        gif.to_str().unwrap(),
    ]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains(".svg or .png") && !err.contains("connecting"),
        "{err}"
    );
    assert!(!gif.exists() && !dir.join("s-kb.gif").exists());
    let missing = dir.join("no/such/dir/s.svg");
    let bad = hostctl(&[
        "tune",
        "--fast",
        "--dry-run",
        "--plot",
        missing.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        !bad.status.success() && err.contains("cannot write the figure file"),
        "{err}"
    );
    assert!(
        !err.contains("connecting"),
        "refused before connecting: {err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
