//! The body: one polyhedron's faces, edges and vertices in compact arenas.
//!
//! Baumgart's body node heads three rings (faces, edges, vertices); here each ring is an
//! arena of records addressed by typed 32-bit slot ids, which gives the same
//! sequential access and constant-time deletion without pointers.
//!
//! * An [`Edge`] holds its two vertices `vt` (NVT, PVT), its two faces `face` (NFACE,
//!   PFACE) and its four wings: `cw` (NCW, PCW) and `ccw` (NCCW, PCCW), each indexed by
//!   [`Side`].
//! * A [`Face`] and a [`Vertex`] hold PED, one edge of their perimeter
//!   ([`EdgeId::NONE`] for the lone face and vertex of a seminal body).
//! * A vertex also holds its locus, in the body's own frame.
//!
//! Vertex loci are the only geometric data; face planes and the like are derived (see
//! `geometry`).

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::arena::Arena;
use super::ids::{EdgeId, FaceId, Serial, Serials, Side, VertexId};

/// A face record: PED, one edge on the face's perimeter.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Face {
    /// One edge of this face's perimeter, or [`EdgeId::NONE`] in a seminal body.
    pub ped: EdgeId,
}

/// A vertex record: its locus and PED, one edge of its perimeter.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Vertex {
    /// The locus, in the body's own frame (meters).
    pub pos: DVec3,
    /// One edge at this vertex, or [`EdgeId::NONE`] in a seminal body.
    pub ped: EdgeId,
}

/// A winged edge: two vertices, two faces and four wings, each pair indexed by [`Side`].
///
/// Seen from outside with the edge running up from NVT to PVT: NFACE lies left, PFACE
/// right; NCCW and PCW meet the edge at PVT (upper left and upper right), NCW and PCCW
/// at NVT (lower left and lower right). Side `s` is the use of the edge by `face[s]`:
/// it runs from `vt[s]` to `vt[!s]`, counter-clockwise about `face[s]`; `ccw[s]` is the
/// next edge of that face after it and `cw[s]` the one before it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Edge {
    /// `[NVT, PVT]`.
    pub vt: [VertexId; 2],
    /// `[NFACE, PFACE]`.
    pub face: [FaceId; 2],
    /// `[NCW, PCW]`.
    pub cw: [EdgeId; 2],
    /// `[NCCW, PCCW]`.
    pub ccw: [EdgeId; 2],
}

impl Edge {
    /// An edge between `vt` and with faces `face` (each `[N, P]`), its wings not yet
    /// linked (the caller links them with `set_next`).
    #[inline]
    pub(crate) fn unlinked(vt: [VertexId; 2], face: [FaceId; 2]) -> Self {
        Edge {
            vt,
            face,
            cw: [EdgeId::NONE; 2],
            ccw: [EdgeId::NONE; 2],
        }
    }

    /// Negative vertex.
    #[inline]
    pub fn nvt(&self) -> VertexId {
        self.vt[0]
    }
    /// Positive vertex.
    #[inline]
    pub fn pvt(&self) -> VertexId {
        self.vt[1]
    }
    /// Negative face (left, seen from outside with the edge pointing up).
    #[inline]
    pub fn nface(&self) -> FaceId {
        self.face[0]
    }
    /// Positive face (right).
    #[inline]
    pub fn pface(&self) -> FaceId {
        self.face[1]
    }
    /// Edge in the negative face clockwise from this one (meets it at NVT).
    #[inline]
    pub fn ncw(&self) -> EdgeId {
        self.cw[0]
    }
    /// Edge in the positive face clockwise from this one (meets it at PVT).
    #[inline]
    pub fn pcw(&self) -> EdgeId {
        self.cw[1]
    }
    /// Edge in the negative face counter-clockwise from this one (meets it at PVT).
    #[inline]
    pub fn nccw(&self) -> EdgeId {
        self.ccw[0]
    }
    /// Edge in the positive face counter-clockwise from this one (meets it at NVT).
    #[inline]
    pub fn pccw(&self) -> EdgeId {
        self.ccw[1]
    }
}

/// One connected winged-edge polyhedron (or a seminal, wire or lamina stage of one).
///
/// Topology is changed only through the Euler operators (`euler`), which keep
/// F − E + V = 2(B − H); the body records its handle count H.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Body {
    pub(crate) faces: Arena<Face>,
    pub(crate) edges: Arena<Edge>,
    pub(crate) vertices: Arena<Vertex>,
    /// Handles (genus) made by gluing faces of this body to each other.
    pub(crate) handles: u32,
}

impl Body {
    /// An empty body: no faces, edges or vertices (the world body, or a body about to be
    /// built). Euler operators start from [`Body::seminal`].
    pub fn empty() -> Self {
        Self::default()
    }

    /// Adds `delta` to the serial of every face, edge and vertex (see
    /// [`Arena::shift_serials`]): how a body numbered from 1 apart from the world takes
    /// its place in the world's serials. Slots and records are unchanged.
    pub(crate) fn shift_serials(&mut self, delta: u64) {
        self.faces.shift_serials(delta);
        self.edges.shift_serials(delta);
        self.vertices.shift_serials(delta);
    }

    /// Number of live faces.
    #[inline]
    pub fn face_count(&self) -> usize {
        self.faces.len()
    }
    /// Number of live edges.
    #[inline]
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }
    /// Number of live vertices.
    #[inline]
    pub fn vertex_count(&self) -> usize {
        self.vertices.len()
    }
    /// Handles (genus) of this body.
    #[inline]
    pub fn handles(&self) -> u32 {
        self.handles
    }
    /// F − E + V.
    pub fn euler_characteristic(&self) -> i64 {
        self.face_count() as i64 - self.edge_count() as i64 + self.vertex_count() as i64
    }
    /// Whether the body has no entities at all.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty() && self.edges.is_empty() && self.vertices.is_empty()
    }

    /// The live faces, in slot order (Baumgart's face ring).
    pub fn faces(&self) -> impl Iterator<Item = FaceId> + '_ {
        self.faces.live_slots().map(FaceId::from_index)
    }
    /// The live edges, in slot order (the edge ring).
    pub fn edges(&self) -> impl Iterator<Item = EdgeId> + '_ {
        self.edges.live_slots().map(EdgeId::from_index)
    }
    /// The live vertices, in slot order (the vertex ring).
    pub fn vertices(&self) -> impl Iterator<Item = VertexId> + '_ {
        self.vertices.live_slots().map(VertexId::from_index)
    }

    /// Whether `f` names a live face of this body.
    #[inline]
    pub fn has_face(&self, f: FaceId) -> bool {
        !f.is_none() && self.faces.is_live(f.index())
    }
    /// Whether `e` names a live edge of this body.
    #[inline]
    pub fn has_edge(&self, e: EdgeId) -> bool {
        !e.is_none() && self.edges.is_live(e.index())
    }
    /// Whether `v` names a live vertex of this body.
    #[inline]
    pub fn has_vertex(&self, v: VertexId) -> bool {
        !v.is_none() && self.vertices.is_live(v.index())
    }

    /// The face record. Precondition: `f` is live (panics if out of range).
    #[inline]
    pub fn face(&self, f: FaceId) -> &Face {
        self.faces.get(f.index())
    }
    /// The edge record. Precondition: `e` is live (panics if out of range).
    #[inline]
    pub fn edge(&self, e: EdgeId) -> &Edge {
        self.edges.get(e.index())
    }
    /// The vertex record. Precondition: `v` is live (panics if out of range).
    #[inline]
    pub fn vertex(&self, v: VertexId) -> &Vertex {
        self.vertices.get(v.index())
    }
    /// The locus of `v`, in the body frame.
    #[inline]
    pub fn position(&self, v: VertexId) -> DVec3 {
        self.vertices.get(v.index()).pos
    }
    /// Moves vertex `v` to `pos` (body frame). Topology is unchanged.
    #[inline]
    pub fn set_position(&mut self, v: VertexId, pos: DVec3) {
        self.vertices.get_mut(v.index()).pos = pos;
    }

    #[inline]
    pub(crate) fn edge_mut(&mut self, e: EdgeId) -> &mut Edge {
        self.edges.get_mut(e.index())
    }
    #[inline]
    pub(crate) fn face_mut(&mut self, f: FaceId) -> &mut Face {
        self.faces.get_mut(f.index())
    }
    #[inline]
    pub(crate) fn vertex_mut(&mut self, v: VertexId) -> &mut Vertex {
        self.vertices.get_mut(v.index())
    }

    /// Serial number of a face ([`Serial::NONE`] if dead).
    #[inline]
    pub fn face_serial(&self, f: FaceId) -> Serial {
        self.faces.serial(f.index())
    }
    /// Serial number of an edge ([`Serial::NONE`] if dead).
    #[inline]
    pub fn edge_serial(&self, e: EdgeId) -> Serial {
        self.edges.serial(e.index())
    }
    /// Serial number of a vertex ([`Serial::NONE`] if dead).
    #[inline]
    pub fn vertex_serial(&self, v: VertexId) -> Serial {
        self.vertices.serial(v.index())
    }

    /// The live face with this serial number, if it is in this body.
    pub fn face_by_serial(&self, s: Serial) -> Option<FaceId> {
        self.faces.find(s).map(FaceId::from_index)
    }
    /// The live edge with this serial number, if it is in this body.
    pub fn edge_by_serial(&self, s: Serial) -> Option<EdgeId> {
        self.edges.find(s).map(EdgeId::from_index)
    }
    /// The live vertex with this serial number, if it is in this body.
    pub fn vertex_by_serial(&self, s: Serial) -> Option<VertexId> {
        self.vertices.find(s).map(VertexId::from_index)
    }

    /// A range holding the serial of every live vertex of this body (and maybe others):
    /// a cheap test that a serial cannot be one of its vertices. `None` without vertices.
    pub fn vertex_serial_bounds(&self) -> Option<(Serial, Serial)> {
        self.vertices.serial_bounds()
    }

    /// Bytes of heap held by the three arenas (capacity), for memory accounting.
    pub fn heap_bytes(&self) -> usize {
        self.faces.heap_bytes() + self.edges.heap_bytes() + self.vertices.heap_bytes()
    }

    // ---- node makers and killers (Baumgart's MKF/MKE/MKV, KLF/KLE/KLV) ----
    //
    // These are the raw allocation routines under the Euler operators: they do not keep
    // any invariant by themselves.

    /// MKF: a new face with PED `ped`.
    #[inline]
    pub(crate) fn mkf(&mut self, serials: &mut Serials, ped: EdgeId) -> FaceId {
        FaceId(self.faces.insert(Face { ped }, serials.take()))
    }
    /// MKV: a new vertex at `pos` with PED `ped`.
    #[inline]
    pub(crate) fn mkv(&mut self, serials: &mut Serials, pos: DVec3, ped: EdgeId) -> VertexId {
        VertexId(self.vertices.insert(Vertex { pos, ped }, serials.take()))
    }
    /// MKE: a new edge with the given record.
    #[inline]
    pub(crate) fn mke(&mut self, serials: &mut Serials, edge: Edge) -> EdgeId {
        EdgeId(self.edges.insert(edge, serials.take()))
    }
    /// KLF.
    #[inline]
    pub(crate) fn klf(&mut self, f: FaceId) {
        self.faces.remove(f.index());
    }
    /// KLE.
    #[inline]
    pub(crate) fn kle(&mut self, e: EdgeId) {
        self.edges.remove(e.index());
    }
    /// KLV.
    #[inline]
    pub(crate) fn klv(&mut self, v: VertexId) {
        self.vertices.remove(v.index());
    }

    /// Inserts a face with a given serial (used when moving entities between bodies).
    pub(crate) fn insert_face_with_serial(&mut self, face: Face, s: Serial) -> FaceId {
        FaceId(self.faces.insert(face, s))
    }
    /// Inserts a vertex with a given serial (used when moving entities between bodies).
    pub(crate) fn insert_vertex_with_serial(&mut self, v: Vertex, s: Serial) -> VertexId {
        VertexId(self.vertices.insert(v, s))
    }

    /// Reserves room for `f` more faces, `e` edges and `v` vertices.
    pub fn reserve(&mut self, f: usize, e: usize, v: usize) {
        self.faces.reserve(f);
        self.edges.reserve(e);
        self.vertices.reserve(v);
    }

    /// Whether edge `e` runs between vertices `a` and `b` (either direction).
    #[inline]
    pub fn edge_joins(&self, e: EdgeId, a: VertexId, b: VertexId) -> bool {
        let r = self.edge(e);
        (r.vt[0] == a && r.vt[1] == b) || (r.vt[0] == b && r.vt[1] == a)
    }

    /// The side of `e` whose vertex is `v` (`vt[side] == v`). Precondition: `v` is an
    /// end of `e`.
    #[inline]
    pub fn side_at(&self, e: EdgeId, v: VertexId) -> Side {
        if self.edge(e).vt[1] == v {
            Side::P
        } else {
            Side::N
        }
    }
}
