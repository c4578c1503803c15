"""Live `winged serve` processes for the tests.

The binary is ``$WINGED_BIN`` (``cargo test`` sets it to the one it built). Each server
listens on ``127.0.0.1:0``; its log line ``bound=IP:PORT`` gives the port.
"""

from __future__ import annotations

import os
import re
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

import winged

BOUND = re.compile(r"bound=(\d+\.\d+\.\d+\.\d+:\d+)")
START_SECONDS = 30.0


def winged_bin() -> str:
    """The server binary, from ``WINGED_BIN``; fails the test run clearly when unset."""
    path = os.environ.get("WINGED_BIN")
    if not path:
        pytest.fail(
            "WINGED_BIN is not set: point it at the winged binary "
            "(cargo build; WINGED_BIN=target/debug/winged pytest clients/python/tests)",
            pytrace=False,
        )
    if not Path(path).is_file():
        pytest.fail(f"WINGED_BIN={path} is not a file", pytrace=False)
    return path


class Server:
    """A running ``winged serve`` with its URL and log; :meth:`stop` ends it."""

    def __init__(self, *args: str) -> None:
        self.args = list(args)
        env = dict(os.environ)
        env.setdefault("RUST_LOG", "warn,winged=info")
        self.process = subprocess.Popen(
            [winged_bin(), "serve", "--addr", "127.0.0.1:0", *args],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            env=env,
        )
        self.log: list[str] = []
        self._bound = threading.Event()
        self.address = ""
        self._reader = threading.Thread(target=self._read_log, daemon=True)
        self._reader.start()
        if not self._bound.wait(START_SECONDS) or not self.address:
            self.stop()
            pytest.fail("winged serve did not start:\n" + "".join(self.log), pytrace=False)
        self.url = f"http://{self.address}"

    def _read_log(self) -> None:
        assert self.process.stdout is not None
        for raw in self.process.stdout:
            line = raw.decode("utf-8", "replace")
            self.log.append(line)
            if not self.address:
                found = BOUND.search(line)
                if found:
                    self.address = found.group(1)
                    self._bound.set()
        self._bound.set()

    def client(self, token: str | None = None, **kwargs: object) -> winged.Client:
        """A blocking client of this server."""
        return winged.Client(self.url, token, **kwargs)  # type: ignore[arg-type]

    def stop(self) -> None:
        """Stops the server (SIGTERM, then SIGKILL if it lingers)."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=15)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout=15)


@pytest.fixture(scope="session")
def server() -> Iterator[Server]:
    """One ``--memory`` server shared by the tests that make their own bodies."""
    s = Server("--memory")
    yield s
    s.stop()


@pytest.fixture(scope="session")
def demo_server() -> Iterator[Server]:
    """One ``--memory --demo`` server (the hand-eye table, camera ``eye``, light ``sun``)."""
    s = Server("--memory", "--demo")
    yield s
    s.stop()


@pytest.fixture
def start_server() -> Iterator[Callable[..., Server]]:
    """Starts servers of the test's own (a fresh world, other flags); stops them after."""
    started: list[Server] = []

    def start(*args: str) -> Server:
        s = Server(*args)
        started.append(s)
        return s

    yield start
    for s in started:
        s.stop()


@pytest.fixture
def client(server: Server) -> Iterator[winged.Client]:
    """A blocking client of the shared ``--memory`` server."""
    with server.client() as c:
        yield c


@pytest.fixture
def demo(demo_server: Server) -> Iterator[winged.Client]:
    """A blocking client of the shared demo server."""
    with demo_server.client() as c:
        yield c


def wait_until(predicate: Callable[[], bool], seconds: float = 10.0) -> bool:
    """Polls ``predicate`` until it holds or ``seconds`` pass."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.02)
    return predicate()
