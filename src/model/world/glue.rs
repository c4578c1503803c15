//! GLUE and UNGLUE: joining bodies along faces or edges, and parting them.

use std::sync::Arc;

use crate::model::ids::{EdgeId, FaceId, VertexId};
use crate::model::parts::BodyId;

use super::*;

impl World {
    /// GLUE face `f1` of body `a` (from vertex `v1`) with face `f2` of body `b` (from
    /// `v2`): Baumgart's GLUE, identifying the two faces' perimeters (see
    /// [`Body::glue_bodies`]). If `a == b` this makes a handle ([`Body::glue`]).
    ///
    /// Two bodies become one: `a` survives with its node (name, supart, pose); `b`'s
    /// geometry is carried into `a`'s frame (nothing moves in the world) and keeps its
    /// serial numbers; `b`'s node is removed and its name freed; `b`'s sub-parts are
    /// re-attached to `a` keeping their world poses. If `a` was itself within `b`'s
    /// parts, it first takes `b`'s place under `b`'s supart. Ids of `b`'s faces, edges
    /// and vertices change (their serials do not): look them up again by serial.
    ///
    /// Inverse: [`World::unglue`] along the loop of `f1`'s old edges.
    ///
    /// Refused for the root, unknown bodies, or whatever GLUE refuses.
    pub fn glue(
        &mut self,
        a: BodyId,
        f1: FaceId,
        v1: VertexId,
        b: BodyId,
        f2: FaceId,
        v2: VertexId,
    ) -> Result<(), WorldError> {
        if a == b {
            return self.in_place(a, |body, _| body.glue(f1, v1, f2, v2));
        }
        self.merge(a, b, |body, other, _| {
            body.glue_bodies(f1, v1, other, f2, v2)
        })
    }

    /// GLUEE between face `f1` of `a` at vertex `v1` and face `f2` of `b` at `v2`: a new
    /// wasp edge joins the two faces into one (see [`Body::gluee_bodies`]); with `a == b`
    /// this makes a handle ([`Body::gluee`]). Returns the new edge, in `a`. The bodies'
    /// nodes are merged as [`World::glue`] merges them. Refused as GLUEE refuses.
    pub fn gluee(
        &mut self,
        a: BodyId,
        f1: FaceId,
        v1: VertexId,
        b: BodyId,
        f2: FaceId,
        v2: VertexId,
    ) -> Result<EdgeId, WorldError> {
        if a == b {
            return self.in_place(a, |body, s| body.gluee(s, f1, v1, f2, v2));
        }
        self.merge(a, b, |body, other, s| {
            body.gluee_bodies(s, f1, v1, other, f2, v2)
        })
    }

    /// GLUEFF between face `f1` of `a` and face `f2` of `b`: a tube of quadrilaterals
    /// between the two faces (see [`Body::glueff_bodies`]; with `a == b`,
    /// [`Body::glueff`]). The nearest vertex of `f2` is chosen in world coordinates.
    /// Returns the edges made, in `a`. The bodies' nodes are merged as [`World::glue`]
    /// merges them. Refused as GLUEFF refuses.
    pub fn glueff(
        &mut self,
        a: BodyId,
        f1: FaceId,
        b: BodyId,
        f2: FaceId,
    ) -> Result<Vec<EdgeId>, WorldError> {
        if a == b {
            return self.in_place(a, |body, s| body.glueff(s, f1, f2));
        }
        self.merge(a, b, |body, other, s| body.glueff_bodies(s, f1, other, f2))
    }

    /// UNGLUE body `b` along `seam`, a closed loop of its edges (see [`Body::unglue`]).
    /// If the cut separates the body, the part on the NFACE side of `seam[0]` becomes a
    /// new unnamed body (it keeps its serials; the body takes a new one) under `b`'s
    /// supart with `b`'s pose, so nothing moves; `b` keeps its name and all its
    /// sub-parts. Otherwise the cut removes a handle.
    ///
    /// Inverse: [`World::glue`] of the two new faces.
    ///
    /// Refused for the root, an unknown body, or whatever UNGLUE refuses.
    pub fn unglue(&mut self, b: BodyId, seam: &[EdgeId]) -> Result<UngluedBodies, WorldError> {
        let node = self.live_part(b, "unglued")?;
        let (supart, pose) = (node.supart, node.pose);
        let mut serials = self.serials.clone();
        let mut node = self.tree.get_mut(b).expect("checked");
        let un = cow_try(&mut node.body, |body| body.unglue(&mut serials, seam))?;
        drop(node);
        let split_off = un.split_off.map(|body| {
            let id = BodyId(serials.take());
            self.tree.add(id, None, supart, pose, Arc::new(body));
            id
        });
        self.serials = serials;
        self.written();
        Ok(UngluedBodies {
            kept_face: un.kept_face,
            new_face: un.new_face,
            split_off,
        })
    }
}
