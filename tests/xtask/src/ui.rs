//! The real-browser test of `hostctl ui` (host/hostctl/tests/ui_browser.rs, `#[ignore]`d in plain
//! `cargo test` because it needs Debian's chromium and chromium-driver, which this installs)
//! and the screenshots it writes to docs/figures/ui-*.png.

use crate::process::cargo;
use crate::{firmware, toolchain};
use anyhow::Result;
use std::path::Path;

/// Runs the browser test; with `screenshots`, it writes its PNGs into that directory.
pub fn browser_test(screenshots: Option<&Path>) -> Result<()> {
    toolchain::ensure_chromium()?;
    let mut c = cargo();
    c.args([
        "test",
        "-p",
        "stiffwall-host",
        "--test",
        "ui_browser",
        "--",
        "--ignored",
    ]);
    if let Some(dir) = screenshots {
        c.env("STIFFWALL_UI_SCREENSHOTS", dir);
    }
    // A filter or a rename that leaves no browser test to run must not pass in silence.
    crate::process::run_counting(&mut c, 1)
}

/// `cargo xtask ui-screenshots`: docs/figures/ui-overview.png, ui-fault.png, ui-map.png.
pub fn screenshots() -> Result<()> {
    let dir = firmware::root().join("docs/figures");
    std::fs::create_dir_all(&dir)?;
    const NAMES: [&str; 3] = ["ui-overview.png", "ui-fault.png", "ui-map.png"];
    // Old pictures never pass for new ones.
    for name in NAMES {
        let _ = std::fs::remove_file(dir.join(name));
    }
    browser_test(Some(&dir))?;
    for name in NAMES {
        let p = dir.join(name);
        anyhow::ensure!(
            p.is_file(),
            "the browser test did not write {}",
            p.display()
        );
        eprintln!("xtask: wrote {}", p.display());
    }
    Ok(())
}
