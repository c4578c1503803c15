"""Spatial access: sphere, box, nearest and ray."""

from __future__ import annotations

from ._base import Base, Vec, Via, drop_none, model_reader, vec3
from ._http import Call
from .models import BoxAnswer, NearestAnswer, RayAnswer, SphereAnswer


class SpatialOperations(Base):
    """Spatial access: sphere, box, nearest and ray."""

    def spatial_sphere(
        self,
        center: Vec,
        radius: float,
        *,
        detail: str | None = None,
        tolerance: float | None = None,
        max_features: int | None = None,
        via: Via = "get",
    ) -> SphereAnswer:
        """The portions of bodies within ``radius`` of ``center``, nearest first.

        ``detail`` is ``bodies``, ``features`` (default) or ``portions``. ``via`` picks
        ``GET`` (a query string) or ``POST`` (a JSON body); both answer alike.
        """
        if via == "post":
            body = drop_none(
                {
                    "center": vec3(center),
                    "radius": radius,
                    "detail": detail,
                    "tolerance": tolerance,
                    "max_features": max_features,
                }
            )
            return self._run(Call("POST", "/v1/spatial/sphere", model_reader(SphereAnswer), json=body))
        x, y, z = center
        params = {
            "x": x,
            "y": y,
            "z": z,
            "r": radius,
            "detail": detail,
            "tolerance": tolerance,
            "max_features": max_features,
        }
        return self._run(Call("GET", "/v1/spatial/sphere", model_reader(SphereAnswer), params=params))

    def spatial_box(
        self,
        min: Vec,
        max: Vec,
        *,
        detail: str | None = None,
        max_features: int | None = None,
        via: Via = "get",
    ) -> BoxAnswer:
        """The portions of bodies inside the closed box ``min..max``, by id (``via``: GET or POST)."""
        if via == "post":
            body = drop_none({"min": vec3(min), "max": vec3(max), "detail": detail, "max_features": max_features})
            return self._run(Call("POST", "/v1/spatial/box", model_reader(BoxAnswer), json=body))
        params = {
            "min_x": min[0],
            "min_y": min[1],
            "min_z": min[2],
            "max_x": max[0],
            "max_y": max[1],
            "max_z": max[2],
            "detail": detail,
            "max_features": max_features,
        }
        return self._run(Call("GET", "/v1/spatial/box", model_reader(BoxAnswer), params=params))

    def spatial_nearest(self, point: Vec, *, max_distance: float | None = None, via: Via = "get") -> NearestAnswer:
        """The body nearest ``point`` (``hit`` ``None`` when none is within ``max_distance``)."""
        if via == "post":
            body = drop_none({"point": vec3(point), "max_distance": max_distance})
            return self._run(Call("POST", "/v1/spatial/nearest", model_reader(NearestAnswer), json=body))
        x, y, z = point
        params = {"x": x, "y": y, "z": z, "max_distance": max_distance}
        return self._run(Call("GET", "/v1/spatial/nearest", model_reader(NearestAnswer), params=params))

    def spatial_ray(
        self, origin: Vec, direction: Vec, *, max_distance: float | None = None, via: Via = "get"
    ) -> RayAnswer:
        """The first surface along the ray from ``origin`` along ``direction``."""
        if via == "post":
            body = drop_none({"origin": vec3(origin), "direction": vec3(direction), "max_distance": max_distance})
            return self._run(Call("POST", "/v1/spatial/ray", model_reader(RayAnswer), json=body))
        x, y, z = origin
        dx, dy, dz = direction
        params = {"x": x, "y": y, "z": z, "dx": dx, "dy": dy, "dz": dz, "max_distance": max_distance}
        return self._run(Call("GET", "/v1/spatial/ray", model_reader(RayAnswer), params=params))
