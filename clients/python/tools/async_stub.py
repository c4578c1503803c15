"""Writes ``winged/aio.pyi``, the type stub of :class:`winged.AsyncClient`.

The operations are written once (``winged/_ops_*.py``, gathered in ``winged/_api.py``); at run time the async client's
``_run`` makes each of them answer a coroutine. The stub tells type checkers so: every
operation as an ``async def`` with the blocking signature. ``tests/test_coverage.py``
checks that the stub is current.

    python clients/python/tools/async_stub.py          # rewrites winged/aio.pyi
"""

from __future__ import annotations

import builtins
import inspect
import re
import sys
from pathlib import Path
from typing import Any

PACKAGE = Path(__file__).resolve().parent.parent
STUB = PACKAGE / "winged" / "aio.pyi"

HEADER = '''"""Type stub of winged.aio, written by clients/python/tools/async_stub.py: the
operations of winged._api.Operations as coroutines. Do not edit by hand."""
'''

NAME = re.compile(r"(?<![.\w])[A-Za-z_][A-Za-z0-9_]*")


def _parameters(signature: inspect.Signature) -> str:
    out: list[str] = []
    star = False
    for p in signature.parameters.values():
        if p.kind is inspect.Parameter.KEYWORD_ONLY and not star:
            out.append("*")
            star = True
        if p.kind is inspect.Parameter.VAR_POSITIONAL:
            star = True
            text = f"*{p.name}"
        elif p.kind is inspect.Parameter.VAR_KEYWORD:
            text = f"**{p.name}"
        else:
            text = p.name
        if p.annotation is not inspect.Parameter.empty:
            text += f": {p.annotation}"
        if p.default is not inspect.Parameter.empty:
            text += " = ..."
        out.append(text)
    return ", ".join(out)


def _import(module: str, names: list[str]) -> str:
    line = f"from {module} import {', '.join(sorted(names))}"
    if len(line) <= 120:
        return line
    return f"from {module} import (\n" + "".join(f"    {n},\n" for n in sorted(names)) + ")"


def _returns(signature: inspect.Signature) -> str:
    ret = signature.return_annotation
    return "None" if ret is inspect.Signature.empty else str(ret)


def render() -> str:
    """The stub's text."""
    sys.path.insert(0, str(PACKAGE))
    import winged._api as api
    import winged.aio as aio
    import winged.models as models

    used: set[str] = set()
    lines: list[str] = []

    def note(*annotations: str) -> None:
        for text in annotations:
            used.update(NAME.findall(text))

    lines.append("class AsyncClient:")
    lines.append(f'    """{inspect.getdoc(aio.AsyncClient)}"""'.replace("\n", "\n    ").replace("\n    \n", "\n\n"))
    lines.append("    retry: RetryPolicy")
    own = aio.AsyncClient.__dict__
    for name, member in own.items():
        if name.startswith("_") and name not in ("__init__", "__aenter__", "__aexit__"):
            continue
        if isinstance(member, property):
            assert member.fget is not None
            sig = inspect.signature(member.fget)
            note(_returns(sig))
            lines += ["    @property", f"    def {name}(self) -> {_returns(sig)}: ..."]
            continue
        if not callable(member):
            continue
        sig = inspect.signature(member)
        note(_parameters(sig), _returns(sig))
        prefix = "async def" if inspect.iscoroutinefunction(member) else "def"
        lines.append(f"    {prefix} {name}({_parameters(sig)}) -> {_returns(sig)}: ...")
    for name, member in inspect.getmembers(api.Operations, inspect.isfunction):
        if name.startswith("_") or name in own:
            continue
        sig = inspect.signature(member)
        note(_parameters(sig), _returns(sig))
        doc = (inspect.getdoc(member) or "").replace("\\", "\\\\").replace("\n", "\n        ")
        lines.append(f"    async def {name}({_parameters(sig)}) -> {_returns(sig)}:")
        lines.append(f'        """{doc}"""'.replace("\n        \n", "\n\n"))

    imports: dict[str, list[str]] = {}
    sources: list[tuple[str, Any]] = [
        ("collections.abc", __import__("collections.abc", fromlist=["Sequence"])),
        ("typing", __import__("typing")),
        (".models", models),
        (".events", __import__("winged.events", fromlist=["AsyncEventStream"])),
        ("._base", __import__("winged._base", fromlist=["Vec"])),
    ]
    for word in sorted(used):
        if word in ("self", "None", "AsyncClient", "httpx") or hasattr(builtins, word):
            continue
        for module_name, module in sources:
            if hasattr(module, word):
                imports.setdefault(module_name, []).append(word)
                break
    head = [HEADER, "from __future__ import annotations", ""]
    for module_name in ("collections.abc", "typing"):
        if imports.get(module_name):
            head.append(_import(module_name, imports[module_name]))
    if "httpx" in used:
        head += ["", "import httpx"]
    head.append("")
    for module_name in ("._base", ".events", ".models"):
        if imports.get(module_name):
            head.append(_import(module_name, imports[module_name]))
        if module_name == "._base":
            head.append("from ._http import RetryPolicy")
    head += ["", '__all__ = ["AsyncClient"]', "", ""]
    return "\n".join(head + lines) + "\n"


if __name__ == "__main__":
    STUB.write_text(render(), encoding="utf-8")
    print(f"wrote {STUB}")
