"""The service, the world as a whole, and bodies: make, read, change, kill, import, export."""

from __future__ import annotations

from typing import Any

from ._base import UNSET, Base, drop_none, model_reader, read_bytes, read_json, read_text
from ._http import Call, if_match, path_segment
from ._json import to_json
from .models import (
    Body,
    BodyList,
    Changed,
    Changes,
    Checkpoint,
    Created,
    Health,
    Imported,
    Killed,
    Ready,
    Topology,
    WorldSummary,
)


class BodyOperations(Base):
    """The service, the world as a whole, and bodies: make, read, change, kill, import, export."""

    # ----- service ---------------------------------------------------------------------

    def health(self) -> Health:
        """``GET /healthz``: whether the server is up, and the world's revision (no token needed)."""
        return self._run(Call("GET", "/healthz", model_reader(Health)))

    def ready(self) -> Ready:
        """``GET /readyz``: the world's owner answers promptly and its storage works.

        Raises :class:`~winged.Unavailable` (after the configured retries) when not ready.
        """
        return self._run(Call("GET", "/readyz", model_reader(Ready)))

    def metrics(self) -> str:
        """``GET /metrics``: Prometheus metrics as OpenMetrics text (read role)."""
        return self._run(Call("GET", "/metrics", read_text))

    def write_snapshot(self) -> Checkpoint:
        """``POST /v1/admin/snapshot``: write a snapshot file of the world now (admin role).

        A server started with ``--memory`` refuses with :class:`~winged.Conflict`.
        """
        return self._run(Call("POST", "/v1/admin/snapshot", model_reader(Checkpoint), write=True))

    def openapi(self) -> dict[str, Any]:
        """``GET /openapi.json``: the API's contract, as a dict."""
        return self._run(Call("GET", "/openapi.json", read_json))

    # ----- world -----------------------------------------------------------------------

    def world(self) -> WorldSummary:
        """``GET /v1/world``: counts of bodies, faces, edges, vertices, cameras and lights."""
        return self._run(Call("GET", "/v1/world", model_reader(WorldSummary)))

    def changes(self, since: int, limit: int | None = None) -> Changes:
        """``GET /v1/world/changes``: every change after revision ``since``, oldest first.

        ``limit`` caps how many (the server's default 1000, at most 10000); ``more``
        says whether more follow. ``resync`` says the history no longer reaches back.
        """
        return self._run(
            Call("GET", "/v1/world/changes", model_reader(Changes), params={"since": since, "limit": limit})
        )

    def export_world(self, format: str = "glb") -> bytes:
        """``GET /v1/world/mesh``: the whole world as one GLB file (its bytes)."""
        return self._run(Call("GET", "/v1/world/mesh", read_bytes, params={"format": format}))

    # ----- bodies ----------------------------------------------------------------------

    def list_bodies(self, name: str | None = None, parent: int | None = None) -> BodyList:
        """``GET /v1/bodies``: every body (or the one named ``name``, or the parts of ``parent``).

        The answer iterates over its :class:`~winged.models.BodySummary` items.
        """
        return self._run(Call("GET", "/v1/bodies", model_reader(BodyList), params={"name": name, "parent": parent}))

    def create_body(
        self,
        shape: Any,
        *,
        name: str | None = None,
        parent: int | None = None,
        pose: Any = None,
        color: str | None = None,
        expected_revision: int | None = None,
    ) -> Created:
        """``POST /v1/bodies``: make a body from a shape (:mod:`winged.requests`, or a dict).

        ``shape`` is :class:`~winged.Box`, :class:`~winged.Tetrahedron`,
        :class:`~winged.Prism`, :class:`~winged.Pyramid`, :class:`~winged.Cylinder`,
        :class:`~winged.Cone`, :class:`~winged.Sphere`, :class:`~winged.Torus`,
        :class:`~winged.Polyhedron`, :class:`~winged.Seminal` (MKBFV; the answer also
        names its ``face`` and ``vertex``) or :class:`~winged.Mesh` (a mesh file; the
        answer lists every body made in ``bodies``).
        """
        body = drop_none({"name": name, "parent": parent, "pose": pose, "color": color})
        body["shape"] = to_json(shape)
        return self._run(
            Call(
                "POST", "/v1/bodies", model_reader(Created), json=body, headers=if_match(expected_revision), write=True
            )
        )

    def import_mesh(
        self,
        data: bytes,
        format: str,
        *,
        name: str | None = None,
        parent: int | None = None,
        color: str | None = None,
        unit: str | None = None,
        merge_coplanar: bool | None = None,
        weld: float | None = None,
        coplanar_tolerance: float | None = None,
        check_intersections: bool | None = None,
        expected_revision: int | None = None,
    ) -> Imported:
        """``POST /v1/bodies/import``: make bodies from a mesh file (its bytes, read as ``format``).

        ``format`` is ``obj``, ``stl``, ``ply``, ``off``, ``gltf``, ``glb`` or ``3mf``. An
        invalid surface is refused with :class:`~winged.Unprocessable` (``mesh-invalid``,
        its ``defect`` and ``where`` in ``extensions``).
        """
        params = {
            "format": format,
            "name": name,
            "parent": parent,
            "color": color,
            "unit": unit,
            "merge_coplanar": merge_coplanar,
            "weld": weld,
            "coplanar_tolerance": coplanar_tolerance,
            "check_intersections": check_intersections,
            "expected_revision": expected_revision,
        }
        return self._run(
            Call(
                "POST",
                "/v1/bodies/import",
                model_reader(Imported),
                params=params,
                content=bytes(data),
                content_type="application/octet-stream",
                write=True,
            )
        )

    def get_body(self, id: int) -> Body:
        """``GET /v1/bodies/{id}``: name, parent, parts, poses, Euler counts, volume, area, bounds."""
        return self._run(Call("GET", f"/v1/bodies/{path_segment(id)}", model_reader(Body)))

    def patch_body(
        self,
        id: int,
        *,
        name: str | None = UNSET,
        parent: int | None = UNSET,
        pose: Any = UNSET,
        color: str | None = UNSET,
        expected_revision: int | None = None,
    ) -> Changed:
        """``PATCH /v1/bodies/{id}``: rename, re-parent, re-pose or re-colour a body.

        Only the arguments given are sent; ``name=None`` removes the name and
        ``color=None`` restores the default colour.
        """
        body: dict[str, Any] = {}
        for key, value in (("name", name), ("parent", parent), ("pose", pose), ("color", color)):
            if value is not UNSET:
                body[key] = to_json(value)
        return self._run(
            Call(
                "PATCH",
                f"/v1/bodies/{path_segment(id)}",
                model_reader(Changed),
                json=body,
                headers=if_match(expected_revision),
                write=True,
            )
        )

    def delete_body(self, id: int, *, expected_revision: int | None = None) -> Killed:
        """``DELETE /v1/bodies/{id}``: kill a body with all its parts (KLBFEV)."""
        return self._run(
            Call(
                "DELETE",
                f"/v1/bodies/{path_segment(id)}",
                model_reader(Killed),
                headers=if_match(expected_revision),
                write=True,
            )
        )

    def topology(self, id: int) -> Topology:
        """``GET /v1/bodies/{id}/topology``: the winged-edge structure (body frame)."""
        return self._run(Call("GET", f"/v1/bodies/{path_segment(id)}/topology", model_reader(Topology)))

    def export_mesh(
        self,
        id: int,
        format: str | None = None,
        frame: str | None = None,
    ) -> bytes:
        """``GET /v1/bodies/{id}/mesh``: one body as a mesh file's bytes.

        ``format`` is ``obj`` (the default), ``stl``, ``ply``, ``off``, ``glb`` or
        ``3mf``; ``frame`` is ``world`` (the default: the world pose applied) or ``body``.
        """
        return self._run(
            Call(
                "GET",
                f"/v1/bodies/{path_segment(id)}/mesh",
                read_bytes,
                params={"format": format, "frame": frame},
            )
        )
