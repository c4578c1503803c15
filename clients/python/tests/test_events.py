"""Changes and the event stream, including resuming after a dropped connection."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import httpx
import pytest

import winged
from winged.events import SseParser
from winged.models import Change, Changes

from .conftest import Server

EVENTS = "/v1/world/events"


def make_boxes(client: winged.Client, n: int) -> list[int]:
    return [client.create_body(winged.Box(size=[1, 1, 1])).revision for _ in range(n)]


def take(events: Iterator[winged.Event], n: int) -> list[winged.Event]:
    return [next(events) for _ in range(n)]


def test_changes_since(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory")
    with s.client() as client:
        made = client.create_body(winged.Box(size=[1, 1, 1]))
        client.patch_body(made.id, name="watched")
        client.put_light("sun", winged.Sun(direction=[0, 0, -1]))
        changes = client.changes(0)
        assert isinstance(changes, Changes)
        assert (changes.since, changes.revision, changes.resync, changes.more) == (0, 3, False, False)
        first, second, third = changes.changes
        assert isinstance(first, Change)
        assert (first.revision, first.edit) == (1, "create_body")
        assert first.changes[0].action == "added" and first.changes[0].id == made.id
        assert second.changes[0].fields == ["name"]
        assert third.changes[0].kind == "light" and third.changes[0].name == "sun"
        page = client.changes(0, limit=2)
        assert len(page.changes) == 2 and page.more


def test_the_stream_catches_up_then_follows_live(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory")
    with s.client() as client:
        make_boxes(client, 2)
        with client.events(since=0) as stream:
            events = iter(stream)
            first = take(events, 2)
            assert [e.event for e in first] == ["change", "change"]
            assert [e.id for e in first] == ["1", "2"]
            assert first[0].change is not None and first[0].change.edit == "create_body"
            made = client.create_body(winged.Box(size=[1, 1, 1]), name="live")
            live = next(events)
            assert live.revision == made.revision == 3
            assert live.change is not None and live.change.changes[0].id == made.id
            assert stream.last_event_id == "3"


def test_without_since_the_stream_starts_now(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory")
    with s.client() as client:
        make_boxes(client, 2)
        with client.events() as stream:
            revision = client.create_body(winged.Box(size=[1, 1, 1])).revision
            assert next(iter(stream)).revision == revision == 3


def test_resume_with_last_event_id_after_closing(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory")
    with s.client() as client:
        make_boxes(client, 2)
        stream = client.events(since=0)
        seen = take(iter(stream), 2)
        stream.close()  # the connection is dropped
        last = stream.last_event_id
        assert last == "2"
        make_boxes(client, 2)  # written while nobody listens
        with client.events(last_event_id=last) as resumed:
            after = take(iter(resumed), 2)
        assert [e.revision for e in seen + after] == [1, 2, 3, 4]


class CutAfterOneEvent(httpx.SyncByteStream):
    """Passes an event stream's bytes through up to the end of its first event, then
    fails as a dropped connection does."""

    def __init__(self, inner: httpx.SyncByteStream) -> None:
        self.inner = inner

    def __iter__(self) -> Iterator[bytes]:
        buffered = b""
        for chunk in self.inner:
            buffered += chunk
            end = buffered.find(b"\n\n")
            if end >= 0:
                yield buffered[: end + 2]
                raise httpx.ReadError("connection dropped by the test")
        raise httpx.ReadError("connection dropped by the test")

    def close(self) -> None:
        self.inner.close()


class DroppingTransport(httpx.BaseTransport):
    """The real transport, except that the first event stream drops after one event."""

    def __init__(self) -> None:
        self.inner = httpx.HTTPTransport()
        self.requests: list[httpx.Request] = []
        self.dropped = False

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        self.requests.append(request)
        response = self.inner.handle_request(request)
        if request.url.path == EVENTS and not self.dropped:
            self.dropped = True
            assert isinstance(response.stream, httpx.SyncByteStream)
            return httpx.Response(
                response.status_code,
                headers=response.headers,
                stream=CutAfterOneEvent(response.stream),
                extensions=response.extensions,
            )
        return response

    def close(self) -> None:
        self.inner.close()


def test_a_dropped_connection_is_resumed_with_last_event_id(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory")
    transport = DroppingTransport()
    with s.client() as writer, winged.Client(s.url, transport=transport) as reader:
        make_boxes(writer, 3)
        with reader.events(since=0) as stream:
            events = take(iter(stream), 3)
        assert [e.revision for e in events] == [1, 2, 3]  # nothing lost, nothing repeated
        streams = [r for r in transport.requests if r.url.path == EVENTS]
        assert len(streams) == 2
        assert streams[0].url.params.get("since") == "0"
        assert streams[1].headers.get("last-event-id") == "1"
        assert stream.resume.connections == 2


def test_without_reconnect_a_drop_raises(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory")
    transport = DroppingTransport()
    with s.client() as writer, winged.Client(s.url, transport=transport) as reader:
        make_boxes(writer, 2)
        with reader.events(since=0, reconnect=False) as stream:
            events = iter(stream)
            assert next(events).revision == 1
            with pytest.raises(httpx.ReadError):
                next(events)


def test_a_stream_older_than_the_history_says_resync(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory", "--history", "2")
    with s.client() as client:
        make_boxes(client, 5)
        with client.events(since=0) as stream:
            events = list(stream)  # the resync event ends the stream
        assert [e.event for e in events] == ["resync"]
        assert events[0].resync is not None and events[0].resync["resync"] is True
        assert client.changes(0).resync


def test_the_parser_follows_the_event_stream_format() -> None:
    parser = SseParser()
    lines = [
        ": keep-alive",
        "event: change",
        "id: 7",
        'data: {"revision": 7,',
        'data: "edit": "dual", "changes": []}',
        "",
    ]
    out = [parser.feed(line) for line in lines]
    assert out[:-1] == [None] * 5
    event = out[-1]
    assert event is not None
    assert event.event == "change" and event.id == "7" and event.revision == 7
    assert event.change == Change(revision=7, edit="dual", changes=[])
    assert parser.feed("") is None  # a blank line alone dispatches nothing
    assert parser.feed("data:plain") is None
    plain = parser.feed("")
    assert plain is not None and plain.event == "message" and plain.data == "plain" and plain.id == "7"
