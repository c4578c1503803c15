//! Where the two surfaces meet: triangle against triangle, exactly.
//!
//! For two triangles in general position the meeting is a segment on the line where
//! their planes cross; its ends are where an edge of one pierces the other. Every
//! decision uses the signs of exact predicates on the input points, and every end is
//! named by a [`Key`]: the smallest element of each surface that holds it (a vertex, an
//! edge, or a triangle's interior). Two triangle pairs that reach the same point reach
//! the same key, so the point is made once and the traces join without tolerances.
//! Coplanar triangles (shared faces, A op A) meet in a polygon, whose boundary is traced.

use super::Map;

use super::exact::{Poly, Ring};
use super::mesh::Mesh;
use super::point::{Def, Pid, Points};
use super::split::coord_cmp;

/// An edge of either mesh, by its two points (smaller first).
pub(crate) type EdgeKey = [Pid; 2];

/// The sorted pair.
#[inline]
pub(crate) fn edge_key(p: Pid, q: Pid) -> EdgeKey {
    if p < q { [p, q] } else { [q, p] }
}

/// The smallest element of one surface holding a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Elem {
    Vertex(Pid),
    Edge(EdgeKey),
    Tri(u32),
}

/// A point of both surfaces, named by the elements holding it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Key {
    Vertex(Pid),
    EdgeEdge(EdgeKey, EdgeKey),
    EdgeTri(EdgeKey, u32),
    TriEdge(u32, EdgeKey),
}

/// Everything the two surfaces share, traced on each triangle.
#[derive(Debug, Default)]
pub(crate) struct Traces {
    keys: Map<Key, Pid>,
    /// Points of both surfaces on each edge (of either mesh), not its ends.
    pub on_edge: Map<EdgeKey, Vec<Pid>>,
    /// Segments on both surfaces, per triangle of A.
    pub segs_a: Map<u32, Vec<[Pid; 2]>>,
    /// Segments on both surfaces, per triangle of B.
    pub segs_b: Map<u32, Vec<[Pid; 2]>>,
}

/// An end of a triangle's meeting with the other's plane: its definition and the
/// element of its own triangle that holds it.
#[derive(Clone, Copy, Debug)]
struct End {
    def: Def,
    elem: Elem,
}

impl Traces {
    fn point(&mut self, pts: &mut Points, key: Key, def: Def) -> Pid {
        if let Key::Vertex(v) = key {
            return v;
        }
        *self.keys.entry(key).or_insert_with(|| pts.add(def))
    }

    fn note_on_edge(&mut self, e: Elem, p: Pid) {
        if let Elem::Edge(k) = e
            && p != k[0]
            && p != k[1]
        {
            let list = self.on_edge.entry(k).or_default();
            if !list.contains(&p) {
                list.push(p);
            }
        }
    }

    fn add_segment(&mut self, ta: u32, tb: u32, s: [Pid; 2]) {
        if s[0] == s[1] {
            return;
        }
        self.segs_a.entry(ta).or_default().push(s);
        self.segs_b.entry(tb).or_default().push(s);
    }

    /// Traces where triangle `ta` of `a` meets triangle `tb` of `b`.
    pub fn pair(&mut self, pts: &mut Points, a: &Mesh, ta: u32, b: &Mesh, tb: u32) {
        let (tra, trb) = (a.tris[ta as usize], b.tris[tb as usize]);
        let sa = tra.map(|p| pts.side(trb, p));
        if sa.iter().all(|&s| s > 0) || sa.iter().all(|&s| s < 0) {
            return;
        }
        let sb = trb.map(|p| pts.side(tra, p));
        if sb.iter().all(|&s| s > 0) || sb.iter().all(|&s| s < 0) {
            return;
        }
        if sa == [0, 0, 0] {
            self.coplanar(pts, ta, tra, tb, trb);
            return;
        }
        let Some((ea, a_is_edge)) = ends(pts, tra, sa, trb) else {
            return;
        };
        let Some((eb, b_is_edge)) = ends(pts, trb, sb, tra) else {
            return;
        };
        // Order both along the line where the planes meet, by a coordinate on which
        // that line advances (the fastest first, by the loci).
        let normal = |t: [Pid; 3]| {
            let [a, b, c] = t.map(|p| pts.input_at(p));
            (b - a).cross(c - a)
        };
        let along = normal(tra).cross(normal(trb)).abs();
        let mut order = [0usize, 1, 2];
        order.sort_by(|&i, &j| along[j].total_cmp(&along[i]));
        let k = order
            .into_iter()
            .find(|&k| {
                LineDir {
                    pts,
                    a: tra,
                    b: trb,
                    k,
                }
                .sign()
                    != 0
            })
            .expect("planes that are not parallel meet in a line");
        let cmp = |p: &End, q: &End| coord_cmp(pts, k, p.def, q.def);
        let [mut a0, mut a1] = ea;
        if cmp(&a0, &a1) > 0 {
            std::mem::swap(&mut a0, &mut a1);
        }
        let [mut b0, mut b1] = eb;
        if cmp(&b0, &b1) > 0 {
            std::mem::swap(&mut b0, &mut b1);
        }
        let inner_a = if let Some(e) = a_is_edge {
            Elem::Edge(e)
        } else {
            Elem::Tri(ta)
        };
        let inner_b = if let Some(e) = b_is_edge {
            Elem::Edge(e)
        } else {
            Elem::Tri(tb)
        };
        // The later of the starts and the earlier of the finishes.
        let start = match cmp(&a0, &b0) {
            0 => (a0.def, a0.elem, b0.elem),
            s if s > 0 => (a0.def, a0.elem, inner_b),
            _ => (b0.def, inner_a, b0.elem),
        };
        let finish = match cmp(&a1, &b1) {
            0 => (a1.def, a1.elem, b1.elem),
            s if s < 0 => (a1.def, a1.elem, inner_b),
            _ => (b1.def, inner_a, b1.elem),
        };
        if coord_cmp(pts, k, start.0, finish.0) >= 0 {
            return; // they touch at a point, or not at all
        }
        let p = self.resolve(pts, start);
        let q = self.resolve(pts, finish);
        self.add_segment(ta, tb, [p, q]);
    }

    /// The point of a segment end, made or found by its key; noted on the edges that
    /// hold it.
    fn resolve(&mut self, pts: &mut Points, (def, ea, eb): (Def, Elem, Elem)) -> Pid {
        let key = match (ea, eb) {
            (Elem::Vertex(v), _) | (_, Elem::Vertex(v)) => Key::Vertex(v),
            (Elem::Edge(e), Elem::Edge(f)) => Key::EdgeEdge(e, f),
            (Elem::Edge(e), Elem::Tri(t)) => Key::EdgeTri(e, t),
            (Elem::Tri(t), Elem::Edge(f)) => Key::TriEdge(t, f),
            (Elem::Tri(_), Elem::Tri(_)) => unreachable!("a segment ends on a triangle's boundary"),
        };
        let p = self.point(pts, key, def);
        self.note_on_edge(ea, p);
        self.note_on_edge(eb, p);
        p
    }

    /// Two triangles in one plane: the boundary of their overlap, traced on both.
    fn coplanar(&mut self, pts: &mut Points, ta: u32, tra: [Pid; 3], tb: u32, trb: [Pid; 3]) {
        let axis = super::split::dominant_axis(pts, tra);
        let sense_a = pts.orient2d(axis, tra);
        debug_assert!(sense_a != 0);
        let sense_b = pts.orient2d(axis, trb);
        // Each edge of one triangle, clipped to the other (closed) triangle.
        let mut segs: Vec<[Pid; 2]> = Vec::new();
        for (edges_of, other, sense_o, e_is_a) in
            [(tra, trb, sense_b, true), (trb, tra, sense_a, false)]
        {
            for i in 0..3 {
                let (f0, f1) = (edges_of[i], edges_of[(i + 1) % 3]);
                let f = edge_key(f0, f1);
                let mut on: Vec<(Pid, Def)> = Vec::new();
                let inside = |p: Pid| {
                    (0..3).all(|j| {
                        pts.orient2d(axis, [other[j], other[(j + 1) % 3], p]) * sense_o >= 0
                    })
                };
                for v in [f0, f1] {
                    if inside(v) {
                        on.push((v, pts.defs[v as usize]));
                        // On an edge of the other triangle: note it there.
                        for j in 0..3 {
                            let (g0, g1) = (other[j], other[(j + 1) % 3]);
                            if v != g0 && v != g1 && pts.orient2d(axis, [g0, g1, v]) == 0 {
                                self.note_on_edge(Elem::Edge(edge_key(g0, g1)), v);
                            }
                        }
                    }
                }
                for j in 0..3 {
                    let (g0, g1) = (other[j], other[(j + 1) % 3]);
                    let g = edge_key(g0, g1);
                    let (s0, s1) = (
                        pts.orient2d(axis, [g0, g1, f0]),
                        pts.orient2d(axis, [g0, g1, f1]),
                    );
                    let (t0, t1) = (
                        pts.orient2d(axis, [f0, f1, g0]),
                        pts.orient2d(axis, [f0, f1, g1]),
                    );
                    // A vertex of the other triangle inside this edge.
                    if t0 == 0 && g0 != f0 && g0 != f1 && between(pts, f0, f1, g0) {
                        on.push((g0, pts.defs[g0 as usize]));
                        self.note_on_edge(Elem::Edge(f), g0);
                    }
                    if s0 * s1 < 0 && t0 * t1 < 0 {
                        let (ke, kf) = if e_is_a { (f, g) } else { (g, f) };
                        let def = Def::Ssi {
                            a: [f0, f1],
                            b: [g0, g1],
                            axis,
                        };
                        let p = self.point(pts, Key::EdgeEdge(ke, kf), def);
                        self.note_on_edge(Elem::Edge(f), p);
                        self.note_on_edge(Elem::Edge(g), p);
                        on.push((p, def));
                    }
                }
                // Sort along the edge; consecutive points bound pieces inside.
                let k = (0..3)
                    .find(|&k| pts.input_at(f0)[k] != pts.input_at(f1)[k])
                    .expect("an edge has two distinct ends");
                on.sort_by(|x, y| coord_cmp(pts, k, x.1, y.1).cmp(&0));
                on.dedup_by(|x, y| x.0 == y.0);
                for w in on.windows(2) {
                    segs.push([w[0].0, w[1].0]);
                }
            }
        }
        for s in segs {
            self.add_segment(ta, tb, s);
        }
    }
}

/// Whether point `p`, on the line through input points `a` and `b`, lies strictly
/// between them.
fn between(pts: &Points, a: Pid, b: Pid, p: Pid) -> bool {
    let (pa, pb, pp) = (pts.input_at(a), pts.input_at(b), pts.input_at(p));
    let k = (0..3).find(|&k| pa[k] != pb[k]).unwrap_or(0);
    let (lo, hi) = if pa[k] < pb[k] {
        (pa[k], pb[k])
    } else {
        (pb[k], pa[k])
    };
    lo < pp[k] && pp[k] < hi
}

/// The two ends of triangle `t`'s meeting with the plane of `other` (whose sides `s`
/// its vertices are on), and the edge it runs along if it lies in that plane. `None`
/// when it meets the plane in a point or not at all.
fn ends(
    pts: &Points,
    t: [Pid; 3],
    s: [i8; 3],
    other: [Pid; 3],
) -> Option<([End; 2], Option<EdgeKey>)> {
    let mut out: Vec<End> = Vec::with_capacity(2);
    for i in 0..3 {
        if s[i] == 0 {
            out.push(End {
                def: pts.defs[t[i] as usize],
                elem: Elem::Vertex(t[i]),
            });
        }
    }
    for i in 0..3 {
        let j = (i + 1) % 3;
        if s[i] * s[j] < 0 {
            out.push(End {
                def: Def::Lpi {
                    line: [t[i], t[j]],
                    plane: other,
                },
                elem: Elem::Edge(edge_key(t[i], t[j])),
            });
        }
    }
    if out.len() != 2 {
        return None;
    }
    let along = match (out[0].elem, out[1].elem) {
        (Elem::Vertex(p), Elem::Vertex(q)) => Some(edge_key(p, q)),
        _ => None,
    };
    Some(([out[0], out[1]], along))
}

/// Component `k` of the direction of the line where the planes of `a` and `b` meet.
struct LineDir<'a> {
    pts: &'a Points,
    a: [Pid; 3],
    b: [Pid; 3],
    k: usize,
}

impl Poly for LineDir<'_> {
    fn eval<R: Ring>(&self) -> R {
        let na = self.pts.normal::<R>(self.a);
        let nb = self.pts.normal::<R>(self.b);
        let (i, j) = match self.k {
            0 => (1, 2),
            1 => (2, 0),
            _ => (0, 1),
        };
        na[i].clone() * nb[j].clone() - na[j].clone() * nb[i].clone()
    }
}
