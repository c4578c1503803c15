"""The asyncio client: the same operations as :class:`winged.Client`, as coroutines."""

from __future__ import annotations

from collections.abc import Awaitable
from typing import Any, TypeVar

import httpx

from ._api import Operations
from ._http import DEFAULT_URL, AsyncTransport, Call, RetryPolicy
from .events import AsyncEventStream, Resume

T = TypeVar("T")

__all__ = ["AsyncClient"]


class AsyncClient(Operations):
    """An asyncio client of a winged server.

    It has every method of :class:`winged.Client`, with the same arguments; each
    answers an awaitable of what the blocking one answers::

        async with winged.AsyncClient(url) as client:
            body = await client.get_body(2)

    Args are those of :class:`winged.Client` (``transport`` an async httpx transport).
    """

    def __init__(
        self,
        url: str = DEFAULT_URL,
        token: str | None = None,
        *,
        timeout: float | httpx.Timeout | None = 60.0,
        retries: int = 3,
        max_retry_wait: float = 10.0,
        transport: httpx.AsyncBaseTransport | None = None,
    ) -> None:
        self.retry = RetryPolicy(retries=retries, max_wait=max_retry_wait)
        self._transport = AsyncTransport(url, token, timeout, self.retry, transport)

    @property
    def url(self) -> str:
        """The server's base URL."""
        return self._transport.url

    def _run(self, call: Call[T]) -> Awaitable[T]:  # type: ignore[override]
        return self._transport.run(call)

    async def events(
        self,
        since: int | None = None,
        *,
        last_event_id: str | int | None = None,
        reconnect: bool = True,
        max_reconnects: int = 5,
        reconnect_wait: float = 0.2,
        idle_timeout: float | None = None,
    ) -> AsyncEventStream:
        """``GET /v1/world/events``: the world's changes as they happen (``async for``).

        The arguments are those of :meth:`winged.Client.events`.
        """
        if since is None and last_event_id is None:
            since = (await self.health()).revision
        resume = Resume(since, last_event_id, reconnect, max_reconnects, reconnect_wait)
        return AsyncEventStream(self._transport, resume, idle_timeout)

    async def close(self) -> None:
        """Closes the client's connections."""
        await self._transport.close()

    async def __aenter__(self) -> AsyncClient:
        return self

    async def __aexit__(self, *exc: Any) -> None:
        await self.close()
