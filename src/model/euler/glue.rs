//! GLUE (identify two faces), GLUEE (join two faces with a wasp edge), GLUEFF, and the
//! merging of two bodies' arenas that gluing two bodies needs.

use std::collections::HashMap;

use super::EulerError;
use crate::model::body::{Body, Edge};
use crate::model::ids::{EdgeId, FaceId, Serials, Side, VertexId};
use crate::model::topology::EdgeUse;

/// Where the entities of a body absorbed by [`Body::absorb`] now live.
#[derive(Debug, Default)]
pub struct Absorbed {
    faces: Vec<FaceId>,
    edges: Vec<EdgeId>,
    vertices: Vec<VertexId>,
}

impl Absorbed {
    /// The new id of the absorbed body's face `f`.
    pub fn face(&self, f: FaceId) -> FaceId {
        self.faces[f.index()]
    }
    /// The new id of the absorbed body's edge `e`.
    pub fn edge(&self, e: EdgeId) -> EdgeId {
        if e.is_none() {
            e
        } else {
            self.edges[e.index()]
        }
    }
    /// The new id of the absorbed body's vertex `v`.
    pub fn vertex(&self, v: VertexId) -> VertexId {
        self.vertices[v.index()]
    }
}

impl Body {
    /// Moves every face, edge and vertex of `other` into this body, keeping their serial
    /// numbers, and adds `other`'s handles to this body's. The result has two connected
    /// polyhedra until a glue joins them. Returns where each moved entity now lives.
    pub fn absorb(&mut self, other: Body) -> Absorbed {
        let mut map = Absorbed {
            faces: vec![FaceId::NONE; other.faces.slots()],
            edges: vec![EdgeId::NONE; other.edges.slots()],
            vertices: vec![VertexId::NONE; other.vertices.slots()],
        };
        self.reserve(other.face_count(), other.edge_count(), other.vertex_count());
        for f in other.faces() {
            let s = other.face_serial(f);
            map.faces[f.index()] = FaceId(self.faces.insert_unsorted(*other.face(f), s));
        }
        for e in other.edges() {
            let s = other.edge_serial(e);
            map.edges[e.index()] = EdgeId(self.edges.insert_unsorted(*other.edge(e), s));
        }
        for v in other.vertices() {
            let s = other.vertex_serial(v);
            map.vertices[v.index()] = VertexId(self.vertices.insert_unsorted(*other.vertex(v), s));
        }
        for f in other.faces() {
            let nf = map.face(f);
            let ped = map.edge(self.face(nf).ped);
            self.face_mut(nf).ped = ped;
        }
        for v in other.vertices() {
            let nv = map.vertex(v);
            let ped = map.edge(self.vertex(nv).ped);
            self.vertex_mut(nv).ped = ped;
        }
        for e in other.edges() {
            let ne = map.edge(e);
            let r = *self.edge(ne);
            *self.edge_mut(ne) = Edge {
                vt: r.vt.map(|v| map.vertex(v)),
                face: r.face.map(|f| map.face(f)),
                cw: r.cw.map(|x| map.edge(x)),
                ccw: r.ccw.map(|x| map.edge(x)),
            };
        }
        self.faces.resort_index();
        self.edges.resort_index();
        self.vertices.resort_index();
        self.handles += other.handles;
        map
    }

    /// The perimeter of face `f` from vertex `v` on, checked for GLUE: `f` and `v` live,
    /// `v` on `f`, the perimeter a simple polygon of at least three edges.
    fn glue_perimeter(&self, f: FaceId, v: VertexId) -> Result<Vec<EdgeUse>, EulerError> {
        self.check_face(f)?;
        self.check_vertex(v)?;
        let uses: Vec<EdgeUse> = self.face_uses(f).collect();
        let mut verts: Vec<VertexId> = uses.iter().map(|&u| self.origin(u)).collect();
        let Some(start) = verts.iter().position(|&x| x == v) else {
            return Err(EulerError::VertexNotOnFace {
                vertex: self.vertex_serial(v),
                face: self.face_serial(f),
            });
        };
        verts.sort_unstable();
        verts.dedup();
        if verts.len() != uses.len() {
            return Err(EulerError::FaceNotSimple {
                face: self.face_serial(f),
            });
        }
        if uses.len() < 3 {
            return Err(EulerError::FaceTooSmall {
                face: self.face_serial(f),
                degree: uses.len(),
            });
        }
        let mut out = uses;
        out.rotate_left(start);
        Ok(out)
    }

    /// Checks GLUE's preconditions for faces `f1` (from `v1`) and `f2` (from `v2`) of
    /// this body and returns their perimeters.
    fn plan_glue(
        &self,
        f1: FaceId,
        v1: VertexId,
        f2: FaceId,
        v2: VertexId,
    ) -> Result<(Vec<EdgeUse>, Vec<EdgeUse>), EulerError> {
        let a = self.glue_perimeter(f1, v1)?;
        let b = self.glue_perimeter(f2, v2)?;
        if f1 == f2 {
            return Err(EulerError::SameFace {
                face: self.face_serial(f1),
            });
        }
        if a.len() != b.len() {
            return Err(EulerError::DegreeMismatch {
                face1: self.face_serial(f1),
                n1: a.len(),
                face2: self.face_serial(f2),
                n2: b.len(),
            });
        }
        let xs: Vec<VertexId> = a.iter().map(|&u| self.origin(u)).collect();
        let ys: Vec<VertexId> = b.iter().map(|&u| self.origin(u)).collect();
        if let Some(&shared) = xs.iter().find(|x| ys.contains(x)) {
            return Err(EulerError::FacesTouch {
                face1: self.face_serial(f1),
                face2: self.face_serial(f2),
                vertex: self.vertex_serial(shared),
            });
        }
        let n = xs.len();
        for (i, &x) in xs.iter().enumerate() {
            let y = ys[(n - i) % n];
            if let Some(e) = self
                .vertex_edges(x)
                .find(|&e| self.other_vertex(e, x) == Some(y))
            {
                return Err(EulerError::WouldMakeLoop {
                    a: self.vertex_serial(x),
                    b: self.vertex_serial(y),
                    edge: self.edge_serial(e),
                });
            }
        }
        Ok((a, b))
    }

    /// GLUE(F1, F2), the 1972 memo's form, on two faces of this body: identifies face
    /// `f2` with face `f1`, vertex `v2` with `v1` and so on around the two perimeters in
    /// opposite senses (exterior to exterior), then kills both faces, `f2`'s edges and
    /// `f2`'s vertices. This makes a handle: F −2, E −N, V −N, H +1. The kept vertices
    /// are `f1`'s, at their own loci.
    ///
    /// Preconditions (refused otherwise): `f1` ≠ `f2`, both simple polygons with the same
    /// number N ≥ 3 of edges; `v1` on `f1`, `v2` on `f2`; the faces share no vertex; no
    /// edge joins two vertices that are to be identified.
    ///
    /// Inverse: [`Body::unglue`] along the loop of `f1`'s old edges.
    pub fn glue(
        &mut self,
        f1: FaceId,
        v1: VertexId,
        f2: FaceId,
        v2: VertexId,
    ) -> Result<(), EulerError> {
        let (a, b) = self.plan_glue(f1, v1, f2, v2)?;
        self.identify(f1, f2, &a, &b);
        self.handles += 1;
        Ok(())
    }

    /// GLUE of face `f1` of this body with face `f2` of body `other`: the two bodies
    /// become one (B −1), with the same identification as [`Body::glue`]. On success
    /// `other` is left empty; on refusal both bodies are unchanged.
    pub fn glue_bodies(
        &mut self,
        f1: FaceId,
        v1: VertexId,
        other: &mut Body,
        f2: FaceId,
        v2: VertexId,
    ) -> Result<(), EulerError> {
        let a = self.glue_perimeter(f1, v1)?;
        let b = other.glue_perimeter(f2, v2)?;
        if a.len() != b.len() {
            return Err(EulerError::DegreeMismatch {
                face1: self.face_serial(f1),
                n1: a.len(),
                face2: other.face_serial(f2),
                n2: b.len(),
            });
        }
        let map = self.absorb(std::mem::take(other));
        let (f2, v2) = (map.face(f2), map.vertex(v2));
        let (a, b) = self
            .plan_glue(f1, v1, f2, v2)
            .expect("two separate bodies meet every GLUE precondition checked above");
        self.identify(f1, f2, &a, &b);
        Ok(())
    }

    /// The identification itself. Preconditions: as checked by `plan_glue`.
    fn identify(&mut self, f1: FaceId, f2: FaceId, a: &[EdgeUse], b: &[EdgeUse]) {
        let n = a.len();
        // Pair a[i] (x_i → x_i+1 in f1) with the other side of b[n-1-i], which runs the
        // same way between the partners of x_i and x_i+1.
        let survivors: Vec<EdgeUse> = a.to_vec();
        let doomed: Vec<EdgeUse> = (0..n).map(|i| b[n - 1 - i].twin()).collect();
        let killed: HashMap<EdgeId, usize> = doomed
            .iter()
            .enumerate()
            .map(|(i, u)| (u.edge, i))
            .collect();
        let map = |u: EdgeUse| -> EdgeUse {
            match killed.get(&u.edge) {
                Some(&i) if doomed[i] == u => survivors[i],
                _ => u,
            }
        };
        let plan: Vec<(FaceId, EdgeUse, EdgeUse)> = doomed
            .iter()
            .map(|&t| (self.use_face(t), map(self.prev(t)), map(self.next(t))))
            .collect();
        let xs: Vec<VertexId> = a.iter().map(|&u| self.origin(u)).collect();
        let ys: Vec<VertexId> = b.iter().map(|&u| self.origin(u)).collect();
        let mut moves: Vec<(EdgeUse, VertexId)> = Vec::new();
        for (i, &x) in xs.iter().enumerate() {
            let y = ys[(n - i) % n];
            for u in self.vertex_uses(y) {
                if !killed.contains_key(&u.edge) {
                    moves.push((u, x));
                }
            }
        }
        for (u, x) in moves {
            self.edge_mut(u.edge).vt[u.side.ix()] = x;
        }
        for (i, &(g, p, nx)) in plan.iter().enumerate() {
            let s = survivors[i];
            self.edge_mut(s.edge).face[s.side.ix()] = g;
            self.set_next(p, s);
            self.set_next(s, nx);
            if self.face(g).ped == doomed[i].edge {
                self.face_mut(g).ped = s.edge;
            }
        }
        for t in &doomed {
            self.kle(t.edge);
        }
        for &y in &ys {
            self.klv(y);
        }
        self.klf(f1);
        self.klf(f2);
    }

    /// Checks GLUEE's preconditions and returns the two corners.
    fn plan_gluee(
        &self,
        f1: FaceId,
        v1: VertexId,
        f2: FaceId,
        v2: VertexId,
    ) -> Result<(EdgeUse, EdgeUse), EulerError> {
        self.check_face(f1)?;
        self.check_face(f2)?;
        self.check_vertex(v1)?;
        self.check_vertex(v2)?;
        if f1 == f2 {
            return Err(EulerError::SameFace {
                face: self.face_serial(f1),
            });
        }
        if v1 == v2 {
            return Err(EulerError::SameVertex {
                vertex: self.vertex_serial(v1),
            });
        }
        for (v, f) in [(v1, f1), (v2, f2)] {
            if self.vertex(v).ped.is_none() {
                return Err(EulerError::NoEdges {
                    vertex: self.vertex_serial(v),
                });
            }
            self.corner(v, f)?;
        }
        Ok((self.corner(v1, f1)?, self.corner(v2, f2)?))
    }

    /// GLUEE(F1, V1, F2, V2), GEOMED's form, on two faces of this body: makes a new
    /// "wasp" edge ENEW from `v1` to `v2` and kills `f2`, whose perimeter joins `f1`'s
    /// through ENEW (F −1, E +1, H +1). Returns ENEW, with PVT = `v1`, NVT = `v2` and
    /// `f1` on both sides; PCW(ENEW) continues `f1` backwards from `v1` and PCCW(ENEW)
    /// continues `f2`'s old perimeter forwards from `v2`, which is how GLUEFF walks the
    /// two faces to tie them with MKFEs.
    ///
    /// Preconditions (refused otherwise): `f1` ≠ `f2`, `v1` ≠ `v2`, each vertex on its
    /// face exactly once.
    pub fn gluee(
        &mut self,
        serials: &mut Serials,
        f1: FaceId,
        v1: VertexId,
        f2: FaceId,
        v2: VertexId,
    ) -> Result<EdgeId, EulerError> {
        let (o1, o2) = self.plan_gluee(f1, v1, f2, v2)?;
        let e = self.join_wasp(serials, f1, o1, f2, o2);
        self.handles += 1;
        Ok(e)
    }

    /// GLUEE between face `f1` of this body and face `f2` of body `other`: the bodies
    /// become one (B −1). On success `other` is left empty; on refusal both are
    /// unchanged.
    pub fn gluee_bodies(
        &mut self,
        serials: &mut Serials,
        f1: FaceId,
        v1: VertexId,
        other: &mut Body,
        f2: FaceId,
        v2: VertexId,
    ) -> Result<EdgeId, EulerError> {
        self.check_face(f1)?;
        self.check_vertex(v1)?;
        other.check_face(f2)?;
        other.check_vertex(v2)?;
        for (b, v, f) in [(&*self, v1, f1), (&*other, v2, f2)] {
            if b.vertex(v).ped.is_none() {
                return Err(EulerError::NoEdges {
                    vertex: b.vertex_serial(v),
                });
            }
            b.corner(v, f)?;
        }
        let map = self.absorb(std::mem::take(other));
        let (f2, v2) = (map.face(f2), map.vertex(v2));
        let (o1, o2) = self
            .plan_gluee(f1, v1, f2, v2)
            .expect("two separate bodies meet every GLUEE precondition checked above");
        Ok(self.join_wasp(serials, f1, o1, f2, o2))
    }

    fn join_wasp(
        &mut self,
        serials: &mut Serials,
        f1: FaceId,
        o1: EdgeUse,
        f2: FaceId,
        o2: EdgeUse,
    ) -> EdgeId {
        let (i1, i2) = (self.prev(o1), self.prev(o2));
        let (v1, v2) = (self.origin(o1), self.origin(o2));
        let mut u = o2;
        loop {
            self.edge_mut(u.edge).face[u.side.ix()] = f1;
            u = self.next(u);
            if u == o2 {
                break;
            }
        }
        let e = self.mke(serials, Edge::unlinked([v2, v1], [f1, f1]));
        let (up, un) = (EdgeUse::new(e, Side::P), EdgeUse::new(e, Side::N));
        self.set_next(i1, up);
        self.set_next(up, o2);
        self.set_next(i2, un);
        self.set_next(un, o1);
        self.klf(f2);
        e
    }

    /// GLUEFF (GEOMED's example 5) on two faces of this body with the same number of
    /// edges: GLUEE from a vertex of `f1` to the nearest vertex of `f2`, then MKFE around
    /// the two perimeters, so the faces are replaced by a ring of quadrilaterals: a tube
    /// between them. Returns the edges made, the wasp edge first.
    ///
    /// Preconditions: as for [`Body::gluee`], and both faces simple with equal edge
    /// counts (refused otherwise).
    pub fn glueff(
        &mut self,
        serials: &mut Serials,
        f1: FaceId,
        f2: FaceId,
    ) -> Result<Vec<EdgeId>, EulerError> {
        let (v1, v2) = self.glueff_vertices(f1, f2)?;
        let e = self.gluee(serials, f1, v1, f2, v2)?;
        Ok(self.tie_tube(serials, f1, e, v1, v2))
    }

    /// GLUEFF between face `f1` of this body and face `f2` of `other`: the dumbbell. On
    /// success `other` is left empty.
    pub fn glueff_bodies(
        &mut self,
        serials: &mut Serials,
        f1: FaceId,
        other: &mut Body,
        f2: FaceId,
    ) -> Result<Vec<EdgeId>, EulerError> {
        self.check_face(f1)?;
        other.check_face(f2)?;
        let n1 = self.simple_degree(f1)?;
        let n2 = other.simple_degree(f2)?;
        if n1 != n2 {
            return Err(EulerError::DegreeMismatch {
                face1: self.face_serial(f1),
                n1,
                face2: other.face_serial(f2),
                n2,
            });
        }
        let v1 = self.first_vertex(f1);
        let p1 = self.position(v1);
        let v2 = other.nearest_vertex_on(f2, p1);
        let e = self.gluee_bodies(serials, f1, v1, other, f2, v2)?;
        let v2 = self.other_vertex(e, v1).expect("the wasp edge ends at v1");
        Ok(self.tie_tube(serials, f1, e, v1, v2))
    }

    fn glueff_vertices(&self, f1: FaceId, f2: FaceId) -> Result<(VertexId, VertexId), EulerError> {
        self.check_face(f1)?;
        self.check_face(f2)?;
        let n1 = self.simple_degree(f1)?;
        let n2 = self.simple_degree(f2)?;
        if n1 != n2 {
            return Err(EulerError::DegreeMismatch {
                face1: self.face_serial(f1),
                n1,
                face2: self.face_serial(f2),
                n2,
            });
        }
        if let Some(shared) = self
            .face_vertices(f1)
            .find(|&x| self.face_vertices(f2).any(|y| y == x))
        {
            return Err(EulerError::FacesTouch {
                face1: self.face_serial(f1),
                face2: self.face_serial(f2),
                vertex: self.vertex_serial(shared),
            });
        }
        let v1 = self.first_vertex(f1);
        Ok((v1, self.nearest_vertex_on(f2, self.position(v1))))
    }

    fn simple_degree(&self, f: FaceId) -> Result<usize, EulerError> {
        let first = self.face_uses(f).next().map(|u| self.origin(u));
        match first {
            Some(v) => self.glue_perimeter(f, v).map(|p| p.len()),
            None => Err(EulerError::FaceTooSmall {
                face: self.face_serial(f),
                degree: 0,
            }),
        }
    }

    /// VCCW(PED(F), F): the vertex GLUEFF starts from.
    fn first_vertex(&self, f: FaceId) -> VertexId {
        let u = self.face_first_use(f).expect("a simple face has edges");
        self.dest(u)
    }

    fn nearest_vertex_on(&self, f: FaceId, p: glam::DVec3) -> VertexId {
        self.face_vertices(f)
            .min_by(|&a, &b| {
                let (da, db) = (self.position(a).distance(p), self.position(b).distance(p));
                da.total_cmp(&db)
            })
            .expect("a simple face has vertices")
    }

    /// The MKFE loop of GLUEFF after its GLUEE made wasp edge `e` from `v1` to `v2`.
    fn tie_tube(
        &mut self,
        serials: &mut Serials,
        f1: FaceId,
        e: EdgeId,
        v1: VertexId,
        v2: VertexId,
    ) -> Vec<EdgeId> {
        let mut made = vec![e];
        let last = self
            .other_vertex(self.edge(e).nccw(), v1)
            .expect("NCCW of the wasp edge meets it at v1");
        let (mut e, mut a, mut b) = (e, v1, v2);
        loop {
            a = self
                .other_vertex(self.edge(e).pcw(), a)
                .expect("PCW meets the edge at its PVT");
            b = self
                .other_vertex(self.edge(e).pccw(), b)
                .expect("PCCW meets the edge at its NVT");
            let (ne, _) = self
                .mkfe(serials, a, f1, b)
                .expect("each pair of GLUEFF vertices has one corner on the wasp face");
            made.push(ne);
            e = ne;
            if a == last {
                break;
            }
        }
        made
    }
}
