"""Typed answers of the winged API.

Each dataclass mirrors a schema of ``proto/openapi.yaml`` and keeps its field names.
They are built with :func:`winged._json.from_json`: members a newer server adds are
ignored, and members the spec marks optional default to ``None``. Vectors are tuples
(``(x, y, z)``), poses :class:`Pose`, ids and counts ``int``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

Vec2 = tuple[float, ...]
Vec3 = tuple[float, ...]


# ----- service ---------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Health:
    """``GET /healthz``: the server is up; the world's revision."""

    status: str
    revision: int


@dataclass(frozen=True, kw_only=True)
class Ready:
    """``GET /readyz``: the world answers promptly and its storage works."""

    status: str
    revision: int
    queue: int


@dataclass(frozen=True, kw_only=True)
class Checkpoint:
    """``POST /v1/admin/snapshot``: the snapshot file written."""

    revision: int
    path: str
    bytes: int
    seconds: float


# ----- world -------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class WorldSummary:
    """``GET /v1/world``: counts at one revision (bodies not counting the world body)."""

    revision: int
    bodies: int
    faces: int
    edges: int
    vertices: int
    cameras: int
    lights: int


@dataclass(frozen=True, kw_only=True)
class EntityChange:
    """One body, camera or light a write added, updated or removed."""

    action: str
    kind: str
    id: int | None = None
    name: str | None = None
    fields: list[str] | None = None


@dataclass(frozen=True, kw_only=True)
class Change:
    """What one applied write changed, with the revision it made."""

    revision: int
    edit: str
    changes: list[EntityChange]


@dataclass(frozen=True, kw_only=True)
class Changes:
    """``GET /v1/world/changes``: the changes after ``since``, or a request to resync."""

    since: int
    revision: int
    resync: bool
    more: bool
    changes: list[Change]
    oldest: int | None = None


# ----- bodies ------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Pose:
    """A placement: ``position`` (meters) and ``rotation`` (unit quaternion ``[qx, qy, qz, qw]``)."""

    position: Vec3 = (0.0, 0.0, 0.0)
    rotation: tuple[float, ...] = (0.0, 0.0, 0.0, 1.0)


@dataclass(frozen=True, kw_only=True)
class EulerCounts:
    """Faces, edges, vertices and handles of a body."""

    F: int
    E: int
    V: int
    H: int


@dataclass(frozen=True, kw_only=True)
class Bounds:
    """Axis-aligned bounds in the body's own frame, meters."""

    min: Vec3
    max: Vec3


@dataclass(frozen=True, kw_only=True)
class BodySummary:
    """A body as listed by ``GET /v1/bodies``."""

    id: int
    name: str | None
    parent: int
    parts: list[int]
    pose: Pose
    world_pose: Pose
    color: str
    euler: EulerCounts
    volume: float
    area: float
    bounds: Bounds | None
    provisional: bool | None = None
    views: int | None = None


@dataclass(frozen=True, kw_only=True)
class Body(BodySummary):
    """``GET /v1/bodies/{id}``: the body's summary and the revision read."""

    revision: int


@dataclass(frozen=True, kw_only=True)
class BodyList:
    """``GET /v1/bodies``: the bodies in id order and the revision read."""

    bodies: list[BodySummary]
    revision: int

    def __iter__(self) -> Any:
        return iter(self.bodies)

    def __len__(self) -> int:
        return len(self.bodies)


@dataclass(frozen=True, kw_only=True)
class Maker:
    """What made a face of a provisional body."""

    kind: str
    view: int | None = None
    ring: int | None = None
    edge: int | None = None


@dataclass(frozen=True, kw_only=True)
class TopoVertex:
    """A vertex: its locus (body frame) and PED (``None`` for a vertex without edges)."""

    id: int
    position: Vec3
    ped: int | None = None


@dataclass(frozen=True, kw_only=True)
class TopoEdge:
    """An edge and Baumgart's eight links."""

    id: int
    nvt: int
    pvt: int
    nface: int
    pface: int
    ncw: int
    pcw: int
    nccw: int
    pccw: int


@dataclass(frozen=True, kw_only=True)
class TopoFace:
    """A face: its PED, plane ``[a, b, c, d]`` and perimeter, counter-clockwise from outside."""

    id: int
    vertices: list[int]
    ped: int | None = None
    plane: tuple[float, ...] | None = None
    made_by: Maker | None = None


@dataclass(frozen=True, kw_only=True)
class Topology:
    """``GET /v1/bodies/{id}/topology``: the winged-edge structure of one body."""

    id: int
    revision: int
    vertices: list[TopoVertex]
    edges: list[TopoEdge]
    faces: list[TopoFace]


# ----- write answers -----------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class ImportedBody:
    """One body a mesh file made."""

    id: int
    parent: int
    faces: int
    edges: int
    vertices: int
    volume: float
    object: int
    faces_read: int
    unmerged: int
    name: str | None = None


@dataclass(frozen=True, kw_only=True)
class Created:
    """A body made (create, copy); for a ``seminal`` body also its ``face`` and ``vertex``."""

    id: int
    faces: int
    edges: int
    vertices: int
    revision: int
    face: int | None = None
    vertex: int | None = None
    bodies: list[ImportedBody] | None = None


@dataclass(frozen=True, kw_only=True)
class Imported:
    """``POST /v1/bodies/import``: the bodies a mesh file made; ``id`` is the first's."""

    id: int
    faces: int
    edges: int
    vertices: int
    bodies: list[ImportedBody]
    revision: int


@dataclass(frozen=True, kw_only=True)
class EulerResult:
    """What an Euler operator made or left, and the body's new counts."""

    id: int
    faces: int
    edges: int
    vertices: int
    revision: int
    face: int | None = None
    edge: int | None = None
    vertex: int | None = None
    new_edges: list[int] | None = None
    new_face: int | None = None
    split_off: int | None = None
    killed: list[int] | None = None


@dataclass(frozen=True, kw_only=True)
class Reshaped:
    """A body whose faces, edges and vertices changed (sweep, dual); a sweep's cap ``face``."""

    id: int
    faces: int
    edges: int
    vertices: int
    revision: int
    face: int | None = None


@dataclass(frozen=True, kw_only=True)
class BooleanPiece:
    """One body of a boolean's result; ``sources`` are ``[face, from body, from face]``."""

    id: int
    faces: int
    edges: int
    vertices: int
    volume: float
    sources: list[tuple[int, ...]]


@dataclass(frozen=True, kw_only=True)
class BooleanResult:
    """What a boolean left: the pieces (the body asked of first) and the bodies killed."""

    id: int
    pieces: list[BooleanPiece]
    killed: list[int]
    revision: int


@dataclass(frozen=True, kw_only=True)
class Changed:
    """A body changed (patch, transform, evert) and the revision."""

    id: int
    revision: int


@dataclass(frozen=True, kw_only=True)
class Killed:
    """The bodies killed (the one named and its parts) and the revision."""

    killed: list[int]
    revision: int


@dataclass(frozen=True, kw_only=True)
class RevisionOnly:
    """A camera or light write's answer."""

    revision: int


# ----- cameras and lights ----------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Intrinsics:
    """Pinhole intrinsics in pixels, from the top-left pixel's corner, u right, v down."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float


@dataclass(frozen=True, kw_only=True)
class Camera:
    """A stored camera (Baumgart's frame; it looks along −k, ``view_direction``)."""

    name: str
    pose: Pose
    intrinsics: Intrinsics
    view_direction: Vec3


@dataclass(frozen=True, kw_only=True)
class CameraList:
    """``GET /v1/cameras``: every camera in name order."""

    cameras: list[Camera]
    revision: int

    def __iter__(self) -> Any:
        return iter(self.cameras)

    def __len__(self) -> int:
        return len(self.cameras)


@dataclass(frozen=True, kw_only=True)
class NamedLight:
    """A stored light: a ``sun`` (with ``direction``) or a ``point`` lamp (with ``position``)."""

    type: str
    name: str
    intensity: float
    direction: Vec3 | None = None
    position: Vec3 | None = None


@dataclass(frozen=True, kw_only=True)
class LightList:
    """``GET /v1/lights``: every light in name order."""

    lights: list[NamedLight]
    revision: int

    def __iter__(self) -> Any:
        return iter(self.lights)

    def __len__(self) -> int:
        return len(self.lights)


# ----- appearance --------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class HiddenSegment:
    """A visible portion of an edge, in pixels, with its depths at ``a`` and ``b``."""

    body: int
    edge: int
    a: Vec2
    b: Vec2
    depth: Vec2


@dataclass(frozen=True, kw_only=True)
class HiddenLines:
    """The exact hidden-line drawing as segments (``mode="hidden"``, ``format="json"``)."""

    revision: int
    width: int
    height: int
    segments: list[HiddenSegment]


@dataclass(frozen=True, kw_only=True)
class IdsLegendBody:
    """A body an ids image shows: its pixel value, id, name, pixel count and box."""

    value: int
    id: int
    pixels: int
    bbox: tuple[int, ...]
    name: str | None = None


@dataclass(frozen=True, kw_only=True)
class IdsLegend:
    """The bodies an ids image shows (``mode="ids"``, ``format="json"``)."""

    revision: int
    width: int
    height: int
    bodies: list[IdsLegendBody]


class Png(bytes):
    """A PNG the server drew: the file's bytes, with what its headers said.

    Attributes:
        revision: the world revision drawn (from ``ETag``).
        depth_scale: ``depth`` images: meters per unit of the pixel values.
        body_ids: ``ids`` images: pixel value → body id (``None`` when not sent).
    """

    revision: int | None
    depth_scale: float | None
    body_ids: dict[int, int] | None

    def __new__(
        cls,
        data: bytes,
        revision: int | None = None,
        depth_scale: float | None = None,
        body_ids: dict[int, int] | None = None,
    ) -> Png:
        self = super().__new__(cls, data)
        self.revision = revision
        self.depth_scale = depth_scale
        self.body_ids = body_ids
        return self

    def to_array(self) -> Any:
        """The image as a numpy array (needs the ``numpy`` extra: numpy and Pillow)."""
        from ._images import png_to_array

        return png_to_array(bytes(self))


# ----- camera solution -------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class SolvedCamera:
    """A solved camera: its pose in the world, its intrinsics and view direction."""

    pose: Pose
    intrinsics: Intrinsics
    view_direction: Vec3


@dataclass(frozen=True, kw_only=True)
class OpenCvCamera:
    """The camera in OpenCV's convention: ``rvec``, ``tvec`` and the camera matrix by rows."""

    rvec: Vec3
    tvec: Vec3
    camera_matrix: list[tuple[float, ...]]


@dataclass(frozen=True, kw_only=True)
class EdgeAlignment:
    """From a picture: the points sampled on the model's edges and the fraction on picture edges."""

    samples: int
    inlier_fraction: float


@dataclass(frozen=True, kw_only=True)
class SolveIterations:
    """RANSAC samples drawn and Levenberg–Marquardt iterations."""

    refine: int
    ransac: int | None = None


@dataclass(frozen=True, kw_only=True)
class Focal:
    """The solved focal length (``solve_focal``)."""

    fx: float
    fy: float
    fx_std: float


@dataclass(frozen=True, kw_only=True)
class CameraSolution:
    """``POST /v1/camera-solution``: the camera, in the world's and OpenCV's conventions."""

    camera: SolvedCamera
    opencv: OpenCvCamera
    rms_px: float
    iterations: SolveIterations
    revision: int
    inliers: list[int] | None = None
    edges: EdgeAlignment | None = None
    correspondences: int | None = None
    confident: bool | None = None
    focal: Focal | None = None
    stored_as: str | None = None


# ----- recognition -----------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class RecognitionCamera:
    """The camera recognition used (aligned with the picture first when ``refined``)."""

    pose: Pose
    intrinsics: Intrinsics
    refined: bool


@dataclass(frozen=True, kw_only=True)
class Evidence:
    """How a body's predicted edges (and depth) agree with the picture."""

    edge_support: float
    edge_points: int
    depth_agreement: float | None = None


@dataclass(frozen=True, kw_only=True)
class RecognizedBody:
    """A body in view: ``seen``, ``moved``, ``absent`` or ``occluded``."""

    id: int
    status: str
    score: float
    visible_fraction: float
    pose: Pose
    evidence: Evidence
    name: str | None = None
    bbox: tuple[float, ...] | None = None


@dataclass(frozen=True, kw_only=True)
class UnexplainedRegion:
    """A region of the picture no modeled body explains, in pixels."""

    outline: list[Vec2]
    area: float
    bbox: tuple[float, ...]
    holes: list[list[Vec2]] | None = None


@dataclass(frozen=True, kw_only=True)
class Recognition:
    """``POST /v1/recognition``: what a picture shows of the model, and what it lacks."""

    revision: int
    camera: RecognitionCamera
    bodies: list[RecognizedBody]
    unexplained: list[UnexplainedRegion]
    elapsed_ms: float
    unexplained_mask: str | None = None
    updated_revision: int | None = None

    def unexplained_mask_png(self) -> bytes | None:
        """The unexplained regions as PNG bytes (with ``unexplained_mask=True``)."""
        import base64

        return base64.b64decode(self.unexplained_mask) if self.unexplained_mask else None


# ----- perception ------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class PerceivedBody:
    """A provisional body perception made or carved."""

    id: int
    volume: float
    faces: int
    views: int
    name: str | None = None


@dataclass(frozen=True, kw_only=True)
class Carvings:
    """Carvings made in the image and by the boolean; pieces left ``uncarved``."""

    image: int
    boolean: int
    uncarved: int


@dataclass(frozen=True, kw_only=True)
class Perception:
    """``POST /v1/perception``: what was inserted, carved and removed."""

    inserted: list[PerceivedBody]
    carved: list[PerceivedBody]
    removed: list[int]
    revision: int
    carvings: Carvings
    elapsed_ms: float


# ----- spatial ---------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class FaceHit:
    """A face that meets the region (``portion``: its part inside, at ``portions`` detail)."""

    id: int
    distance: float | None = None
    portion: list[list[Vec3]] | None = None


@dataclass(frozen=True, kw_only=True)
class EdgeHit:
    """The part of an edge inside the region."""

    id: int
    segment: list[Vec3]


@dataclass(frozen=True, kw_only=True)
class VertexHit:
    """A vertex inside the region."""

    id: int
    position: Vec3


@dataclass(frozen=True, kw_only=True)
class BodyHit:
    """A body that reaches into the region."""

    id: int
    inside: bool
    name: str | None = None
    distance: float | None = None
    faces: list[FaceHit] | None = None
    edges: list[EdgeHit] | None = None
    vertices: list[VertexHit] | None = None


@dataclass(frozen=True, kw_only=True)
class SphereAnswer:
    """The bodies within a radius of a point, nearest first."""

    revision: int
    center: Vec3
    radius: float
    detail: str
    bodies: list[BodyHit]
    tolerance: float | None = None


@dataclass(frozen=True, kw_only=True)
class BoxAnswer:
    """The bodies inside an axis-aligned box, by id."""

    revision: int
    min: Vec3
    max: Vec3
    detail: str
    bodies: list[BodyHit]


@dataclass(frozen=True, kw_only=True)
class NearestHit:
    """The body nearest a point: distances, the closest surface point and its face."""

    id: int
    distance: float
    inside: bool
    surface_distance: float
    point: Vec3
    face: int
    name: str | None = None


@dataclass(frozen=True, kw_only=True)
class NearestAnswer:
    """The nearest body, or ``hit`` ``None``."""

    revision: int
    hit: NearestHit | None = None


@dataclass(frozen=True, kw_only=True)
class RayHit:
    """The first surface along a ray."""

    id: int
    face: int
    point: Vec3
    distance: float
    normal: Vec3
    entering: bool
    name: str | None = None


@dataclass(frozen=True, kw_only=True)
class RayAnswer:
    """The first surface along a ray, or ``hit`` ``None``."""

    revision: int
    hit: RayHit | None = None


# ----- events ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Event:
    """One server-sent event of ``GET /v1/world/events``.

    Attributes:
        event: ``change`` or ``resync``.
        id: the revision (for ``change``), as the ``id:`` line gave it.
        data: the event's data, as sent (JSON text).
        change: for ``change``, the data as a :class:`Change`.
        resync: for ``resync``, the data as a dict (how far the history reaches).
    """

    event: str
    data: str
    id: str | None = None
    change: Change | None = None
    resync: dict[str, Any] | None = field(default=None)

    @property
    def revision(self) -> int | None:
        """The revision this event carries (``change``), if any."""
        if self.change is not None:
            return self.change.revision
        if self.id is not None and self.id.isdigit():
            return int(self.id)
        return None
