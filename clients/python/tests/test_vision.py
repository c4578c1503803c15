"""Cameras, lights, appearance, camera solution, recognition and perception."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

import winged
from winged.models import Camera, HiddenLines, IdsLegend, NamedLight, Png

from .conftest import Server

EYE = winged.CameraSpec(
    look_at=winged.LookAt(eye=[4, -3, 3], target=[0, 0, 0]),
    intrinsics=winged.Intrinsics(width=640, height=480, fx=500, fy=500, cx=320, cy=240),
)


def test_cameras_put_get_list_delete(client: winged.Client) -> None:
    stored = client.put_camera("cam-a", EYE)
    assert stored.revision > 0
    camera = client.get_camera("cam-a")
    assert isinstance(camera, Camera)
    assert camera.intrinsics.width == 640
    assert camera.pose.position == pytest.approx((4.0, -3.0, 3.0))
    assert sum(x * x for x in camera.view_direction) == pytest.approx(1.0)
    client.put_camera(
        "cam b/ü",  # a name that needs percent-encoding
        {
            "pose": {"position": [0, 0, 5]},
            "baumgart": {"focal": 0.035, "ldx": 320, "ldy": 240, "pdx": 0.036, "pdy": 0.027},
        },
    )
    names = [c.name for c in client.list_cameras()]
    assert "cam-a" in names and "cam b/ü" in names
    assert client.get_camera("cam b/ü").intrinsics.cx == pytest.approx(160.0)
    client.delete_camera("cam b/ü")
    with pytest.raises(winged.NotFound):
        client.get_camera("cam b/ü")


def test_lights_put_get_list_delete(client: winged.Client) -> None:
    client.put_light("noon", winged.Sun(direction=[0, 0, -2], intensity=0.8))
    client.put_light("lamp", winged.PointLamp(position=[1, 2, 3]))
    noon = client.get_light("noon")
    assert isinstance(noon, NamedLight)
    assert noon.type == "sun" and noon.direction == pytest.approx((0.0, 0.0, -1.0))
    assert noon.intensity == pytest.approx(0.8)
    lamp = client.get_light("lamp")
    assert lamp.type == "point" and lamp.position == (1.0, 2.0, 3.0) and lamp.intensity == 1.0
    assert {"noon", "lamp"} <= {light.name for light in client.list_lights()}
    client.delete_light("lamp")
    with pytest.raises(winged.NotFound):
        client.get_light("lamp")
    with pytest.raises(winged.Unprocessable) as refused:
        client.put_light("dark", winged.Sun(direction=[0, 0, 0]))
    assert refused.value.kind == "invalid-light"


def test_appearance_as_png_bytes_arrays_segments_and_svg(demo: winged.Client) -> None:
    png = demo.camera_image("eye")
    assert isinstance(png, Png) and isinstance(png, bytes)
    assert png.startswith(b"\x89PNG\r\n\x1a\n")
    assert png.revision == demo.world().revision

    rgb = demo.camera_image("eye", mode="wire", width=320, as_array=True)
    assert isinstance(rgb, np.ndarray)
    assert rgb.shape == (240, 320, 3) and rgb.dtype == np.uint8

    depth_png = demo.camera_image("eye", mode="depth")
    assert depth_png.depth_scale == pytest.approx(0.001)
    depth = depth_png.to_array()
    assert depth.dtype == np.uint16 and depth.shape == (480, 640)
    assert depth.max() > 0 and depth.min() == 0

    ids_png = demo.camera_image("eye", mode="ids")
    assert ids_png.body_ids
    ids = ids_png.to_array()
    assert set(np.unique(ids)) - {0} <= set(ids_png.body_ids)

    legend = demo.camera_image("eye", mode="ids", format="json")
    assert isinstance(legend, IdsLegend)
    assert {b.id for b in legend.bodies} == set(ids_png.body_ids.values())

    lines = demo.camera_image("eye", mode="hidden", format="json")
    assert isinstance(lines, HiddenLines)
    assert lines.segments and lines.width == 640
    seg = lines.segments[0]
    assert len(seg.a) == 2 and len(seg.depth) == 2

    svg = demo.camera_image("eye", mode="hidden", format="svg")
    assert isinstance(svg, str) and "<svg" in svg

    inline = demo.appearance(
        {
            "look_at": {"eye": [2, -2, 2], "target": [0, 0, 0.75]},
            "intrinsics": {"width": 64, "height": 48, "fx": 50, "fy": 50, "cx": 32, "cy": 24},
        },
        mode="shaded",
        background="#102030",
        shadows=False,
        as_array=True,
    )
    assert inline.shape == (48, 64, 3)
    by_name = demo.hidden_lines("eye", width=320)
    assert isinstance(by_name, HiddenLines) and by_name.width == 320
    with pytest.raises(winged.Unprocessable) as refused:
        demo.camera_image("eye", mode="wire", format="json")
    assert refused.value.kind == "render-refused"


def test_camera_solution_from_correspondences_and_from_a_picture(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory")
    with s.client() as client:
        block = client.create_body(winged.Box(size=[2, 2, 2]), name="block")
        assert block.id == 2
        client.put_camera("eye", EYE)
        pixels = {
            4: (433.38, 317.78),
            5: (333.25, 249.09),
            7: (212.59, 297.89),
            9: (300.56, 393.33),
            13: (456.06, 166.67),
            15: (335.34, 118.95),
            17: (192.45, 152.5),
            19: (100, 50),
        }
        solved = client.solve_camera(
            "eye",
            [winged.Correspondence(pixel=list(p), vertex=v) for v, p in pixels.items()],
            store_as="solved",
        )
        assert solved.camera.pose.position == pytest.approx((4.0, -3.0, 3.0), abs=1e-3)
        assert solved.inliers == [0, 1, 2, 3, 4, 5, 6]
        assert solved.rms_px < 0.1
        assert solved.stored_as == "solved"
        assert len(solved.opencv.camera_matrix) == 3
        assert client.get_camera("solved").intrinsics.fx == pytest.approx(500.0)

        picture = client.camera_image("eye", mode="hidden")
        rough = {"look_at": {"eye": [4.05, -3.0, 3.0], "target": [0, 0, 0]}, "intrinsics": EYE.intrinsics}
        aligned = client.solve_camera(image=bytes(picture), initial=rough)
        assert aligned.edges is not None and aligned.edges.inlier_fraction > 0.5
        assert aligned.camera.pose.position == pytest.approx((4.0, -3.0, 3.0), abs=0.03)
        with pytest.raises(winged.Unprocessable) as refused:
            client.solve_camera("eye", [winged.Correspondence(pixel=[1, 1], vertex=4)])
        assert refused.value.kind == "too-few-correspondences"


def test_recognition_sees_the_demo_scene(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory", "--demo")
    with s.client() as client:
        picture = client.camera_image("eye")
        seen = client.recognize("eye", picture, search=None)
        assert seen.revision == picture.revision
        statuses = {b.name: b.status for b in seen.bodies}
        assert statuses.get("table") == "seen"
        table = next(b for b in seen.bodies if b.name == "table")
        assert 0 < table.score <= 1 and table.evidence.edge_points > 0
        raw = client.recognize("eye", picture, raw=True, unexplained_mask=True)
        assert {b.id for b in raw.bodies} == {b.id for b in seen.bodies}
        mask = raw.unexplained_mask_png()
        assert mask is not None and mask.startswith(b"\x89PNG")


def test_perception_carves_a_body_from_silhouettes(start_server: Callable[..., Server]) -> None:
    s = start_server("--memory")
    with s.client() as client:
        intrinsics = winged.Intrinsics(width=64, height=48, fx=60, fy=60, cx=32, cy=24)
        eyes = {"front": [3, 0, 0.5], "side": [0, 3, 0.5], "above": [0.3, 0.2, 3]}
        for name, eye in eyes.items():
            client.put_camera(
                name, winged.CameraSpec(look_at=winged.LookAt(eye=eye, target=[0, 0, 0]), intrinsics=intrinsics)
            )
        mask = np.zeros((48, 64), dtype=bool)
        mask[16:32, 24:40] = True
        views = [winged.View(camera=name, mask=mask) for name in eyes]
        perceived = client.perceive(views, name="thing", near=0.5, far=6)
        assert perceived.inserted, perceived
        made = perceived.inserted[0]
        assert made.name == "thing" and made.volume > 0 and made.views == 3
        body = client.get_body(made.id)
        assert body.provisional is True
        assert any(f.made_by is not None for f in client.topology(made.id).faces)
        more = client.perceive([winged.View(camera="front", mask=mask)], body=made.id)
        assert [b.id for b in more.carved] == [made.id] or made.id in more.removed
        with pytest.raises(winged.Unprocessable) as refused:
            client.perceive([winged.View(camera="front", mask=np.zeros((48, 64), dtype=bool))])
        assert refused.value.kind == "empty-mask"
