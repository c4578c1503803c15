//! KLFE: kill a face and an edge, merging two faces.

use super::EulerError;
use crate::model::body::Body;
use crate::model::ids::{EdgeId, FaceId, Side};
use crate::model::topology::EdgeUse;

impl Body {
    /// KLFE(E): kills edge `e` and its NFACE, whose perimeter joins PFACE(E)'s. Returns
    /// the surviving face PFACE(E). (To kill the PFACE instead, [`Body::invert`] first.)
    ///
    /// Preconditions (refused otherwise): `e` is live and has two different faces
    /// (removing an edge with one face on both sides would split that face's perimeter).
    ///
    /// Inverse: [`Body::mkfe`]`(PVT(E), PFACE(E), NVT(E))` makes the same topology again
    /// with new serial numbers.
    pub fn klfe(&mut self, e: EdgeId) -> Result<FaceId, EulerError> {
        self.check_edge(e)?;
        let r = *self.edge(e);
        let (fneg, fpos) = (r.face[0], r.face[1]);
        if fneg == fpos {
            return Err(EulerError::SameFaceBothSides {
                edge: self.edge_serial(e),
                face: self.face_serial(fpos),
            });
        }
        let (ep, en) = (EdgeUse::new(e, Side::P), EdgeUse::new(e, Side::N));
        let (pp, np) = (self.prev(ep), self.next(ep));
        let (pn, nn) = (self.prev(en), self.next(en));
        // The dying face's other uses join the surviving face.
        let mut u = nn;
        while u != en {
            self.edge_mut(u.edge).face[u.side.ix()] = fpos;
            u = self.next(u);
        }
        self.set_next(pp, nn);
        self.set_next(pn, np);
        if self.face(fpos).ped == e {
            self.face_mut(fpos).ped = nn.edge;
        }
        self.repoint_vertex_ped(r.vt[1], e, nn.edge);
        self.repoint_vertex_ped(r.vt[0], e, np.edge);
        self.klf(fneg);
        self.kle(e);
        Ok(fpos)
    }
}
