//! `winged`: the world-model server's command line.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use tracing::info;
use winged::model::solids::{cylinder, mkcube, mktetra, sphere, torus};
use winged::model::{Body, Serials, World, check_solid};
use winged::server;

/// A networked world model of Baumgart's winged-edge polyhedra.
#[derive(Parser)]
#[command(name = "winged", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Serve the world over HTTP/JSON.
    Serve {
        /// Address to listen on.
        #[arg(long, default_value = "127.0.0.1:7878")]
        addr: SocketAddr,
        /// Directory for the world's data (reserved for persistence; the world is
        /// currently held in memory only).
        #[arg(long)]
        data: Option<PathBuf>,
        /// Start with the demo scene: the hand-eye table with blocks, a camera and a sun.
        #[arg(long)]
        demo: bool,
    },
    /// Build the seeds' example solids through the Euler operators and validate them.
    Check,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Serve { addr, data, demo } => serve(addr, data, demo),
        Command::Check => check(),
    }
}

fn serve(addr: SocketAddr, data: Option<PathBuf>, demo: bool) -> ExitCode {
    tracing_subscriber::fmt()
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stdout()))
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()),
        )
        .init();
    if let Some(dir) = &data {
        tracing::warn!(dir = %dir.display(), "--data is accepted but the world is not yet persisted");
    }
    let world = if demo {
        match server::demo::demo_world() {
            Ok(w) => w,
            Err(e) => {
                eprintln!("winged: the demo scene failed to build: {e}");
                return ExitCode::FAILURE;
            }
        }
    } else {
        World::new()
    };
    let runtime = match tokio::runtime::Runtime::new() {
        Ok(r) => r,
        Err(e) => {
            eprintln!("winged: cannot start the runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    let bodies = world.body_count();
    let app = match runtime.block_on(async { server::in_memory(world, server::Limits::default()) })
    {
        Ok(a) => a,
        Err(e) => {
            eprintln!("winged: cannot start the world's owner: {e}");
            return ExitCode::FAILURE;
        }
    };
    let result = runtime.block_on(server::serve(
        addr,
        app,
        |bound| info!(%bound, bodies, "winged is listening; try: curl http://{bound}/v1/world"),
        shutdown_signal(),
    ));
    match result {
        Ok(()) => {
            info!("stopped");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("winged: cannot serve on {addr}: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Resolves on Ctrl-C or SIGTERM.
async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {},
        _ = term => {},
    }
    info!("shutting down: finishing requests in flight");
}

fn check() -> ExitCode {
    let mut serials = Serials::new();
    let mut failed = false;
    let mut show = |name: &str, body: Result<Body, String>| match body {
        Ok(b) => {
            let report = check_solid(&b, 1e-9);
            println!(
                "{name:<12} F={:<4} E={:<4} V={:<4} H={} volume={:<10.4} {}",
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
    let s = &mut serials;
    show(
        "MKCUBE",
        mkcube(s, 2.0, 2.0, 2.0).map_err(|e| e.to_string()),
    );
    show("MKTETRA", mktetra(s, 1.0).map_err(|e| e.to_string()));
    show(
        "cylinder",
        cylinder(s, 1.0, 2.0, 32).map_err(|e| e.to_string()),
    );
    show("sphere", sphere(s, 1.0, 32, 16).map_err(|e| e.to_string()));
    show(
        "torus",
        torus(s, 2.0, 0.5, 32, 16).map_err(|e| e.to_string()),
    );
    if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}
