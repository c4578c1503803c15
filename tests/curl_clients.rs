//! The curl clients of `clients/curl/` against the real `winged` binary: each script runs
//! with `WINGED` pointing at a server on an ephemeral loopback port and must exit 0 with
//! its summary line; a failed request must stop a script with a non-zero exit.
//!
//! These tests need `bash` and `curl` (and `jq` or `python3`); they fail, never skip, when
//! one is missing.

#[path = "support/process.rs"]
mod process;

use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

use process::Server;

/// A `winged serve --memory` on 127.0.0.1:0 (with the demo scene if asked), killed when
/// dropped.
fn start(demo: bool) -> Server {
    if demo {
        Server::start(&["--memory", "--demo"])
    } else {
        Server::start(&["--memory"])
    }
}

fn scripts() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("clients/curl")
}

/// Fails loudly if a tool the scripts need is not installed.
fn require_tools() {
    for (tool, arg) in [("bash", "--version"), ("curl", "--version")] {
        let ok = Command::new(tool)
            .arg(arg)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        assert!(
            ok,
            "`{tool}` is not installed (or not on PATH); the curl client tests need it"
        );
    }
}

/// Whether `tool --version` runs.
fn has(tool: &str) -> bool {
    Command::new(tool)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Runs `clients/curl/<script>` with `WINGED=url` and extra environment.
fn run(script: &str, url: &str, env: &[(&str, &str)]) -> Output {
    require_tools();
    let mut cmd = Command::new("bash");
    cmd.arg(scripts().join(script))
        .env("WINGED", url)
        .stdin(Stdio::null());
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("run bash")
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Runs a script and asserts it exits 0; returns its standard output.
fn run_ok(script: &str, url: &str, env: &[(&str, &str)]) -> String {
    let o = run(script, url, env);
    let (out, err) = text(&o);
    assert!(
        o.status.success(),
        "{script} failed ({}):\n--- stdout\n{out}\n--- stderr\n{err}",
        o.status
    );
    out
}

#[test]
fn euler_cube_builds_checks_moves_and_deletes_a_cube() {
    let server = start(false);
    let out = run_ok("euler_cube.sh", &server.base, &[]);
    assert!(out.contains("topology: F=6 E=12 V=8"), "{out}");
    assert!(out.contains("moved: world position (3"), "{out}");
    assert!(out.contains("euler_cube: ok (body "), "{out}");
    // The transcript shows every request as a curl command line, and its answer.
    assert_eq!(
        out.matches("/euler -H 'Content-Type: application/json'")
            .count(),
        12,
        "{out}"
    );
    assert!(out.contains("\"op\": \"mkfe\""), "{out}");
    // Again, without the transcript.
    let out = run_ok("euler_cube.sh", &server.base, &[("QUIET", "1")]);
    assert!(
        !out.contains("$ curl"),
        "QUIET=1 keeps the transcript out: {out}"
    );
    assert!(out.contains("euler_cube: ok"), "{out}");
}

#[test]
fn euler_cube_reads_json_with_python3_and_with_jq() {
    let server = start(false);
    let mut readers = vec!["python3"];
    if has("jq") {
        readers.push("jq");
    }
    for reader in readers {
        let out = run_ok(
            "euler_cube.sh",
            &server.base,
            &[("WINGED_JSON", reader), ("QUIET", "1")],
        );
        assert!(out.contains("euler_cube: ok"), "{reader}: {out}");
    }
}

#[test]
fn demo_tour_reads_the_demo_scene() {
    let server = start(true);
    let out = run_ok("demo_tour.sh", &server.base, &[]);
    for want in [
        "table: body ",
        " leg1 ",
        " drum ",
        "cube: body ",
        "F=6 E=12 V=8",
        "an edge with its eight links: {\"id\":",
        "eye: at ",
        "640x480 px",
        "sun: light travelling along ",
        "  shaded: ",
        "  ids: ",
        "visible segments",
        "bodies in view: ",
        "demo_tour: ok",
    ] {
        assert!(out.contains(want), "missing {want:?} in:\n{out}");
    }
}

#[test]
fn demo_tour_on_an_empty_world_says_to_start_with_demo() {
    let server = start(false);
    let o = run("demo_tour.sh", &server.base, &[]);
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}");
    assert!(err.contains("--demo"), "{err}");
}

#[test]
fn errors_shows_404_422_and_400_as_problem_json() {
    let server = start(false);
    let out = run_ok("errors.sh", &server.base, &[]);
    for want in [
        "HTTP 404, Content-Type: application/problem+json",
        "HTTP 422, Content-Type: application/problem+json",
        "HTTP 400, Content-Type: application/problem+json",
        "\"type\":\"urn:winged:problem:euler-refused\"",
        "the world is unchanged",
        "errors: ok",
    ] {
        assert!(out.contains(want), "missing {want:?} in:\n{out}");
    }
}

#[test]
fn a_refused_request_stops_a_script_with_the_problem_on_stderr() {
    let server = start(false);
    require_tools();
    let lib = scripts().join("lib.sh");
    let o = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "set -euo pipefail; . '{}'; r=$(call GET /v1/bodies/424242); echo not reached",
            lib.display()
        ))
        .env("WINGED", &server.base)
        .output()
        .expect("run bash");
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}\n{err}");
    assert!(!out.contains("not reached"), "{out}");
    assert!(err.contains("answered 404"), "{err}");
    assert!(err.contains("no body has id 424242"), "{err}");
}

#[test]
fn no_server_stops_a_script() {
    // Bind and drop a listener to find a port nothing listens on.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("bind")
        .port();
    let url = format!("http://127.0.0.1:{port}");
    let o = run("euler_cube.sh", &url, &[]);
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}");
    assert!(err.contains("no answer from"), "{err}");
}
