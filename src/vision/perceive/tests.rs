//! Visual hulls of solids whose masks a ray caster in the test draws (not winged's
//! renderer), checked against the truth and against the general boolean on the same
//! cones.

use glam::{DVec2, DVec3};

use super::*;
use crate::model::camera::Intrinsics;
use crate::model::check_solid;
use crate::model::geometry::fibonacci_sphere as fibonacci;
use crate::vision::image::Mask;

/// A solid the test draws: a union of axis-aligned boxes, or a ball, or either turned
/// about the origin.
#[derive(Clone, Debug)]
enum Solid {
    Boxes(Vec<(DVec3, DVec3)>),
    Ball(f64),
    Turned(Box<Solid>, glam::DQuat),
}

impl Solid {
    /// Whether the ray from `o` along `d` meets the solid in front of `o`.
    fn hit(&self, o: DVec3, d: DVec3) -> bool {
        match self {
            Solid::Boxes(boxes) => boxes.iter().any(|&(lo, hi)| {
                let inv = d.recip();
                let (a, b) = ((lo - o) * inv, (hi - o) * inv);
                let t0 = a.min(b).max_element();
                let t1 = a.max(b).min_element();
                t1 >= t0.max(0.0)
            }),
            Solid::Ball(r) => {
                let b = o.dot(d);
                let c = o.length_squared() - r * r;
                b * b - c >= 0.0 && -b + (b * b - c).sqrt() > 0.0
            }
            Solid::Turned(solid, q) => solid.hit(q.inverse() * o, q.inverse() * d),
        }
    }

    fn volume(&self) -> f64 {
        match self {
            Solid::Boxes(boxes) => boxes
                .iter()
                .map(|(lo, hi)| (*hi - *lo).element_product())
                .sum(),
            Solid::Ball(r) => 4.0 / 3.0 * std::f64::consts::PI * r * r * r,
            Solid::Turned(solid, _) => solid.volume(),
        }
    }

    /// Points of the solid: box corners pulled in by a nanometre, or points of the
    /// ball's surface pulled in likewise.
    fn samples(&self) -> Vec<DVec3> {
        match self {
            Solid::Boxes(boxes) => boxes
                .iter()
                .flat_map(|&(lo, hi)| {
                    let (lo, hi) = (lo + 1e-9, hi - 1e-9);
                    (0..8).map(move |i| {
                        DVec3::new(
                            if i & 1 == 0 { lo.x } else { hi.x },
                            if i & 2 == 0 { lo.y } else { hi.y },
                            if i & 4 == 0 { lo.z } else { hi.z },
                        )
                    })
                })
                .collect(),
            Solid::Ball(r) => fibonacci(200).into_iter().map(|d| d * (r - 1e-9)).collect(),
            Solid::Turned(solid, q) => solid.samples().into_iter().map(|p| *q * p).collect(),
        }
    }
}

/// `n` cameras at `distance` from the origin on a Fibonacci sphere, looking at it.
fn cameras(n: usize, distance: f64, focal: f64) -> Vec<Camera> {
    let intrinsics = Intrinsics::centered(640, 480, focal).expect("intrinsics");
    fibonacci(n)
        .into_iter()
        .map(|d| {
            let up = if d.z.abs() > 0.9 { DVec3::X } else { DVec3::Z };
            Camera::look_at(d * distance, DVec3::ZERO, up, intrinsics).expect("camera")
        })
        .collect()
}

/// The mask of `solid` seen by `camera`: a pixel is inside when the ray through its
/// centre meets the solid.
fn draw(solid: &Solid, camera: &Camera) -> Mask {
    let k = camera.intrinsics;
    let o = camera.position();
    Mask::from_fn(k.width, k.height, |x, y| {
        let d = camera.pixel_ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
        solid.hit(o, d)
    })
}

fn sights(solid: &Solid, cameras: &[Camera]) -> Vec<Sight> {
    cameras
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let mask = draw(solid, c);
            let mut found = silhouette::silhouettes(&mask, 1.0, 0.0);
            assert_eq!(found.len(), 1, "one region in view {i}");
            Sight {
                camera: *c,
                outline: found.remove(0).outline,
                view: i as u32,
            }
        })
        .collect()
}

/// Every piece is a valid closed body (the kernel's validator), and the pieces hold
/// every sample point of the solid.
fn assert_valid_and_holding(pieces: &[Mesh], solid: &Solid) {
    for (i, p) in pieces.iter().enumerate() {
        let body = p
            .to_body(&mut Serials::new())
            .unwrap_or_else(|e| panic!("piece {i}: {e}"));
        let report = check_solid(&body, 1e-9);
        assert!(report.is_ok(), "piece {i}: {report:?}");
        assert!(p.volume() > 0.0);
    }
    for x in solid.samples() {
        let w: f64 = pieces.iter().map(|p| p.winding(x)).sum();
        assert!(
            (w - 1.0).abs() < 1e-6,
            "{x} is not inside the hull (winding {w})"
        );
    }
}

fn hull(solid: &Solid, cams: &[Camera]) -> (Vec<Mesh>, Tally) {
    let mut tally = Tally::default();
    let pieces = visual_hull(&sights(solid, cams), Depths::default(), &mut tally).expect("hull");
    (pieces, tally)
}

fn total_volume(pieces: &[Mesh]) -> f64 {
    pieces.iter().map(Mesh::volume).sum()
}

fn a_box() -> Solid {
    Solid::Boxes(vec![(
        DVec3::new(-0.1, -0.07, -0.05),
        DVec3::new(0.1, 0.07, 0.05),
    )])
}

#[test]
fn a_box_seen_by_four_cameras_is_held_by_its_hull() {
    let solid = a_box();
    let (pieces, tally) = hull(&solid, &cameras(4, 0.6, 500.0));
    assert_eq!(pieces.len(), 1);
    assert_valid_and_holding(&pieces, &solid);
    let v = total_volume(&pieces);
    assert!(v > solid.volume() && v < 3.0 * solid.volume(), "volume {v}");
    assert_eq!(tally.boolean, 0, "{tally:?}");
}

#[test]
fn the_image_method_and_the_general_boolean_agree_on_the_same_cones() {
    let solid = a_box();
    let cams = cameras(3, 0.6, 500.0);
    let sights = sights(&solid, &cams);
    let depths = Depths::default();
    let mut tally = Tally::default();
    let carved = visual_hull(&sights, depths, &mut tally).expect("carved");
    assert_eq!(tally.boolean, 0);
    // The same cones intersected by the general boolean alone.
    let s0 = &sights[0];
    let mut reference = vec![cone::cone(
        &s0.camera,
        &s0.outline.rings[0],
        depths.near,
        depths.far,
        0,
        0,
    )];
    for s in &sights[1..] {
        reference = reference
            .iter()
            .flat_map(|p| carve_by_boolean(p, s, depths).expect("boolean"))
            .collect();
    }
    let (a, b) = (total_volume(&carved), total_volume(&reference));
    assert!((a - b).abs() <= 1e-9 * b, "image {a} against boolean {b}");
    assert_eq!(carved.len(), reference.len());
}

#[test]
fn every_face_records_the_view_that_made_it() {
    let solid = a_box();
    let (pieces, _) = hull(&solid, &cameras(5, 0.6, 500.0));
    for p in &pieces {
        for m in &p.makers {
            assert!(matches!(m, Maker::Wall { view, .. } if *view < 5), "{m:?}");
        }
    }
    let views: std::collections::BTreeSet<u32> = pieces
        .iter()
        .flat_map(|p| p.makers.iter().filter_map(Maker::view))
        .collect();
    assert!(views.len() >= 3, "{views:?}");
}

#[test]
fn an_l_prism_keeps_its_notch_where_a_view_sees_into_it() {
    // Seen along z, the notch is a concave corner of every silhouette near that axis.
    let solid = Solid::Boxes(vec![
        (DVec3::new(-0.1, -0.1, -0.05), DVec3::new(0.1, 0.0, 0.05)),
        (DVec3::new(-0.1, 0.0, -0.05), DVec3::new(0.0, 0.1, 0.05)),
    ]);
    let (pieces, tally) = hull(&solid, &cameras(8, 0.7, 450.0));
    assert_eq!(tally.boolean, 0, "{tally:?}");
    assert_valid_and_holding(&pieces, &solid);
    let notch = DVec3::new(0.07, 0.07, 0.0);
    let w: f64 = pieces.iter().map(|p| p.winding(notch)).sum();
    assert!(w.abs() < 1e-6, "the notch is filled: winding {w}");
}

#[test]
fn a_frame_seen_through_its_hole_keeps_the_hole() {
    // A square frame in the z = 0 plane: seen from above, its silhouette has a hole.
    let solid = Solid::Boxes(vec![
        (DVec3::new(-0.1, -0.1, -0.02), DVec3::new(0.1, -0.05, 0.02)),
        (DVec3::new(-0.1, 0.05, -0.02), DVec3::new(0.1, 0.1, 0.02)),
        (
            DVec3::new(-0.1, -0.05, -0.02),
            DVec3::new(-0.05, 0.05, 0.02),
        ),
        (DVec3::new(0.05, -0.05, -0.02), DVec3::new(0.1, 0.05, 0.02)),
    ]);
    let (pieces, tally) = hull(&solid, &cameras(12, 0.7, 450.0));
    assert_eq!(tally.boolean, 0, "{tally:?}");
    assert_valid_and_holding(&pieces, &solid);
    let w: f64 = pieces.iter().map(|p| p.winding(DVec3::ZERO)).sum();
    assert!(w.abs() < 1e-6, "the hole is filled: winding {w}");
}

#[test]
fn a_ball_seen_by_more_cameras_has_less_to_spare() {
    let solid = Solid::Ball(0.1);
    let mut last = f64::INFINITY;
    for n in [4, 8, 16] {
        let (pieces, _) = hull(&solid, &cameras(n, 0.5, 500.0));
        assert_valid_and_holding(&pieces, &solid);
        let excess = total_volume(&pieces) / solid.volume() - 1.0;
        assert!(excess > 0.0 && excess < last, "{n} views: excess {excess}");
        last = excess;
    }
}

#[test]
fn random_boxes_and_l_prisms_give_valid_hulls_that_hold_them() {
    let mut rng = crate::render::sample::SplitMix64::new(31);
    for trial in 0..40 {
        let size = DVec3::new(
            rng.range(0.05, 0.2),
            rng.range(0.05, 0.2),
            rng.range(0.05, 0.2),
        );
        let (lo, hi) = (-size / 2.0, size / 2.0);
        let solid = if trial % 2 == 0 {
            Solid::Boxes(vec![(lo, hi)])
        } else {
            // An L: the box less one quarter of its extent in x and y.
            let mid = DVec3::new(0.0, 0.0, hi.z);
            Solid::Boxes(vec![
                (lo, DVec3::new(hi.x, 0.0, hi.z)),
                (DVec3::new(lo.x, 0.0, lo.z), mid),
            ])
        };
        let axis = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let turn = glam::DQuat::from_axis_angle(axis.normalize(), rng.range(0.0, 3.0));
        let solid = Solid::Turned(Box::new(solid), turn);
        let n = 2 + (rng.next_u64() % 7) as usize;
        let cams = cameras(n, rng.range(0.5, 0.9), rng.range(400.0, 700.0));
        let (pieces, _) = hull(&solid, &cams);
        assert!(!pieces.is_empty(), "trial {trial}: nothing left");
        assert_valid_and_holding(&pieces, &solid);
    }
}

#[test]
fn one_more_view_carves_a_hull_further() {
    let solid = Solid::Turned(Box::new(a_box()), glam::DQuat::from_rotation_z(0.4));
    let cams = cameras(6, 0.6, 500.0);
    let all = sights(&solid, &cams);
    let depths = Depths::default();
    let mut tally = Tally::default();
    let five = visual_hull(&all[..5], depths, &mut tally).expect("five views");
    let six = carve_by(five.clone(), &all[5], depths, &mut tally).expect("one more");
    let at_once = visual_hull(&all, depths, &mut tally).expect("six views");
    let (v5, v6, v) = (
        total_volume(&five),
        total_volume(&six),
        total_volume(&at_once),
    );
    assert!(v6 < v5, "{v6} < {v5}");
    assert!(
        (v6 - v).abs() <= 1e-9 * v,
        "one more view {v6} against all at once {v}"
    );
    assert_valid_and_holding(&six, &solid);
    assert_eq!(tally.boolean, 0, "{tally:?}");
}

#[test]
fn a_camera_that_carved_before_carves_again_with_a_new_silhouette() {
    let big = Solid::Ball(0.1);
    let small = Solid::Ball(0.08);
    let cams = cameras(6, 0.5, 500.0);
    let depths = Depths::default();
    let mut tally = Tally::default();
    let first = visual_hull(&sights(&big, &cams), depths, &mut tally).expect("six views");
    // Camera 0 again, now seeing only the smaller ball: its earlier walls are seen
    // edge-on.
    let again = Sight {
        view: 6,
        ..sights(&small, &cams[..1]).remove(0)
    };
    let carved = carve_by(first, &again, depths, &mut tally).expect("carved again");
    assert_eq!(tally.boolean, 0, "{tally:?}");
    assert_valid_and_holding(&carved, &small);
    let mut mixed = sights(&big, &cams);
    mixed[0] = sights(&small, &cams[..1]).remove(0);
    let reference = visual_hull(&mixed, depths, &mut Tally::default()).expect("reference");
    let (a, b) = (total_volume(&carved), total_volume(&reference));
    assert!(
        (a - b).abs() <= 1e-9 * b,
        "carved again {a} against at once {b}"
    );
}

#[test]
fn a_piece_the_boolean_refuses_is_kept_whole_and_counted() {
    // Two boxes that pass through each other, as one closed mesh: its faces cross, so
    // the general boolean refuses it as an operand.
    let mut serials = Serials::new();
    let cube = crate::model::solids::box_solid(&mut serials, DVec3::splat(0.1)).expect("box");
    let first = Mesh::of_body(&cube, |p| p, |_| Maker::Unrecorded);
    let second = Mesh::of_body(&cube, |p| p + DVec3::splat(0.03), |_| Maker::Unrecorded);
    let base = first.positions.len() as u32;
    let crossed = Mesh {
        positions: [first.positions.clone(), second.positions.clone()].concat(),
        faces: first
            .faces
            .iter()
            .cloned()
            .chain(
                second
                    .faces
                    .iter()
                    .map(|f| f.iter().map(|i| i + base).collect()),
            )
            .collect(),
        makers: [first.makers.clone(), second.makers.clone()].concat(),
    };
    // A camera looking away from it: the piece is behind the camera, so only the
    // boolean could carve it.
    let intrinsics = Intrinsics::centered(640, 480, 500.0).expect("intrinsics");
    let camera = Camera::look_at(
        DVec3::new(0.0, -1.0, 0.0),
        DVec3::new(0.0, -2.0, 0.0),
        DVec3::Z,
        intrinsics,
    )
    .expect("camera");
    let square = |c: f64, r: f64| {
        vec![
            DVec2::new(c - r, 240.0 - r),
            DVec2::new(c + r, 240.0 - r),
            DVec2::new(c + r, 240.0 + r),
            DVec2::new(c - r, 240.0 + r),
        ]
    };
    let sight = Sight {
        camera,
        outline: Outline {
            rings: vec![square(320.0, 50.0)],
        },
        view: 7,
    };
    let mut tally = Tally::default();
    let out = carve_by(vec![crossed.clone()], &sight, Depths::default(), &mut tally)
        .expect("carving goes on");
    assert_eq!(tally.uncarved, 1, "{tally:?}");
    assert_eq!(tally.boolean, 0, "{tally:?}");
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].positions, crossed.positions);
    assert_eq!(out[0].faces, crossed.faces);
}
