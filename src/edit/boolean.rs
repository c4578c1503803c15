//! Booleans in the edit language: a request ([`Edit::Boolean`]) is applied by running the
//! kernel and gives the geometry it made ([`Edit::BooleanResult`]), which is what the
//! journal keeps and what a replay applies, without the kernel.
//!
//! Both place the same shells with [`World::place_boolean`] on the same world, so a
//! replay gives the same bodies, ids and serials as the live run.

use super::apply::{Edit, EditError, Outcome, PieceOutcome, body_id};
use super::command::{BooleanPiece, FaceList};
use crate::model::boolean::Op;
use crate::model::boolean::Solution;
use crate::model::{BooleanBasis, BooleanOutcome, ShellRef, World, WorldError};

/// A boolean's solution computed ahead, on a snapshot of the world, with what it was
/// computed from.
#[derive(Debug)]
pub(super) struct Solved {
    basis: BooleanBasis,
    solution: Result<Solution, WorldError>,
}

/// Computes the boolean `op` of bodies `body` and `with` on `snapshot`, to be placed by
/// [`run`] if the world is still on the same basis then. `None` when the operands are
/// refused before the kernel runs (the owner refuses them again, at no cost).
pub(super) fn solve_ahead(snapshot: &World, body: u64, with: u64, op: Op) -> Option<Solved> {
    let (b1, b2) = (body_id(snapshot, body).ok()?, body_id(snapshot, with).ok()?);
    let basis = snapshot.boolean_basis(b1, b2).ok()?;
    let solution = basis.solve(op);
    Some(Solved { basis, solution })
}

/// Runs the boolean `op` of bodies `body` (B1) and `with` (B2) and places its result
/// (see [`World::boolean`]). A solution computed ahead is taken instead of running the
/// kernel when `world` is still on its basis ([`World::on_basis`]). Returns the edit to
/// journal, carrying the result's shells as polygons, with the outcome.
///
/// Refused, with the world unchanged, for an unknown id (before the kernel runs), or as
/// [`World::boolean_solution`] and [`World::place_boolean`] refuse.
pub(super) fn run(
    world: &mut World,
    (body, with, op, keep_with): (u64, u64, Op, bool),
    ahead: Option<Solved>,
) -> Result<(Edit, Outcome), EditError> {
    let (b1, b2) = (body_id(world, body)?, body_id(world, with)?);
    let solution = match ahead {
        Some(solved) if world.on_basis(&solved.basis) => solved.solution?,
        _ => world.boolean_solution(b1, b2, op)?,
    };
    let shells: Vec<ShellRef<'_, Vec<u32>>> = solution.shells.iter().map(Into::into).collect();
    let placed = world.place_boolean(b1, b2, keep_with, &shells)?;
    drop(shells);
    let pieces = solution
        .shells
        .into_iter()
        .map(|s| BooleanPiece {
            faces: s.faces.iter().collect::<FaceList>(),
            positions: s.positions,
        })
        .collect();
    let journaled = Edit::BooleanResult {
        body,
        with,
        keep_with,
        op,
        pieces,
    };
    Ok((journaled, outcome(body, &placed)))
}

/// Places the journaled result `pieces` of a boolean of `body` and `with` (see
/// [`World::place_boolean`]). The outcome has no provenance (the journal does not keep
/// it). Refused as [`World::place_boolean`] refuses, with the world unchanged.
pub(super) fn replay(
    world: &mut World,
    body: u64,
    with: u64,
    keep_with: bool,
    pieces: &[BooleanPiece],
) -> Result<Outcome, EditError> {
    let (b1, b2) = (body_id(world, body)?, body_id(world, with)?);
    let faces: Vec<Vec<&[u32]>> = pieces.iter().map(|p| p.faces.iter().collect()).collect();
    let shells: Vec<ShellRef<'_, &[u32]>> = pieces
        .iter()
        .zip(&faces)
        .map(|(p, f)| ShellRef {
            positions: &p.positions,
            faces: f,
            sources: &[],
        })
        .collect();
    let placed = world.place_boolean(b1, b2, keep_with, &shells)?;
    Ok(outcome(body, &placed))
}

/// The outcome of a boolean that kept `body`: its pieces and the bodies killed.
fn outcome(body: u64, placed: &BooleanOutcome) -> Outcome {
    let pieces = placed
        .pieces
        .iter()
        .map(|p| PieceOutcome {
            id: p.id.get(),
            faces: p.size.faces,
            edges: p.size.edges,
            vertices: p.size.vertices,
            volume: p.volume,
            sources: p
                .sources
                .iter()
                .map(|(face, from, from_face)| [face.get(), from.get(), from_face.get()])
                .collect(),
        })
        .collect();
    Outcome {
        id: Some(body),
        killed: placed.killed.iter().map(|b| b.get()).collect(),
        pieces: Some(pieces),
        ..Outcome::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edit::apply;
    use crate::edit::command::{CreateBody, PatchBody, Shape};
    use crate::edit::plan_on;
    use crate::model::{Pose, Serial};
    use glam::DVec3;

    fn world() -> World {
        let mut w = World::new();
        for (name, x) in [("a", 0.0), ("b", 1.0)] {
            let edit = Edit::CreateBody(CreateBody {
                name: Some(name.into()),
                parent: None,
                pose: Some(Pose::from_translation(DVec3::new(x, 0.0, 0.0))),
                color: None,
                shape: Shape::Box {
                    size: DVec3::splat(2.0),
                },
            });
            apply(&mut w, &edit).expect("a box");
        }
        w
    }

    /// A box as polygons, the faces counter-clockwise seen from outside.
    fn unit_box(at: f64) -> BooleanPiece {
        let p = |i: u32| {
            DVec3::new(
                at + f64::from(i & 1),
                f64::from((i >> 1) & 1),
                f64::from((i >> 2) & 1),
            )
        };
        let faces: [[u32; 4]; 6] = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        BooleanPiece {
            positions: (0..8).map(p).collect(),
            faces: faces.iter().collect(),
        }
    }

    #[test]
    fn a_request_is_never_journaled_and_a_result_round_trips() {
        let request = Edit::Boolean {
            body: 2,
            with: 3,
            op: Op::Union,
            keep_with: false,
        };
        assert!(serde_json::to_string(&request).is_err());
        let result = Edit::BooleanResult {
            body: 2,
            with: 3,
            keep_with: true,
            op: Op::Difference,
            pieces: vec![unit_box(0.0)],
        };
        let text = serde_json::to_string(&result).expect("serializes");
        assert!(text.starts_with(r#"{"edit":"boolean","#), "{text}");
        let back: Edit = serde_json::from_str(&text).expect("reads back");
        assert_eq!(back, result);
    }

    #[test]
    fn a_result_replays_to_the_same_world_and_refuses_what_the_request_refuses() {
        let mut w = world();
        let (a, b) = (2, w.find_by_name("b").expect("b").get());
        let result = Edit::BooleanResult {
            body: a,
            with: b,
            keep_with: false,
            op: Op::Union,
            pieces: vec![unit_box(0.0), unit_box(5.0)],
        };
        let before = serde_json::to_value(&w).expect("serializes");
        for (body, with) in [(a, a), (a, 999), (999, b), (1, b)] {
            let bad = Edit::BooleanResult {
                body,
                with,
                keep_with: false,
                op: Op::Union,
                pieces: vec![unit_box(0.0)],
            };
            assert!(apply(&mut w, &bad).is_err(), "{body} with {with}");
        }
        assert_eq!(serde_json::to_value(&w).expect("serializes"), before);

        let o = apply(&mut w, &result).expect("placed");
        assert_eq!(o.killed, vec![b]);
        let pieces = o.pieces.expect("pieces");
        assert_eq!(pieces.len(), 2);
        assert_eq!(pieces[0].id, a);
        assert_eq!(
            (pieces[1].faces, pieces[1].edges, pieces[1].vertices),
            (6, 12, 8)
        );
        assert!((pieces[1].volume - 1.0).abs() < 1e-12);
        assert!(w.find_entity(Serial(pieces[1].id)).is_some());

        let mut again = world();
        apply(&mut again, &result).expect("placed again");
        assert_eq!(
            serde_json::to_value(&again).expect("serializes"),
            serde_json::to_value(&w).expect("serializes")
        );
    }

    #[test]
    fn a_request_refuses_ids_before_the_kernel_runs() {
        let mut w = world();
        let b = w.find_by_name("b").expect("b").get();
        for (body, with) in [(2, 2), (2, 999), (999, b), (1, b)] {
            let e = apply(
                &mut w,
                &Edit::Boolean {
                    body,
                    with,
                    op: Op::Intersection,
                    keep_with: false,
                },
            )
            .expect_err("refused");
            assert!(!e.to_string().is_empty());
        }
        assert_eq!(w.revision(), 2);
    }

    /// A boolean solved ahead on a snapshot is placed as the kernel run on the world
    /// would place it; after an operand has moved, the stale solution is not placed:
    /// the kernel runs again on the world as it is.
    #[test]
    fn a_boolean_solved_ahead_is_placed_only_on_the_same_basis() {
        let w0 = world();
        let b = w0.find_by_name("b").expect("b").get();
        let request = Edit::Boolean {
            body: 2,
            with: b,
            op: Op::Intersection,
            keep_with: false,
        };
        let snapshot = w0.clone();
        let volume = |o: &Outcome| o.pieces.as_ref().expect("pieces")[0].volume;
        // The same world: the result and the world after it are those of a direct run.
        let planned =
            plan_on(Box::new(request.clone()), &snapshot, w0.next_serial()).expect("planned");
        let (mut live, mut direct) = (w0.clone(), w0.clone());
        let (journaled, got) = planned.apply(&mut live);
        let got = got.expect("placed");
        let want = apply(&mut direct, &request).expect("placed");
        assert!(matches!(*journaled, Edit::BooleanResult { .. }));
        assert!((volume(&got) - 4.0).abs() < 1e-12, "{}", volume(&got));
        assert_eq!(volume(&got), volume(&want));
        assert_eq!(
            serde_json::to_value(&live).expect("serializes"),
            serde_json::to_value(&direct).expect("serializes")
        );
        // B moved after the snapshot: the overlap halves, as a direct run finds.
        let planned =
            plan_on(Box::new(request.clone()), &snapshot, w0.next_serial()).expect("planned");
        let mut moved = w0.clone();
        let shift = Edit::PatchBody {
            body: b,
            patch: PatchBody {
                pose: Some(Pose::from_translation(DVec3::new(1.5, 0.0, 0.0))),
                ..PatchBody::default()
            },
        };
        apply(&mut moved, &shift).expect("moved");
        let mut direct = moved.clone();
        let (_, got) = planned.apply(&mut moved);
        let got = got.expect("placed");
        let want = apply(&mut direct, &request).expect("placed");
        assert!((volume(&got) - 2.0).abs() < 1e-12, "{}", volume(&got));
        assert_eq!(volume(&got), volume(&want));
    }
}
