//! Perimeter access: Baumgart's ECW, ECCW, FCW, FCCW, VCW, VCCW, OTHER and LINKED, the
//! wing mungers WING, INVERT and EVERT, and iterators over face and vertex perimeters.
//!
//! Clockwise and counter-clockwise are always as seen from outside the solid.
//!
//! Underneath, a face perimeter is walked as a cycle of [`EdgeUse`]s: side `s` of edge
//! `e` runs from `vt[s]` to `vt[!s]` with `face[s]` on its left. The next use after it
//! is on edge `ccw[s]`, and its side is the one that starts where this use ends. Telling
//! the side by the shared vertex rather than by the face keeps the walk right on spurs
//! and wires, whose edges have the same face on both sides.

use super::body::Body;
use super::ids::{EdgeId, FaceId, Side, VertexId};

/// One side of an edge: the use of the edge by the face on that side, directed from
/// `vt[side]` to `vt[!side]` (counter-clockwise about that face).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct EdgeUse {
    /// The edge.
    pub edge: EdgeId,
    /// Which side of it.
    pub side: Side,
}

impl EdgeUse {
    /// The use of `edge` on `side`.
    #[inline]
    pub fn new(edge: EdgeId, side: Side) -> Self {
        Self { edge, side }
    }
    /// The other side of the same edge.
    #[inline]
    pub fn twin(self) -> Self {
        Self {
            edge: self.edge,
            side: !self.side,
        }
    }
}

/// A face or a vertex: what Baumgart's perimeter fetches clock about.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Around {
    /// About a face's perimeter.
    Face(FaceId),
    /// About a vertex's perimeter.
    Vertex(VertexId),
}

impl From<FaceId> for Around {
    fn from(f: FaceId) -> Self {
        Around::Face(f)
    }
}
impl From<VertexId> for Around {
    fn from(v: VertexId) -> Self {
        Around::Vertex(v)
    }
}

/// What LINKED found between two entities.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Link {
    /// The entities share this edge (face–face, vertex–vertex).
    Edge(EdgeId),
    /// The entities share this vertex (edge–edge).
    Vertex(VertexId),
    /// The face or vertex is on the edge (face–edge, edge–vertex).
    Incident,
}

impl Body {
    // ---------------------------------------------------------------- edge uses

    /// Where a use starts: `vt[side]`.
    #[inline]
    pub fn origin(&self, u: EdgeUse) -> VertexId {
        self.edge(u.edge).vt[u.side.ix()]
    }
    /// Where a use ends: `vt[!side]`.
    #[inline]
    pub fn dest(&self, u: EdgeUse) -> VertexId {
        self.edge(u.edge).vt[(!u.side).ix()]
    }
    /// The face a use belongs to: `face[side]`.
    #[inline]
    pub fn use_face(&self, u: EdgeUse) -> FaceId {
        self.edge(u.edge).face[u.side.ix()]
    }
    /// The next use counter-clockwise about the same face.
    #[inline]
    pub fn next(&self, u: EdgeUse) -> EdgeUse {
        let r = self.edge(u.edge);
        let n = r.ccw[u.side.ix()];
        let at = r.vt[(!u.side).ix()];
        EdgeUse::new(n, self.side_at(n, at))
    }
    /// The previous use about the same face (the next one clockwise).
    #[inline]
    pub fn prev(&self, u: EdgeUse) -> EdgeUse {
        let r = self.edge(u.edge);
        let p = r.cw[u.side.ix()];
        let at = r.vt[u.side.ix()];
        // The previous use ends at `at`: its side is the one whose vt[!side] is `at`.
        EdgeUse::new(p, !self.side_at(p, at))
    }
    /// The next outgoing use counter-clockwise about the origin vertex of `u`.
    #[inline]
    pub fn ccw_about_origin(&self, u: EdgeUse) -> EdgeUse {
        self.prev(u).twin()
    }
    /// The next outgoing use clockwise about the origin vertex of `u`.
    #[inline]
    pub fn cw_about_origin(&self, u: EdgeUse) -> EdgeUse {
        self.next(u.twin())
    }
    /// Links `a` to `b` as consecutive uses of one face: `ccw` of `a` becomes `b`'s edge
    /// and `cw` of `b` becomes `a`'s edge.
    ///
    /// Precondition: `a` ends where `b` starts and both belong to the same face.
    #[inline]
    pub(crate) fn set_next(&mut self, a: EdgeUse, b: EdgeUse) {
        self.edge_mut(a.edge).ccw[a.side.ix()] = b.edge;
        self.edge_mut(b.edge).cw[b.side.ix()] = a.edge;
    }

    /// The first use of face `f`'s perimeter (the use of PED(f) on `f`'s side), or `None`
    /// for a face without edges.
    #[inline]
    pub fn face_first_use(&self, f: FaceId) -> Option<EdgeUse> {
        let e = self.face(f).ped;
        if e.is_none() {
            return None;
        }
        let side = if self.edge(e).face[1] == f {
            Side::P
        } else {
            Side::N
        };
        Some(EdgeUse::new(e, side))
    }

    /// The outgoing use of PED(v) at `v`, or `None` for a vertex without edges.
    #[inline]
    pub fn vertex_first_use(&self, v: VertexId) -> Option<EdgeUse> {
        let e = self.vertex(v).ped;
        if e.is_none() {
            return None;
        }
        Some(EdgeUse::new(e, self.side_at(e, v)))
    }

    // ---------------------------------------------------------------- iterators

    /// The uses of face `f`'s perimeter, counter-clockwise from PED(f).
    pub fn face_uses(&self, f: FaceId) -> FaceUses<'_> {
        FaceUses(Walk::new(self, self.face_first_use(f)))
    }
    /// The edges of face `f`'s perimeter, counter-clockwise (a spur edge appears twice).
    pub fn face_edges(&self, f: FaceId) -> impl Iterator<Item = EdgeId> + '_ {
        self.face_uses(f).map(|u| u.edge)
    }
    /// The vertices of face `f`'s perimeter, counter-clockwise, each use's origin.
    pub fn face_vertices(&self, f: FaceId) -> impl Iterator<Item = VertexId> + '_ {
        self.face_uses(f).map(|u| self.origin(u))
    }
    /// The outgoing uses at vertex `v`, counter-clockwise from PED(v).
    pub fn vertex_uses(&self, v: VertexId) -> VertexUses<'_> {
        VertexUses(Walk::new(self, self.vertex_first_use(v)))
    }
    /// The edges at vertex `v`, counter-clockwise.
    pub fn vertex_edges(&self, v: VertexId) -> impl Iterator<Item = EdgeId> + '_ {
        self.vertex_uses(v).map(|u| u.edge)
    }
    /// The faces around vertex `v`, counter-clockwise; the face following each edge.
    pub fn vertex_faces(&self, v: VertexId) -> impl Iterator<Item = FaceId> + '_ {
        self.vertex_uses(v).map(|u| self.use_face(u))
    }
    /// Number of edge uses around face `f` (its perimeter length).
    pub fn face_degree(&self, f: FaceId) -> usize {
        self.face_uses(f).count()
    }
    /// Number of edges at vertex `v` (its valence).
    pub fn valence(&self, v: VertexId) -> usize {
        self.vertex_uses(v).count()
    }

    // ------------------------------------------------- Baumgart's perimeter fetches

    /// ECW: the edge clockwise from `e` about the face or vertex `x`, or `None` when `x`
    /// is not on `e`. About a face whose both sides are `e` (a spur), the P side is used.
    pub fn ecw(&self, e: EdgeId, x: impl Into<Around>) -> Option<EdgeId> {
        let r = self.edge(e);
        match x.into() {
            Around::Face(f) if r.face[1] == f => Some(r.cw[1]),
            Around::Face(f) if r.face[0] == f => Some(r.cw[0]),
            Around::Vertex(v) if r.vt[1] == v => Some(r.ccw[0]),
            Around::Vertex(v) if r.vt[0] == v => Some(r.ccw[1]),
            _ => None,
        }
    }
    /// ECCW: the edge counter-clockwise from `e` about the face or vertex `x`.
    pub fn eccw(&self, e: EdgeId, x: impl Into<Around>) -> Option<EdgeId> {
        let r = self.edge(e);
        match x.into() {
            Around::Face(f) if r.face[1] == f => Some(r.ccw[1]),
            Around::Face(f) if r.face[0] == f => Some(r.ccw[0]),
            Around::Vertex(v) if r.vt[1] == v => Some(r.cw[1]),
            Around::Vertex(v) if r.vt[0] == v => Some(r.cw[0]),
            _ => None,
        }
    }
    /// FCW: the face clockwise from `e` about its vertex `v`.
    pub fn fcw(&self, e: EdgeId, v: VertexId) -> Option<FaceId> {
        let r = self.edge(e);
        if r.vt[1] == v {
            Some(r.face[0])
        } else if r.vt[0] == v {
            Some(r.face[1])
        } else {
            None
        }
    }
    /// FCCW: the face counter-clockwise from `e` about its vertex `v`.
    pub fn fccw(&self, e: EdgeId, v: VertexId) -> Option<FaceId> {
        let r = self.edge(e);
        if r.vt[1] == v {
            Some(r.face[1])
        } else if r.vt[0] == v {
            Some(r.face[0])
        } else {
            None
        }
    }
    /// VCW: the vertex clockwise from `e` about its face `f` (where `e`'s use in `f`
    /// starts).
    pub fn vcw(&self, e: EdgeId, f: FaceId) -> Option<VertexId> {
        let r = self.edge(e);
        if r.face[1] == f {
            Some(r.vt[1])
        } else if r.face[0] == f {
            Some(r.vt[0])
        } else {
            None
        }
    }
    /// VCCW: the vertex counter-clockwise from `e` about its face `f` (where `e`'s use
    /// in `f` ends).
    pub fn vccw(&self, e: EdgeId, f: FaceId) -> Option<VertexId> {
        let r = self.edge(e);
        if r.face[1] == f {
            Some(r.vt[0])
        } else if r.face[0] == f {
            Some(r.vt[1])
        } else {
            None
        }
    }
    /// OTHER: the face of `e` that is not `f`.
    pub fn other_face(&self, e: EdgeId, f: FaceId) -> Option<FaceId> {
        let r = self.edge(e);
        if r.face[1] == f {
            Some(r.face[0])
        } else if r.face[0] == f {
            Some(r.face[1])
        } else {
            None
        }
    }
    /// OTHER: the vertex of `e` that is not `v`.
    pub fn other_vertex(&self, e: EdgeId, v: VertexId) -> Option<VertexId> {
        let r = self.edge(e);
        if r.vt[1] == v {
            Some(r.vt[0])
        } else if r.vt[0] == v {
            Some(r.vt[1])
        } else {
            None
        }
    }

    /// LINKED face–face: an edge the two faces share.
    pub fn linked_faces(&self, a: FaceId, b: FaceId) -> Option<Link> {
        self.face_edges(a)
            .find(|&e| self.other_face(e, a) == Some(b))
            .map(Link::Edge)
    }
    /// LINKED face–edge: whether `f` is a face of `e`.
    pub fn linked_face_edge(&self, f: FaceId, e: EdgeId) -> Option<Link> {
        self.edge(e).face.contains(&f).then_some(Link::Incident)
    }
    /// LINKED edge–edge: a vertex the two edges share.
    pub fn linked_edges(&self, a: EdgeId, b: EdgeId) -> Option<Link> {
        let (ra, rb) = (self.edge(a), self.edge(b));
        ra.vt
            .iter()
            .find(|v| rb.vt.contains(v))
            .map(|&v| Link::Vertex(v))
    }
    /// LINKED edge–vertex: whether `v` is an end of `e`.
    pub fn linked_edge_vertex(&self, e: EdgeId, v: VertexId) -> Option<Link> {
        self.edge(e).vt.contains(&v).then_some(Link::Incident)
    }
    /// LINKED vertex–vertex: an edge joining the two vertices.
    pub fn linked_vertices(&self, a: VertexId, b: VertexId) -> Option<Link> {
        self.vertex_edges(a)
            .find(|&e| self.other_vertex(e, a) == Some(b))
            .map(Link::Edge)
    }

    // ------------------------------------------------------------ wing mungers

    /// WING(e1, e2): for every vertex and face the two edges share in a way that makes
    /// them consecutive about that face, stores each in the other's wing (Baumgart's
    /// eight cases).
    ///
    /// Precondition: the faces and vertices of both edges are already set.
    pub fn wing(&mut self, e1: EdgeId, e2: EdgeId) {
        for s1 in Side::BOTH {
            for s2 in Side::BOTH {
                let (a, b) = (*self.edge(e1), *self.edge(e2));
                // e1's use on side s1 ends where e2's use on side s2 starts, same face.
                if a.vt[(!s1).ix()] == b.vt[s2.ix()] && a.face[s1.ix()] == b.face[s2.ix()] {
                    self.set_next(EdgeUse::new(e1, s1), EdgeUse::new(e2, s2));
                }
                // ... or the other way round.
                if b.vt[(!s2).ix()] == a.vt[s1.ix()] && b.face[s2.ix()] == a.face[s1.ix()] {
                    self.set_next(EdgeUse::new(e2, s2), EdgeUse::new(e1, s1));
                }
            }
        }
    }

    /// INVERT(e): reverses the direction of `e` by exchanging its N and P sides
    /// (vertices, faces, and both pairs of wings): the same edge drawn turned half a
    /// turn. The shape and every perimeter are unchanged. Its own inverse.
    ///
    /// (The 1975 paper lists the wing swaps as NCW↔NCCW, PCW↔PCCW; the figure of the
    /// winged edge turned half a turn gives NCW↔PCW, NCCW↔PCCW, which is what is done.)
    pub fn invert(&mut self, e: EdgeId) {
        let r = self.edge_mut(e);
        r.vt.swap(0, 1);
        r.face.swap(0, 1);
        r.cw.swap(0, 1);
        r.ccw.swap(0, 1);
    }

    /// EVERT: turns the whole body inside out (a cube becomes a room): on every edge
    /// PFACE↔NFACE, NCW↔PCCW and NCCW↔PCW. Every face perimeter reverses its direction,
    /// so every face normal flips and the volume changes sign. Its own inverse.
    pub fn evert(&mut self) {
        let slots: Vec<usize> = self.edges.live_slots().collect();
        for i in slots {
            let r = self.edges.get_mut(i);
            r.face.swap(0, 1);
            let (cw, ccw) = (r.cw, r.ccw);
            r.cw = [ccw[1], ccw[0]];
            r.ccw = [cw[1], cw[0]];
        }
    }
}

/// A walk round a ring of edge uses, stopping when it is back at its start. A budget of
/// one step per edge side (plus slack) stops it on a corrupted structure that never
/// closes, which only misuse of [`Body::wing`] can make.
struct Walk<'a> {
    body: &'a Body,
    start: EdgeUse,
    cur: EdgeUse,
    left: usize,
}

impl<'a> Walk<'a> {
    fn new(body: &'a Body, start: Option<EdgeUse>) -> Self {
        let (start, left) = match start {
            Some(u) => (u, 2 * body.edges.slots() + 2),
            None => (EdgeUse::new(EdgeId::NONE, Side::P), 0),
        };
        Walk {
            body,
            start,
            cur: start,
            left,
        }
    }

    #[inline]
    fn step(&mut self, next: impl Fn(&Body, EdgeUse) -> EdgeUse) -> Option<EdgeUse> {
        if self.left == 0 {
            return None;
        }
        let u = self.cur;
        self.cur = next(self.body, u);
        self.left = if self.cur == self.start {
            0
        } else {
            self.left - 1
        };
        Some(u)
    }
}

/// Iterator over a face's perimeter: see [`Body::face_uses`].
pub struct FaceUses<'a>(Walk<'a>);

impl Iterator for FaceUses<'_> {
    type Item = EdgeUse;
    #[inline]
    fn next(&mut self) -> Option<EdgeUse> {
        self.0.step(Body::next)
    }
}

/// Iterator over a vertex's perimeter: see [`Body::vertex_uses`].
pub struct VertexUses<'a>(Walk<'a>);

impl Iterator for VertexUses<'_> {
    type Item = EdgeUse;
    #[inline]
    fn next(&mut self) -> Option<EdgeUse> {
        self.0.step(Body::ccw_about_origin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::check::check_topology;
    use crate::model::ids::Serials;
    use crate::model::solids::mkcube;

    #[test]
    fn wing_relinks_a_broken_wing_pair() {
        let mut b = mkcube(&mut Serials::new(), 2.0, 2.0, 2.0).unwrap();
        let e = b.edges().next().unwrap();
        let w = b.edge(e).pccw();
        let good = b.clone();
        // Break the link both ways: E's PCCW and W's clockwise wing back to E.
        let far = b.edges().find(|&x| x != e && x != w).unwrap();
        b.edge_mut(e).ccw[1] = far;
        // W's use that follows E's P use starts at NVT(E).
        let ws = b.side_at(w, b.edge(e).nvt());
        b.edge_mut(w).cw[ws.ix()] = far;
        assert!(!check_topology(&b).is_ok());
        b.wing(e, w);
        assert!(check_topology(&b).is_ok());
        for x in b.edges() {
            assert_eq!(b.edge(x), good.edge(x));
        }
    }

    #[test]
    fn invert_keeps_every_perimeter_and_is_its_own_inverse() {
        let mut b = mkcube(&mut Serials::new(), 2.0, 2.0, 2.0).unwrap();
        let e = b.edges().next().unwrap();
        let r = *b.edge(e);
        let cycles: Vec<Vec<VertexId>> = b.faces().map(|f| b.face_vertices(f).collect()).collect();
        b.invert(e);
        let s = *b.edge(e);
        assert_eq!(
            (s.pvt(), s.nvt(), s.pface(), s.nface()),
            (r.nvt(), r.pvt(), r.nface(), r.pface())
        );
        assert_eq!(
            (s.pcw(), s.ncw(), s.pccw(), s.nccw()),
            (r.ncw(), r.pcw(), r.nccw(), r.pccw())
        );
        assert!(check_topology(&b).is_ok());
        for (f, c) in b.faces().zip(&cycles) {
            let now: Vec<VertexId> = b.face_vertices(f).collect();
            let k = now.iter().position(|v| *v == c[0]).unwrap();
            let mut now = now;
            now.rotate_left(k);
            assert_eq!(&now, c);
        }
        b.invert(e);
        assert_eq!(*b.edge(e), r);
    }
}
