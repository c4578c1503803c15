//! `winged`: the world-model server's command line.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;

use std::sync::Arc;
use std::time::Duration;

use clap::{Args, Parser, Subcommand, ValueEnum};
use tracing::{error, info, warn};
use winged::model::solids::{cylinder, mkcube, mktetra, sphere, torus};
use winged::model::{Body, Serials, World, check_solid};
use winged::server::actor::{ActorConfig, InMemory};
use winged::server::auth::{Tokens, check_bind};
use winged::server::durable::{self, SnapshotPolicy};
use winged::server::metrics::Metrics;
use winged::server::{self, Limits, Options};
use winged::store::{Durability, Store, StoreOptions};

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
    Serve(Box<ServeArgs>),
    /// Validate a data directory offline (every body of the recovered world), or with
    /// no --data, build the seeds' example solids through the Euler operators and
    /// validate them.
    Check {
        /// The data directory to check (the server must not be running on it).
        #[arg(long)]
        data: Option<PathBuf>,
    },
}

#[derive(Args)]
struct ServeArgs {
    /// Address to listen on. Without tokens only loopback addresses are allowed.
    #[arg(long, default_value = "127.0.0.1:7878")]
    addr: SocketAddr,
    /// Directory holding the world: the journal (journal.db, SQLite) and snapshots.
    #[arg(long, default_value = "winged-data", conflicts_with = "memory")]
    data: PathBuf,
    /// Keep the world in memory only: nothing survives a restart.
    #[arg(long)]
    memory: bool,
    /// Start a fresh data directory (or a --memory world) with the demo scene: the
    /// hand-eye table with blocks, a camera and a sun.
    #[arg(long)]
    demo: bool,
    /// `full`: a write is acknowledged once it is on disk (fsync). `normal`: once it is
    /// safe from a crash of the server; a power loss may take the last writes.
    #[arg(long, value_enum, default_value = "full")]
    durability: DurabilityArg,
    /// Start even if the data directory recovers to an older revision than it once
    /// acknowledged (a lost write-ahead log, say): the missing writes are logged and the
    /// world resumes at the acknowledged revision, so no revision or id is issued twice.
    /// Without it such a directory is refused, naming both revisions.
    #[arg(long)]
    accept_loss: bool,
    /// Revisions between background snapshots.
    #[arg(long, default_value_t = 100_000)]
    snapshot_every: u64,
    /// A bearer token, as ROLE:TOKEN with ROLE read, write or admin (repeatable).
    /// Prefer --tokens-file or WINGED_TOKENS: flags show in the process list.
    #[arg(long = "token", value_name = "ROLE:TOKEN")]
    tokens: Vec<String>,
    /// A file of tokens, one `ROLE TOKEN` per line (# comments allowed).
    #[arg(long, env = "WINGED_TOKENS_FILE", value_name = "FILE")]
    tokens_file: Option<PathBuf>,
    /// Serve a non-loopback address without tokens: anyone who can reach it may
    /// change the world.
    #[arg(long)]
    insecure: bool,
    /// The largest request body, in MiB.
    #[arg(long, default_value_t = 64)]
    max_body_mib: usize,
    /// Seconds a request may take before it is answered 503.
    #[arg(long, default_value_t = 60)]
    request_timeout: u64,
    /// Requests handled at once; more are answered 503 with Retry-After.
    #[arg(long, default_value_t = 4096)]
    max_in_flight: usize,
    /// Requests that may wait for the world's owner; more writes are answered 503.
    #[arg(long, default_value_t = 1024)]
    queue: usize,
    /// Changes kept for GET /v1/world/changes and event-stream catch-up.
    #[arg(long, default_value_t = 100_000)]
    history: usize,
    /// The largest image appearance draws, in pixels (width × height).
    #[arg(long, default_value_t = 4096 * 4096)]
    max_render_pixels: u64,
    /// Seconds a request line and headers may take to arrive (from accept for a
    /// connection's first request, from its first byte for later ones); a connection
    /// still short of a complete head then is closed.
    #[arg(long, value_name = "SECS", default_value = "10", value_parser = seconds)]
    header_timeout: Duration,
    /// Seconds a kept-alive connection may wait with no request in flight before it is
    /// closed (an open event stream is in flight).
    #[arg(long, value_name = "SECS", default_value = "60", value_parser = seconds)]
    idle_timeout: Duration,
    /// Connections served at once, lowered to fit the open-file limit (RLIMIT_NOFILE less
    /// 64 descriptors). Past it the longest idle connection is closed, or if none is idle
    /// the new one is answered 503 with Retry-After.
    #[arg(long, value_name = "N", default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..))]
    max_connections: u32,
    /// Seconds a stop (SIGTERM, Ctrl-C) waits for connections to finish before closing
    /// them.
    #[arg(long, value_name = "SECS", default_value = "10", value_parser = seconds)]
    shutdown_deadline: Duration,
}

/// The longest timeout the flags take, a day.
const LONGEST_TIMEOUT_SECS: f64 = 86_400.0;

/// A flag's number of seconds (fractions allowed): positive, finite, at most a day.
fn seconds(text: &str) -> Result<Duration, String> {
    let secs: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a number of seconds"))?;
    if !(secs.is_finite() && secs > 0.0 && secs <= LONGEST_TIMEOUT_SECS) {
        return Err(format!(
            "{text} s: give a positive number of seconds, at most {LONGEST_TIMEOUT_SECS}"
        ));
    }
    Ok(Duration::from_secs_f64(secs))
}

#[derive(Clone, Copy, ValueEnum)]
enum DurabilityArg {
    Full,
    Normal,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Serve(args) => serve(*args),
        Command::Check { data: None } => check(),
        Command::Check { data: Some(dir) } => check_data(&dir),
    }
}

fn fail(what: impl std::fmt::Display) -> ExitCode {
    eprintln!("winged: {what}");
    ExitCode::FAILURE
}

fn serve(args: ServeArgs) -> ExitCode {
    tracing_subscriber::fmt()
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stdout()))
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()),
        )
        .init();
    let env_tokens = std::env::var("WINGED_TOKENS").ok();
    let tokens = match Tokens::from_sources(
        &args.tokens,
        env_tokens.as_deref(),
        args.tokens_file.as_deref(),
    ) {
        Ok(t) => Arc::new(t),
        Err(e) => return fail(e),
    };
    if let Err(e) = check_bind(&args.addr, &tokens, args.insecure) {
        return fail(e);
    }
    if tokens.is_empty() && !args.addr.ip().is_loopback() {
        warn!(addr = %args.addr, "serving without tokens on a non-loopback address (--insecure)");
    }
    let limits = Limits {
        max_request_bytes: args.max_body_mib.saturating_mul(1024 * 1024),
        request_timeout: Duration::from_secs(args.request_timeout.max(1)),
        max_in_flight: args.max_in_flight,
        actor: ActorConfig {
            queue: args.queue,
            ..ActorConfig::default()
        },
        history: args.history,
        max_render_pixels: args.max_render_pixels,
        header_timeout: args.header_timeout,
        idle_timeout: args.idle_timeout,
        max_connections: usize::try_from(args.max_connections).unwrap_or(usize::MAX),
        shutdown_deadline: args.shutdown_deadline,
    };
    let options = Options {
        limits,
        tokens: tokens.clone(),
        metrics: Arc::new(Metrics::new()),
    };
    let runtime = match tokio::runtime::Runtime::new() {
        Ok(r) => r,
        Err(e) => return fail(format!("cannot start the runtime: {e}")),
    };
    let demo = args.demo;
    let seed = move || -> Option<World> {
        if !demo {
            return None;
        }
        match server::demo::demo_world() {
            Ok(w) => Some(w),
            Err(e) => {
                error!(error = %e, "the demo scene failed to build; starting empty");
                None
            }
        }
    };
    let built = if args.memory {
        let world = seed().unwrap_or_default();
        info!("the world is held in memory only (--memory): nothing survives a restart");
        runtime.block_on(async { server::build(world, InMemory, Vec::new(), options) })
    } else {
        let store_options = StoreOptions {
            durability: match args.durability {
                DurabilityArg::Full => Durability::Full,
                DurabilityArg::Normal => Durability::Normal,
            },
            accept_loss: args.accept_loss,
            ..StoreOptions::default()
        };
        let policy = SnapshotPolicy {
            every: args.snapshot_every.max(1),
            keep: args.history as u64,
        };
        info!(dir = %args.data.display(), "opening the data directory");
        let opened = match durable::open(
            &args.data,
            store_options,
            policy,
            args.history,
            options.metrics.clone(),
            seed,
        ) {
            Ok(o) => o,
            Err(e) => return fail(format!("cannot open {}: {e}", args.data.display())),
        };
        runtime
            .block_on(async { server::build(opened.world, opened.journal, opened.recent, options) })
    };
    let app = match built {
        Ok(a) => a,
        Err(e) => return fail(format!("cannot start the world's owner: {e}")),
    };
    let roles = tokens.len();
    let result = runtime.block_on(server::serve(
        args.addr,
        app,
        |bound| {
            info!(%bound, tokens = roles, "winged is listening; try: curl http://{bound}/v1/world")
        },
        shutdown_signal(),
    ));
    match result {
        Ok(()) => {
            info!("stopped");
            ExitCode::SUCCESS
        }
        Err(e) => fail(format!("cannot serve on {}: {e}", args.addr)),
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

/// Recovers the world in data directory `dir` and validates every body.
fn check_data(dir: &std::path::Path) -> ExitCode {
    if !dir.exists() {
        return fail(format!("{} does not exist", dir.display()));
    }
    let mut store = match Store::open(dir, StoreOptions::default()) {
        Ok(s) => s,
        Err(e) => return fail(format!("cannot open {}: {e}", dir.display())),
    };
    let recovered = match store.recover(|_, _, _, _| {}) {
        Ok(r) => r,
        Err(e) => return fail(format!("cannot recover {}: {e}", dir.display())),
    };
    let world = recovered.world;
    // The rules every snapshot is loaded with: parts tree, range, serials, cameras.
    let verdict = winged::store::check_world(&world);
    if let Err(e) = &verdict {
        println!("world: {e}");
    }
    let mut bad = 0;
    for (id, node) in world.bodies() {
        let report = winged::model::check_topology(&node.body);
        if !report.is_ok() {
            bad += 1;
            println!("body {}: {report}", id.get());
        }
    }
    println!(
        "revision {}: {} bodies, {} invalid; snapshot {:?}, {} journal entries replayed in {:.3} s",
        world.revision(),
        world.body_count(),
        bad,
        recovered.snapshot,
        recovered.replayed,
        recovered.elapsed.as_secs_f64()
    );
    if bad == 0 && verdict.is_ok() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
