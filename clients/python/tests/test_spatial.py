"""Spatial access: sphere, box, nearest and ray, each by GET and by POST."""

from __future__ import annotations

from collections.abc import Callable

import pytest

import winged
from winged.models import BodyHit, SphereAnswer

from .conftest import Server


def test_the_readme_queries(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory")
    with s.client() as client:
        made = client.create_body(winged.Box(size=[2, 2, 2]), name="block")
        assert made.id == 2
        for via in ("get", "post"):
            sphere = client.spatial_sphere([1, 1, 1], 0.5, via=via)
            assert isinstance(sphere, SphereAnswer)
            assert sphere.detail == "features" and sphere.revision == made.revision
            hit = sphere.bodies[0]
            assert isinstance(hit, BodyHit)
            assert (hit.id, hit.name, hit.inside, hit.distance) == (2, "block", True, 0.0)
            assert hit.faces is not None and sorted(f.id for f in hit.faces) == [11, 21, 27]
            assert hit.vertices is not None and [v.id for v in hit.vertices] == [13]
            assert hit.edges is not None and all(len(e.segment) == 2 for e in hit.edges)

            portions = client.spatial_sphere([3, 0, 0], 2.1, detail="portions", tolerance=0.001, via=via)
            faces = portions.bodies[0].faces
            assert faces is not None
            face = faces[0]
            assert face.id == 27 and face.portion and len(face.portion[0][0]) == 3
            assert portions.tolerance is not None

            box = client.spatial_box([0.5, 0.5, 0.5], [2, 2, 2], detail="bodies", via=via)
            assert [(b.id, b.inside) for b in box.bodies] == [(2, False)]
            assert box.bodies[0].faces is None

            near = client.spatial_nearest([4, 0.5, 0], via=via)
            assert near.hit is not None
            assert (near.hit.id, near.hit.distance, near.hit.face) == (2, 3.0, 27)
            assert near.hit.point == (1.0, 0.5, 0.0)
            assert client.spatial_nearest([4, 0.5, 0], max_distance=2.5, via=via).hit is None

            ray = client.spatial_ray([-5, 0.2, 0.3], [1, 0, 0], via=via)
            assert ray.hit is not None and ray.hit.entering and ray.hit.distance == pytest.approx(4.0)
            out = client.spatial_ray([0, 0, 0], [0, 0, 1], max_distance=10, via=via)
            assert out.hit is not None and not out.hit.entering and out.hit.normal == (0.0, 0.0, 1.0)

        with pytest.raises(winged.Unprocessable) as refused:
            client.spatial_sphere([float("nan"), 0, 0], 1)
        assert refused.value.kind == "invalid-query"
        with pytest.raises(winged.Unprocessable) as too_many:
            client.spatial_sphere([0, 0, 0], 5, max_features=1)
        assert too_many.value.kind == "too-many-features"
