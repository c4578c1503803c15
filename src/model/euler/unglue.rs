//! UNGLUE: cut a body along a closed seam of edges.

use std::collections::HashMap;

use super::EulerError;
use crate::model::body::{Body, Edge};
use crate::model::ids::{EdgeId, FaceId, Serials, Side, VertexId};
use crate::model::topology::EdgeUse;

/// What [`Body::unglue`] made.
#[derive(Debug)]
pub struct Unglued {
    /// The new face capping the cut on the PFACE side of the seam's first edge; its
    /// perimeter is the seam's old edges.
    pub kept_face: FaceId,
    /// The new face capping the cut on the NFACE side, bounded by the new edges. When
    /// the cut split the body, this face's id is in [`Unglued::split_off`].
    pub new_face: FaceId,
    /// The part on the NFACE side, when the seam separated the body in two; it keeps
    /// its serial numbers. `None` when the cut removed a handle instead.
    pub split_off: Option<Body>,
}

impl Body {
    /// UNGLUE(E): cuts the surface along `seam`, a closed loop of edges, duplicating its
    /// edges and vertices and capping each side of the cut with a new face (F +2,
    /// E +N, V +N). If the cut separates the body, the part on the NFACE side of
    /// `seam[0]` becomes a new body (B +1) returned in [`Unglued::split_off`]; otherwise a
    /// handle is removed (H −1).
    ///
    /// Preconditions (refused otherwise): the seam is N ≥ 3 distinct live edges forming
    /// one simple closed loop (every seam vertex on exactly two seam edges), and every
    /// seam edge has two different faces.
    ///
    /// Inverse: [`Body::glue`] (or [`Body::glue_bodies`]) of the two new faces.
    pub fn unglue(
        &mut self,
        serials: &mut Serials,
        seam: &[EdgeId],
    ) -> Result<Unglued, EulerError> {
        let loop_uses = self.plan_unglue(seam)?;
        let n = loop_uses.len();
        let xs: Vec<VertexId> = loop_uses.iter().map(|&u| self.origin(u)).collect();

        // Before any change: the far side of each seam use, its neighbours, and the edges
        // on the far side of the seam at each seam vertex.
        let twins: Vec<EdgeUse> = loop_uses.iter().map(|u| u.twin()).collect();
        let twin_ix: HashMap<EdgeId, usize> =
            twins.iter().enumerate().map(|(i, u)| (u.edge, i)).collect();
        let far: Vec<(FaceId, EdgeUse, EdgeUse)> = twins
            .iter()
            .map(|&t| (self.use_face(t), self.prev(t), self.next(t)))
            .collect();
        let mut movers: Vec<Vec<EdgeUse>> = Vec::with_capacity(n);
        for i in 0..n {
            let from = twins[(i + n - 1) % n]; // leaves x_i toward x_i-1
            let mut w = self.ccw_about_origin(from);
            let mut here = Vec::new();
            while w != loop_uses[i] {
                here.push(w);
                w = self.ccw_about_origin(w);
            }
            movers.push(here);
        }

        let kept_face = self.mkf(serials, loop_uses[0].edge);
        let new_face = self.mkf(serials, EdgeId::NONE);
        let xs2: Vec<VertexId> = xs
            .iter()
            .map(|&x| self.mkv(serials, self.position(x), EdgeId::NONE))
            .collect();
        let cs2: Vec<EdgeId> = (0..n)
            .map(|i| {
                self.mke(
                    serials,
                    Edge::unlinked([xs2[i], xs2[(i + 1) % n]], [new_face, far[i].0]),
                )
            })
            .collect();
        let remap = |u: EdgeUse| -> EdgeUse {
            match twin_ix.get(&u.edge) {
                Some(&j) if twins[j] == u => EdgeUse::new(cs2[j], Side::P),
                _ => u,
            }
        };
        for (i, here) in movers.iter().enumerate() {
            for u in here {
                self.edge_mut(u.edge).vt[u.side.ix()] = xs2[i];
            }
        }
        for i in 0..n {
            let (g, p, nx) = far[i];
            let r = EdgeUse::new(cs2[i], Side::P);
            self.set_next(remap(p), r);
            self.set_next(r, remap(nx));
            if self.face(g).ped == twins[i].edge {
                self.face_mut(g).ped = cs2[i];
            }
        }
        for t in &twins {
            self.edge_mut(t.edge).face[t.side.ix()] = kept_face;
        }
        for i in 0..n {
            self.set_next(twins[i], twins[(i + n - 1) % n]);
            self.set_next(
                EdgeUse::new(cs2[i], Side::N),
                EdgeUse::new(cs2[(i + 1) % n], Side::N),
            );
            self.vertex_mut(xs[i]).ped = loop_uses[i].edge;
            self.vertex_mut(xs2[i]).ped = cs2[i];
        }
        self.face_mut(new_face).ped = cs2[0];

        if self.reaches(xs[0], xs2[0]) {
            self.handles = self.handles.saturating_sub(1);
            Ok(Unglued {
                kept_face,
                new_face,
                split_off: None,
            })
        } else {
            let (part, map) = self.split_component(xs2[0]);
            Ok(Unglued {
                kept_face,
                new_face: map[&new_face],
                split_off: Some(part),
            })
        }
    }

    /// Checks UNGLUE's preconditions and returns the seam's uses in loop order, the
    /// first being the P side of `seam[0]` (from its PVT).
    fn plan_unglue(&self, seam: &[EdgeId]) -> Result<Vec<EdgeUse>, EulerError> {
        let bad = |reason: &str| EulerError::BadSeam {
            reason: reason.to_string(),
        };
        if seam.len() < 3 {
            return Err(bad("it needs at least three edges"));
        }
        let mut at: HashMap<VertexId, Vec<EdgeId>> = HashMap::new();
        for &e in seam {
            self.check_edge(e)?;
            let r = self.edge(e);
            if r.face[0] == r.face[1] {
                return Err(EulerError::SameFaceBothSides {
                    edge: self.edge_serial(e),
                    face: self.face_serial(r.face[0]),
                });
            }
            for v in r.vt {
                let list = at.entry(v).or_default();
                if list.contains(&e) {
                    return Err(bad("an edge is listed twice"));
                }
                list.push(e);
            }
        }
        if at.values().any(|l| l.len() != 2) {
            return Err(bad(
                "a vertex of the seam is on more or fewer than two seam edges",
            ));
        }
        let first = EdgeUse::new(seam[0], Side::P);
        let mut uses = vec![first];
        let mut u = first;
        loop {
            let x = self.dest(u);
            let pair = &at[&x];
            let next_edge = if pair[0] == u.edge { pair[1] } else { pair[0] };
            u = EdgeUse::new(next_edge, self.side_at(next_edge, x));
            if u.edge == seam[0] {
                break;
            }
            uses.push(u);
        }
        if uses.len() != seam.len() {
            return Err(bad("the edges form more than one loop"));
        }
        Ok(uses)
    }

    /// Whether vertex `b` can be reached from `a` along edges.
    fn reaches(&self, a: VertexId, b: VertexId) -> bool {
        let mut seen = vec![false; self.vertices.slots()];
        let mut stack = vec![a];
        seen[a.index()] = true;
        while let Some(v) = stack.pop() {
            if v == b {
                return true;
            }
            for e in self.vertex_edges(v) {
                let w = self.other_vertex(e, v).unwrap_or(v);
                if !seen[w.index()] {
                    seen[w.index()] = true;
                    stack.push(w);
                }
            }
        }
        false
    }

    /// Moves the connected piece containing `seed` out into a new body (same serial
    /// numbers). Returns it and where its faces went.
    fn split_component(&mut self, seed: VertexId) -> (Body, HashMap<FaceId, FaceId>) {
        let mut vs = vec![seed];
        let mut seen_v = vec![false; self.vertices.slots()];
        let mut seen_e = vec![false; self.edges.slots()];
        let mut seen_f = vec![false; self.faces.slots()];
        seen_v[seed.index()] = true;
        let (mut es, mut fs) = (Vec::new(), Vec::new());
        let mut i = 0;
        while i < vs.len() {
            let v = vs[i];
            i += 1;
            for u in self.vertex_uses(v) {
                if !seen_e[u.edge.index()] {
                    seen_e[u.edge.index()] = true;
                    es.push(u.edge);
                }
                let f = self.use_face(u);
                if !seen_f[f.index()] {
                    seen_f[f.index()] = true;
                    fs.push(f);
                }
                let w = self.dest(u);
                if !seen_v[w.index()] {
                    seen_v[w.index()] = true;
                    vs.push(w);
                }
            }
        }
        let mut part = Body::empty();
        part.reserve(fs.len(), es.len(), vs.len());
        let fmap: HashMap<FaceId, FaceId> = fs
            .iter()
            .map(|&f| {
                let s = self.face_serial(f);
                (f, FaceId(part.faces.insert_unsorted(*self.face(f), s)))
            })
            .collect();
        let emap: HashMap<EdgeId, EdgeId> = es
            .iter()
            .map(|&e| {
                let s = self.edge_serial(e);
                (e, EdgeId(part.edges.insert_unsorted(*self.edge(e), s)))
            })
            .collect();
        let vmap: HashMap<VertexId, VertexId> = vs
            .iter()
            .map(|&v| {
                let s = self.vertex_serial(v);
                (
                    v,
                    VertexId(part.vertices.insert_unsorted(*self.vertex(v), s)),
                )
            })
            .collect();
        for &nf in fmap.values() {
            let r = part.face_mut(nf);
            r.ped = emap[&r.ped];
        }
        for &nv in vmap.values() {
            let r = part.vertex_mut(nv);
            r.ped = emap[&r.ped];
        }
        for &ne in emap.values() {
            let r = *part.edge(ne);
            *part.edge_mut(ne) = Edge {
                vt: r.vt.map(|v| vmap[&v]),
                face: r.face.map(|f| fmap[&f]),
                cw: r.cw.map(|x| emap[&x]),
                ccw: r.ccw.map(|x| emap[&x]),
            };
        }
        part.faces.resort_index();
        part.edges.resort_index();
        part.vertices.resort_index();
        for f in fs {
            self.klf(f);
        }
        for e in es {
            self.kle(e);
        }
        for v in vs {
            self.klv(v);
        }
        // Each piece keeps the handles its own Euler characteristic shows.
        let part_handles = ((2 - part.euler_characteristic()) / 2).max(0) as u32;
        part.handles = part_handles;
        self.handles = self.handles.saturating_sub(part_handles);
        (part, fmap)
    }
}
