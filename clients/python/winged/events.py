"""The world's changes as a live stream of server-sent events (``GET /v1/world/events``).

Each ``change`` event's ``id`` is the revision it made. When the connection drops, the
stream connects again with ``Last-Event-ID`` set to the last id seen, so no change is
lost or repeated; when the server's history no longer reaches back, it sends one
``resync`` event and the stream ends (read the world whole again).

:class:`EventStream` (blocking) and :class:`AsyncEventStream` (asyncio) share the parser
(:class:`SseParser`) and the reconnection rules (:class:`Resume`).
"""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import AsyncIterator, Iterator
from typing import TYPE_CHECKING, Any

import httpx

from ._json import from_json
from .errors import error_from_response, parse_retry_after
from .models import Change, Event

if TYPE_CHECKING:
    from ._http import AsyncTransport, SyncTransport

__all__ = ["AsyncEventStream", "Event", "EventStream", "Resume", "SseParser"]

EVENTS_PATH = "/v1/world/events"


class SseParser:
    """Reads the ``text/event-stream`` format line by line (the WHATWG rules)."""

    def __init__(self) -> None:
        self._event = ""
        self._data: list[str] = []
        self._id: str | None = None

    def feed(self, line: str) -> Event | None:
        """Takes one line (without its end); answers an event when a blank line ends one."""
        if line == "":
            return self._dispatch()
        if line.startswith(":"):
            return None  # a comment (a keep-alive)
        name, colon, value = line.partition(":")
        if colon and value.startswith(" "):
            value = value[1:]
        if name == "event":
            self._event = value
        elif name == "data":
            self._data.append(value)
        elif name == "id" and "\0" not in value:
            self._id = value
        return None

    def _dispatch(self) -> Event | None:
        if not self._data and not self._event:
            return None
        kind = self._event or "message"
        data = "\n".join(self._data)
        self._event = ""
        self._data = []
        return make_event(kind, data, self._id)


def make_event(kind: str, data: str, event_id: str | None) -> Event:
    """An :class:`Event` with its data read as a :class:`Change` or a resync notice."""
    change: Change | None = None
    resync: dict[str, Any] | None = None
    try:
        payload = json.loads(data) if data else None
    except ValueError:
        payload = None
    if kind == "change" and isinstance(payload, dict):
        change = from_json(Change, payload)
    elif kind == "resync":
        resync = payload if isinstance(payload, dict) else {}
    return Event(event=kind, data=data, id=event_id, change=change, resync=resync)


class Resume:
    """Where a stream is, and whether and when to connect again after a drop.

    Attributes:
        last_event_id: the id of the last event seen (sent as ``Last-Event-ID``).
        since: the revision the stream started after, until an event is seen.
        reconnect: whether to connect again after the connection drops.
        max_reconnects: the most attempts in a row without an event in between.
        wait: seconds before an attempt (doubling up to ``max_wait``).
    """

    def __init__(
        self,
        since: int | None,
        last_event_id: str | int | None,
        reconnect: bool,
        max_reconnects: int,
        wait: float,
        max_wait: float = 10.0,
    ) -> None:
        self.since = since
        self.last_event_id = None if last_event_id is None else str(last_event_id)
        self.reconnect = reconnect
        self.max_reconnects = max_reconnects
        self.wait = wait
        self.max_wait = max_wait
        self.failures = 0
        self.connections = 0
        self.done = False

    def request(self) -> tuple[dict[str, str], dict[str, str]]:
        """The query and headers of the next connection."""
        self.connections += 1
        if self.last_event_id is not None:
            return {}, {"Last-Event-ID": self.last_event_id, "Accept": "text/event-stream"}
        params = {} if self.since is None else {"since": str(self.since)}
        return params, {"Accept": "text/event-stream"}

    def seen(self, event: Event) -> None:
        """Records an event: its id is where to resume; a ``resync`` ends the stream."""
        self.failures = 0
        if event.id is not None:
            self.last_event_id = event.id
        if event.event == "resync":
            self.done = True

    def retry_after_drop(self) -> float | None:
        """Seconds to wait before connecting again, or ``None`` to give up."""
        if not self.reconnect or self.failures >= self.max_reconnects:
            return None
        delay = min(self.wait * 2.0**self.failures, self.max_wait)
        self.failures += 1
        return delay

    def retry_after_refusal(self, status: int, headers: httpx.Headers) -> float | None:
        """Seconds to wait after a 503 with ``Retry-After``, or ``None`` to raise."""
        if status != 503 or not self.reconnect or self.failures >= self.max_reconnects:
            return None
        seconds = parse_retry_after(headers.get("retry-after"))
        if seconds is None:
            return None
        self.failures += 1
        return min(seconds, self.max_wait)


def _stream_timeout(base: float | httpx.Timeout | None, idle: float | None) -> httpx.Timeout:
    connect = base.connect if isinstance(base, httpx.Timeout) else base
    return httpx.Timeout(connect=connect, read=idle, write=connect, pool=connect)


class EventStream:
    """An iterator over the world's change events, resuming after dropped connections.

    Use it as a context manager (or call :meth:`close`) to end it::

        with client.events() as events:
            for event in events:
                print(event.revision, event.change)
    """

    def __init__(self, transport: SyncTransport, resume: Resume, idle_timeout: float | None) -> None:
        self._transport = transport
        self.resume = resume
        self._idle_timeout = idle_timeout
        self._iterator: Iterator[Event] | None = None

    @property
    def last_event_id(self) -> str | None:
        """The id of the last event seen (the revision of the last change)."""
        return self.resume.last_event_id

    def __iter__(self) -> Iterator[Event]:
        if self._iterator is None:
            self._iterator = self._events()
        return self._iterator

    def __next__(self) -> Event:
        return next(iter(self))

    def __enter__(self) -> EventStream:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Ends the stream and closes its connection."""
        self.resume.done = True
        if self._iterator is not None:
            close = getattr(self._iterator, "close", None)
            if callable(close):
                close()

    def _events(self) -> Iterator[Event]:
        http = self._transport.http
        timeout = _stream_timeout(self._transport.timeout, self._idle_timeout)
        while not self.resume.done:
            params, headers = self.resume.request()
            try:
                with http.stream("GET", EVENTS_PATH, params=params, headers=headers, timeout=timeout) as response:
                    if response.status_code >= 400:
                        body = response.read()
                        delay = self.resume.retry_after_refusal(response.status_code, response.headers)
                        if delay is None:
                            raise error_from_response(response.status_code, response.headers, body)
                        time.sleep(delay)
                        continue
                    parser = SseParser()
                    for line in response.iter_lines():
                        event = parser.feed(line)
                        if event is None:
                            continue
                        self.resume.seen(event)
                        yield event
                        if self.resume.done:
                            return
            except httpx.TransportError:
                if self.resume.done:
                    return
                delay = self.resume.retry_after_drop()
                if delay is None:
                    raise
                time.sleep(delay)
                continue
            delay = self.resume.retry_after_drop()
            if delay is None:
                return
            time.sleep(delay)


class AsyncEventStream:
    """An async iterator over the world's change events, resuming after dropped connections.

    ::

        async with client.events() as events:
            async for event in events:
                print(event.revision, event.change)
    """

    def __init__(self, transport: AsyncTransport, resume: Resume, idle_timeout: float | None) -> None:
        self._transport = transport
        self.resume = resume
        self._idle_timeout = idle_timeout
        self._iterator: AsyncIterator[Event] | None = None

    @property
    def last_event_id(self) -> str | None:
        """The id of the last event seen (the revision of the last change)."""
        return self.resume.last_event_id

    def __aiter__(self) -> AsyncIterator[Event]:
        if self._iterator is None:
            self._iterator = self._events()
        return self._iterator

    async def __anext__(self) -> Event:
        return await self.__aiter__().__anext__()

    async def __aenter__(self) -> AsyncEventStream:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()

    async def aclose(self) -> None:
        """Ends the stream and closes its connection."""
        self.resume.done = True
        if self._iterator is not None:
            aclose = getattr(self._iterator, "aclose", None)
            if callable(aclose):
                await aclose()

    async def _events(self) -> AsyncIterator[Event]:
        http = self._transport.http
        timeout = _stream_timeout(self._transport.timeout, self._idle_timeout)
        while not self.resume.done:
            params, headers = self.resume.request()
            try:
                async with http.stream("GET", EVENTS_PATH, params=params, headers=headers, timeout=timeout) as response:
                    if response.status_code >= 400:
                        body = await response.aread()
                        delay = self.resume.retry_after_refusal(response.status_code, response.headers)
                        if delay is None:
                            raise error_from_response(response.status_code, response.headers, body)
                        await asyncio.sleep(delay)
                        continue
                    parser = SseParser()
                    async for line in response.aiter_lines():
                        event = parser.feed(line)
                        if event is None:
                            continue
                        self.resume.seen(event)
                        yield event
                        if self.resume.done:
                            return
            except httpx.TransportError:
                if self.resume.done:
                    return
                delay = self.resume.retry_after_drop()
                if delay is None:
                    raise
                await asyncio.sleep(delay)
                continue
            delay = self.resume.retry_after_drop()
            if delay is None:
                return
            await asyncio.sleep(delay)
