"""Building typed answers from JSON, tolerantly.

A dataclass is built from a JSON object field by field, by the field's annotation:
nested dataclasses, lists and tuples of them, ``X | None``, and plain values. Members the
dataclass does not know (a newer server's additions) are ignored; members it knows but
the answer lacks take the field's default.
"""

from __future__ import annotations

import dataclasses
import functools
import types
import typing
from typing import Any, TypeVar

T = TypeVar("T")

_NOTHING = object()


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


@functools.cache
def _fields(cls: type) -> tuple[dataclasses.Field[Any], ...]:
    return tuple(f for f in dataclasses.fields(cls) if f.init)


def from_json(cls: type[T], data: Any) -> T:
    """``cls`` (a dataclass) built from the JSON object ``data``."""
    if not isinstance(data, dict):
        raise TypeError(f"{cls.__name__}: expected a JSON object, got {type(data).__name__}")
    hints = _hints(typing.cast(type, cls))
    kwargs: dict[str, Any] = {}
    for field in _fields(typing.cast(type, cls)):
        key = field.metadata.get("json", field.name)
        if key not in data:
            continue
        kwargs[field.name] = convert(hints[field.name], data[key])
    return cls(**kwargs)


def convert(tp: Any, value: Any) -> Any:
    """``value`` (decoded JSON) as the type ``tp`` says, as far as it can be."""
    if value is None:
        return None
    origin = typing.get_origin(tp)
    if origin is typing.Union or origin is types.UnionType:
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        for arg in args:
            result = _try(arg, value)
            if result is not _NOTHING:
                return result
        return value
    if tp is Any:
        return value
    if origin is list:
        item = (typing.get_args(tp) or (Any,))[0]
        return [convert(item, v) for v in value] if isinstance(value, list) else value
    if origin is tuple:
        parts = typing.get_args(tp)
        if not isinstance(value, list):
            return value
        if len(parts) == 2 and parts[1] is Ellipsis:
            return tuple(convert(parts[0], v) for v in value)
        if len(parts) == len(value):
            return tuple(convert(a, v) for a, v in zip(parts, value, strict=True))
        return tuple(value)
    if origin is dict:
        return dict(value) if isinstance(value, dict) else value
    if origin is typing.Literal:
        return value
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        return from_json(tp, value) if isinstance(value, dict) else value
    if tp is float and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


def _try(tp: Any, value: Any) -> Any:
    """``convert`` for one arm of a union: ``_NOTHING`` when the value is of another kind."""
    origin = typing.get_origin(tp)
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        return from_json(tp, value) if isinstance(value, dict) else _NOTHING
    if origin in (list, tuple):
        return convert(tp, value) if isinstance(value, list) else _NOTHING
    if tp is float:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
        return _NOTHING
    if tp in (int, str, bool):
        return value if type(value) is tp else _NOTHING
    return convert(tp, value)


def to_json(value: Any) -> Any:
    """A request value as JSON: dataclasses as objects (``None`` fields left out)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        extra_of = getattr(value, "_json_extra", None)
        extra: dict[str, Any] = extra_of() if callable(extra_of) else {}
        out: dict[str, Any] = {}
        for field in dataclasses.fields(value):
            key = field.metadata.get("json", field.name)
            v = getattr(value, field.name)
            if key in extra or (v is None and not field.metadata.get("send_none", False)):
                continue
            out[key] = to_json(v)
        out.update(extra)
        return out
    if isinstance(value, dict):
        return {k: to_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_json(v) for v in value]
    tolist = getattr(value, "tolist", None)  # numpy arrays and scalars
    if callable(tolist):
        return tolist()
    return value
