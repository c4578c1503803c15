"""Cameras, lights, appearance, camera solution, recognition and perception."""

from __future__ import annotations

import base64
from collections.abc import Sequence
from typing import Any

from ._base import UNSET, Base, drop_none, model_reader, rendering_reader
from ._http import Call, if_match, path_segment
from ._json import to_json
from .models import (
    Camera,
    CameraList,
    CameraSolution,
    HiddenLines,
    LightList,
    NamedLight,
    Perception,
    Recognition,
    RevisionOnly,
)
from .requests import encode_image


class VisionOperations(Base):
    """Cameras, lights, appearance, camera solution, recognition and perception."""

    # ----- the named registers: cameras and lights alike ---------------------------------

    def _put_named(self, register: str, name: str, value: Any, expected_revision: int | None) -> RevisionOnly:
        """``PUT /v1/{register}/{name}``: store ``value`` under ``name``."""
        return self._run(
            Call(
                "PUT",
                f"/v1/{register}/{path_segment(name)}",
                model_reader(RevisionOnly),
                json=to_json(value),
                headers=if_match(expected_revision),
                write=True,
            )
        )

    def _delete_named(self, register: str, name: str, expected_revision: int | None) -> RevisionOnly:
        """``DELETE /v1/{register}/{name}``: remove what is stored under ``name``."""
        return self._run(
            Call(
                "DELETE",
                f"/v1/{register}/{path_segment(name)}",
                model_reader(RevisionOnly),
                headers=if_match(expected_revision),
                write=True,
            )
        )

    # ----- cameras ---------------------------------------------------------------------

    def list_cameras(self) -> CameraList:
        """``GET /v1/cameras``: every camera, in name order."""
        return self._run(Call("GET", "/v1/cameras", model_reader(CameraList)))

    def get_camera(self, name: str) -> Camera:
        """``GET /v1/cameras/{name}``: one camera."""
        return self._run(Call("GET", f"/v1/cameras/{path_segment(name)}", model_reader(Camera)))

    def put_camera(self, name: str, camera: Any, *, expected_revision: int | None = None) -> RevisionOnly:
        """``PUT /v1/cameras/{name}``: store a camera (a :class:`~winged.CameraSpec` or dict)."""
        return self._put_named("cameras", name, camera, expected_revision)

    def delete_camera(self, name: str, *, expected_revision: int | None = None) -> RevisionOnly:
        """``DELETE /v1/cameras/{name}``: remove a camera."""
        return self._delete_named("cameras", name, expected_revision)

    # ----- appearance ------------------------------------------------------------------

    def camera_image(
        self,
        name: str,
        *,
        mode: str | None = None,
        format: str | None = None,
        width: int | None = None,
        height: int | None = None,
        background: str | None = None,
        shadows: bool | None = None,
        near: float | None = None,
        depth_scale: float | None = None,
        as_array: bool = False,
    ) -> Any:
        """``GET /v1/cameras/{name}/image``: what the world looks like from a stored camera.

        ``mode`` is ``shaded`` (default), ``wire``, ``hidden``, ``depth`` or ``ids``. The
        answer is a :class:`~winged.models.Png` (the PNG's bytes, with ``revision``,
        ``depth_scale`` and ``body_ids``), a numpy array with ``as_array=True`` (``uint16``
        for depth and ids), :class:`~winged.models.HiddenLines` (the visible segments) for
        ``mode="hidden", format="json"``, :class:`~winged.models.IdsLegend` for
        ``mode="ids", format="json"``, or the SVG text for ``format="svg"``.
        """
        params = {
            "mode": mode,
            "format": format,
            "width": width,
            "height": height,
            "background": background,
            "shadows": shadows,
            "near": near,
            "depth_scale": depth_scale,
        }
        return self._run(
            Call("GET", f"/v1/cameras/{path_segment(name)}/image", rendering_reader(as_array), params=params)
        )

    def hidden_lines(self, camera: Any, *, width: int | None = None, height: int | None = None) -> HiddenLines:
        """The exact hidden-line drawing from ``camera`` (a name or a camera) as segments."""
        return self.appearance(camera, mode="hidden", format="json", width=width, height=height)  # type: ignore[no-any-return]

    def appearance(
        self,
        camera: Any,
        *,
        mode: str | None = None,
        format: str | None = None,
        width: int | None = None,
        height: int | None = None,
        background: str | None = None,
        shadows: bool | None = None,
        near: float | None = None,
        depth_scale: float | None = None,
        as_array: bool = False,
    ) -> Any:
        """``POST /v1/appearance``: the same drawing as :meth:`camera_image`, from a stored
        camera's name or a camera given inline (:class:`~winged.CameraSpec` or dict)."""
        body = drop_none(
            {
                "camera": camera,
                "mode": mode,
                "format": format,
                "width": width,
                "height": height,
                "background": background,
                "shadows": shadows,
                "near": near,
                "depth_scale": depth_scale,
            }
        )
        return self._run(Call("POST", "/v1/appearance", rendering_reader(as_array), json=body))

    # ----- camera solution -------------------------------------------------------------

    def solve_camera(
        self,
        intrinsics: Any = None,
        correspondences: Sequence[Any] | None = None,
        *,
        image: Any = None,
        initial: Any = None,
        store_as: str | None = None,
        threshold_px: float | None = None,
        confidence: float | None = None,
        max_iterations: int | None = None,
        min_inliers: int | None = None,
        seed: int | None = None,
        solve_focal: bool | None = None,
    ) -> CameraSolution:
        """``POST /v1/camera-solution``: the camera that sees given points at given pixels.

        From correspondences: ``intrinsics`` (an :class:`~winged.Intrinsics`, or a stored
        camera's name) and ``correspondences`` (:class:`~winged.Correspondence` items,
        each a pixel and a model ``vertex`` or a world ``point``). From a picture:
        ``image`` (PNG bytes or an array) and ``initial`` (the rough camera, a name or a
        camera). ``store_as`` stores the solved camera (the write role).
        """
        if image is not None:
            if correspondences is not None or initial is None:
                raise ValueError("a solve from a picture takes image and initial, and no correspondences")
            body = drop_none({"image": encode_image(image), "initial": initial, "store_as": store_as})
        else:
            if intrinsics is None or correspondences is None:
                raise ValueError("a solve takes intrinsics and correspondences, or image and initial")
            body = drop_none(
                {
                    "intrinsics": intrinsics,
                    "correspondences": list(correspondences),
                    "store_as": store_as,
                    "threshold_px": threshold_px,
                    "confidence": confidence,
                    "max_iterations": max_iterations,
                    "min_inliers": min_inliers,
                    "seed": seed,
                    "solve_focal": solve_focal,
                }
            )
        return self._run(
            Call("POST", "/v1/camera-solution", model_reader(CameraSolution), json=body, write=store_as is not None)
        )

    # ----- recognition and perception --------------------------------------------------

    def recognize(
        self,
        camera: Any,
        image: Any,
        *,
        depth: Any = None,
        depth_scale: float | None = None,
        refine_camera: bool | None = None,
        search: Any = UNSET,
        unexplained_mask: bool | None = None,
        update: bool | None = None,
        raw: bool = False,
        expected_revision: int | None = None,
    ) -> Recognition:
        """``POST /v1/recognition``: which modeled bodies the picture ``image`` shows.

        ``camera`` took it (a stored camera's name or a camera); ``image`` is PNG bytes
        or a numpy array. ``search`` bounds how far moved bodies are looked for
        (``{"translation_m": .., "rotation_deg": ..}``; ``None`` does not look). With
        ``raw=True`` the PNG is sent as the request body (``camera`` must be a name, and
        ``depth``/``search`` cannot be given). ``update=True`` (write role) applies the
        moved bodies' corrected poses.
        """
        if raw:
            if not isinstance(camera, str):
                raise ValueError("the raw-PNG form takes a stored camera's name")
            if depth is not None or depth_scale is not None or search is not UNSET:
                raise ValueError("the raw-PNG form takes no depth or search")
            png = image if isinstance(image, (bytes, bytearray)) else base64.b64decode(encode_image(image))
            params = {
                "camera": camera,
                "refine_camera": refine_camera,
                "unexplained_mask": unexplained_mask,
                "update": update,
            }
            return self._run(
                Call(
                    "POST",
                    "/v1/recognition",
                    model_reader(Recognition),
                    params=params,
                    content=bytes(png),
                    content_type="image/png",
                    headers=if_match(expected_revision),
                    write=bool(update),
                )
            )
        body = drop_none(
            {
                "camera": camera,
                "image": encode_image(image),
                "depth": None if depth is None else encode_image(depth),
                "depth_scale": depth_scale,
                "refine_camera": refine_camera,
                "unexplained_mask": unexplained_mask,
                "update": update,
            }
        )
        if search is not UNSET:
            body["search"] = to_json(search)
        return self._run(
            Call(
                "POST",
                "/v1/recognition",
                model_reader(Recognition),
                json=body,
                headers=if_match(expected_revision),
                write=bool(update),
            )
        )

    def perceive(
        self,
        views: Sequence[Any],
        *,
        name: str | None = None,
        body: int | None = None,
        near: float | None = None,
        far: float | None = None,
        tolerance_px: float | None = None,
        min_area_px: float | None = None,
        expected_revision: int | None = None,
    ) -> Perception:
        """``POST /v1/perception``: new provisional bodies carved from silhouettes.

        ``views`` are :class:`~winged.View` items (a camera and a ``mask`` or ``image``).
        Without ``body`` each piece of the visual hull becomes a new provisional body;
        with ``body`` that provisional body is carved further.
        """
        payload = drop_none(
            {
                "views": list(views),
                "name": name,
                "body": body,
                "near": near,
                "far": far,
                "tolerance_px": tolerance_px,
                "min_area_px": min_area_px,
            }
        )
        return self._run(
            Call(
                "POST",
                "/v1/perception",
                model_reader(Perception),
                json=payload,
                headers=if_match(expected_revision),
                write=True,
            )
        )

    # ----- lights ----------------------------------------------------------------------

    def list_lights(self) -> LightList:
        """``GET /v1/lights``: every light, in name order."""
        return self._run(Call("GET", "/v1/lights", model_reader(LightList)))

    def get_light(self, name: str) -> NamedLight:
        """``GET /v1/lights/{name}``: one light."""
        return self._run(Call("GET", f"/v1/lights/{path_segment(name)}", model_reader(NamedLight)))

    def put_light(self, name: str, light: Any, *, expected_revision: int | None = None) -> RevisionOnly:
        """``PUT /v1/lights/{name}``: store a light (:class:`~winged.Sun`, :class:`~winged.PointLamp` or dict)."""
        return self._put_named("lights", name, light, expected_revision)

    def delete_light(self, name: str, *, expected_revision: int | None = None) -> RevisionOnly:
        """``DELETE /v1/lights/{name}``: remove a light."""
        return self._delete_named("lights", name, expected_revision)
