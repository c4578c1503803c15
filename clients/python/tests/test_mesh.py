"""Mesh files in (raw import and the ``mesh`` shape) and out (every export format)."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

import winged
from winged.models import Imported

CORNERS = [(x, y, z) for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0)]
# The cube's six faces as quads of corner indices, counter-clockwise seen from outside.
QUADS = [
    (0, 2, 3, 1),  # z = 0
    (4, 5, 7, 6),  # z = 1
    (0, 1, 5, 4),  # y = 0
    (2, 6, 7, 3),  # y = 1
    (0, 4, 6, 2),  # x = 0
    (1, 3, 7, 5),  # x = 1
]


def cube_triangles(scale: float = 1.0) -> list[tuple[tuple[float, float, float], ...]]:
    tris = []
    for a, b, c, d in QUADS:
        for tri in ((a, b, c), (a, c, d)):
            tris.append(tuple(tuple(scale * t for t in CORNERS[i]) for i in tri))
    return tris


def binary_stl(triangles: list[tuple[tuple[float, float, float], ...]]) -> bytes:
    out = bytearray(b"winged client test cube".ljust(80, b" "))
    out += struct.pack("<I", len(triangles))
    for tri in triangles:
        out += struct.pack("<3f", 0.0, 0.0, 0.0)
        for corner in tri:
            out += struct.pack("<3f", *corner)
        out += struct.pack("<H", 0)
    return bytes(out)


def cube_obj() -> str:
    lines = ["o cube"]
    lines += [f"v {x} {y} {z}" for x, y, z in CORNERS]
    lines += ["f " + " ".join(str(i + 1) for i in quad) for quad in QUADS]
    return "\n".join(lines) + "\n"


def test_raw_stl_import_from_a_file(client: winged.Client, tmp_path: Path) -> None:
    path = tmp_path / "gripper.stl"
    path.write_bytes(binary_stl(cube_triangles(20.0)))
    imported = client.import_mesh(path.read_bytes(), "stl", name="gripper-stl", unit="mm", color="#336699")
    assert isinstance(imported, Imported)
    assert (imported.faces, imported.edges, imported.vertices) == (6, 12, 8)
    first = imported.bodies[0]
    assert first.name == "gripper-stl"
    assert first.faces_read == 12
    assert first.volume == pytest.approx(8e-6)
    body = client.get_body(imported.id)
    assert body.color == "#336699"


def test_mesh_shape_and_export_round_trip(client: winged.Client, tmp_path: Path) -> None:
    obj = tmp_path / "cube.obj"
    obj.write_text(cube_obj())
    made = client.create_body(
        winged.Mesh(format="obj", data=obj.read_bytes()), name="obj-cube", pose={"position": [5, 0, 0]}
    )
    assert (made.faces, made.edges, made.vertices) == (6, 12, 8)
    assert made.bodies is not None and made.bodies[0].id == made.id

    exported = client.export_mesh(made.id, "obj", "body")
    assert b"\nf " in exported
    again = client.import_mesh(exported, "obj", name="obj-cube-again", merge_coplanar=False)
    assert (again.faces, again.edges, again.vertices) == (6, 12, 8)
    assert client.get_body(again.id).volume == pytest.approx(1.0)
    # The world frame applies the pose: the copy read back from it lies at x = 5..6.
    world = client.import_mesh(client.export_mesh(made.id), "obj", name="obj-cube-world")
    bounds = client.get_body(world.id).bounds
    assert bounds is not None and bounds.min[0] == pytest.approx(5.0)

    magic = {"stl": None, "ply": b"ply", "off": b"OFF", "glb": b"glTF", "3mf": b"PK"}
    for fmt, head in magic.items():
        data = client.export_mesh(made.id, fmt)
        assert data, fmt
        if head is not None:
            assert data.startswith(head), fmt
    stl = client.export_mesh(made.id, "stl")
    assert client.import_mesh(stl, "stl", name="stl-again").faces == 6

    world_glb = client.export_world()
    assert world_glb.startswith(b"glTF")


def test_an_open_surface_is_refused_with_where(client: winged.Client) -> None:
    before = client.world().revision
    with pytest.raises(winged.Unprocessable) as refused:
        client.import_mesh(binary_stl(cube_triangles()[:-1]), "stl")
    problem = refused.value
    assert problem.status == 422
    assert problem.kind == "mesh-invalid"
    assert problem.type == "urn:winged:problem:mesh-invalid"
    assert problem.extensions["defect"] == "open"
    assert "where" in problem.extensions
    assert client.world().revision == before
