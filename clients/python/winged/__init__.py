"""Python client of winged, a networked world model of Baumgart's winged-edge polyhedra.

::

    import winged

    with winged.Client("http://127.0.0.1:7878") as client:
        cube = client.create_body(winged.Box(size=[2, 2, 2]), name="block")
        print(client.get_body(cube.id).euler)

:class:`Client` blocks; :class:`AsyncClient` has the same methods as coroutines.
Answers are the dataclasses of :mod:`winged.models`; requests take the dataclasses of
:mod:`winged.requests` (or plain dicts); refusals raise :class:`WingedError` subclasses.
"""

from . import models, requests
from ._api import OPERATIONS, UNSET
from ._http import RetryPolicy
from .aio import AsyncClient
from .client import Client
from .errors import (
    BadRequest,
    Conflict,
    Forbidden,
    HeaderTooLarge,
    InternalError,
    NameTaken,
    NotFound,
    PreconditionFailed,
    ProtocolError,
    ServerError,
    TooLarge,
    Unauthorized,
    Unavailable,
    Unprocessable,
    UnsupportedMediaType,
    WingedError,
)
from .events import AsyncEventStream, EventStream
from .models import Event, Intrinsics, Png, Pose
from .requests import (
    Baumgart,
    Box,
    CameraSpec,
    Cone,
    Correspondence,
    Cylinder,
    Dilate,
    Esplit,
    Glue,
    Gluee,
    Glueff,
    Invert,
    Klev,
    Klfe,
    Klve,
    LookAt,
    Mesh,
    Mkev,
    Mkfe,
    PointLamp,
    Polyhedron,
    Prism,
    Pyramid,
    Reflect,
    Rotate,
    Seminal,
    Sphere,
    Sun,
    Tetrahedron,
    Torus,
    Translate,
    Unglue,
    View,
)

__version__ = "0.1.0"

__all__ = [
    "OPERATIONS",
    "UNSET",
    "AsyncClient",
    "AsyncEventStream",
    "BadRequest",
    "Baumgart",
    "Box",
    "CameraSpec",
    "Client",
    "Cone",
    "Conflict",
    "Correspondence",
    "Cylinder",
    "Dilate",
    "Esplit",
    "Event",
    "EventStream",
    "Forbidden",
    "Glue",
    "Gluee",
    "Glueff",
    "HeaderTooLarge",
    "InternalError",
    "Intrinsics",
    "Invert",
    "Klev",
    "Klfe",
    "Klve",
    "LookAt",
    "Mesh",
    "Mkev",
    "Mkfe",
    "NameTaken",
    "NotFound",
    "Png",
    "PointLamp",
    "Polyhedron",
    "Pose",
    "PreconditionFailed",
    "Prism",
    "ProtocolError",
    "Pyramid",
    "Reflect",
    "RetryPolicy",
    "Rotate",
    "Seminal",
    "ServerError",
    "Sphere",
    "Sun",
    "Tetrahedron",
    "TooLarge",
    "Torus",
    "Translate",
    "Unauthorized",
    "Unavailable",
    "Unglue",
    "Unprocessable",
    "UnsupportedMediaType",
    "View",
    "WingedError",
    "models",
    "requests",
]
