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

use serde::{Deserialize, Serialize};

use super::arena::Arena;
use super::body::Body;
use super::boolean::BooleanError;
use super::camera::{Camera, CameraError, Light, LightError};
use super::check::{Report, check_topology};
use super::euler::EulerError;
use super::ids::{FaceId, Serial, Serials};
use super::parts::{BodyId, BodyNode, PartsTree, Size, validate_name};
use super::pose::PoseError;
use super::range::{self, MAX_COORDINATE, RangeError};
use super::solids::BuildError;
use super::transform::TransformError;

mod body_ops;
mod boolean;
mod glue;
mod insert;
mod named;
mod perceived;
mod read;
mod tree;

pub use boolean::{BooleanBasis, BooleanOutcome, Entangled, Piece, ShellRef};
pub use insert::Built;
pub use named::{Named, Register};
pub use perceived::PerceivedShell;

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
    /// A boolean of a body with itself or with one of its own parts (at any depth).
    #[error("{0}")]
    Entangled(Entangled),
    /// The boolean kernel refused an operand (not closed, self-intersecting, not
    /// finite in the boolean's frame).
    #[error("{}", boolean::refusal_message(.body, .error))]
    Boolean {
        /// The body of the operand refused.
        body: BodyId,
        /// The kernel's refusal.
        error: BooleanError,
    },
    /// The boolean kernel failed (panicked); nothing was changed.
    #[error("{0}")]
    BooleanFailed(String),
    /// Perception was asked to carve a body that it did not make (or that was made an
    /// ordinary body since).
    #[error("body {0} is not provisional: only bodies perception made can be carved by views")]
    NotProvisional(BodyId),
    /// The result of a write would have more faces than one write may make.
    #[error("the result would have {faces} faces; at most {max} are allowed per request")]
    TooLarge {
        /// Faces it would have.
        faces: usize,
        /// The limit ([`crate::model::range::MAX_BODY_FACES`]).
        max: usize,
    },
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
    cameras: Register<Camera>,
    lights: Register<Light>,
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
            cameras: Register::default(),
            lights: Register::default(),
            revision: 0,
        }
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
