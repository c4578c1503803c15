//! Edits: every write the server accepts, as data, and how each one is applied to the
//! world.
//!
//! An [`Edit`] names entities by their serial numbers and carries everything needed to
//! apply it again (a shape's parameters, a vertex's locus), so that the same sequence of
//! edits on an empty world gives the same world with the same ids. The actor applies
//! edits one at a time; [`apply`] either changes the world and returns an [`Outcome`] or
//! refuses with an [`EditError`] and changes nothing.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::command::{
    BooleanPiece, CameraSpec, CameraSpecError, CreateBody, EulerOp, ImportedBody, LightSpec,
    Motion, Move, PatchBody, PerceivedPiece, Shape, Sweep, SweepKind,
};
use super::plan::{Prepared, prepare};
use crate::model::boolean::Op;
use crate::model::range;
use crate::model::solids::{
    BuildError, SolidError, Twist, box_solid, cone, cylinder, mktetra, prism_solid, pyramid_solid,
    sphere, torus,
};
use crate::model::{
    Body, BodyId, Built, EdgeId, Entity, EulerError, FaceId, LightError, PerceivedShell, Pose,
    Serial, Transform, VertexId, World, WorldError,
};

pub use super::command::MAX_BODY_FACES;

/// One write to the world.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "edit", rename_all = "snake_case")]
pub enum Edit {
    /// Make a body.
    CreateBody(CreateBody),
    /// Rename, re-parent or re-pose a body.
    PatchBody {
        /// The body.
        body: u64,
        /// What changes.
        patch: PatchBody,
    },
    /// Re-pose several bodies at once (recognition's corrections of bodies that moved):
    /// all or none.
    PlaceBodies {
        /// Each body and its new pose relative to its supart.
        places: Vec<Place>,
    },
    /// KLBFEV: kill a body with all its parts.
    DeleteBody {
        /// The body.
        body: u64,
    },
    /// An Euler operator on a body.
    Euler {
        /// The body.
        body: u64,
        /// The operator.
        op: EulerOp,
    },
    /// A Euclidean transform of a body or one of its faces, edges or vertices.
    Transform {
        /// The body.
        body: u64,
        /// The motion.
        #[serde(rename = "req")]
        motion: Move,
    },
    /// A sweep of a face.
    Sweep {
        /// The body.
        body: u64,
        /// The sweep.
        #[serde(rename = "req")]
        sweep: Sweep,
    },
    /// FVDUAL.
    Dual {
        /// The body.
        body: u64,
    },
    /// EVERT.
    Evert {
        /// The body.
        body: u64,
    },
    /// MKCOPY: a copy beside the original, under the same supart.
    Copy {
        /// The body.
        body: u64,
        /// The copy's name.
        name: Option<String>,
    },
    /// Store a camera.
    PutCamera {
        /// Its name.
        name: String,
        /// The camera.
        camera: CameraSpec,
    },
    /// Remove a camera.
    DeleteCamera {
        /// Its name.
        name: String,
    },
    /// Store a light.
    PutLight {
        /// Its name.
        name: String,
        /// The light.
        light: LightSpec,
    },
    /// Remove a light.
    DeleteLight {
        /// Its name.
        name: String,
    },
    /// A boolean as asked for: BIN, BUN or the difference of `body` and `with`. Applied by
    /// running the boolean kernel; never journaled (it has no serde form): the journal
    /// keeps the [`Edit::BooleanResult`] it gave (see [`Planned`](super::Planned)).
    #[serde(skip)]
    Boolean {
        /// The body kept (B1): the result replaces it.
        body: u64,
        /// The other operand (B2).
        with: u64,
        /// Which boolean.
        op: Op,
        /// Whether `with` survives; else it is killed.
        keep_with: bool,
    },
    /// A boolean's result as geometry, in the journal as `"edit": "boolean"`: `pieces`
    /// (in `body`'s frame) placed as [`World::place_boolean`] places shells. Applying it
    /// runs no kernel, so a replay does not depend on the version of the algorithm that
    /// computed it.
    #[serde(rename = "boolean")]
    BooleanResult {
        /// The body kept (B1).
        body: u64,
        /// The other operand (B2).
        with: u64,
        /// Whether `with` survived.
        keep_with: bool,
        /// Which boolean it was (for the record; the pieces say what it made).
        op: Op,
        /// The result's shells, the first replacing `body`'s polyhedron.
        pieces: Vec<BooleanPiece>,
    },
    /// Perception's result as geometry: provisional bodies inserted or carved again,
    /// and those carved to nothing removed, all or none. Applying it runs no carving.
    Perception {
        /// Bodies inserted or carved again, in the order the answer lists them.
        pieces: Vec<PerceivedPiece>,
        /// Provisional bodies carved to nothing.
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        removed: Vec<u64>,
    },
    /// The bodies a mesh file made, all or none, each a part of the world, of a body
    /// already there, or of an earlier body of the list. The file itself is not kept:
    /// the polygons are, so a replay does not depend on the parsers.
    ImportBodies {
        /// The bodies, each supart before its parts.
        bodies: Vec<ImportedBody>,
    },
}

impl Edit {
    /// The edit's kind, as written in its `edit` tag (`create_body`, `euler`, ...).
    pub fn kind(&self) -> &'static str {
        match self {
            Edit::CreateBody(_) => "create_body",
            Edit::PatchBody { .. } => "patch_body",
            Edit::PlaceBodies { .. } => "place_bodies",
            Edit::DeleteBody { .. } => "delete_body",
            Edit::Euler { .. } => "euler",
            Edit::Transform { .. } => "transform",
            Edit::Sweep { .. } => "sweep",
            Edit::Dual { .. } => "dual",
            Edit::Evert { .. } => "evert",
            Edit::Copy { .. } => "copy",
            Edit::PutCamera { .. } => "put_camera",
            Edit::DeleteCamera { .. } => "delete_camera",
            Edit::PutLight { .. } => "put_light",
            Edit::DeleteLight { .. } => "delete_light",
            Edit::Boolean { .. } | Edit::BooleanResult { .. } => "boolean",
            Edit::Perception { .. } => "perception",
            Edit::ImportBodies { .. } => "import_bodies",
        }
    }
}

/// One body's new place: its pose relative to its supart.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Place {
    /// The body.
    pub body: u64,
    /// Its new pose relative to its supart.
    pub pose: Pose,
}

/// What an applied edit made or changed, by id.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
pub struct Outcome {
    /// A body made (or the body changed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub id: Option<u64>,
    /// A face made, or the face that survived.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub face: Option<u64>,
    /// An edge made, or the edge that survived.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edge: Option<u64>,
    /// A vertex made, or the vertex that survived.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vertex: Option<u64>,
    /// Several edges made (GLUEFF).
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub new_edges: Vec<u64>,
    /// The second new face (UNGLUE).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub new_face: Option<u64>,
    /// A body split off (UNGLUE).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub split_off: Option<u64>,
    /// Bodies killed.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub killed: Vec<u64>,
    /// Face, edge and vertex counts of the body made or changed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub faces: Option<usize>,
    /// Edge count.
    #[serde(skip_serializing_if = "Option::is_none", rename = "edges")]
    pub edges_count: Option<usize>,
    /// Vertex count.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vertices: Option<usize>,
    /// The bodies a boolean left, the one kept first (empty when nothing is left).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub pieces: Option<Vec<PieceOutcome>>,
}

/// One body a boolean left (see [`crate::model::Piece`]).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
pub struct PieceOutcome {
    /// The body.
    pub id: u64,
    /// Face count.
    pub faces: usize,
    /// Edge count.
    pub edges: usize,
    /// Vertex count.
    pub vertices: usize,
    /// Volume, cubic meters.
    pub volume: f64,
    /// For each face, `[face, from body, from face]`: the input face it is a piece of
    /// (empty when replayed from the journal, which does not keep it).
    pub sources: Vec<[u64; 3]>,
}

impl PieceOutcome {
    /// Body `id`'s counts and volume, without sources.
    fn of(id: BodyId, body: &Body) -> Self {
        PieceOutcome {
            id: id.get(),
            faces: body.face_count(),
            edges: body.edge_count(),
            vertices: body.vertex_count(),
            volume: body.volume(),
            sources: Vec::new(),
        }
    }
}

/// Why an edit was refused.
#[derive(Debug, thiserror::Error)]
pub enum EditError {
    /// The world refused (unknown ids, a refused Euler operator, bad names, ...).
    #[error(transparent)]
    World(#[from] WorldError),
    /// A solid's parameters are not a solid.
    #[error(transparent)]
    Solid(#[from] SolidError),
    /// The camera described is not a camera.
    #[error(transparent)]
    Camera(#[from] CameraSpecError),
    /// The light described is not a light.
    #[error(transparent)]
    Light(#[from] LightError),
    /// An id that names nothing, or names something of another kind or body.
    #[error("{id} is not the id of any {kind} in body {body}")]
    NotInBody {
        /// The id given.
        id: u64,
        /// The kind expected.
        kind: &'static str,
        /// The body.
        body: u64,
    },
    /// An id that names nothing in the world.
    #[error("no {what} has id {id}")]
    Unknown {
        /// What was looked for.
        what: &'static str,
        /// The id given.
        id: u64,
    },
    /// A request that would make too big a body.
    #[error("the body would have {faces} faces; at most {max} are allowed per request")]
    TooLarge {
        /// Faces it would have.
        faces: usize,
        /// The limit.
        max: usize,
    },
    /// A number that is NaN or infinite, or otherwise out of range.
    #[error("{0}")]
    BadNumber(String),
}

impl EditError {
    /// Whether the refusal is about the world's range (see [`crate::model::range`]).
    pub fn is_out_of_range(&self) -> bool {
        match self {
            EditError::World(e) => e.is_out_of_range(),
            EditError::Solid(e) => e.is_out_of_range(),
            EditError::Camera(CameraSpecError::Camera(e)) => e.is_out_of_range(),
            EditError::Light(e) => e.is_out_of_range(),
            _ => false,
        }
    }
}

impl From<EulerError> for EditError {
    fn from(e: EulerError) -> Self {
        EditError::World(WorldError::Euler(e))
    }
}

impl From<BuildError> for EditError {
    fn from(e: BuildError) -> Self {
        EditError::World(WorldError::Build(e))
    }
}

pub(super) fn body_id(world: &World, id: u64) -> Result<BodyId, EditError> {
    let b = BodyId(Serial(id));
    if world.node(b).is_some() {
        Ok(b)
    } else {
        Err(EditError::Unknown { what: "body", id })
    }
}

fn body_of(world: &World, b: BodyId) -> &Body {
    world.body(b).expect("body_id checked the body")
}

/// The entity of body `b` with serial `id`, found by `find` (a `*_by_serial` lookup),
/// or a 404-class error naming the `kind` sought.
fn in_body<T>(
    world: &World,
    b: BodyId,
    id: u64,
    kind: &'static str,
    find: impl Fn(&Body, Serial) -> Option<T>,
) -> Result<T, EditError> {
    find(body_of(world, b), Serial(id)).ok_or(EditError::NotInBody {
        id,
        kind,
        body: b.get(),
    })
}

fn face_in(world: &World, b: BodyId, id: u64) -> Result<FaceId, EditError> {
    in_body(world, b, id, "face", Body::face_by_serial)
}

fn edge_in(world: &World, b: BodyId, id: u64) -> Result<EdgeId, EditError> {
    in_body(world, b, id, "edge", Body::edge_by_serial)
}

fn vertex_in(world: &World, b: BodyId, id: u64) -> Result<VertexId, EditError> {
    in_body(world, b, id, "vertex", Body::vertex_by_serial)
}

/// The body holding face `id`, wherever it is, and the face.
fn face_anywhere(world: &World, id: u64) -> Result<(BodyId, FaceId), EditError> {
    match world.find_entity(Serial(id)) {
        Some((b, Entity::Face(f))) => Ok((b, f)),
        _ => Err(EditError::Unknown { what: "face", id }),
    }
}

fn finite3(what: &str, p: DVec3) -> Result<DVec3, EditError> {
    if p.is_finite() {
        Ok(p)
    } else {
        Err(EditError::BadNumber(format!("{what} is not finite")))
    }
}

fn check_faces(faces: usize) -> Result<(), EditError> {
    if faces > MAX_BODY_FACES {
        Err(EditError::TooLarge {
            faces,
            max: MAX_BODY_FACES,
        })
    } else {
        Ok(())
    }
}

/// An upper bound on the faces a shape makes, checked before anything is built.
pub(super) fn shape_faces(shape: &Shape) -> usize {
    let (s, r) = match *shape {
        Shape::Cylinder { segments, .. } | Shape::Cone { segments, .. } => (segments as usize, 1),
        Shape::Sphere {
            segments, rings, ..
        }
        | Shape::Torus {
            segments, rings, ..
        } => (segments as usize, rings as usize),
        Shape::Polyhedron { ref faces, .. } => (faces.len(), 1),
        Shape::Prism { ref polygon, .. } | Shape::Pyramid { ref polygon, .. } => (polygon.len(), 1),
        _ => (1, 1),
    };
    s.saturating_mul(r).saturating_add(2)
}

/// Builds the body for `shape` with the world's serials.
fn build(shape: &Shape, s: &mut crate::model::Serials) -> Result<Body, EditError> {
    Ok(match shape {
        Shape::Box { size } => box_solid(s, *size)?,
        Shape::Tetrahedron { radius } => {
            if !(radius.is_finite() && *radius > 0.0) {
                return Err(SolidError::NotPositive {
                    parameter: "radius",
                    value: *radius,
                }
                .into());
            }
            range::length("radius", *radius).map_err(SolidError::from)?;
            mktetra(s, *radius)?
        }
        Shape::Prism { polygon, height } => prism_solid(s, polygon, *height)?,
        Shape::Pyramid { polygon, height } => pyramid_solid(s, polygon, *height)?,
        Shape::Cylinder {
            radius,
            height,
            segments,
        } => cylinder(s, *radius, *height, *segments as usize)?,
        Shape::Cone {
            radius,
            height,
            segments,
        } => cone(s, *radius, *height, *segments as usize)?,
        Shape::Sphere {
            radius,
            segments,
            rings,
        } => sphere(s, *radius, *segments as usize, *rings as usize)?,
        Shape::Torus {
            major_radius,
            minor_radius,
            segments,
            rings,
        } => torus(
            s,
            *major_radius,
            *minor_radius,
            *segments as usize,
            *rings as usize,
        )?,
        Shape::Polyhedron { vertices, faces } => {
            let faces: Vec<&[u32]> = faces.iter().collect();
            Body::from_polygons(s, vertices, &faces)?
        }
        Shape::Seminal { position } => Body::seminal(s, finite3("position", *position)?).0,
    })
}

fn counts(outcome: &mut Outcome, b: &Body) {
    outcome.faces = Some(b.face_count());
    outcome.edges_count = Some(b.edge_count());
    outcome.vertices = Some(b.vertex_count());
}

/// Applies `edit` to `world`: plans it ([`plan`](super::plan)) and applies the plan at
/// once. On refusal the world is unchanged.
pub fn apply(world: &mut World, edit: &Edit) -> Result<Outcome, EditError> {
    let prepared = prepare(edit, world.next_serial())?;
    apply_prepared(world, edit, prepared)
}

/// Applies `edit`, whose world-free work `prepared` holds, to `world`. On refusal the
/// world is unchanged. Precondition: `prepared` was made by [`prepare`] from `edit`.
pub(super) fn apply_prepared(
    world: &mut World,
    edit: &Edit,
    prepared: Prepared,
) -> Result<Outcome, EditError> {
    match edit {
        Edit::CreateBody(req) => {
            let built = match prepared {
                Prepared::Body(built) => *built,
                _ => build_checked(req, world.next_serial())?,
            };
            create(world, req, built)
        }
        Edit::PatchBody { body, patch } => {
            let b = body_id(world, *body)?;
            patch_body(world, b, patch)?;
            Ok(Outcome {
                id: Some(*body),
                ..Outcome::default()
            })
        }
        Edit::PlaceBodies { places } => {
            place_bodies(world, places)?;
            Ok(Outcome::default())
        }
        Edit::DeleteBody { body } => {
            let b = body_id(world, *body)?;
            let killed = world.kill(b)?;
            Ok(Outcome {
                killed: killed.ids().map(|b| b.get()).collect(),
                ..Outcome::default()
            })
        }
        Edit::Euler { body, op } => {
            let b = body_id(world, *body)?;
            euler(world, b, op)
        }
        Edit::Transform { body, motion } => {
            let b = body_id(world, *body)?;
            transform(world, b, motion)?;
            Ok(Outcome {
                id: Some(*body),
                ..Outcome::default()
            })
        }
        Edit::Sweep { body, sweep: req } => {
            let b = body_id(world, *body)?;
            sweep(world, b, req)
        }
        Edit::Dual { body } => {
            let b = body_id(world, *body)?;
            world.edit(b, |body, _| body.fvdual())?;
            let mut o = Outcome {
                id: Some(*body),
                ..Outcome::default()
            };
            counts(&mut o, body_of(world, b));
            Ok(o)
        }
        Edit::Evert { body } => {
            let b = body_id(world, *body)?;
            world.edit(b, |body, _| {
                body.evert();
                Ok::<_, WorldError>(())
            })?;
            Ok(Outcome {
                id: Some(*body),
                ..Outcome::default()
            })
        }
        Edit::Copy { body, name } => {
            let b = body_id(world, *body)?;
            if b == world.root() {
                return Err(WorldError::Root { what: "copied" }.into());
            }
            let node = world.node(b).expect("checked");
            let (supart, pose, color) = (node.supart, node.pose, node.color);
            let original = node.body.clone();
            let id = world.insert_colored_with(name.as_deref(), supart, pose, color, |s| {
                Ok::<_, WorldError>(original.mkcopy(s))
            })?;
            let mut o = Outcome {
                id: Some(id.get()),
                ..Outcome::default()
            };
            counts(&mut o, body_of(world, id));
            Ok(o)
        }
        Edit::PutCamera { name, camera } => {
            let c = match prepared {
                Prepared::Camera(c) => c,
                _ => camera.to_camera()?,
            };
            world.set_camera(name, c)?;
            Ok(Outcome::default())
        }
        Edit::DeleteCamera { name } => {
            world.remove_camera(name)?;
            Ok(Outcome::default())
        }
        Edit::PutLight { name, light } => {
            let l = match prepared {
                Prepared::Light(l) => l,
                _ => light.to_light()?,
            };
            world.set_light(name, l)?;
            Ok(Outcome::default())
        }
        Edit::DeleteLight { name } => {
            world.remove_light(name)?;
            Ok(Outcome::default())
        }
        Edit::Boolean {
            body,
            with,
            op,
            keep_with,
        } => super::boolean::run(world, (*body, *with, *op, *keep_with), None).map(|(_, o)| o),
        Edit::BooleanResult {
            body,
            with,
            keep_with,
            pieces,
            ..
        } => super::boolean::replay(world, *body, *with, *keep_with, pieces),
        Edit::Perception { pieces, removed } => perception(world, pieces, removed),
        Edit::ImportBodies { bodies } => {
            let built = match prepared {
                Prepared::Bodies(built) => Some(built),
                _ => None,
            };
            import_bodies(world, bodies, built)
        }
    }
}

/// Builds each body of an import as [`Built`]s numbered for a world whose next serial is
/// `next`, one after another as they will be inserted.
pub(super) fn build_imported(
    bodies: &[ImportedBody],
    next: Serial,
) -> Result<Vec<Built>, EditError> {
    let mut out = Vec::with_capacity(bodies.len());
    let mut next = next;
    for b in bodies {
        check_faces(b.faces.len())?;
        let faces: Vec<&[u32]> = b.faces.iter().collect();
        let built = Built::expecting(next, |s| {
            Body::from_polygons(s, &b.vertices, &faces)
                .map_err(|e| EditError::from(SolidError::from(e)))
        })?;
        next = built.next_serial();
        out.push(built);
    }
    Ok(out)
}

/// Inserts an import's bodies on a copy of the world that replaces it only when every
/// body went in: a refusal leaves the world as it was.
fn import_bodies(
    world: &mut World,
    bodies: &[ImportedBody],
    built: Option<Vec<Built>>,
) -> Result<Outcome, EditError> {
    let built = match built {
        Some(b) if b.len() == bodies.len() => b,
        _ => build_imported(bodies, world.next_serial())?,
    };
    let mut next = world.clone();
    let mut ids: Vec<BodyId> = Vec::with_capacity(bodies.len());
    let mut placed = Vec::with_capacity(bodies.len());
    for (k, (b, built)) in bodies.iter().zip(built).enumerate() {
        let parent = match (b.within, b.parent) {
            (Some(i), _) => *ids.get(i).filter(|_| i < k).ok_or_else(|| {
                EditError::BadNumber(format!(
                    "body {k} of the import is to be a part of body {i}, which does not come before it"
                ))
            })?,
            (None, Some(p)) => body_id(&next, p)?,
            (None, None) => next.root(),
        };
        let pose = b.pose.unwrap_or(Pose::IDENTITY);
        let id = next.insert_built(built, b.name.as_deref(), parent, pose, b.color)?;
        ids.push(id);
        placed.push(PieceOutcome::of(id, body_of(&next, id)));
    }
    *world = next;
    Ok(Outcome {
        id: ids.first().map(|b| b.get()),
        pieces: Some(placed),
        ..Outcome::default()
    })
}

/// Places perception's result on a copy of the world that replaces it only when every
/// piece was placed: a refusal leaves the world as it was.
fn perception(
    world: &mut World,
    pieces: &[PerceivedPiece],
    removed: &[u64],
) -> Result<Outcome, EditError> {
    let mut next = world.clone();
    let mut killed = Vec::new();
    for &id in removed {
        let b = body_id(&next, id)?;
        if next.perceived(b).is_none() {
            return Err(WorldError::NotProvisional(b).into());
        }
        killed.extend(next.kill(b)?.ids().map(|b| b.get()));
    }
    let mut placed = Vec::with_capacity(pieces.len());
    for piece in pieces {
        let faces: Vec<Vec<u32>> = piece.faces.iter().map(<[u32]>::to_vec).collect();
        let shell = PerceivedShell {
            positions: &piece.positions,
            faces: &faces,
            makers: &piece.makers,
            views: piece.views,
            outline_px: piece.outline_px,
        };
        let b = match piece.body {
            Some(id) => {
                let b = body_id(&next, id)?;
                next.recarve_perceived(b, &shell)?;
                b
            }
            None => next.insert_perceived(piece.name.as_deref(), &shell)?,
        };
        placed.push(PieceOutcome::of(b, body_of(&next, b)));
    }
    *world = next;
    Ok(Outcome {
        pieces: Some(placed),
        killed,
        ..Outcome::default()
    })
}

/// The body `req` asks for, built and checked apart from any world (see [`Built`]),
/// numbered for a world whose next serial is `next`.
pub(super) fn build_checked(req: &CreateBody, next: Serial) -> Result<Built, EditError> {
    check_faces(shape_faces(&req.shape))?;
    Built::expecting(next, |s| build(&req.shape, s))
}

fn create(world: &mut World, req: &CreateBody, built: Built) -> Result<Outcome, EditError> {
    let parent = match req.parent {
        Some(p) => body_id(world, p)?,
        None => world.root(),
    };
    let pose = req.pose.unwrap_or(Pose::IDENTITY);
    let color = req.color;
    let id = world.insert_built(built, req.name.as_deref(), parent, pose, color)?;
    let body = body_of(world, id);
    let mut o = Outcome {
        id: Some(id.get()),
        ..Outcome::default()
    };
    counts(&mut o, body);
    if matches!(req.shape, Shape::Seminal { .. }) {
        o.face = body.faces().next().map(|f| body.face_serial(f).get());
        o.vertex = body.vertices().next().map(|v| body.vertex_serial(v).get());
    }
    Ok(o)
}

fn patch_body(world: &mut World, b: BodyId, patch: &PatchBody) -> Result<(), EditError> {
    let parent = patch.parent.map(|p| body_id(world, p)).transpose()?;
    let name = patch.name.as_ref().map(|n| n.as_deref());
    world.update(b, name, parent, patch.pose, patch.color)?;
    Ok(())
}

/// Gives each body its new pose, on a copy of the world that replaces it only when every
/// body took its pose: a refusal leaves the world as it was. (The world's maps are
/// persistent, so the copy shares everything the poses do not change.)
fn place_bodies(world: &mut World, places: &[Place]) -> Result<(), EditError> {
    let mut next = world.clone();
    for place in places {
        let b = body_id(&next, place.body)?;
        next.update(b, None, None, Some(place.pose), None)?;
    }
    *world = next;
    Ok(())
}

fn euler(world: &mut World, b: BodyId, op: &EulerOp) -> Result<Outcome, EditError> {
    let sv = |body: &Body, v: VertexId| body.vertex_serial(v).get();
    let se = |body: &Body, e: EdgeId| body.edge_serial(e).get();
    let sf = |body: &Body, f: FaceId| body.face_serial(f).get();
    let mut o = Outcome {
        id: Some(b.get()),
        ..Outcome::default()
    };
    match *op {
        EulerOp::Mkev {
            face,
            vertex,
            position,
        } => {
            let (f, v) = (face_in(world, b, face)?, vertex_in(world, b, vertex)?);
            let pos = match position {
                Some(p) => finite3("position", p)?,
                None => body_of(world, b).position(v),
            };
            let (e, vnew) = world.edit(b, |body, s| body.mkev(s, f, v, pos))?;
            let body = body_of(world, b);
            o.edge = Some(se(body, e));
            o.vertex = Some(sv(body, vnew));
        }
        EulerOp::Mkfe { v1, face, v2 } => {
            let f = face_in(world, b, face)?;
            let (a, c) = (vertex_in(world, b, v1)?, vertex_in(world, b, v2)?);
            let (e, fnew) = world.edit(b, |body, s| body.mkfe(s, a, f, c))?;
            let body = body_of(world, b);
            o.edge = Some(se(body, e));
            o.face = Some(sf(body, fnew));
        }
        EulerOp::Esplit { edge, position } => {
            let e = edge_in(world, b, edge)?;
            let pos = match position {
                Some(p) => finite3("position", p)?,
                None => {
                    let body = body_of(world, b);
                    let r = body.edge(e);
                    body.position(r.nvt()).lerp(body.position(r.pvt()), 0.5)
                }
            };
            let (enew, vnew) = world.edit(b, |body, s| body.esplit(s, e, pos))?;
            let body = body_of(world, b);
            o.edge = Some(se(body, enew));
            o.vertex = Some(sv(body, vnew));
        }
        EulerOp::Klfe { edge } => {
            let e = edge_in(world, b, edge)?;
            let f = world.edit(b, |body, _| body.klfe(e))?;
            o.face = Some(sf(body_of(world, b), f));
        }
        EulerOp::Klev { vertex } => {
            let v = vertex_in(world, b, vertex)?;
            let keep = world.edit(b, |body, _| body.klev(v))?;
            o.vertex = Some(sv(body_of(world, b), keep));
        }
        EulerOp::Klve { edge } => {
            let e = edge_in(world, b, edge)?;
            let keep = world.edit(b, |body, _| body.klve(e))?;
            o.vertex = Some(sv(body_of(world, b), keep));
        }
        EulerOp::Invert { edge } => {
            let e = edge_in(world, b, edge)?;
            world.edit(b, |body, _| {
                body.invert(e);
                Ok::<_, WorldError>(())
            })?;
            o.edge = Some(edge);
        }
        EulerOp::Glue {
            face1,
            face2,
            vertex1,
            vertex2,
        } => {
            let f1 = face_in(world, b, face1)?;
            let (b2, f2) = face_anywhere(world, face2)?;
            let v1 = match vertex1 {
                Some(v) => vertex_in(world, b, v)?,
                None => {
                    let body = body_of(world, b);
                    body.face_vertices(f1)
                        .next()
                        .ok_or(EulerError::FaceTooSmall {
                            face: body.face_serial(f1),
                            degree: 0,
                        })?
                }
            };
            let v2 = match vertex2 {
                Some(v) => vertex_in(world, b2, v)?,
                None => nearest_vertex(world, b, v1, b2, f2)?,
            };
            world.glue(b, f1, v1, b2, f2, v2)?;
            absorbed(&mut o, b, b2);
        }
        EulerOp::Gluee {
            face1,
            vertex1,
            face2,
            vertex2,
        } => {
            let (f1, v1) = (face_in(world, b, face1)?, vertex_in(world, b, vertex1)?);
            let (b2, f2) = face_anywhere(world, face2)?;
            let v2 = vertex_in(world, b2, vertex2)?;
            let e = world.gluee(b, f1, v1, b2, f2, v2)?;
            o.edge = Some(se(body_of(world, b), e));
            absorbed(&mut o, b, b2);
        }
        EulerOp::Glueff { face1, face2 } => {
            let f1 = face_in(world, b, face1)?;
            let (b2, f2) = face_anywhere(world, face2)?;
            let made = world.glueff(b, f1, b2, f2)?;
            absorbed(&mut o, b, b2);
            let body = body_of(world, b);
            o.new_edges = made.iter().map(|&e| se(body, e)).collect();
        }
        EulerOp::Unglue { ref edges } => {
            let seam = edges
                .iter()
                .map(|&e| edge_in(world, b, e))
                .collect::<Result<Vec<_>, _>>()?;
            let cut = world.unglue(b, &seam)?;
            o.face = Some(sf(body_of(world, b), cut.kept_face));
            let holder = cut.split_off.unwrap_or(b);
            o.new_face = Some(sf(body_of(world, holder), cut.new_face));
            o.split_off = cut.split_off.map(|s| s.get());
        }
    }
    counts(&mut o, body_of(world, b));
    Ok(o)
}

/// Notes in `o` that gluing body `b2` into `b` removed `b2` (when they differ).
fn absorbed(o: &mut Outcome, b: BodyId, b2: BodyId) {
    if b2 != b {
        o.killed.push(b2.get());
    }
}

/// The vertex of face `f2` (body `b2`) nearest, in the world, to vertex `v1` of body `b`.
fn nearest_vertex(
    world: &World,
    b: BodyId,
    v1: VertexId,
    b2: BodyId,
    f2: FaceId,
) -> Result<VertexId, EditError> {
    let p1 = world.world_position(b, v1).expect("checked vertex");
    let body2 = body_of(world, b2);
    body2
        .face_vertices(f2)
        .min_by(|&x, &y| {
            let dx = world
                .world_position(b2, x)
                .map_or(f64::INFINITY, |p| p.distance(p1));
            let dy = world
                .world_position(b2, y)
                .map_or(f64::INFINITY, |p| p.distance(p1));
            dx.total_cmp(&dy)
        })
        .ok_or_else(|| {
            EulerError::FaceTooSmall {
                face: body2.face_serial(f2),
                degree: 0,
            }
            .into()
        })
}

fn transform(world: &mut World, b: BodyId, req: &Move) -> Result<(), EditError> {
    let t = match req.motion {
        Motion::Translate { vector } => Transform::Translate(finite3("vector", vector)?),
        Motion::Rotate {
            axis,
            angle_deg,
            center,
        } => Transform::Rotate {
            axis: finite3("axis", axis)?,
            angle_rad: angle_deg.to_radians(),
            center: finite3("center", center)?,
        },
        Motion::Dilate { factor, center } => Transform::Dilate {
            factor,
            center: finite3("center", center)?,
        },
        Motion::Reflect { normal, point } => Transform::Reflect {
            normal: finite3("normal", normal)?,
            point: finite3("point", point)?,
        },
    };
    let frame = req.frame;
    let what = match req.target {
        None => Entity::Body,
        Some(id) => match world.find_entity(Serial(id)) {
            Some((owner, e)) if owner == b && e != Entity::Body => e,
            _ => {
                return Err(EditError::NotInBody {
                    id,
                    kind: "face, edge or vertex",
                    body: b.get(),
                });
            }
        },
    };
    world.transform(b, what, &t, frame)?;
    Ok(())
}

fn sweep(world: &mut World, b: BodyId, req: &Sweep) -> Result<Outcome, EditError> {
    let f = face_in(world, b, req.face)?;
    let body = body_of(world, b);
    let plane = body.face_plane(f).ok_or(SolidError::DegenerateFace {
        face: body.face_serial(f),
    })?;
    let center = body.face_center(f);
    let distance = req.distance.unwrap_or(1.0);
    if !distance.is_finite() {
        return Err(EditError::BadNumber("distance is not finite".into()));
    }
    let scale = req.scale.unwrap_or(1.0);
    let cap = match req.kind {
        SweepKind::Pyramid => {
            let peak = match req.peak {
                Some(p) => finite3("peak", p)?,
                None => center + plane.normal * distance,
            };
            world.edit(b, |body, s| body.pyramid(s, f, peak).map(|_| f))?
        }
        kind => {
            let offset = match req.offset {
                Some(o) => finite3("offset", o)?,
                None => plane.normal * distance,
            };
            world.edit(b, |body, s| match kind {
                SweepKind::Prism => body.prism(s, f, offset, scale).map(|w| w.cap),
                SweepKind::CwPrismoid => {
                    body.prismoid(s, f, offset, scale, Twist::Cw).map(|w| w.cap)
                }
                _ => body
                    .prismoid(s, f, offset, scale, Twist::Ccw)
                    .map(|w| w.cap),
            })?
        }
    };
    let body = body_of(world, b);
    let mut o = Outcome {
        id: Some(b.get()),
        face: Some(body.face_serial(cap).get()),
        ..Outcome::default()
    };
    counts(&mut o, body);
    Ok(o)
}
