//! The Python client (`clients/python`) and its pytest suite, against the real `winged`
//! binary: `clients/setup.sh` makes the virtual environment (PyPI pins, the client
//! installed editable), then pytest runs `clients/python/tests` with `WINGED_BIN` set to
//! the binary cargo built. The suite starts its own servers on ephemeral ports.
//!
//! Needs `python3` (with `venv`) and `bash`, and PyPI on first run; it fails, never
//! skips, when either is missing or the install fails.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn report(what: &str, o: &Output) -> String {
    format!(
        "{what} exited with {}\n--- stdout ---\n{}\n--- stderr ---\n{}",
        o.status,
        text(&o.stdout),
        text(&o.stderr)
    )
}

/// Runs `clients/setup.sh` (without chromium) and answers the venv's python, the last
/// line it prints.
fn setup() -> PathBuf {
    let python3 = Command::new("python3")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    assert!(
        python3.is_ok_and(|s| s.success()),
        "`python3` is not installed (or not on PATH); the Python client tests need it \
         (Debian: apt-get install -y python3 python3-venv)"
    );
    let o = Command::new("bash")
        .arg("clients/setup.sh")
        .current_dir(repo())
        .env("SKIP_CHROMIUM", "1")
        .stdin(Stdio::null())
        .output()
        .expect("run bash clients/setup.sh");
    assert!(o.status.success(), "{}", report("clients/setup.sh", &o));
    let stdout = text(&o.stdout);
    let python = stdout
        .lines()
        .map(str::trim)
        .rfind(|l| !l.is_empty())
        .unwrap_or_else(|| panic!("{}", report("clients/setup.sh printed no python", &o)));
    let python = PathBuf::from(python);
    assert!(
        Path::new(&python).is_file(),
        "clients/setup.sh named {} as the venv's python, which is not a file",
        python.display()
    );
    python
}

#[test]
fn the_python_client_suite_passes_against_the_real_server() {
    let python = setup();
    let o = Command::new(&python)
        .args([
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "clients/python/tests",
        ])
        .current_dir(repo())
        .env("WINGED_BIN", env!("CARGO_BIN_EXE_winged"))
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .stdin(Stdio::null())
        .output()
        .expect("run pytest");
    assert!(
        o.status.success(),
        "{}",
        report("pytest clients/python/tests", &o)
    );
    let out = text(&o.stdout);
    assert!(
        out.contains(" passed"),
        "pytest reported no passed tests:\n{out}"
    );
    println!("{out}");
}
