//! Whether a triangulated surface crosses itself: exact tests on its triangles.
//!
//! Two triangles of one surface may share a vertex or an edge; anything more is a
//! crossing (or a touching, which a closed polyhedron may not have either). Every test
//! is decided by the signs of Shewchuk's adaptive `orient3d`/`orient2d` on the input
//! loci, so no rounding decides it.

use glam::DVec3;
use robust::{Coord, Coord3D, orient2d, orient3d};

use super::broad::Tree;

/// The first pair `(i, j)`, `i < j`, of triangles (indices into `points`) that meet in
/// more than the vertices and edges they share, in an order fixed by the input; `None`
/// when the surface does not cross itself.
///
/// Precondition: no triangle repeats a vertex. Triangles sharing all three vertices are
/// not compared (a surface that lists one twice is refused as non-manifold elsewhere).
pub fn first_crossing(points: &[DVec3], triangles: &[[u32; 3]]) -> Option<(usize, usize)> {
    let boxes: Vec<[DVec3; 2]> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| points[i as usize]);
            [a.min(b).min(c), a.max(b).max(c)]
        })
        .collect();
    let tree = Tree::new(&boxes);
    let mut out = Vec::new();
    let mut found = false;
    tree.self_pairs(
        &boxes,
        |i, j| {
            if found {
                return false;
            }
            let hit = triangles_cross(points, triangles[i as usize], triangles[j as usize]);
            found |= hit;
            hit
        },
        &mut out,
    );
    out.into_iter().min().map(|(i, j)| (i as usize, j as usize))
}

/// Whether triangles `s` and `t` meet in more than what they share.
fn triangles_cross(points: &[DVec3], s: [u32; 3], t: [u32; 3]) -> bool {
    let p = |i: u32| points[i as usize];
    let shared: Vec<u32> = s.iter().copied().filter(|v| t.contains(v)).collect();
    match shared.len() {
        0 => {
            let (a, b) = (s.map(p), t.map(p));
            (0..3).any(|k| segment_meets_triangle(a[k], a[(k + 1) % 3], b))
                || (0..3).any(|k| segment_meets_triangle(b[k], b[(k + 1) % 3], a))
        }
        1 => {
            // Beyond the shared vertex, one triangle's opposite edge meets the other.
            let v = shared[0];
            let opposite = |x: [u32; 3]| {
                let k = x.iter().position(|&w| w == v).unwrap_or(0);
                (p(x[(k + 1) % 3]), p(x[(k + 2) % 3]))
            };
            let (a1, a2) = opposite(s);
            let (b1, b2) = opposite(t);
            segment_meets_triangle(a1, a2, t.map(p)) || segment_meets_triangle(b1, b2, s.map(p))
        }
        2 => {
            // Folded onto each other: coplanar, on the same side of the shared edge.
            let other = |x: [u32; 3]| x.iter().copied().find(|w| !shared.contains(w));
            let (Some(a), Some(b)) = (other(s), other(t)) else {
                return false;
            };
            let (e0, e1) = (p(shared[0]), p(shared[1]));
            if orient3d(c3(e0), c3(e1), c3(p(a)), c3(p(b))) != 0.0 {
                return false;
            }
            let axis = dominant_axis((e1 - e0).cross(p(a) - e0));
            let side = |x: DVec3| orient2d(c2(e0, axis), c2(e1, axis), c2(x, axis));
            let (sa, sb) = (side(p(a)), side(p(b)));
            (sa > 0.0 && sb > 0.0) || (sa < 0.0 && sb < 0.0)
        }
        _ => false,
    }
}

/// Whether the closed segment `a`–`b` meets the closed triangle `t`.
fn segment_meets_triangle(a: DVec3, b: DVec3, t: [DVec3; 3]) -> bool {
    let [t0, t1, t2] = t.map(c3);
    let oa = orient3d(t0, t1, t2, c3(a));
    let ob = orient3d(t0, t1, t2, c3(b));
    if (oa > 0.0 && ob > 0.0) || (oa < 0.0 && ob < 0.0) {
        return false;
    }
    if oa == 0.0 && ob == 0.0 {
        return coplanar_segment_meets_triangle(a, b, t);
    }
    // The line through a and b pierces the plane within the segment: it meets the
    // triangle where it passes on the same side of (or on) each of the triangle's edges.
    let (ca, cb) = (c3(a), c3(b));
    let s0 = orient3d(ca, cb, t0, t1);
    let s1 = orient3d(ca, cb, t1, t2);
    let s2 = orient3d(ca, cb, t2, t0);
    (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0)
}

/// [`segment_meets_triangle`] when all five points lie in one plane.
fn coplanar_segment_meets_triangle(a: DVec3, b: DVec3, t: [DVec3; 3]) -> bool {
    let axis = dominant_axis((t[1] - t[0]).cross(t[2] - t[0]));
    let q = t.map(|x| c2(x, axis));
    let (pa, pb) = (c2(a, axis), c2(b, axis));
    if inside(pa, q) || inside(pb, q) {
        return true;
    }
    (0..3).any(|k| segments_meet(pa, pb, q[k], q[(k + 1) % 3]))
}

/// Whether `p` lies in the closed triangle `q` (either winding).
fn inside(p: Coord<f64>, q: [Coord<f64>; 3]) -> bool {
    let s0 = orient2d(q[0], q[1], p);
    let s1 = orient2d(q[1], q[2], p);
    let s2 = orient2d(q[2], q[0], p);
    (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0)
}

/// Whether the closed segments `a`–`b` and `c`–`d` meet.
fn segments_meet(a: Coord<f64>, b: Coord<f64>, c: Coord<f64>, d: Coord<f64>) -> bool {
    let (d1, d2) = (orient2d(a, b, c), orient2d(a, b, d));
    let (d3, d4) = (orient2d(c, d, a), orient2d(c, d, b));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |p: Coord<f64>, q: Coord<f64>, r: Coord<f64>| {
        p.x.min(q.x) <= r.x && r.x <= p.x.max(q.x) && p.y.min(q.y) <= r.y && r.y <= p.y.max(q.y)
    };
    (d1 == 0.0 && on(a, b, c))
        || (d2 == 0.0 && on(a, b, d))
        || (d3 == 0.0 && on(c, d, a))
        || (d4 == 0.0 && on(c, d, b))
}

/// The axis along which `n` is largest: dropping it projects a plane of normal `n`
/// without folding it.
fn dominant_axis(n: DVec3) -> usize {
    let a = n.abs();
    if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    }
}

fn c3(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

fn c2(p: DVec3, drop: usize) -> Coord<f64> {
    match drop {
        0 => Coord { x: p.y, y: p.z },
        1 => Coord { x: p.z, y: p.x },
        _ => Coord { x: p.x, y: p.y },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        (p, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    }

    #[test]
    fn a_closed_tetrahedron_does_not_cross_itself() {
        let (p, t) = tetra();
        assert_eq!(first_crossing(&p, &t), None);
    }

    #[test]
    fn a_pierced_triangle_and_a_folded_pair_are_crossings() {
        let (mut p, mut t) = tetra();
        // A triangle through the tetrahedron, sharing nothing with it.
        p.extend([
            DVec3::new(0.2, 0.2, -1.0),
            DVec3::new(0.2, 0.2, 2.0),
            DVec3::new(-1.0, 0.2, 0.5),
        ]);
        t.push([4, 5, 6]);
        assert!(first_crossing(&p, &t).is_some());
        // Two triangles on one edge: flat and apart, then folded onto each other.
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(0.5, -0.5, 0.0)];
        assert_eq!(first_crossing(&p, &[[0, 1, 2], [1, 0, 3]]), None);
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(0.2, 0.2, 0.0)];
        assert_eq!(first_crossing(&p, &[[0, 1, 2], [1, 0, 3]]), Some((0, 1)));
    }

    #[test]
    fn triangles_sharing_a_vertex_cross_only_beyond_it() {
        // A fan about the origin touches only there.
        let p = vec![
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(0.0, -1.0, 0.0),
        ];
        assert_eq!(first_crossing(&p, &[[0, 1, 2], [0, 3, 4]]), None);
        // A triangle from the same vertex through the other's interior.
        let p = vec![
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(1.0, 0.5, -1.0),
            DVec3::new(0.5, 1.0, 1.0),
        ];
        assert_eq!(first_crossing(&p, &[[0, 1, 2], [0, 3, 4]]), Some((0, 1)));
    }
}
