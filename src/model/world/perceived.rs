//! Perceived bodies in the world: inserting what perception carved, carving a
//! provisional body again, and reading its record ([`Perceived`]).

use std::sync::Arc;

use glam::DVec3;

use super::{World, WorldError, check_geometry_input};
use crate::model::body::Body;
use crate::model::parts::BodyId;
use crate::model::perceived::{Maker, Perceived};
use crate::model::pose::Pose;
use crate::model::range::MAX_BODY_FACES;
use crate::model::solids::BuildError;

/// One closed polyhedron perception made, as polygons with each face's maker.
#[derive(Clone, Copy, Debug)]
pub struct PerceivedShell<'a> {
    /// Vertex loci.
    pub positions: &'a [DVec3],
    /// Faces, rings of indices into `positions`, counter-clockwise seen from outside.
    pub faces: &'a [Vec<u32>],
    /// What made each face.
    pub makers: &'a [Maker],
    /// Views that carved it, over every request.
    pub views: u32,
    /// How far its outline may lie outside the object's (see [`Perceived::outline_px`]).
    pub outline_px: f64,
}

impl PerceivedShell<'_> {
    /// The body of these polygons, checked, numbered from `serials`.
    fn build(&self, serials: &mut crate::model::ids::Serials) -> Result<Body, WorldError> {
        if self.makers.len() != self.faces.len() {
            return Err(WorldError::Build(BuildError::NoFaces));
        }
        if self.faces.len() > MAX_BODY_FACES {
            return Err(WorldError::TooLarge {
                faces: self.faces.len(),
                max: MAX_BODY_FACES,
            });
        }
        let body = Body::from_polygons(serials, self.positions, self.faces)?;
        check_geometry_input(&body)?;
        Ok(body)
    }

    /// The record of `body`, built from these polygons (face `i` has the `i`-th least
    /// face serial).
    fn record(&self, body: &Body) -> Perceived {
        let mut serials: Vec<_> = body.faces().map(|f| body.face_serial(f)).collect();
        serials.sort_unstable();
        Perceived {
            views: self.views,
            outline_px: self.outline_px,
            makers: serials
                .into_iter()
                .zip(self.makers.iter().copied())
                .collect(),
        }
    }
}

impl World {
    /// The record of a provisional body, or `None` for an ordinary (or unknown) body.
    pub fn perceived(&self, b: BodyId) -> Option<&Perceived> {
        self.tree.get(b).and_then(|n| n.perceived.as_deref())
    }

    /// Inserts `shell` (in world coordinates) as a new provisional body under the root,
    /// with the identity pose. Refused, changing nothing, as [`World::insert_with`]
    /// refuses, or when the polygons are not a closed solid or hold too many faces.
    /// Inverse: [`World::kill`].
    pub fn insert_perceived(
        &mut self,
        name: Option<&str>,
        shell: &PerceivedShell<'_>,
    ) -> Result<BodyId, WorldError> {
        let id = self.insert_with(name, self.root(), Pose::IDENTITY, |s| shell.build(s))?;
        // The insertion may have shifted the serials; their order is kept.
        let mut node = self.tree.get_mut(id).expect("just inserted");
        let record = shell.record(&node.body);
        node.perceived = Some(Arc::new(record));
        Ok(id)
    }

    /// Replaces provisional body `b`'s polyhedron by `shell`, given in `b`'s own frame,
    /// and its record. Refused, changing nothing, when `b` is unknown or not
    /// provisional, or the polygons are not a closed solid.
    pub fn recarve_perceived(
        &mut self,
        b: BodyId,
        shell: &PerceivedShell<'_>,
    ) -> Result<(), WorldError> {
        if self.perceived(b).is_none() {
            self.live_part(b, "carved")?;
            return Err(WorldError::NotProvisional(b));
        }
        let mut serials = self.serials.clone();
        let body = shell.build(&mut serials)?;
        let record = shell.record(&body);
        self.serials = serials;
        {
            let mut node = self.tree.get_mut(b).expect("checked");
            node.body = Arc::new(body);
            node.perceived = Some(Arc::new(record));
        }
        self.written();
        Ok(())
    }
}
