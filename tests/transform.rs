//! TRANSLATE, ROTATE, DILATE and REFLECT of bodies, faces, edges and vertices, in body
//! and world frames, on a lone body and through the world.

#[path = "support/kernel.rs"]
mod common;

use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::Arc;

use glam::{DQuat, DVec3};
use winged::model::solids::mkcube;
use winged::model::{
    Body, Entity, Frame, Pose, Serials, Transform, TransformError, World, WorldError, check_solid,
    check_topology,
};

use common::dump;

fn cube(s: &mut Serials) -> Body {
    mkcube(s, 2.0, 2.0, 2.0).unwrap()
}

fn assert_solid(b: &Body) {
    let r = check_solid(b, 1e-9);
    assert!(r.is_ok(), "{r}");
}

fn close(a: DVec3, b: DVec3) -> bool {
    a.abs_diff_eq(b, 1e-12)
}

fn rot_z(angle: f64) -> Transform {
    Transform::Rotate {
        axis: DVec3::Z,
        angle_rad: angle,
        center: DVec3::ZERO,
    }
}

/// Loci by vertex serial.
fn loci(b: &Body) -> Vec<(u64, DVec3)> {
    b.vertices()
        .map(|v| (b.vertex_serial(v).get(), b.position(v)))
        .collect()
}

fn face_with_normal(b: &Body, n: DVec3) -> winged::model::FaceId {
    b.faces()
        .find(|&f| b.face_plane(f).unwrap().normal.dot(n) > 0.99)
        .unwrap()
}

#[test]
fn rotating_a_cube_a_quarter_turn_about_z_maps_each_corner() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let before = loci(&b);
    rot_z(FRAC_PI_2)
        .apply(&mut b, Entity::Body, Frame::Body, &Pose::IDENTITY)
        .unwrap();
    for (serial, p) in before {
        let v = b.vertex_by_serial(winged::model::Serial(serial)).unwrap();
        // (x, y, z) -> (-y, x, z)
        assert!(close(b.position(v), DVec3::new(-p.y, p.x, p.z)), "{p}");
    }
    assert_solid(&b);
    assert!((b.volume() - 8.0).abs() < 1e-12);
}

#[test]
fn rotation_about_an_off_origin_axis_keeps_the_axis_fixed() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    // A half turn about the vertical line through (1, 1, *): corner (1,1,z) stays,
    // corner (-1,-1,z) goes to (3,3,z).
    Transform::Rotate {
        axis: DVec3::Z * 5.0,
        angle_rad: PI,
        center: DVec3::new(1.0, 1.0, 7.0),
    }
    .apply(&mut b, Entity::Body, Frame::Body, &Pose::IDENTITY)
    .unwrap();
    let bounds = b.bounds().unwrap();
    assert!(close(bounds.min, DVec3::new(1.0, 1.0, -1.0)));
    assert!(close(bounds.max, DVec3::new(3.0, 3.0, 1.0)));
    assert_solid(&b);
}

#[test]
fn dilating_by_two_multiplies_the_volume_by_eight() {
    let mut s = Serials::new();
    let mut b = mkcube(&mut s, 1.0, 2.0, 3.0).unwrap();
    let v0 = b.volume();
    let a0 = b.surface_area();
    let c = DVec3::new(0.5, -1.0, 2.0);
    Transform::Dilate {
        factor: 2.0,
        center: c,
    }
    .apply(&mut b, Entity::Body, Frame::Body, &Pose::IDENTITY)
    .unwrap();
    assert!((b.volume() - 8.0 * v0).abs() < 1e-9);
    assert!((b.surface_area() - 4.0 * a0).abs() < 1e-9);
    // The fixed point stays: the old centroid (origin) goes to c + 2(0 - c) = -c.
    assert!(close(b.centroid().unwrap(), -c));
    assert_solid(&b);
}

#[test]
fn reflecting_a_body_everts_it_so_it_stays_an_outward_solid() {
    let mut s = Serials::new();
    let mut b = mkcube(&mut s, 1.0, 2.0, 3.0).unwrap();
    Transform::Translate(DVec3::new(3.0, 0.5, 0.0))
        .apply(&mut b, Entity::Body, Frame::Body, &Pose::IDENTITY)
        .unwrap();
    let before = loci(&b);
    let t = Transform::Reflect {
        normal: DVec3::new(2.0, 0.0, 0.0),
        point: DVec3::new(1.0, 0.0, 0.0),
    };
    let plan = t
        .plan(&b, Entity::Body, Frame::Body, &Pose::IDENTITY)
        .unwrap();
    assert!(plan.everts());
    plan.apply(&mut b);
    for (serial, p) in before {
        let v = b.vertex_by_serial(winged::model::Serial(serial)).unwrap();
        assert!(close(b.position(v), DVec3::new(2.0 - p.x, p.y, p.z)));
    }
    assert!((b.volume() - 6.0).abs() < 1e-9, "{}", b.volume());
    assert_solid(&b);
    // Its own inverse: reflecting again restores the loci and the orientation.
    let mut c = b.clone();
    t.inverse()
        .apply(&mut c, Entity::Body, Frame::Body, &Pose::IDENTITY)
        .unwrap();
    assert_solid(&c);
    assert!((c.volume() - 6.0).abs() < 1e-9);
}

#[test]
fn translating_a_face_moves_only_its_perimeter() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let top = face_with_normal(&b, DVec3::Z);
    let on_top: Vec<_> = b.face_vertices(top).collect();
    Transform::Translate(DVec3::Z)
        .apply(&mut b, Entity::Face(top), Frame::Body, &Pose::IDENTITY)
        .unwrap();
    for v in b.vertices().collect::<Vec<_>>() {
        let z = b.position(v).z;
        if on_top.contains(&v) {
            assert_eq!(z, 2.0);
        } else {
            assert_eq!(z, -1.0);
        }
    }
    assert!((b.volume() - 12.0).abs() < 1e-12);
    assert_solid(&b);
}

#[test]
fn rotating_a_face_about_its_own_normal_keeps_the_solid_planar() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let top = face_with_normal(&b, DVec3::Z);
    // A twist of the top face: the sides become non-planar, the top stays put in z.
    rot_z(0.3)
        .apply(&mut b, Entity::Face(top), Frame::Body, &Pose::IDENTITY)
        .unwrap();
    assert!(check_topology(&b).is_ok());
    assert!(
        b.face_vertices(top)
            .all(|v| (b.position(v).z - 1.0).abs() < 1e-12)
    );
    assert!(
        !check_solid(&b, 1e-6).is_ok(),
        "a twisted box has warped sides"
    );
    // Twisting back restores it.
    rot_z(-0.3)
        .apply(&mut b, Entity::Face(top), Frame::Body, &Pose::IDENTITY)
        .unwrap();
    assert_solid(&b);
}

#[test]
fn edge_and_vertex_transforms_move_just_their_vertices() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let e = b.edges().next().unwrap();
    let ends = b.edge(e).vt;
    let before = loci(&b);
    let t = Transform::Dilate {
        factor: 1.5,
        center: DVec3::ZERO,
    };
    t.apply(&mut b, Entity::Edge(e), Frame::Body, &Pose::IDENTITY)
        .unwrap();
    for (serial, p) in &before {
        let v = b.vertex_by_serial(winged::model::Serial(*serial)).unwrap();
        let want = if ends.contains(&v) { *p * 1.5 } else { *p };
        assert!(close(b.position(v), want));
    }
    let v = b.vertices().last().unwrap();
    let others: Vec<_> = loci(&b)
        .into_iter()
        .filter(|(sn, _)| *sn != b.vertex_serial(v).get())
        .collect();
    let p = b.position(v);
    Transform::Reflect {
        normal: DVec3::Z,
        point: DVec3::ZERO,
    }
    .apply(&mut b, Entity::Vertex(v), Frame::Body, &Pose::IDENTITY)
    .unwrap();
    assert!(close(b.position(v), DVec3::new(p.x, p.y, -p.z)));
    for (serial, q) in others {
        let w = b.vertex_by_serial(winged::model::Serial(serial)).unwrap();
        assert_eq!(b.position(w), q);
    }
    assert!(check_topology(&b).is_ok());
}

#[test]
fn world_frame_transforms_are_conjugated_by_the_body_pose() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    let pose = Pose::new(DVec3::new(5.0, 0.0, 1.0), DQuat::from_rotation_z(FRAC_PI_2)).unwrap();
    let world = |b: &Body| -> Vec<DVec3> {
        b.vertices()
            .map(|v| pose.transform_point(b.position(v)))
            .collect()
    };
    let w0 = world(&b);
    // A world translation along +x moves every world locus by +x...
    Transform::Translate(DVec3::X)
        .apply(&mut b, Entity::Body, Frame::World, &pose)
        .unwrap();
    for (p, q) in w0.iter().zip(world(&b)) {
        assert!(close(*p + DVec3::X, q));
    }
    // ...which in the body's (quarter-turned) frame is along -y.
    let v = b.vertices().next().unwrap();
    let w1 = world(&b);
    let p_body = b.position(v);
    Transform::Translate(DVec3::X)
        .apply(&mut b, Entity::Vertex(v), Frame::Body, &pose)
        .unwrap();
    assert!(close(b.position(v), p_body + DVec3::X));
    b.set_position(v, p_body);
    // A world rotation about the world z axis through the origin.
    let t = rot_z(FRAC_PI_2);
    t.apply(&mut b, Entity::Body, Frame::World, &pose).unwrap();
    let q = DQuat::from_rotation_z(FRAC_PI_2);
    for (p, r) in w1.iter().zip(world(&b)) {
        assert!(close(q * *p, r), "{p} {r}");
    }
    // Dilation about a world point.
    let c = DVec3::new(6.0, 1.0, 1.0);
    let w2 = world(&b);
    Transform::Dilate {
        factor: 0.5,
        center: c,
    }
    .apply(&mut b, Entity::Body, Frame::World, &pose)
    .unwrap();
    for (p, r) in w2.iter().zip(world(&b)) {
        assert!(close(c + (*p - c) * 0.5, r));
    }
    assert_solid(&b);
    assert!((b.volume() - 1.0).abs() < 1e-12);
}

#[test]
fn inverse_transforms_restore_the_loci() {
    let mut s = Serials::new();
    let pose = Pose::new(DVec3::new(1.0, 2.0, 3.0), DQuat::from_rotation_x(0.7)).unwrap();
    let ts = [
        Transform::Translate(DVec3::new(1.0, -2.0, 0.5)),
        Transform::Rotate {
            axis: DVec3::new(1.0, 1.0, 0.0),
            angle_rad: 0.9,
            center: DVec3::new(0.0, 3.0, 0.0),
        },
        Transform::Dilate {
            factor: 3.0,
            center: DVec3::ONE,
        },
        Transform::Reflect {
            normal: DVec3::new(0.0, 1.0, 1.0),
            point: DVec3::Y,
        },
    ];
    for t in ts {
        for frame in [Frame::Body, Frame::World] {
            let mut b = cube(&mut s);
            let before = loci(&b);
            t.apply(&mut b, Entity::Body, frame, &pose).unwrap();
            t.inverse()
                .apply(&mut b, Entity::Body, frame, &pose)
                .unwrap();
            for ((s1, p), (s2, q)) in before.iter().zip(loci(&b)) {
                assert_eq!(*s1, s2);
                assert!(p.abs_diff_eq(q, 1e-9), "{t:?} {frame:?}: {p} vs {q}");
            }
            assert_solid(&b);
        }
    }
}

#[test]
fn bad_transforms_are_refused_and_change_nothing() {
    let mut s = Serials::new();
    let mut b = cube(&mut s);
    // Slot ids that are not live in b: beyond its arenas.
    let f_dead = winged::model::FaceId::from_index(99);
    let e_dead = winged::model::EdgeId::from_index(99);
    let v_dead = winged::model::VertexId::from_index(99);
    let before = dump(&b);
    let id = Pose::IDENTITY;
    let cases: Vec<(Transform, Entity, TransformError)> = vec![
        (
            Transform::Translate(DVec3::new(f64::NAN, 0.0, 0.0)),
            Entity::Body,
            TransformError::NonFinite {
                what: "translation",
            },
        ),
        (
            Transform::Rotate {
                axis: DVec3::ZERO,
                angle_rad: 1.0,
                center: DVec3::ZERO,
            },
            Entity::Body,
            TransformError::ZeroAxis,
        ),
        (
            Transform::Rotate {
                axis: DVec3::Z,
                angle_rad: f64::INFINITY,
                center: DVec3::ZERO,
            },
            Entity::Body,
            TransformError::NonFinite { what: "angle" },
        ),
        (
            Transform::Dilate {
                factor: 0.0,
                center: DVec3::ZERO,
            },
            Entity::Body,
            TransformError::BadFactor { factor: 0.0 },
        ),
        (
            Transform::Dilate {
                factor: -2.0,
                center: DVec3::ZERO,
            },
            Entity::Body,
            TransformError::BadFactor { factor: -2.0 },
        ),
        (
            Transform::Reflect {
                normal: DVec3::ZERO,
                point: DVec3::ZERO,
            },
            Entity::Body,
            TransformError::ZeroNormal,
        ),
        (
            Transform::Translate(DVec3::X),
            Entity::Face(f_dead),
            TransformError::UnknownFace(f_dead),
        ),
        (
            Transform::Translate(DVec3::X),
            Entity::Edge(e_dead),
            TransformError::UnknownEdge(e_dead),
        ),
        (
            Transform::Translate(DVec3::X),
            Entity::Vertex(v_dead),
            TransformError::UnknownVertex(v_dead),
        ),
        (
            Transform::Dilate {
                factor: 1e308,
                center: DVec3::splat(-1e308),
            },
            Entity::Body,
            TransformError::NonFiniteResult,
        ),
    ];
    for (t, what, want) in cases {
        for frame in [Frame::Body, Frame::World] {
            assert_eq!(t.apply(&mut b, what, frame, &id), Err(want), "{t:?}");
            assert_eq!(dump(&b), before);
        }
    }
    let bad_pose = Pose {
        position: DVec3::new(f64::NAN, 0.0, 0.0),
        rotation: DQuat::IDENTITY,
    };
    assert_eq!(
        Transform::Translate(DVec3::X).apply(&mut b, Entity::Body, Frame::World, &bad_pose),
        Err(TransformError::NonFinite { what: "body pose" })
    );
    assert_eq!(dump(&b), before);
}

#[test]
fn a_seminal_face_has_no_perimeter_vertices_to_move() {
    let mut s = Serials::new();
    let (mut b, f, v) = Body::seminal(&mut s, DVec3::ONE);
    Transform::Translate(DVec3::X)
        .apply(&mut b, Entity::Face(f), Frame::Body, &Pose::IDENTITY)
        .unwrap();
    assert_eq!(b.position(v), DVec3::ONE);
    Transform::Translate(DVec3::X)
        .apply(&mut b, Entity::Body, Frame::Body, &Pose::IDENTITY)
        .unwrap();
    assert_eq!(b.position(v), DVec3::new(2.0, 1.0, 1.0));
}

// ------------------------------------------------------------------ through the world

fn world_loci(w: &World, id: winged::model::BodyId) -> Vec<DVec3> {
    let b = w.body(id).unwrap();
    b.vertices()
        .map(|v| w.world_position(id, v).unwrap())
        .collect()
}

#[test]
fn world_rotate_of_a_body_changes_its_pose_not_its_loci() {
    let mut w = World::new();
    let id = w
        .insert_with(
            Some("box"),
            w.root(),
            Pose::from_translation(DVec3::new(3.0, 0.0, 0.0)),
            |s| mkcube(s, 2.0, 2.0, 2.0),
        )
        .unwrap();
    let arc = Arc::clone(w.body_arc(id).unwrap());
    let before = world_loci(&w, id);
    w.transform(id, Entity::Body, &rot_z(FRAC_PI_2), Frame::World)
        .unwrap();
    assert!(Arc::ptr_eq(&arc, w.body_arc(id).unwrap()), "loci untouched");
    let q = DQuat::from_rotation_z(FRAC_PI_2);
    for (p, r) in before.iter().zip(world_loci(&w, id)) {
        assert!(p.abs_diff_eq(q.inverse() * r, 1e-12));
    }
    assert!(
        w.world_pose(id)
            .unwrap()
            .position
            .abs_diff_eq(DVec3::new(0.0, 3.0, 0.0), 1e-12)
    );
    // In its own frame, a quarter turn about its own z axis spins it in place.
    w.transform(id, Entity::Body, &rot_z(FRAC_PI_2), Frame::Body)
        .unwrap();
    let p = w.world_pose(id).unwrap();
    assert!(p.position.abs_diff_eq(DVec3::new(0.0, 3.0, 0.0), 1e-12));
    assert!(p.approx_eq(
        &Pose {
            position: DVec3::new(0.0, 3.0, 0.0),
            rotation: DQuat::from_rotation_z(PI)
        },
        1e-12,
        1e-9
    ));
    // Translate in the body frame: along the body's x, which now points along world -x.
    w.transform(
        id,
        Entity::Body,
        &Transform::Translate(DVec3::X),
        Frame::Body,
    )
    .unwrap();
    assert!(
        w.world_pose(id)
            .unwrap()
            .position
            .abs_diff_eq(DVec3::new(-1.0, 3.0, 0.0), 1e-12)
    );
    assert_eq!(w.revision(), 4);
}

#[test]
fn world_dilate_and_reflect_of_a_posed_body_change_its_loci() {
    let mut w = World::new();
    let pose = Pose::new(DVec3::new(0.0, 0.0, 5.0), DQuat::from_rotation_y(0.4)).unwrap();
    let id = w
        .insert_with(None, w.root(), pose, |s| mkcube(s, 1.0, 2.0, 3.0))
        .unwrap();
    let before = world_loci(&w, id);
    let c = DVec3::new(1.0, 1.0, 1.0);
    w.transform(
        id,
        Entity::Body,
        &Transform::Dilate {
            factor: 2.0,
            center: c,
        },
        Frame::World,
    )
    .unwrap();
    assert_eq!(w.pose(id), Some(pose), "the pose does not scale");
    for (p, r) in before.iter().zip(world_loci(&w, id)) {
        assert!((c + (*p - c) * 2.0).abs_diff_eq(r, 1e-9));
    }
    assert!((w.body(id).unwrap().volume() - 48.0).abs() < 1e-9);
    let before = world_loci(&w, id);
    w.transform(
        id,
        Entity::Body,
        &Transform::Reflect {
            normal: DVec3::Z,
            point: DVec3::ZERO,
        },
        Frame::World,
    )
    .unwrap();
    for (p, r) in before.iter().zip(world_loci(&w, id)) {
        assert!(DVec3::new(p.x, p.y, -p.z).abs_diff_eq(r, 1e-9));
    }
    let b = w.body(id).unwrap();
    assert!((b.volume() - 48.0).abs() < 1e-9);
    let r = check_solid(b, 1e-9);
    assert!(r.is_ok(), "{r}");
}

#[test]
fn world_face_transform_moves_the_face_in_world_coordinates() {
    let mut w = World::new();
    let pose = Pose::new(DVec3::new(2.0, 0.0, 0.0), DQuat::from_rotation_x(FRAC_PI_2)).unwrap();
    let id = w
        .insert_with(None, w.root(), pose, |s| mkcube(s, 2.0, 2.0, 2.0))
        .unwrap();
    // The body's +z face points along world -y after the quarter turn about x.
    let b = w.body(id).unwrap();
    let f = face_with_normal(b, DVec3::Z);
    let vs: Vec<_> = b.face_vertices(f).collect();
    let before: Vec<DVec3> = vs
        .iter()
        .map(|&v| w.world_position(id, v).unwrap())
        .collect();
    w.transform(
        id,
        Entity::Face(f),
        &Transform::Translate(DVec3::new(0.0, -1.0, 0.0)),
        Frame::World,
    )
    .unwrap();
    for (v, p) in vs.iter().zip(before) {
        let q = w.world_position(id, *v).unwrap();
        assert!((p + DVec3::new(0.0, -1.0, 0.0)).abs_diff_eq(q, 1e-12));
    }
    let b = w.body(id).unwrap();
    assert!((b.volume() - 12.0).abs() < 1e-9);
    assert!(check_solid(b, 1e-9).is_ok());
}

#[test]
fn refused_world_transforms_leave_the_world_as_it_was() {
    let mut w = World::new();
    let id = w
        .insert_with(None, w.root(), Pose::IDENTITY, |s| mkcube(s, 2.0, 2.0, 2.0))
        .unwrap();
    let rev = w.revision();
    let before = dump(w.body(id).unwrap());
    let pose = w.pose(id);
    let bad = Transform::Rotate {
        axis: DVec3::ZERO,
        angle_rad: 1.0,
        center: DVec3::ZERO,
    };
    assert_eq!(
        w.transform(id, Entity::Body, &bad, Frame::World),
        Err(WorldError::Transform(TransformError::ZeroAxis))
    );
    assert!(matches!(
        w.transform(w.root(), Entity::Body, &rot_z(1.0), Frame::World),
        Err(WorldError::Root { .. })
    ));
    let e = winged::model::EdgeId::from_index(500);
    assert_eq!(
        w.transform(id, Entity::Edge(e), &rot_z(1.0), Frame::World),
        Err(WorldError::Transform(TransformError::UnknownEdge(e)))
    );
    assert_eq!(w.revision(), rev);
    assert_eq!(w.pose(id), pose);
    assert_eq!(dump(w.body(id).unwrap()), before);
}
