//! The world: every body in a parts tree, the cameras and lights, the serial-number
//! counter and a revision number.
//!
//! [`World`] is the one value the server's actor owns and changes. Every write
//!
//! * checks all of its inputs first, and either succeeds or is refused with a
//!   [`WorldError`] leaving the world exactly as it was, revision included;
//! * on success increases [`World::revision`] by exactly one;
//! * keeps the parts tree sound (see [`PartsTree`]) and every body a valid winged-edge
//!   polyhedron (its topology is changed only by the Euler operators);
//! * never reuses a serial number: bodies, faces, edges and vertices all take theirs from
//!   the world's one [`Serials`] counter, so a stale id never finds another entity.
//!
//! # Cheap snapshots
//!
//! Each body sits behind an `Arc`, and the parts tree's nodes and names are persistent
//! maps, so `World` is `Clone` in O(cameras + lights): a clone (a snapshot for readers)
//! shares every node and every body's geometry. A later write to the original copies
//! only what it changes (copy-on-write): the body it edits, and the path of the tree's
//! maps down to the node it changes (a few nodes of 16 entries). The snapshot keeps the
//! old geometry and poses, and every other node and body stays shared between the two
//! (`std::ptr::eq`, `Arc::ptr_eq`).
//!
//! # Names
//!
//! Body names are unique: FDNAME ([`World::find_by_name`]) finds at most one body, and a
//! write that would give a second body the same name is refused
//! ([`WorldError::DuplicateName`]). The root is named `"world"`. Camera and light names
//! are separate name spaces of their own. All names follow [`validate_name`].

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::arena::Arena;
use super::body::Body;
use super::camera::{Camera, CameraError, Light, LightError};
use super::check::{Report, check_topology};
use super::euler::EulerError;
use super::ids::{EdgeId, FaceId, Serial, Serials, VertexId};
use super::parts::{BodyId, BodyNode, Color, Entity, PartsTree, Size, validate_name};
use super::pose::{Pose, PoseError};
use super::range::{self, MAX_COORDINATE, RangeError};
use super::solids::BuildError;
use super::transform::{Frame, Transform, TransformError};

/// Why a world operation was refused. The world is unchanged.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WorldError {
    /// An Euler operator refused.
    #[error(transparent)]
    Euler(#[from] EulerError),
    /// A transform was refused.
    #[error(transparent)]
    Transform(#[from] TransformError),
    /// A pose was refused.
    #[error(transparent)]
    Pose(#[from] PoseError),
    /// A camera was refused.
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// A light was refused.
    #[error(transparent)]
    Light(#[from] LightError),
    /// Building a body from vertex and face lists was refused.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// A solid primitive refused.
    #[error(transparent)]
    Solid(#[from] crate::model::solids::SolidError),
    /// No live body has this id.
    #[error("body {0} does not exist")]
    UnknownBody(BodyId),
    /// No live body, face, edge or vertex has this serial number.
    #[error("no live entity has serial number {0}")]
    UnknownEntity(Serial),
    /// No camera has this name.
    #[error("no camera is named {0:?}")]
    UnknownCamera(String),
    /// No light has this name.
    #[error("no light is named {0:?}")]
    UnknownLight(String),
    /// Attaching `body` to `supart` would make the parts tree a cycle, because `supart`
    /// is `body` itself or one of its parts (at any depth).
    #[error(
        "body {supart} is {body} or one of its parts; attaching {body} to it would make a cycle"
    )]
    Cycle {
        /// The body to be attached.
        body: BodyId,
        /// The would-be supart.
        supart: BodyId,
    },
    /// The operation does not apply to the world body (it is fixed at the root, has no
    /// geometry and keeps its name).
    #[error("the world body cannot be {what}")]
    Root {
        /// What was attempted ("killed", "attached", ...).
        what: &'static str,
    },
    /// A name that [`validate_name`] refuses.
    #[error("bad name {name:?}: {reason}")]
    BadName {
        /// The name given.
        name: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The name already belongs to another body.
    #[error("the name {name:?} already belongs to body {owner}")]
    DuplicateName {
        /// The name given.
        name: String,
        /// The body that has it.
        owner: BodyId,
    },
    /// A body offered for insertion is not a valid winged-edge polyhedron.
    #[error("the body is not a valid polyhedron: {0}")]
    InvalidBody(Report),
    /// A vertex locus (or other number) that is NaN or infinite.
    #[error("{what} is not finite")]
    NonFinite {
        /// What.
        what: &'static str,
    },
    /// A locus or size outside the world's range (see [`crate::model::range`]).
    #[error(transparent)]
    OutOfRange(#[from] RangeError),
    /// The write would place a body's origin outside the world's range.
    #[error(
        "body {body} would have its origin at a world coordinate of {value:e} m, beyond the range of ±{MAX_COORDINATE:e} m"
    )]
    Placement {
        /// The body.
        body: BodyId,
        /// Its coordinate farthest from zero.
        value: f64,
    },
}

impl WorldError {
    /// Whether the refusal is about the world's range (see [`crate::model::range`]): a
    /// locus, a placement or a size the world does not take.
    pub fn is_out_of_range(&self) -> bool {
        match self {
            WorldError::OutOfRange(_) | WorldError::Placement { .. } => true,
            WorldError::Euler(e) => e.is_out_of_range(),
            WorldError::Transform(e) => e.is_out_of_range(),
            WorldError::Camera(e) => e.is_out_of_range(),
            WorldError::Light(e) => e.is_out_of_range(),
            WorldError::Build(e) => e.is_out_of_range(),
            WorldError::Solid(e) => e.is_out_of_range(),
            _ => false,
        }
    }
}

/// What [`World::kill`] removed: the body and all its sub-parts, in pre-order (the killed
/// body first), each with its node as it was (name, links, pose, geometry).
#[derive(Clone, Debug)]
pub struct Killed {
    /// The removed nodes.
    pub bodies: Vec<(BodyId, BodyNode)>,
}

impl Killed {
    /// The ids of the removed bodies, killed body first.
    pub fn ids(&self) -> impl Iterator<Item = BodyId> + '_ {
        self.bodies.iter().map(|(id, _)| *id)
    }
    /// Total faces, edges and vertices removed.
    pub fn counts(&self) -> (usize, usize, usize) {
        let s = Size::total(self.bodies.iter().map(|(_, n)| n));
        (s.faces, s.edges, s.vertices)
    }
}

/// What [`World::unglue`] made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UngluedBodies {
    /// The new face capping the cut in the ungluing body.
    pub kept_face: FaceId,
    /// The new face capping the other side of the cut: in [`Self::split_off`] when the
    /// cut split the body, else in the ungluing body.
    pub new_face: FaceId,
    /// The body split off, if the seam separated the body in two: a new unnamed node
    /// under the same supart with the same pose.
    pub split_off: Option<BodyId>,
}

/// The world model: bodies in a parts tree, cameras, lights, serials and a revision.
/// See the [module documentation](self).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct World {
    tree: PartsTree,
    serials: Serials,
    cameras: BTreeMap<String, Camera>,
    lights: BTreeMap<String, Light>,
    revision: u64,
}

impl Default for World {
    fn default() -> Self {
        Self::new()
    }
}

impl World {
    /// An empty world: only the root body (serial 1, named `"world"`), no cameras or
    /// lights, revision 0.
    pub fn new() -> World {
        let mut serials = Serials::new();
        let root = BodyId(serials.take());
        World {
            tree: PartsTree::new(root),
            serials,
            cameras: BTreeMap::new(),
            lights: BTreeMap::new(),
            revision: 0,
        }
    }

    // ------------------------------------------------------------------ reads

    /// The number of successful writes so far.
    #[inline]
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// The world body at the root of the parts tree.
    #[inline]
    pub fn root(&self) -> BodyId {
        self.tree.root()
    }

    /// The parts tree, for the questions it answers (subtrees, ancestors, checks).
    #[inline]
    pub fn tree(&self) -> &PartsTree {
        &self.tree
    }

    /// The serial number the next new entity will get.
    pub fn next_serial(&self) -> Serial {
        self.serials.peek()
    }

    /// Moves the revision forward to `revision` and the serial counter forward to
    /// `next_serial`, changing nothing else (each stays where it is if already past).
    ///
    /// For recovery that accepts a loss of acknowledged writes: the world continues at
    /// the revision and serial that clients were last told of, so that neither a
    /// revision nor an id is issued twice. Postcondition: `revision() >= revision` and
    /// `next_serial() >= next_serial`. There is no inverse.
    pub fn resume_at(&mut self, revision: u64, next_serial: Serial) {
        self.revision = self.revision.max(revision);
        if next_serial.0 > 0 {
            self.serials.skip_past(Serial(next_serial.0 - 1));
        }
    }

    /// The node of body `b`.
    pub fn node(&self, b: BodyId) -> Option<&BodyNode> {
        self.tree.get(b)
    }

    /// The polyhedron of body `b` (loci in its own frame).
    pub fn body(&self, b: BodyId) -> Option<&Body> {
        self.tree.get(b).map(|n| &*n.body)
    }

    /// The shared handle of body `b`'s polyhedron (for snapshots; see `Arc::ptr_eq`).
    pub fn body_arc(&self, b: BodyId) -> Option<&Arc<Body>> {
        self.tree.get(b).map(|n| &n.body)
    }

    /// The name of body `b`, if it has one.
    pub fn name(&self, b: BodyId) -> Option<&str> {
        self.tree.get(b).and_then(|n| n.name.as_deref())
    }

    /// SUPART(b).
    pub fn supart(&self, b: BodyId) -> Option<BodyId> {
        self.tree.supart(b)
    }

    /// The sub-parts of `b`, in attachment order.
    pub fn parts(&self, b: BodyId) -> Option<&imbl::Vector<BodyId>> {
        self.tree.parts(b)
    }

    /// `b`'s pose relative to its supart.
    pub fn pose(&self, b: BodyId) -> Option<Pose> {
        self.tree.get(b).map(|n| n.pose)
    }

    /// `b`'s pose in the world: its supart chain's poses composed, so turning a
    /// shoulder turns the whole arm.
    pub fn world_pose(&self, b: BodyId) -> Option<Pose> {
        self.tree.world_pose(b)
    }

    /// [`world_pose`](Self::world_pose) of `b` whose node, already looked up with
    /// [`node`](Self::node), is `node` (one lookup fewer). Precondition: `node` is
    /// `b`'s node.
    pub fn world_pose_of(&self, b: BodyId, node: &BodyNode) -> Pose {
        self.tree.world_pose_of(b, node)
    }

    /// The world locus of vertex `v` of body `b`.
    pub fn world_position(&self, b: BodyId, v: VertexId) -> Option<DVec3> {
        let node = self.tree.get(b)?;
        node.body
            .has_vertex(v)
            .then(|| self.tree.world_pose(b))
            .flatten()
            .map(|p| p.transform_point(node.body.position(v)))
    }

    /// FDNAME: the body with this name (the root is `"world"`).
    pub fn find_by_name(&self, name: &str) -> Option<BodyId> {
        self.tree.find_by_name(name)
    }

    /// Every body except the root, in id order.
    pub fn bodies(&self) -> impl Iterator<Item = (BodyId, &BodyNode)> + '_ {
        let root = self.root();
        self.tree.iter().filter(move |(id, _)| *id != root)
    }

    /// Number of bodies, not counting the root.
    pub fn body_count(&self) -> usize {
        self.tree.node_count() - 1
    }

    /// Faces, edges and vertices of all the bodies together. Constant time: kept as
    /// bodies are added, changed and removed.
    pub fn size(&self) -> Size {
        self.tree.size()
    }

    /// BGET by serial number: the live body, face, edge or vertex with serial `s`, and
    /// the body it belongs to. `None` for a serial never issued or whose entity was
    /// killed: serials are never reused, so a stale id never finds another entity.
    ///
    /// Cost: a map lookup, then a binary search in each body's serial index.
    pub fn find_entity(&self, s: Serial) -> Option<(BodyId, Entity)> {
        if s == Serial::NONE {
            return None;
        }
        if self.tree.contains(BodyId(s)) {
            return Some((BodyId(s), Entity::Body));
        }
        self.tree.iter().find_map(|(id, n)| {
            let b = &n.body;
            let e = if let Some(f) = b.face_by_serial(s) {
                Entity::Face(f)
            } else if let Some(e) = b.edge_by_serial(s) {
                Entity::Edge(e)
            } else {
                Entity::Vertex(b.vertex_by_serial(s)?)
            };
            Some((id, e))
        })
    }

    /// Many vertices by serial number at once: for each of `serials`, the body and
    /// vertex it names and the vertex's world locus, or `None` when it is no live vertex
    /// (never issued, killed, or a face, edge or body).
    ///
    /// Cost: one pass over the bodies, each passed over unless the range of its vertex
    /// serials holds a wanted one (a binary search), so O(bodies · log n + n · log V),
    /// where [`World::find_entity`] would be O(bodies) for each.
    pub fn find_vertices(&self, serials: &[Serial]) -> Vec<Option<(BodyId, VertexId, DVec3)>> {
        let mut out = vec![None; serials.len()];
        let mut wanted: Vec<(Serial, usize)> = serials
            .iter()
            .enumerate()
            .filter(|(_, s)| **s != Serial::NONE)
            .map(|(i, &s)| (s, i))
            .collect();
        wanted.sort_unstable();
        if wanted.is_empty() {
            return out;
        }
        for (id, node) in self.tree.iter() {
            let Some((lo, hi)) = node.body.vertex_serial_bounds() else {
                continue;
            };
            let start = wanted.partition_point(|(s, _)| *s < lo);
            let mut pose = None;
            for &(s, i) in wanted[start..].iter().take_while(|(s, _)| *s <= hi) {
                let Some(v) = node.body.vertex_by_serial(s) else {
                    continue;
                };
                let Some(p) = *pose.get_or_insert_with(|| self.tree.world_pose(id)) else {
                    continue;
                };
                out[i] = Some((id, v, p.transform_point(node.body.position(v))));
            }
        }
        out
    }

    /// The camera with this name.
    pub fn camera(&self, name: &str) -> Option<&Camera> {
        self.cameras.get(name)
    }

    /// Every camera, by name.
    pub fn cameras(&self) -> impl Iterator<Item = (&str, &Camera)> + '_ {
        self.cameras.iter().map(|(k, c)| (k.as_str(), c))
    }

    /// The light with this name.
    pub fn light(&self, name: &str) -> Option<&Light> {
        self.lights.get(name)
    }

    /// Every light, by name.
    pub fn lights(&self) -> impl Iterator<Item = (&str, &Light)> + '_ {
        self.lights.iter().map(|(k, l)| (k.as_str(), l))
    }

    // ---------------------------------------------------------------- checks

    fn live(&self, b: BodyId) -> Result<&BodyNode, WorldError> {
        self.tree.get(b).ok_or(WorldError::UnknownBody(b))
    }

    /// `b` lives and is not the root.
    fn live_part(&self, b: BodyId, what: &'static str) -> Result<&BodyNode, WorldError> {
        if b == self.root() {
            return Err(WorldError::Root { what });
        }
        self.live(b)
    }

    /// A valid name not held by a body other than `owner`.
    fn free_name(&self, name: &str, owner: Option<BodyId>) -> Result<String, WorldError> {
        valid_name(name)?;
        match self.tree.find_by_name(name) {
            Some(other) if Some(other) != owner => Err(WorldError::DuplicateName {
                name: name.to_owned(),
                owner: other,
            }),
            _ => Ok(name.to_owned()),
        }
    }

    fn written(&mut self) {
        self.revision += 1;
    }

    /// Moves `b` under `supart` keeping its world pose. Preconditions: both live, `b`
    /// not the root, `supart` not within `b`.
    fn relink_in_place(&mut self, b: BodyId, supart: BodyId) {
        let w = self.tree.world_pose(b).expect("b is live");
        let s = self.tree.world_pose(supart).expect("supart is live");
        self.tree.relink(b, supart);
        self.tree.get_mut(b).expect("b is live").pose = s.inverse().compose(&w);
    }

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
        let (name, pose) = self.check_insert(name, supart, pose)?;
        let mut serials = self.serials.clone();
        let id = BodyId(serials.take());
        let from = serials.peek();
        let body = build(&mut serials)?;
        check_geometry_input(&body)?;
        let body = if serials_fresh(&body, from, serials.peek()) {
            body
        } else {
            renumber(&body, &mut serials)
        };
        self.serials = serials;
        self.tree.add(id, name, supart, pose, Arc::new(body));
        self.tree.get_mut(id).expect("just added").color = color;
        self.written();
        Ok(id)
    }

    fn check_insert(
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
    fn check_placement(&self, b: BodyId, supart: BodyId, pose: &Pose) -> Result<(), WorldError> {
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

    /// ATTACH(b, supart): DETs `b` (with all its parts) from its supart and ATTs it to
    /// `supart`, at the end of its parts list. The body does not move: its pose is
    /// recomputed so that its world pose is unchanged. Inverse: `attach(b, old_supart)`.
    ///
    /// Refused when either body is unknown, `b` is the root, or `supart` is `b` or one of
    /// its parts at any depth ([`WorldError::Cycle`]).
    pub fn attach(&mut self, b: BodyId, supart: BodyId) -> Result<(), WorldError> {
        let node = self.live_part(b, "attached to another body")?;
        let old = node.supart;
        self.live(supart)?;
        if self.tree.is_within(supart, b) {
            return Err(WorldError::Cycle { body: b, supart });
        }
        if old != supart {
            self.relink_in_place(b, supart);
        }
        self.written();
        Ok(())
    }

    /// DETACH(b): ATTACH(b, world), keeping its world pose. Refused for the root or an
    /// unknown body.
    pub fn detach(&mut self, b: BodyId) -> Result<(), WorldError> {
        self.attach(b, self.root())
    }

    /// Names body `b` (`None` removes its name). Refused for the root, an unknown body,
    /// a bad name, or a name another body has.
    pub fn rename(&mut self, b: BodyId, name: Option<&str>) -> Result<(), WorldError> {
        self.live_part(b, "renamed")?;
        let name = name.map(|n| self.free_name(n, Some(b))).transpose()?;
        self.tree.set_name(b, name);
        self.written();
        Ok(())
    }

    /// Sets `b`'s pose relative to its supart (renormalising the quaternion); its parts
    /// move with it. Refused for the root, an unknown body, a bad pose, or one that
    /// would place `b` or a part of it beyond the world's range.
    pub fn set_pose(&mut self, b: BodyId, pose: Pose) -> Result<(), WorldError> {
        self.live_part(b, "posed")?;
        let pose = pose.validated()?;
        let supart = self.tree.supart(b).expect("checked");
        self.check_placement(b, supart, &pose)?;
        self.tree.get_mut(b).expect("checked").pose = pose;
        self.written();
        Ok(())
    }

    /// Sets (or with `None` clears) body `b`'s material colour. Refused for the root or
    /// an unknown body.
    pub fn set_color(&mut self, b: BodyId, color: Option<Color>) -> Result<(), WorldError> {
        self.live_part(b, "coloured")?;
        self.tree.get_mut(b).expect("checked").color = color;
        self.written();
        Ok(())
    }

    /// Renames (`Some(None)` removes the name), re-parents, re-poses and re-colours
    /// (`Some(None)` restores the default colour) body `b` in one write: either all of
    /// the given changes happen, as one revision, or none does.
    /// The re-parenting happens before the new pose is set, so `pose` is relative to the
    /// new supart.
    ///
    /// Refused as [`World::rename`], [`World::attach`] and [`World::set_pose`] are, in
    /// that order. Every check is made before anything changes (none of the three
    /// changes affects whether another is allowed), so the cost is that of the changes
    /// themselves, not of a trial copy of the world.
    ///
    /// Returns whether anything changed. A request whose every given value equals the
    /// body's current one (or that gives none) changes nothing and leaves the revision
    /// as it was; it is still refused as above (an unknown body, say).
    pub fn update(
        &mut self,
        b: BodyId,
        name: Option<Option<&str>>,
        supart: Option<BodyId>,
        pose: Option<Pose>,
        color: Option<Option<Color>>,
    ) -> Result<bool, WorldError> {
        // Plan: the same checks, in the same order, as rename, attach and set_pose.
        let name = match name {
            Some(name) => {
                self.live_part(b, "renamed")?;
                Some(name.map(|n| self.free_name(n, Some(b))).transpose()?)
            }
            None => None,
        };
        if let Some(supart) = supart {
            self.live_part(b, "attached to another body")?;
            self.live(supart)?;
            if self.tree.is_within(supart, b) {
                return Err(WorldError::Cycle { body: b, supart });
            }
        }
        let pose = match pose {
            Some(pose) => {
                self.live_part(b, "posed")?;
                let pose = pose.validated()?;
                let under = match supart {
                    Some(s) => s,
                    None => self.tree.supart(b).expect("checked"),
                };
                self.check_placement(b, under, &pose)?;
                Some(pose)
            }
            None => None,
        };
        if color.is_some() {
            self.live_part(b, "coloured")?;
        }
        // Drop what would not change: a write that changes nothing is no write.
        let node = self.tree.get(b).expect("checked");
        let name = name.filter(|n| *n != node.name);
        let supart = supart.filter(|&s| Some(s) != self.tree.supart(b));
        let pose = pose.filter(|p| supart.is_some() || *p != node.pose);
        let color = color.filter(|c| *c != node.color);
        if name.is_none() && supart.is_none() && pose.is_none() && color.is_none() {
            return Ok(false);
        }
        // Apply: nothing below can fail.
        if let Some(name) = name {
            self.tree.set_name(b, name);
        }
        if let Some(supart) = supart {
            self.relink_in_place(b, supart);
        }
        if let Some(pose) = pose {
            self.tree.get_mut(b).expect("checked").pose = pose;
        }
        if let Some(color) = color {
            self.tree.get_mut(b).expect("checked").color = color;
        }
        self.written();
        Ok(true)
    }

    /// KLBFEV: removes body `b` with all its faces, edges and vertices, and all its
    /// sub-parts at any depth. Their serial numbers are never issued again. Returns what
    /// was removed. Refused for the root or an unknown body.
    pub fn kill(&mut self, b: BodyId) -> Result<Killed, WorldError> {
        self.live_part(b, "killed")?;
        let bodies = self.tree.remove_subtree(b);
        self.written();
        Ok(Killed { bodies })
    }

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

    /// A kernel operation on one body that refuses without changing it (every Euler
    /// operator does): applied in place, copying the body first only if a snapshot
    /// shares it.
    fn in_place<R>(
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
    fn merge<R>(
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

    /// Stores (or replaces) the camera `name`. Refused for a bad name or camera.
    pub fn set_camera(&mut self, name: &str, camera: Camera) -> Result<(), WorldError> {
        valid_name(name)?;
        let camera = camera.validated()?;
        self.cameras.insert(name.to_owned(), camera);
        self.written();
        Ok(())
    }

    /// Removes the camera `name` and returns it. Refused if there is none.
    pub fn remove_camera(&mut self, name: &str) -> Result<Camera, WorldError> {
        let c = self
            .cameras
            .remove(name)
            .ok_or_else(|| WorldError::UnknownCamera(name.to_owned()))?;
        self.written();
        Ok(c)
    }

    /// Stores (or replaces) the light `name`. Refused for a bad name or light.
    pub fn set_light(&mut self, name: &str, light: Light) -> Result<(), WorldError> {
        valid_name(name)?;
        let light = light.validated()?;
        self.lights.insert(name.to_owned(), light);
        self.written();
        Ok(())
    }

    /// Removes the light `name` and returns it. Refused if there is none.
    pub fn remove_light(&mut self, name: &str) -> Result<Light, WorldError> {
        let l = self
            .lights
            .remove(name)
            .ok_or_else(|| WorldError::UnknownLight(name.to_owned()))?;
        self.written();
        Ok(l)
    }
}

fn valid_name(name: &str) -> Result<(), WorldError> {
    validate_name(name).map_err(|reason| WorldError::BadName {
        name: name.to_owned(),
        reason,
    })
}

/// Checks a body offered from outside: valid topology and finite loci.
fn check_geometry_input(body: &Body) -> Result<(), WorldError> {
    let report = check_topology(body);
    if !report.is_ok() {
        return Err(WorldError::InvalidBody(report));
    }
    check_loci(body)
}

/// Checks that every locus of `body` is finite and within the world's range.
fn check_loci(body: &Body) -> Result<(), WorldError> {
    for v in body.vertices() {
        let p = body.position(v);
        if !p.is_finite() {
            return Err(WorldError::NonFinite {
                what: "a vertex locus",
            });
        }
        if !range::is_within(p, MAX_COORDINATE) {
            range::coordinate("a vertex locus", p)?;
        }
    }
    Ok(())
}

/// Applies `op` to the body behind `slot`, in place if no one else holds it, else on a
/// copy that replaces it only on success. Precondition: `op` changes nothing when it
/// fails, so on failure `slot` is as it was (the same allocation, if it was shared).
fn cow_try<R, E>(slot: &mut Arc<Body>, op: impl FnOnce(&mut Body) -> Result<R, E>) -> Result<R, E> {
    if let Some(body) = Arc::get_mut(slot) {
        return op(body);
    }
    let mut copy = Body::clone(slot);
    let r = op(&mut copy)?;
    *slot = Arc::new(copy);
    Ok(r)
}

/// Every live serial of `body` (faces, edges, vertices).
fn live_serials(body: &Body) -> Vec<Serial> {
    let mut out = Vec::with_capacity(body.face_count() + body.edge_count() + body.vertex_count());
    out.extend(body.faces().map(|f| body.face_serial(f)));
    out.extend(body.edges().map(|e| body.edge_serial(e)));
    out.extend(body.vertices().map(|v| body.vertex_serial(v)));
    out
}

/// Whether every serial of `body` lies in `from..to` and none repeats.
fn serials_fresh(body: &Body, from: Serial, to: Serial) -> bool {
    let mut all = live_serials(body);
    if all.iter().any(|&s| s < from || s >= to) {
        return false;
    }
    all.sort_unstable();
    all.windows(2).all(|w| w[0] != w[1])
}

/// A copy of `body` whose faces, edges and vertices carry fresh serials from `serials`,
/// taken in the order of their old serials. Slot ids, records and handles are unchanged.
fn renumber(body: &Body, serials: &mut Serials) -> Body {
    let mut order: Vec<(Serial, u8, usize)> = Vec::new();
    order.extend(body.faces().map(|f| (body.face_serial(f), 0, f.index())));
    order.extend(body.edges().map(|e| (body.edge_serial(e), 1, e.index())));
    order.extend(
        body.vertices()
            .map(|v| (body.vertex_serial(v), 2, v.index())),
    );
    order.sort_unstable();
    let mut fresh = [
        vec![Serial::NONE; body.faces.slots()],
        vec![Serial::NONE; body.edges.slots()],
        vec![Serial::NONE; body.vertices.slots()],
    ];
    for (_, kind, slot) in order {
        fresh[kind as usize][slot] = serials.take();
    }
    let [f, e, v] = fresh;
    Body {
        faces: reserial(&body.faces, &f),
        edges: reserial(&body.edges, &e),
        vertices: reserial(&body.vertices, &v),
        handles: body.handles,
    }
}

/// An arena with the same records in the same slots, live slots carrying `serials[slot]`
/// and dead slots (those given [`Serial::NONE`]) dead again.
fn reserial<T: Copy>(old: &Arena<T>, serials: &[Serial]) -> Arena<T> {
    let mut a = Arena::default();
    a.reserve(old.slots());
    let mut dead = Vec::new();
    for (i, &s) in serials.iter().enumerate() {
        // A dead slot is filled and then killed, so that slot numbers stay put; its
        // placeholder serial is never seen outside.
        let s = if s == Serial::NONE {
            dead.push(i);
            Serial(u64::MAX - i as u64)
        } else {
            s
        };
        a.insert_unsorted(*old.get(i), s);
    }
    for &i in dead.iter().rev() {
        a.remove(i);
    }
    a.resort_index();
    a
}
