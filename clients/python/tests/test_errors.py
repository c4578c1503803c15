"""Refusals as WingedError subclasses carrying the problem's members; tokens; service routes."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

import winged

from .conftest import Server
from .test_mesh import binary_stl, cube_triangles


def test_not_found_carries_the_problem(client: winged.Client) -> None:
    with pytest.raises(winged.NotFound) as caught:
        client.get_body(999999999)
    e = caught.value
    assert isinstance(e, winged.WingedError)
    assert e.status == 404
    assert e.type == "urn:winged:problem:not-found"
    assert e.kind == "not-found"
    assert e.title == "Not found"
    assert e.detail == "no body has id 999999999"
    assert e["detail"] == e.detail
    assert "999999999" in str(e)


def test_unprocessable_and_bad_request(client: winged.Client) -> None:
    box = client.create_body(winged.Box(size=[2, 2, 2]))
    corner = client.topology(box.id).vertices[0].id
    before = client.world().revision
    with pytest.raises(winged.Unprocessable) as refused:
        client.klev(box.id, corner)
    assert refused.value.status == 422
    assert refused.value.type == "urn:winged:problem:euler-refused"
    assert "three edges" in (refused.value.detail or "") or "3 edges" in (refused.value.detail or "")
    assert client.world().revision == before

    with pytest.raises(winged.BadRequest) as bad:
        client.create_body({"type": "box", "size": [2, 2, 2], "colour": "red"})  # an unknown field
    assert bad.value.status == 400 and bad.value.kind == "bad-request"
    with pytest.raises(winged.BadRequest):
        client.list_bodies(name=" padded ")
    with pytest.raises(winged.Unprocessable) as bad_name:
        client.create_body(winged.Box(size=[1, 1, 1]), name=" padded ")
    assert bad_name.value.kind == "invalid-name"


def test_name_taken_is_a_conflict(client: winged.Client) -> None:
    client.create_body(winged.Box(size=[1, 1, 1]), name="unique-name")
    with pytest.raises(winged.Conflict) as taken:
        client.create_body(winged.Box(size=[1, 1, 1]), name="unique-name")
    assert taken.value.kind == "name-taken"
    assert winged.NameTaken is winged.Conflict


def test_expected_revision_preconditions(client: winged.Client) -> None:
    tiny = {
        "pose": {"position": [0, 0, 5]},
        "intrinsics": {"width": 4, "height": 4, "fx": 4, "fy": 4, "cx": 2, "cy": 2},
    }
    client.put_camera("c", tiny)
    client.put_light("l", winged.Sun(direction=[0, 0, -1]))
    made = client.create_body(winged.Box(size=[1, 1, 1]))
    at = made.revision
    moved = client.patch_body(made.id, pose={"position": [1, 0, 0]}, expected_revision=at)
    assert moved.revision == at + 1
    with pytest.raises(winged.PreconditionFailed) as stale:
        client.patch_body(made.id, pose={"position": [2, 0, 0]}, expected_revision=at)
    e = stale.value
    assert e.status == 412 and e.kind == "revision-moved"
    assert e.revision == client.world().revision
    assert e.extensions["revision"] == e.revision
    assert client.get_body(made.id).pose.position == (1.0, 0.0, 0.0)

    now = client.world().revision
    stale_writes = [
        lambda: client.create_body(winged.Box(size=[1, 1, 1]), expected_revision=at),
        lambda: client.import_mesh(binary_stl(cube_triangles()), "stl", expected_revision=at),
        lambda: client.delete_body(made.id, expected_revision=at),
        lambda: client.translate(made.id, [1, 0, 0], expected_revision=at),
        lambda: client.evert(made.id, expected_revision=at),
        lambda: client.dual(made.id, expected_revision=at),
        lambda: client.copy_body(made.id, expected_revision=at),
        lambda: client.put_light("l", winged.Sun(direction=[0, 0, -1]), expected_revision=at),
        lambda: client.mkev(made.id, 1, 1, expected_revision=at),
        lambda: client.sweep(made.id, 1, expected_revision=at),
        lambda: client.boolean(made.id, "union", made.id, expected_revision=at),
        lambda: client.delete_light("l", expected_revision=at),
        lambda: client.delete_camera("c", expected_revision=at),
        lambda: client.put_camera("c", tiny, expected_revision=at),
    ]
    for write in stale_writes:
        with pytest.raises(winged.PreconditionFailed):
            write()
    assert client.world().revision == now
    ok = client.create_body(winged.Box(size=[1, 1, 1]), expected_revision=now)
    assert ok.revision == now + 1


def test_expected_revision_on_perception(client: winged.Client) -> None:
    tiny = {
        "pose": {"position": [0, 0, 5]},
        "intrinsics": {"width": 4, "height": 4, "fx": 4, "fy": 4, "cx": 2, "cy": 2},
    }
    at = client.put_camera("perceiver", tiny).revision
    client.put_light("moves-the-world", winged.Sun(direction=[0, 0, -1]))
    now = client.world().revision
    with pytest.raises(winged.PreconditionFailed) as stale:
        client.perceive([winged.View(camera="perceiver", mask=np.ones((4, 4), dtype=bool))], expected_revision=at)
    assert stale.value.revision == now
    assert client.world().revision == now


def test_service_routes(client: winged.Client) -> None:
    health = client.health()
    assert health.status == "ok"
    ready = client.ready()
    assert ready.status == "ready" and ready.queue >= 0
    metrics = client.metrics()
    assert "winged_http_requests_total" in metrics
    spec = client.openapi()
    assert spec["openapi"].startswith("3.1")
    with pytest.raises(winged.Conflict) as in_memory:
        client.write_snapshot()
    assert in_memory.value.kind == "in-memory"


def test_snapshot_on_a_data_directory(start_server: Callable[..., Server], tmp_path: object) -> None:
    s = start_server("--data", str(tmp_path), "--durability", "normal")
    with s.client() as client:
        client.create_body(winged.Box(size=[1, 1, 1]))
        checkpoint = client.write_snapshot()
        assert checkpoint.revision == 1 and checkpoint.bytes > 0 and checkpoint.path


def test_tokens_read_and_write_roles(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory", "--token", "read:READ-SECRET", "--token", "write:WRITE-SECRET")
    with s.client() as anonymous:
        assert anonymous.health().status == "ok"  # open
        assert "paths" in anonymous.openapi()
        with pytest.raises(winged.Unauthorized) as no_token:
            anonymous.world()
        assert no_token.value.status == 401 and no_token.value.kind == "unauthorized"
        assert no_token.value.headers.get("www-authenticate", "").startswith("Bearer")
    with s.client("not-a-token") as unknown, pytest.raises(winged.Unauthorized):
        unknown.world()
    with s.client("READ-SECRET") as reader:
        assert reader.world().bodies == 0
        assert reader.list_bodies().bodies == []
        with pytest.raises(winged.Forbidden) as refused:
            reader.create_body(winged.Box(size=[1, 1, 1]))
        assert refused.value.status == 403 and refused.value.kind == "forbidden"
    with s.client("WRITE-SECRET") as writer:
        made = writer.create_body(winged.Box(size=[1, 1, 1]))
        assert writer.get_body(made.id).euler.F == 6
        with pytest.raises(winged.Forbidden):
            writer.write_snapshot()  # the admin role
