"""503 with Retry-After: retried a bounded number of times, the wait capped.

A live server with ``--max-connections 1`` answers 503 ``overloaded`` with
``Retry-After: 1`` to a new connection while its one connection holds an open event
stream; the client's retry then succeeds once the stream is closed. The rules themselves
(the count, the cap, writes that timed out) are checked against an httpx MockTransport.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable

import httpx
import pytest

import winged

from .conftest import Server

OVERLOADED = {
    "type": "urn:winged:problem:overloaded",
    "title": "Server overloaded",
    "status": 503,
    "detail": "busy",
}


def _hold_a_stream(url: str, opened: threading.Event, release: threading.Event) -> None:
    with (
        httpx.Client(base_url=url, timeout=httpx.Timeout(5.0, read=None)) as http,
        http.stream("GET", "/v1/world/events") as response,
    ):
        assert response.status_code == 200
        opened.set()
        release.wait(20)


def test_a_live_503_is_retried_after_retry_after(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory", "--max-connections", "1")
    opened, release = threading.Event(), threading.Event()
    holder = threading.Thread(target=_hold_a_stream, args=(s.url, opened, release), daemon=True)
    holder.start()
    assert opened.wait(10)
    try:
        with s.client(retries=0) as impatient, pytest.raises(winged.Unavailable) as refused:
            impatient.world()
        e = refused.value
        assert e.status == 503 and e.kind == "overloaded"
        assert e.retry_after == 1.0
        # Release the connection while the patient client waits out Retry-After.
        threading.Timer(0.3, release.set).start()
        started = time.monotonic()
        with s.client(retries=3, max_retry_wait=2.0) as patient:
            assert patient.world().revision == 0
        assert time.monotonic() - started >= 0.9
    finally:
        release.set()
        holder.join(10)


class Script:
    """A MockTransport handler answering from a list, recording the requests."""

    def __init__(self, answers: list[httpx.Response]) -> None:
        self.answers = answers
        self.requests: list[httpx.Request] = []

    def __call__(self, request: httpx.Request) -> httpx.Response:
        self.requests.append(request)
        answer = self.answers[min(len(self.requests), len(self.answers)) - 1]
        return httpx.Response(answer.status_code, headers=answer.headers, content=answer.content)


def busy(retry_after: str | None = "0", kind: str = "overloaded") -> httpx.Response:
    headers = {"content-type": "application/problem+json"}
    if retry_after is not None:
        headers["retry-after"] = retry_after
    problem = dict(OVERLOADED, type=f"urn:winged:problem:{kind}")
    return httpx.Response(503, headers=headers, content=json.dumps(problem).encode())


HEALTHY = httpx.Response(200, json={"status": "ok", "revision": 7, "added_later": [1, 2]})


def mock_client(script: Script, **kwargs: object) -> winged.Client:
    return winged.Client("http://winged.test", transport=httpx.MockTransport(script), **kwargs)  # type: ignore[arg-type]


def test_retries_until_an_answer() -> None:
    script = Script([busy(), busy(), HEALTHY])
    with winged.Client("http://winged.test", transport=httpx.MockTransport(script)) as client:
        assert client.health() == winged.models.Health(status="ok", revision=7)
    assert len(script.requests) == 3


def test_gives_up_after_the_configured_retries() -> None:
    script = Script([busy()])
    with mock_client(script, retries=2) as client, pytest.raises(winged.Unavailable) as refused:
        client.world()
    assert len(script.requests) == 3  # the first try and two retries
    assert refused.value.kind == "overloaded"
    assert refused.value.detail == "busy"


def test_default_is_three_retries_and_no_retry_without_retry_after() -> None:
    script = Script([busy()])
    with mock_client(script) as client, pytest.raises(winged.Unavailable):
        client.world()
    assert len(script.requests) == 4
    bare = Script([busy(retry_after=None)])
    with mock_client(bare) as client, pytest.raises(winged.Unavailable):
        client.world()
    assert len(bare.requests) == 1


def test_the_wait_honours_retry_after_but_is_capped(monkeypatch: pytest.MonkeyPatch) -> None:
    waits: list[float] = []
    monkeypatch.setattr(time, "sleep", waits.append)
    script = Script([busy("3600"), busy("2"), HEALTHY])
    with winged.Client("http://winged.test", max_retry_wait=5.0, transport=httpx.MockTransport(script)) as client:
        client.health()
    assert waits == [5.0, 2.0]


def test_a_write_that_timed_out_is_not_retried() -> None:
    script = Script([busy(kind="timeout")])
    with winged.Client("http://winged.test", transport=httpx.MockTransport(script)) as client:
        with pytest.raises(winged.Unavailable) as refused:
            client.create_body(winged.Box(size=[1, 1, 1]))
        assert refused.value.kind == "timeout"
        assert len(script.requests) == 1
        with pytest.raises(winged.Unavailable):
            client.world()  # a read that timed out may be asked again
        assert len(script.requests) == 5


def test_requests_carry_the_token_and_if_match() -> None:
    created = httpx.Response(201, json={"id": 2, "faces": 6, "edges": 12, "vertices": 8, "revision": 5})
    script = Script([created])
    with winged.Client("http://winged.test", "s3cret", transport=httpx.MockTransport(script)) as client:
        client.create_body(winged.Box(size=[1, 1, 1]), expected_revision=4)
    request = script.requests[0]
    assert request.headers["authorization"] == "Bearer s3cret"
    assert request.headers["if-match"] == '"4"'
    assert request.headers["content-type"] == "application/json"
    assert json.loads(request.content) == {"shape": {"type": "box", "size": [1, 1, 1]}}


async def test_the_async_client_retries_alike(monkeypatch: pytest.MonkeyPatch) -> None:
    import asyncio

    waits: list[float] = []

    async def no_sleep(seconds: float) -> None:
        waits.append(seconds)

    monkeypatch.setattr(asyncio, "sleep", no_sleep)
    script = Script([busy("1"), busy("30"), HEALTHY])
    async with winged.AsyncClient(
        "http://winged.test", max_retry_wait=4.0, transport=httpx.MockTransport(script)
    ) as client:
        assert (await client.health()).revision == 7
    assert waits == [1.0, 4.0]
