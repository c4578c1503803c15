//! MKEV: make an edge and a vertex, as a wire or as a spur.

use glam::DVec3;

use super::EulerError;
use crate::model::body::{Body, Edge};
use crate::model::ids::{EdgeId, FaceId, Serials, Side, VertexId};
use crate::model::topology::EdgeUse;

impl Body {
    /// MKEV(F, V): a new edge ENEW from `v` to a new vertex VNEW at `pos`, placed as a
    /// spur in the corner of face `f` at `v`.
    ///
    /// * On a seminal body it makes a wire of one edge; on a wire's negative (newest)
    ///   end it extends the wire; elsewhere it makes a dangling spur into `f`.
    /// * ENEW has PVT = `v`, NVT = VNEW and `f` on both sides; PED(VNEW) = ENEW.
    ///
    /// Preconditions (refused otherwise): `f` and `v` are live; `pos` is finite; `v` is on `f` exactly
    /// once (so one spur at a vertex per face at a time, and no MKEV at a wire's inner
    /// vertices); `v` is not the positive end of a wire.
    ///
    /// Inverse: [`Body::klev`]`(VNEW)`.
    pub fn mkev(
        &mut self,
        serials: &mut Serials,
        f: FaceId,
        v: VertexId,
        pos: DVec3,
    ) -> Result<(EdgeId, VertexId), EulerError> {
        self.check_face(f)?;
        self.check_vertex(v)?;
        Self::check_locus(pos)?;
        let ped = self.vertex(v).ped;
        // The corner of `f` at `v` the spur goes into, as (incoming, outgoing) uses;
        // `None` for the lone vertex of a seminal body.
        let corner = if ped.is_none() {
            // Seminal vertex: it is on `f` only if `f` is its lone, edgeless face.
            if !self.face(f).ped.is_none() {
                return Err(EulerError::VertexNotOnFace {
                    vertex: self.vertex_serial(v),
                    face: self.face_serial(f),
                });
            }
            None
        } else {
            let out = self.corner(v, f)?;
            let r = self.edge(ped);
            // A wire is a body of one face; its positive end is a valence-one PVT.
            let valence_one_pvt = r.vt[1] == v && r.cw[1] == ped;
            if valence_one_pvt && self.face_count() == 1 {
                return Err(EulerError::WirePositiveEnd {
                    vertex: self.vertex_serial(v),
                });
            }
            Some((self.prev(out), out))
        };
        let vnew = self.mkv(serials, pos, EdgeId::NONE);
        let e = self.mke(serials, Edge::unlinked([vnew, v], [f, f]));
        let (up, un) = (EdgeUse::new(e, Side::P), EdgeUse::new(e, Side::N));
        self.set_next(up, un);
        match corner {
            Some((inc, out)) => {
                self.set_next(inc, up);
                self.set_next(un, out);
            }
            None => {
                self.set_next(un, up);
                self.vertex_mut(v).ped = e;
                self.face_mut(f).ped = e;
            }
        }
        self.vertex_mut(vnew).ped = e;
        Ok((e, vnew))
    }
}
