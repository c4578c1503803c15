"""What every group of operations shares: the answer readers and ``_run``."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Literal, TypeVar

from ._http import Answer, Call
from ._json import from_json, to_json
from .errors import ProtocolError
from .models import HiddenLines, IdsLegend, Png

T = TypeVar("T")
Vec = Sequence[float]
Via = Literal["get", "post"]


class _Unset:
    """The value of an argument that was not given (where ``None`` means something)."""

    def __repr__(self) -> str:
        return "UNSET"


UNSET: Any = _Unset()


def model_reader(cls: type[T]) -> Callable[[Answer], T]:
    """A reader of a JSON answer as the dataclass ``cls``."""

    def read(answer: Answer) -> T:
        return from_json(cls, answer.json())

    return read


def read_json(answer: Answer) -> Any:
    """The answer as decoded JSON."""
    return answer.json()


def read_bytes(answer: Answer) -> bytes:
    """The answer's body as bytes."""
    return answer.content


def read_text(answer: Answer) -> str:
    """The answer's body as UTF-8 text."""
    return answer.content.decode("utf-8")


def rendering_reader(as_array: bool) -> Callable[[Answer], Any]:
    """A reader of a drawing: PNG (or an array), hidden lines, an ids legend or SVG."""

    def read(answer: Answer) -> Any:
        media = answer.media_type
        if media == "image/png":
            png = Png(answer.content, answer.etag_revision, _depth_scale(answer), _body_ids(answer))
            return png.to_array() if as_array else png
        if media == "application/json":
            data = answer.json()
            if isinstance(data, dict) and "segments" in data:
                return from_json(HiddenLines, data)
            return from_json(IdsLegend, data)
        if media == "image/svg+xml":
            return answer.content.decode("utf-8")
        raise ProtocolError(status=answer.status, detail=f"unexpected drawing type {media!r}", headers=answer.headers)

    return read


def _depth_scale(answer: Answer) -> float | None:
    value = answer.headers.get("x-depth-scale")
    try:
        return float(value) if value is not None else None
    except ValueError:
        return None


def _body_ids(answer: Answer) -> dict[int, int] | None:
    value = answer.headers.get("x-body-ids")
    if value is None:
        return None
    ids: dict[int, int] = {}
    for pair in value.split(","):
        key, _, body = pair.strip().partition("=")
        if key.isdigit() and body.isdigit():
            ids[int(key)] = int(body)
    return ids


def drop_none(fields: dict[str, Any]) -> dict[str, Any]:
    """The fields given (not ``None`` or ``UNSET``), as JSON."""
    return {k: to_json(v) for k, v in fields.items() if v is not None and v is not UNSET}


def vec3(v: Vec) -> list[float]:
    """A vector as a JSON list of floats."""
    return [float(x) for x in v]


class Base:
    """Sends a call: :class:`winged.Client` answers its result, :class:`winged.AsyncClient`
    an awaitable of it."""

    def _run(self, call: Call[T]) -> T:  # pragma: no cover - each client overrides it
        raise NotImplementedError
