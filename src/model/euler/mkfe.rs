//! MKFE: make a face and an edge, splitting a face.

use super::EulerError;
use crate::model::body::{Body, Edge};
use crate::model::ids::{EdgeId, FaceId, Serials, Side, VertexId};
use crate::model::topology::EdgeUse;

impl Body {
    /// MKFE(V1, F, V2): splits face `f` by a new edge ENEW from `v1` to `v2`, making a
    /// new face FNEW on the clockwise side of the line V1→V2 and leaving `f` on the
    /// counter-clockwise side.
    ///
    /// Postconditions: PVT(ENEW) = `v1`, NVT(ENEW) = `v2`, PFACE(ENEW) = `f`,
    /// NFACE(ENEW) = FNEW, and PED(`f`) = PED(FNEW) = ENEW. FNEW's perimeter is the part
    /// of `f`'s old perimeter from `v1` counter-clockwise to `v2`, closed by ENEW. Closing
    /// a wire's two ends makes a lamina whose FNEW faces the side from which the wire's
    /// vertices, in the order they were made, run counter-clockwise.
    ///
    /// Preconditions (refused otherwise): all three live; `v1` ≠ `v2`; each vertex is on
    /// `f`'s perimeter exactly once.
    ///
    /// Inverse: [`Body::klfe`]`(ENEW)`, which kills FNEW.
    pub fn mkfe(
        &mut self,
        serials: &mut Serials,
        v1: VertexId,
        f: FaceId,
        v2: VertexId,
    ) -> Result<(EdgeId, FaceId), EulerError> {
        self.check_face(f)?;
        self.check_vertex(v1)?;
        self.check_vertex(v2)?;
        if v1 == v2 {
            return Err(EulerError::SameVertex {
                vertex: self.vertex_serial(v1),
            });
        }
        let (o1, o2) = self.two_corners(f, v1, v2)?;
        let i1 = self.prev(o1);
        let i2 = self.prev(o2);

        let fnew = self.mkf(serials, EdgeId::NONE);
        let e = self.mke(serials, Edge::unlinked([v2, v1], [fnew, f]));
        // The run o1 .. i2 of the old perimeter goes to the new face.
        let mut u = o1;
        loop {
            self.edge_mut(u.edge).face[u.side.ix()] = fnew;
            if u == i2 {
                break;
            }
            u = self.next(u);
        }
        let (up, un) = (EdgeUse::new(e, Side::P), EdgeUse::new(e, Side::N));
        self.set_next(i1, up);
        self.set_next(up, o2);
        self.set_next(i2, un);
        self.set_next(un, o1);
        self.face_mut(f).ped = e;
        self.face_mut(fnew).ped = e;
        Ok((e, fnew))
    }

    /// The corners of face `f` at `v1` and at `v2` (the uses leaving each), found in one
    /// walk of `f`'s perimeter; refused unless each vertex is on `f` exactly once.
    fn two_corners(
        &self,
        f: FaceId,
        v1: VertexId,
        v2: VertexId,
    ) -> Result<(EdgeUse, EdgeUse), EulerError> {
        let (mut c1, mut c2) = ((None, 0), (None, 0));
        for u in self.face_uses(f) {
            let o = self.origin(u);
            if o == v1 {
                c1 = (Some(u), c1.1 + 1);
            } else if o == v2 {
                c2 = (Some(u), c2.1 + 1);
            }
        }
        let pick = |(u, n): (Option<EdgeUse>, usize), v: VertexId| match (u, n) {
            (Some(u), 1) => Ok(u),
            (None, _) => Err(EulerError::VertexNotOnFace {
                vertex: self.vertex_serial(v),
                face: self.face_serial(f),
            }),
            (Some(_), corners) => Err(EulerError::AmbiguousCorner {
                vertex: self.vertex_serial(v),
                face: self.face_serial(f),
                corners,
            }),
        };
        Ok((pick(c1, v1)?, pick(c2, v2)?))
    }
}
