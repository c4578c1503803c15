"""Every operation of the API, described once for both clients.

:class:`Operations` builds each request as a :class:`~winged._http.Call` and hands it to
``self._run``: :class:`winged.Client` runs it and answers the result,
:class:`winged.AsyncClient` answers a coroutine of it. The method names are mapped to the
spec's operation ids in :data:`OPERATIONS` (a test checks that every operation of the
spec has one).
"""

from __future__ import annotations

from typing import Any

from ._base import UNSET
from ._ops_bodies import BodyOperations
from ._ops_operators import OperatorOperations
from ._ops_spatial import SpatialOperations
from ._ops_vision import VisionOperations

__all__ = ["OPERATIONS", "UNSET", "Operations"]

#: The spec's operation ids and the client method that performs each, with the
#: arguments that select it when one method performs several.
OPERATIONS: dict[str, tuple[str, dict[str, Any]]] = {
    "health": ("health", {}),
    "ready": ("ready", {}),
    "metrics": ("metrics", {}),
    "writeSnapshot": ("write_snapshot", {}),
    "openapi": ("openapi", {}),
    "getWorld": ("world", {}),
    "changesSince": ("changes", {}),
    "changeEvents": ("events", {}),
    "exportWorld": ("export_world", {}),
    "listBodies": ("list_bodies", {}),
    "createBody": ("create_body", {}),
    "importMesh": ("import_mesh", {}),
    "getBody": ("get_body", {}),
    "patchBody": ("patch_body", {}),
    "deleteBody": ("delete_body", {}),
    "getTopology": ("topology", {}),
    "exportMesh": ("export_mesh", {}),
    "eulerOperator": ("euler", {}),
    "transformBody": ("transform", {}),
    "sweepFace": ("sweep", {}),
    "dualBody": ("dual", {}),
    "evertBody": ("evert", {}),
    "copyBody": ("copy_body", {}),
    "booleanBody": ("boolean", {}),
    "listCameras": ("list_cameras", {}),
    "getCamera": ("get_camera", {}),
    "putCamera": ("put_camera", {}),
    "deleteCamera": ("delete_camera", {}),
    "cameraImage": ("camera_image", {}),
    "appearance": ("appearance", {}),
    "cameraSolution": ("solve_camera", {}),
    "recognition": ("recognize", {}),
    "perception": ("perceive", {}),
    "spatialSphere": ("spatial_sphere", {"via": "get"}),
    "spatialSpherePost": ("spatial_sphere", {"via": "post"}),
    "spatialBox": ("spatial_box", {"via": "get"}),
    "spatialBoxPost": ("spatial_box", {"via": "post"}),
    "spatialNearest": ("spatial_nearest", {"via": "get"}),
    "spatialNearestPost": ("spatial_nearest", {"via": "post"}),
    "spatialRay": ("spatial_ray", {"via": "get"}),
    "spatialRayPost": ("spatial_ray", {"via": "post"}),
    "listLights": ("list_lights", {}),
    "getLight": ("get_light", {}),
    "putLight": ("put_light", {}),
    "deleteLight": ("delete_light", {}),
}


# ----- answer readers ----------------------------------------------------------------------


class Operations(BodyOperations, OperatorOperations, VisionOperations, SpatialOperations):
    """The API's operations; the clients differ only in how ``_run`` sends a call."""
