"""What requests carry: shapes, Euler operators, transforms, cameras, lights, views.

Each is a small dataclass whose fields are the spec's; fields left ``None`` are not sent,
so the server's defaults apply. Plain dicts in the spec's JSON form are accepted wherever
these are.
"""

from __future__ import annotations

import base64
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from .models import Intrinsics, Pose

Vec = Sequence[float]


__all__ = [
    "Baumgart",
    "Box",
    "CameraSpec",
    "Cone",
    "Correspondence",
    "Cylinder",
    "Dilate",
    "Esplit",
    "Glue",
    "Gluee",
    "Glueff",
    "Intrinsics",
    "Invert",
    "Klev",
    "Klfe",
    "Klve",
    "LookAt",
    "Mesh",
    "Mkev",
    "Mkfe",
    "PointLamp",
    "Polyhedron",
    "Pose",
    "Prism",
    "Pyramid",
    "Reflect",
    "Rotate",
    "Seminal",
    "Sphere",
    "Sun",
    "Tetrahedron",
    "Torus",
    "Translate",
    "Unglue",
    "View",
    "encode_image",
]


def encode_image(image: Any) -> str:
    """A picture as the base64 text requests carry.

    ``image`` is PNG bytes, text already in base64, or a numpy array (encoded as a PNG
    with Pillow: 2-D ``uint8``/``bool`` grey, ``uint16`` 16-bit grey, ``H×W×3`` RGB,
    ``H×W×4`` RGBA).
    """
    if isinstance(image, str):
        return image
    if isinstance(image, (bytes, bytearray, memoryview)):
        return base64.b64encode(bytes(image)).decode("ascii")
    from ._images import array_to_png

    return base64.b64encode(array_to_png(image)).decode("ascii")


def _typed(tag: str, value: str) -> dict[str, str]:
    return {tag: value}


# ----- shapes ------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Box:
    """A box of edge lengths ``size`` centred on the origin (MKCUBE)."""

    size: Vec

    def _json_extra(self) -> dict[str, str]:
        return _typed("type", "box")


@dataclass(frozen=True, kw_only=True)
class Tetrahedron:
    """A regular tetrahedron with its vertices ``radius`` from the origin (MKTETRA)."""

    radius: float

    def _json_extra(self) -> dict[str, str]:
        return _typed("type", "tetrahedron")


@dataclass(frozen=True, kw_only=True)
class Prism:
    """A polygon (``[x, y]`` corners) in the xy-plane swept up by ``height``."""

    polygon: Sequence[Vec]
    height: float

    def _json_extra(self) -> dict[str, str]:
        return _typed("type", "prism")


@dataclass(frozen=True, kw_only=True)
class Pyramid:
    """A polygon in the xy-plane with a peak ``height`` above its centroid."""

    polygon: Sequence[Vec]
    height: float

    def _json_extra(self) -> dict[str, str]:
        return _typed("type", "pyramid")


@dataclass(frozen=True, kw_only=True)
class Cylinder:
    """A prism over a regular ``segments``-gon of ``radius``, axis on z."""

    radius: float
    height: float
    segments: int | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("type", "cylinder")


@dataclass(frozen=True, kw_only=True)
class Cone:
    """A pyramid over a regular ``segments``-gon of ``radius``, axis on z."""

    radius: float
    height: float
    segments: int | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("type", "cone")


@dataclass(frozen=True, kw_only=True)
class Sphere:
    """A UV sphere of ``radius`` centred on the origin."""

    radius: float
    segments: int | None = None
    rings: int | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("type", "sphere")


@dataclass(frozen=True, kw_only=True)
class Torus:
    """A torus round the z axis (``minor_radius`` < ``major_radius``)."""

    major_radius: float
    minor_radius: float
    segments: int | None = None
    rings: int | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("type", "torus")


@dataclass(frozen=True, kw_only=True)
class Polyhedron:
    """A closed polyhedron: vertex loci and faces as vertex indices, counter-clockwise."""

    vertices: Sequence[Vec]
    faces: Sequence[Sequence[int]]

    def _json_extra(self) -> dict[str, str]:
        return _typed("type", "polyhedron")


@dataclass(frozen=True, kw_only=True)
class Seminal:
    """MKBFV: one face and one vertex at ``position``, the seed of Euler constructions."""

    position: Vec | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("type", "seminal")


@dataclass(frozen=True, kw_only=True)
class Mesh:
    """A mesh file (its bytes in ``data``, read as ``format``) as a ``mesh`` shape."""

    format: str
    data: bytes
    unit: str | None = None
    merge_coplanar: bool | None = None
    weld: float | None = None
    coplanar_tolerance: float | None = None
    check_intersections: bool | None = None

    def _json_extra(self) -> dict[str, str]:
        return {"type": "mesh", "data": base64.b64encode(self.data).decode("ascii")}


# ----- Euler operators ---------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Mkev:
    """MKEV: a spur edge from ``vertex`` into ``face``, its new vertex at ``position``."""

    face: int
    vertex: int
    position: Vec | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "mkev")


@dataclass(frozen=True, kw_only=True)
class Mkfe:
    """MKFE: split ``face`` by a new edge from ``v1`` to ``v2``."""

    v1: int
    face: int
    v2: int

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "mkfe")


@dataclass(frozen=True, kw_only=True)
class Esplit:
    """ESPLIT: split ``edge`` with a new vertex at ``position`` (default its midpoint)."""

    edge: int
    position: Vec | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "esplit")


@dataclass(frozen=True, kw_only=True)
class Klfe:
    """KLFE: kill ``edge`` and its NFACE, merging it into the PFACE."""

    edge: int

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "klfe")


@dataclass(frozen=True, kw_only=True)
class Klev:
    """KLEV: kill ``vertex`` (one or two edges) and its PED."""

    vertex: int

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "klev")


@dataclass(frozen=True, kw_only=True)
class Klve:
    """KLVE: contract ``edge``, killing it and its NVT."""

    edge: int

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "klve")


@dataclass(frozen=True, kw_only=True)
class Invert:
    """INVERT: turn ``edge`` round."""

    edge: int

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "invert")


@dataclass(frozen=True, kw_only=True)
class Glue:
    """GLUE: identify ``face2`` with ``face1`` (pairing ``vertex1`` with ``vertex2``)."""

    face1: int
    face2: int
    vertex1: int | None = None
    vertex2: int | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "glue")


@dataclass(frozen=True, kw_only=True)
class Gluee:
    """GLUEE: a wasp edge from ``vertex1`` on ``face1`` to ``vertex2`` on ``face2``."""

    face1: int
    vertex1: int
    face2: int
    vertex2: int

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "gluee")


@dataclass(frozen=True, kw_only=True)
class Glueff:
    """GLUEFF: join ``face1`` and ``face2`` by a tube of quadrilaterals."""

    face1: int
    face2: int

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "glueff")


@dataclass(frozen=True, kw_only=True)
class Unglue:
    """UNGLUE: cut the body along the closed loop of ``edges``."""

    edges: Sequence[int]

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "unglue")


# ----- transforms --------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Translate:
    """TRANSLATE by ``vector`` (meters), in the ``world`` or ``body`` frame."""

    vector: Vec
    frame: str | None = None
    target: int | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "translate")


@dataclass(frozen=True, kw_only=True)
class Rotate:
    """ROTATE by ``angle_deg`` about ``axis`` through ``center``."""

    axis: Vec
    angle_deg: float
    center: Vec | None = None
    frame: str | None = None
    target: int | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "rotate")


@dataclass(frozen=True, kw_only=True)
class Dilate:
    """DILATE by ``factor`` about ``center``."""

    factor: float
    center: Vec | None = None
    frame: str | None = None
    target: int | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "dilate")


@dataclass(frozen=True, kw_only=True)
class Reflect:
    """REFLECT in the plane through ``point`` with normal ``normal``."""

    normal: Vec
    point: Vec | None = None
    frame: str | None = None
    target: int | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("op", "reflect")


# ----- cameras and lights --------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class LookAt:
    """A camera at ``eye`` looking at ``target``, its j axis toward ``up`` (default +z)."""

    eye: Vec
    target: Vec
    up: Vec | None = None


@dataclass(frozen=True, kw_only=True)
class Baumgart:
    """Baumgart's camera form: FOCAL and the logical (LDX × LDY) and physical rasters."""

    focal: float
    ldx: int
    ldy: int
    pdx: float
    pdy: float


@dataclass(frozen=True, kw_only=True)
class CameraSpec:
    """A camera as ``PUT /v1/cameras/{name}`` takes it.

    Exactly one of ``pose`` and ``look_at`` places it, and exactly one of
    ``intrinsics`` and ``baumgart`` describes its lens and raster.
    """

    pose: Pose | None = None
    look_at: LookAt | None = None
    intrinsics: Intrinsics | None = None
    baumgart: Baumgart | None = None


@dataclass(frozen=True, kw_only=True)
class Sun:
    """Light at infinity travelling along ``direction``."""

    direction: Vec
    intensity: float | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("type", "sun")


@dataclass(frozen=True, kw_only=True)
class PointLamp:
    """A point lamp at ``position`` (world meters)."""

    position: Vec
    intensity: float | None = None

    def _json_extra(self) -> dict[str, str]:
        return _typed("type", "point")


# ----- camera solution and perception ------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Correspondence:
    """A pixel ``[u, v]`` and what is seen there: a model ``vertex`` or a world ``point``."""

    pixel: Vec
    vertex: int | None = None
    point: Vec | None = None


@dataclass(frozen=True, kw_only=True)
class View:
    """One view for perception: a camera (name or :class:`CameraSpec`) and a silhouette.

    Give ``mask`` (non-zero pixels are the object) or ``image`` (its unexplained regions
    are the mask), each PNG bytes, base64 text or a numpy array; ``depth`` goes with
    ``image``.
    """

    camera: str | CameraSpec | dict[str, Any]
    mask: Any = None
    image: Any = None
    depth: Any = None
    depth_scale: float | None = None

    def _json_extra(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for key in ("mask", "image", "depth"):
            value = getattr(self, key)
            if value is not None:
                out[key] = encode_image(value)
        return out
