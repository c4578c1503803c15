//! The world: parts tree, poses, names, kill, snapshots, revisions, glue and unglue
//! between bodies, cameras and lights.

#[path = "support/kernel.rs"]
mod common;

use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::Arc;

use glam::{DMat3, DQuat, DVec2, DVec3};
use proptest::prelude::*;
use winged::model::camera::BaumgartRaster;
use winged::model::solids::mkcube;
use winged::model::{
    Body, BodyId, Camera, CameraError, Color, EdgeId, Entity, EulerError, FaceId, Frame,
    Intrinsics, Light, LightError, Pose, PoseError, Serial, Serials, Size, Transform, VertexId,
    World, WorldError, check_solid, check_topology,
};

use common::dump;

/// The tree is sound and every body is a valid polyhedron.
fn assert_sound(w: &World) {
    let problems = w.tree().check();
    assert!(problems.is_empty(), "{problems:?}");
    for (id, n) in w.bodies() {
        let r = check_topology(&n.body);
        assert!(r.is_ok(), "body {id}: {r}");
    }
}

fn cube_at(w: &mut World, name: &str, supart: BodyId, at: DVec3) -> BodyId {
    w.insert_with(Some(name), supart, Pose::from_translation(at), |s| {
        mkcube(s, 1.0, 1.0, 1.0)
    })
    .unwrap()
}

struct Arm {
    shoulder: BodyId,
    upper: BodyId,
    forearm: BodyId,
    hand: BodyId,
}

/// Shoulder at (0,0,1); upper arm 1 above it; forearm 2 along x; hand 1 further.
fn arm(w: &mut World) -> Arm {
    let root = w.root();
    let shoulder = cube_at(w, "JOINT1", root, DVec3::new(0.0, 0.0, 1.0));
    let upper = cube_at(w, "JOINT2", shoulder, DVec3::new(0.0, 0.0, 1.0));
    let forearm = cube_at(w, "JOINT3", upper, DVec3::new(2.0, 0.0, 0.0));
    let hand = cube_at(w, "HAND", forearm, DVec3::new(1.0, 0.0, 0.0));
    Arm {
        shoulder,
        upper,
        forearm,
        hand,
    }
}

fn rot(axis: DVec3, angle: f64) -> Transform {
    Transform::Rotate {
        axis,
        angle_rad: angle,
        center: DVec3::ZERO,
    }
}

fn counts(b: &Body) -> (usize, usize, usize) {
    (b.face_count(), b.edge_count(), b.vertex_count())
}

fn serials_of(b: &Body) -> Vec<Serial> {
    let mut out: Vec<Serial> = b.faces().map(|f| b.face_serial(f)).collect();
    out.extend(b.edges().map(|e| b.edge_serial(e)));
    out.extend(b.vertices().map(|v| b.vertex_serial(v)));
    out
}

// ------------------------------------------------------------------ parts tree

#[test]
fn turning_the_shoulder_moves_the_whole_arm() {
    let mut w = World::new();
    let a = arm(&mut w);
    assert_sound(&w);
    assert_eq!(w.supart(a.hand), Some(a.forearm));
    assert_eq!(parts_of(&w, a.shoulder), Some(vec![a.upper]));
    let hand = w.world_pose(a.hand).unwrap();
    assert!(hand.position.abs_diff_eq(DVec3::new(3.0, 0.0, 2.0), 1e-12));
    let arcs: Vec<Arc<Body>> = [a.shoulder, a.upper, a.forearm, a.hand]
        .iter()
        .map(|&b| Arc::clone(w.body_arc(b).unwrap()))
        .collect();

    // GEOMED's ROTATE(-J1, 0, 0, π/2): about the shoulder's own vertical axis.
    let j1 = w.find_by_name("JOINT1").unwrap();
    assert_eq!(j1, a.shoulder);
    w.transform(j1, Entity::Body, &rot(DVec3::Z, FRAC_PI_2), Frame::Body)
        .unwrap();
    let shoulder = w.world_pose(a.shoulder).unwrap();
    assert!(
        shoulder
            .position
            .abs_diff_eq(DVec3::new(0.0, 0.0, 1.0), 1e-12)
    );
    let hand = w.world_pose(a.hand).unwrap();
    assert!(hand.approx_eq(
        &Pose {
            position: DVec3::new(0.0, 3.0, 2.0),
            rotation: DQuat::from_rotation_z(FRAC_PI_2),
        },
        1e-12,
        1e-9
    ));
    // A hand corner, (0.5, 0.5, 0.5) in the hand's frame, follows.
    let b = w.body(a.hand).unwrap();
    let v = b
        .vertices()
        .find(|&v| b.position(v).abs_diff_eq(DVec3::splat(0.5), 1e-12))
        .unwrap();
    assert!(
        w.world_position(a.hand, v)
            .unwrap()
            .abs_diff_eq(DVec3::new(-0.5, 3.5, 2.5), 1e-12)
    );

    // ROTATE(-J2, ...): the upper arm about its own y axis; the forearm swings down,
    // the shoulder does not move.
    w.transform(
        a.upper,
        Entity::Body,
        &rot(DVec3::Y, FRAC_PI_2),
        Frame::Body,
    )
    .unwrap();
    assert_eq!(w.world_pose(a.shoulder), Some(shoulder));
    assert!(
        w.world_pose(a.hand)
            .unwrap()
            .position
            .abs_diff_eq(DVec3::new(0.0, 0.0, -1.0), 1e-12)
    );
    // The world pose is the composition down the tree.
    let composed = [a.shoulder, a.upper, a.forearm, a.hand]
        .iter()
        .fold(Pose::IDENTITY, |p, &b| p * w.pose(b).unwrap());
    assert!(composed.approx_eq(&w.world_pose(a.hand).unwrap(), 1e-12, 1e-9));

    // A world-frame turn of the forearm about the vertical line through its origin:
    // its world pose becomes T·W, and the hand follows.
    let forearm = w.world_pose(a.forearm).unwrap();
    let hand = w.world_pose(a.hand).unwrap();
    let t = Transform::Rotate {
        axis: DVec3::Z,
        angle_rad: 0.5,
        center: forearm.position,
    };
    w.transform(a.forearm, Entity::Body, &t, Frame::World)
        .unwrap();
    let tp = t.to_pose().unwrap().unwrap();
    assert!(
        w.world_pose(a.forearm)
            .unwrap()
            .approx_eq(&(tp * forearm), 1e-12, 1e-9)
    );
    assert!(
        w.world_pose(a.forearm)
            .unwrap()
            .position
            .abs_diff_eq(forearm.position, 1e-12)
    );
    assert!(
        w.world_pose(a.hand)
            .unwrap()
            .approx_eq(&(tp * hand), 1e-12, 1e-9)
    );
    assert_eq!(w.world_pose(a.shoulder), Some(shoulder));

    // Only poses changed: every body's geometry is the same allocation.
    for (arc, b) in arcs.iter().zip([a.shoulder, a.upper, a.forearm, a.hand]) {
        assert!(Arc::ptr_eq(arc, w.body_arc(b).unwrap()));
    }
    assert_sound(&w);
}

#[test]
fn attach_and_detach_keep_world_poses_and_refuse_cycles() {
    let mut w = World::new();
    let a = arm(&mut w);
    w.transform(a.shoulder, Entity::Body, &rot(DVec3::Z, 0.3), Frame::Body)
        .unwrap();
    let rev = w.revision();
    let hand = w.world_pose(a.hand).unwrap();
    let forearm = w.world_pose(a.forearm).unwrap();

    // Refusals: cycles, the root, unknown bodies.
    for (b, s) in [
        (a.shoulder, a.hand),
        (a.shoulder, a.shoulder),
        (a.upper, a.forearm),
    ] {
        assert_eq!(
            w.attach(b, s),
            Err(WorldError::Cycle { body: b, supart: s })
        );
    }
    assert!(matches!(
        w.attach(w.root(), a.hand),
        Err(WorldError::Root { .. })
    ));
    assert!(matches!(w.detach(w.root()), Err(WorldError::Root { .. })));
    let ghost = BodyId(Serial(9999));
    assert_eq!(w.attach(a.hand, ghost), Err(WorldError::UnknownBody(ghost)));
    assert_eq!(w.detach(ghost), Err(WorldError::UnknownBody(ghost)));
    assert_eq!(w.revision(), rev);
    assert_sound(&w);

    // DETACH the forearm: it hangs from the world, with the hand, where it was.
    w.detach(a.forearm).unwrap();
    assert_eq!(w.supart(a.forearm), Some(w.root()));
    assert_eq!(parts_of(&w, a.upper), Some(vec![]));
    assert_eq!(parts_of(&w, a.hand), Some(vec![]));
    assert_eq!(w.supart(a.hand), Some(a.forearm));
    assert!(
        w.world_pose(a.forearm)
            .unwrap()
            .approx_eq(&forearm, 1e-12, 1e-9)
    );
    assert!(w.world_pose(a.hand).unwrap().approx_eq(&hand, 1e-12, 1e-9));
    // Turning the shoulder no longer moves it.
    w.transform(a.shoulder, Entity::Body, &rot(DVec3::Z, 1.0), Frame::Body)
        .unwrap();
    assert!(w.world_pose(a.hand).unwrap().approx_eq(&hand, 1e-12, 1e-9));
    // ATTACH it back: its relative pose is recomputed, its world pose kept.
    w.attach(a.forearm, a.upper).unwrap();
    assert!(w.world_pose(a.hand).unwrap().approx_eq(&hand, 1e-12, 1e-9));
    assert_eq!(parts_of(&w, a.upper), Some(vec![a.forearm]));
    // Moving the hand to the shoulder (a grasp the other way round) is fine.
    w.attach(a.hand, a.shoulder).unwrap();
    assert_eq!(parts_of(&w, a.shoulder), Some(vec![a.upper, a.hand]));
    assert_eq!(w.revision(), rev + 4);
    assert_sound(&w);
}

#[test]
fn set_pose_moves_the_parts_and_refuses_bad_poses() {
    let mut w = World::new();
    let a = arm(&mut w);
    let rev = w.revision();
    w.set_pose(
        a.upper,
        Pose::new(
            DVec3::new(0.0, 0.0, 2.0),
            DQuat::from_xyzw(0.0, 0.0, 0.0, 3.0),
        )
        .unwrap(),
    )
    .unwrap();
    assert!(
        w.world_pose(a.hand)
            .unwrap()
            .position
            .abs_diff_eq(DVec3::new(3.0, 0.0, 3.0), 1e-12)
    );
    // An unnormalised quaternion is renormalised.
    w.set_pose(
        a.hand,
        Pose {
            position: DVec3::X,
            rotation: DQuat::from_xyzw(0.0, 0.0, 2.0, 0.0),
        },
    )
    .unwrap();
    assert!((w.pose(a.hand).unwrap().rotation.length() - 1.0).abs() < 1e-15);
    let before = w.pose(a.hand);
    for bad in [
        Pose {
            position: DVec3::new(f64::NAN, 0.0, 0.0),
            rotation: DQuat::IDENTITY,
        },
        Pose {
            position: DVec3::ZERO,
            rotation: DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0),
        },
    ] {
        assert!(matches!(
            w.set_pose(a.hand, bad),
            Err(WorldError::Pose(
                PoseError::NonFinite { .. } | PoseError::ZeroRotation { .. }
            ))
        ));
    }
    assert!(matches!(
        w.set_pose(w.root(), Pose::IDENTITY),
        Err(WorldError::Root { .. })
    ));
    assert_eq!(w.pose(a.hand), before);
    assert_eq!(w.revision(), rev + 2);
}

#[test]
fn update_makes_all_its_changes_as_one_revision_or_none() {
    let mut w = World::new();
    let a = arm(&mut w);
    let rev = w.revision();
    let before = dump_nodes(&w);
    // The rename would do, but the re-parenting makes a cycle.
    assert!(matches!(
        w.update(a.upper, Some(Some("new")), Some(a.hand), None, None),
        Err(WorldError::Cycle { .. })
    ));
    // The rename and the re-parenting would do, but the pose is refused.
    let bad = Pose {
        position: DVec3::ZERO,
        rotation: DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0),
    };
    assert!(matches!(
        w.update(a.hand, Some(Some("new")), Some(a.shoulder), Some(bad), None),
        Err(WorldError::Pose(PoseError::ZeroRotation { .. }))
    ));
    // The name is taken: refused before the other two are looked at.
    assert!(matches!(
        w.update(a.hand, Some(Some("JOINT1")), Some(a.upper), Some(bad), None),
        Err(WorldError::DuplicateName { .. })
    ));
    assert!(matches!(
        w.update(w.root(), Some(None), None, None, None),
        Err(WorldError::Root { .. })
    ));
    assert_eq!(w.revision(), rev);
    assert_eq!(dump_nodes(&w), before, "a refused update changes nothing");

    // All three at once: one revision; the pose is relative to the new supart.
    let pose = Pose::from_translation(DVec3::new(0.0, 1.0, 0.0));
    w.update(
        a.hand,
        Some(Some("grip")),
        Some(a.shoulder),
        Some(pose),
        None,
    )
    .unwrap();
    assert_eq!(w.revision(), rev + 1);
    assert_eq!(w.name(a.hand), Some("grip"));
    w.update(a.hand, None, None, None, Some(Some(Color([1, 2, 3]))))
        .unwrap();
    assert_eq!(w.node(a.hand).unwrap().color, Some(Color([1, 2, 3])));
    assert_eq!(w.revision(), rev + 2);
    w.update(a.hand, None, None, None, Some(None)).unwrap();
    assert_eq!(w.node(a.hand).unwrap().color, None);
    assert_eq!(w.find_by_name("HAND"), None);
    assert_eq!(w.supart(a.hand), Some(a.shoulder));
    assert_eq!(w.pose(a.hand), Some(pose));
    // Re-parenting alone keeps the world pose; removing the name frees it.
    let world_pose = w.world_pose(a.hand).unwrap();
    w.update(a.hand, Some(None), Some(a.forearm), None, None)
        .unwrap();
    assert_eq!(w.name(a.hand), None);
    assert_eq!(w.find_by_name("grip"), None);
    assert!(
        w.world_pose(a.hand)
            .unwrap()
            .position
            .abs_diff_eq(world_pose.position, 1e-12)
    );
    assert_eq!(w.revision(), rev + 4);
    assert_sound(&w);
}

/// The parts of `b` in order, if it lives.
fn parts_of(w: &World, b: BodyId) -> Option<Vec<BodyId>> {
    w.parts(b).map(|p| p.iter().copied().collect())
}

/// A body's id, name, supart, parts and pose.
type NodeDump = (BodyId, Option<String>, BodyId, Vec<BodyId>, Pose);

/// Names, links and poses of every body, for an exact "unchanged" test.
fn dump_nodes(w: &World) -> Vec<NodeDump> {
    w.tree()
        .iter()
        .map(|(id, n)| {
            (
                id,
                n.name.clone(),
                n.supart,
                n.parts.iter().copied().collect(),
                n.pose,
            )
        })
        .collect()
}

// ------------------------------------------------------------------------ names

#[test]
fn fdname_finds_bodies_by_unique_names() {
    let mut w = World::new();
    let a = arm(&mut w);
    assert_eq!(w.find_by_name("world"), Some(w.root()));
    assert_eq!(w.find_by_name("HAND"), Some(a.hand));
    assert_eq!(w.find_by_name("JOINT4"), None);
    assert_eq!(w.name(a.forearm), Some("JOINT3"));
    let rev = w.revision();

    // Duplicates and bad names are refused.
    assert_eq!(
        w.rename(a.hand, Some("JOINT1")),
        Err(WorldError::DuplicateName {
            name: "JOINT1".into(),
            owner: a.shoulder
        })
    );
    assert!(matches!(
        w.insert_with(Some("world"), w.root(), Pose::IDENTITY, |s| mkcube(
            s, 1.0, 1.0, 1.0
        )),
        Err(WorldError::DuplicateName { .. })
    ));
    let long = "x".repeat(200);
    for bad in ["", " hand", "hand ", "a\nb", long.as_str()] {
        assert!(
            matches!(w.rename(a.hand, Some(bad)), Err(WorldError::BadName { .. })),
            "{bad:?}"
        );
    }
    assert!(matches!(
        w.rename(w.root(), Some("universe")),
        Err(WorldError::Root { .. })
    ));
    assert_eq!(w.revision(), rev);
    assert_eq!(w.find_by_name("HAND"), Some(a.hand));

    // Renaming to its own name is fine; a freed name can be taken.
    w.rename(a.hand, Some("HAND")).unwrap();
    w.rename(a.hand, None).unwrap();
    assert_eq!(w.find_by_name("HAND"), None);
    assert_eq!(w.name(a.hand), None);
    w.rename(a.forearm, Some("HAND")).unwrap();
    assert_eq!(w.find_by_name("HAND"), Some(a.forearm));
    assert_eq!(w.find_by_name("JOINT3"), None);
    w.rename(a.hand, Some("JOINT3")).unwrap();
    assert_eq!(w.find_by_name("JOINT3"), Some(a.hand));
    assert_eq!(w.revision(), rev + 4);
    assert_sound(&w);
}

// ------------------------------------------------------------------------- kill

#[test]
fn kill_removes_the_sub_parts_and_stale_serials_are_never_found_again() {
    let mut w = World::new();
    let a = arm(&mut w);
    let mut doomed: Vec<Serial> = vec![];
    for b in [a.upper, a.forearm, a.hand] {
        doomed.push(b.serial());
        doomed.extend(serials_of(w.body(b).unwrap()));
    }
    for &s in &doomed {
        assert!(w.find_entity(s).is_some());
    }
    let rev = w.revision();
    let killed = w.kill(a.upper).unwrap();
    assert_eq!(
        killed.ids().collect::<Vec<_>>(),
        vec![a.upper, a.forearm, a.hand]
    );
    assert_eq!(killed.counts(), (18, 36, 24));
    assert_eq!(w.revision(), rev + 1);
    assert_eq!(parts_of(&w, a.shoulder), Some(vec![]));
    assert_eq!(w.body_count(), 1);
    for b in [a.upper, a.forearm, a.hand] {
        assert!(w.node(b).is_none());
        assert_eq!(w.kill(b).unwrap_err(), WorldError::UnknownBody(b));
    }
    assert_eq!(w.find_by_name("JOINT2"), None);
    assert_eq!(w.revision(), rev + 1);
    for &s in &doomed {
        assert_eq!(w.find_entity(s), None, "serial {s}");
    }
    // New bodies take new serials, and may take the freed names.
    let again = cube_at(&mut w, "JOINT2", a.shoulder, DVec3::Z);
    let fresh = serials_of(w.body(again).unwrap());
    let max_old = doomed.iter().max().unwrap();
    assert!(again.serial() > *max_old);
    assert!(fresh.iter().all(|s| s > max_old));
    for &s in &doomed {
        assert_eq!(w.find_entity(s), None);
    }
    assert!(matches!(w.kill(w.root()), Err(WorldError::Root { .. })));
    assert_sound(&w);
}

#[test]
fn find_entity_answers_for_every_kind() {
    let mut w = World::new();
    let (b, f, v) = w.mkbfv(DVec3::new(1.0, 2.0, 3.0)).unwrap();
    assert_eq!(
        [
            b.get(),
            w.body(b).unwrap().face_serial(f).get(),
            w.body(b).unwrap().vertex_serial(v).get()
        ],
        [2, 3, 4],
        "MKBFV takes B, F, V in order after the world's 1"
    );
    assert_eq!(w.find_entity(Serial(1)), Some((w.root(), Entity::Body)));
    assert_eq!(w.find_entity(b.serial()), Some((b, Entity::Body)));
    assert_eq!(w.find_entity(Serial(3)), Some((b, Entity::Face(f))));
    assert_eq!(w.find_entity(Serial(4)), Some((b, Entity::Vertex(v))));
    let (e, v2) = w
        .edit(b, |body, s| body.mkev(s, f, v, DVec3::ZERO))
        .unwrap();
    let es = w.body(b).unwrap().edge_serial(e);
    assert_eq!(w.find_entity(es), Some((b, Entity::Edge(e))));
    let vs = w.body(b).unwrap().vertex_serial(v2);
    assert_eq!(w.find_entity(vs), Some((b, Entity::Vertex(v2))));
    assert_eq!(w.find_entity(Serial(0)), None);
    assert_eq!(w.find_entity(w.next_serial()), None);
    // KLEV kills them; their serials are dead for good.
    w.edit(b, |body, _| body.klev(v2)).unwrap();
    assert_eq!(w.find_entity(es), None);
    assert_eq!(w.find_entity(vs), None);
    assert!(matches!(
        w.mkbfv(DVec3::new(f64::INFINITY, 0.0, 0.0)),
        Err(WorldError::NonFinite { .. })
    ));
    assert_sound(&w);
}

#[test]
fn find_vertices_agrees_with_find_entity_and_world_position() {
    let mut w = World::new();
    let a = arm(&mut w);
    w.transform(a.shoulder, Entity::Body, &rot(DVec3::Z, 0.7), Frame::World)
        .unwrap();
    let every: Vec<Serial> = (0..w.next_serial().get() + 3).map(Serial).collect();
    // Asked in reverse, with repeats: answers follow the order asked.
    let mut asked: Vec<Serial> = every.iter().rev().copied().collect();
    asked.extend([Serial(9), Serial(9)]);
    let found = w.find_vertices(&asked);
    assert_eq!(found.len(), asked.len());
    let mut vertices = 0;
    for (s, got) in asked.iter().zip(&found) {
        let want = match w.find_entity(*s) {
            Some((b, Entity::Vertex(v))) => Some((b, v, w.world_position(b, v).unwrap())),
            _ => None,
        };
        assert_eq!(*got, want, "serial {}", s.get());
        vertices += usize::from(got.is_some());
    }
    assert!(
        vertices >= 4 * 8,
        "every cube's vertices are found ({vertices})"
    );
    // A killed body's vertices are found no more.
    let hand_vertex = serials_of(w.body(a.hand).unwrap())
        .into_iter()
        .find(|&s| matches!(w.find_entity(s), Some((_, Entity::Vertex(_)))))
        .unwrap();
    assert!(w.find_vertices(&[hand_vertex])[0].is_some());
    w.kill(a.hand).unwrap();
    assert_eq!(w.find_vertices(&[hand_vertex]), vec![None]);
    assert_eq!(w.find_vertices(&[]), vec![]);
}

// -------------------------------------------------------------- insert, serials

#[test]
fn insert_with_keeps_the_builders_serials() {
    let mut w = World::new();
    let next = w.next_serial();
    let id = w
        .insert_with(None, w.root(), Pose::IDENTITY, |s| mkcube(s, 2.0, 2.0, 2.0))
        .unwrap();
    assert_eq!(id.serial(), next);
    // The same cube built on a counter at the same point has the same serials.
    let mut s = Serials::new();
    s.skip_past(next);
    let reference = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
    assert_eq!(dump(w.body(id).unwrap()), dump(&reference));
    assert_eq!(w.next_serial(), s.peek());
}

#[test]
fn insert_renumbers_a_body_built_elsewhere() {
    let mut w = World::new();
    let first = w
        .insert_with(None, w.root(), Pose::IDENTITY, |s| mkcube(s, 1.0, 1.0, 1.0))
        .unwrap();
    // A cube on its own counter: serials 1..=26, colliding with the world's.
    let mut foreign = Serials::new();
    let body = mkcube(&mut foreign, 2.0, 2.0, 2.0).unwrap();
    let faces: Vec<FaceId> = body.faces().collect();
    let loci: Vec<DVec3> = body.vertices().map(|v| body.position(v)).collect();
    let next = w.next_serial();
    let id = w
        .insert(body.clone(), Some("foreign"), first, Pose::IDENTITY)
        .unwrap();
    assert_eq!(id.serial(), next);
    let b = w.body(id).unwrap();
    // Same slots and loci, fresh serials in the old order.
    assert_eq!(b.faces().collect::<Vec<_>>(), faces);
    assert_eq!(
        b.vertices().map(|v| b.position(v)).collect::<Vec<_>>(),
        loci
    );
    let mut pairs: Vec<(Serial, Serial)> =
        serials_of(&body).into_iter().zip(serials_of(b)).collect();
    pairs.sort();
    assert!(pairs.iter().all(|(_, new)| *new > next));
    assert!(pairs.windows(2).all(|p| p[0].1 < p[1].1), "order kept");
    assert_eq!(w.find_entity(Serial(1)), Some((w.root(), Entity::Body)));
    for s in serials_of(w.body(first).unwrap()) {
        assert_eq!(w.find_entity(s).unwrap().0, first);
    }
    for s in serials_of(w.body(id).unwrap()) {
        assert_eq!(w.find_entity(s).unwrap().0, id);
    }
    let r = check_solid(w.body(id).unwrap(), 1e-9);
    assert!(r.is_ok(), "{r}");
    // Inserting the same body again gives another set of serials.
    let twin = w.insert(body, None, w.root(), Pose::IDENTITY).unwrap();
    let a: Vec<Serial> = serials_of(w.body(id).unwrap());
    assert!(
        serials_of(w.body(twin).unwrap())
            .iter()
            .all(|s| !a.contains(s))
    );
    assert_sound(&w);
}

#[test]
fn a_killed_body_cannot_come_back_with_its_old_serials() {
    let mut w = World::new();
    let id = w
        .insert_with(None, w.root(), Pose::IDENTITY, |s| mkcube(s, 1.0, 1.0, 1.0))
        .unwrap();
    let copy = w.body(id).unwrap().clone();
    let old = serials_of(&copy);
    w.kill(id).unwrap();
    let back = w.insert(copy, None, w.root(), Pose::IDENTITY).unwrap();
    for s in old {
        assert_eq!(w.find_entity(s), None);
    }
    assert!(
        serials_of(w.body(back).unwrap())
            .iter()
            .all(|s| *s > back.serial())
    );
}

#[test]
fn refused_inserts_take_nothing() {
    let mut w = World::new();
    let rev = w.revision();
    let next = w.next_serial();
    let mut s = Serials::new();
    let mut bad = mkcube(&mut s, 1.0, 1.0, 1.0).unwrap();
    let v = bad.vertices().next().unwrap();
    bad.set_position(v, DVec3::new(f64::NAN, 0.0, 0.0));
    assert!(matches!(
        w.insert(bad, None, w.root(), Pose::IDENTITY),
        Err(WorldError::NonFinite { .. })
    ));
    let good = mkcube(&mut s, 1.0, 1.0, 1.0).unwrap();
    let ghost = BodyId(Serial(777));
    assert_eq!(
        w.insert(good.clone(), None, ghost, Pose::IDENTITY),
        Err(WorldError::UnknownBody(ghost))
    );
    assert!(matches!(
        w.insert(
            good,
            None,
            w.root(),
            Pose {
                position: DVec3::ZERO,
                rotation: DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0)
            }
        ),
        Err(WorldError::Pose(PoseError::ZeroRotation { .. }))
    ));
    // The builder fails half-way: the serials it took are given back.
    let r = w.insert_with(None, w.root(), Pose::IDENTITY, |s| {
        let (mut b, f, v) = Body::seminal(s, DVec3::ZERO);
        b.mkev(s, f, v, DVec3::X)?;
        b.mkev(s, f, VertexId::from_index(42), DVec3::Y)?;
        Ok::<Body, EulerError>(b)
    });
    assert!(matches!(
        r,
        Err(WorldError::Euler(EulerError::UnknownVertex(_)))
    ));
    assert_eq!(w.revision(), rev);
    assert_eq!(w.next_serial(), next);
    assert_eq!(w.body_count(), 0);
}

// ------------------------------------------------------ edits, snapshots, revision

#[test]
fn a_snapshot_keeps_the_old_geometry_and_shares_the_rest() {
    let mut w = World::new();
    let a = arm(&mut w);
    let snap = w.clone();
    let old = dump(w.body(a.forearm).unwrap());
    let e = w.body(a.forearm).unwrap().edges().next().unwrap();
    let (_, v) = w
        .edit(a.forearm, |b, s| {
            let mid = (b.position(b.edge(e).vt[0]) + b.position(b.edge(e).vt[1])) / 2.0;
            b.esplit(s, e, mid)
        })
        .unwrap();
    w.set_pose(a.hand, Pose::from_translation(DVec3::new(1.5, 0.0, 0.0)))
        .unwrap();
    // The world has the new geometry and pose; the snapshot the old.
    assert_eq!(counts(w.body(a.forearm).unwrap()), (6, 13, 9));
    assert!(w.body(a.forearm).unwrap().has_vertex(v));
    assert_eq!(counts(snap.body(a.forearm).unwrap()), (6, 12, 8));
    assert_eq!(dump(snap.body(a.forearm).unwrap()), old);
    assert!(
        snap.world_pose(a.hand)
            .unwrap()
            .position
            .abs_diff_eq(DVec3::new(3.0, 0.0, 2.0), 1e-12)
    );
    assert_eq!(snap.revision() + 2, w.revision());
    // Only the edited body was copied.
    assert!(!Arc::ptr_eq(
        w.body_arc(a.forearm).unwrap(),
        snap.body_arc(a.forearm).unwrap()
    ));
    for b in [a.shoulder, a.upper, a.hand] {
        assert!(Arc::ptr_eq(
            w.body_arc(b).unwrap(),
            snap.body_arc(b).unwrap()
        ));
    }
    // A vertex transform also copies on write.
    let snap2 = w.clone();
    w.transform(
        a.hand,
        Entity::Vertex(VertexId::from_index(0)),
        &Transform::Translate(DVec3::Z),
        Frame::Body,
    )
    .unwrap();
    assert!(!Arc::ptr_eq(
        w.body_arc(a.hand).unwrap(),
        snap2.body_arc(a.hand).unwrap()
    ));
    assert!(Arc::ptr_eq(
        w.body_arc(a.forearm).unwrap(),
        snap2.body_arc(a.forearm).unwrap()
    ));
    assert_sound(&w);
    assert_sound(&snap);
}

/// Nodes of `a` that are the very nodes of `b` (the same memory, not equal copies).
fn shared_nodes(a: &World, b: &World) -> usize {
    a.bodies()
        .filter(|(id, n)| b.node(*id).is_some_and(|m| std::ptr::eq(*n, m)))
        .count()
}

#[test]
fn a_snapshot_of_many_bodies_shares_every_node_a_write_does_not_reach() {
    let mut w = World::new();
    let root = w.root();
    let ids: Vec<BodyId> = (0..2000)
        .map(|i| {
            cube_at(
                &mut w,
                &format!("c{i}"),
                root,
                DVec3::new(i as f64, 0.0, 0.0),
            )
        })
        .collect();
    let snap = w.clone();
    assert_eq!(shared_nodes(&w, &snap), 2000);
    // A move copies the moved body's node and a few of its neighbours in the map, no more.
    let moved = ids[1234];
    w.set_pose(moved, Pose::from_translation(DVec3::new(0.0, 9.0, 0.0)))
        .unwrap();
    let shared = shared_nodes(&w, &snap);
    assert!((1900..2000).contains(&shared), "{shared} of 2000 shared");
    assert!(!std::ptr::eq(
        w.node(moved).unwrap(),
        snap.node(moved).unwrap()
    ));
    // The snapshot still has every body where it was; the world has the move.
    for (i, &id) in ids.iter().enumerate() {
        let at = snap.world_pose(id).unwrap().position;
        assert!(at.abs_diff_eq(DVec3::new(i as f64, 0.0, 0.0), 0.0), "{id}");
    }
    assert_eq!(
        w.world_pose(moved).unwrap().position,
        DVec3::new(0.0, 9.0, 0.0)
    );
    // A rename and a kill reach the snapshot's names no more than its nodes.
    w.rename(ids[7], Some("seventh")).unwrap();
    w.kill(ids[8]).unwrap();
    assert_eq!(snap.find_by_name("c7"), Some(ids[7]));
    assert_eq!(snap.find_by_name("seventh"), None);
    assert!(snap.node(ids[8]).is_some());
    assert_eq!(w.find_by_name("seventh"), Some(ids[7]));
    assert_eq!(w.find_by_name("c7"), None);
    assert!(w.node(ids[8]).is_none());
    assert_sound(&w);
    assert_sound(&snap);
}

/// The faces, edges and vertices of `w`'s bodies, counted one by one.
fn counted(w: &World) -> Size {
    w.bodies().fold(Size::default(), |s, (_, n)| {
        s.plus(Size {
            faces: n.body.face_count(),
            edges: n.body.edge_count(),
            vertices: n.body.vertex_count(),
        })
    })
}

#[test]
fn the_world_size_follows_every_write_and_is_read_back_from_a_snapshot_file() {
    let mut w = World::new();
    let root = w.root();
    assert_eq!(w.size(), Size::default());
    let a = cube_at(&mut w, "a", root, DVec3::ZERO);
    cube_at(&mut w, "b", a, DVec3::new(3.0, 0.0, 0.0));
    let two_cubes = Size {
        faces: 12,
        edges: 24,
        vertices: 16,
    };
    assert_eq!(w.size(), two_cubes);
    let snap = w.clone();
    // Euler operators: MKBFV makes a face and a vertex, MKEV an edge and a vertex.
    let (c, f, v) = w.mkbfv(DVec3::ZERO).unwrap();
    w.edit(c, |body, s| body.mkev(s, f, v, DVec3::X)).unwrap();
    let grown = two_cubes.plus(Size {
        faces: 1,
        edges: 1,
        vertices: 2,
    });
    assert_eq!(w.size(), grown);
    // A refused operator changes nothing.
    assert!(w.edit(c, |body, s| body.mkev(s, f, v, DVec3::NAN)).is_err());
    assert_eq!(w.size(), grown);
    // A move and a transform of the geometry change no count.
    w.set_pose(a, Pose::from_translation(DVec3::Y)).unwrap();
    let dilate = Transform::Dilate {
        factor: 2.0,
        center: DVec3::ZERO,
    };
    w.transform(a, Entity::Body, &dilate, Frame::Body).unwrap();
    assert_eq!(w.size(), grown);
    assert_sound(&w);
    // Killing a body takes its parts with it.
    w.kill(a).unwrap();
    assert_eq!(w.size(), grown.minus(two_cubes));
    assert_eq!(w.size(), counted(&w));
    assert_sound(&w);
    // The snapshot kept its own.
    assert_eq!(snap.size(), two_cubes);
    // Read back from the stored form, the size is worked out again.
    let bytes = postcard::to_allocvec(&snap).unwrap();
    let back: World = postcard::from_bytes(&bytes).unwrap();
    assert_eq!(back.size(), two_cubes);
    assert_sound(&back);
}

#[test]
fn a_failed_edit_leaves_the_world_exactly_as_it_was() {
    let mut w = World::new();
    let (b, f, v) = w.mkbfv(DVec3::ZERO).unwrap();
    let snap = w.clone();
    let rev = w.revision();
    let next = w.next_serial();
    let before = dump(w.body(b).unwrap());
    // The first MKEV succeeds, the second refuses: nothing of the first remains.
    let r = w.transaction(b, |body, s| {
        let (_, v2) = body.mkev(s, f, v, DVec3::X)?;
        body.mkev(s, f, v, DVec3::Y)?; // v is now a wire's positive end
        Ok::<_, EulerError>(v2)
    });
    assert!(matches!(
        r,
        Err(WorldError::Euler(EulerError::WirePositiveEnd { .. }))
    ));
    assert_eq!(dump(w.body(b).unwrap()), before);
    assert_eq!(w.revision(), rev);
    assert_eq!(w.next_serial(), next);
    assert!(Arc::ptr_eq(
        w.body_arc(b).unwrap(),
        snap.body_arc(b).unwrap()
    ));
    // A locus left non-finite is refused too.
    assert!(matches!(
        w.transaction(b, |body, _| {
            body.set_position(v, DVec3::splat(f64::NAN));
            Ok::<_, EulerError>(())
        }),
        Err(WorldError::NonFinite { .. })
    ));
    assert_eq!(dump(w.body(b).unwrap()), before);
    assert!(matches!(
        w.edit(w.root(), |_, _| Ok::<_, EulerError>(())),
        Err(WorldError::Root { .. })
    ));
    assert_eq!(w.revision(), rev);
    // A kernel operator refuses a non-finite locus before changing anything.
    assert!(matches!(
        w.edit(b, |body, s| body.mkev(
            s,
            f,
            v,
            DVec3::new(0.0, f64::NAN, 0.0)
        )),
        Err(WorldError::Euler(EulerError::NonFiniteLocus { .. }))
    ));
    assert_eq!(dump(w.body(b).unwrap()), before);
    assert_eq!(w.revision(), rev);
    assert_eq!(w.next_serial(), next);
}

#[test]
fn edit_changes_an_unshared_body_in_place_and_copies_a_shared_one() {
    let mut w = World::new();
    let (b, f, v) = w.mkbfv(DVec3::ZERO).unwrap();
    let before = Arc::as_ptr(w.body_arc(b).unwrap());
    w.edit(b, |body, s| body.mkev(s, f, v, DVec3::X)).unwrap();
    assert_eq!(
        Arc::as_ptr(w.body_arc(b).unwrap()),
        before,
        "no copy when unshared"
    );
    let snap = w.clone();
    let (_, v2) = {
        let body = w.body(b).unwrap();
        let e = body.vertex(v).ped;
        (e, body.other_vertex(e, v).unwrap())
    };
    w.edit(b, |body, s| body.mkev(s, f, v2, DVec3::Y)).unwrap();
    assert!(!Arc::ptr_eq(
        w.body_arc(b).unwrap(),
        snap.body_arc(b).unwrap()
    ));
    assert_eq!(
        snap.body(b).unwrap().edge_count(),
        1,
        "the snapshot keeps the old body"
    );
    assert_eq!(w.body(b).unwrap().edge_count(), 2);
}

#[test]
fn revision_counts_successful_writes_only() {
    let mut w = World::new();
    assert_eq!(w.revision(), 0);
    let mut expect = 0;
    let mut step = |w: &World, ok: bool| {
        if ok {
            expect += 1;
        }
        assert_eq!(w.revision(), expect);
    };
    let (b, f, v) = w.mkbfv(DVec3::ZERO).unwrap();
    step(&w, true);
    let ok = w.edit(b, |body, s| body.mkev(s, f, v, DVec3::X)).is_ok();
    step(&w, ok);
    let ok = w
        .edit(b, |body, _| body.klfe(EdgeId::from_index(7)))
        .is_ok();
    step(&w, ok);
    let ok = w.rename(b, Some("stick")).is_ok();
    step(&w, ok);
    let ok = w.rename(b, Some("")).is_ok();
    step(&w, ok);
    let c = w
        .insert_with(None, b, Pose::IDENTITY, |s| mkcube(s, 1.0, 1.0, 1.0))
        .unwrap();
    step(&w, true);
    let ok = w.attach(b, c).is_ok();
    step(&w, ok);
    let ok = w.detach(c).is_ok();
    step(&w, ok);
    let ok = w.attach(c, b).is_ok(); // c was detached to the world; back under b
    step(&w, ok);
    let ok = w
        .transform(
            c,
            Entity::Body,
            &Transform::Translate(DVec3::X),
            Frame::World,
        )
        .is_ok();
    step(&w, ok);
    let ok = w
        .transform(
            c,
            Entity::Body,
            &Transform::Dilate {
                factor: -1.0,
                center: DVec3::ZERO,
            },
            Frame::World,
        )
        .is_ok();
    step(&w, ok);
    let cam = Camera::look_at(
        DVec3::new(5.0, 0.0, 1.0),
        DVec3::ZERO,
        DVec3::Z,
        Intrinsics::centered(640, 480, 500.0).unwrap(),
    )
    .unwrap();
    let ok = w.set_camera("left", cam).is_ok();
    step(&w, ok);
    let ok = w.remove_camera("right").is_ok();
    step(&w, ok);
    let ok = w.remove_camera("left").is_ok();
    step(&w, ok);
    let ok = w
        .set_light("sun", Light::sun(-DVec3::Z, 1.0).unwrap())
        .is_ok();
    step(&w, ok);
    let ok = w.kill(c).is_ok();
    step(&w, ok);
    let ok = w.kill(c).is_ok();
    step(&w, ok);
    assert_eq!(expect, 11);
}

// ------------------------------------------------------------ glue and unglue

/// Two unit... 2×2×2 cubes, `b` standing on `a`, with different poses.
fn stacked(w: &mut World) -> (BodyId, BodyId) {
    let a = w
        .insert_with(
            Some("bottom"),
            w.root(),
            Pose::from_translation(DVec3::new(1.0, 0.0, 0.0)),
            |s| mkcube(s, 2.0, 2.0, 2.0),
        )
        .unwrap();
    let b = w
        .insert_with(
            Some("top"),
            w.root(),
            Pose::new(DVec3::new(1.0, 0.0, 2.0), DQuat::from_rotation_z(FRAC_PI_2)).unwrap(),
            |s| mkcube(s, 2.0, 2.0, 2.0),
        )
        .unwrap();
    (a, b)
}

/// The face of `b` whose outward normal is `n` in world coordinates.
fn world_face(w: &World, b: BodyId, n: DVec3) -> FaceId {
    let body = w.body(b).unwrap();
    let rot = w.world_pose(b).unwrap();
    body.faces()
        .find(|&f| {
            rot.transform_vector(body.face_plane(f).unwrap().normal)
                .dot(n)
                > 0.99
        })
        .unwrap()
}

/// The vertex of face `f` of `b` at world locus `p`.
fn vertex_at(w: &World, b: BodyId, f: FaceId, p: DVec3) -> VertexId {
    let body = w.body(b).unwrap();
    body.face_vertices(f)
        .find(|&v| w.world_position(b, v).unwrap().abs_diff_eq(p, 1e-9))
        .unwrap()
}

fn world_cloud(w: &World, b: BodyId) -> Vec<[i64; 3]> {
    let body = w.body(b).unwrap();
    let mut out: Vec<[i64; 3]> = body
        .vertices()
        .map(|v| {
            let p = w.world_position(b, v).unwrap() * 1e6;
            [p.x.round() as i64, p.y.round() as i64, p.z.round() as i64]
        })
        .collect();
    out.sort();
    out
}

#[test]
fn gluing_two_bodies_merges_their_nodes() {
    let mut w = World::new();
    let (a, b) = stacked(&mut w);
    let lid = cube_at(&mut w, "lid", b, DVec3::new(0.0, 0.0, 2.0));
    let lid_pose = w.world_pose(lid).unwrap();
    let top = world_face(&w, a, DVec3::Z);
    let bottom = world_face(&w, b, -DVec3::Z);
    let v1 = w.body(a).unwrap().face_vertices(top).next().unwrap();
    let p1 = w.world_position(a, v1).unwrap();
    let v2 = vertex_at(&w, b, bottom, p1);
    let b_survivors: Vec<Serial> = {
        let body = w.body(b).unwrap();
        let on_bottom: Vec<VertexId> = body.face_vertices(bottom).collect();
        body.vertices()
            .filter(|v| !on_bottom.contains(v))
            .map(|v| body.vertex_serial(v))
            .collect()
    };
    let rev = w.revision();
    w.glue(a, top, v1, b, bottom, v2).unwrap();
    assert_eq!(w.revision(), rev + 1);
    assert!(w.node(b).is_none());
    assert_eq!(w.find_by_name("top"), None);
    assert_eq!(w.find_by_name("bottom"), Some(a));
    let body = w.body(a).unwrap();
    assert_eq!(counts(body), (10, 20, 12));
    assert!((body.volume() - 16.0).abs() < 1e-9);
    let r = check_solid(body, 1e-9);
    assert!(r.is_ok(), "{r}");
    // b's other vertices are now a's, at the same world loci, with the same serials.
    for s in b_survivors {
        let (owner, e) = w.find_entity(s).unwrap();
        assert_eq!(owner, a);
        assert!(matches!(e, Entity::Vertex(_)));
    }
    let bounds = body.bounds().unwrap();
    assert!(bounds.min.abs_diff_eq(DVec3::new(-1.0, -1.0, -1.0), 1e-12));
    assert!(bounds.max.abs_diff_eq(DVec3::new(1.0, 1.0, 3.0), 1e-12));
    // b's part now hangs from a, where it was.
    assert_eq!(w.supart(lid), Some(a));
    assert!(w.world_pose(lid).unwrap().approx_eq(&lid_pose, 1e-12, 1e-9));
    assert_sound(&w);
}

#[test]
fn gluing_a_part_to_its_ancestor_reorders_the_tree() {
    let mut w = World::new();
    let base = w
        .insert_with(Some("base"), w.root(), Pose::IDENTITY, |s| {
            mkcube(s, 2.0, 2.0, 2.0)
        })
        .unwrap();
    // An assembly node without geometry between them.
    let frame = w
        .insert(
            Body::empty(),
            Some("frame"),
            base,
            Pose::from_translation(DVec3::Z),
        )
        .unwrap();
    let cap = w
        .insert_with(Some("cap"), frame, Pose::from_translation(DVec3::Z), |s| {
            mkcube(s, 2.0, 2.0, 2.0)
        })
        .unwrap();
    let frame_pose = w.world_pose(frame).unwrap();
    let f1 = world_face(&w, cap, -DVec3::Z);
    let f2 = world_face(&w, base, DVec3::Z);
    let v1 = w.body(cap).unwrap().face_vertices(f1).next().unwrap();
    let v2 = vertex_at(&w, base, f2, w.world_position(cap, v1).unwrap());
    w.glue(cap, f1, v1, base, f2, v2).unwrap();
    // cap took base's place under the world, and adopted the frame (whose part it was).
    assert!(w.node(base).is_none());
    assert_eq!(w.supart(cap), Some(w.root()));
    assert_eq!(parts_of(&w, cap), Some(vec![frame]));
    assert_eq!(parts_of(&w, frame), Some(vec![]));
    assert!(
        w.world_pose(frame)
            .unwrap()
            .approx_eq(&frame_pose, 1e-12, 1e-9)
    );
    let body = w.body(cap).unwrap();
    assert!((body.volume() - 16.0).abs() < 1e-9);
    assert!(check_solid(body, 1e-9).is_ok());
    assert_sound(&w);
}

#[test]
fn unglue_splits_off_a_new_body_where_it_was() {
    let mut w = World::new();
    let (a, b) = stacked(&mut w);
    let top = world_face(&w, a, DVec3::Z);
    let bottom = world_face(&w, b, -DVec3::Z);
    let v1 = w.body(a).unwrap().face_vertices(top).next().unwrap();
    let v2 = vertex_at(&w, b, bottom, w.world_position(a, v1).unwrap());
    let seam: Vec<EdgeId> = w.body(a).unwrap().face_edges(top).collect();
    let before = world_cloud(&w, a);
    w.glue(a, top, v1, b, bottom, v2).unwrap();
    let glued = world_cloud(&w, a);
    let child = cube_at(&mut w, "child", a, DVec3::Z);
    let rev = w.revision();
    let un = w.unglue(a, &seam).unwrap();
    assert_eq!(w.revision(), rev + 1);
    let c = un.split_off.expect("the seam separates the two cubes");
    assert_eq!(w.supart(c), w.supart(a));
    assert_eq!(w.pose(c), w.pose(a));
    assert_eq!(w.name(c), None);
    assert_eq!(w.supart(child), Some(a));
    for id in [a, c] {
        let body = w.body(id).unwrap();
        assert_eq!(counts(body), (6, 12, 8));
        assert!((body.volume() - 8.0).abs() < 1e-9);
        let r = check_solid(body, 1e-9);
        assert!(r.is_ok(), "{r}");
    }
    assert!(w.body(c).unwrap().has_face(un.new_face));
    assert!(w.body(a).unwrap().has_face(un.kept_face));
    // Nothing moved: the two cubes' loci are the glued body's, the seam's doubled.
    let mut both = world_cloud(&w, a);
    both.extend(world_cloud(&w, c));
    both.sort();
    both.dedup();
    assert_eq!(both, glued);
    assert!(before.iter().all(|p| both.contains(p)));
    // Refusals leave it as it was.
    let rev = w.revision();
    assert!(matches!(
        w.unglue(a, &seam[..2]),
        Err(WorldError::Euler(EulerError::BadSeam { .. }))
    ));
    assert_eq!(w.revision(), rev);
    assert_sound(&w);
}

#[test]
fn gluing_two_faces_of_one_body_makes_a_handle() {
    let mut w = World::new();
    let a = w
        .insert_with(Some("ring"), w.root(), Pose::IDENTITY, |s| {
            mkcube(s, 2.0, 2.0, 2.0)
        })
        .unwrap();
    let top = world_face(&w, a, DVec3::Z);
    let bottom = world_face(&w, a, -DVec3::Z);
    let v1 = w.body(a).unwrap().face_vertices(top).next().unwrap();
    let p1 = w.world_position(a, v1).unwrap();
    let below = vertex_at(&w, a, bottom, DVec3::new(p1.x, p1.y, -1.0));
    let snap = w.clone();
    // Refused: the shared geometry is not even copied.
    assert!(matches!(
        w.glue(a, top, v1, a, bottom, below),
        Err(WorldError::Euler(EulerError::WouldMakeLoop { .. }))
    ));
    assert!(Arc::ptr_eq(
        w.body_arc(a).unwrap(),
        snap.body_arc(a).unwrap()
    ));
    assert_eq!(w.revision(), snap.revision());
    // GLUEFF of the top and bottom faces: a torus, and the snapshot keeps the cube.
    let made = w.glueff(a, top, a, bottom).unwrap();
    assert_eq!(made.len(), 4);
    assert_eq!(w.revision(), snap.revision() + 1);
    let body = w.body(a).unwrap();
    assert_eq!(body.handles(), 1);
    assert_eq!(body.euler_characteristic(), 0);
    assert_eq!(counts(snap.body(a).unwrap()), (6, 12, 8));
    assert_eq!(snap.body(a).unwrap().handles(), 0);
    assert_sound(&w);
}

#[test]
fn glue_refusals_change_nothing() {
    let mut w = World::new();
    let (a, b) = stacked(&mut w);
    let snap = w.clone();
    let top = world_face(&w, a, DVec3::Z);
    let bottom = world_face(&w, b, -DVec3::Z);
    let v1 = w.body(a).unwrap().face_vertices(top).next().unwrap();
    let v_not_on_bottom = {
        let body = w.body(b).unwrap();
        let on: Vec<VertexId> = body.face_vertices(bottom).collect();
        body.vertices().find(|v| !on.contains(v)).unwrap()
    };
    assert!(matches!(
        w.glue(a, top, v1, b, bottom, v_not_on_bottom),
        Err(WorldError::Euler(EulerError::VertexNotOnFace { .. }))
    ));
    assert!(matches!(
        w.glue(a, top, v1, w.root(), bottom, v1),
        Err(WorldError::Root { .. })
    ));
    let ghost = BodyId(Serial(4242));
    assert_eq!(
        w.glueff(a, top, ghost, bottom),
        Err(WorldError::UnknownBody(ghost))
    );
    assert_eq!(w.revision(), snap.revision());
    for id in [a, b] {
        assert!(Arc::ptr_eq(
            w.body_arc(id).unwrap(),
            snap.body_arc(id).unwrap()
        ));
        assert_eq!(dump(w.body(id).unwrap()), dump(snap.body(id).unwrap()));
    }
    assert_sound(&w);
}

#[test]
fn glueff_picks_the_nearest_vertex_in_world_coordinates() {
    let mut w = World::new();
    let a = w
        .insert_with(
            None,
            w.root(),
            Pose::from_translation(DVec3::new(-3.0, 0.0, 0.0)),
            |s| mkcube(s, 2.0, 2.0, 2.0),
        )
        .unwrap();
    let b = w
        .insert_with(
            None,
            w.root(),
            Pose::new(DVec3::new(4.0, 0.0, 0.0), DQuat::from_rotation_x(PI)).unwrap(),
            |s| mkcube(s, 3.0, 3.0, 3.0),
        )
        .unwrap();
    let fa = world_face(&w, a, DVec3::X);
    let fb = world_face(&w, b, -DVec3::X);
    let made = w.glueff(a, fa, b, fb).unwrap();
    assert_eq!(made.len(), 4);
    let body = w.body(a).unwrap();
    assert_eq!(counts(body), (14, 28, 16));
    let r = check_solid(body, 1e-9);
    assert!(r.is_ok(), "{r}");
    // Two cubes and the frustum between their facing faces.
    let frustum = 4.5 / 3.0 * (4.0 + 9.0 + 6.0); // height 2.5 − (−2)
    assert!((body.volume() - (8.0 + 27.0 + frustum)).abs() < 1e-9);
    assert_sound(&w);
}

// --------------------------------------------------------------------- root

#[test]
fn the_world_body_is_its_own_supart_and_stays_put() {
    let mut w = World::new();
    let root = w.root();
    assert_eq!(w.supart(root), Some(root));
    assert_eq!(w.world_pose(root), Some(Pose::IDENTITY));
    assert!(w.body(root).unwrap().is_empty());
    assert_eq!(w.body_count(), 0);
    assert_eq!(w.bodies().count(), 0);
    let b = cube_at(&mut w, "x", root, DVec3::ZERO);
    assert_eq!(parts_of(&w, root), Some(vec![b]));
    assert_eq!(w.tree().ancestors(b).collect::<Vec<_>>(), vec![root]);
    assert!(w.tree().is_within(b, root));
    assert!(!w.tree().is_within(root, b));
    assert_eq!(w.tree().subtree(root), vec![root, b]);
}

// ------------------------------------------------------------ cameras, lights

fn k640() -> Intrinsics {
    Intrinsics::centered(640, 480, 500.0).unwrap()
}

#[test]
fn look_at_looks_along_minus_k_at_the_target() {
    let eye = DVec3::new(5.0, -2.0, 3.0);
    let target = DVec3::new(0.0, 1.0, 0.5);
    let c = Camera::look_at(eye, target, DVec3::Z, k640()).unwrap();
    let dir = (target - eye).normalize();
    assert!(c.view_direction().abs_diff_eq(dir, 1e-12));
    assert!(c.k().abs_diff_eq(-dir, 1e-12));
    // A right-handed orthonormal frame, i level, j upward.
    assert!(c.i().cross(c.j()).abs_diff_eq(c.k(), 1e-12));
    assert!(c.i().z.abs() < 1e-12);
    assert!(c.j().z > 0.0);
    // The target is in front (ZCC < 0) and projects to the principal point.
    let cc = c.world_to_camera(target);
    assert!(cc.z < 0.0);
    assert!((cc.z + eye.distance(target)).abs() < 1e-12);
    let uv = c.project(target).unwrap();
    assert!(uv.abs_diff_eq(DVec2::new(320.0, 240.0), 1e-9));
    // Up in the world is up in the image (smaller v); i is to the right (larger u).
    assert!(c.project(target + DVec3::Z * 0.1).unwrap().y < 240.0);
    assert!(c.project(target + c.i() * 0.1).unwrap().x > 320.0);
    // Behind the camera: no projection.
    assert_eq!(c.project(eye - dir), None);
    // The ray through the principal point is the view direction.
    assert!(
        c.pixel_ray(DVec2::new(320.0, 240.0))
            .abs_diff_eq(dir, 1e-12)
    );
    let p = target + DVec3::new(0.3, -0.2, 0.4);
    let ray = c.pixel_ray(c.project(p).unwrap());
    assert!(ray.abs_diff_eq((p - eye).normalize(), 1e-12));
}

#[test]
fn bad_cameras_are_refused() {
    let k = k640();
    let (i, j, kk) = (DVec3::X, DVec3::Y, DVec3::Z);
    assert!(Camera::from_ijk(DVec3::ZERO, i, j, kk, k).is_ok());
    assert!(matches!(
        Camera::from_ijk(DVec3::ZERO, i * 1.1, j, kk, k),
        Err(CameraError::NotOrthonormal { .. })
    ));
    assert!(matches!(
        Camera::from_ijk(DVec3::ZERO, i, (i + j).normalize(), kk, k),
        Err(CameraError::NotOrthonormal { .. })
    ));
    assert_eq!(
        Camera::from_ijk(DVec3::ZERO, i, j, -kk, k),
        Err(CameraError::LeftHanded)
    );
    assert!(matches!(
        Intrinsics::new(640, 480, 0.0, 500.0, 320.0, 240.0),
        Err(CameraError::BadFocal { .. })
    ));
    assert!(matches!(
        Intrinsics::new(640, 480, 500.0, -1.0, 320.0, 240.0),
        Err(CameraError::BadFocal { .. })
    ));
    assert!(matches!(
        Intrinsics::new(0, 480, 500.0, 500.0, 320.0, 240.0),
        Err(CameraError::BadImageSize { .. })
    ));
    assert!(matches!(
        Intrinsics::new(640, 100_000, 500.0, 500.0, 320.0, 240.0),
        Err(CameraError::BadImageSize { .. })
    ));
    assert!(matches!(
        Intrinsics::new(640, 480, 500.0, 500.0, f64::NAN, 240.0),
        Err(CameraError::NonFinite { .. })
    ));
    let fov = Intrinsics::from_fov_y(640, 480, FRAC_PI_2).unwrap();
    assert!((fov.fy - 240.0).abs() < 1e-9 && fov.fx == fov.fy);
    for bad in [0.0, PI, -1.0] {
        assert_eq!(
            Intrinsics::from_fov_y(640, 480, bad),
            Err(CameraError::BadFieldOfView { fov_rad: bad })
        );
    }
    assert_eq!(
        Camera::look_at(DVec3::ONE, DVec3::ONE, DVec3::Z, k),
        Err(CameraError::EyeAtTarget)
    );
    assert_eq!(
        Camera::look_at(DVec3::Z * 5.0, DVec3::ZERO, DVec3::Z, k),
        Err(CameraError::UpParallel)
    );
    assert_eq!(
        Camera::look_at(DVec3::X, DVec3::ZERO, DVec3::ZERO, k),
        Err(CameraError::UpParallel)
    );

    // The world refuses them too (the fields are public, so a bad camera can be built).
    let mut w = World::new();
    let good = Camera::look_at(DVec3::X * 3.0, DVec3::ZERO, DVec3::Z, k).unwrap();
    let mut zero_focal = good;
    zero_focal.intrinsics.fx = 0.0;
    let mut zero_width = good;
    zero_width.intrinsics.width = 0;
    let mut bad_rotation = good;
    bad_rotation.pose.rotation = DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    for bad in [zero_focal, zero_width, bad_rotation] {
        assert!(matches!(
            w.set_camera("cam", bad),
            Err(WorldError::Camera(_))
        ));
    }
    assert!(matches!(
        w.set_camera("", good),
        Err(WorldError::BadName { .. })
    ));
    assert_eq!(w.revision(), 0);
    assert_eq!(w.camera("cam"), None);
    assert_eq!(
        w.remove_camera("cam"),
        Err(WorldError::UnknownCamera("cam".into()))
    );
    // A slightly unnormalised quaternion is renormalised on the way in.
    let mut loose = good;
    loose.pose.rotation *= 1.5;
    w.set_camera("cam", loose).unwrap();
    let stored = *w.camera("cam").unwrap();
    assert!((stored.pose.rotation.length() - 1.0).abs() < 1e-15);
    assert_eq!(w.cameras().count(), 1);
    assert_eq!(w.remove_camera("cam").unwrap(), stored);
    assert_eq!(w.revision(), 2);
}

#[test]
fn baumgarts_raster_form_matches_his_projection() {
    // A 1" vidicon: 12.8 × 9.6 mm behind a 12.5 mm lens, read as 512 × 480 pixels.
    let raster = BaumgartRaster {
        focal: 12.5,
        ldx: 512,
        ldy: 480,
        pdx: 12.8,
        pdy: 9.6,
    };
    let k = Intrinsics::from_baumgart(&raster).unwrap();
    assert!((k.fx - 500.0).abs() < 1e-12);
    assert!((k.fy - 625.0).abs() < 1e-12);
    assert_eq!((k.width, k.height, k.cx, k.cy), (512, 480, 256.0, 240.0));
    let back = k.to_baumgart(12.5).unwrap();
    assert!((back.pdx - 12.8).abs() < 1e-12 && (back.pdy - 9.6).abs() < 1e-12);
    // WINGED.DOC: XPP = SCALEX·XCC/ZCC with SCALEX = −FOCAL·LDX/PDX; u = cx + XPP,
    // v = cy − YPP.
    let cam = Camera::look_at(
        DVec3::new(2.0, -6.0, 1.5),
        DVec3::new(0.0, 0.0, 0.5),
        DVec3::Z,
        k,
    )
    .unwrap();
    let p = DVec3::new(0.4, 0.3, 0.9);
    let cc = cam.world_to_camera(p);
    let scalex = -raster.focal * raster.ldx as f64 / raster.pdx;
    let scaley = -raster.focal * raster.ldy as f64 / raster.pdy;
    let (xpp, ypp) = (scalex * cc.x / cc.z, scaley * cc.y / cc.z);
    let uv = cam.project(p).unwrap();
    assert!(uv.abs_diff_eq(DVec2::new(256.0 + xpp, 240.0 - ypp), 1e-9));
    // Baumgart's camera-coordinate formulas: XCC = I·(p − C) and so on.
    let d = p - cam.position();
    assert!(cc.abs_diff_eq(
        DVec3::new(cam.i().dot(d), cam.j().dot(d), cam.k().dot(d)),
        1e-12
    ));
    for bad in [
        BaumgartRaster {
            focal: 0.0,
            ..raster
        },
        BaumgartRaster {
            pdx: -1.0,
            ..raster
        },
    ] {
        assert!(matches!(
            Intrinsics::from_baumgart(&bad),
            Err(CameraError::BadRaster { .. })
        ));
    }
}

#[test]
fn opencv_extrinsics_round_trip() {
    let k = Intrinsics::new(800, 600, 700.0, 710.0, 401.0, 299.0).unwrap();
    let cam = Camera::look_at(DVec3::new(3.0, 4.0, 2.0), DVec3::ZERO, DVec3::Z, k).unwrap();
    let (r, t) = cam.to_opencv();
    // OpenCV's frame: the target straight ahead (+z), world up is image up (−y).
    let ahead = r * DVec3::ZERO + t;
    assert!(ahead.z > 0.0 && ahead.x.abs() < 1e-12 && ahead.y.abs() < 1e-12);
    let above = r * DVec3::Z + t;
    assert!(above.y < 0.0);
    assert!((r.determinant() - 1.0).abs() < 1e-12);
    let back = Camera::from_opencv(r, t, k).unwrap();
    assert!(back.pose.approx_eq(&cam.pose, 1e-12, 1e-9));
    // OpenCV's pinhole model gives the same pixel, half a pixel apart in convention.
    let kcv: DMat3 = k.opencv_matrix();
    let p = DVec3::new(0.2, -0.3, 0.7);
    let x = r * p + t;
    let uv_cv = kcv * (x / x.z);
    let uv = cam.project(p).unwrap();
    assert!(uv.abs_diff_eq(DVec2::new(uv_cv.x + 0.5, uv_cv.y + 0.5), 1e-9));
    assert_eq!(Intrinsics::from_opencv_matrix(kcv, 800, 600).unwrap(), k);
}

#[test]
fn lights_are_checked_and_kept_by_name() {
    assert_eq!(Light::sun(DVec3::ZERO, 1.0), Err(LightError::ZeroDirection));
    assert_eq!(
        Light::point(DVec3::ZERO, -0.5),
        Err(LightError::BadIntensity { intensity: -0.5 })
    );
    assert!(matches!(
        Light::point(DVec3::splat(f64::NAN), 1.0),
        Err(LightError::NonFinite { .. })
    ));
    let sun = Light::sun(DVec3::new(1.0, 0.0, -1.0), 0.8).unwrap();
    match sun {
        Light::Sun { direction, .. } => assert!((direction.length() - 1.0).abs() < 1e-15),
        _ => unreachable!(),
    }
    let mut w = World::new();
    w.set_light("sun", sun).unwrap();
    w.set_light("lamp", Light::point(DVec3::Z * 3.0, 2.0).unwrap())
        .unwrap();
    assert!(matches!(
        w.set_light(
            "bad",
            Light::Sun {
                direction: DVec3::ZERO,
                intensity: 1.0
            }
        ),
        Err(WorldError::Light(LightError::ZeroDirection))
    ));
    assert_eq!(
        w.lights().map(|(n, _)| n).collect::<Vec<_>>(),
        ["lamp", "sun"]
    );
    assert_eq!(w.light("sun"), Some(&sun));
    w.remove_light("lamp").unwrap();
    assert_eq!(
        w.remove_light("lamp"),
        Err(WorldError::UnknownLight("lamp".into()))
    );
    assert_eq!(w.revision(), 3);
}

// ------------------------------------------------------- random tree operations

#[derive(Clone, Debug)]
enum TreeOp {
    Insert { under: usize },
    Attach { b: usize, to: usize },
    Detach { b: usize },
    Kill { b: usize },
    Rename { b: usize, name: u8 },
    Turn { b: usize, angle: f64 },
}

fn tree_op() -> impl Strategy<Value = TreeOp> {
    prop_oneof![
        (0usize..16).prop_map(|under| TreeOp::Insert { under }),
        (0usize..16, 0usize..16).prop_map(|(b, to)| TreeOp::Attach { b, to }),
        (0usize..16).prop_map(|b| TreeOp::Detach { b }),
        (0usize..16).prop_map(|b| TreeOp::Kill { b }),
        (0usize..16, 0u8..4).prop_map(|(b, name)| TreeOp::Rename { b, name }),
        (0usize..16, -3.0f64..3.0).prop_map(|(b, angle)| TreeOp::Turn { b, angle }),
    ]
}

/// One node's id, name, supart, parts and pose bits.
type NodePrint = (BodyId, Option<String>, BodyId, Vec<BodyId>, [u64; 7]);

/// Everything about the tree, for an exact "unchanged" comparison.
fn fingerprint(w: &World) -> Vec<NodePrint> {
    w.tree()
        .iter()
        .map(|(id, n)| {
            let p = n.pose;
            (
                id,
                n.name.clone(),
                n.supart,
                n.parts.iter().copied().collect(),
                [
                    p.position.x.to_bits(),
                    p.position.y.to_bits(),
                    p.position.z.to_bits(),
                    p.rotation.x.to_bits(),
                    p.rotation.y.to_bits(),
                    p.rotation.z.to_bits(),
                    p.rotation.w.to_bits(),
                ],
            )
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Random parts-tree operations keep the tree sound; every refusal leaves it exactly
    /// as it was; the revision counts the successes; world poses survive re-parenting.
    #[test]
    fn random_tree_operations_keep_the_tree_sound(ops in proptest::collection::vec(tree_op(), 1..40)) {
        let mut w = World::new();
        let mut ids: Vec<BodyId> = vec![w.root()];
        let mut ok_count = 0u64;
        for op in ops {
            let pick = |k: usize| ids[k % ids.len()];
            let before = fingerprint(&w);
            let rev = w.revision();
            let poses: Vec<(BodyId, Pose)> =
                w.tree().iter().map(|(id, _)| (id, w.world_pose(id).unwrap())).collect();
            let (ok, keeps_world_poses) = match op {
                TreeOp::Insert { under } => {
                    let r = w.insert_with(None, pick(under), Pose::from_translation(DVec3::X), |s| {
                        Ok::<_, EulerError>(Body::seminal(s, DVec3::ZERO).0)
                    });
                    if let Ok(id) = r { ids.push(id); }
                    (r.is_ok(), true)
                }
                TreeOp::Attach { b, to } => (w.attach(pick(b), pick(to)).is_ok(), true),
                TreeOp::Detach { b } => (w.detach(pick(b)).is_ok(), true),
                TreeOp::Kill { b } => {
                    let r = w.kill(pick(b));
                    if let Ok(k) = &r {
                        let dead: Vec<BodyId> = k.ids().collect();
                        ids.retain(|id| !dead.contains(id));
                    }
                    (r.is_ok(), true)
                }
                TreeOp::Rename { b, name } => {
                    let name = format!("n{name}");
                    (w.rename(pick(b), Some(name.as_str())).is_ok(), true)
                }
                TreeOp::Turn { b, angle } => {
                    let r = w.transform(pick(b), Entity::Body, &rot(DVec3::Z, angle), Frame::Body);
                    (r.is_ok(), false)
                }
            };
            if ok {
                ok_count += 1;
                prop_assert_eq!(w.revision(), rev + 1);
            } else {
                prop_assert_eq!(w.revision(), rev);
                prop_assert_eq!(fingerprint(&w), before);
            }
            let problems = w.tree().check();
            prop_assert!(problems.is_empty(), "{:?}", problems);
            if keeps_world_poses {
                for (id, p) in poses {
                    if let Some(q) = w.world_pose(id) {
                        prop_assert!(q.approx_eq(&p, 1e-9, 1e-7));
                    }
                }
            }
        }
        prop_assert_eq!(w.revision(), ok_count);
    }
}
