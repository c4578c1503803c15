//! MKCOPY: a copy of a body with fresh serial numbers.

use crate::model::body::{Body, Edge};
use crate::model::ids::{EdgeId, FaceId, Serials, VertexId};

/// Where each entity of the original went in its copy (see [`Body::mkcopy_mapped`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CopyMap {
    faces: Vec<FaceId>,
    edges: Vec<EdgeId>,
    vertices: Vec<VertexId>,
}

impl CopyMap {
    /// The copy of face `f` of the original, if `f` was live.
    pub fn face(&self, f: FaceId) -> Option<FaceId> {
        self.faces.get(f.index()).copied().filter(|x| !x.is_none())
    }
    /// The copy of edge `e` of the original, if `e` was live.
    pub fn edge(&self, e: EdgeId) -> Option<EdgeId> {
        self.edges.get(e.index()).copied().filter(|x| !x.is_none())
    }
    /// The copy of vertex `v` of the original, if `v` was live.
    pub fn vertex(&self, v: VertexId) -> Option<VertexId> {
        self.vertices
            .get(v.index())
            .copied()
            .filter(|x| !x.is_none())
    }
}

impl Body {
    /// MKCOPY(B): a new body with the same topology (every link, every perimeter, the
    /// handle count) and the same vertex loci, under fresh serial numbers.
    ///
    /// Serial numbers are taken for the vertices, then the faces, then the edges, each
    /// in the original's slot order; so a copy's serials are all new and the copy of a
    /// given body is always numbered the same way. Slots are packed: when the original
    /// has no dead slots (nothing was killed in it), every entity keeps its slot id, so
    /// `f` in the original is `f` in the copy. Otherwise use [`Body::mkcopy_mapped`].
    ///
    /// The original is not changed. The copy is a separate body; killing it (dropping it)
    /// is the inverse.
    pub fn mkcopy(&self, serials: &mut Serials) -> Body {
        self.mkcopy_mapped(serials).0
    }

    /// [`Body::mkcopy`], also returning where each entity went.
    pub fn mkcopy_mapped(&self, serials: &mut Serials) -> (Body, CopyMap) {
        let mut b = Body::empty();
        b.reserve(self.face_count(), self.edge_count(), self.vertex_count());
        let mut map = CopyMap {
            faces: vec![FaceId::NONE; self.faces.slots()],
            edges: vec![EdgeId::NONE; self.edges.slots()],
            vertices: vec![VertexId::NONE; self.vertices.slots()],
        };
        for v in self.vertices() {
            map.vertices[v.index()] = b.mkv(serials, self.position(v), EdgeId::NONE);
        }
        for f in self.faces() {
            map.faces[f.index()] = b.mkf(serials, EdgeId::NONE);
        }
        for e in self.edges() {
            let r = self.edge(e);
            map.edges[e.index()] = b.mke(
                serials,
                Edge::unlinked(
                    r.vt.map(|v| map.vertices[v.index()]),
                    r.face.map(|f| map.faces[f.index()]),
                ),
            );
        }
        let edge_of = |e: EdgeId| {
            if e.is_none() {
                EdgeId::NONE
            } else {
                map.edges[e.index()]
            }
        };
        for e in self.edges() {
            let r = self.edge(e);
            let c = b.edge_mut(map.edges[e.index()]);
            c.cw = r.cw.map(edge_of);
            c.ccw = r.ccw.map(edge_of);
        }
        for f in self.faces() {
            b.face_mut(map.faces[f.index()]).ped = edge_of(self.face(f).ped);
        }
        for v in self.vertices() {
            b.vertex_mut(map.vertices[v.index()]).ped = edge_of(self.vertex(v).ped);
        }
        b.handles = self.handles;
        (b, map)
    }
}
