//! Putting bodies into the world: MKBFV, whole bodies, and the checks they pass.

use std::sync::Arc;

use glam::DVec3;

use crate::model::body::Body;
use crate::model::ids::{FaceId, Serials, VertexId};
use crate::model::parts::{BodyId, Color};
use crate::model::pose::Pose;
use crate::model::range::{self, MAX_COORDINATE};

use super::*;

impl World {
    // ---------------------------------------------------------------- writes

    /// MKBFV at world level: a new seminal body (one face, one vertex at `pos`, no
    /// edges), unnamed, attached to the world with the identity pose, so `pos` is also
    /// its world locus. Serials are taken for the body, the face and the vertex, in that
    /// order. Inverse: [`World::kill`].
    ///
    /// Refused when `pos` is not finite or beyond the world's range.
    pub fn mkbfv(&mut self, pos: DVec3) -> Result<(BodyId, FaceId, VertexId), WorldError> {
        if !pos.is_finite() {
            return Err(WorldError::NonFinite {
                what: "the vertex locus",
            });
        }
        range::coordinate("the vertex locus", pos)?;
        let id = BodyId(self.serials.take());
        let (body, f, v) = Body::seminal(&mut self.serials, pos);
        self.tree
            .add(id, None, self.root(), Pose::IDENTITY, Arc::new(body));
        self.written();
        Ok((id, f, v))
    }

    /// Inserts a body built elsewhere, as a part of `supart` placed at `pose` (relative
    /// to `supart`), under `name` if given. Returns its id.
    ///
    /// The body's faces, edges and vertices get **fresh serial numbers** (in the order of
    /// their old ones) after the body's own, so a body built with another counter, or a
    /// copy of a body killed earlier, can never collide with or revive an id. Slot ids
    /// ([`FaceId`] etc.) are kept. To keep the serials a builder takes, build it with
    /// [`World::insert_with`] instead.
    ///
    /// Refused when `supart` is unknown, the name is bad or taken, the pose is not
    /// finite or would place the body beyond the world's range, the body fails
    /// [`check_topology`], or a locus is not finite or beyond the range.
    /// Inverse: [`World::kill`].
    pub fn insert(
        &mut self,
        body: Body,
        name: Option<&str>,
        supart: BodyId,
        pose: Pose,
    ) -> Result<BodyId, WorldError> {
        let (name, pose) = self.check_insert(name, supart, pose)?;
        check_geometry_input(&body)?;
        let id = BodyId(self.serials.take());
        let body = renumber(&body, &mut self.serials);
        self.tree.add(id, name, supart, pose, Arc::new(body));
        self.written();
        Ok(id)
    }

    /// Builds a body with the world's serial counter and inserts it like
    /// [`World::insert`], keeping the serials the builder took (the body's own serial is
    /// taken first): `world.insert_with(Some("box"), world.root(), pose, |s| mkcube(s, 2.0,
    /// 2.0, 2.0))`. If `build` returns a body with serials it did not take from the
    /// counter given, they are renumbered as [`World::insert`] does.
    ///
    /// Refused as [`World::insert`] is, or with `build`'s own error; a refused call takes
    /// no serials.
    pub fn insert_with<E>(
        &mut self,
        name: Option<&str>,
        supart: BodyId,
        pose: Pose,
        build: impl FnOnce(&mut Serials) -> Result<Body, E>,
    ) -> Result<BodyId, WorldError>
    where
        WorldError: From<E>,
    {
        self.insert_colored_with(name, supart, pose, None, build)
    }

    /// [`World::insert_with`] giving the new body a material colour too, in the same
    /// single write.
    pub fn insert_colored_with<E>(
        &mut self,
        name: Option<&str>,
        supart: BodyId,
        pose: Pose,
        color: Option<Color>,
        build: impl FnOnce(&mut Serials) -> Result<Body, E>,
    ) -> Result<BodyId, WorldError>
    where
        WorldError: From<E>,
    {
        self.check_insert(name, supart, pose)?;
        let built = Built::new(|s| build(s).map_err(WorldError::from))?;
        self.insert_built(built, name, supart, pose, color)
    }

    /// Inserts a body made by [`Built::new`] as [`World::insert_colored_with`] would
    /// have built and inserted it here: the body's own serial is taken first, then its
    /// faces, edges and vertices take the next serials in the order they were numbered
    /// apart. So the same build gives the same ids whether it ran inside the world's
    /// owner or beside it. Costs nothing in the size of the body when the world's next
    /// serial is the one the build expected, else one pass over its serials; nothing is
    /// rebuilt or checked again but the placement.
    ///
    /// Refused, taking no serials, when `supart` is unknown, the name is bad or taken, or
    /// the pose is not finite or would place the body beyond the world's range.
    /// Inverse: [`World::kill`].
    pub fn insert_built(
        &mut self,
        built: Built,
        name: Option<&str>,
        supart: BodyId,
        pose: Pose,
        color: Option<Color>,
    ) -> Result<BodyId, WorldError> {
        let (name, pose) = self.check_insert(name, supart, pose)?;
        let id = BodyId(self.serials.take());
        let Built {
            mut body,
            first,
            end,
        } = built;
        // Serials only grow, but a world reloaded after a failed commit may be behind
        // the one expected: the shift is taken modulo 2^64 either way.
        let shift = self.serials.peek().0.wrapping_sub(first);
        if shift != 0 {
            body.shift_serials(shift);
        }
        let end = end.wrapping_add(shift);
        if end > self.serials.peek().0 {
            self.serials.skip_past(Serial(end - 1));
        }
        self.tree.add(id, name, supart, pose, Arc::new(body));
        self.tree.get_mut(id).expect("just added").color = color;
        self.written();
        Ok(id)
    }

    pub(super) fn check_insert(
        &self,
        name: Option<&str>,
        supart: BodyId,
        pose: Pose,
    ) -> Result<(Option<String>, Pose), WorldError> {
        self.live(supart)?;
        let name = name.map(|n| self.free_name(n, None)).transpose()?;
        let pose = pose.validated()?;
        let origin = self
            .tree
            .world_pose(supart)
            .expect("supart is live")
            .compose(&pose)
            .position;
        if !range::is_within(origin, MAX_COORDINATE) {
            return Err(WorldError::Placement {
                body: BodyId(self.serials.peek()),
                value: range::reach(origin),
            });
        }
        Ok((name, pose))
    }

    /// Checks that giving body `b` the pose `pose` relative to `supart` keeps the
    /// origins of `b` and of all its parts, at any depth, within the world's range.
    /// Preconditions: `b` and `supart` are live, `b` is not the root. Linear in the size
    /// of `b`'s subtree.
    pub(super) fn check_placement(
        &self,
        b: BodyId,
        supart: BodyId,
        pose: &Pose,
    ) -> Result<(), WorldError> {
        let top = self
            .tree
            .world_pose(supart)
            .expect("supart is live")
            .compose(pose);
        let mut stack = vec![(b, top)];
        while let Some((x, w)) = stack.pop() {
            if !range::is_within(w.position, MAX_COORDINATE) {
                return Err(WorldError::Placement {
                    body: x,
                    value: range::reach(w.position),
                });
            }
            if let Some(parts) = self.tree.parts(x) {
                for &p in parts {
                    let node = self.tree.get(p).expect("a part is live");
                    stack.push((p, w.compose(&node.pose)));
                }
            }
        }
        Ok(())
    }
}

/// A body built apart from any world and checked: the part of an insertion whose cost
/// grows with the body, done before the world is touched so that it can run beside the
/// world's owner. [`World::insert_built`] places it.
///
/// Its serials are numbered as if the world's next serial were the one expected when it
/// was built ([`Built::expecting`]; 1 with [`Built::new`]). Inserted into a world whose
/// next serial is that one, it goes in as it is; otherwise its serials are shifted into
/// place, one pass over them.
#[derive(Debug, Clone)]
pub struct Built {
    body: Body,
    /// The first serial the build took (the one after the body's own).
    first: u64,
    /// The serial the build would have taken next: the body's lie in `first..end`.
    end: u64,
}

impl Built {
    /// [`Built::expecting`] a world whose next serial is 1 (the body's own: its faces,
    /// edges and vertices are numbered from 2).
    pub fn new<E>(build: impl FnOnce(&mut Serials) -> Result<Body, E>) -> Result<Built, E>
    where
        E: From<WorldError>,
    {
        Built::expecting(Serial(1), build)
    }

    /// Builds a body with a counter of its own, as a world whose next serial is `next`
    /// would (that serial for the body, the following ones for its faces, edges and
    /// vertices), and checks it as [`World::insert`] would: topology
    /// ([`check_topology`]) and loci (finite, within the world's range). Serials the
    /// builder did not take from the counter it was given are renumbered after the ones
    /// it took, in the order of their old values.
    ///
    /// Refused with `build`'s own error, or when the body fails those checks (a
    /// [`WorldError`] converted into `build`'s error type).
    pub fn expecting<E>(
        next: Serial,
        build: impl FnOnce(&mut Serials) -> Result<Body, E>,
    ) -> Result<Built, E>
    where
        E: From<WorldError>,
    {
        let mut serials = Serials::new();
        serials.skip_past(next);
        let from = serials.peek();
        let body = build(&mut serials)?;
        check_geometry_input(&body)?;
        let body = if serials_fresh(&body, from, serials.peek()) {
            body
        } else {
            renumber(&body, &mut serials)
        };
        Ok(Built {
            body,
            first: from.0,
            end: serials.peek().0,
        })
    }

    /// The body, numbered as built.
    pub fn body(&self) -> &Body {
        &self.body
    }

    /// The serial a world that took this body as built would take next: the one to
    /// build the next body of a batch for.
    pub fn next_serial(&self) -> Serial {
        Serial(self.end)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::solids::sphere;

    /// The serials of every face, edge and vertex, slot by slot.
    fn serials(body: &Body) -> Vec<u64> {
        let mut out: Vec<u64> = body.faces().map(|f| body.face_serial(f).get()).collect();
        out.extend(body.edges().map(|e| body.edge_serial(e).get()));
        out.extend(body.vertices().map(|v| body.vertex_serial(v).get()));
        out
    }

    #[test]
    fn a_body_built_apart_is_numbered_as_if_built_in_the_world() {
        let mut world = World::new();
        world.mkbfv(DVec3::ZERO).expect("a seminal body");
        world.mkbfv(DVec3::X).expect("another");
        // Built with the world's own counter, after the body's serial.
        let mut counter = world.serials.clone();
        let id = counter.take();
        let direct = sphere(&mut counter, 1.0, 12, 6).expect("a sphere");

        let built =
            Built::new(|s| sphere(s, 1.0, 12, 6).map_err(WorldError::from)).expect("built apart");
        assert_eq!(serials(built.body()).iter().min(), Some(&2));
        let b = world
            .insert_built(built, Some("ball"), world.root(), Pose::IDENTITY, None)
            .expect("inserted");
        assert_eq!(b.0, id);
        let placed = world.body(b).expect("live");
        assert_eq!(serials(placed), serials(&direct));
        assert_eq!(world.serials.peek(), counter.peek());
        for f in placed.faces() {
            let s = placed.face_serial(f);
            assert_eq!(placed.face_by_serial(s), Some(f), "found by its serial");
        }
        assert!(check_topology(placed).is_ok());

        // Expecting the right next serial, or a wrong one, gives the same numbers.
        for guess in [world.serials.peek().0, 1, world.serials.peek().0 + 1_000] {
            let mut inside = world.clone();
            let mut counter = inside.serials.clone();
            counter.take();
            let direct = sphere(&mut counter, 1.0, 12, 6).expect("a sphere");
            let built = Built::expecting(Serial(guess), |s| {
                sphere(s, 1.0, 12, 6).map_err(WorldError::from)
            })
            .expect("built apart");
            let b = inside
                .insert_built(built, None, inside.root(), Pose::IDENTITY, None)
                .expect("inserted");
            assert_eq!(serials(inside.body(b).expect("live")), serials(&direct));
            assert_eq!(inside.serials.peek(), counter.peek(), "expecting {guess}");
        }
    }

    #[test]
    fn a_refused_insertion_takes_no_serials() {
        let mut world = World::new();
        world.mkbfv(DVec3::ZERO).expect("a seminal body");
        let next = world.serials.peek();
        let built =
            Built::new(|s| sphere(s, 1.0, 12, 6).map_err(WorldError::from)).expect("built apart");
        let unknown = BodyId(Serial(999));
        assert!(
            world
                .insert_built(built, None, unknown, Pose::IDENTITY, None)
                .is_err()
        );
        assert_eq!(world.serials.peek(), next);
    }
}
