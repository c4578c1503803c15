//! Cutting planar faces into triangles for manifold3d (see `bench/triangles.rs`).

use super::off::Mesh;
use super::triangles::triangles;

/// The mesh with every face cut into triangles wound like the face.
pub fn triangulate(mesh: &Mesh) -> Mesh {
    Mesh {
        positions: mesh.positions.clone(),
        faces: triangles(&mesh.positions, &mesh.faces)
            .into_iter()
            .map(|t| t.to_vec())
            .collect(),
    }
}
