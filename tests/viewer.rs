//! The browser viewer in a real headless Chromium: sets up the Python environment with
//! `clients/setup.sh` (Selenium, and Debian's chromium and chromium-driver when missing)
//! and runs `clients/viewer/tests` against the `winged` binary built for this test.
//!
//! A failed setup fails the test: it is never skipped.

use std::path::Path;
use std::process::Command;

/// The combined output of a finished command, for failure messages.
fn output_of(out: &std::process::Output) -> String {
    format!(
        "--- stdout\n{}\n--- stderr\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

#[test]
fn the_viewer_works_in_headless_chromium() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let setup = Command::new("bash")
        .arg("clients/setup.sh")
        .current_dir(root)
        .output()
        .expect("bash runs clients/setup.sh");
    assert!(
        setup.status.success(),
        "clients/setup.sh failed ({}):\n{}",
        setup.status,
        output_of(&setup)
    );
    let stdout = String::from_utf8_lossy(&setup.stdout);
    let python = stdout
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .map(str::trim)
        .unwrap_or_else(|| panic!("clients/setup.sh named no python:\n{}", output_of(&setup)));

    let tests = Command::new(python)
        .args([
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "clients/viewer/tests",
        ])
        .current_dir(root)
        .env("WINGED_BIN", env!("CARGO_BIN_EXE_winged"))
        .output()
        .expect("the venv's python runs");
    assert!(
        tests.status.success(),
        "the viewer's browser tests failed ({}):\n{}",
        tests.status,
        output_of(&tests)
    );
    println!("{}", String::from_utf8_lossy(&tests.stdout));
}
