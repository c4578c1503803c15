//! The hidden-line drawing against analytic answers and against an independent
//! supersampled depth buffer.
//!
//! The oracle rasterises the scene's triangles at 4 × 4 samples per pixel (perspective-
//! correct depth, its own near clipping) and judges a drawing both ways, every quarter
//! pixel: (1) each drawn point lies within half a pixel, along its segment, of a point
//! the buffer may show (one of the edge's own faces nearby, or nothing nearer), unless a
//! silhouette passes within half a pixel (slivers seen through cracks narrower than a
//! sample); (2) each point of an edge the buffer clearly shows (nothing but its own faces
//! nearer within half a pixel) lies within half a pixel of a drawn piece of that edge.
//! `the_oracle_rejects_wrong_drawings` checks that it notices occlusion left out, pieces
//! left out and pieces cut short.

use std::collections::HashMap;

use glam::{DQuat, DVec2, DVec3};
use winged::camera::{self, Camera, Intrinsics, View};
use winged::model::{Pose, World, solids};
use winged::render::Scene;
use winged::render::hidden::{self, Segment};
use winged::render::sample::{self, SplitMix64};

fn view(eye: DVec3, target: DVec3, w: u32, h: u32, f: f64) -> View {
    let k = Intrinsics::centered(w, h, f).unwrap();
    let cam = Camera::look_at(eye, target, DVec3::Z, k).unwrap();
    View::new(&cam, camera::DEFAULT_NEAR)
}

fn add_box(w: &mut World, centre: DVec3, rotation: DQuat, size: DVec3) {
    let root = w.root();
    let pose = Pose {
        position: centre,
        rotation,
    };
    w.insert_with(None, root, pose, |s| {
        solids::mkcube(s, size.x, size.y, size.z)
    })
    .unwrap();
}

/// The pixel of a world point (independently of the drawing's own clipping).
fn pixel(v: &View, p: DVec3) -> DVec2 {
    v.project(v.to_camera(p))
}

/// Scene edges by (body id, serial).
fn edges_by_key(s: &Scene) -> HashMap<(u64, u64), usize> {
    s.edges
        .iter()
        .enumerate()
        .map(|(i, e)| ((s.bodies[e.body as usize].id.get(), e.serial), i))
        .collect()
}

/// Checks the invariants every drawing keeps: finite ends in the window, depths beyond
/// the near plane, deterministic order, and the same answer twice.
fn check_sane(s: &Scene, v: &View, segs: &[Segment]) {
    let (w, h) = v.size();
    for g in segs {
        for p in [g.a, g.b] {
            assert!(p.is_finite(), "{g:?}");
            assert!(p.x >= -1e-6 && p.x <= w as f64 + 1e-6, "{g:?}");
            assert!(p.y >= -1e-6 && p.y <= h as f64 + 1e-6, "{g:?}");
        }
        for d in g.depth {
            assert!(d >= v.near * (1.0 - 1e-9), "{g:?}");
        }
    }
    for pair in segs.windows(2) {
        assert!(
            (pair[0].body, pair[0].edge) <= (pair[1].body, pair[1].edge),
            "out of order"
        );
    }
    assert_eq!(hidden::hidden_lines(s, v), segs, "not deterministic");
}

#[test]
fn a_cube_in_general_position_shows_nine_whole_edges() {
    let mut w = World::new();
    add_box(&mut w, DVec3::ZERO, DQuat::IDENTITY, DVec3::ONE);
    let s = Scene::build(&w);
    let v = view(
        DVec3::new(3.0, 2.2, 1.7),
        DVec3::new(0.05, -0.02, 0.01),
        640,
        480,
        500.0,
    );
    let segs = hidden::hidden_lines(&s, &v);
    check_sane(&s, &v, &segs);
    assert_eq!(segs.len(), 9, "{segs:#?}");
    let by_key = edges_by_key(&s);
    let mut seen = std::collections::HashSet::new();
    for g in &segs {
        assert!(seen.insert(g.edge), "edge {} twice", g.edge);
        let e = &s.edges[by_key[&(g.body.get(), g.edge)]];
        let [p, q] = e.ends.map(|i| s.points[i as usize]);
        // The hidden corner is (−½, −½, −½): no visible edge touches it.
        let corner = DVec3::splat(-0.5);
        assert!((p - corner).length() > 1e-9 && (q - corner).length() > 1e-9);
        assert!((g.a - pixel(&v, p)).length() < 1e-9, "{g:?}");
        assert!((g.b - pixel(&v, q)).length() < 1e-9, "{g:?}");
        let (dp, dq) = (-v.to_camera(p).z, -v.to_camera(q).z);
        assert!((g.depth[0] - dp).abs() < 1e-12 && (g.depth[1] - dq).abs() < 1e-12);
    }
    // The three edges at the far corner are the ones missing.
    let corner = DVec3::splat(-0.5);
    let hidden_edges = s
        .edges
        .iter()
        .filter(|e| {
            e.ends
                .iter()
                .any(|&i| (s.points[i as usize] - corner).length() < 1e-12)
        })
        .count();
    assert_eq!(hidden_edges, 3);
}

/// 2D convex hull (counter-clockwise in a y-up frame; orientation does not matter here).
fn hull(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut lower: Vec<DVec2> = Vec::new();
    for &p in &pts {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0.0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<DVec2> = Vec::new();
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0.0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// Cyrus–Beck: the parameter range of `p + s·(q − p)`, s ∈ [0, 1], inside the convex
/// polygon `poly` (counter-clockwise in the sense of `perp_dot > 0` inside).
fn inside_range(poly: &[DVec2], p: DVec2, q: DVec2) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    let d = q - p;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let e = b - a;
        // Inside: e.perp_dot(x − a) ≥ 0.
        let f0 = e.perp_dot(p - a);
        let fd = e.perp_dot(d);
        if fd == 0.0 {
            if f0 < 0.0 {
                return None;
            }
        } else {
            let s = -f0 / fd;
            if fd > 0.0 {
                lo = lo.max(s);
            } else {
                hi = hi.min(s);
            }
        }
    }
    (lo < hi).then_some((lo, hi))
}

#[test]
fn a_cube_behind_another_is_cut_at_the_front_cubes_silhouette() {
    let mut w = World::new();
    // The front cube, then a back cube partly behind it; the plane y = 1.5 separates them
    // and the eye is on the front cube's side, so the front cube is nearer along every ray.
    add_box(&mut w, DVec3::ZERO, DQuat::IDENTITY, DVec3::ONE);
    add_box(
        &mut w,
        DVec3::new(0.55, 3.0, 0.23),
        DQuat::from_rotation_z(0.3),
        DVec3::new(1.0, 1.0, 1.2),
    );
    let s = Scene::build(&w);
    let v = view(
        DVec3::new(0.7, -6.0, 2.1),
        DVec3::new(0.3, 1.0, 0.1),
        800,
        600,
        700.0,
    );
    let segs = hidden::hidden_lines(&s, &v);
    check_sane(&s, &v, &segs);
    let eye = v.eye();
    let front_id = s.bodies[0].id;
    // The front cube's projected silhouette, found independently in the image.
    let corners: Vec<DVec2> = s
        .points
        .iter()
        .enumerate()
        .filter(|(i, _)| {
            s.edges
                .iter()
                .any(|e| e.body == 0 && e.ends.contains(&(*i as u32)))
        })
        .map(|(_, &p)| pixel(&v, p))
        .collect();
    let mut sil = hull(corners);
    // Make it counter-clockwise in the perp_dot sense.
    let area: f64 = (0..sil.len())
        .map(|i| sil[i].perp_dot(sil[(i + 1) % sil.len()]))
        .sum();
    if area < 0.0 {
        sil.reverse();
    }
    let mut expected: Vec<(u64, u64, DVec2, DVec2)> = Vec::new();
    let mut cut = 0;
    for e in &s.edges {
        if !s.edge_faces_toward(e, eye) {
            continue;
        }
        let body = s.bodies[e.body as usize].id;
        let [p, q] = e.ends.map(|i| pixel(&v, s.points[i as usize]));
        if body == front_id {
            expected.push((body.get(), e.serial, p, q));
            continue;
        }
        match inside_range(&sil, p, q) {
            None => expected.push((body.get(), e.serial, p, q)),
            Some((s0, s1)) => {
                cut += 1;
                let at = |s: f64| p + (q - p) * s;
                if s0 > 1e-12 {
                    expected.push((body.get(), e.serial, p, at(s0)));
                }
                if s1 < 1.0 - 1e-12 {
                    expected.push((body.get(), e.serial, at(s1), q));
                }
            }
        }
    }
    assert!(cut >= 2, "the scene should cut some back edges, cut {cut}");
    expected.sort_by_key(|x| (x.0, x.1));
    assert_eq!(segs.len(), expected.len(), "{segs:#?}\n{expected:#?}");
    let mut partial = 0;
    for (g, x) in segs.iter().zip(&expected) {
        assert_eq!((g.body.get(), g.edge), (x.0, x.1));
        assert!((g.a - x.2).length() < 1e-6, "{g:?} vs {x:?}");
        assert!((g.b - x.3).length() < 1e-6, "{g:?} vs {x:?}");
        let e = &s.edges[edges_by_key(&s)[&(x.0, x.1)]];
        let whole = (x.2 - pixel(&v, s.points[e.ends[0] as usize])).length() < 1e-9
            && (x.3 - pixel(&v, s.points[e.ends[1] as usize])).length() < 1e-9;
        partial += usize::from(!whole);
    }
    assert!(partial >= 2, "some pieces must end at a cut");
}

#[test]
fn an_l_prism_hides_part_of_itself() {
    let l = winged::render::sample::L_SHAPE;
    let mut w = World::new();
    let root = w.root();
    w.insert_with(None, root, Pose::IDENTITY, |s| {
        solids::prism_solid(s, &l, 1.0)
    })
    .unwrap();
    let s = Scene::build(&w);
    // Seen from +x at mid height: the arm's end face x = 2 (y ∈ [0, 1]) hides the part
    // of the inner face x = 1 (y ∈ [1, 2]) whose rays pass through it. The ray from the
    // eye (5, ½, z) through (1, y, ·) meets x = 2 at y' = ½ + ¾(y − ½), inside the end
    // face while y' < 1: the inner face is hidden for y < 7/6.
    let eye = DVec3::new(5.0, 0.5, 0.2);
    let v = view(eye, DVec3::new(0.0, 1.0, 0.0), 640, 480, 250.0);
    let segs = hidden::hidden_lines(&s, &v);
    check_sane(&s, &v, &segs);
    let by_key = edges_by_key(&s);
    let ends = |g: &Segment| {
        let e = &s.edges[by_key[&(g.body.get(), g.edge)]];
        e.ends.map(|i| s.points[i as usize])
    };
    let at = |x: f64, y: f64, z: f64| pixel(&v, DVec3::new(x, y, z));
    let close = |a: DVec2, b: DVec2| (a - b).length() < 1e-9;
    // 4 edges of the end face, the inner face's far vertical edge, and its top and bottom
    // edges cut at y = 7/6; the reflex vertical edge at (1, 1) is hidden.
    assert_eq!(segs.len(), 7, "{segs:#?}");
    let mut cut = 0;
    for g in &segs {
        let [p, q] = ends(g);
        let is = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(
            !(is(p.x, 1.0) && is(p.y, 1.0) && is(q.x, 1.0) && is(q.y, 1.0)),
            "the reflex edge is hidden"
        );
        let on_inner = is(p.x, 1.0) && is(q.x, 1.0) && is(p.z, q.z);
        if on_inner {
            cut += 1;
            let z = p.z;
            let (near_end, far_end) = (at(1.0, 7.0 / 6.0, z), at(1.0, 2.0, z));
            let fits = (close(g.a, near_end) && close(g.b, far_end))
                || (close(g.b, near_end) && close(g.a, far_end));
            assert!(fits, "{g:?} should run from y = 7/6 to 2");
        } else {
            assert!(
                close(g.a, pixel(&v, p)) && close(g.b, pixel(&v, q)),
                "{g:?}"
            );
        }
    }
    assert_eq!(cut, 2);
}

/// The pieces of the 2D segment `p`–`q` outside every convex polygon of `hulls`.
fn outside_all(hulls: &[Vec<DVec2>], p: DVec2, q: DVec2) -> Vec<(DVec2, DVec2)> {
    let mut cover: Vec<(f64, f64)> = hulls.iter().filter_map(|h| inside_range(h, p, q)).collect();
    cover.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = Vec::new();
    let mut from = 0.0;
    for (s0, s1) in cover {
        if s0 > from + 1e-12 {
            out.push((from, s0));
        }
        from = f64::max(from, s1);
    }
    if from < 1.0 - 1e-12 {
        out.push((from, 1.0));
    }
    let at = |s: f64| p + (q - p) * s;
    out.into_iter().map(|(a, b)| (at(a), at(b))).collect()
}

/// `hull` of some points, counter-clockwise in the `perp_dot` sense.
fn ccw_hull(pts: Vec<DVec2>) -> Vec<DVec2> {
    let mut h = hull(pts);
    let area: f64 = (0..h.len())
        .map(|i| h[i].perp_dot(h[(i + 1) % h.len()]))
        .sum();
    if area < 0.0 {
        h.reverse();
    }
    h
}

#[test]
fn a_concave_plate_hides_a_bar_except_under_its_notch() {
    let mut w = World::new();
    let root = w.root();
    // An L-shaped plate, z ∈ [0.9, 1.1], its notch over x, y ∈ (0, 1); below it a bar
    // along x that passes under one arm, the notch and out beyond the plate.
    let plate = Pose::from_translation(DVec3::new(0.0, 0.0, 1.0));
    w.insert_with(None, root, plate, |s| {
        solids::prism_solid(s, &l_shape(1.0), 0.2)
    })
    .unwrap();
    add_box(
        &mut w,
        DVec3::new(0.0, 0.5, 0.0),
        DQuat::IDENTITY,
        DVec3::new(3.0, 0.2, 0.2),
    );
    let s = Scene::build(&w);
    let k = Intrinsics::centered(800, 600, 450.0).unwrap();
    let cam = Camera::look_at(
        DVec3::new(0.23, 0.17, 6.0),
        DVec3::new(0.1, 0.05, 0.0),
        DVec3::Y,
        k,
    )
    .unwrap();
    let v = View::new(&cam, camera::DEFAULT_NEAR);
    let segs = hidden::hidden_lines(&s, &v);
    check_sane(&s, &v, &segs);
    let eye = v.eye();
    // The plate's projection: the union of its two arms' (convex) projections.
    let arm = |x0: f64, x1: f64, y0: f64, y1: f64| {
        let mut pts = Vec::new();
        for x in [x0, x1] {
            for y in [y0, y1] {
                for z in [0.9, 1.1] {
                    pts.push(pixel(&v, DVec3::new(x, y, z)));
                }
            }
        }
        ccw_hull(pts)
    };
    let arms = [arm(-1.0, 1.0, -1.0, 0.0), arm(-1.0, 0.0, 0.0, 1.0)];
    let plate_id = s.bodies[0].id;
    // The top cap is concave and faces the eye: the general (not convex) path runs.
    assert!(
        s.faces
            .iter()
            .any(|f| f.body == 0 && f.faces_toward(eye) && s.ring(f).len() == 6)
    );
    let mut expected = Vec::new();
    for e in &s.edges {
        if !s.edge_faces_toward(e, eye) {
            continue;
        }
        let body = s.bodies[e.body as usize].id;
        let [p, q] = e.ends.map(|i| pixel(&v, s.points[i as usize]));
        let pieces = if body == plate_id {
            vec![(p, q)]
        } else {
            outside_all(&arms, p, q)
        };
        expected.extend(
            pieces
                .into_iter()
                .map(|(a, b)| (body.get(), e.serial, a, b)),
        );
    }
    expected.sort_by_key(|x| (x.0, x.1));
    assert_eq!(segs.len(), expected.len(), "{segs:#?}\n{expected:#?}");
    for (g, x) in segs.iter().zip(&expected) {
        assert_eq!((g.body.get(), g.edge), (x.0, x.1));
        assert!((g.a - x.2).length() < 1e-6, "{g:?} vs {x:?}");
        assert!((g.b - x.3).length() < 1e-6, "{g:?} vs {x:?}");
    }
    // The bar's three long edges show two pieces each (before the plate, and from the
    // notch on), its four short edges one each.
    let bar_pieces = segs.iter().filter(|g| g.body != plate_id).count();
    assert_eq!(bar_pieces, 10, "{segs:#?}");
}

#[test]
fn degenerate_cameras_give_sane_drawings() {
    let mut w = World::new();
    add_box(&mut w, DVec3::ZERO, DQuat::IDENTITY, DVec3::splat(2.0));
    add_box(
        &mut w,
        DVec3::new(6.0, 0.5, 0.0),
        DQuat::from_rotation_z(0.4),
        DVec3::ONE,
    );
    let s = Scene::build(&w);
    let big = s.bodies[0].id;

    // Inside the big box, looking at the small one: the big box's faces all turn away.
    let v = view(
        DVec3::new(0.1, 0.2, 0.3),
        DVec3::new(6.0, 0.5, 0.0),
        320,
        240,
        200.0,
    );
    let segs = hidden::hidden_lines(&s, &v);
    check_sane(&s, &v, &segs);
    assert!(segs.iter().all(|g| g.body != big));
    assert!(!segs.is_empty());

    // Everything behind the camera.
    let v = view(
        DVec3::new(10.0, 0.0, 0.0),
        DVec3::new(20.0, 0.0, 0.0),
        320,
        240,
        200.0,
    );
    assert!(hidden::hidden_lines(&s, &v).is_empty());

    // A one-pixel image.
    let v = view(DVec3::new(5.0, -4.0, 3.0), DVec3::ZERO, 1, 1, 1.0);
    let segs = hidden::hidden_lines(&s, &v);
    check_sane(&s, &v, &segs);
    let img = hidden::draw(&segs, 1, 1, [255; 3], [0; 3]);
    assert_eq!(img.data.len(), 3);

    // The near plane cuts through the big box: its front face is clipped away there and
    // hides only what lies behind the part beyond the near plane.
    let v = view(
        DVec3::new(-1.005, 0.0, 0.0),
        DVec3::new(0.0, 0.3, 0.2),
        320,
        240,
        200.0,
    );
    let segs = hidden::hidden_lines(&s, &v);
    check_sane(&s, &v, &segs);

    // An empty world.
    let empty = Scene::build(&World::new());
    assert!(hidden::hidden_lines(&empty, &v).is_empty());
}

// ---------------------------------------------------------------------------------------
// The oracle: an independent supersampled depth buffer.

/// Subsamples per pixel side.
const SS: usize = 4;

/// The depth buffer extends this many pixels beyond each side of the window, so points
/// on the window's border have whole neighbourhoods.
const MARGIN: usize = 1;

/// A depth buffer at SS× resolution over the window widened by [`MARGIN`]: depth (−ZCC,
/// +∞ where nothing) and face index.
struct ZBuffer {
    w: usize,
    h: usize,
    depth: Vec<f64>,
    face: Vec<u32>,
}

/// Clips a polygon (camera coordinates) to z ≤ −near (Sutherland–Hodgman).
fn clip_near(poly: &[DVec3], near: f64) -> Vec<DVec3> {
    let mut out = Vec::new();
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (ia, ib) = (a.z <= -near, b.z <= -near);
        if ia {
            out.push(a);
        }
        if ia != ib {
            let t = (-near - a.z) / (b.z - a.z);
            out.push(a + (b - a) * t);
        }
    }
    out
}

fn zbuffer(s: &Scene, v: &View) -> ZBuffer {
    let (w, h) = v.size();
    let (w, h) = (
        (w as usize + 2 * MARGIN) * SS,
        (h as usize + 2 * MARGIN) * SS,
    );
    let mut z = ZBuffer {
        w,
        h,
        depth: vec![f64::INFINITY; w * h],
        face: vec![u32::MAX; w * h],
    };
    let k = &v.intrinsics;
    let proj = |c: DVec3| {
        let d = -c.z;
        (DVec2::new(k.cx + k.fx * c.x / d, k.cy - k.fy * c.y / d) + MARGIN as f64) * SS as f64
    };
    for (t, &f) in s.triangles.iter().zip(&s.triangle_faces) {
        let tri = t.map(|i| v.to_camera(s.points[i as usize]));
        let poly = clip_near(&tri, v.near);
        for i in 1..poly.len().saturating_sub(1) {
            let c = [poly[0], poly[i], poly[i + 1]];
            let p = c.map(proj);
            let d = c.map(|c| -c.z);
            let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
            if area == 0.0 || !area.is_finite() {
                continue;
            }
            let x0 = p.iter().map(|q| q.x).fold(f64::INFINITY, f64::min).max(0.0) as usize;
            let y0 = p.iter().map(|q| q.y).fold(f64::INFINITY, f64::min).max(0.0) as usize;
            let x1 = (p
                .iter()
                .map(|q| q.x)
                .fold(f64::NEG_INFINITY, f64::max)
                .ceil())
            .min(w as f64)
            .max(0.0) as usize;
            let y1 = (p
                .iter()
                .map(|q| q.y)
                .fold(f64::NEG_INFINITY, f64::max)
                .ceil())
            .min(h as f64)
            .max(0.0) as usize;
            for y in y0..y1 {
                for x in x0..x1 {
                    let q = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    let l0 = (p[2] - p[1]).perp_dot(q - p[1]) / area;
                    let l1 = (p[0] - p[2]).perp_dot(q - p[2]) / area;
                    let l2 = 1.0 - l0 - l1;
                    if l0 < 0.0 || l1 < 0.0 || l2 < 0.0 {
                        continue;
                    }
                    let depth = 1.0 / (l0 / d[0] + l1 / d[1] + l2 / d[2]);
                    let i = y * w + x;
                    if depth < z.depth[i] {
                        z.depth[i] = depth;
                        z.face[i] = f;
                    }
                }
            }
        }
    }
    z
}

/// Neighbourhood radius, pixels.
const RADIUS: f64 = 0.5;
/// Relative depth tolerance.
const DEPTH_TOL: f64 = 1e-6;

impl ZBuffer {
    /// The subsamples whose centres lie within [`RADIUS`] of pixel point `p`.
    fn around(&self, p: DVec2) -> impl Iterator<Item = usize> + '_ {
        let c = (p + MARGIN as f64) * SS as f64;
        let r = RADIUS * SS as f64;
        let x0 = (c.x - r).floor().max(0.0) as usize;
        let y0 = (c.y - r).floor().max(0.0) as usize;
        let x1 = ((c.x + r).ceil().max(0.0) as usize).min(self.w);
        let y1 = ((c.y + r).ceil().max(0.0) as usize).min(self.h);
        (y0..y1).flat_map(move |y| {
            (x0..x1).filter_map(move |x| {
                let q = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                ((q - c).length_squared() <= r * r).then_some(y * self.w + x)
            })
        })
    }

    /// Whether a point at pixel `p` and depth `d` on an edge of faces `own` can be seen:
    /// near it the buffer shows one of its own faces, or something not nearer than it.
    fn maybe_visible(&self, p: DVec2, d: f64, own: [u32; 2]) -> bool {
        self.around(p)
            .any(|i| own.contains(&self.face[i]) || self.depth[i] >= d * (1.0 - DEPTH_TOL))
    }

    /// Whether a silhouette passes near pixel `p`: the buffer shows more than one body
    /// (or a body and the background) within [`RADIUS`]. Slivers of an edge seen through
    /// a crack between two occluders narrower than a subsample lie at such places.
    fn near_silhouette(&self, s: &Scene, p: DVec2) -> bool {
        let body = |i: usize| s.faces.get(self.face[i] as usize).map(|f| f.body);
        let mut around = self.around(p);
        let Some(first) = around.next() else {
            return false;
        };
        let b = body(first);
        around.any(|i| body(i) != b)
    }

    /// Whether it is clearly visible: nothing but its own faces is nearer anywhere near it.
    fn clearly_visible(&self, p: DVec2, d: f64, own: [u32; 2]) -> bool {
        self.around(p)
            .all(|i| own.contains(&self.face[i]) || self.depth[i] >= d * (1.0 - DEPTH_TOL))
    }
}

/// Distance from `p` to the segment `a`–`b`.
fn distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let t = if d.length_squared() > 0.0 {
        ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + d * t)).length()
}

/// What the oracle finds wrong with a drawing: points drawn where the buffer shows
/// something nearer all around, and clearly visible points of edges left undrawn.
#[derive(Debug, Default)]
struct Verdict {
    drawn_hidden: usize,
    missed_visible: usize,
    drawn_samples: usize,
    visible_samples: usize,
    first: Vec<String>,
}

fn judge(s: &Scene, v: &View, segs: &[Segment]) -> Verdict {
    let z = zbuffer(s, v);
    let by_key = edges_by_key(s);
    let mut verdict = Verdict::default();
    let note = |verdict: &mut Verdict, what: String| {
        if verdict.first.len() < 5 {
            verdict.first.push(what);
        }
    };
    // (1) Every drawn point, every quarter pixel, is within RADIUS (along its segment) of
    // a point that may be visible: the drawing is within RADIUS of the oracle's.
    let mut drawn: HashMap<(u64, u64), Vec<&Segment>> = HashMap::new();
    for g in segs {
        let own = s.edges[by_key[&(g.body.get(), g.edge)]].faces;
        drawn.entry((g.body.get(), g.edge)).or_default().push(g);
        let len = (g.b - g.a).length();
        let n = (len / 0.25).ceil().max(1.0) as usize;
        let reach = (RADIUS / (len / n as f64)).floor() as usize;
        let ok: Vec<bool> = (0..=n)
            .map(|k| {
                let u = k as f64 / n as f64;
                // 1/depth is linear in the image along a 3D segment.
                let d = 1.0 / ((1.0 - u) / g.depth[0] + u / g.depth[1]);
                z.maybe_visible(g.a.lerp(g.b, u), d, own)
            })
            .collect();
        for k in 0..=n {
            verdict.drawn_samples += 1;
            let p = g.a.lerp(g.b, k as f64 / n as f64);
            if !ok[k.saturating_sub(reach)..=(k + reach).min(n)].contains(&true)
                && !z.near_silhouette(s, p)
            {
                verdict.drawn_hidden += 1;
                note(&mut verdict, format!("drawn but hidden: {g:?} at {p}"));
            }
        }
    }
    // (2) Every clearly visible point of every edge, every quarter pixel, is drawn.
    let (w, h) = v.size();
    let eye = v.eye();
    let folds: std::collections::HashSet<(u64, u64)> = s
        .edges
        .iter()
        .filter(|e| {
            e.faces.iter().any(|&f| {
                let f = &s.faces[f as usize];
                let p = s.points[s.rings[f.ring.start as usize] as usize];
                f.normal.dot(eye - p) > 0.0
            })
        })
        .map(|e| (s.bodies[e.body as usize].id.get(), e.serial))
        .collect();
    for e in &s.edges {
        let key = (s.bodies[e.body as usize].id.get(), e.serial);
        let [a, b] = e.ends.map(|i| v.to_camera(s.points[i as usize]));
        // Keep the part beyond the near plane.
        let lim = -v.near;
        if a.z > lim && b.z > lim {
            continue;
        }
        let cut = |a: DVec3, b: DVec3| {
            if a.z > lim {
                a + (b - a) * ((lim - a.z) / (b.z - a.z))
            } else {
                a
            }
        };
        let (a, b) = (cut(a, b), cut(b, a));
        let (pa, pb) = (v.project(a), v.project(b));
        let n = (((pb - pa).length() / 0.25).ceil() as usize).clamp(1, 1 << 20);
        for k in 0..=n {
            let u = k as f64 / n as f64;
            let p = pa.lerp(pb, u);
            if p.x < 0.0 || p.y < 0.0 || p.x > w as f64 || p.y > h as f64 {
                continue;
            }
            let d = 1.0 / ((1.0 - u) / -a.z + u / -b.z);
            if !z.clearly_visible(p, d, e.faces) {
                continue;
            }
            verdict.visible_samples += 1;
            let close = |g: &&Segment| distance(p, g.a, g.b) <= RADIUS + 1e-9;
            // An edge with a front face must be drawn there itself; an edge whose faces
            // both turn away is seen only at its ends, silhouette vertices that edges
            // of the same body draw.
            let near = if folds.contains(&key) {
                drawn.get(&key).is_some_and(|gs| gs.iter().any(close))
            } else {
                drawn
                    .iter()
                    .filter(|(k, _)| k.0 == key.0)
                    .any(|(_, gs)| gs.iter().any(close))
            };
            if !near {
                verdict.missed_visible += 1;
                note(
                    &mut verdict,
                    format!(
                        "visible but not drawn: edge {key:?} at {p}, drawn {:?}",
                        drawn.get(&key)
                    ),
                );
            }
        }
    }
    verdict
}

/// The L-shaped hexagon of [`an_l_prism_hides_part_of_itself`], scaled by `s` and
/// centred on the origin (its corners lie within `s·√2` of it).
fn l_shape(s: f64) -> Vec<DVec2> {
    winged::render::sample::L_SHAPE
        .iter()
        .map(|&p| (p - DVec2::ONE) * s)
        .collect()
}

/// A world of `n` solids of random sizes and orientations that do not overlap (their
/// bounding spheres are apart) in a cube of side 8 about the origin: boxes, and one in
/// three a concave L-prism. Also the solids' centres and bounding radii.
fn random_solids(n: usize, seed: u64) -> (World, Vec<(DVec3, f64)>) {
    let mut rng = SplitMix64::new(seed);
    let mut w = World::new();
    let mut placed: Vec<(DVec3, f64)> = Vec::new();
    let mut tries = 0;
    while placed.len() < n && tries < 10_000 {
        tries += 1;
        let size = DVec3::new(
            rng.range(0.3, 1.6),
            rng.range(0.3, 1.6),
            rng.range(0.3, 1.6),
        );
        let prism = rng.next_u64().is_multiple_of(3);
        let r = if prism {
            (2.0 * (size.x / 2.0).powi(2) + (size.z / 2.0).powi(2)).sqrt()
        } else {
            size.length() / 2.0
        };
        let c = DVec3::new(
            rng.range(-4.0, 4.0),
            rng.range(-4.0, 4.0),
            rng.range(-4.0, 4.0),
        );
        if placed.iter().any(|&(o, ro)| (o - c).length() < r + ro) {
            continue;
        }
        let axis = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize_or(DVec3::Z);
        let rot = DQuat::from_axis_angle(axis, rng.range(0.0, std::f64::consts::TAU));
        if prism {
            let root = w.root();
            let pose = Pose {
                position: c,
                rotation: rot,
            };
            let l = l_shape(size.x / 2.0);
            w.insert_with(None, root, pose, |s| solids::prism_solid(s, &l, size.z))
                .unwrap();
        } else {
            add_box(&mut w, c, rot, size);
        }
        placed.push((c, r));
    }
    (w, placed)
}

/// Random cameras of `w × h` pixels looking into the middle of a world, their eyes
/// outside every bounding sphere in `keep_out`; some close enough for the near plane and
/// the window to cut edges.
fn random_views(
    rng: &mut SplitMix64,
    count: usize,
    keep_out: &[(DVec3, f64)],
    w: u32,
    h: u32,
) -> Vec<View> {
    let mut out = Vec::new();
    while out.len() < count {
        let dir = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        if dir.length() < 0.2 || dir.length() > 1.0 {
            continue;
        }
        let eye = dir.normalize() * rng.range(3.0, 14.0);
        if keep_out.iter().any(|&(c, r)| (c - eye).length() < r + 0.1) {
            continue;
        }
        let target = DVec3::new(
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
        );
        let k = Intrinsics::centered(w, h, rng.range(0.5, 1.2) * w as f64).unwrap();
        let Ok(cam) = Camera::look_at(eye, target, DVec3::Z, k) else {
            continue;
        };
        out.push(View::new(&cam, camera::DEFAULT_NEAR));
    }
    out
}

fn assert_agrees(s: &Scene, v: &View, what: &str) -> Verdict {
    let segs = hidden::hidden_lines(s, v);
    check_sane(s, v, &segs);
    let verdict = judge(s, v, &segs);
    assert!(
        verdict.drawn_hidden == 0 && verdict.missed_visible == 0,
        "{what}: {verdict:#?}"
    );
    assert!(verdict.visible_samples > 0, "{what}: nothing visible");
    verdict
}

/// Four worlds by default; `ORACLE_SEEDS=200 cargo test --test hidden_lines` tries more.
#[test]
fn random_solids_agree_with_a_supersampled_depth_buffer() {
    let seeds: u64 = std::env::var("ORACLE_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(4);
    let mut checked = 0;
    for seed in 1..=seeds {
        let (w, keep_out) = random_solids(40, seed);
        let s = Scene::build(&w);
        let mut rng = SplitMix64::new(seed ^ 0xabcdef);
        for (i, v) in random_views(&mut rng, 3, &keep_out, 240, 180)
            .iter()
            .enumerate()
        {
            let verdict = assert_agrees(&s, v, &format!("seed {seed} camera {i}"));
            checked += verdict.drawn_samples;
        }
    }
    assert!(checked > 10_000, "too few samples: {checked}");
}

#[test]
fn block_worlds_agree_with_a_supersampled_depth_buffer() {
    for (count, seed) in [(12usize, 3u64), (30, 5)] {
        let w = sample::blocks(count, seed).unwrap();
        let s = Scene::build(&w);
        for (i, cam) in sample::ring_cameras(count, 5, 240, 180)
            .iter()
            .enumerate()
            .step_by(2)
        {
            let v = View::new(cam, camera::DEFAULT_NEAR);
            assert_agrees(&s, &v, &format!("blocks {count}/{seed} camera {i}"));
        }
    }
}

/// Boxes that touch: towers of unit cubes on a grid, each cube on the one below and
/// against its neighbours, so faces meet in a plane, edges coincide and corners meet.
#[test]
fn touching_boxes_agree_with_a_supersampled_depth_buffer() {
    let mut w = World::new();
    let mut keep_out = Vec::new();
    let mut rng = SplitMix64::new(17);
    for i in 0..4 {
        for j in 0..4 {
            let height = 1 + rng.next_u64() % 3;
            for k in 0..height {
                let c = DVec3::new(i as f64 - 1.5, j as f64 - 1.5, k as f64 + 0.5);
                add_box(&mut w, c, DQuat::IDENTITY, DVec3::ONE);
                keep_out.push((c, 0.9));
            }
        }
    }
    let s = Scene::build(&w);
    for (i, v) in random_views(&mut rng, 6, &keep_out, 240, 180)
        .iter()
        .enumerate()
    {
        assert_agrees(&s, v, &format!("touching boxes camera {i}"));
    }
}

#[test]
fn the_oracle_rejects_wrong_drawings() {
    let (w, keep_out) = random_solids(40, 11);
    let s = Scene::build(&w);
    let mut rng = SplitMix64::new(99);
    let v = random_views(&mut rng, 1, &keep_out, 240, 180)[0];
    let eye = v.eye();
    // Without occlusion: every fold, clipped to the window.
    let mut all = Vec::new();
    for e in &s.edges {
        if !s.edge_faces_toward(e, eye) {
            continue;
        }
        let [a, b] = e.ends.map(|i| v.to_camera(s.points[i as usize]));
        if let Some((t0, t1)) = v.clip_segment(a, b) {
            let (p, q) = (a.lerp(b, t0), a.lerp(b, t1));
            all.push(Segment {
                body: s.bodies[e.body as usize].id,
                edge: e.serial,
                a: v.project(p),
                b: v.project(q),
                depth: [-p.z, -q.z],
            });
        }
    }
    let verdict = judge(&s, &v, &all);
    assert!(verdict.drawn_hidden > 100, "{verdict:#?}");
    assert_eq!(verdict.missed_visible, 0, "{verdict:#?}");
    // Missing pieces: the true drawing with every third segment left out.
    let segs = hidden::hidden_lines(&s, &v);
    let fewer: Vec<Segment> = segs
        .iter()
        .enumerate()
        .filter(|(i, _)| i % 3 != 0)
        .map(|(_, g)| *g)
        .collect();
    let verdict = judge(&s, &v, &fewer);
    assert_eq!(verdict.drawn_hidden, 0, "{verdict:#?}");
    assert!(verdict.missed_visible > 100, "{verdict:#?}");
    // Pieces shortened by a pixel at each end are caught too.
    let short: Vec<Segment> = segs
        .iter()
        .filter_map(|g| {
            let len = (g.b - g.a).length();
            (len > 4.0).then(|| {
                let d = (g.b - g.a) / len;
                Segment {
                    a: g.a + d,
                    b: g.b - d,
                    ..*g
                }
            })
        })
        .collect();
    let verdict = judge(&s, &v, &short);
    assert!(verdict.missed_visible > 0, "{verdict:#?}");
}
