"""Every operation of the spec has a client method, in both clients.

The spec is read from the live server (``GET /openapi.json``, the same document as
``proto/openapi.yaml``), so a new operation added to the spec without a client method
fails this test.
"""

from __future__ import annotations

import importlib.util
import inspect
from pathlib import Path

import pytest

import winged
from winged import OPERATIONS

from .conftest import Server

HTTP_METHODS = {"get", "put", "post", "delete", "patch", "head", "options", "trace"}


def spec_operations(server: Server) -> dict[str, tuple[str, str]]:
    with server.client() as client:
        spec = client.openapi()
    found: dict[str, tuple[str, str]] = {}
    for path, item in spec["paths"].items():
        for method, operation in item.items():
            if method in HTTP_METHODS:
                found[operation["operationId"]] = (method.upper(), path)
    return found


def test_every_operation_of_the_spec_has_a_client_method(server: Server) -> None:
    operations = spec_operations(server)
    assert len(operations) >= 45
    missing = sorted(f"{m} {p} ({op})" for op, (m, p) in operations.items() if op not in OPERATIONS)
    assert not missing, "operations of the spec without a client method: " + ", ".join(missing)
    stale = sorted(op for op in OPERATIONS if op not in operations)
    assert not stale, "client methods for operations the spec no longer has: " + ", ".join(stale)


@pytest.mark.parametrize("client_class", [winged.Client, winged.AsyncClient])
def test_the_mapped_methods_exist_and_take_their_selectors(client_class: type) -> None:
    for operation, (name, selectors) in OPERATIONS.items():
        method = getattr(client_class, name, None)
        assert callable(method), f"{client_class.__name__}.{name} ({operation}) is missing"
        assert method.__doc__, f"{client_class.__name__}.{name} has no doc string"
        parameters = inspect.signature(method).parameters
        for selector in selectors:
            assert selector in parameters, f"{name} takes no {selector!r} ({operation})"


def test_every_write_that_takes_a_precondition_takes_expected_revision(server: Server) -> None:
    with server.client() as client:
        spec = client.openapi()
    for path, item in spec["paths"].items():
        for method, operation in item.items():
            if method not in HTTP_METHODS or "412" not in operation.get("responses", {}):
                continue
            name, _ = OPERATIONS[operation["operationId"]]
            for client_class in (winged.Client, winged.AsyncClient):
                parameters = inspect.signature(getattr(client_class, name)).parameters
                assert "expected_revision" in parameters, f"{method.upper()} {path}: {name} lacks expected_revision"


def test_every_public_method_has_a_doc_string() -> None:
    for client_class in (winged.Client, winged.AsyncClient):
        for name, member in inspect.getmembers(client_class, callable):
            if not name.startswith("_"):
                assert member.__doc__, f"{client_class.__name__}.{name} has no doc string"


def test_the_async_type_stub_is_current() -> None:
    tools = Path(__file__).resolve().parent.parent / "tools" / "async_stub.py"
    spec = importlib.util.spec_from_file_location("async_stub", tools)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.STUB.read_text(encoding="utf-8") == module.render(), (
        "winged/aio.pyi is out of date: run python clients/python/tools/async_stub.py"
    )
