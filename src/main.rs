//! `winged`: the world-model server's command line.
//!
//! `winged check` builds the seeds' example solids through the Euler operators and
//! prints each one's counts and the validator's verdict.

use std::process::ExitCode;

use winged::model::solids::{cylinder, mkcube, mktetra, sphere, torus};
use winged::model::{Body, Serials, check_solid};

const USAGE: &str = "usage: winged check    build the seeds' example solids and validate them";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        None | Some("check") => check(),
        Some("-h" | "--help" | "help") => {
            println!("{USAGE}");
            ExitCode::SUCCESS
        }
        Some(other) => {
            eprintln!("winged: unknown command {other:?}\n{USAGE}");
            ExitCode::from(2)
        }
    }
}

fn check() -> ExitCode {
    let mut serials = Serials::new();
    let mut failed = false;
    let mut show = |name: &str, body: Result<Body, String>| match body {
        Ok(b) => {
            let report = check_solid(&b, 1e-9);
            println!(
                "{name:<12} F={:<3} E={:<3} V={:<3} H={} volume={:<10.4} {}",
                b.face_count(),
                b.edge_count(),
                b.vertex_count(),
                b.handles(),
                b.volume(),
                report
            );
            failed |= !report.is_ok();
        }
        Err(e) => {
            println!("{name:<12} failed: {e}");
            failed = true;
        }
    };
    show(
        "MKCUBE",
        mkcube(&mut serials, 2.0, 2.0, 2.0).map_err(|e| e.to_string()),
    );
    show(
        "MKTETRA",
        mktetra(&mut serials, 1.0).map_err(|e| e.to_string()),
    );
    show(
        "cylinder",
        cylinder(&mut serials, 1.0, 2.0, 32).map_err(|e| e.to_string()),
    );
    show(
        "sphere",
        sphere(&mut serials, 1.0, 32, 16).map_err(|e| e.to_string()),
    );
    show(
        "torus",
        torus(&mut serials, 2.0, 0.5, 32, 16).map_err(|e| e.to_string()),
    );
    if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}
