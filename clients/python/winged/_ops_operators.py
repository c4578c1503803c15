"""Euler operators, transforms, sweeps, dual, evert, copy and booleans."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ._base import Base, Vec, drop_none, model_reader, vec3
from ._http import Call, if_match, path_segment
from ._json import to_json
from .models import BooleanResult, Changed, Created, EulerResult, Reshaped
from .requests import (
    Dilate,
    Esplit,
    Glue,
    Gluee,
    Glueff,
    Invert,
    Klev,
    Klfe,
    Klve,
    Mkev,
    Mkfe,
    Reflect,
    Rotate,
    Translate,
    Unglue,
)


class OperatorOperations(Base):
    """Euler operators, transforms, sweeps, dual, evert, copy and booleans."""

    # ----- operators -------------------------------------------------------------------

    def euler(self, id: int, op: Any, *, expected_revision: int | None = None) -> EulerResult:
        """``POST /v1/bodies/{id}/euler``: apply one Euler operator (:class:`~winged.Mkev`, ...).

        A refused operator raises :class:`~winged.Unprocessable` (``euler-refused``) and
        leaves the body as it was.
        """
        return self._run(
            Call(
                "POST",
                f"/v1/bodies/{path_segment(id)}/euler",
                model_reader(EulerResult),
                json=to_json(op),
                headers=if_match(expected_revision),
                write=True,
            )
        )

    def mkev(
        self, id: int, face: int, vertex: int, position: Vec | None = None, *, expected_revision: int | None = None
    ) -> EulerResult:
        """MKEV: a spur edge from ``vertex`` into ``face``; answers the new ``edge`` and ``vertex``."""
        return self.euler(id, Mkev(face=face, vertex=vertex, position=position), expected_revision=expected_revision)

    def mkfe(self, id: int, v1: int, face: int, v2: int, *, expected_revision: int | None = None) -> EulerResult:
        """MKFE: split ``face`` by an edge from ``v1`` to ``v2``; answers the new ``edge`` and ``face``."""
        return self.euler(id, Mkfe(v1=v1, face=face, v2=v2), expected_revision=expected_revision)

    def esplit(
        self, id: int, edge: int, position: Vec | None = None, *, expected_revision: int | None = None
    ) -> EulerResult:
        """ESPLIT: split ``edge`` with a new vertex (at ``position``, default the midpoint)."""
        return self.euler(id, Esplit(edge=edge, position=position), expected_revision=expected_revision)

    def klfe(self, id: int, edge: int, *, expected_revision: int | None = None) -> EulerResult:
        """KLFE: kill ``edge`` and its NFACE; answers the surviving ``face``."""
        return self.euler(id, Klfe(edge=edge), expected_revision=expected_revision)

    def klev(self, id: int, vertex: int, *, expected_revision: int | None = None) -> EulerResult:
        """KLEV: kill ``vertex`` (one or two edges) and its PED; answers the surviving ``vertex``."""
        return self.euler(id, Klev(vertex=vertex), expected_revision=expected_revision)

    def klve(self, id: int, edge: int, *, expected_revision: int | None = None) -> EulerResult:
        """KLVE: contract ``edge``, killing it and its NVT; answers the surviving ``vertex``."""
        return self.euler(id, Klve(edge=edge), expected_revision=expected_revision)

    def invert(self, id: int, edge: int, *, expected_revision: int | None = None) -> EulerResult:
        """INVERT: turn ``edge`` round (swap its N and P sides)."""
        return self.euler(id, Invert(edge=edge), expected_revision=expected_revision)

    def glue(
        self,
        id: int,
        face1: int,
        face2: int,
        vertex1: int | None = None,
        vertex2: int | None = None,
        *,
        expected_revision: int | None = None,
    ) -> EulerResult:
        """GLUE: identify ``face2`` (of this or another body) with ``face1``."""
        op = Glue(face1=face1, face2=face2, vertex1=vertex1, vertex2=vertex2)
        return self.euler(id, op, expected_revision=expected_revision)

    def gluee(
        self,
        id: int,
        face1: int,
        vertex1: int,
        face2: int,
        vertex2: int,
        *,
        expected_revision: int | None = None,
    ) -> EulerResult:
        """GLUEE: a wasp edge from ``vertex1`` on ``face1`` to ``vertex2`` on ``face2``."""
        op = Gluee(face1=face1, vertex1=vertex1, face2=face2, vertex2=vertex2)
        return self.euler(id, op, expected_revision=expected_revision)

    def glueff(self, id: int, face1: int, face2: int, *, expected_revision: int | None = None) -> EulerResult:
        """GLUEFF: join ``face1`` and ``face2`` by a tube; answers the tube's ``new_edges``."""
        return self.euler(id, Glueff(face1=face1, face2=face2), expected_revision=expected_revision)

    def unglue(self, id: int, edges: Sequence[int], *, expected_revision: int | None = None) -> EulerResult:
        """UNGLUE: cut the body along the closed loop of ``edges``."""
        return self.euler(id, Unglue(edges=list(edges)), expected_revision=expected_revision)

    def transform(self, id: int, op: Any, *, expected_revision: int | None = None) -> Changed:
        """``POST /v1/bodies/{id}/transform``: :class:`~winged.Translate`, :class:`~winged.Rotate`,
        :class:`~winged.Dilate` or :class:`~winged.Reflect` the body (or one of its entities)."""
        return self._run(
            Call(
                "POST",
                f"/v1/bodies/{path_segment(id)}/transform",
                model_reader(Changed),
                json=to_json(op),
                headers=if_match(expected_revision),
                write=True,
            )
        )

    def translate(
        self,
        id: int,
        vector: Vec,
        *,
        frame: str | None = None,
        target: int | None = None,
        expected_revision: int | None = None,
    ) -> Changed:
        """TRANSLATE the body (its pose) or ``target`` entity by ``vector``."""
        op = Translate(vector=vec3(vector), frame=frame, target=target)
        return self.transform(id, op, expected_revision=expected_revision)

    def rotate(
        self,
        id: int,
        axis: Vec,
        angle_deg: float,
        *,
        center: Vec | None = None,
        frame: str | None = None,
        target: int | None = None,
        expected_revision: int | None = None,
    ) -> Changed:
        """ROTATE by ``angle_deg`` (right-hand rule) about ``axis`` through ``center``."""
        op = Rotate(axis=vec3(axis), angle_deg=angle_deg, center=center, frame=frame, target=target)
        return self.transform(id, op, expected_revision=expected_revision)

    def dilate(
        self,
        id: int,
        factor: float,
        *,
        center: Vec | None = None,
        frame: str | None = None,
        target: int | None = None,
        expected_revision: int | None = None,
    ) -> Changed:
        """DILATE the body's loci (or ``target``'s) by ``factor`` about ``center``."""
        op = Dilate(factor=factor, center=center, frame=frame, target=target)
        return self.transform(id, op, expected_revision=expected_revision)

    def reflect(
        self,
        id: int,
        normal: Vec,
        *,
        point: Vec | None = None,
        frame: str | None = None,
        target: int | None = None,
        expected_revision: int | None = None,
    ) -> Changed:
        """REFLECT in the plane through ``point`` with normal ``normal`` (the body is everted too)."""
        op = Reflect(normal=vec3(normal), point=point, frame=frame, target=target)
        return self.transform(id, op, expected_revision=expected_revision)

    def sweep(
        self,
        id: int,
        face: int,
        kind: str = "prism",
        *,
        distance: float | None = None,
        offset: Vec | None = None,
        peak: Vec | None = None,
        scale: float | None = None,
        expected_revision: int | None = None,
    ) -> Reshaped:
        """``POST /v1/bodies/{id}/sweep``: sweep ``face`` as a ``prism``, ``pyramid``,
        ``cw_prismoid`` or ``ccw_prismoid``; the answer's ``face`` is the cap."""
        body = drop_none(
            {"face": face, "kind": kind, "distance": distance, "offset": offset, "peak": peak, "scale": scale}
        )
        return self._run(
            Call(
                "POST",
                f"/v1/bodies/{path_segment(id)}/sweep",
                model_reader(Reshaped),
                json=body,
                headers=if_match(expected_revision),
                write=True,
            )
        )

    def dual(self, id: int, *, expected_revision: int | None = None) -> Reshaped:
        """``POST /v1/bodies/{id}/dual``: replace the body by its face-vertex dual (FVDUAL)."""
        return self._run(
            Call(
                "POST",
                f"/v1/bodies/{path_segment(id)}/dual",
                model_reader(Reshaped),
                headers=if_match(expected_revision),
                write=True,
            )
        )

    def evert(self, id: int, *, expected_revision: int | None = None) -> Changed:
        """``POST /v1/bodies/{id}/evert``: turn the body inside out (EVERT)."""
        return self._run(
            Call(
                "POST",
                f"/v1/bodies/{path_segment(id)}/evert",
                model_reader(Changed),
                headers=if_match(expected_revision),
                write=True,
            )
        )

    def copy_body(
        self,
        id: int,
        name: str | None = None,
        *,
        expected_revision: int | None = None,
    ) -> Created:
        """``POST /v1/bodies/{id}/copy``: copy a body (MKCOPY), named ``name`` if given."""
        return self._run(
            Call(
                "POST",
                f"/v1/bodies/{path_segment(id)}/copy",
                model_reader(Created),
                json={"name": name} if name is not None else None,
                headers=if_match(expected_revision),
                write=True,
            )
        )

    def boolean(
        self,
        id: int,
        op: str,
        with_: int,
        *,
        keep_with: bool | None = None,
        expected_revision: int | None = None,
    ) -> BooleanResult:
        """``POST /v1/bodies/{id}/boolean``: ``intersection``, ``union`` or ``difference``
        with body ``with_`` (killed unless ``keep_with``); the result replaces this body."""
        body = drop_none({"op": op, "with": with_, "keep_with": keep_with})
        return self._run(
            Call(
                "POST",
                f"/v1/bodies/{path_segment(id)}/boolean",
                model_reader(BooleanResult),
                json=body,
                headers=if_match(expected_revision),
                write=True,
            )
        )
