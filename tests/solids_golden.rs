//! Golden tests of the solid primitives: the sweeps (PYRAMID, PRISM, CWPRISMOID,
//! CCWPRISMOID), solids of rotation, MKCOPY, FVDUAL and EVERT, with WINGED.DOC's own
//! examples: Euclid's dodecahedron (figure 3.8) and the rocket (figure 3.5).

use std::collections::HashSet;
use std::f64::consts::{PI, TAU};

use glam::{DVec2, DVec3};
use winged::model::solids::{
    DualLocus, MAX_SWEEP_FACES, PolygonFault, SolidError, Twist, box_solid, cone, cylinder, lamina,
    mkcube, prism_solid, pyramid_solid, rotation_sweep, sphere, torus,
};
use winged::model::{
    Body, Edge, EdgeId, EulerError, FaceId, Serial, Serials, VertexId, Violation, check_solid,
    check_topology,
};

fn counts(b: &Body) -> (usize, usize, usize) {
    (b.face_count(), b.edge_count(), b.vertex_count())
}

fn assert_topology(b: &Body) {
    let r = check_topology(b);
    assert!(r.is_ok(), "{r}");
}

fn assert_solid(b: &Body) {
    let r = check_solid(b, 1e-9);
    assert!(r.is_ok(), "{r}");
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-300)
}

/// Everything a body holds: every record with its slot and serial, and the handles.
#[derive(Debug, PartialEq)]
struct Snapshot {
    faces: Vec<(FaceId, Serial, EdgeId)>,
    edges: Vec<(EdgeId, Serial, Edge)>,
    vertices: Vec<(VertexId, Serial, DVec3, EdgeId)>,
    handles: u32,
}

fn snapshot(b: &Body) -> Snapshot {
    Snapshot {
        faces: b
            .faces()
            .map(|f| (f, b.face_serial(f), b.face(f).ped))
            .collect(),
        edges: b
            .edges()
            .map(|e| (e, b.edge_serial(e), *b.edge(e)))
            .collect(),
        vertices: b
            .vertices()
            .map(|v| (v, b.vertex_serial(v), b.position(v), b.vertex(v).ped))
            .collect(),
        handles: b.handles(),
    }
}

fn face_facing(b: &Body, dir: DVec3) -> FaceId {
    b.faces()
        .find(|&f| b.face_plane(f).is_some_and(|p| p.normal.dot(dir) > 0.999))
        .expect("a face facing that way")
}

fn regular_polygon(n: usize, r: f64, phase: f64) -> Vec<DVec2> {
    (0..n)
        .map(|k| {
            let (s, c) = (phase + TAU * k as f64 / n as f64).sin_cos();
            DVec2::new(r * c, r * s)
        })
        .collect()
}

fn polygon_area(p: &[DVec2]) -> f64 {
    let n = p.len();
    (0..n).map(|i| p[i].perp_dot(p[(i + 1) % n])).sum::<f64>() / 2.0
}

/// The inverse of PYRAMID: KLFE of the edges from the peak, newest first (each kills
/// the triangle on its NFACE side), then KLEV of the peak's spur.
fn unpyramid(b: &mut Body, peak: VertexId) {
    let spur = b.vertex(peak).ped;
    let mut ties: Vec<EdgeId> = b.vertex_edges(peak).filter(|&e| e != spur).collect();
    ties.sort_by_key(|&e| std::cmp::Reverse(b.edge_serial(e)));
    for e in ties {
        b.klfe(e).unwrap();
        assert_topology(b);
    }
    b.klev(peak).unwrap();
    assert_topology(b);
}

/// Asserts that `op` refuses with an error matching `want`, takes no serial number and
/// leaves the body exactly as it was.
macro_rules! assert_refused {
    ($b:expr, $s:expr, $op:expr, $want:pat) => {{
        let before = snapshot(&$b);
        let next = $s.peek();
        let got = $op;
        assert!(matches!(got, Err($want)), "got {got:?}");
        assert_eq!(
            snapshot(&$b),
            before,
            "a refused operation changed the body"
        );
        assert_eq!($s.peek(), next, "a refused operation took serial numbers");
    }};
}

// ------------------------------------------------------------------ box and lamina

#[test]
fn box_solid_is_mkcube_with_the_box_volume() {
    let mut s = Serials::new();
    let b = box_solid(&mut s, DVec3::new(4.0, 3.0, 2.0)).unwrap();
    assert_eq!(counts(&b), (6, 12, 8));
    assert_solid(&b);
    assert!(close(b.volume(), 24.0, 1e-12));
    let bounds = b.bounds().unwrap();
    assert_eq!(bounds.min, DVec3::new(-2.0, -1.5, -1.0));
    assert_eq!(bounds.max, DVec3::new(2.0, 1.5, 1.0));
}

#[test]
fn box_solid_refuses_bad_sizes_without_taking_serials() {
    let mut s = Serials::new();
    let next = s.peek();
    for (size, bad) in [
        (DVec3::new(0.0, 1.0, 1.0), "size.x"),
        (DVec3::new(1.0, -1.0, 1.0), "size.y"),
        (DVec3::new(1.0, 1.0, f64::NAN), "size.z"),
        (DVec3::new(f64::INFINITY, 1.0, 1.0), "size.x"),
    ] {
        match box_solid(&mut s, size) {
            Err(SolidError::NotPositive { parameter, .. })
            | Err(SolidError::NotFinite { parameter }) => assert_eq!(parameter, bad),
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(s.peek(), next);
}

#[test]
fn lamina_is_two_faces_back_to_back_with_top_facing_up_either_way_round() {
    let mut s = Serials::new();
    let mut square = vec![
        DVec2::new(0.0, 0.0),
        DVec2::new(2.0, 0.0),
        DVec2::new(2.0, 1.0),
        DVec2::new(0.0, 1.0),
    ];
    for _ in 0..2 {
        let l = lamina(&mut s, &square, 0.5).unwrap();
        assert_eq!(counts(&l.body), (2, 4, 4));
        assert_topology(&l.body);
        let up = l.body.face_plane(l.top).unwrap();
        let down = l.body.face_plane(l.bottom).unwrap();
        assert!((up.normal - DVec3::Z).length() < 1e-12);
        assert!((down.normal + DVec3::Z).length() < 1e-12);
        assert!((l.body.face_area(l.top) - 2.0).abs() < 1e-12);
        assert_eq!(l.body.volume(), 0.0);
        square.reverse(); // clockwise input gives the same lamina
    }
}

#[test]
fn lamina_refuses_polygons_that_are_not_simple() {
    let mut s = Serials::new();
    let next = s.peek();
    let p = |x: f64, y: f64| DVec2::new(x, y);
    let cases: Vec<(Vec<DVec2>, PolygonFault)> = vec![
        (
            vec![p(0.0, 0.0), p(1.0, 0.0)],
            PolygonFault::TooFewPoints { count: 2, min: 3 },
        ),
        (
            vec![p(0.0, 0.0), p(1.0, f64::NAN), p(0.0, 1.0)],
            PolygonFault::NotFinite { index: 1 },
        ),
        (
            vec![p(0.0, 0.0), p(1.0, 0.0), p(1.0, 0.0), p(0.0, 1.0)],
            PolygonFault::ZeroLengthSegment { index: 1 },
        ),
        // A bow tie: segments 0 and 2 cross.
        (
            vec![p(0.0, 0.0), p(1.0, 1.0), p(1.0, 0.0), p(0.0, 1.0)],
            PolygonFault::Crossing { a: 0, b: 2 },
        ),
        // A spike that folds back on itself.
        (
            vec![p(0.0, 0.0), p(2.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)],
            PolygonFault::Crossing { a: 0, b: 1 },
        ),
        // Collinear points fold back somewhere.
        (
            vec![p(0.0, 0.0), p(1.0, 1.0), p(2.0, 2.0)],
            PolygonFault::Crossing { a: 1, b: 2 },
        ),
    ];
    for (poly, fault) in cases {
        match lamina(&mut s, &poly, 0.0) {
            Err(SolidError::Polygon(f)) => assert_eq!(f, fault),
            other => panic!("{poly:?}: {other:?}"),
        }
    }
    assert!(matches!(
        lamina(&mut s, &regular_polygon(5, 1.0, 0.0), f64::NAN),
        Err(SolidError::NotFinite { parameter: "z" })
    ));
    assert_eq!(s.peek(), next);
}

// ------------------------------------------------------------------ sweeps

#[test]
fn pyramid_on_a_cube_face_adds_n_minus_1_faces_and_klfe_klev_undo_it() {
    let mut s = Serials::new();
    let mut b = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
    let before = snapshot(&b);
    let top = face_facing(&b, DVec3::Z);
    let peak = b.pyramid(&mut s, top, DVec3::new(0.0, 0.0, 4.0)).unwrap();
    assert_topology(&b);
    // n = 4: F + 3, E + 4, V + 1.
    assert_eq!(counts(&b), (9, 16, 9));
    assert_solid(&b);
    assert!(b.is_convex(1e-12));
    // Cube plus a pyramid of base 4 and height 3.
    assert!(close(b.volume(), 8.0 + 4.0 * 3.0 / 3.0, 1e-12));
    assert_eq!(b.valence(peak), 4);
    assert!(b.vertex_faces(peak).all(|f| b.face_degree(f) == 3));
    assert!(
        b.vertex_faces(peak).any(|f| f == top),
        "f survives as a triangle"
    );
    // KLFEs and KLEV un-pyramid: the cube's counts, volume and loci again, and the top
    // face is the top face again.
    unpyramid(&mut b, peak);
    assert_eq!(b.face_degree(top), 4);
    assert_eq!(counts(&b), (6, 12, 8));
    assert_solid(&b);
    assert!(close(b.volume(), 8.0, 1e-12));
    assert_eq!(snapshot(&b).vertices, before.vertices);
}

#[test]
fn prism_on_a_cube_face_adds_area_times_height() {
    let mut s = Serials::new();
    let mut b = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
    let top = face_facing(&b, DVec3::Z);
    let swept = b.prism(&mut s, top, DVec3::Z * 3.0, 1.0).unwrap();
    assert_topology(&b);
    // n = 4: F + 4, E + 8, V + 4.
    assert_eq!(counts(&b), (10, 20, 12));
    assert_solid(&b);
    assert_eq!(swept.cap, top);
    assert_eq!(
        (swept.base.len(), swept.ring.len(), swept.sides.len()),
        (4, 4, 4)
    );
    for (&v, &w) in swept.base.iter().zip(&swept.ring) {
        assert!((b.position(w) - b.position(v) - DVec3::Z * 3.0).length() < 1e-12);
    }
    // The cap is the swept face, now on the new ring.
    let cap: HashSet<_> = b.face_vertices(top).collect();
    assert_eq!(cap, swept.ring.iter().copied().collect());
    assert!((b.face_plane(top).unwrap().offset - 4.0).abs() < 1e-12);
    for &side in &swept.sides {
        assert_eq!(b.face_degree(side), 4);
    }
    assert!(close(b.volume(), 8.0 + 4.0 * 3.0, 1e-12));
    assert!(b.is_convex(1e-12));
}

#[test]
fn klfe_and_klev_undo_a_prism_and_a_prismoid() {
    for twist in [None, Some(Twist::Ccw), Some(Twist::Cw)] {
        let mut s = Serials::new();
        let mut b = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
        let before = snapshot(&b);
        let top = face_facing(&b, DVec3::Z);
        let mark = s.peek();
        let swept = match twist {
            None => b.prism(&mut s, top, DVec3::Z, 0.5),
            Some(t) => b.prismoid(&mut s, top, DVec3::Z, 0.5, t),
        }
        .unwrap();
        assert_solid(&b);
        // The edges made between the rings (ties and diagonals), newest first: every new
        // edge but the spurs, which are the ring vertices' PEDs.
        let mut between: Vec<EdgeId> = b
            .edges()
            .filter(|&e| b.edge_serial(e) >= mark)
            .filter(|&e| swept.ring.iter().all(|&w| b.vertex(w).ped != e))
            .collect();
        assert_eq!(between.len(), if twist.is_some() { 8 } else { 4 });
        between.sort_by_key(|&e| std::cmp::Reverse(b.edge_serial(e)));
        for e in between {
            b.klfe(e).unwrap();
            assert_topology(&b);
        }
        for &w in &swept.ring {
            b.klev(w).unwrap();
            assert_topology(&b);
        }
        assert_eq!(counts(&b), (6, 12, 8));
        assert_solid(&b);
        assert_eq!(b.face_degree(top), 4);
        assert_eq!(snapshot(&b).vertices, before.vertices);
        assert!(close(b.volume(), 8.0, 1e-12));
    }
}

#[test]
fn prism_with_scale_makes_a_frustum() {
    let mut s = Serials::new();
    let mut b = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
    let top = face_facing(&b, DVec3::Z);
    b.prism(&mut s, top, DVec3::Z * 3.0, 0.5).unwrap();
    assert_topology(&b);
    assert_solid(&b);
    // Frustum of a pyramid: h/3·(A1 + A2 + √(A1·A2)) with A1 = 4, A2 = 1, h = 3.
    let frustum = 3.0 / 3.0 * (4.0 + 1.0 + 2.0);
    assert!(close(b.volume(), 8.0 + frustum, 1e-12));
    assert!(close(b.face_area(top), 1.0, 1e-12));
    assert!(b.is_convex(1e-12));
    // A slanted, widening sweep is fine too.
    let mut c = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
    let top = face_facing(&c, DVec3::Z);
    c.prism(&mut s, top, DVec3::new(0.5, -0.25, 2.0), 1.5)
        .unwrap();
    assert_solid(&c);
    let frustum = 2.0 / 3.0 * (4.0 + 9.0 + 6.0);
    assert!(close(c.volume(), 8.0 + frustum, 1e-12));
}

#[test]
fn prism_and_pyramid_solids_are_centred_in_height() {
    let mut s = Serials::new();
    let hexagon = regular_polygon(6, 1.5, 0.3);
    let area = polygon_area(&hexagon);
    let p = prism_solid(&mut s, &hexagon, 2.0).unwrap();
    assert_eq!(counts(&p), (8, 18, 12));
    assert_solid(&p);
    assert!(close(p.volume(), area * 2.0, 1e-12));
    let bounds = p.bounds().unwrap();
    assert_eq!((bounds.min.z, bounds.max.z), (-1.0, 1.0));

    let l_shape = vec![
        DVec2::new(0.0, 0.0),
        DVec2::new(2.0, 0.0),
        DVec2::new(2.0, 1.0),
        DVec2::new(1.0, 1.0),
        DVec2::new(1.0, 2.0),
        DVec2::new(0.0, 2.0),
    ];
    let mut cw = l_shape.clone();
    cw.reverse();
    let q = prism_solid(&mut s, &cw, 0.5).unwrap();
    assert_solid(&q);
    assert!(close(q.volume(), 3.0 * 0.5, 1e-12));
    assert!(!q.is_convex(1e-9));

    let y = pyramid_solid(&mut s, &hexagon, 3.0).unwrap();
    assert_eq!(counts(&y), (7, 12, 7));
    assert_solid(&y);
    assert!(close(y.volume(), area * 3.0 / 3.0, 1e-12));
    assert!(y.is_convex(1e-12));
    let bounds = y.bounds().unwrap();
    assert_eq!((bounds.min.z, bounds.max.z), (-1.5, 1.5));
    // The L is star-shaped about its centroid (5/6, 5/6) ...
    let yl = pyramid_solid(&mut s, &l_shape, 1.0).unwrap();
    assert_solid(&yl);
    assert!(close(yl.volume(), 3.0 / 3.0, 1e-12));
    // ... a thin C is not.
    let c_shape = vec![
        DVec2::new(0.0, 0.0),
        DVec2::new(3.0, 0.0),
        DVec2::new(3.0, 0.2),
        DVec2::new(0.2, 0.2),
        DVec2::new(0.2, 2.8),
        DVec2::new(3.0, 2.8),
        DVec2::new(3.0, 3.0),
        DVec2::new(0.0, 3.0),
    ];
    let next = s.peek();
    assert!(matches!(
        pyramid_solid(&mut s, &c_shape, 1.0),
        Err(SolidError::Polygon(PolygonFault::NotStarShaped { .. }))
    ));
    assert!(matches!(
        prism_solid(&mut s, &hexagon, 0.0),
        Err(SolidError::NotPositive {
            parameter: "height",
            ..
        })
    ));
    assert_eq!(s.peek(), next);
}

#[test]
fn prismoids_cut_each_side_along_the_documented_diagonal() {
    for twist in [Twist::Ccw, Twist::Cw] {
        let mut s = Serials::new();
        let mut l = lamina(&mut s, &regular_polygon(5, 1.0, 0.0), 0.0).unwrap();
        let b = &mut l.body;
        let swept = b.prismoid(&mut s, l.top, DVec3::Z, 0.75, twist).unwrap();
        assert_topology(b);
        // Lamina 2/5/5, n = 5: F + 10, E + 15, V + 5.
        assert_eq!(counts(b), (12, 20, 10));
        assert_solid(b);
        assert_eq!(swept.sides.len(), 10);
        assert!(swept.sides.iter().all(|&f| b.face_degree(f) == 3));
        let n = swept.base.len();
        for i in 0..n {
            let j = (i + 1) % n;
            let (lo, hi) = match twist {
                Twist::Ccw => (swept.base[j], swept.ring[i]),
                Twist::Cw => (swept.base[i], swept.ring[j]),
            };
            assert!(
                b.linked_vertices(lo, hi).is_some(),
                "{twist:?} diagonal {i}"
            );
            // The low triangle has a base edge, the high one a ring edge.
            let low: HashSet<_> = b.face_vertices(swept.sides[2 * i]).collect();
            assert!(low.contains(&swept.base[i]) && low.contains(&swept.base[j]));
            let high: HashSet<_> = b.face_vertices(swept.sides[2 * i + 1]).collect();
            assert!(high.contains(&swept.ring[i]) && high.contains(&swept.ring[j]));
        }
        // Unturned, the prismoid is the frustum cut into triangles.
        let area = polygon_area(&regular_polygon(5, 1.0, 0.0));
        let a2 = area * 0.75 * 0.75;
        assert!(close(
            b.volume(),
            (area + a2 + (area * a2).sqrt()) / 3.0,
            1e-12
        ));
    }
}

#[test]
fn a_turned_prismoid_of_a_hexagon_is_a_convex_antiprism() {
    for twist in [Twist::Ccw, Twist::Cw] {
        let mut s = Serials::new();
        let hexagon = regular_polygon(6, 1.0, 0.0);
        let mut l = lamina(&mut s, &hexagon, 0.0).unwrap();
        let b = &mut l.body;
        let h = 0.8;
        let swept = b
            .prismoid_turned(&mut s, l.top, DVec3::Z * h, 1.0, twist, PI / 6.0)
            .unwrap();
        assert_topology(b);
        assert_solid(b);
        assert!(b.is_convex(1e-9));
        assert!(b.vertices().all(|v| b.valence(v) == 4));
        // Prismatoid volume h/6·(bottom + top + 4·middle); the middle section is the
        // 12-gon through the midpoints of the side edges.
        let n = swept.base.len();
        let at = |v: VertexId| b.position(v);
        let mids: Vec<DVec2> = (0..n)
            .flat_map(|i| {
                let j = (i + 1) % n;
                let (vi, wi) = (at(swept.base[i]), at(swept.ring[i]));
                match twist {
                    Twist::Ccw => [(vi + wi) / 2.0, (at(swept.base[j]) + wi) / 2.0],
                    Twist::Cw => [(vi + wi) / 2.0, (vi + at(swept.ring[j])) / 2.0],
                }
            })
            .map(|p| p.truncate())
            .collect();
        let area = polygon_area(&hexagon);
        let expected = h / 6.0 * (2.0 * area + 4.0 * polygon_area(&mids));
        assert!(
            close(b.volume(), expected, 1e-12),
            "{} {expected}",
            b.volume()
        );
        // The cap really turned, in the twist's sense.
        let w0 = b.position(swept.ring[0]).truncate();
        let v0 = b.position(swept.base[0]).truncate();
        let sense = v0.perp_dot(w0).signum();
        assert_eq!(sense, if twist == Twist::Ccw { 1.0 } else { -1.0 });
    }
}

#[test]
fn refused_sweeps_leave_the_body_and_the_serials_untouched() {
    let mut s = Serials::new();
    let mut b = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
    let top = face_facing(&b, DVec3::Z);
    let up = DVec3::Z;
    assert_refused!(
        b,
        s,
        b.prism(&mut s, top, DVec3::ZERO, 1.0),
        SolidError::ZeroOffset
    );
    assert_refused!(
        b,
        s,
        b.prism(&mut s, top, DVec3::new(f64::NAN, 0.0, 1.0), 1.0),
        SolidError::NotFinite {
            parameter: "offset"
        }
    );
    assert_refused!(
        b,
        s,
        b.prism(&mut s, top, -up, 1.0),
        SolidError::OffsetNotOutward { .. }
    );
    assert_refused!(
        b,
        s,
        b.prism(&mut s, top, DVec3::X, 1.0),
        SolidError::OffsetNotOutward { .. }
    );
    for scale in [0.0, -1.0] {
        assert_refused!(
            b,
            s,
            b.prism(&mut s, top, up, scale),
            SolidError::NotPositive {
                parameter: "scale",
                ..
            }
        );
    }
    assert_refused!(
        b,
        s,
        b.prismoid(&mut s, top, up, f64::INFINITY, Twist::Cw),
        SolidError::NotFinite { parameter: "scale" }
    );
    assert_refused!(
        b,
        s,
        b.prismoid_turned(&mut s, top, up, 1.0, Twist::Ccw, PI),
        SolidError::TurnAngle { .. }
    );
    assert_refused!(
        b,
        s,
        b.prismoid_turned(&mut s, top, up, 1.0, Twist::Ccw, -0.1),
        SolidError::TurnAngle { .. }
    );
    assert_refused!(
        b,
        s,
        b.pyramid(&mut s, top, DVec3::new(0.0, 0.0, 1.0)),
        SolidError::PeakNotAbove { .. }
    );
    assert_refused!(
        b,
        s,
        b.pyramid(&mut s, top, DVec3::new(0.0, 0.0, -5.0)),
        SolidError::PeakNotAbove { .. }
    );
    assert_refused!(
        b,
        s,
        b.pyramid(&mut s, top, DVec3::new(0.0, f64::NAN, 5.0)),
        SolidError::NotFinite { parameter: "peak" }
    );
    assert_refused!(
        b,
        s,
        b.prism(&mut s, FaceId::from_index(99), up, 1.0),
        SolidError::Euler(EulerError::UnknownFace(_))
    );
    // A face with a spur is not a simple polygon.
    let corner = b.face_vertices(top).next().unwrap();
    b.mkev(&mut s, top, corner, DVec3::new(0.0, 0.0, 1.0))
        .unwrap();
    assert_refused!(
        b,
        s,
        b.prism(&mut s, top, up, 1.0),
        SolidError::Euler(EulerError::FaceNotSimple { .. })
    );
    assert_refused!(
        b,
        s,
        b.pyramid(&mut s, top, DVec3::Z * 3.0),
        SolidError::Euler(EulerError::FaceNotSimple { .. })
    );
    // A one-edge wire's face has two edges.
    let (mut w, f, v) = Body::seminal(&mut s, DVec3::ZERO);
    w.mkev(&mut s, f, v, DVec3::X).unwrap();
    assert_refused!(
        w,
        s,
        w.prism(&mut s, f, up, 1.0),
        SolidError::Euler(EulerError::FaceTooSmall { degree: 2, .. })
    );
    // A lamina whose face has collapsed to zero area has no plane.
    let mut l = lamina(&mut s, &regular_polygon(3, 1.0, 0.0), 0.0).unwrap();
    for v in l.body.vertices().collect::<Vec<_>>() {
        l.body.set_position(v, DVec3::ZERO);
    }
    assert_refused!(
        l.body,
        s,
        l.body.prism(&mut s, l.top, up, 1.0),
        SolidError::DegenerateFace { .. }
    );
}

// ------------------------------------------------------------------ the rocket

#[test]
fn rocket_of_figure_3_5() {
    let mut s = Serials::new();
    // A nine-sided lamina: F = 2, E = 9, V = 9.
    let mut l = lamina(&mut s, &regular_polygon(9, 1.0, 0.0), 0.0).unwrap();
    let b = &mut l.body;
    let f = l.top;
    assert_eq!(counts(b), (2, 9, 9));
    assert_topology(b);
    // Each step's counts, with n = 9 edges on the swept face throughout:
    //   prism     F + n = 9,      E + 2n = 18, V + n = 9
    //   prismoid  F + 2n = 18,    E + 3n = 27, V + n = 9
    //   pyramid   F + n − 1 = 8,  E + n = 9,   V + 1
    //   fin (a prism of a quadrilateral side face): F + 4, E + 8, V + 4
    let mut expect = (2, 9, 9);
    let mut step = |b: &Body, df: usize, de: usize, dv: usize| {
        expect = (expect.0 + df, expect.1 + de, expect.2 + dv);
        assert_eq!(counts(b), expect);
        assert_topology(b);
    };
    let area = polygon_area(&regular_polygon(9, 1.0, 0.0));
    // Two prism stages: the first straight up, the second tapering.
    let stage1 = b.prism(&mut s, f, DVec3::Z * 3.0, 1.0).unwrap();
    step(b, 9, 18, 9); // 11 / 27 / 18
    assert!(close(b.volume(), area * 3.0, 1e-12));
    b.prism(&mut s, f, DVec3::Z * 1.0, 0.8).unwrap();
    step(b, 9, 18, 9); // 20 / 45 / 27
    let a2 = area * 0.64;
    assert!(close(
        b.volume(),
        area * 3.0 + (area + a2 + (area * a2).sqrt()) / 3.0,
        1e-12
    ));
    // Two counter-clockwise prismoid stages, turning the cap a little each time ...
    for _ in 0..2 {
        b.prismoid_turned(&mut s, f, DVec3::Z * 1.5, 0.95, Twist::Ccw, PI / 18.0)
            .unwrap();
        step(b, 18, 27, 9); // 38 / 72 / 36, then 56 / 99 / 45
    }
    // ... and two clockwise ones, turning it back.
    for _ in 0..2 {
        b.prismoid_turned(&mut s, f, DVec3::Z * 1.5, 0.9, Twist::Cw, PI / 18.0)
            .unwrap();
        step(b, 18, 27, 9); // 74 / 126 / 54, then 92 / 153 / 63
    }
    // The nose cone.
    let center = b.face_center(f);
    let nose = b.pyramid(&mut s, f, center + DVec3::Z * 2.5).unwrap();
    step(b, 8, 9, 1); // 100 / 162 / 64
    assert_eq!(b.valence(nose), 9);
    let body_volume = b.volume();
    // Fins: a prism out of every third side face of the first stage.
    for &side in stage1.sides.iter().step_by(3) {
        let out = b.face_plane(side).unwrap().normal;
        b.prism(&mut s, side, out * 1.2, 0.5).unwrap();
        step(b, 4, 8, 4); // 104 / 170 / 68, 108 / 178 / 72, 112 / 186 / 76
    }
    // 2 + 2·9 + 4·18 + 8 + 3·4 = 112 faces; 9 + 2·18 + 4·27 + 9 + 3·8 = 186 edges;
    // 9 + 2·9 + 4·9 + 1 + 3·4 = 76 vertices; 112 − 186 + 76 = 2.
    assert_eq!(counts(b), (112, 186, 76));
    assert_eq!(b.euler_characteristic(), 2);
    assert_solid(b);
    assert!(!b.is_convex(1e-9));
    // Each fin adds a frustum over a side face: h/3·(A + A/4 + A/2).
    let side_area = b.face_area(stage1.sides[1]);
    let fins = 3.0 * 1.2 / 3.0 * side_area * (1.0 + 0.25 + 0.5);
    assert!(close(b.volume(), body_volume + fins, 1e-12));
}

// ------------------------------------------------------------------ Euclid's dodecahedron

/// The golden ratio.
fn phi() -> f64 {
    (1.0 + 5.0f64.sqrt()) / 2.0
}

/// Euclid's construction (WINGED.DOC figure 3.8) with exact golden-ratio loci: MKCUBE
/// at ±1, ESPLIT every edge, move each midpoint onto the roof ridge over one of its
/// faces, then MKFE across each octagon.
fn euclid_dodecahedron(s: &mut Serials) -> Body {
    let phi = phi();
    let mut b = mkcube(s, 2.0, 2.0, 2.0).unwrap();
    // Each cube face's outward axis and sign, before the faces stop being planar.
    let axes: Vec<(FaceId, usize, f64)> = b
        .faces()
        .map(|f| {
            let n = b.face_plane(f).unwrap().normal;
            let k = (0..3)
                .max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
                .unwrap();
            (f, k, n[k].signum())
        })
        .collect();
    let edges: Vec<EdgeId> = b.edges().collect();
    assert_eq!(edges.len(), 12);
    for e in edges {
        let r = *b.edge(e);
        let mid = (b.position(r.vt[0]) + b.position(r.vt[1])) / 2.0;
        let (_, m) = b.esplit(s, e, mid).unwrap();
        assert_topology(&b);
        // The roof vertex: (0, ±1/φ, ±φ) and its cyclic permutations.
        let roof = if mid.x == 0.0 {
            DVec3::new(0.0, mid.y / phi, mid.z * phi)
        } else if mid.z == 0.0 {
            DVec3::new(mid.x / phi, mid.y * phi, 0.0)
        } else {
            DVec3::new(mid.x * phi, 0.0, mid.z / phi)
        };
        b.set_position(m, roof);
    }
    assert_eq!(counts(&b), (6, 24, 20));
    for (f, k, sign) in axes {
        assert_eq!(b.face_degree(f), 8);
        let ridge: Vec<VertexId> = b
            .face_vertices(f)
            .filter(|&v| (b.position(v)[k] * sign - phi).abs() < 1e-12)
            .collect();
        assert_eq!(ridge.len(), 2);
        b.mkfe(s, ridge[0], f, ridge[1]).unwrap();
        assert_topology(&b);
    }
    b
}

#[test]
fn euclid_dodecahedron_from_a_cube_is_regular() {
    let mut s = Serials::new();
    let b = euclid_dodecahedron(&mut s);
    assert_eq!(counts(&b), (12, 30, 20));
    assert_solid(&b);
    assert!(b.is_convex(1e-12));
    assert!(b.faces().all(|f| b.face_degree(f) == 5));
    assert!(b.vertices().all(|v| b.valence(v) == 3));
    let a = 2.0 / phi();
    for e in b.edges() {
        assert!((b.edge_length(e) - a).abs() < 1e-12);
    }
    let regular = (15.0 + 7.0 * 5.0f64.sqrt()) / 4.0 * a.powi(3);
    assert!(
        close(b.volume(), regular, 1e-12),
        "{} vs {regular}",
        b.volume()
    );
    assert!(b.centroid().unwrap().length() < 1e-12);
}

#[test]
fn fvdual_of_the_dodecahedron_is_the_icosahedron() {
    let mut s = Serials::new();
    let mut b = euclid_dodecahedron(&mut s);
    let face_serials: HashSet<Serial> = b.faces().map(|f| b.face_serial(f)).collect();
    let vertex_serials: HashSet<Serial> = b.vertices().map(|v| b.vertex_serial(v)).collect();
    let edge_serials: Vec<Serial> = b.edges().map(|e| b.edge_serial(e)).collect();
    let next = s.peek();
    b.fvdual().unwrap();
    assert_topology(&b);
    assert_eq!(counts(&b), (20, 30, 12));
    assert!(b.faces().all(|f| b.face_degree(f) == 3));
    assert!(b.vertices().all(|v| b.valence(v) == 5));
    assert_solid(&b);
    assert!(b.is_convex(1e-12));
    // Serials are re-typed, not renewed.
    assert_eq!(s.peek(), next);
    let new_vertices: HashSet<Serial> = b.vertices().map(|v| b.vertex_serial(v)).collect();
    let new_faces: HashSet<Serial> = b.faces().map(|f| b.face_serial(f)).collect();
    assert_eq!(new_vertices, face_serials);
    assert_eq!(new_faces, vertex_serials);
    assert_eq!(
        b.edges().map(|e| b.edge_serial(e)).collect::<Vec<_>>(),
        edge_serials
    );
    // A regular icosahedron: all edges equal; vertices at the dodecahedron's face
    // centres, at the inradius of the dodecahedron of edge a.
    let a = 2.0 / phi();
    let inradius = a / 2.0 * (5.0 / 2.0 + 11.0 / 10.0 * 5.0f64.sqrt()).sqrt();
    let edge = b.edge_length(b.edges().next().unwrap());
    for e in b.edges() {
        assert!((b.edge_length(e) - edge).abs() < 1e-12);
    }
    for v in b.vertices() {
        assert!((b.position(v).length() - inradius).abs() < 1e-12);
    }
    let ico = 5.0 * (3.0 + 5.0f64.sqrt()) / 12.0 * edge.powi(3);
    assert!(close(b.volume(), ico, 1e-12));
}

#[test]
fn fvdual_twice_restores_the_topology_with_every_edge_inverted() {
    let mut s = Serials::new();
    let original = euclid_dodecahedron(&mut s);
    let mut b = original.mkcopy(&mut s);
    let before = snapshot(&b);
    b.fvdual().unwrap();
    b.fvdual().unwrap();
    assert_topology(&b);
    assert_eq!(counts(&b), (12, 30, 20));
    let after = snapshot(&b);
    // Same slots and serials for every face and vertex, and the same PEDs.
    assert_eq!(after.faces, before.faces);
    assert_eq!(
        after
            .vertices
            .iter()
            .map(|v| (v.0, v.1, v.3))
            .collect::<Vec<_>>(),
        before
            .vertices
            .iter()
            .map(|v| (v.0, v.1, v.3))
            .collect::<Vec<_>>()
    );
    // Every edge is the same edge turned half a turn.
    for ((e, s1, r1), (_, s2, r2)) in after.edges.iter().zip(&before.edges) {
        assert_eq!(s1, s2);
        let mut inv = *r2;
        inv.vt.swap(0, 1);
        inv.face.swap(0, 1);
        inv.cw.swap(0, 1);
        inv.ccw.swap(0, 1);
        assert_eq!(*r1, inv, "edge {e:?}");
    }
    // Face centres of face centres: the same shape, shrunk.
    assert_solid(&b);
    assert!(b.faces().all(|f| b.face_degree(f) == 5));
}

#[test]
fn polar_fvdual_twice_restores_every_locus() {
    let mut s = Serials::new();
    // A box and a frustum: the face-centre dual of these is not planar, the polar one is.
    let mut b = box_solid(&mut s, DVec3::new(2.0, 3.0, 4.0)).unwrap();
    let top = face_facing(&b, DVec3::Z);
    b.prism(&mut s, top, DVec3::new(0.2, 0.1, 1.0), 0.6)
        .unwrap();
    assert_solid(&b);
    let before = snapshot(&b);
    let volume = b.volume();
    let locus = DualLocus::Polar {
        center: DVec3::new(0.1, 0.0, 0.5),
        radius: 1.5,
    };
    b.fvdual_with(locus).unwrap();
    assert_topology(&b);
    assert_eq!(counts(&b), (12, 20, 10));
    assert_solid(&b);
    assert!(b.is_convex(1e-9));
    b.fvdual_with(locus).unwrap();
    assert_solid(&b);
    let after = snapshot(&b);
    for (x, y) in after.vertices.iter().zip(&before.vertices) {
        assert_eq!((x.0, x.1), (y.0, y.1));
        assert!((x.2 - y.2).length() < 1e-12, "{:?} vs {:?}", x.2, y.2);
    }
    assert!(close(b.volume(), volume, 1e-12));
}

#[test]
fn fvdual_refusals_leave_the_body_untouched() {
    let mut s = Serials::new();
    // A wire's edges have one face on both sides.
    let (mut w, f, v) = Body::seminal(&mut s, DVec3::ZERO);
    w.mkev(&mut s, f, v, DVec3::X).unwrap();
    assert_refused!(w, s, w.fvdual(), SolidError::DualLoop { .. });
    // The polar centre must be inside every face plane.
    let mut b = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
    for (center, radius) in [(DVec3::new(0.0, 0.0, 1.0), 1.0), (DVec3::ZERO, -1.0)] {
        let locus = DualLocus::Polar { center, radius };
        assert_refused!(
            b,
            s,
            b.fvdual_with(locus),
            SolidError::PolarCenter { .. } | SolidError::NotPositive { .. }
        );
    }
    // A seminal body is its own dual, its vertex where it was.
    let (mut m, _, v) = Body::seminal(&mut s, DVec3::new(1.0, 2.0, 3.0));
    let (fs, vs) = (m.faces().next().unwrap(), v);
    let (sf, sv) = (m.face_serial(fs), m.vertex_serial(vs));
    m.fvdual().unwrap();
    assert_topology(&m);
    let v = m.vertices().next().unwrap();
    assert_eq!(m.position(v), DVec3::new(1.0, 2.0, 3.0));
    assert_eq!(m.vertex_serial(v), sf);
    assert_eq!(m.face_serial(m.faces().next().unwrap()), sv);
}

#[test]
fn fvdual_of_a_cube_is_an_octahedron_and_of_a_torus_keeps_its_handle() {
    let mut s = Serials::new();
    let mut b = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
    b.fvdual().unwrap();
    assert_eq!(counts(&b), (8, 12, 6));
    assert_solid(&b);
    assert!(close(b.volume(), 4.0 / 3.0, 1e-12));
    let mut t = torus(&mut s, 3.0, 1.0, 8, 6).unwrap();
    t.fvdual().unwrap();
    assert_topology(&t);
    assert_eq!(counts(&t), (48, 96, 48));
    assert_eq!(t.handles(), 1);
    assert!(t.faces().all(|f| t.face_degree(f) == 4));
}

// ------------------------------------------------------------------ MKCOPY and EVERT

#[test]
fn mkcopy_is_the_same_body_under_fresh_serials() {
    let mut s = Serials::new();
    let b = euclid_dodecahedron(&mut s);
    let mark = s.peek();
    let c = b.mkcopy(&mut s);
    assert_topology(&c);
    assert_solid(&c);
    assert_eq!(counts(&c), counts(&b));
    assert_eq!(c.volume(), b.volume());
    let serials = |x: &Body| -> HashSet<Serial> {
        x.faces()
            .map(|f| x.face_serial(f))
            .chain(x.edges().map(|e| x.edge_serial(e)))
            .chain(x.vertices().map(|v| x.vertex_serial(v)))
            .collect()
    };
    let (sb, sc) = (serials(&b), serials(&c));
    assert_eq!(sc.len(), 62);
    assert!(sb.is_disjoint(&sc));
    assert!(sc.iter().all(|&x| x >= mark));
    assert_eq!(s.peek(), Serial(mark.get() + 62));
    // No dead slots in the original: every entity keeps its slot id.
    let (pb, pc) = (snapshot(&b), snapshot(&c));
    assert_eq!(
        pb.edges.iter().map(|x| x.2).collect::<Vec<_>>(),
        pc.edges.iter().map(|x| x.2).collect::<Vec<_>>()
    );
    assert_eq!(
        pb.vertices.iter().map(|x| (x.0, x.2)).collect::<Vec<_>>(),
        pc.vertices.iter().map(|x| (x.0, x.2)).collect::<Vec<_>>()
    );
}

#[test]
fn mkcopy_of_a_body_with_dead_slots_packs_them_and_maps_every_entity() {
    let mut s = Serials::new();
    let mut b = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
    let top = face_facing(&b, DVec3::Z);
    // A pyramid and its undoing leave dead slots; a split reuses some of them.
    let peak = b.pyramid(&mut s, top, DVec3::Z * 3.0).unwrap();
    unpyramid(&mut b, peak);
    let e = b.edges().next().unwrap();
    let mid = (b.position(b.edge(e).vt[0]) + b.position(b.edge(e).vt[1])) / 2.0;
    b.esplit(&mut s, e, mid).unwrap();
    assert_topology(&b);
    assert_eq!(counts(&b), (6, 13, 9));
    let (c, map) = b.mkcopy_mapped(&mut s);
    assert_topology(&c);
    assert_eq!(counts(&c), counts(&b));
    assert_eq!(c.handles(), b.handles());
    assert!(close(c.volume(), b.volume(), 1e-12));
    for f in b.faces() {
        let g = map.face(f).unwrap();
        let want: Vec<VertexId> = b.face_vertices(f).map(|v| map.vertex(v).unwrap()).collect();
        let got: Vec<VertexId> = c.face_vertices(g).collect();
        assert_eq!(got, want);
    }
    for v in b.vertices() {
        assert_eq!(c.position(map.vertex(v).unwrap()), b.position(v));
    }
    for e in b.edges() {
        assert!(map.edge(e).is_some());
    }
    assert_eq!(map.face(FaceId::from_index(1000)), None);
}

#[test]
fn evert_turns_a_solid_into_a_room_and_back() {
    let mut s = Serials::new();
    let mut b = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
    let before = snapshot(&b);
    b.evert();
    assert_topology(&b);
    assert!(close(b.volume(), -8.0, 1e-12));
    let r = check_solid(&b, 1e-9);
    assert_eq!(r.violations.len(), 1, "{r}");
    assert!(matches!(r.violations[0], Violation::Inward { volume } if volume < 0.0));
    for f in b.faces() {
        // Every normal now points into the room.
        let p = b.face_plane(f).unwrap();
        assert!(p.distance(DVec3::ZERO) > 0.0);
    }
    b.evert();
    assert_eq!(snapshot(&b), before);
    assert_solid(&b);

    let mut t = sphere(&mut s, 1.0, 12, 6).unwrap();
    let v = t.volume();
    t.evert();
    assert_topology(&t);
    assert!(close(t.volume(), -v, 1e-12));
    t.evert();
    assert_solid(&t);
}

// ------------------------------------------------------------------ rotation solids

/// The exact volume of a rotation polyhedron: `n·sin(2π/n)/2 · Σ dz/3·(r0² + r0·r1 +
/// r1²)` over the segments of a counter-clockwise profile (each band is a frustum of a
/// pyramid over a regular n-gon).
fn rotation_volume(profile: &[DVec2], n: usize, closed: bool) -> f64 {
    let m = profile.len();
    let segs = if closed { m } else { m - 1 };
    let k = n as f64 * (TAU / n as f64).sin() / 2.0;
    (0..segs)
        .map(|j| {
            let (a, b) = (profile[j], profile[(j + 1) % m]);
            (b.y - a.y) / 3.0 * (a.x * a.x + a.x * b.x + b.x * b.x)
        })
        .sum::<f64>()
        * k
}

#[test]
fn cylinder_is_the_inscribed_prism() {
    let mut s = Serials::new();
    for n in [3, 4, 7, 16, 100] {
        let (r, h) = (1.5, 2.0);
        let b = cylinder(&mut s, r, h, n).unwrap();
        assert_eq!(counts(&b), (n + 2, 3 * n, 2 * n));
        assert_solid(&b);
        assert!(b.is_convex(1e-9));
        let exact = n as f64 / 2.0 * r * r * (TAU / n as f64).sin() * h;
        assert!(close(b.volume(), exact, 1e-12), "n = {n}");
        let bounds = b.bounds().unwrap();
        assert_eq!((bounds.min.z, bounds.max.z), (-1.0, 1.0));
        assert!(b.centroid().unwrap().length() < 1e-12);
    }
    // Convergence: the relative error is 1 − sin(x)/x for x = 2π/n, below x²/6.
    let mut last = f64::INFINITY;
    for n in [8, 16, 32, 64, 128, 256] {
        let b = cylinder(&mut s, 1.0, 1.0, n).unwrap();
        let err = 1.0 - b.volume() / PI;
        let x = TAU / n as f64;
        assert!(err > 0.0 && err <= x * x / 6.0, "n = {n}: {err}");
        assert!(err < last / 3.5);
        last = err;
    }
}

#[test]
fn cone_is_the_inscribed_pyramid() {
    let mut s = Serials::new();
    for n in [3, 5, 12, 64] {
        let (r, h) = (2.0, 3.0);
        let b = cone(&mut s, r, h, n).unwrap();
        assert_eq!(counts(&b), (n + 1, 2 * n, n + 1));
        assert_solid(&b);
        assert!(b.is_convex(1e-9));
        let exact = n as f64 / 6.0 * r * r * (TAU / n as f64).sin() * h;
        assert!(close(b.volume(), exact, 1e-12), "n = {n}");
        let bounds = b.bounds().unwrap();
        assert_eq!((bounds.min.z, bounds.max.z), (-1.5, 1.5));
    }
    let mut last = f64::INFINITY;
    for n in [8, 16, 32, 64, 128] {
        let b = cone(&mut s, 1.0, 3.0, n).unwrap();
        let err = 1.0 - b.volume() / PI;
        let x = TAU / n as f64;
        assert!(err > 0.0 && err <= x * x / 6.0, "n = {n}: {err}");
        assert!(err < last / 3.5);
        last = err;
    }
}

#[test]
fn sphere_counts_exact_volume_and_convergence() {
    let mut s = Serials::new();
    for (n, rings) in [(3, 2), (4, 2), (8, 3), (12, 6), (32, 16)] {
        let r = 2.0;
        let b = sphere(&mut s, r, n, rings).unwrap();
        // F = n·rings, E = n·(2·rings − 1), V = n·(rings − 1) + 2.
        assert_eq!(
            counts(&b),
            (n * rings, n * (2 * rings - 1), n * (rings - 1) + 2)
        );
        assert_solid(&b);
        assert!(b.is_convex(1e-9));
        for v in b.vertices() {
            assert!((b.position(v).length() - r).abs() < 1e-12);
        }
        let mut profile = vec![DVec2::new(0.0, -r)];
        for j in 1..rings {
            let lat = -PI / 2.0 + PI * j as f64 / rings as f64;
            profile.push(DVec2::new(r * lat.cos(), r * lat.sin()));
        }
        profile.push(DVec2::new(0.0, r));
        let exact = rotation_volume(&profile, n, false);
        assert!(close(b.volume(), exact, 1e-12), "{n}×{rings}");
    }
    // Towards 4/3·π·r³: the relative error shrinks about four times per doubling.
    let mut last = f64::INFINITY;
    for (n, rings) in [(8, 4), (16, 8), (32, 16), (64, 32), (128, 64)] {
        let b = sphere(&mut s, 1.0, n, rings).unwrap();
        let err = 1.0 - b.volume() / (4.0 / 3.0 * PI);
        let bound = 2.0 * (PI / n as f64).powi(2) + 2.0 * (PI / rings as f64).powi(2);
        assert!(err > 0.0 && err < bound, "{n}×{rings}: {err} vs {bound}");
        assert!(err < last / 3.5, "{n}×{rings}: {err} after {last}");
        last = err;
    }
}

#[test]
fn torus_counts_handle_exact_volume_and_convergence() {
    let mut s = Serials::new();
    for (n, rings) in [(3, 3), (8, 4), (24, 12)] {
        let (major, minor) = (3.0, 1.0);
        let b = torus(&mut s, major, minor, n, rings).unwrap();
        assert_eq!(counts(&b), (n * rings, 2 * n * rings, n * rings));
        assert_eq!(b.handles(), 1);
        assert_eq!(b.euler_characteristic(), 0);
        assert_solid(&b);
        assert!(b.faces().all(|f| b.face_degree(f) == 4));
        let profile: Vec<DVec2> = (0..rings)
            .map(|j| {
                let a = TAU * j as f64 / rings as f64;
                DVec2::new(major + minor * a.cos(), minor * a.sin())
            })
            .collect();
        let exact = rotation_volume(&profile, n, true);
        assert!(close(b.volume(), exact, 1e-12), "{n}×{rings}");
        assert!(b.centroid().unwrap().length() < 1e-12);
    }
    // Towards 2·π²·R·r².
    let mut last = f64::INFINITY;
    for (n, rings) in [(8, 8), (16, 16), (32, 32), (64, 64)] {
        let b = torus(&mut s, 2.0, 0.5, n, rings).unwrap();
        let err = 1.0 - b.volume() / (2.0 * PI * PI * 2.0 * 0.25);
        let bound = 2.0 * (PI / n as f64).powi(2) + 2.0 * (PI / rings as f64).powi(2);
        assert!(err > 0.0 && err < bound, "{n}×{rings}: {err} vs {bound}");
        assert!(err < last / 3.5);
        last = err;
    }
}

#[test]
fn rotation_sweep_of_a_vase_profile_either_way_round() {
    let mut s = Serials::new();
    // A vase: flat bottom cap, a bulge, a narrower flat top cap.
    let vase = vec![
        DVec2::new(1.0, 0.0),
        DVec2::new(1.5, 1.0),
        DVec2::new(1.2, 2.0),
        DVec2::new(0.6, 3.0),
    ];
    let n = 10;
    let up = rotation_sweep(&mut s, &vase, n, false).unwrap();
    assert_eq!(counts(&up), (3 * n + 2, 7 * n, 4 * n));
    assert_solid(&up);
    assert!(close(up.volume(), rotation_volume(&vase, n, false), 1e-12));
    let mut down = vase.clone();
    down.reverse();
    let down = rotation_sweep(&mut s, &down, n, false).unwrap();
    assert_solid(&down);
    assert!(close(down.volume(), up.volume(), 1e-12));
    // A closed square profile: a square-section ring.
    let ring = vec![
        DVec2::new(2.0, 0.0),
        DVec2::new(3.0, 0.0),
        DVec2::new(3.0, 1.0),
        DVec2::new(2.0, 1.0),
    ];
    let b = rotation_sweep(&mut s, &ring, 6, true).unwrap();
    assert_eq!(counts(&b), (24, 48, 24));
    assert_eq!(b.handles(), 1);
    assert_solid(&b);
    let k = 6.0 * (TAU / 6.0).sin() / 2.0;
    assert!(close(b.volume(), k * (9.0 - 4.0), 1e-12));
}

#[test]
fn rotation_solids_refuse_bad_parameters_without_taking_serials() {
    let mut s = Serials::new();
    let next = s.peek();
    assert!(matches!(
        cylinder(&mut s, 1.0, 1.0, 2),
        Err(SolidError::TooFew {
            parameter: "segments",
            value: 2,
            min: 3
        })
    ));
    assert!(matches!(
        cylinder(&mut s, 0.0, 1.0, 8),
        Err(SolidError::NotPositive {
            parameter: "radius",
            ..
        })
    ));
    assert!(matches!(
        cylinder(&mut s, 1.0, f64::NAN, 8),
        Err(SolidError::NotFinite {
            parameter: "height"
        })
    ));
    assert!(matches!(
        cone(&mut s, 1.0, -1.0, 8),
        Err(SolidError::NotPositive {
            parameter: "height",
            ..
        })
    ));
    assert!(matches!(
        sphere(&mut s, 1.0, 8, 1),
        Err(SolidError::TooFew {
            parameter: "rings",
            value: 1,
            min: 2
        })
    ));
    assert!(matches!(
        sphere(&mut s, f64::INFINITY, 8, 4),
        Err(SolidError::NotFinite {
            parameter: "radius"
        })
    ));
    assert!(matches!(
        torus(&mut s, 1.0, 1.0, 8, 8),
        Err(SolidError::MinorNotBelowMajor { .. })
    ));
    assert!(matches!(
        torus(&mut s, 2.0, 1.0, 8, 2),
        Err(SolidError::TooFew {
            parameter: "rings",
            ..
        })
    ));
    assert!(matches!(
        torus(&mut s, 2.0, -1.0, 8, 8),
        Err(SolidError::NotPositive {
            parameter: "minor_radius",
            ..
        })
    ));
    // Too many faces: refused before anything is allocated.
    assert!(matches!(
        cylinder(&mut s, 1.0, 1.0, MAX_SWEEP_FACES as usize),
        Err(SolidError::TooManyElements { what: "faces", .. })
    ));
    assert!(matches!(
        sphere(&mut s, 1.0, 1 << 20, 1 << 20),
        Err(SolidError::TooManyElements { what: "faces", .. })
    ));
    assert!(matches!(
        torus(&mut s, 2.0, 1.0, usize::MAX, usize::MAX),
        Err(SolidError::TooManyElements { what: "faces", .. })
    ));
    assert!(matches!(
        sphere(&mut s, 1.0, 3, 5000),
        Err(SolidError::TooManyElements {
            what: "profile points",
            ..
        })
    ));
    // Bad profiles.
    let p = DVec2::new;
    let bad: Vec<(Vec<DVec2>, bool, PolygonFault)> = vec![
        (
            vec![p(1.0, 0.0)],
            false,
            PolygonFault::TooFewPoints { count: 1, min: 2 },
        ),
        (
            vec![p(1.0, 0.0), p(2.0, 1.0)],
            true,
            PolygonFault::TooFewPoints { count: 2, min: 3 },
        ),
        (
            vec![p(1.0, 0.0), p(-1.0, 1.0)],
            false,
            PolygonFault::NegativeRadius { index: 1 },
        ),
        (
            vec![p(1.0, 0.0), p(0.0, 1.0), p(1.0, 2.0)],
            false,
            PolygonFault::OnAxis { index: 1 },
        ),
        (
            vec![p(1.0, 0.0), p(2.0, 0.0), p(2.0, 1.0), p(0.0, 1.0)],
            true,
            PolygonFault::OnAxis { index: 3 },
        ),
        (
            vec![p(0.0, 0.0), p(f64::NAN, 1.0)],
            false,
            PolygonFault::NotFinite { index: 1 },
        ),
        // Both caps at the same height would coincide.
        (
            vec![p(1.0, 0.0), p(2.0, 1.0), p(1.5, 0.0)],
            false,
            PolygonFault::ZeroLengthSegment { index: 3 },
        ),
        // A profile that crosses itself.
        (
            vec![p(1.0, 0.0), p(2.0, 2.0), p(2.0, 0.0), p(1.0, 2.0)],
            false,
            PolygonFault::Crossing { a: 0, b: 2 },
        ),
        // Entirely on the axis.
        (
            vec![p(0.0, 0.0), p(0.0, 1.0)],
            false,
            PolygonFault::TooFewPoints { count: 2, min: 3 },
        ),
    ];
    for (profile, closed, fault) in bad {
        match rotation_sweep(&mut s, &profile, 8, closed) {
            Err(SolidError::Profile(f)) => assert_eq!(f, fault, "{profile:?}"),
            other => panic!("{profile:?}: {other:?}"),
        }
    }
    assert!(matches!(
        rotation_sweep(&mut s, &vec![p(1.0, 0.0); 5000], 3, false),
        Err(SolidError::Profile(PolygonFault::TooManyPoints {
            count: 5000,
            ..
        }))
    ));
    assert_eq!(s.peek(), next);
}

// ------------------------------------------------------------------ random sweeps

/// Each face as the cycle of its vertices' serials, rotated to start at the smallest,
/// keyed by the face's serial.
fn face_cycles(b: &Body) -> Vec<(Serial, Vec<Serial>)> {
    let mut out: Vec<(Serial, Vec<Serial>)> = b
        .faces()
        .map(|f| {
            let mut c: Vec<Serial> = b.face_vertices(f).map(|v| b.vertex_serial(v)).collect();
            let k = (0..c.len()).min_by_key(|&i| c[i]).unwrap();
            c.rotate_left(k);
            (b.face_serial(f), c)
        })
        .collect();
    out.sort();
    out
}

fn loci(b: &Body) -> Vec<(Serial, DVec3)> {
    let mut out: Vec<_> = b
        .vertices()
        .map(|v| (b.vertex_serial(v), b.position(v)))
        .collect();
    out.sort_by_key(|x| x.0);
    out
}

enum Made {
    Peak(VertexId),
    Ring(Serial, Vec<VertexId>),
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]

    /// Random outward sweeps of random faces keep a valid solid whose volume grows, and
    /// undoing them newest first (KLFE, then KLEV) gives the cube back.
    #[test]
    fn random_sweeps_are_valid_and_undo(
        ops in proptest::collection::vec(
            (0u8..4, 0usize..1000, 0.3f64..1.5, 0.1f64..2.0, -0.5f64..0.5),
            1..7,
        )
    ) {
        let mut s = Serials::new();
        let mut b = mkcube(&mut s, 2.0, 2.0, 2.0).unwrap();
        let (cycles, positions) = (face_cycles(&b), loci(&b));
        let mut made = Vec::new();
        for (kind, pick, scale, height, shear) in ops {
            let faces: Vec<FaceId> = b.faces().collect();
            let f = faces[pick % faces.len()];
            let plane = b.face_plane(f).unwrap();
            let tangent = plane.normal.any_orthonormal_vector();
            let offset = plane.normal * height + tangent * shear;
            let volume = b.volume();
            let mark = s.peek();
            let (df, de, dv) = {
                let n = b.face_degree(f);
                match kind {
                    0 => (n, 2 * n, n),
                    1 | 2 => (2 * n, 3 * n, n),
                    _ => (n - 1, n, 1),
                }
            };
            let before = counts(&b);
            made.push(match kind {
                0 => Made::Ring(mark, b.prism(&mut s, f, offset, scale).unwrap().ring),
                1 | 2 => {
                    let twist = if kind == 1 { Twist::Cw } else { Twist::Ccw };
                    Made::Ring(mark, b.prismoid(&mut s, f, offset, scale, twist).unwrap().ring)
                }
                _ => Made::Peak(b.pyramid(&mut s, f, b.face_center(f) + offset).unwrap()),
            });
            proptest::prop_assert_eq!(counts(&b), (before.0 + df, before.1 + de, before.2 + dv));
            let r = check_solid(&b, 1e-9);
            proptest::prop_assert!(r.is_ok(), "{}", r);
            proptest::prop_assert!(b.volume() > volume);
        }
        while let Some(m) = made.pop() {
            match m {
                Made::Peak(peak) => unpyramid(&mut b, peak),
                Made::Ring(mark, ring) => {
                    let mut between: Vec<EdgeId> = b
                        .edges()
                        .filter(|&e| b.edge_serial(e) >= mark)
                        .filter(|&e| ring.iter().all(|&w| b.vertex(w).ped != e))
                        .collect();
                    between.sort_by_key(|&e| std::cmp::Reverse(b.edge_serial(e)));
                    for e in between {
                        b.klfe(e).unwrap();
                    }
                    for w in ring {
                        b.klev(w).unwrap();
                    }
                }
            }
            let r = check_solid(&b, 1e-9);
            proptest::prop_assert!(r.is_ok(), "{}", r);
        }
        proptest::prop_assert_eq!(face_cycles(&b), cycles);
        proptest::prop_assert_eq!(loci(&b), positions);
    }
}
