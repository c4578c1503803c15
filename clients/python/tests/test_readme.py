"""The README's walk-through runs: every ``python`` block, in order, in one namespace,
against a fresh ``--memory`` server, and prints what its ``# `` comment lines say (each
comment line that starts a line is one line of output; ``...`` stands for anything)."""

from __future__ import annotations

import contextlib
import io
import re
from collections.abc import Callable
from pathlib import Path

import pytest

from .conftest import Server
from .test_mesh import binary_stl, cube_triangles

README = Path(__file__).resolve().parent.parent / "README.md"
BLOCK = re.compile(r"^```python\n(.*?)^```$", re.DOTALL | re.MULTILINE)


def expected_output(block: str) -> list[str]:
    return [line[2:] for line in block.splitlines() if line.startswith("# ")]


def matches(expected: str, line: str) -> bool:
    pattern = ".*".join(re.escape(part) for part in expected.split("..."))
    return re.fullmatch(pattern, line) is not None


def test_the_readme_blocks_run(
    start_server: Callable[..., Server], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    blocks = BLOCK.findall(README.read_text(encoding="utf-8"))
    assert len(blocks) >= 10
    s = start_server("--memory")
    monkeypatch.setenv("WINGED", s.url)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "gripper.stl").write_bytes(binary_stl(cube_triangles(20.0)))
    namespace: dict[str, object] = {"__name__": "readme"}
    for number, block in enumerate(blocks, 1):
        out = io.StringIO()
        try:
            with contextlib.redirect_stdout(out):
                exec(compile(block, f"README.md python block {number}", "exec"), namespace)
        except Exception as exc:
            raise AssertionError(f"README python block {number} failed:\n{block}") from exc
        printed = out.getvalue().splitlines()
        expected = expected_output(block)
        assert len(printed) == len(expected) and all(map(matches, expected, printed)), (
            f"README python block {number} printed\n" + "\n".join(printed) + "\ninstead of\n" + "\n".join(expected)
        )
