//! Planning an edit: the part of its work that needs no world (building a shape and
//! checking it, reading a camera or a light), done before the world's owner takes the
//! edit. A plan is made anywhere, on any thread; only [`Planned::apply`] touches the
//! world. So a body of a million faces is built beside the owner, which then only gives
//! it serials and inserts it, while other writes go on.
//!
//! Applying a plan gives exactly what [`apply`](super::apply()) gives for the same edit
//! on the same world, ids included: a body is built with serials numbered from 1 and
//! takes its place in the world's serials when inserted (see [`Built`]).

use super::apply::{
    Edit, EditError, Outcome, apply_prepared, build_checked, build_imported, shape_faces,
};
use super::boolean::Solved;
use crate::model::{Built, Camera, Light, Serial, World};

/// Faces from which a new body is worth building away from the world's owner: below
/// this the hand-over costs more than the build (a box, a 32-sided cylinder).
pub const HEAVY_FACES: usize = 4_096;

/// The world-free work of one edit, done.
#[derive(Debug)]
pub(super) enum Prepared {
    /// Nothing to do before the world is at hand.
    Nothing,
    /// The new body, built and checked (boxed: the other plans are small).
    Body(Box<Built>),
    /// The camera described, checked.
    Camera(Camera),
    /// The light described, checked.
    Light(Light),
    /// A boolean solved on a snapshot (boxed: the other plans are small).
    Boolean(Box<Solved>),
    /// The bodies of an import, built and checked, numbered one after another.
    Bodies(Vec<Built>),
}

/// Does the world-free work of `edit`, numbering a new body for a world whose next
/// serial is `next`. Refused as [`apply`](super::apply()) would refuse it for a reason
/// that does not depend on the world.
pub(super) fn prepare(edit: &Edit, next: Serial) -> Result<Prepared, EditError> {
    Ok(match edit {
        Edit::CreateBody(req) => Prepared::Body(Box::new(build_checked(req, next)?)),
        Edit::ImportBodies { bodies } => Prepared::Bodies(build_imported(bodies, next)?),
        Edit::PutCamera { camera, .. } => Prepared::Camera(camera.to_camera()?),
        Edit::PutLight { light, .. } => Prepared::Light(light.to_light()?),
        _ => Prepared::Nothing,
    })
}

/// An edit whose world-free work is done, ready for the world's owner.
#[derive(Debug)]
pub struct Planned {
    edit: Box<Edit>,
    prepared: Prepared,
}

/// Plans `edit`: does the work that needs no world. Refused with the error
/// [`apply`](super::apply()) would give for it on any world (a shape that is not a
/// solid, too many faces, a camera or a light that is not one); what depends on the
/// world (ids, names, the parts tree, ranges of placed bodies) is checked when the plan
/// is applied.
pub fn plan(edit: Box<Edit>) -> Result<Planned, EditError> {
    plan_expecting(edit, Serial(1))
}

/// [`plan`], numbering a new body for a world whose next serial is `next` (the one a
/// recent snapshot shows, say): if the world is still there when the plan is applied,
/// the body goes in without a pass over its serials. Any `next` gives the same result.
pub fn plan_expecting(edit: Box<Edit>, next: Serial) -> Result<Planned, EditError> {
    let prepared = prepare(&edit, next)?;
    Ok(Planned { edit, prepared })
}

/// Plans an import ([`Edit::ImportBodies`]) whose bodies are already built: `built[k]`
/// is `bodies[k]` built by [`Built::new`] (or for any next serial) and checked, as
/// [`crate::mesh`] leaves them. The owner then only inserts them.
///
/// Refused when the lists differ in length or a built body does not have the faces
/// and vertices its entry lists (they were not built from it), or has too many faces.
pub fn plan_import(
    bodies: Vec<super::command::ImportedBody>,
    built: Vec<Built>,
) -> Result<Planned, EditError> {
    let matches = bodies.len() == built.len()
        && bodies.iter().zip(&built).all(|(b, built)| {
            built.body().face_count() == b.faces.len()
                && built.body().vertex_count() == b.vertices.len()
        });
    if !matches {
        return Err(EditError::BadNumber(
            "the built bodies are not those of the import".into(),
        ));
    }
    for b in &bodies {
        if b.faces.len() > super::apply::MAX_BODY_FACES {
            return Err(EditError::TooLarge {
                faces: b.faces.len(),
                max: super::apply::MAX_BODY_FACES,
            });
        }
    }
    Ok(Planned {
        edit: Box::new(Edit::ImportBodies { bodies }),
        prepared: Prepared::Bodies(built),
    })
}

/// Plans `edit` with a snapshot of the world at hand: as [`plan_expecting`], and a
/// boolean ([`Edit::Boolean`]) is solved on the snapshot, so that the owner only places
/// its result, if the world is still on the same basis when the plan is applied (else
/// the owner runs the kernel itself). Any snapshot gives the same result.
pub fn plan_on(edit: Box<Edit>, snapshot: &World, next: Serial) -> Result<Planned, EditError> {
    if let Edit::Boolean { body, with, op, .. } = *edit {
        let prepared = match super::boolean::solve_ahead(snapshot, body, with, op) {
            Some(solved) => Prepared::Boolean(Box::new(solved)),
            None => Prepared::Nothing,
        };
        return Ok(Planned { edit, prepared });
    }
    plan_expecting(edit, next)
}

impl Planned {
    /// The edit planned.
    pub fn edit(&self) -> &Edit {
        &self.edit
    }

    /// Applies the plan to `world`, giving back the edit to journal with the outcome.
    /// That is the edit planned, except for a boolean ([`Edit::Boolean`]): the journal
    /// keeps the geometry it made ([`Edit::BooleanResult`]), so a replay applies that
    /// without running the kernel. On refusal the world is unchanged and the edit
    /// planned is given back.
    pub fn apply(self, world: &mut World) -> (Box<Edit>, Result<Outcome, EditError>) {
        if let Edit::Boolean {
            body,
            with,
            op,
            keep_with,
        } = *self.edit
        {
            let ahead = match self.prepared {
                Prepared::Boolean(solved) => Some(*solved),
                _ => None,
            };
            return match super::boolean::run(world, (body, with, op, keep_with), ahead) {
                Ok((journaled, outcome)) => (Box::new(journaled), Ok(outcome)),
                Err(e) => (self.edit, Err(e)),
            };
        }
        let outcome = apply_prepared(world, &self.edit, self.prepared);
        (self.edit, outcome)
    }
}

impl Edit {
    /// Whether planning this edit is worth a thread of its own: it builds a body of at
    /// least [`HEAVY_FACES`] faces, or it is a boolean (planned on a snapshot with
    /// [`plan_on`]).
    pub fn is_heavy(&self) -> bool {
        match self {
            Edit::CreateBody(req) => shape_faces(&req.shape) >= HEAVY_FACES,
            Edit::ImportBodies { bodies } => {
                bodies.iter().map(|b| b.faces.len()).sum::<usize>() >= HEAVY_FACES
            }
            Edit::Boolean { .. } => true,
            _ => false,
        }
    }

    /// Whether planning this edit wants a snapshot of the world ([`plan_on`]).
    pub fn wants_snapshot(&self) -> bool {
        matches!(self, Edit::Boolean { .. })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edit::apply;
    use crate::edit::command::{CreateBody, Shape};
    use crate::model::Pose;
    use crate::model::check_topology;
    use glam::{DQuat, DVec3};

    fn create(name: &str, shape: Shape) -> Edit {
        Edit::CreateBody(CreateBody {
            name: Some(name.into()),
            parent: None,
            pose: Some(Pose {
                position: DVec3::new(1.0, 2.0, 3.0),
                rotation: DQuat::IDENTITY,
            }),
            color: None,
            shape,
        })
    }

    fn sphere(segments: u32, rings: u32) -> Shape {
        Shape::Sphere {
            radius: 2.0,
            segments,
            rings,
        }
    }

    /// A world with a few bodies and some serials spent, so that a new body's serials do
    /// not start at 1.
    fn busy_world() -> World {
        let mut w = World::new();
        apply(&mut w, &create("a", Shape::Box { size: DVec3::ONE })).expect("a box");
        apply(&mut w, &create("b", sphere(8, 4))).expect("a sphere");
        w
    }

    #[test]
    fn a_planned_body_gets_the_ids_a_build_inside_the_world_gives() {
        for (i, shape) in [
            sphere(64, 32),
            Shape::Box {
                size: DVec3::new(1.0, 2.0, 3.0),
            },
            Shape::Seminal {
                position: DVec3::new(0.5, 0.0, 0.0),
            },
            Shape::Torus {
                major_radius: 3.0,
                minor_radius: 1.0,
                segments: 24,
                rings: 12,
            },
        ]
        .into_iter()
        .enumerate()
        {
            let edit = create(&format!("new{i}"), shape);
            let mut inside = busy_world();
            let direct = apply(&mut inside, &edit).expect("applied inside");
            let mut beside = busy_world();
            let planned = plan(Box::new(edit.clone())).expect("planned");
            let (back, outcome) = planned.apply(&mut beside);
            assert_eq!(*back, edit, "the plan gives its edit back");
            assert_eq!(outcome.expect("applied from the plan"), direct);
            assert_eq!(
                serde_json::to_value(&beside).expect("serializes"),
                serde_json::to_value(&inside).expect("serializes"),
                "the same world, serials and all"
            );
            for (_, node) in beside.bodies() {
                let report = check_topology(&node.body);
                assert!(report.is_ok(), "{report:?}");
            }
        }
    }

    #[test]
    fn a_plan_refused_by_the_world_changes_nothing() {
        let mut w = busy_world();
        let before = serde_json::to_value(&w).expect("serializes");
        // The name is taken: only the world can tell.
        let planned = plan(Box::new(create("a", sphere(64, 32)))).expect("planned");
        let (_, outcome) = planned.apply(&mut w);
        assert!(outcome.is_err(), "a taken name is refused");
        assert_eq!(serde_json::to_value(&w).expect("serializes"), before);
        // The next body takes the serials a refused plan did not.
        let mut fresh = busy_world();
        let made = apply(&mut w, &create("c", sphere(6, 3))).expect("made");
        let also = apply(&mut fresh, &create("c", sphere(6, 3))).expect("made");
        assert_eq!(made, also);
    }

    #[test]
    fn what_needs_no_world_is_refused_by_the_plan() {
        let too_big = create("big", sphere(4_000, 1_000));
        assert!(matches!(
            plan(Box::new(too_big)),
            Err(EditError::TooLarge { .. })
        ));
        let flat = create(
            "flat",
            Shape::Box {
                size: DVec3::new(1.0, 0.0, 1.0),
            },
        );
        assert!(plan(Box::new(flat)).is_err());
    }

    #[test]
    fn only_large_bodies_are_heavy() {
        assert!(create("s", sphere(128, 64)).is_heavy());
        assert!(!create("s", sphere(32, 16)).is_heavy());
        assert!(!Edit::Dual { body: 1 }.is_heavy());
    }
}
