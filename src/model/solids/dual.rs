//! FVDUAL: the face–vertex dual of a body, in place.

use glam::DVec3;

use super::error::{SolidError, positive};
use crate::model::arena::Arena;
use crate::model::body::{Body, Edge, Face, Vertex};
use crate::model::ids::{EdgeId, FaceId, VertexId};

/// Where FVDUAL puts the vertex made from each face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DualLocus {
    /// At the face's centre (the mean of its perimeter vertices), as WINGED.DOC does.
    /// The dual of a regular solid is regular; the faces of other duals need not be
    /// planar.
    FaceCenter,
    /// At the pole of the face's plane with respect to the sphere of `radius` about
    /// `center`: the plane at distance `d` from the centre along unit normal `n` becomes
    /// the vertex `center + n·radius²/d`. For a convex body with the centre inside,
    /// the dual is convex with planar faces, and the polar dual of the polar dual is
    /// the original body again (within rounding).
    Polar {
        /// The centre of reciprocation; it must lie strictly inside every face plane.
        center: DVec3,
        /// The radius of the sphere of reciprocation.
        radius: f64,
    },
}

impl Body {
    /// FVDUAL(B) with vertices at the face centres: [`Body::fvdual_with`]`(`
    /// [`DualLocus::FaceCenter`]`)`.
    pub fn fvdual(&mut self) -> Result<(), SolidError> {
        self.fvdual_with(DualLocus::FaceCenter)
    }

    /// FVDUAL(B): turns every face into a vertex and every vertex into a face, in place.
    ///
    /// As WINGED.DOC puts it, this computes a locus for each face, re-types faces and
    /// vertices, and swaps the face and vertex links of every edge. Edge `e` keeps its
    /// slot and serial; its dual crosses it, running from the vertex made from its
    /// NFACE to the one made from its PFACE, with the faces made from its old PVT on
    /// the left (new NFACE) and from its old NVT on the right (new PFACE). Its wings
    /// follow: new NCCW = old PCW, new PCCW = old NCW, new NCW = old NCCW, new PCW = old
    /// PCCW. So the counter-clockwise order of faces about a vertex becomes the
    /// counter-clockwise perimeter of its dual face.
    ///
    /// Serial numbers: no entity is made or killed and no serial is taken. The vertex
    /// made from a face carries that face's serial, and the face made from a vertex
    /// carries that vertex's serial (serials are unique across kinds in a world, so
    /// they stay unique). Slots are packed: in a body with no dead slots, face `f`
    /// becomes vertex slot `f.index()` and vertex `v` face slot `v.index()`. PEDs carry
    /// over (the dual vertex's PED is the face's PED, and the reverse).
    ///
    /// F and V swap, E and H are unchanged, so F − E + V is kept. FVDUAL twice gives
    /// the original topology with every edge inverted (its N and P sides exchanged,
    /// as [`Body::invert`] does), every entity back under its own serial.
    ///
    /// Preconditions (refused otherwise, before any change): no edge has the same face
    /// on both sides (a wire or a spur, whose dual would be a loop); for
    /// [`DualLocus::Polar`], a finite centre and positive radius, every face of non-zero
    /// area with the centre strictly inside its plane, every pole within the world's
    /// range. Face centres lie within the bounding box of the body's loci, so the dual
    /// at [`DualLocus::FaceCenter`] of a body in range is in range.
    ///
    /// A seminal body (one face, one vertex, no edges) keeps its vertex locus.
    pub fn fvdual_with(&mut self, locus: DualLocus) -> Result<(), SolidError> {
        // Plan: every check, and the new loci.
        for e in self.edges() {
            let r = self.edge(e);
            if r.face[0] == r.face[1] {
                return Err(SolidError::DualLoop {
                    edge: self.edge_serial(e),
                    face: self.face_serial(r.face[0]),
                });
            }
        }
        let loci: Vec<DVec3> = if self.edge_count() == 0 {
            let p = self
                .vertices()
                .next()
                .map_or(DVec3::ZERO, |v| self.position(v));
            self.faces().map(|_| p).collect()
        } else {
            match locus {
                DualLocus::FaceCenter => self.faces().map(|f| self.face_center(f)).collect(),
                DualLocus::Polar { center, radius } => {
                    if !center.is_finite() {
                        return Err(SolidError::NotFinite {
                            parameter: "center",
                        });
                    }
                    let r2 = positive("radius", radius)?.powi(2);
                    let mut loci = Vec::with_capacity(self.face_count());
                    for f in self.faces() {
                        let plane = self.face_plane(f).ok_or(SolidError::DegenerateFace {
                            face: self.face_serial(f),
                        })?;
                        let d = -plane.distance(center);
                        let p = center + plane.normal * (r2 / d);
                        if !(d > 0.0 && p.is_finite()) {
                            return Err(SolidError::PolarCenter {
                                face: self.face_serial(f),
                                distance: d,
                            });
                        }
                        crate::model::range::coordinate("a polar dual vertex", p)?;
                        loci.push(p);
                    }
                    loci
                }
            }
        };

        // Apply: build the re-typed arenas, then relink every edge.
        let mut faces = Arena::<Face>::default();
        let mut vertices = Arena::<Vertex>::default();
        faces.reserve(self.vertex_count());
        vertices.reserve(self.face_count());
        let mut face_of_vertex = vec![FaceId::NONE; self.vertices.slots()];
        let mut vertex_of_face = vec![VertexId::NONE; self.faces.slots()];
        for v in self.vertices() {
            let slot = faces.insert_unsorted(
                Face {
                    ped: self.vertex(v).ped,
                },
                self.vertex_serial(v),
            );
            face_of_vertex[v.index()] = FaceId(slot);
        }
        for (f, pos) in self.faces().zip(loci) {
            let slot = vertices.insert_unsorted(
                Vertex {
                    pos,
                    ped: self.face(f).ped,
                },
                self.face_serial(f),
            );
            vertex_of_face[f.index()] = VertexId(slot);
        }
        faces.resort_index();
        vertices.resort_index();
        let edges: Vec<EdgeId> = self.edges().collect();
        for e in edges {
            let r = *self.edge(e);
            *self.edge_mut(e) = Edge {
                vt: [
                    vertex_of_face[r.face[0].index()],
                    vertex_of_face[r.face[1].index()],
                ],
                face: [
                    face_of_vertex[r.vt[1].index()],
                    face_of_vertex[r.vt[0].index()],
                ],
                cw: [r.ccw[0], r.ccw[1]],
                ccw: [r.cw[1], r.cw[0]],
            };
        }
        self.faces = faces;
        self.vertices = vertices;
        Ok(())
    }
}
