//! Whether a triangulated surface crosses itself: exact tests on its triangles.
//!
//! Two triangles of one surface may share a vertex or an edge; anything more is a
//! crossing (or a touching, which a closed polyhedron may not have either). Every test
//! is decided by the signs of Shewchuk's adaptive `orient3d`/`orient2d` on the input
//! loci, so no rounding decides it.

use glam::DVec3;
use robust::{Coord, Coord3D, orient2d, orient3d};

use super::broad::Tree;

/// The triangles of a surface with a box hierarchy over them, to find the pairs that
/// cross; the search may be split by ranges of triangles (and run on several threads
/// by the caller).
pub struct Crossings<'a> {
    points: &'a [DVec3],
    triangles: &'a [[u32; 3]],
    boxes: Vec<[DVec3; 2]>,
    tree: Tree,
}

impl<'a> Crossings<'a> {
    /// The hierarchy over `triangles` (indices into `points`).
    ///
    /// Precondition: no triangle repeats a vertex, and the surface is consistently
    /// oriented (two triangles sharing an edge run along it in opposite directions).
    pub fn new(points: &'a [DVec3], triangles: &'a [[u32; 3]]) -> Self {
        let boxes: Vec<[DVec3; 2]> = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| points[i as usize]);
                [a.min(b).min(c), a.max(b).max(c)]
            })
            .collect();
        let tree = Tree::new(&boxes);
        Crossings {
            points,
            triangles,
            boxes,
            tree,
        }
    }

    /// The number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The search split into about `n` independent parts (see [`Crossings::first_in`]).
    pub fn parts(&self, n: usize) -> Vec<(usize, usize)> {
        self.tree.self_pair_parts(n)
    }

    /// The least pair `(i, j)`, `i < j`, of triangles in `part` of the search that meet
    /// in more than the vertices and edges they share, among the pairs `skip` does not
    /// rule out; `None` when there is none. The parts of [`Crossings::parts`] together
    /// cover every pair once.
    pub fn first_in(
        &self,
        part: (usize, usize),
        skip: impl Fn(usize, usize) -> bool,
    ) -> Option<(usize, usize)> {
        let mut out = Vec::new();
        self.tree.self_pairs_in(
            &self.boxes,
            part,
            |i, j| {
                !skip(i as usize, j as usize)
                    && triangles_cross(
                        self.points,
                        self.triangles[i as usize],
                        self.triangles[j as usize],
                    )
            },
            &mut out,
        );
        out.into_iter().min().map(|(i, j)| (i as usize, j as usize))
    }
}

/// The least pair `(i, j)`, `i < j`, of triangles (indices into `points`) that meet in
/// more than the vertices and edges they share; `None` when the surface does not cross
/// itself. Preconditions as [`Crossings::new`]'s.
pub fn first_crossing(points: &[DVec3], triangles: &[[u32; 3]]) -> Option<(usize, usize)> {
    let c = Crossings::new(points, triangles);
    c.parts(1)
        .into_iter()
        .filter_map(|part| c.first_in(part, |_, _| false))
        .min()
}

/// Whether triangles `s` and `t` meet in more than what they share.
///
/// Float filters decide the plain cases (a triangle wholly on one side of the other's
/// plane with room to spare; two triangles on one edge that face the same way; two
/// flat triangles about one vertex whose angles at it are apart); what they cannot
/// decide goes to the exact tests.
fn triangles_cross(points: &[DVec3], s: [u32; 3], t: [u32; 3]) -> bool {
    let p = |i: u32| points[i as usize];
    let mut shared = [0u32; 3];
    let mut n = 0;
    for v in s {
        if t.contains(&v) {
            shared[n] = v;
            n += 1;
        }
    }
    let shared = &shared[..n];
    if n == 0 && (apart(s.map(p), t.map(p)) || apart_in_plane(s.map(p), t.map(p))) {
        return false;
    }
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
            let (ts, tt) = (s.map(p), t.map(p));
            if clear_side(ts, &[b1, b2]) || clear_side(tt, &[a1, a2]) {
                return false;
            }
            if wedges_apart(p(v), (a1, a2), (b1, b2)) {
                return false;
            }
            segment_meets_triangle(a1, a2, t.map(p)) || segment_meets_triangle(b1, b2, s.map(p))
        }
        2 => {
            // Folded onto each other: coplanar, on the same side of the shared edge.
            let other = |x: [u32; 3]| x.iter().copied().find(|w| !shared.contains(w));
            let (Some(a), Some(b)) = (other(s), other(t)) else {
                return false;
            };
            let (e0, e1) = (p(shared[0]), p(shared[1]));
            // Folded, two consistently oriented triangles face opposite ways.
            let (na, nb) = ((e1 - e0).cross(p(a) - e0), (e0 - e1).cross(p(b) - e1));
            if na.dot(nb) > 1e-6 * na.length() * nb.length() {
                return false;
            }
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

/// Whether one triangle lies wholly on one side of the other's plane by more than
/// the rounding of the distances could cover (a float filter: `true` is certain,
/// `false` decides nothing).
fn apart(s: [DVec3; 3], t: [DVec3; 3]) -> bool {
    clear_side(s, &t) || clear_side(t, &s)
}

/// Whether two triangles, seen along the axis their planes are least inclined to, are
/// separated by one of their edges' lines with a clear margin (a float filter: `true`
/// is certain, since triangles apart in a projection are apart in space).
fn apart_in_plane(s: [DVec3; 3], t: [DVec3; 3]) -> bool {
    let axis = dominant_axis((s[1] - s[0]).cross(s[2] - s[0]));
    let flat = |x: DVec3| match axis {
        0 => glam::DVec2::new(x.y, x.z),
        1 => glam::DVec2::new(x.z, x.x),
        _ => glam::DVec2::new(x.x, x.y),
    };
    let (a, b) = (s.map(flat), t.map(flat));
    let scale = a
        .iter()
        .chain(b.iter())
        .map(|q| (*q - a[0]).abs().max_element())
        .fold(0.0, f64::max);
    let margin = 1e-9 * scale * scale;
    let separates = |e0: glam::DVec2, e1: glam::DVec2| {
        let n = (e1 - e0).perp();
        let (mut lo_a, mut hi_a) = (f64::INFINITY, f64::NEG_INFINITY);
        for q in a {
            let d = n.dot(q - e0);
            lo_a = lo_a.min(d);
            hi_a = hi_a.max(d);
        }
        let (mut lo_b, mut hi_b) = (f64::INFINITY, f64::NEG_INFINITY);
        for q in b {
            let d = n.dot(q - e0);
            lo_b = lo_b.min(d);
            hi_b = hi_b.max(d);
        }
        hi_a < lo_b - margin || hi_b < lo_a - margin
    };
    (0..3).any(|k| separates(a[k], a[(k + 1) % 3]) || separates(b[k], b[(k + 1) % 3]))
}

/// Whether every point of `ys` lies strictly on one side of triangle `x`'s plane by
/// more than the rounding of its distance could cover (a float filter).
fn clear_side(x: [DVec3; 3], ys: &[DVec3]) -> bool {
    let n = (x[1] - x[0]).cross(x[2] - x[0]);
    let scale = (x[1] - x[0])
        .abs()
        .max_element()
        .max((x[2] - x[0]).abs().max_element());
    let reach = ys
        .iter()
        .map(|q| (*q - x[0]).abs().max_element())
        .fold(scale, f64::max);
    // n·(q − a) is computed within a few units of roundoff of |e||f||q − a|.
    let bound = 32.0 * f64::EPSILON * scale * scale * reach;
    let mut above = true;
    let mut below = true;
    for q in ys {
        let d = n.dot(*q - x[0]);
        above &= d > bound;
        below &= d < -bound;
    }
    above || below
}

/// Whether two triangles about the common vertex `v`, with far edges `a` and `b`,
/// lie in one plane with their angles at `v` apart by a clear margin (a float filter:
/// `true` is certain, `false` decides nothing).
fn wedges_apart(v: DVec3, a: (DVec3, DVec3), b: (DVec3, DVec3)) -> bool {
    let n = (a.0 - v).cross(a.1 - v);
    let len = n.length();
    if len == 0.0 || n.dot((b.0 - v).cross(b.1 - v)) <= 0.0 {
        return false;
    }
    let n = n / len;
    // Both in the plane (within a margin of their size): else leave it to the exact tests.
    let flat = |q: DVec3| n.dot(q - v).abs() <= 1e-12 * (q - v).length();
    if !(flat(b.0) && flat(b.1)) {
        return false;
    }
    let (u, w) = n.any_orthonormal_pair();
    let angle = |q: DVec3| {
        let d = q - v;
        d.dot(w).atan2(d.dot(u))
    };
    // Each wedge runs counter-clockwise about n from its first far corner to its second.
    let wedge = |e: (DVec3, DVec3)| {
        let from = angle(e.0);
        let mut to = angle(e.1);
        if to < from {
            to += std::f64::consts::TAU;
        }
        (from, to)
    };
    let (a0, a1) = wedge(a);
    let (b0, b1) = wedge(b);
    let margin = 1e-9;
    // Disjoint arcs on the circle, with the margin, in either wrap.
    [-std::f64::consts::TAU, 0.0, std::f64::consts::TAU]
        .iter()
        .all(|&k| b1 + k < a0 - margin || b0 + k > a1 + margin)
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
