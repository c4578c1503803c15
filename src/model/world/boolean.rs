//! BIN, BUN and the difference of two bodies of the world (the kernel is
//! [`crate::model::boolean`]): the operands checked and placed in one frame, the
//! kernel's refusals in the world's terms, and the result's shells made into bodies.
//!
//! A boolean is done in two steps, so that its result can be kept apart from the run
//! that computed it (a journal keeps the shells and replays them without the kernel):
//!
//! 1. [`World::boolean_solution`] checks the two bodies and runs the kernel in B1's own
//!    frame, changing nothing;
//! 2. [`World::place_boolean`] puts shells (in B1's frame) into the world: the first
//!    replaces B1's polyhedron, each further one becomes a new body beside B1, and B2
//!    is killed unless it is kept; no shell at all kills B1.
//!
//! [`World::boolean`] does both.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;

use glam::{DAffine3, DVec3};

use crate::model::body::Body;
use crate::model::boolean::{self, Op, Operand, Shell, Solution, Source, Which};
use crate::model::ids::Serial;
use crate::model::parts::{BodyId, Size};
use crate::model::range::MAX_BODY_FACES;

use super::*;

/// One shell to be made into a body: its polygons in B1's frame and, when known, the
/// input face each of its faces came from.
///
/// Preconditions (checked when it is placed: [`Body::from_polygons`] refuses otherwise):
/// one closed, manifold, consistently and outward oriented piece. `sources` is either
/// empty (provenance unknown, as when a journal is replayed) or holds one entry per
/// face.
#[derive(Clone, Copy, Debug)]
pub struct ShellRef<'a, F> {
    /// Vertex loci in B1's frame.
    pub positions: &'a [DVec3],
    /// Faces, each a ring of indices into `positions`, counter-clockwise seen from
    /// outside.
    pub faces: &'a [F],
    /// The input face of each face, or nothing.
    pub sources: &'a [Source],
}

impl<'a> From<&'a Shell> for ShellRef<'a, Vec<u32>> {
    fn from(s: &'a Shell) -> Self {
        ShellRef {
            positions: &s.positions,
            faces: &s.faces,
            sources: &s.sources,
        }
    }
}

/// One body a boolean left: B1 itself (for the first shell) or a new body beside it.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// The body.
    pub id: BodyId,
    /// Its faces, edges and vertices.
    pub size: Size,
    /// Its volume, cubic meters.
    pub volume: f64,
    /// For each of its faces, in the order of their serials: the face's serial, and
    /// the body and face serial of the input face it is a piece of. Empty when the shell
    /// was placed without sources.
    pub sources: Vec<(Serial, BodyId, Serial)>,
}

/// What [`World::place_boolean`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct BooleanOutcome {
    /// The bodies holding the result, B1 first (none when the result is empty).
    pub pieces: Vec<Piece>,
    /// The bodies removed, each with its parts (pre-order): B1 when the result is empty,
    /// then B2 unless it was kept.
    pub killed: Vec<BodyId>,
}

/// Why a boolean's operands are refused before the kernel runs, beside unknown ids and
/// the root: one operand lies within the other's subtree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Entangled {
    /// The operand that lies within the other's subtree (the body itself, when the two
    /// operands are one).
    pub part: BodyId,
    /// The operand it lies within.
    pub whole: BodyId,
}

impl std::fmt::Display for Entangled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a boolean of a body with itself or with one of its own parts: ")?;
        if self.part == self.whole {
            write!(f, "body {} is both operands", self.part)
        } else {
            write!(f, "body {} is a part of body {}", self.part, self.whole)
        }
    }
}

/// What a boolean is computed from: the two operands' polyhedra and B2's place in B1's
/// frame ([`World::boolean_basis`]). It needs no world, so a solution can be computed
/// from a snapshot, away from the world's owner, and placed later if the world is still
/// on the same basis ([`World::on_basis`]).
#[derive(Clone, Debug)]
pub struct BooleanBasis {
    ids: [BodyId; 2],
    bodies: [Arc<Body>; 2],
    place: DAffine3,
}

impl BooleanBasis {
    /// Runs the kernel: B1 in its own frame, B2 at its place. Refused with the kernel's
    /// refusal ([`WorldError::Boolean`], naming the body), or [`WorldError::BooleanFailed`]
    /// if the kernel panicked.
    pub fn solve(&self, op: Op) -> Result<Solution, WorldError> {
        let [b1, b2] = self.ids;
        let a = Operand {
            body: &self.bodies[0],
            place: DAffine3::IDENTITY,
        };
        let b = Operand {
            body: &self.bodies[1],
            place: self.place,
        };
        // The kernel only reads: a panic in it changes nothing, so it is answered as a
        // failure of this write instead of taking the owner down.
        match catch_unwind(AssertUnwindSafe(|| boolean::boolean(a, b, op))) {
            Ok(Ok(solution)) => Ok(solution),
            Ok(Err(error)) => {
                let body = match operand_of(&error) {
                    Which::A => b1,
                    Which::B => b2,
                };
                Err(WorldError::Boolean { body, error })
            }
            Err(panic) => Err(WorldError::BooleanFailed(panic_text(&*panic))),
        }
    }
}

/// The detail of a kernel refusal, the operand named by its body id.
pub(super) fn refusal_message(body: &BodyId, error: &boolean::BooleanError) -> String {
    use boolean::BooleanError as E;
    match error {
        E::NotClosed { why, .. } => format!("body {body} is not a closed solid: {why}"),
        E::SelfIntersecting { faces, .. } => format!(
            "body {body} intersects itself: its faces {} and {} cross",
            faces[0], faces[1]
        ),
        E::NonFinite { .. } => {
            format!("body {body} has a vertex that is not finite in the frame of the boolean")
        }
        E::BadFace { face, .. } => {
            format!(
                "body {body}: face {face} is not a simple polygon: its outline crosses itself, repeats a vertex or has no area"
            )
        }
        E::Cavity | E::Unbounded | E::Unresolved { .. } => {
            format!("the boolean with body {body} is refused: {error}")
        }
    }
}

impl World {
    /// BIN, BUN or A − B of bodies `b1` and `b2`, as one write: [`World::boolean_solution`]
    /// then [`World::place_boolean`] of its shells. The result is computed in `b1`'s own
    /// frame, so its first piece keeps `b1`'s pose.
    ///
    /// Refused, with the world unchanged, as those two are.
    pub fn boolean(
        &mut self,
        b1: BodyId,
        b2: BodyId,
        op: Op,
        keep_with: bool,
    ) -> Result<BooleanOutcome, WorldError> {
        let solution = self.boolean_solution(b1, b2, op)?;
        let refuse = |error| WorldError::Boolean { body: b1, error };
        if solution.shells.iter().any(|s| s.cavity_of.is_some()) {
            return Err(refuse(boolean::BooleanError::Cavity));
        }
        if solution.shells.is_empty() && solution.unbounded {
            return Err(refuse(boolean::BooleanError::Unbounded));
        }
        let shells: Vec<ShellRef<'_, Vec<u32>>> = solution.shells.iter().map(Into::into).collect();
        self.place_boolean(b1, b2, keep_with, &shells)
    }

    /// Runs the boolean kernel on `b1` (operand A, its own frame: the identity place)
    /// and `b2` (operand B, placed by `world_pose(b1)⁻¹ ∘ world_pose(b2)`), changing
    /// nothing. The shells are in `b1`'s frame. [`World::boolean_basis`] then
    /// [`BooleanBasis::solve`].
    ///
    /// Refused before the kernel runs for an unknown body ([`WorldError::UnknownBody`]),
    /// the root ([`WorldError::Root`]), or the same body twice or a body and one of its
    /// parts at any depth ([`WorldError::Entangled`]); then with the kernel's refusal
    /// ([`WorldError::Boolean`], naming the body), or [`WorldError::BooleanFailed`] if
    /// the kernel panicked.
    pub fn boolean_solution(&self, b1: BodyId, b2: BodyId, op: Op) -> Result<Solution, WorldError> {
        self.boolean_basis(b1, b2)?.solve(op)
    }

    /// What a boolean of `b1` and `b2` would be computed from, as the world stands:
    /// both polyhedra and B2's place in B1's frame. Refused as
    /// [`World::boolean_solution`] refuses before the kernel runs.
    pub fn boolean_basis(&self, b1: BodyId, b2: BodyId) -> Result<BooleanBasis, WorldError> {
        self.check_operands(b1, b2)?;
        let (n1, n2) = (self.live(b1)?, self.live(b2)?);
        let w1 = self.tree.world_pose_of(b1, n1);
        let w2 = self.tree.world_pose_of(b2, n2);
        Ok(BooleanBasis {
            ids: [b1, b2],
            bodies: [n1.body.clone(), n2.body.clone()],
            place: w1.inverse().compose(&w2).to_affine(),
        })
    }

    /// Whether a solution computed on `basis` (on this world or an earlier snapshot of
    /// it) is the one the kernel would compute now: both bodies hold the very same
    /// polyhedra (a write to a body replaces its `Arc`; the basis keeps the old ones
    /// alive, so an address is never reused) and B2 has the same place in B1's frame.
    pub fn on_basis(&self, basis: &BooleanBasis) -> bool {
        self.boolean_basis(basis.ids[0], basis.ids[1])
            .is_ok_and(|now| {
                Arc::ptr_eq(&now.bodies[0], &basis.bodies[0])
                    && Arc::ptr_eq(&now.bodies[1], &basis.bodies[1])
                    && now.place == basis.place
            })
    }

    /// Puts a boolean's result into the world as one write: the first of `shells`
    /// replaces `b1`'s polyhedron (`b1` keeps its id, name, pose, colour, supart and
    /// parts); each further one becomes a new unnamed body under `b1`'s supart with
    /// `b1`'s pose and colour; with no shells `b1` is killed with its parts. Unless
    /// `keep_with`, `b2` is killed with its parts. Bodies are built with
    /// [`Body::from_polygons`] from the world's serials: a new body's id first, then its
    /// vertices, faces and edges; the shells in order.
    ///
    /// Every check is made and every body built before anything changes: refused, with
    /// the world unchanged, as [`World::boolean_solution`] refuses the operands, when
    /// the shells have more than [`MAX_BODY_FACES`] faces in all
    /// ([`WorldError::TooLarge`]), or when a shell is not a valid polyhedron or has a
    /// locus beyond the world's range. Postcondition: the revision is one more.
    pub fn place_boolean<F: AsRef<[u32]>>(
        &mut self,
        b1: BodyId,
        b2: BodyId,
        keep_with: bool,
        shells: &[ShellRef<'_, F>],
    ) -> Result<BooleanOutcome, WorldError> {
        self.check_operands(b1, b2)?;
        let faces = shells
            .iter()
            .fold(0usize, |n, s| n.saturating_add(s.faces.len()));
        if faces > MAX_BODY_FACES {
            return Err(WorldError::TooLarge {
                faces,
                max: MAX_BODY_FACES,
            });
        }
        let node = self.live(b1)?;
        let (supart, pose, color) = (node.supart, node.pose, node.color);
        // Built on a copy of the counter: the world takes it only once all are built.
        let mut serials = self.serials.clone();
        let mut built = Vec::with_capacity(shells.len());
        for (i, shell) in shells.iter().enumerate() {
            let id = if i == 0 { b1 } else { BodyId(serials.take()) };
            let body = boolean::build_shell(&mut serials, shell.positions, shell.faces)?;
            check_geometry_input(&body)?;
            let piece = Piece {
                id,
                size: Size::of(&body),
                volume: body.volume(),
                sources: provenance(&body, shell.sources, b1, b2),
            };
            built.push((piece, body));
        }
        // Apply: nothing below can fail.
        self.serials = serials;
        let mut killed = Vec::new();
        let mut pieces = Vec::with_capacity(built.len());
        for (i, (piece, body)) in built.into_iter().enumerate() {
            if i == 0 {
                self.tree.get_mut(b1).expect("checked").body = Arc::new(body);
            } else {
                self.tree.add(piece.id, None, supart, pose, Arc::new(body));
                self.tree.get_mut(piece.id).expect("just added").color = color;
            }
            pieces.push(piece);
        }
        if pieces.is_empty() {
            killed.extend(self.remove_with_parts(b1).ids());
        }
        if !keep_with {
            killed.extend(self.remove_with_parts(b2).ids());
        }
        self.written();
        Ok(BooleanOutcome { pieces, killed })
    }

    /// Refuses a boolean of `b1` with `b2` that cannot be taken whatever their shapes:
    /// an unknown body, the root, the same body twice, or one within the other's parts.
    fn check_operands(&self, b1: BodyId, b2: BodyId) -> Result<(), WorldError> {
        self.live(b1)?;
        self.live(b2)?;
        if b1 == self.root() || b2 == self.root() {
            return Err(WorldError::Root {
                what: "an operand of a boolean",
            });
        }
        let entangled = if self.tree.is_within(b2, b1) {
            Some(Entangled {
                part: b2,
                whole: b1,
            })
        } else if self.tree.is_within(b1, b2) {
            Some(Entangled {
                part: b1,
                whole: b2,
            })
        } else {
            None
        };
        entangled.map_or(Ok(()), |e| Err(WorldError::Entangled(e)))
    }
}

/// The operand a kernel refusal names.
fn operand_of(e: &boolean::BooleanError) -> Which {
    use boolean::BooleanError as E;
    match *e {
        E::NotClosed { operand, .. }
        | E::SelfIntersecting { operand, .. }
        | E::BadFace { operand, .. }
        | E::NonFinite { operand } => operand,
        E::Cavity | E::Unbounded | E::Unresolved { .. } => Which::A,
    }
}

/// The message a panic carried, if it was text.
fn panic_text(panic: &(dyn std::any::Any + Send)) -> String {
    let what = panic
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".to_owned());
    format!("the boolean kernel failed ({what}); the world is unchanged")
}

/// For each face of `body` (built by [`Body::from_polygons`], so face `i` of the shell
/// has the `i`-th face serial), its serial and the body and face `sources[i]` names.
/// Empty unless there is one source per face.
fn provenance(
    body: &Body,
    sources: &[Source],
    b1: BodyId,
    b2: BodyId,
) -> Vec<(Serial, BodyId, Serial)> {
    if sources.len() != body.face_count() {
        return Vec::new();
    }
    let mut serials: Vec<Serial> = body.faces().map(|f| body.face_serial(f)).collect();
    serials.sort_unstable();
    serials
        .into_iter()
        .zip(sources)
        .map(|(s, src)| {
            let from = match src.operand {
                Which::A => b1,
                Which::B => b2,
            };
            (s, from, src.face)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Pose;
    use crate::model::solids::mkcube;

    /// A world with two cubes side by side and a third hung under the first.
    fn world() -> (World, BodyId, BodyId, BodyId) {
        let mut w = World::new();
        let root = w.root();
        let cube = |s: &mut Serials| mkcube(s, 2.0, 2.0, 2.0);
        let a = w
            .insert_with(Some("a"), root, Pose::IDENTITY, cube)
            .expect("a");
        let b = w
            .insert_with(
                None,
                root,
                Pose::from_translation(DVec3::new(1.0, 0.0, 0.0)),
                cube,
            )
            .expect("b");
        let part = w.insert_with(None, a, Pose::IDENTITY, cube).expect("part");
        (w, a, b, part)
    }

    /// The eight corners and six faces of an axis-aligned box from `lo` to `hi`.
    fn box_shell(lo: DVec3, hi: DVec3) -> (Vec<DVec3>, Vec<Vec<u32>>) {
        let p = |i: u32| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        };
        let positions = (0..8).map(p).collect();
        let faces = vec![
            vec![0, 2, 3, 1],
            vec![4, 5, 7, 6],
            vec![0, 1, 5, 4],
            vec![2, 6, 7, 3],
            vec![0, 4, 6, 2],
            vec![1, 3, 7, 5],
        ];
        (positions, faces)
    }

    fn json(w: &World) -> serde_json::Value {
        serde_json::to_value(w).expect("serializes")
    }

    #[test]
    fn operands_that_cannot_be_combined_are_refused_before_the_kernel() {
        let (w, a, b, part) = world();
        let unknown = BodyId(Serial(9_999));
        let cases = [
            (a, unknown, "unknown"),
            (unknown, b, "unknown"),
            (w.root(), b, "root"),
            (a, a, "itself"),
            (a, part, "own part"),
            (part, a, "own whole"),
        ];
        for (x, y, what) in cases {
            // Refused before the kernel runs: these never reach it.
            let e = w.boolean_solution(x, y, Op::Union).expect_err(what);
            match what {
                "unknown" => assert!(matches!(e, WorldError::UnknownBody(_)), "{e}"),
                "root" => assert!(matches!(e, WorldError::Root { .. }), "{e}"),
                _ => {
                    assert!(matches!(e, WorldError::Entangled(_)), "{what}: {e}");
                    assert!(
                        e.to_string()
                            .contains("itself or with one of its own parts")
                    );
                }
            }
        }
    }

    #[test]
    fn shells_replace_b1_add_siblings_and_kill_b2_in_one_revision() {
        let (mut w, a, b, part) = world();
        let before = w.revision();
        let (p1, f1) = box_shell(DVec3::splat(-1.0), DVec3::splat(1.0));
        let (p2, f2) = box_shell(DVec3::splat(3.0), DVec3::splat(4.0));
        let sources: Vec<Source> = (0..6)
            .map(|i| Source {
                operand: if i % 2 == 0 { Which::A } else { Which::B },
                face: Serial(100 + i),
            })
            .collect();
        let shells = [
            ShellRef {
                positions: &p1,
                faces: &f1,
                sources: &sources,
            },
            ShellRef {
                positions: &p2,
                faces: &f2,
                sources: &[],
            },
        ];
        let out = w.place_boolean(a, b, false, &shells).expect("placed");
        assert_eq!(w.revision(), before + 1);
        assert_eq!(out.killed, vec![b]);
        assert_eq!(out.pieces.len(), 2);
        assert_eq!(out.pieces[0].id, a);
        assert!((out.pieces[0].volume - 8.0).abs() < 1e-12);
        assert!((out.pieces[1].volume - 1.0).abs() < 1e-12);
        assert_eq!(out.pieces[0].sources.len(), 6);
        assert_eq!(out.pieces[0].sources[1].1, b);
        assert_eq!(out.pieces[0].sources[1].2, Serial(101));
        assert!(out.pieces[1].sources.is_empty());
        let new = out.pieces[1].id;
        assert_eq!(w.name(a), Some("a"));
        assert_eq!(w.supart(new), w.supart(a));
        assert_eq!(w.pose(new), w.pose(a));
        assert_eq!(
            w.parts(a).map(|p| p.len()),
            Some(1),
            "a keeps its part {part}"
        );
        assert!(w.node(b).is_none());
        assert!(w.tree().check().is_empty(), "{:?}", w.tree().check());

        // The same shells on the same world give the same world, serials and all.
        let (mut again, ..) = world();
        again.place_boolean(a, b, false, &shells).expect("placed");
        assert_eq!(json(&again), json(&w));
    }

    #[test]
    fn no_shells_kill_b1_with_its_parts_and_keep_with_keeps_b2() {
        let (mut w, a, b, part) = world();
        let none: [ShellRef<'_, Vec<u32>>; 0] = [];
        let out = w.place_boolean(a, b, true, &none).expect("placed");
        assert!(out.pieces.is_empty());
        assert_eq!(out.killed, vec![a, part]);
        assert!(w.node(b).is_some());
        assert_eq!(w.revision(), 4);
    }

    #[test]
    fn a_result_of_too_many_faces_is_refused_before_anything_is_built() {
        let (mut w, a, b, _) = world();
        let before = json(&w);
        let positions = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let faces = vec![[0u32, 1, 2]; MAX_BODY_FACES / 2 + 1];
        let half = ShellRef {
            positions: &positions,
            faces: &faces,
            sources: &[],
        };
        let e = w
            .place_boolean(a, b, false, &[half, half])
            .expect_err("too large");
        assert!(
            matches!(e, WorldError::TooLarge { faces, max: MAX_BODY_FACES } if faces > MAX_BODY_FACES),
            "{e}"
        );
        assert_eq!(json(&w), before);
    }

    #[test]
    fn a_refused_placement_changes_nothing() {
        let (mut w, a, b, _) = world();
        let before = json(&w);
        let (p, mut f) = box_shell(DVec3::ZERO, DVec3::ONE);
        f.pop(); // open
        let shells = [ShellRef {
            positions: &p,
            faces: &f,
            sources: &[],
        }];
        assert!(matches!(
            w.place_boolean(a, b, false, &shells),
            Err(WorldError::Build(_))
        ));
        let (far, f) = box_shell(DVec3::splat(2e9), DVec3::splat(2e9 + 1.0));
        let shells = [ShellRef {
            positions: &far,
            faces: &f,
            sources: &[],
        }];
        let e = w.place_boolean(a, b, false, &shells).expect_err("far");
        assert!(e.is_out_of_range(), "{e}");
        assert_eq!(json(&w), before);
    }
}
