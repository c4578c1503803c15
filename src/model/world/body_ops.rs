//! Operators on one body in place: Euler operators, transactions, transforms.

use std::sync::Arc;

use crate::model::body::Body;
use crate::model::check::check_topology;
use crate::model::euler::EulerError;
use crate::model::ids::{Serials, VertexId};
use crate::model::parts::{BodyId, Entity};
use crate::model::transform::{Frame, Transform, TransformError};

use super::*;

impl World {
    /// Applies one kernel operator `op` to body `b` in place, passing the world's serial
    /// counter, and returns its result.
    ///
    /// Copy-on-write: the body is cloned only if a snapshot still holds it. `op` must
    /// leave the body and the counter as they were when it returns `Err`, as every
    /// kernel operator does (each checks all its preconditions before changing
    /// anything). For a sequence of operators that may fail half-way, use
    /// [`World::transaction`].
    ///
    /// `op` must leave a valid body with every locus in the world's range (the Euler
    /// operators and sweeps refuse loci beyond it); a body split in two by UNGLUE
    /// inside `op` would be lost with its serials, so use [`World::unglue`] for that, and
    /// [`World::glue`] and its kin for gluing two bodies.
    ///
    /// Refused for the root (which has no geometry), an unknown body, or `op`'s own error.
    pub fn edit<R, E>(
        &mut self,
        b: BodyId,
        op: impl FnOnce(&mut Body, &mut Serials) -> Result<R, E>,
    ) -> Result<R, WorldError>
    where
        WorldError: From<E>,
    {
        self.live_part(b, "edited")?;
        let mut node = self.tree.get_mut(b).expect("checked");
        let body = Arc::make_mut(&mut node.body);
        let r = op(body, &mut self.serials)?;
        debug_assert!(
            check_topology(body).is_ok(),
            "edit left an invalid body: {}",
            check_topology(body)
        );
        debug_assert!(
            check_loci(body).is_ok(),
            "edit left a locus out of range: {:?}",
            check_loci(body)
        );
        drop(node);
        self.written();
        Ok(r)
    }

    /// Applies `op`, any sequence of kernel operations, to body `b` as one transaction.
    ///
    /// `op` works on a private copy of the body and of the serial counter, which replace
    /// the originals only if it succeeds and leaves every locus finite and in range; if it
    /// fails (even
    /// half-way through a sequence), the world is unchanged. The copy costs one clone of
    /// the body. The same cautions as for [`World::edit`] apply to UNGLUE and GLUE.
    ///
    /// Refused for the root, an unknown body, `op`'s own error, or a locus left
    /// non-finite or beyond the world's range.
    pub fn transaction<R, E>(
        &mut self,
        b: BodyId,
        op: impl FnOnce(&mut Body, &mut Serials) -> Result<R, E>,
    ) -> Result<R, WorldError>
    where
        WorldError: From<E>,
    {
        let node = self.live_part(b, "edited")?;
        let mut body = Body::clone(&node.body);
        let mut serials = self.serials.clone();
        let r = op(&mut body, &mut serials)?;
        check_loci(&body)?;
        debug_assert!(
            check_topology(&body).is_ok(),
            "transaction left an invalid body: {}",
            check_topology(&body)
        );
        self.serials = serials;
        self.tree.get_mut(b).expect("checked").body = Arc::new(body);
        self.written();
        Ok(r)
    }

    /// TRANSLATE, ROTATE, DILATE or REFLECT `what` (the body itself, or one of its faces,
    /// edges or vertices) of body `b`, with `t` given in `frame`.
    ///
    /// * A translation or rotation of the **body itself** changes its pose, not its
    ///   loci, so its sub-parts move with it: in [`Frame::World`] the body's world pose
    ///   becomes `T · W`; in [`Frame::Body`] (the transform's axes and centre in the
    ///   body's own coordinates, like GEOMED's `ROTATE(-J1, ...)`) it becomes `W · T`.
    /// * A dilation or reflection of the body itself changes its vertex loci (conjugated
    ///   by its world pose for [`Frame::World`]); REFLECT also everts it so it stays
    ///   outward-facing (see [`Transform::plan`]). Poses cannot scale or mirror, so its
    ///   sub-parts do not follow: they keep their poses.
    /// * A face, edge or vertex: its vertices' loci change (see [`Transform::plan`]).
    ///
    /// Inverse: the same call with [`Transform::inverse`].
    ///
    /// Refused for the root, an unknown body, bad parameters, an entity that is not live
    /// in `b`, or a result that would not be finite or would leave the world's range (a
    /// locus, or the origin of `b` or of one of its parts: see [`crate::model::range`]).
    pub fn transform(
        &mut self,
        b: BodyId,
        what: Entity,
        t: &Transform,
        frame: Frame,
    ) -> Result<(), WorldError> {
        let node = self.live_part(b, "transformed")?;
        if what == Entity::Body
            && let Some(tp) = t.to_pose()?
        {
            let rel = node.pose;
            let pose = match frame {
                Frame::Body => rel.compose(&tp),
                Frame::World => {
                    let s = self.tree.world_pose(node.supart).expect("supart is live");
                    s.inverse().compose(&tp).compose(&s).compose(&rel)
                }
            };
            if !pose.is_finite() {
                return Err(TransformError::NonFiniteResult.into());
            }
            self.check_placement(b, node.supart, &pose)?;
            self.tree.get_mut(b).expect("checked").pose = pose;
        } else {
            let w = self.tree.world_pose(b).expect("b is live");
            let moves = t.plan(&node.body, what, frame, &w)?;
            let mut node = self.tree.get_mut(b).expect("checked");
            moves.apply(Arc::make_mut(&mut node.body));
        }
        self.written();
        Ok(())
    }

    /// A kernel operation on one body that refuses without changing it (every Euler
    /// operator does): applied in place, copying the body first only if a snapshot
    /// shares it.
    pub(super) fn in_place<R>(
        &mut self,
        b: BodyId,
        op: impl FnOnce(&mut Body, &mut Serials) -> Result<R, EulerError>,
    ) -> Result<R, WorldError> {
        self.live_part(b, "glued")?;
        let mut serials = self.serials.clone();
        let mut node = self.tree.get_mut(b).expect("checked");
        let r = cow_try(&mut node.body, |body| op(body, &mut serials))?;
        drop(node);
        self.serials = serials;
        self.written();
        Ok(r)
    }

    /// Runs a two-body gluing operator with `a` surviving and `b` absorbed, then merges
    /// their nodes (see [`World::glue`]). Preconditions: `a != b`.
    pub(super) fn merge<R>(
        &mut self,
        a: BodyId,
        b: BodyId,
        op: impl FnOnce(&mut Body, &mut Body, &mut Serials) -> Result<R, EulerError>,
    ) -> Result<R, WorldError> {
        self.live_part(a, "glued")?;
        let nb = self.live_part(b, "glued")?;
        let wa = self.tree.world_pose(a).expect("a is live");
        let wb = self.tree.world_pose(b).expect("b is live");
        // Carry b's loci into a's frame.
        let to_a = wa.inverse().compose(&wb);
        let mut other = Body::clone(&nb.body);
        let vs: Vec<VertexId> = other.vertices().collect();
        for v in vs {
            let p = to_a.transform_point(other.position(v));
            other.set_position(v, p);
        }
        check_loci(&other)?;
        let mut serials = self.serials.clone();
        let mut node = self.tree.get_mut(a).expect("checked");
        let r = cow_try(&mut node.body, |body| op(body, &mut other, &mut serials))?;
        drop(node);
        self.serials = serials;
        // The parts tree: a takes b's place if it was within b, then adopts b's parts.
        if self.tree.is_within(a, b) {
            let sb = self.tree.supart(b).expect("b is live");
            self.relink_in_place(a, sb);
        }
        let parts: Vec<BodyId> = self
            .tree
            .parts(b)
            .expect("b is live")
            .iter()
            .copied()
            .collect();
        for p in parts {
            self.relink_in_place(p, a);
        }
        let removed = self.tree.remove_subtree(b);
        debug_assert_eq!(removed.len(), 1);
        self.written();
        Ok(r)
    }
}
