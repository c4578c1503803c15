"""The blocking client."""

from __future__ import annotations

from typing import Any, TypeVar

import httpx

from ._api import Operations
from ._http import DEFAULT_URL, Call, RetryPolicy, SyncTransport
from .events import EventStream, Resume

T = TypeVar("T")

__all__ = ["Client"]


class Client(Operations):
    """A blocking client of a winged server.

    Args:
        url: the server's base URL.
        token: a bearer token, sent as ``Authorization: Bearer <token>``.
        timeout: seconds a request may take (an :class:`httpx.Timeout` for finer control).
        retries: how many times a 503 with ``Retry-After`` is retried (0: never).
        max_retry_wait: the longest wait before a retry, seconds (``Retry-After`` is
            capped at this).
        transport: an httpx transport to send through (tests, proxies).

    Every method raises a :class:`~winged.WingedError` subclass when the server refuses.
    Use it as a context manager, or call :meth:`close`, to release its connections.
    """

    def __init__(
        self,
        url: str = DEFAULT_URL,
        token: str | None = None,
        *,
        timeout: float | httpx.Timeout | None = 60.0,
        retries: int = 3,
        max_retry_wait: float = 10.0,
        transport: httpx.BaseTransport | None = None,
    ) -> None:
        self.retry = RetryPolicy(retries=retries, max_wait=max_retry_wait)
        self._transport = SyncTransport(url, token, timeout, self.retry, transport)

    @property
    def url(self) -> str:
        """The server's base URL."""
        return self._transport.url

    def _run(self, call: Call[T]) -> T:
        return self._transport.run(call)

    def events(
        self,
        since: int | None = None,
        *,
        last_event_id: str | int | None = None,
        reconnect: bool = True,
        max_reconnects: int = 5,
        reconnect_wait: float = 0.2,
        idle_timeout: float | None = None,
    ) -> EventStream:
        """``GET /v1/world/events``: the world's changes as they happen.

        Iterate over the answer for :class:`~winged.Event` items. Starts after revision
        ``since`` (or after ``last_event_id``); with neither, after the revision the world
        is at now. A dropped connection is resumed with ``Last-Event-ID`` (up to
        ``max_reconnects`` attempts in a row); a ``resync`` event ends the stream.
        ``idle_timeout`` bounds the wait for the next line (default: no bound).
        """
        if since is None and last_event_id is None:
            since = self.health().revision
        resume = Resume(since, last_event_id, reconnect, max_reconnects, reconnect_wait)
        return EventStream(self._transport, resume, idle_timeout)

    def close(self) -> None:
        """Closes the client's connections."""
        self._transport.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
