"""The asyncio client: a representative set of operations, errors and the event stream."""

from __future__ import annotations

import asyncio
from collections.abc import Callable

import numpy as np
import pytest

import winged
from winged.models import Body, HiddenLines, Png, Topology

from .conftest import Server


async def test_bodies_operators_and_reads(server: Server) -> None:
    async with winged.AsyncClient(server.url) as client:
        health = await client.health()
        assert health.status == "ok"
        seed = await client.create_body(winged.Seminal(position=[0, 0, 0]), name="async-seed")
        assert seed.face is not None and seed.vertex is not None
        spur = await client.mkev(seed.id, seed.face, seed.vertex, [1, 0, 0])
        assert spur.vertices == 2
        box = await client.create_body(winged.Box(size=[2, 2, 2]), name="async-box")
        body = await client.get_body(box.id)
        assert isinstance(body, Body) and body.volume == pytest.approx(8.0)
        topo = await client.topology(box.id)
        assert isinstance(topo, Topology) and len(topo.faces) == 6
        moved = await client.translate(box.id, [0, 0, 1], expected_revision=body.revision)
        assert moved.revision == body.revision + 1
        with pytest.raises(winged.PreconditionFailed) as stale:
            await client.translate(box.id, [0, 0, 1], expected_revision=body.revision)
        assert stale.value.revision == moved.revision
        listed = await client.list_bodies(name="async-box")
        assert [b.id for b in listed] == [box.id]
        near = await client.spatial_nearest([0, 0, 5], via="post")
        assert near.hit is not None
        mesh = await client.export_mesh(box.id, "off")
        assert mesh.startswith(b"OFF")
        killed = await client.delete_body(box.id)
        assert killed.killed == [box.id]
        with pytest.raises(winged.NotFound):
            await client.get_body(box.id)


async def test_many_requests_at_once(server: Server) -> None:
    async with winged.AsyncClient(server.url) as client:
        made = await asyncio.gather(*(client.create_body(winged.Tetrahedron(radius=0.5)) for _ in range(8)))
        assert len({m.id for m in made}) == 8
        bodies = await asyncio.gather(*(client.get_body(m.id) for m in made))
        assert all(b.euler.F == 4 for b in bodies)


async def test_appearance(demo_server: Server) -> None:
    async with winged.AsyncClient(demo_server.url) as client:
        png = await client.camera_image("eye", width=160)
        assert isinstance(png, Png) and png.startswith(b"\x89PNG")
        array = await client.appearance("eye", mode="depth", width=160, as_array=True)
        assert array.dtype == np.uint16 and array.shape == (120, 160)
        lines = await client.hidden_lines("eye")
        assert isinstance(lines, HiddenLines) and lines.segments
        cameras = await client.list_cameras()
        assert [c.name for c in cameras] == ["eye"]


async def test_async_events_resume(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory")
    async with winged.AsyncClient(s.url) as client:
        for _ in range(2):
            await client.create_body(winged.Box(size=[1, 1, 1]))
        stream = await client.events(since=0)
        seen = [await stream.__anext__() for _ in range(2)]
        await stream.aclose()
        assert stream.last_event_id == "2"
        await client.create_body(winged.Box(size=[1, 1, 1]))
        async with await client.events(last_event_id=stream.last_event_id) as resumed:
            async for event in resumed:
                seen.append(event)
                break
        assert [e.revision for e in seen] == [1, 2, 3]
        assert all(e.change is not None and e.change.edit == "create_body" for e in seen)


async def test_async_tokens(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory", "--token", "read:R-TOKEN")
    async with winged.AsyncClient(s.url, token="R-TOKEN") as reader:
        assert (await reader.world()).bodies == 0
        with pytest.raises(winged.Forbidden):
            await reader.create_body(winged.Box(size=[1, 1, 1]))
    async with winged.AsyncClient(s.url) as anonymous:
        with pytest.raises(winged.Unauthorized):
            await anonymous.metrics()
