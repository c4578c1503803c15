"""The shared request layer and its two thin transports (blocking and asyncio).

An operation is described once as a :class:`Call`: method, path, query, body, headers
and how to read the answer. :class:`SyncTransport` and :class:`AsyncTransport` only send
it, retrying a 503 that carries ``Retry-After`` by the same rule
(:meth:`RetryPolicy.delay`), and hand the answer to the same reader (:func:`finish`).
"""

from __future__ import annotations

import asyncio
import json
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Generic, TypeVar
from urllib.parse import quote

import httpx

from .errors import ProtocolError, error_from_response, parse_retry_after

T = TypeVar("T")

DEFAULT_URL = "http://127.0.0.1:7878"
USER_AGENT = "winged-client-python/0.1.0"


@dataclass(frozen=True)
class Answer:
    """A successful answer, read whole: status, headers and body."""

    status: int
    headers: httpx.Headers
    content: bytes

    @property
    def media_type(self) -> str:
        """The ``Content-Type`` without parameters, lower case."""
        value: str = self.headers.get("content-type", "")
        return value.split(";")[0].strip().lower()

    def json(self) -> Any:
        """The body as JSON (a :class:`ProtocolError` when it is not)."""
        try:
            return json.loads(self.content)
        except (ValueError, UnicodeDecodeError) as exc:
            raise ProtocolError(
                status=self.status,
                detail=f"the answer is not JSON ({self.media_type or 'no content type'})",
                headers=self.headers,
            ) from exc

    @property
    def etag_revision(self) -> int | None:
        """The revision in ``ETag: "<revision>"``, if the answer has one."""
        tag = self.headers.get("etag")
        if tag is None:
            return None
        tag = tag.strip()
        if tag.startswith("W/"):
            tag = tag[2:]
        tag = tag.strip('"')
        return int(tag) if tag.isdigit() else None


@dataclass
class Call(Generic[T]):
    """One request of the API and how to read its answer."""

    method: str
    path: str
    read: Callable[[Answer], T]
    params: Mapping[str, Any] | None = None
    json: Any = None
    content: bytes | None = None
    content_type: str | None = None
    headers: dict[str, str] = field(default_factory=dict)
    write: bool = False

    def query(self) -> list[tuple[str, str | int | float | bool | None]]:
        """The query string's pairs: ``None`` left out, booleans as ``true``/``false``."""
        return encode_query(self.params or {})

    def body(self) -> tuple[bytes | None, dict[str, str]]:
        """The request body and the headers that go with it."""
        headers = dict(self.headers)
        if self.json is not None:
            headers["Content-Type"] = "application/json"
            data = json.dumps(self.json, separators=(",", ":"), allow_nan=False)
            return data.encode("utf-8"), headers
        if self.content is not None:
            headers["Content-Type"] = self.content_type or "application/octet-stream"
            return self.content, headers
        return None, headers


def encode_value(value: Any) -> str:
    """One query value as text."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "NaN"
        return repr(value)
    return str(value)


def encode_query(params: Mapping[str, Any]) -> list[tuple[str, str | int | float | bool | None]]:
    """Query pairs from a mapping: ``None`` values left out."""
    return [(k, encode_value(v)) for k, v in params.items() if v is not None]


def path_segment(value: str | int) -> str:
    """A path parameter, percent-encoded (names are UTF-8, ``/`` included)."""
    return quote(str(value), safe="")


def if_match(expected_revision: int | None) -> dict[str, str]:
    """The ``If-Match`` header of a write applied only at ``expected_revision``."""
    if expected_revision is None:
        return {}
    return {"If-Match": f'"{int(expected_revision)}"'}


@dataclass(frozen=True)
class RetryPolicy:
    """How 503 answers with ``Retry-After`` are retried.

    Attributes:
        retries: the most retries of one request (0: never retry).
        max_wait: the longest wait before a retry, seconds (``Retry-After`` is capped
            at this).
        default_wait: the wait when ``Retry-After`` is not in seconds.
    """

    retries: int = 3
    max_wait: float = 10.0
    default_wait: float = 1.0

    def delay(self, call: Call[Any], status: int, headers: httpx.Headers, body: bytes, attempt: int) -> float | None:
        """Seconds to wait before retrying after this answer, or ``None``: do not retry.

        Only a 503 with ``Retry-After`` is retried, at most ``retries`` times. A write
        answered ``timeout`` is not retried: it may still have been applied.
        """
        if status != 503 or attempt >= self.retries:
            return None
        header = headers.get("retry-after")
        if header is None:
            return None
        if call.write and _problem_kind(body) == "timeout":
            return None
        seconds = parse_retry_after(header)
        if seconds is None:
            seconds = self.default_wait
        return max(0.0, min(seconds, self.max_wait))


def _problem_kind(body: bytes) -> str | None:
    try:
        problem = json.loads(body)
    except (ValueError, UnicodeDecodeError):
        return None
    kind = problem.get("type") if isinstance(problem, dict) else None
    return kind.rsplit(":", 1)[-1] if isinstance(kind, str) else None


def finish(call: Call[T], status: int, headers: httpx.Headers, content: bytes) -> T:
    """The call's result from its answer, or the :class:`~winged.WingedError` it means."""
    if status >= 400:
        raise error_from_response(status, headers, content)
    return call.read(Answer(status, headers, content))


def client_headers(token: str | None) -> dict[str, str]:
    """The headers every request carries: the user agent and the bearer token."""
    headers = {"User-Agent": USER_AGENT, "Accept": "application/json, */*;q=0.5"}
    if token:
        headers["Authorization"] = f"Bearer {token}"
    return headers


class SyncTransport:
    """Sends calls with a blocking :class:`httpx.Client`."""

    def __init__(
        self,
        url: str,
        token: str | None,
        timeout: float | httpx.Timeout | None,
        retry: RetryPolicy,
        transport: httpx.BaseTransport | None = None,
    ) -> None:
        self.url = url.rstrip("/")
        self.token = token
        self.retry = retry
        self.timeout = timeout
        self.transport = transport
        self.http = httpx.Client(
            base_url=self.url,
            headers=client_headers(token),
            timeout=timeout,
            transport=transport,
        )

    def run(self, call: Call[T]) -> T:
        """Sends ``call`` (retrying as the policy says) and reads its answer."""
        content, headers = call.body()
        attempt = 0
        while True:
            response = self.http.request(call.method, call.path, params=call.query(), content=content, headers=headers)
            delay = self.retry.delay(call, response.status_code, response.headers, response.content, attempt)
            if delay is None:
                return finish(call, response.status_code, response.headers, response.content)
            attempt += 1
            time.sleep(delay)

    def close(self) -> None:
        """Closes the connection pool."""
        self.http.close()


class AsyncTransport:
    """Sends calls with an :class:`httpx.AsyncClient`."""

    def __init__(
        self,
        url: str,
        token: str | None,
        timeout: float | httpx.Timeout | None,
        retry: RetryPolicy,
        transport: httpx.AsyncBaseTransport | None = None,
    ) -> None:
        self.url = url.rstrip("/")
        self.token = token
        self.retry = retry
        self.timeout = timeout
        self.transport = transport
        self.http = httpx.AsyncClient(
            base_url=self.url,
            headers=client_headers(token),
            timeout=timeout,
            transport=transport,
        )

    async def run(self, call: Call[T]) -> T:
        """Sends ``call`` (retrying as the policy says) and reads its answer."""
        content, headers = call.body()
        attempt = 0
        while True:
            response = await self.http.request(
                call.method, call.path, params=call.query(), content=content, headers=headers
            )
            delay = self.retry.delay(call, response.status_code, response.headers, response.content, attempt)
            if delay is None:
                return finish(call, response.status_code, response.headers, response.content)
            attempt += 1
            await asyncio.sleep(delay)

    async def close(self) -> None:
        """Closes the connection pool."""
        await self.http.aclose()
