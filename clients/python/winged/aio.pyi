"""Type stub of winged.aio, written by clients/python/tools/async_stub.py: the
operations of winged._api.Operations as coroutines. Do not edit by hand."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import httpx

from ._base import Vec, Via
from ._http import RetryPolicy
from .events import AsyncEventStream
from .models import (
    Body,
    BodyList,
    BooleanResult,
    BoxAnswer,
    Camera,
    CameraList,
    CameraSolution,
    Changed,
    Changes,
    Checkpoint,
    Created,
    EulerResult,
    Health,
    HiddenLines,
    Imported,
    Killed,
    LightList,
    NamedLight,
    NearestAnswer,
    Perception,
    RayAnswer,
    Ready,
    Recognition,
    Reshaped,
    RevisionOnly,
    SphereAnswer,
    Topology,
    WorldSummary,
)

__all__ = ["AsyncClient"]


class AsyncClient:
    """An asyncio client of a winged server.

    It has every method of :class:`winged.Client`, with the same arguments; each
    answers an awaitable of what the blocking one answers::

        async with winged.AsyncClient(url) as client:
            body = await client.get_body(2)

    Args are those of :class:`winged.Client` (``transport`` an async httpx transport)."""
    retry: RetryPolicy
    def __init__(self, url: str = ..., token: str | None = ..., *, timeout: float | httpx.Timeout | None = ..., retries: int = ..., max_retry_wait: float = ..., transport: httpx.AsyncBaseTransport | None = ...) -> None: ...
    @property
    def url(self) -> str: ...
    async def events(self, since: int | None = ..., *, last_event_id: str | int | None = ..., reconnect: bool = ..., max_reconnects: int = ..., reconnect_wait: float = ..., idle_timeout: float | None = ...) -> AsyncEventStream: ...
    async def close(self) -> None: ...
    async def __aenter__(self) -> AsyncClient: ...
    async def __aexit__(self, *exc: Any) -> None: ...
    async def appearance(self, camera: Any, *, mode: str | None = ..., format: str | None = ..., width: int | None = ..., height: int | None = ..., background: str | None = ..., shadows: bool | None = ..., near: float | None = ..., depth_scale: float | None = ..., as_array: bool = ...) -> Any:
        """``POST /v1/appearance``: the same drawing as :meth:`camera_image`, from a stored
        camera's name or a camera given inline (:class:`~winged.CameraSpec` or dict)."""
    async def boolean(self, id: int, op: str, with_: int, *, keep_with: bool | None = ..., expected_revision: int | None = ...) -> BooleanResult:
        """``POST /v1/bodies/{id}/boolean``: ``intersection``, ``union`` or ``difference``
        with body ``with_`` (killed unless ``keep_with``); the result replaces this body."""
    async def camera_image(self, name: str, *, mode: str | None = ..., format: str | None = ..., width: int | None = ..., height: int | None = ..., background: str | None = ..., shadows: bool | None = ..., near: float | None = ..., depth_scale: float | None = ..., as_array: bool = ...) -> Any:
        """``GET /v1/cameras/{name}/image``: what the world looks like from a stored camera.

        ``mode`` is ``shaded`` (default), ``wire``, ``hidden``, ``depth`` or ``ids``. The
        answer is a :class:`~winged.models.Png` (the PNG's bytes, with ``revision``,
        ``depth_scale`` and ``body_ids``), a numpy array with ``as_array=True`` (``uint16``
        for depth and ids), :class:`~winged.models.HiddenLines` (the visible segments) for
        ``mode="hidden", format="json"``, :class:`~winged.models.IdsLegend` for
        ``mode="ids", format="json"``, or the SVG text for ``format="svg"``."""
    async def changes(self, since: int, limit: int | None = ...) -> Changes:
        """``GET /v1/world/changes``: every change after revision ``since``, oldest first.

        ``limit`` caps how many (the server's default 1000, at most 10000); ``more``
        says whether more follow. ``resync`` says the history no longer reaches back."""
    async def copy_body(self, id: int, name: str | None = ..., *, expected_revision: int | None = ...) -> Created:
        """``POST /v1/bodies/{id}/copy``: copy a body (MKCOPY), named ``name`` if given."""
    async def create_body(self, shape: Any, *, name: str | None = ..., parent: int | None = ..., pose: Any = ..., color: str | None = ..., expected_revision: int | None = ...) -> Created:
        """``POST /v1/bodies``: make a body from a shape (:mod:`winged.requests`, or a dict).

        ``shape`` is :class:`~winged.Box`, :class:`~winged.Tetrahedron`,
        :class:`~winged.Prism`, :class:`~winged.Pyramid`, :class:`~winged.Cylinder`,
        :class:`~winged.Cone`, :class:`~winged.Sphere`, :class:`~winged.Torus`,
        :class:`~winged.Polyhedron`, :class:`~winged.Seminal` (MKBFV; the answer also
        names its ``face`` and ``vertex``) or :class:`~winged.Mesh` (a mesh file; the
        answer lists every body made in ``bodies``)."""
    async def delete_body(self, id: int, *, expected_revision: int | None = ...) -> Killed:
        """``DELETE /v1/bodies/{id}``: kill a body with all its parts (KLBFEV)."""
    async def delete_camera(self, name: str, *, expected_revision: int | None = ...) -> RevisionOnly:
        """``DELETE /v1/cameras/{name}``: remove a camera."""
    async def delete_light(self, name: str, *, expected_revision: int | None = ...) -> RevisionOnly:
        """``DELETE /v1/lights/{name}``: remove a light."""
    async def dilate(self, id: int, factor: float, *, center: Vec | None = ..., frame: str | None = ..., target: int | None = ..., expected_revision: int | None = ...) -> Changed:
        """DILATE the body's loci (or ``target``'s) by ``factor`` about ``center``."""
    async def dual(self, id: int, *, expected_revision: int | None = ...) -> Reshaped:
        """``POST /v1/bodies/{id}/dual``: replace the body by its face-vertex dual (FVDUAL)."""
    async def esplit(self, id: int, edge: int, position: Vec | None = ..., *, expected_revision: int | None = ...) -> EulerResult:
        """ESPLIT: split ``edge`` with a new vertex (at ``position``, default the midpoint)."""
    async def euler(self, id: int, op: Any, *, expected_revision: int | None = ...) -> EulerResult:
        """``POST /v1/bodies/{id}/euler``: apply one Euler operator (:class:`~winged.Mkev`, ...).

        A refused operator raises :class:`~winged.Unprocessable` (``euler-refused``) and
        leaves the body as it was."""
    async def evert(self, id: int, *, expected_revision: int | None = ...) -> Changed:
        """``POST /v1/bodies/{id}/evert``: turn the body inside out (EVERT)."""
    async def export_mesh(self, id: int, format: str | None = ..., frame: str | None = ...) -> bytes:
        """``GET /v1/bodies/{id}/mesh``: one body as a mesh file's bytes.

        ``format`` is ``obj`` (the default), ``stl``, ``ply``, ``off``, ``glb`` or
        ``3mf``; ``frame`` is ``world`` (the default: the world pose applied) or ``body``."""
    async def export_world(self, format: str = ...) -> bytes:
        """``GET /v1/world/mesh``: the whole world as one GLB file (its bytes)."""
    async def get_body(self, id: int) -> Body:
        """``GET /v1/bodies/{id}``: name, parent, parts, poses, Euler counts, volume, area, bounds."""
    async def get_camera(self, name: str) -> Camera:
        """``GET /v1/cameras/{name}``: one camera."""
    async def get_light(self, name: str) -> NamedLight:
        """``GET /v1/lights/{name}``: one light."""
    async def glue(self, id: int, face1: int, face2: int, vertex1: int | None = ..., vertex2: int | None = ..., *, expected_revision: int | None = ...) -> EulerResult:
        """GLUE: identify ``face2`` (of this or another body) with ``face1``."""
    async def gluee(self, id: int, face1: int, vertex1: int, face2: int, vertex2: int, *, expected_revision: int | None = ...) -> EulerResult:
        """GLUEE: a wasp edge from ``vertex1`` on ``face1`` to ``vertex2`` on ``face2``."""
    async def glueff(self, id: int, face1: int, face2: int, *, expected_revision: int | None = ...) -> EulerResult:
        """GLUEFF: join ``face1`` and ``face2`` by a tube; answers the tube's ``new_edges``."""
    async def health(self) -> Health:
        """``GET /healthz``: whether the server is up, and the world's revision (no token needed)."""
    async def hidden_lines(self, camera: Any, *, width: int | None = ..., height: int | None = ...) -> HiddenLines:
        """The exact hidden-line drawing from ``camera`` (a name or a camera) as segments."""
    async def import_mesh(self, data: bytes, format: str, *, name: str | None = ..., parent: int | None = ..., color: str | None = ..., unit: str | None = ..., merge_coplanar: bool | None = ..., weld: float | None = ..., coplanar_tolerance: float | None = ..., check_intersections: bool | None = ..., expected_revision: int | None = ...) -> Imported:
        """``POST /v1/bodies/import``: make bodies from a mesh file (its bytes, read as ``format``).

        ``format`` is ``obj``, ``stl``, ``ply``, ``off``, ``gltf``, ``glb`` or ``3mf``. An
        invalid surface is refused with :class:`~winged.Unprocessable` (``mesh-invalid``,
        its ``defect`` and ``where`` in ``extensions``)."""
    async def invert(self, id: int, edge: int, *, expected_revision: int | None = ...) -> EulerResult:
        """INVERT: turn ``edge`` round (swap its N and P sides)."""
    async def klev(self, id: int, vertex: int, *, expected_revision: int | None = ...) -> EulerResult:
        """KLEV: kill ``vertex`` (one or two edges) and its PED; answers the surviving ``vertex``."""
    async def klfe(self, id: int, edge: int, *, expected_revision: int | None = ...) -> EulerResult:
        """KLFE: kill ``edge`` and its NFACE; answers the surviving ``face``."""
    async def klve(self, id: int, edge: int, *, expected_revision: int | None = ...) -> EulerResult:
        """KLVE: contract ``edge``, killing it and its NVT; answers the surviving ``vertex``."""
    async def list_bodies(self, name: str | None = ..., parent: int | None = ...) -> BodyList:
        """``GET /v1/bodies``: every body (or the one named ``name``, or the parts of ``parent``).

        The answer iterates over its :class:`~winged.models.BodySummary` items."""
    async def list_cameras(self) -> CameraList:
        """``GET /v1/cameras``: every camera, in name order."""
    async def list_lights(self) -> LightList:
        """``GET /v1/lights``: every light, in name order."""
    async def metrics(self) -> str:
        """``GET /metrics``: Prometheus metrics as OpenMetrics text (read role)."""
    async def mkev(self, id: int, face: int, vertex: int, position: Vec | None = ..., *, expected_revision: int | None = ...) -> EulerResult:
        """MKEV: a spur edge from ``vertex`` into ``face``; answers the new ``edge`` and ``vertex``."""
    async def mkfe(self, id: int, v1: int, face: int, v2: int, *, expected_revision: int | None = ...) -> EulerResult:
        """MKFE: split ``face`` by an edge from ``v1`` to ``v2``; answers the new ``edge`` and ``face``."""
    async def openapi(self) -> dict[str, Any]:
        """``GET /openapi.json``: the API's contract, as a dict."""
    async def patch_body(self, id: int, *, name: str | None = ..., parent: int | None = ..., pose: Any = ..., color: str | None = ..., expected_revision: int | None = ...) -> Changed:
        """``PATCH /v1/bodies/{id}``: rename, re-parent, re-pose or re-colour a body.

        Only the arguments given are sent; ``name=None`` removes the name and
        ``color=None`` restores the default colour."""
    async def perceive(self, views: Sequence[Any], *, name: str | None = ..., body: int | None = ..., near: float | None = ..., far: float | None = ..., tolerance_px: float | None = ..., min_area_px: float | None = ..., expected_revision: int | None = ...) -> Perception:
        """``POST /v1/perception``: new provisional bodies carved from silhouettes.

        ``views`` are :class:`~winged.View` items (a camera and a ``mask`` or ``image``).
        Without ``body`` each piece of the visual hull becomes a new provisional body;
        with ``body`` that provisional body is carved further."""
    async def put_camera(self, name: str, camera: Any, *, expected_revision: int | None = ...) -> RevisionOnly:
        """``PUT /v1/cameras/{name}``: store a camera (a :class:`~winged.CameraSpec` or dict)."""
    async def put_light(self, name: str, light: Any, *, expected_revision: int | None = ...) -> RevisionOnly:
        """``PUT /v1/lights/{name}``: store a light (:class:`~winged.Sun`, :class:`~winged.PointLamp` or dict)."""
    async def ready(self) -> Ready:
        """``GET /readyz``: the world's owner answers promptly and its storage works.

        Raises :class:`~winged.Unavailable` (after the configured retries) when not ready."""
    async def recognize(self, camera: Any, image: Any, *, depth: Any = ..., depth_scale: float | None = ..., refine_camera: bool | None = ..., search: Any = ..., unexplained_mask: bool | None = ..., update: bool | None = ..., raw: bool = ..., expected_revision: int | None = ...) -> Recognition:
        """``POST /v1/recognition``: which modeled bodies the picture ``image`` shows.

        ``camera`` took it (a stored camera's name or a camera); ``image`` is PNG bytes
        or a numpy array. ``search`` bounds how far moved bodies are looked for
        (``{"translation_m": .., "rotation_deg": ..}``; ``None`` does not look). With
        ``raw=True`` the PNG is sent as the request body (``camera`` must be a name, and
        ``depth``/``search`` cannot be given). ``update=True`` (write role) applies the
        moved bodies' corrected poses."""
    async def reflect(self, id: int, normal: Vec, *, point: Vec | None = ..., frame: str | None = ..., target: int | None = ..., expected_revision: int | None = ...) -> Changed:
        """REFLECT in the plane through ``point`` with normal ``normal`` (the body is everted too)."""
    async def rotate(self, id: int, axis: Vec, angle_deg: float, *, center: Vec | None = ..., frame: str | None = ..., target: int | None = ..., expected_revision: int | None = ...) -> Changed:
        """ROTATE by ``angle_deg`` (right-hand rule) about ``axis`` through ``center``."""
    async def solve_camera(self, intrinsics: Any = ..., correspondences: Sequence[Any] | None = ..., *, image: Any = ..., initial: Any = ..., store_as: str | None = ..., threshold_px: float | None = ..., confidence: float | None = ..., max_iterations: int | None = ..., min_inliers: int | None = ..., seed: int | None = ..., solve_focal: bool | None = ...) -> CameraSolution:
        """``POST /v1/camera-solution``: the camera that sees given points at given pixels.

        From correspondences: ``intrinsics`` (an :class:`~winged.Intrinsics`, or a stored
        camera's name) and ``correspondences`` (:class:`~winged.Correspondence` items,
        each a pixel and a model ``vertex`` or a world ``point``). From a picture:
        ``image`` (PNG bytes or an array) and ``initial`` (the rough camera, a name or a
        camera). ``store_as`` stores the solved camera (the write role)."""
    async def spatial_box(self, min: Vec, max: Vec, *, detail: str | None = ..., max_features: int | None = ..., via: Via = ...) -> BoxAnswer:
        """The portions of bodies inside the closed box ``min..max``, by id (``via``: GET or POST)."""
    async def spatial_nearest(self, point: Vec, *, max_distance: float | None = ..., via: Via = ...) -> NearestAnswer:
        """The body nearest ``point`` (``hit`` ``None`` when none is within ``max_distance``)."""
    async def spatial_ray(self, origin: Vec, direction: Vec, *, max_distance: float | None = ..., via: Via = ...) -> RayAnswer:
        """The first surface along the ray from ``origin`` along ``direction``."""
    async def spatial_sphere(self, center: Vec, radius: float, *, detail: str | None = ..., tolerance: float | None = ..., max_features: int | None = ..., via: Via = ...) -> SphereAnswer:
        """The portions of bodies within ``radius`` of ``center``, nearest first.

        ``detail`` is ``bodies``, ``features`` (default) or ``portions``. ``via`` picks
        ``GET`` (a query string) or ``POST`` (a JSON body); both answer alike."""
    async def sweep(self, id: int, face: int, kind: str = ..., *, distance: float | None = ..., offset: Vec | None = ..., peak: Vec | None = ..., scale: float | None = ..., expected_revision: int | None = ...) -> Reshaped:
        """``POST /v1/bodies/{id}/sweep``: sweep ``face`` as a ``prism``, ``pyramid``,
        ``cw_prismoid`` or ``ccw_prismoid``; the answer's ``face`` is the cap."""
    async def topology(self, id: int) -> Topology:
        """``GET /v1/bodies/{id}/topology``: the winged-edge structure (body frame)."""
    async def transform(self, id: int, op: Any, *, expected_revision: int | None = ...) -> Changed:
        """``POST /v1/bodies/{id}/transform``: :class:`~winged.Translate`, :class:`~winged.Rotate`,
        :class:`~winged.Dilate` or :class:`~winged.Reflect` the body (or one of its entities)."""
    async def translate(self, id: int, vector: Vec, *, frame: str | None = ..., target: int | None = ..., expected_revision: int | None = ...) -> Changed:
        """TRANSLATE the body (its pose) or ``target`` entity by ``vector``."""
    async def unglue(self, id: int, edges: Sequence[int], *, expected_revision: int | None = ...) -> EulerResult:
        """UNGLUE: cut the body along the closed loop of ``edges``."""
    async def world(self) -> WorldSummary:
        """``GET /v1/world``: counts of bodies, faces, edges, vertices, cameras and lights."""
    async def write_snapshot(self) -> Checkpoint:
        """``POST /v1/admin/snapshot``: write a snapshot file of the world now (admin role).

        A server started with ``--memory`` refuses with :class:`~winged.Conflict`."""
