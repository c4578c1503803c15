//! Changes: what each applied write did to the world, in the terms clients watch.
//!
//! Every applied [`Edit`] is described by one [`Change`] carrying the world revision it
//! produced and, for each body, camera or light it touched, whether it was added,
//! updated or removed and which of its fields changed. Clients that keep a copy of the
//! world read these from `GET /v1/world/changes?since=N` or the `GET /v1/world/events`
//! stream and fetch what they care about again.
//!
//! A description needs a little of the world as it was before the edit (a body's old
//! supart, whether a camera already existed): take a [`Before`] with [`before`] just
//! before applying, then [`describe`] after.

use serde::{Deserialize, Serialize};

use crate::edit::command::Motion;
use crate::edit::{Edit, Outcome};
use crate::model::{BodyId, Serial, World};

/// What one applied write changed.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Change {
    /// The world revision the write produced.
    pub revision: u64,
    /// The kind of write, as in the journal (`create_body`, `euler`, `put_camera`, ...).
    pub edit: String,
    /// Each entity touched.
    pub changes: Vec<EntityChange>,
}

/// How an entity was touched.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Action {
    /// It is new.
    Added,
    /// Some of its fields changed.
    Updated,
    /// It is gone.
    Removed,
}

/// The kind of entity touched.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// A body in the parts tree (named by `id`).
    Body,
    /// A camera (named by `name`).
    Camera,
    /// A light (named by `name`).
    Light,
}

/// A field of a body that a write changed.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum Field {
    /// Its name.
    Name,
    /// Its supart.
    Parent,
    /// Its pose relative to its supart.
    Pose,
    /// Its list of sub-parts.
    Parts,
    /// Its faces, edges and vertices (and possibly their loci).
    Topology,
    /// Its vertex loci only; the structure is the same.
    Geometry,
    /// Its material colour.
    Color,
}

/// One entity touched by a write.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct EntityChange {
    /// Added, updated or removed.
    pub action: Action,
    /// Body, camera or light.
    pub kind: Kind,
    /// A body's id.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub id: Option<u64>,
    /// A camera's or light's name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// For an update of a body, the fields that changed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fields: Vec<Field>,
}

impl EntityChange {
    /// Body `id` touched by `action`, with the `fields` an update changed.
    pub(crate) fn body(action: Action, id: u64, fields: &[Field]) -> Self {
        EntityChange {
            action,
            kind: Kind::Body,
            id: Some(id),
            name: None,
            fields: fields.to_vec(),
        }
    }

    fn named(action: Action, kind: Kind, name: &str) -> Self {
        EntityChange {
            action,
            kind,
            id: None,
            name: Some(name.to_owned()),
            fields: Vec::new(),
        }
    }
}

/// What a description needs of the world before an edit.
#[derive(Clone, Debug, Default)]
pub struct Before {
    /// `(body, supart)` for the bodies the edit names.
    suparts: Vec<(u64, u64)>,
    /// Whether the camera or light the edit names existed.
    existed: bool,
}

impl Before {
    fn supart_of(&self, body: u64) -> Option<u64> {
        self.suparts
            .iter()
            .find(|(b, _)| *b == body)
            .map(|(_, s)| *s)
    }
}

/// Takes what [`describe`] will need, from `world` as it is before `edit` is applied.
pub fn before(world: &World, edit: &Edit) -> Before {
    let supart = |id: u64| {
        world
            .supart(BodyId(Serial(id)))
            .map(|s| (id, s.get()))
            .into_iter()
    };
    match edit {
        Edit::PatchBody { body, .. }
        | Edit::DeleteBody { body }
        | Edit::Euler { body, .. }
        | Edit::Copy { body, .. } => {
            let mut suparts: Vec<(u64, u64)> = supart(*body).collect();
            // A glue names a second body through its face; note that body's supart too.
            if let Edit::Euler { op, .. } = edit
                && let Some(face2) = op.second_face()
                && let Some((b2, _)) = world.find_entity(Serial(face2))
            {
                suparts.extend(supart(b2.get()));
            }
            Before {
                suparts,
                existed: false,
            }
        }
        Edit::Boolean { body, with, .. } | Edit::BooleanResult { body, with, .. } => Before {
            suparts: supart(*body).chain(supart(*with)).collect(),
            existed: false,
        },
        Edit::Perception { removed, .. } => Before {
            suparts: removed.iter().flat_map(|&b| supart(b)).collect(),
            existed: false,
        },
        Edit::PutCamera { name, .. } => Before {
            suparts: Vec::new(),
            existed: world.camera(name).is_some(),
        },
        Edit::PutLight { name, .. } => Before {
            suparts: Vec::new(),
            existed: world.light(name).is_some(),
        },
        _ => Before::default(),
    }
}

/// Describes `edit`, applied with `outcome`, which brought `after` to `revision`.
///
/// Precondition: `before` was taken by [`before`] from the world just before `edit`
/// was applied, and the apply succeeded.
pub fn describe(
    revision: u64,
    edit: &Edit,
    outcome: &Outcome,
    before: &Before,
    after: &World,
) -> Change {
    use Action::{Added, Removed, Updated};
    let mut changes = Vec::new();
    let parts_of = |changes: &mut Vec<EntityChange>, supart: Option<u64>| {
        if let Some(s) = supart {
            changes.push(EntityChange::body(Updated, s, &[Field::Parts]));
        }
    };
    match edit {
        Edit::CreateBody(_) | Edit::Copy { .. } => {
            if let Some(id) = outcome.id {
                changes.push(EntityChange::body(Added, id, &[]));
                parts_of(
                    &mut changes,
                    after.supart(BodyId(Serial(id))).map(|s| s.get()),
                );
            }
        }
        Edit::PatchBody { body, patch } => {
            let mut fields = Vec::new();
            if patch.name.is_some() {
                fields.push(Field::Name);
            }
            let old = before.supart_of(*body);
            let new = after.supart(BodyId(Serial(*body))).map(|s| s.get());
            let moved = patch.parent.is_some() && old != new;
            if moved {
                fields.push(Field::Parent);
            }
            if patch.pose.is_some() || moved {
                fields.push(Field::Pose);
            }
            if patch.color.is_some() {
                fields.push(Field::Color);
            }
            changes.push(EntityChange::body(Updated, *body, &fields));
            if moved {
                parts_of(&mut changes, old);
                parts_of(&mut changes, new);
            }
        }
        Edit::PlaceBodies { places } => {
            for place in places {
                changes.push(EntityChange::body(Updated, place.body, &[Field::Pose]));
            }
        }
        Edit::DeleteBody { body } => {
            changes.extend(
                outcome
                    .killed
                    .iter()
                    .map(|&k| EntityChange::body(Removed, k, &[])),
            );
            parts_of(&mut changes, before.supart_of(*body));
        }
        Edit::Euler { body, .. } => {
            let mut fields = vec![Field::Topology];
            if !outcome.killed.is_empty() {
                // A glue across bodies takes in the other body's sub-parts.
                fields.push(Field::Parts);
            }
            changes.push(EntityChange::body(Updated, *body, &fields));
            for &k in &outcome.killed {
                changes.push(EntityChange::body(Removed, k, &[]));
                let old = before.supart_of(k);
                if old != Some(*body) {
                    parts_of(&mut changes, old);
                }
            }
            if let Some(s) = outcome.split_off {
                changes.push(EntityChange::body(Added, s, &[]));
                parts_of(
                    &mut changes,
                    after.supart(BodyId(Serial(s))).map(|p| p.get()),
                );
            }
        }
        Edit::Transform { body, motion } => {
            let rigid = matches!(
                motion.motion,
                Motion::Translate { .. } | Motion::Rotate { .. }
            );
            let field = if motion.target.is_none() && rigid {
                Field::Pose
            } else {
                Field::Geometry
            };
            changes.push(EntityChange::body(Updated, *body, &[field]));
        }
        Edit::Sweep { body, .. } | Edit::Dual { body } | Edit::Evert { body } => {
            changes.push(EntityChange::body(Updated, *body, &[Field::Topology]));
        }
        Edit::Boolean { body, with, .. } | Edit::BooleanResult { body, with, .. } => {
            boolean(&mut changes, *body, *with, outcome, before);
        }
        Edit::PutCamera { name, .. } => {
            let action = if before.existed { Updated } else { Added };
            changes.push(EntityChange::named(action, Kind::Camera, name));
        }
        Edit::DeleteCamera { name } => {
            changes.push(EntityChange::named(Removed, Kind::Camera, name));
        }
        Edit::PutLight { name, .. } => {
            let action = if before.existed { Updated } else { Added };
            changes.push(EntityChange::named(action, Kind::Light, name));
        }
        Edit::DeleteLight { name } => {
            changes.push(EntityChange::named(Removed, Kind::Light, name));
        }
        Edit::Perception { pieces, .. } => {
            // New bodies go under the world; removed ones were provisional bodies there
            // or wherever a user moved them.
            let mut suparts = Vec::new();
            let placed = outcome.pieces.as_deref().unwrap_or_default();
            for (piece, p) in pieces.iter().zip(placed) {
                if piece.body.is_some() {
                    changes.push(EntityChange::body(Updated, p.id, &[Field::Topology]));
                } else {
                    changes.push(EntityChange::body(Added, p.id, &[]));
                    suparts.extend(after.supart(BodyId(Serial(p.id))).map(|s| s.get()));
                }
            }
            for &k in &outcome.killed {
                changes.push(EntityChange::body(Removed, k, &[]));
                suparts.extend(before.supart_of(k));
            }
            suparts.sort_unstable();
            suparts.dedup();
            for s in suparts {
                parts_of(&mut changes, Some(s));
            }
        }
        Edit::ImportBodies { .. } => {
            // Every body is new; a supart outside the import gains parts.
            let placed = outcome.pieces.as_deref().unwrap_or_default();
            let new: Vec<u64> = placed.iter().map(|p| p.id).collect();
            let mut suparts = Vec::new();
            for &id in &new {
                changes.push(EntityChange::body(Added, id, &[]));
                suparts.extend(
                    after
                        .supart(BodyId(Serial(id)))
                        .map(|s| s.get())
                        .filter(|s| !new.contains(s)),
                );
            }
            suparts.sort_unstable();
            suparts.dedup();
            for s in suparts {
                parts_of(&mut changes, Some(s));
            }
        }
    }
    Change {
        revision,
        edit: edit.kind().to_owned(),
        changes,
    }
}

/// The changes of a boolean that kept `body` and took `with`: `body` reshaped (unless
/// killed), the pieces added beside it, the bodies killed removed, and the parts lists
/// of the suparts that gained or lost a body, each once.
fn boolean(
    changes: &mut Vec<EntityChange>,
    body: u64,
    with: u64,
    outcome: &Outcome,
    before: &Before,
) {
    use Action::{Added, Removed, Updated};
    let pieces = outcome.pieces.as_deref().unwrap_or_default();
    let mut suparts = Vec::new();
    if !pieces.is_empty() {
        changes.push(EntityChange::body(Updated, body, &[Field::Topology]));
    }
    if pieces.len() > 1 {
        suparts.extend(before.supart_of(body));
    }
    for p in pieces.iter().skip(1) {
        changes.push(EntityChange::body(Added, p.id, &[]));
    }
    for &k in &outcome.killed {
        changes.push(EntityChange::body(Removed, k, &[]));
        if k == body || k == with {
            suparts.extend(before.supart_of(k));
        }
    }
    suparts.sort_unstable();
    suparts.dedup();
    for s in suparts {
        if !outcome.killed.contains(&s) {
            changes.push(EntityChange::body(Updated, s, &[Field::Parts]));
        }
    }
}
