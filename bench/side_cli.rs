//! What the side-by-side examples (`boolean_side`, `perception_side`) share: one line
//! per panic, logs on stderr, panics caught per case, and the exit code of a command.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::process::ExitCode;

/// Prints each panic on one line and sends `RUST_LOG`-filtered logs to stderr.
pub fn start() {
    std::panic::set_hook(Box::new(|info| eprintln!("panic: {info}")));
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_writer(std::io::stderr)
        .init();
}

/// Success, or the error printed and failure.
pub fn exit(result: Result<(), String>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}

/// `f`'s result, a panic turned into an error that quotes it.
pub fn caught<T>(f: impl FnOnce() -> Result<T, String>) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f))
        .unwrap_or_else(|p| Err(format!("panicked: {}", panic_text(&*p))))
}

fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".into())
}
