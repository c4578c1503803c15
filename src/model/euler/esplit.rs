//! ESPLIT: split an edge in two with a new vertex.

use glam::DVec3;

use super::EulerError;
use crate::model::body::{Body, Edge};
use crate::model::ids::{EdgeId, Serials, Side, VertexId};
use crate::model::topology::EdgeUse;

impl Body {
    /// ESPLIT(E): splits edge `e` at a new vertex VNEW placed at `pos`, making a new edge
    /// ENEW between the old PVT(E) and VNEW.
    ///
    /// Postconditions: PVT(ENEW) = old PVT(E), NVT(ENEW) = VNEW, PVT(E) = VNEW, NVT(E)
    /// unchanged; both edges keep E's two faces; PED(VNEW) = ENEW. Every face and vertex
    /// perimeter is as before with VNEW and ENEW inserted.
    ///
    /// Preconditions (refused otherwise): `e` is live, `pos` is finite. Inverse: [`Body::klev`]`(VNEW)`.
    pub fn esplit(
        &mut self,
        serials: &mut Serials,
        e: EdgeId,
        pos: DVec3,
    ) -> Result<(EdgeId, VertexId), EulerError> {
        self.check_edge(e)?;
        Self::check_locus(pos)?;
        let (ep, en) = (EdgeUse::new(e, Side::P), EdgeUse::new(e, Side::N));
        let r = *self.edge(e);
        let top = r.vt[1];
        // Neighbours of E's two uses before the split.
        let pp = self.prev(ep); // arrives at PVT, before E's P use
        let nn = self.next(en); // leaves PVT, after E's N use

        let vnew = self.mkv(serials, pos, EdgeId::NONE);
        let enew = self.mke(serials, Edge::unlinked([vnew, top], r.face));
        self.edge_mut(e).vt[1] = vnew;
        let (np, nnew) = (EdgeUse::new(enew, Side::P), EdgeUse::new(enew, Side::N));
        // E's uses at PVT now belong to ENEW.
        let pp = if pp == en { nnew } else { pp };
        let nn = if nn == ep { np } else { nn };
        self.set_next(pp, np);
        self.set_next(np, ep);
        self.set_next(en, nnew);
        self.set_next(nnew, nn);
        self.vertex_mut(vnew).ped = enew;
        if self.vertex(top).ped == e {
            self.vertex_mut(top).ped = enew;
        }
        Ok((enew, vnew))
    }
}
