"""Errors the client raises.

Every refusal of the server is an RFC 9457 problem (``application/problem+json``) with a
stable ``type`` (``urn:winged:problem:<kind>``), a ``title``, the ``status`` and a
``detail``; some carry more members (``revision`` on 412, ``defect`` and ``where`` on a
``mesh-invalid`` 422, ...). The client raises a :class:`WingedError` subclass chosen by
the status, carrying all of them.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

import httpx

__all__ = [
    "BadRequest",
    "Conflict",
    "Forbidden",
    "HeaderTooLarge",
    "InternalError",
    "NameTaken",
    "NotFound",
    "PreconditionFailed",
    "ProtocolError",
    "ServerError",
    "TooLarge",
    "Unauthorized",
    "Unavailable",
    "Unprocessable",
    "UnsupportedMediaType",
    "WingedError",
    "error_from_response",
]

_PROBLEM_PREFIX = "urn:winged:problem:"


class WingedError(Exception):
    """A request the server refused (or answered in a way the client cannot read).

    Attributes:
        status: the HTTP status code.
        type: the problem's ``type`` URI (``urn:winged:problem:<kind>``), or ``None``
            when the answer was not problem+json.
        title: the problem's short summary.
        detail: what exactly went wrong.
        extensions: every other member of the problem (``revision``, ``defect``,
            ``where``, ``format``, ...).
        headers: the answer's headers.
    """

    status: int | None
    type: str | None
    title: str | None
    detail: str | None
    extensions: dict[str, Any]
    headers: httpx.Headers

    def __init__(
        self,
        status: int | None = None,
        type: str | None = None,
        title: str | None = None,
        detail: str | None = None,
        extensions: Mapping[str, Any] | None = None,
        headers: httpx.Headers | None = None,
    ) -> None:
        self.status = status
        self.type = type
        self.title = title
        self.detail = detail
        self.extensions = dict(extensions or {})
        self.headers = headers if headers is not None else httpx.Headers()
        super().__init__(self._message())

    def _message(self) -> str:
        parts = [str(self.status) if self.status is not None else "error"]
        if self.kind:
            parts.append(self.kind)
        text = " ".join(parts)
        if self.detail:
            text += f": {self.detail}"
        elif self.title:
            text += f": {self.title}"
        return text

    @property
    def kind(self) -> str | None:
        """The problem's kind: its ``type`` without the ``urn:winged:problem:`` prefix."""
        if self.type is None:
            return None
        if self.type.startswith(_PROBLEM_PREFIX):
            return self.type[len(_PROBLEM_PREFIX) :]
        return self.type

    @property
    def revision(self) -> int | None:
        """The world's revision the problem names (a 412 carries it), if any."""
        value = self.extensions.get("revision")
        return value if isinstance(value, int) else None

    @property
    def retry_after(self) -> float | None:
        """The answer's ``Retry-After``, in seconds, if it had one in that form."""
        return parse_retry_after(self.headers.get("retry-after"))

    def __getitem__(self, key: str) -> Any:
        """A member of the problem by name (``type``, ``title``, ... or an extension)."""
        if key in ("type", "title", "status", "detail"):
            return getattr(self, key)
        return self.extensions[key]


class BadRequest(WingedError):
    """400: the request is not well-formed (bad JSON, an unknown field, a bad value)."""


class Unauthorized(WingedError):
    """401: no bearer token, a malformed one, or one the server does not know."""


class Forbidden(WingedError):
    """403: the token's role is below the one the route needs."""


class NotFound(WingedError):
    """404: an id or name that names nothing (or an unknown route)."""


class Conflict(WingedError):
    """409: a name already taken, or an operation the server's state does not allow."""


NameTaken = Conflict


class PreconditionFailed(WingedError):
    """412: the world moved past the expected revision; ``revision`` is where it is now."""


class TooLarge(WingedError):
    """413: the request, or what it would make, is over the server's limits."""


class UnsupportedMediaType(WingedError):
    """415: a request body without the content type the route reads."""


class Unprocessable(WingedError):
    """422: well-formed, but refused by the model; ``kind`` says why."""


class HeaderTooLarge(WingedError):
    """431: a request line and headers over the server's limit."""


class ServerError(WingedError):
    """5xx: the server failed (the world is unchanged)."""


class InternalError(ServerError):
    """500: the server failed internally."""


class Unavailable(ServerError):
    """503: not now (overloaded, timed out, storage failed, shutting down).

    ``retry_after`` says when to try again. The client has already retried as many
    times as it was configured to before raising this.
    """


class ProtocolError(WingedError):
    """An answer the client cannot read (not the JSON or media type the spec promises)."""


_BY_STATUS: dict[int, type[WingedError]] = {
    400: BadRequest,
    401: Unauthorized,
    403: Forbidden,
    404: NotFound,
    409: Conflict,
    412: PreconditionFailed,
    413: TooLarge,
    415: UnsupportedMediaType,
    422: Unprocessable,
    431: HeaderTooLarge,
    500: InternalError,
    503: Unavailable,
}


def error_class(status: int) -> type[WingedError]:
    """The exception class for an HTTP error status."""
    if status in _BY_STATUS:
        return _BY_STATUS[status]
    if status >= 500:
        return ServerError
    return WingedError


def parse_retry_after(value: str | None) -> float | None:
    """``Retry-After`` as seconds (the delay-seconds form; an HTTP date gives ``None``)."""
    if value is None:
        return None
    try:
        seconds = float(value.strip())
    except ValueError:
        return None
    if seconds != seconds or seconds < 0:  # NaN or negative
        return None
    return seconds


def error_from_response(status: int, headers: httpx.Headers, body: bytes) -> WingedError:
    """The exception for an error answer: its problem members when it has them."""
    cls = error_class(status)
    problem: Any = None
    if body:
        try:
            problem = json.loads(body)
        except (ValueError, UnicodeDecodeError):
            problem = None
    if not isinstance(problem, dict):
        text = body.decode("utf-8", "replace").strip() if body else None
        return cls(status=status, detail=text or None, headers=headers)
    known = ("type", "title", "status", "detail")
    extensions = {k: v for k, v in problem.items() if k not in known}
    ptype = problem.get("type")
    title = problem.get("title")
    detail = problem.get("detail")
    return cls(
        status=status,
        type=ptype if isinstance(ptype, str) else None,
        title=title if isinstance(title, str) else None,
        detail=detail if isinstance(detail, str) else None,
        extensions=extensions,
        headers=headers,
    )
