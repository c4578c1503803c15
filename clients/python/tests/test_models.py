"""Typed answers are built tolerantly; requests serialize to the spec's JSON."""

from __future__ import annotations

import httpx
import pytest

import winged
from winged._json import from_json, to_json
from winged.errors import error_from_response
from winged.models import Body, NearestAnswer, Pose

BODY = {
    "id": 2,
    "name": None,
    "parent": 1,
    "parts": [],
    "color": "#a5ca72",
    "pose": {"position": [0, 0, 0], "rotation": [0, 0, 0, 1]},
    "world_pose": {"position": [0, 0, 1], "rotation": [0, 0, 0, 1], "scale": 2},
    "euler": {"F": 6, "E": 12, "V": 8, "H": 0, "genus_note": "x"},
    "volume": 8,
    "area": 24.0,
    "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]},
    "revision": 13,
    "a_field_from_a_newer_server": {"nested": [1, 2, 3]},
}


def test_unknown_members_are_ignored_and_types_follow_the_fields() -> None:
    body = from_json(Body, BODY)
    assert body.id == 2 and body.name is None
    assert body.world_pose == Pose(position=(0.0, 0.0, 1.0), rotation=(0.0, 0.0, 0.0, 1.0))
    assert body.euler.V == 8
    assert isinstance(body.volume, float) and body.volume == 8.0
    assert body.provisional is None  # optional, absent
    assert not hasattr(body, "a_field_from_a_newer_server")


def test_a_null_hit() -> None:
    assert from_json(NearestAnswer, {"revision": 1, "hit": None}).hit is None


def test_requests_serialize_with_their_tags() -> None:
    assert to_json(winged.Box(size=(1, 2, 3))) == {"type": "box", "size": [1, 2, 3]}
    assert to_json(winged.Seminal()) == {"type": "seminal"}
    assert to_json(winged.Mkev(face=3, vertex=4)) == {"op": "mkev", "face": 3, "vertex": 4}
    assert to_json(winged.Mesh(format="obj", data=b"o x\n")) == {"type": "mesh", "format": "obj", "data": "byB4Cg=="}
    assert to_json(winged.Rotate(axis=[0, 0, 1], angle_deg=90)) == {"op": "rotate", "axis": [0, 0, 1], "angle_deg": 90}
    spec = winged.CameraSpec(
        look_at=winged.LookAt(eye=[1, 2, 3], target=[0, 0, 0]),
        intrinsics=winged.Intrinsics(width=4, height=3, fx=2, fy=2, cx=2, cy=1.5),
    )
    assert to_json(spec) == {
        "look_at": {"eye": [1, 2, 3], "target": [0, 0, 0]},
        "intrinsics": {"width": 4, "height": 3, "fx": 2, "fy": 2, "cx": 2, "cy": 1.5},
    }
    view = to_json(winged.View(camera="c0", mask=b"\x89PNG"))
    assert view == {"camera": "c0", "mask": "iVBORw=="}


def test_problem_members_and_classes() -> None:
    body = (
        b'{"type":"urn:winged:problem:mesh-invalid","title":"t","status":422,"detail":"d",'
        b'"defect":"open","where":{"object":0}}'
    )
    e = error_from_response(422, httpx.Headers(), body)
    assert isinstance(e, winged.Unprocessable)
    assert (e.type, e.title, e.status, e.detail) == ("urn:winged:problem:mesh-invalid", "t", 422, "d")
    assert e.extensions == {"defect": "open", "where": {"object": 0}}
    assert e["where"] == {"object": 0}
    plain = error_from_response(502, httpx.Headers(), b"bad gateway")
    assert isinstance(plain, winged.ServerError) and plain.type is None and plain.detail == "bad gateway"
    assert isinstance(error_from_response(500, httpx.Headers(), b"{}"), winged.InternalError)
    with pytest.raises(KeyError):
        e["missing"]
