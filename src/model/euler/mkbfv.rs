//! MKBFV: make a seminal body, one face and one vertex.

use glam::DVec3;

use crate::model::body::{Body, Face, Vertex};
use crate::model::ids::{EdgeId, FaceId, Serials, VertexId};

impl Body {
    /// MKBFV: a new seminal body of one face and one vertex at `pos`, and no edges
    /// (F − E + V = 2, B = 1): the point polyhedron every Euler construction starts from.
    ///
    /// Postcondition: the face and vertex have PED = [`EdgeId::NONE`]. The world's
    /// KLBFEV is its inverse.
    pub fn seminal(serials: &mut Serials, pos: DVec3) -> (Body, FaceId, VertexId) {
        let mut b = Body::empty();
        let f = b.insert_face_with_serial(Face { ped: EdgeId::NONE }, serials.take());
        let v = b.insert_vertex_with_serial(
            Vertex {
                pos,
                ped: EdgeId::NONE,
            },
            serials.take(),
        );
        (b, f, v)
    }
}
