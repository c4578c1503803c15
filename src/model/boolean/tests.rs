//! The boolean on small cases whose answers are known exactly.

use glam::{DAffine3, DQuat, DVec3};

use super::*;
use crate::model::check::{Violation, check_solid};
use crate::model::ids::Serials;
use crate::model::solids::{box_solid, cylinder};

fn boxed(s: &mut Serials, size: DVec3) -> Body {
    box_solid(s, size).unwrap()
}

fn at(body: &Body, place: DAffine3) -> Operand<'_> {
    Operand { body, place }
}

fn moved(v: DVec3) -> DAffine3 {
    DAffine3::from_translation(v)
}

/// Builds every shell, checks it, and returns the bodies.
fn built(sol: &Solution) -> Vec<Body> {
    let mut s = Serials::new();
    sol.shells
        .iter()
        .map(|sh| {
            let b = Body::from_polygons(&mut s, &sh.positions, &sh.faces)
                .unwrap_or_else(|e| panic!("shell does not build: {e}\n{sh:?}"));
            let r = check_solid(&b, 1e-9);
            assert!(
                r.violations
                    .iter()
                    .all(|v| matches!(v, Violation::Inward { .. })),
                "{r}"
            );
            assert_eq!(sh.sources.len(), sh.faces.len());
            b
        })
        .collect()
}

fn volume(sol: &Solution) -> f64 {
    built(sol).iter().map(|b| b.volume()).sum()
}

#[test]
fn two_overlapping_boxes() {
    let mut s = Serials::new();
    let a = boxed(&mut s, DVec3::splat(2.0));
    let b = boxed(&mut s, DVec3::splat(2.0));
    let (pa, pb) = (moved(DVec3::ZERO), moved(DVec3::new(1.0, 1.0, 1.0)));
    let i = boolean(at(&a, pa), at(&b, pb), Op::Intersection).unwrap();
    assert_eq!(i.shells.len(), 1);
    assert_eq!(i.shells[0].faces.len(), 6, "{:?}", i.shells[0]);
    assert_eq!(i.shells[0].positions.len(), 8);
    assert_eq!(volume(&i), 1.0);
    let u = boolean(at(&a, pa), at(&b, pb), Op::Union).unwrap();
    assert_eq!(u.shells.len(), 1);
    assert_eq!(volume(&u), 15.0);
    assert_eq!(u.shells[0].faces.len(), 12);
    let d = boolean(at(&a, pa), at(&b, pb), Op::Difference).unwrap();
    assert_eq!(volume(&d), 7.0);
    assert_eq!(d.shells[0].faces.len(), 9);
}

#[test]
fn a_body_with_itself() {
    let mut s = Serials::new();
    let a = boxed(&mut s, DVec3::new(1.0, 2.0, 3.0));
    let p = moved(DVec3::ZERO);
    for op in [Op::Union, Op::Intersection] {
        let r = boolean(at(&a, p), at(&a, p), op).unwrap();
        assert_eq!(r.shells.len(), 1);
        assert_eq!(r.shells[0].faces.len(), 6);
        assert_eq!(volume(&r), 6.0);
    }
    let d = boolean(at(&a, p), at(&a, p), Op::Difference).unwrap();
    assert!(d.shells.is_empty());
}

#[test]
fn boxes_sharing_a_face_edge_or_vertex() {
    let mut s = Serials::new();
    let a = boxed(&mut s, DVec3::ONE);
    for (offset, pieces) in [
        (DVec3::X, 1),
        (DVec3::new(1.0, 1.0, 0.0), 2),
        (DVec3::ONE, 2),
        (DVec3::new(1.0, 0.5, 0.0), 1),
    ] {
        let u = boolean(at(&a, moved(DVec3::ZERO)), at(&a, moved(offset)), Op::Union).unwrap();
        assert_eq!(u.shells.len(), pieces, "union at {offset}");
        assert_eq!(volume(&u), 2.0, "union at {offset}");
        let i = boolean(
            at(&a, moved(DVec3::ZERO)),
            at(&a, moved(offset)),
            Op::Intersection,
        )
        .unwrap();
        assert!(i.shells.is_empty(), "touching bodies share no volume");
        let d = boolean(
            at(&a, moved(DVec3::ZERO)),
            at(&a, moved(offset)),
            Op::Difference,
        )
        .unwrap();
        assert_eq!(volume(&d), 1.0);
        assert_eq!(d.shells.len(), 1);
    }
}

#[test]
fn a_cylinder_drills_a_hole() {
    let mut s = Serials::new();
    let a = boxed(&mut s, DVec3::new(4.0, 4.0, 1.0));
    let c = cylinder(&mut s, 1.0, 3.0, 16).unwrap();
    let d = boolean(
        at(&a, moved(DVec3::ZERO)),
        at(&c, moved(DVec3::ZERO)),
        Op::Difference,
    )
    .unwrap();
    let bodies = built(&d);
    assert_eq!(bodies.len(), 1);
    assert_eq!(bodies[0].handles(), 1);
    let expected = 16.0 - c.volume() / 3.0;
    assert!((bodies[0].volume() - expected).abs() < 1e-12);
}

#[test]
fn rotated_and_everted_operands() {
    let mut s = Serials::new();
    let a = boxed(&mut s, DVec3::splat(2.0));
    let r = DAffine3::from_rotation_translation(
        DQuat::from_rotation_z(0.3) * DQuat::from_rotation_x(0.2),
        DVec3::new(0.5, 0.2, 0.1),
    );
    let i = boolean(at(&a, moved(DVec3::ZERO)), at(&a, r), Op::Intersection).unwrap();
    let u = boolean(at(&a, moved(DVec3::ZERO)), at(&a, r), Op::Union).unwrap();
    let d = boolean(at(&a, moved(DVec3::ZERO)), at(&a, r), Op::Difference).unwrap();
    let (vi, vu, vd) = (volume(&i), volume(&u), volume(&d));
    assert!((vi + vu - 16.0).abs() < 1e-12, "{vi} + {vu}");
    assert!((vd - (8.0 - vi)).abs() < 1e-12, "{vd}");
    // A ∩ EVERT(B) = A − B.
    let mut e = a.clone();
    e.evert();
    let ie = boolean(at(&a, moved(DVec3::ZERO)), at(&e, r), Op::Intersection).unwrap();
    assert!((volume(&ie) - vd).abs() < 1e-12);
}

#[test]
fn bad_operands_are_refused() {
    let mut s = Serials::new();
    let a = boxed(&mut s, DVec3::ONE);
    let (lamina, _, _) = Body::seminal(&mut s, DVec3::ZERO);
    let e = boolean(
        at(&a, moved(DVec3::ZERO)),
        at(&lamina, moved(DVec3::ZERO)),
        Op::Union,
    );
    assert!(
        matches!(
            e,
            Err(BooleanError::NotClosed {
                operand: Which::B,
                ..
            })
        ),
        "{e:?}"
    );
}

#[test]
fn boxes_a_hair_apart() {
    let mut s = Serials::new();
    let a = boxed(&mut s, DVec3::new(1.0, 3.0, 1.0));
    let b = boxed(&mut s, DVec3::new(2.0, 1.5, 1.0));
    let u = boolean(
        at(&a, moved(DVec3::ZERO)),
        at(&b, moved(DVec3::new(0.500000000001, 0.0, 0.0))),
        Op::Union,
    )
    .unwrap();
    assert_eq!(u.shells.len(), 1);
    assert!((volume(&u) - (6.0 - 1.5 * 0.999999999999)).abs() < 1e-12);
}

/// Boxes whose faces coincide before a rotation places both: rounded, the shared faces
/// are only nearly shared, and the exact result holds slivers narrower than the f64
/// grid, which safe rounding must clear. Every output is a valid solid and the volumes
/// agree with the exact ones (A lies in B, sharing four of its faces) to rounding.
#[test]
fn boxes_that_coincide_before_rounding() {
    let mut s = Serials::new();
    let a = boxed(&mut s, DVec3::new(1.0, 3.0, 2.0));
    let b = boxed(&mut s, DVec3::new(1.0, 6.0, 2.0));
    for k in 0..24 {
        let angle = 0.1 + 0.27 * k as f64;
        let axis = DVec3::new(1.0, 2.0 + k as f64, 3.0 - k as f64).normalize();
        let place = DAffine3::from_rotation_translation(
            DQuat::from_axis_angle(axis, angle),
            DVec3::new(0.3, -0.2, 0.1 * k as f64),
        );
        let pb = place * moved(DVec3::new(0.0, 1.5, 0.0));
        let i = volume(&boolean(at(&a, place), at(&b, pb), Op::Intersection).unwrap());
        let u = volume(&boolean(at(&a, place), at(&b, pb), Op::Union).unwrap());
        let d = volume(&boolean(at(&a, place), at(&b, pb), Op::Difference).unwrap());
        assert!((i - 6.0).abs() < 1e-12, "turn {k}: A ∩ B has volume {i}");
        assert!((u - 12.0).abs() < 1e-12, "turn {k}: A ∪ B has volume {u}");
        assert!(d.abs() < 1e-12, "turn {k}: A − B has volume {d}");
    }
}

/// A pocket cut into the middle of a face leaves that face with a hole: it becomes two
/// polygons cut through corners (no vertex where a cut met a triangulation's diagonal),
/// so every vertex is a corner of the box or of the pocket, on the integer grid.
#[test]
fn a_pocket_leaves_a_face_with_a_hole_as_two_polygons_through_corners() {
    let mut s = Serials::new();
    let a = boxed(&mut s, DVec3::splat(4.0));
    let b = boxed(&mut s, DVec3::new(2.0, 2.0, 3.0));
    let (pa, pb) = (moved(DVec3::splat(2.0)), moved(DVec3::new(2.0, 2.0, 3.5)));
    let d = boolean(at(&a, pa), at(&b, pb), Op::Difference).unwrap();
    assert_eq!(d.shells.len(), 1);
    let sh = &d.shells[0];
    assert_eq!(sh.positions.len(), 16, "{sh:?}");
    assert!(sh.positions.iter().all(|p| *p == p.round()), "{sh:?}");
    // Five whole faces of the box, the top in two, four walls and a floor.
    assert_eq!(sh.faces.len(), 12, "{sh:?}");
    assert_eq!(volume(&d), 64.0 - 8.0);
    let top: Vec<_> = (0..sh.faces.len())
        .filter(|&i| {
            sh.faces[i]
                .iter()
                .all(|&v| sh.positions[v as usize].z == 4.0)
        })
        .collect();
    assert_eq!(top.len(), 2);
    assert!(top.iter().all(|&i| sh.sources[i] == sh.sources[top[0]]));
}
