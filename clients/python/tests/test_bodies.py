"""Bodies: shapes, reads, edits, Euler operators, transforms and the other operators."""

from __future__ import annotations

import math

import pytest

import winged
from winged.models import Body, BodySummary, Created, EulerCounts, Pose, TopoFace, Topology

SQUARE = [[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]]

SHAPES = [
    (winged.Box(size=[2, 1, 0.5]), (6, 12, 8)),
    (winged.Tetrahedron(radius=1.0), (4, 6, 4)),
    (winged.Prism(polygon=SQUARE, height=1.0), (6, 12, 8)),
    (winged.Pyramid(polygon=SQUARE, height=1.0), (5, 8, 5)),
    (winged.Cylinder(radius=0.5, height=1.0, segments=8), (10, 24, 16)),
    (winged.Cone(radius=0.5, height=1.0, segments=8), (9, 16, 9)),
    (winged.Sphere(radius=1.0, segments=8, rings=4), (32, 56, 26)),
    (winged.Torus(major_radius=1.0, minor_radius=0.25, segments=8, rings=6), (48, 96, 48)),
    (
        winged.Polyhedron(
            vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
            faces=[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        ),
        (4, 6, 4),
    ),
    (winged.Seminal(position=[1, 2, 3]), (1, 0, 1)),
]


@pytest.mark.parametrize(("shape", "counts"), SHAPES, ids=[type(s).__name__ for s, _ in SHAPES])
def test_each_shape_makes_a_body_with_its_counts(
    client: winged.Client, shape: object, counts: tuple[int, int, int]
) -> None:
    made = client.create_body(shape)
    assert isinstance(made, Created)
    assert (made.faces, made.edges, made.vertices) == counts
    body = client.get_body(made.id)
    assert isinstance(body, Body)
    assert body.euler == EulerCounts(
        F=counts[0], E=counts[1], V=counts[2], H=1 if isinstance(shape, winged.Torus) else 0
    )
    if isinstance(shape, winged.Seminal):
        assert made.face is not None and made.vertex is not None
    else:
        assert made.face is None
        assert body.volume > 0


def test_a_dict_shape_and_every_create_option(client: winged.Client) -> None:
    parent = client.create_body({"type": "box", "size": [1, 1, 1]}, name="shelf-base")
    made = client.create_body(
        winged.Box(size=[0.2, 0.2, 0.2]),
        name="shelf-part",
        parent=parent.id,
        pose=Pose(position=(0.0, 0.0, 1.0)),
        color="#c08040",
    )
    body = client.get_body(made.id)
    assert body.name == "shelf-part"
    assert body.parent == parent.id
    assert body.color == "#c08040"
    assert body.pose.position == (0.0, 0.0, 1.0)
    assert body.bounds is not None and body.bounds.max == pytest.approx((0.1, 0.1, 0.1))
    assert client.get_body(parent.id).parts == [made.id]


def test_get_list_patch_delete_with_typed_answers(client: winged.Client) -> None:
    made = client.create_body(winged.Box(size=[2, 2, 2]), name="crate-a")
    listed = client.list_bodies(name="crate-a")
    assert [b.id for b in listed] == [made.id]
    assert isinstance(listed.bodies[0], BodySummary)
    assert listed.revision >= made.revision
    everything = client.list_bodies()
    assert made.id in [b.id for b in everything.bodies]
    assert made.id in [b.id for b in client.list_bodies(parent=1)]

    changed = client.patch_body(made.id, name="crate-b", pose={"position": [0, 3, 0]})
    assert changed.id == made.id and changed.revision > made.revision
    body = client.get_body(made.id)
    assert body.name == "crate-b"
    assert body.world_pose.position == (0.0, 3.0, 0.0)
    assert body.revision == changed.revision

    client.patch_body(made.id, name=None)  # None removes the name
    assert client.get_body(made.id).name is None

    killed = client.delete_body(made.id)
    assert killed.killed == [made.id]
    with pytest.raises(winged.NotFound):
        client.get_body(made.id)


def test_the_readme_cube_from_euler_operators(client: winged.Client) -> None:
    seed = client.create_body(winged.Seminal(position=[1, 1, -1]))
    b, f, v1 = seed.id, seed.face, seed.vertex
    assert f is not None and v1 is not None
    v2 = client.mkev(b, f, v1, [-1, 1, -1]).vertex
    v3 = client.mkev(b, f, v2, [-1, -1, -1]).vertex
    v4 = client.mkev(b, f, v3, [1, -1, -1]).vertex
    top = client.mkfe(b, v1, f, v4)
    assert (top.faces, top.edges, top.vertices) == (2, 4, 4)
    ring = [
        client.mkev(b, top.face, v, [x, y, 1]).vertex
        for v, (x, y) in zip([v1, v2, v3, v4], [(1, 1), (-1, 1), (-1, -1), (1, -1)], strict=True)
    ]
    last = None
    for a, c in zip(ring, ring[1:] + ring[:1], strict=True):
        last = client.euler(b, winged.Mkfe(v1=a, face=top.face, v2=c))
    assert last is not None and (last.faces, last.edges, last.vertices) == (6, 12, 8)

    body = client.get_body(b)
    assert body.volume == pytest.approx(8.0)
    assert body.area == pytest.approx(24.0)
    topo = client.topology(b)
    assert isinstance(topo, Topology)
    assert (len(topo.faces), len(topo.edges), len(topo.vertices)) == (6, 12, 8)
    edge_ids = {e.id for e in topo.edges}
    for e in topo.edges:
        assert {e.ncw, e.pcw, e.nccw, e.pccw} <= edge_ids
    for face in topo.faces:
        assert face.plane is not None and len(face.plane) == 4
        assert len(face.vertices) == 4
    assert all(len(v.position) == 3 for v in topo.vertices)

    # ESPLIT then KLEV undoes it; INVERT is its own inverse; KLFE undoes MKFE.
    split = client.esplit(b, topo.edges[0].id)
    assert split.vertices == 9
    assert client.klev(b, split.vertex).vertices == 8
    turned = client.invert(b, topo.edges[1].id)
    assert turned.edge == topo.edges[1].id
    client.invert(b, topo.edges[1].id)
    made = client.mkfe(b, topo.faces[0].vertices[0], topo.faces[0].id, topo.faces[0].vertices[2])
    assert made.faces == 7
    assert client.klfe(b, made.edge).faces == 6
    spur = client.mkev(b, topo.faces[0].id, topo.faces[0].vertices[0], [0.5, 0.5, -1])
    assert client.klve(b, spur.edge).vertices == 8
    with pytest.raises(winged.Unprocessable) as refused:
        client.klev(b, topo.vertices[0].id)  # a corner has three edges
    assert refused.value.kind == "euler-refused"
    assert client.get_body(b).euler == EulerCounts(F=6, E=12, V=8, H=0)


def test_glue(client: winged.Client) -> None:
    # Two unit cubes side by side, glued face to face: one body of twice the volume.
    left = client.create_body(winged.Box(size=[1, 1, 1]), pose={"position": [0, 0, 0]})
    right = client.create_body(winged.Box(size=[1, 1, 1]), pose={"position": [1, 0, 0]})
    lt = client.topology(left.id)
    rt = client.topology(right.id)
    plus_x = next(f.id for f in lt.faces if f.plane is not None and f.plane[0] > 0.9)
    minus_x = next(f.id for f in rt.faces if f.plane is not None and f.plane[0] < -0.9)
    glued = client.glue(left.id, plus_x, minus_x)
    assert glued.killed == [right.id]
    with pytest.raises(winged.NotFound):
        client.get_body(right.id)
    assert client.get_body(left.id).volume == pytest.approx(2.0)


def _facing_pair(client: winged.Client) -> tuple[int, int, TopoFace, TopoFace]:
    """Two unit cubes 3 m apart on x, and their faces that look at each other."""
    a = client.create_body(winged.Box(size=[1, 1, 1]))
    b = client.create_body(winged.Box(size=[1, 1, 1]), pose={"position": [3, 0, 0]})
    fa = next(f for f in client.topology(a.id).faces if f.plane is not None and f.plane[0] > 0.9)
    fb = next(f for f in client.topology(b.id).faces if f.plane is not None and f.plane[0] < -0.9)
    return a.id, b.id, fa, fb


def test_glueff_gluee_and_unglue(client: winged.Client) -> None:
    a, b, fa, fb = _facing_pair(client)
    tube = client.glueff(a, fa.id, fb.id)  # a tube of quadrilaterals joins the two cubes
    assert tube.killed == [b]
    assert tube.new_edges is not None and len(tube.new_edges) == 4
    assert (tube.faces, tube.edges, tube.vertices) == (14, 28, 16)
    assert client.get_body(a).euler == EulerCounts(F=14, E=28, V=16, H=0)

    # UNGLUE along the ring where the tube meets the first cube cuts it off again.
    ring = set(fa.vertices)
    loop = [e.id for e in client.topology(a).edges if e.nvt in ring and e.pvt in ring]
    cut = client.unglue(a, loop)
    assert cut.split_off is not None and cut.new_face is not None
    assert client.get_body(a).euler == EulerCounts(F=6, E=12, V=8, H=0)
    assert client.get_body(cut.split_off).euler == EulerCounts(F=10, E=20, V=12, H=0)

    c, d, fc, fd = _facing_pair(client)
    wasp = client.gluee(c, fc.id, fc.vertices[0], fd.id, fd.vertices[0])
    assert wasp.edge is not None and wasp.killed == [d]
    assert (wasp.faces, wasp.edges, wasp.vertices) == (11, 25, 16)


def test_transforms(client: winged.Client) -> None:
    made = client.create_body(winged.Box(size=[2, 2, 2]))
    assert client.translate(made.id, [3, 0, 0], frame="world").id == made.id
    client.rotate(made.id, [0, 0, 1], 90)
    pose = client.get_body(made.id).world_pose
    assert pose.position == pytest.approx((0.0, 3.0, 0.0), abs=1e-9)
    client.dilate(made.id, 2.0)
    assert client.get_body(made.id).volume == pytest.approx(64.0)
    client.reflect(made.id, [1, 0, 0])
    assert client.get_body(made.id).volume == pytest.approx(64.0)
    topo = client.topology(made.id)
    client.transform(made.id, winged.Translate(vector=[0, 0, 1], target=topo.vertices[0].id, frame="body"))
    moved = client.topology(made.id).vertices[0].position
    assert moved[2] == pytest.approx(topo.vertices[0].position[2] + 1)


def test_sweep_dual_evert_copy(client: winged.Client) -> None:
    made = client.create_body(winged.Box(size=[1, 1, 1]), name="sweep-me")
    top = next(f.id for f in client.topology(made.id).faces if f.plane is not None and f.plane[2] > 0.9)
    swept = client.sweep(made.id, top, "prism", distance=0.5)
    assert (swept.faces, swept.edges, swept.vertices) == (10, 20, 12)
    assert swept.face == top
    assert client.get_body(made.id).volume == pytest.approx(1.5)

    pyramid = client.create_body(winged.Box(size=[1, 1, 1]))
    cap = client.topology(pyramid.id).faces[0].id
    assert client.sweep(pyramid.id, cap, "pyramid", distance=1.0).vertices == 9

    cube = client.create_body(winged.Box(size=[1, 1, 1]))
    dual = client.dual(cube.id)
    assert (dual.faces, dual.vertices) == (8, 6)  # an octahedron

    volume = client.get_body(cube.id).volume
    client.evert(cube.id)
    assert client.get_body(cube.id).volume == pytest.approx(-volume)
    client.evert(cube.id)

    named = client.copy_body(made.id, "sweep-copy")
    unnamed = client.copy_body(made.id)
    assert client.get_body(named.id).name == "sweep-copy"
    assert client.get_body(unnamed.id).name is None
    assert (named.faces, named.edges, named.vertices) == (10, 20, 12)


def test_booleans(client: winged.Client) -> None:
    block = client.create_body(winged.Box(size=[2, 2, 2]))
    drill = client.create_body(winged.Cylinder(radius=0.5, height=4, segments=16))
    result = client.boolean(block.id, "difference", drill.id)
    assert result.id == block.id
    assert result.killed == [drill.id]
    assert result.pieces[0].id == block.id
    hole = math.pi * 0.25 * 2 * (16 / (2 * math.pi)) * math.sin(2 * math.pi / 16)
    assert result.pieces[0].volume == pytest.approx(8 - hole, rel=1e-9)
    assert all(len(s) == 3 for s in result.pieces[0].sources)
    assert client.get_body(block.id).euler.H == 1

    a = client.create_body(winged.Box(size=[2, 2, 2]))
    b = client.create_body(winged.Box(size=[2, 2, 2]), pose={"position": [1, 0, 0]})
    union = client.boolean(a.id, "union", b.id, keep_with=True)
    assert union.pieces[0].volume == pytest.approx(12.0)
    assert union.killed == []
    both = client.boolean(a.id, "intersection", b.id)  # the union with b is b's box and more
    assert both.pieces[0].volume == pytest.approx(8.0)
    assert both.killed == [b.id]
    with pytest.raises(winged.Unprocessable) as refused:
        client.boolean(a.id, "union", a.id)
    assert refused.value.kind in ("boolean-refused", "invalid-parts-tree")
