"""Fixtures for the viewer's browser tests: `winged serve` processes started from the
binary named by WINGED_BIN, and a headless Chromium driven through Selenium.

Everything is local: Debian's /usr/bin/chromium and /usr/bin/chromedriver (Selenium is
told where both are, so it never looks for or downloads a browser), servers on
ephemeral loopback ports.
"""

from __future__ import annotations

import os
import re
import secrets
import shutil
import subprocess
import tempfile
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from selenium import webdriver
from selenium.webdriver.chrome.service import Service

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
BOUND = re.compile(r"bound=(\d+\.\d+\.\d+\.\d+:\d+)")


@dataclass
class Server:
    """A running `winged serve`: its base URL, process and log lines."""

    base: str
    process: subprocess.Popen[str]
    log: list[str] = field(default_factory=list)
    read_token: str | None = None
    write_token: str | None = None

    def stop(self) -> None:
        """Stops the server (SIGTERM, then SIGKILL after 10 s)."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


def start_server(extra_env: dict[str, str] | None = None) -> Server:
    """Starts `winged serve --memory --demo --addr 127.0.0.1:0` and waits for the
    `bound=IP:PORT` line of its log (60 s at most)."""
    binary = os.environ.get("WINGED_BIN")
    if not binary:
        pytest.fail("WINGED_BIN must name the winged binary (cargo test --test viewer sets it)")
    env = dict(os.environ, RUST_LOG="info")
    env.update(extra_env or {})
    process = subprocess.Popen(
        [binary, "serve", "--memory", "--demo", "--addr", "127.0.0.1:0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        text=True,
        env=env,
    )
    lines: list[str] = []
    found: list[str] = []
    ready = threading.Event()

    def drain() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            lines.append(line.rstrip("\n"))
            if not found:
                m = BOUND.search(line)
                if m:
                    found.append(m.group(1))
                    ready.set()
        ready.set()

    threading.Thread(target=drain, daemon=True).start()
    if not ready.wait(60) or not found:
        process.kill()
        process.wait()
        pytest.fail("the server did not start listening:\n" + "\n".join(lines))
    return Server(base=f"http://{found[0]}", process=process, log=lines)


@pytest.fixture(scope="session")
def server() -> Iterator[Server]:
    """The demo world, open to everyone on loopback (no tokens)."""
    s = start_server()
    yield s
    s.stop()


@pytest.fixture(scope="session")
def token_server() -> Iterator[Server]:
    """The demo world behind tokens: a read token and a write token."""
    read, write = secrets.token_hex(16), secrets.token_hex(16)
    s = start_server({"WINGED_TOKENS": f"read:{read},write:{write}"})
    s.read_token, s.write_token = read, write
    yield s
    s.stop()


def make_driver(width: int, height: int) -> tuple[webdriver.Chrome, str]:
    """A headless Chromium of the given window size, with its console log kept, and the
    throw-away profile directory it uses."""
    for path in (CHROMIUM, CHROMEDRIVER):
        if not os.access(path, os.X_OK):
            pytest.fail(f"{path} is missing: run `bash clients/setup.sh` as root to install chromium")
    profile = tempfile.mkdtemp(prefix="winged-viewer-chromium-")
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--disable-dev-shm-usage",
        f"--user-data-dir={profile}",
        f"--window-size={width},{height}",
    ):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(executable_path=CHROMEDRIVER), options=options)
    return driver, profile


@pytest.fixture()
def browser() -> Iterator[webdriver.Chrome]:
    """A fresh headless Chromium, 1024 × 768, for one test."""
    driver, profile = make_driver(1024, 768)
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def wait_for(predicate, timeout: float = 10.0, interval: float = 0.05, what: str = "the condition"):
    """Polls `predicate` until it answers something true; fails after `timeout` s."""
    deadline = time.monotonic() + timeout
    last = None
    while time.monotonic() < deadline:
        last = predicate()
        if last:
            return last
        time.sleep(interval)
    pytest.fail(f"timed out after {timeout} s waiting for {what} (last: {last!r})")


@pytest.fixture(scope="session")
def repo_root() -> Path:
    """The repository's root directory."""
    return Path(__file__).resolve().parents[3]
