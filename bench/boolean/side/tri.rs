//! Cutting planar faces into triangles for manifold3d: a fan for convex faces, the
//! `earcut` ear clipper (as the renderer uses) for concave ones.

use glam::{DVec2, DVec3};

use super::off::Mesh;

/// The mesh with every face cut into triangles wound like the face.
pub fn triangulate(mesh: &Mesh) -> Mesh {
    let mut ear = earcut::Earcut::new();
    let mut out = Mesh {
        positions: mesh.positions.clone(),
        faces: Vec::with_capacity(mesh.triangle_count()),
    };
    let mut flat: Vec<[f64; 2]> = Vec::new();
    let mut idx: Vec<u32> = Vec::new();
    for ring in &mesh.faces {
        if ring.len() == 3 {
            out.faces.push(ring.clone());
            continue;
        }
        let points: Vec<DVec3> = ring.iter().map(|&i| mesh.positions[i as usize]).collect();
        let mut normal = DVec3::ZERO;
        for (k, &p) in points.iter().enumerate() {
            normal += p.cross(points[(k + 1) % points.len()]);
        }
        let (u, v) = normal.normalize_or(DVec3::Z).any_orthonormal_pair();
        flat.clear();
        flat.extend(points.iter().map(|p| [p.dot(u), p.dot(v)]));
        if convex(&flat) {
            out.faces
                .extend((1..ring.len() - 1).map(|i| vec![ring[0], ring[i], ring[i + 1]]));
            continue;
        }
        idx.clear();
        ear.earcut(flat.iter().copied(), &[] as &[u32], &mut idx);
        for t in idx.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| i as usize);
            let (pa, pb, pc) = (
                DVec2::from(flat[a]),
                DVec2::from(flat[b]),
                DVec2::from(flat[c]),
            );
            let tri = if (pb - pa).perp_dot(pc - pa) > 0.0 {
                [a, b, c]
            } else {
                [a, c, b]
            };
            out.faces.push(tri.iter().map(|&i| ring[i]).collect());
        }
    }
    out
}

/// Whether a counter-clockwise polygon turns left at every corner.
fn convex(poly: &[[f64; 2]]) -> bool {
    let n = poly.len();
    (0..n).all(|i| {
        let (a, b, c) = (
            DVec2::from(poly[i]),
            DVec2::from(poly[(i + 1) % n]),
            DVec2::from(poly[(i + 2) % n]),
        );
        (b - a).perp_dot(c - b) > 0.0
    })
}
