//! The real `winged` binary as a child process, for the crash, overload and start-up
//! tests.

#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// A running `winged serve`.
pub struct Server {
    pub child: Child,
    pub base: String,
    /// Log lines after the one that gave the address (kept so the pipe never fills).
    pub log: mpsc::Receiver<String>,
}

impl Server {
    /// Starts `winged serve --addr 127.0.0.1:0 ARGS...` and waits until it listens.
    ///
    /// Panics with the server's output if it exits or does not listen within 60 s.
    pub fn start(args: &[&str]) -> Server {
        Self::start_with_env(args, &[])
    }

    /// As [`Server::start`], with extra environment variables.
    pub fn start_with_env(args: &[&str], env: &[(&str, &str)]) -> Server {
        Self::start_with(args, |cmd| {
            for (k, v) in env {
                cmd.env(k, v);
            }
        })
    }

    /// As [`Server::start`], with the command adjusted by `configure` before it runs.
    pub fn start_with(args: &[&str], configure: impl FnOnce(&mut Command)) -> Server {
        Self::try_start_with(args, configure)
            .unwrap_or_else(|seen| panic!("the server did not start listening:\n{seen}"))
    }

    /// As [`Server::start`]; `Err` with the server's output when it exits (or does not
    /// listen within 60 s) instead.
    pub fn try_start(args: &[&str]) -> Result<Server, String> {
        Self::try_start_with(args, |_| {})
    }

    fn try_start_with(
        args: &[&str],
        configure: impl FnOnce(&mut Command),
    ) -> Result<Server, String> {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_winged"));
        cmd.arg("serve")
            .arg("--addr")
            .arg("127.0.0.1:0")
            .args(args)
            .env("RUST_LOG", "info")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        configure(&mut cmd);
        let mut child = cmd.spawn().expect("the winged binary starts");
        let stdout = child.stdout.take().expect("stdout");
        let stderr = child.stderr.take().expect("stderr");
        let (tx, rx) = mpsc::channel::<String>();
        let tx2 = tx.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if tx2.send(line).is_err() {
                    break;
                }
            }
        });
        // Owned by a guard from here on: a panic below kills and reaps the child.
        let mut server = Server {
            child,
            base: String::new(),
            log: rx,
        };
        let mut seen = Vec::new();
        loop {
            match server.log.recv_timeout(Duration::from_secs(60)) {
                Ok(line) => {
                    if let Some(addr) = line
                        .split_whitespace()
                        .find_map(|w| w.strip_prefix("bound="))
                    {
                        server.base = format!("http://{addr}");
                        return Ok(server);
                    }
                    seen.push(line);
                }
                // Both output pipes closed (the server exited), or 60 s of silence.
                Err(_) => {
                    let _ = server.child.kill();
                    let status = server.child.wait().ok();
                    seen.push(format!("(exit: {status:?})"));
                    return Err(seen.join("\n"));
                }
            }
        }
    }

    /// The server's process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// SIGKILL: no chance to flush or clean up.
    pub fn kill(mut self) {
        self.child.kill().expect("the server can be killed");
        let _ = self.child.wait();
    }

    /// SIGTERM and wait for a graceful exit; its exit status.
    pub fn stop(mut self) -> std::process::ExitStatus {
        let pid = self.child.id().to_string();
        let _ = Command::new("kill").args(["-TERM", &pid]).status();
        self.child.wait().expect("the server exits")
    }

    /// Sends SIGTERM and waits at most `within` for the process to exit; its exit status,
    /// or `None` if it is still running then.
    pub fn terminate_within(&mut self, within: Duration) -> Option<std::process::ExitStatus> {
        let pid = self.child.id().to_string();
        let _ = Command::new("kill").args(["-TERM", &pid]).status();
        let until = std::time::Instant::now() + within;
        loop {
            if let Ok(Some(status)) = self.child.try_wait() {
                return Some(status);
            }
            if std::time::Instant::now() >= until {
                return None;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// The next log line containing `text`, waiting at most `within`; `None` if none came.
    pub fn log_line(&self, text: &str, within: Duration) -> Option<String> {
        let until = std::time::Instant::now() + within;
        loop {
            let left = until.checked_duration_since(std::time::Instant::now())?;
            match self.log.recv_timeout(left) {
                Ok(line) if line.contains(text) => return Some(line),
                Ok(_) => {}
                Err(_) => return None,
            }
        }
    }

    /// A kilobyte figure from /proc/PID/status (`VmRSS`, `VmHWM`).
    pub fn memory_kib(&self, field: &str) -> Option<u64> {
        memory_kib_of(self.pid(), field)
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A kilobyte figure from /proc/`pid`/status (`VmRSS`, `VmHWM`), if the process is there.
pub fn memory_kib_of(pid: u32, field: &str) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    status
        .lines()
        .find(|l| l.starts_with(field))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|n| n.parse().ok())
}

/// Runs `winged ARGS...` to completion: its exit status and its output.
pub fn run(args: &[&str]) -> (std::process::ExitStatus, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_winged"))
        .args(args)
        .output()
        .expect("the winged binary runs");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status, text)
}

/// Checks a data directory offline with `winged check --data`.
pub fn check_data(dir: &Path) -> String {
    let (status, text) = run(&["check", "--data", &dir.display().to_string()]);
    assert!(status.success(), "winged check --data failed:\n{text}");
    text
}

/// An HTTP agent that reports statuses instead of failing on them.
pub fn agent(timeout: Duration) -> ureq::Agent {
    ureq::Agent::config_builder()
        .http_status_as_error(false)
        .timeout_global(Some(timeout))
        .build()
        .into()
}
