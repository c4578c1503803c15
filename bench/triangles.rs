//! Planar polygon faces cut into triangles for the peers that take triangles only
//! (manifold3d): a fan for convex faces, the `earcut` ear clipper (as the renderer uses)
//! in the face's plane otherwise.

use glam::{DVec2, DVec3};

/// The faces (rings of indices into `positions`) of a closed mesh cut into triangles wound like them: a fan for convex
/// faces, the `earcut` ear clipper in the face's plane otherwise.
pub fn triangles(positions: &[DVec3], faces: &[Vec<u32>]) -> Vec<[u32; 3]> {
    let mut ear = earcut::Earcut::new();
    let mut out = Vec::new();
    let mut flat: Vec<[f64; 2]> = Vec::new();
    let mut idx: Vec<u32> = Vec::new();
    for ring in faces {
        let points: Vec<DVec3> = ring.iter().map(|&i| positions[i as usize]).collect();
        let mut normal = DVec3::ZERO;
        for (k, &p) in points.iter().enumerate() {
            normal += p.cross(points[(k + 1) % points.len()]);
        }
        let (u, v) = normal.normalize_or(DVec3::Z).any_orthonormal_pair();
        flat.clear();
        flat.extend(points.iter().map(|p| [p.dot(u), p.dot(v)]));
        let n = flat.len();
        let convex = (0..n).all(|i| {
            let (a, b, c) = (
                DVec2::from(flat[i]),
                DVec2::from(flat[(i + 1) % n]),
                DVec2::from(flat[(i + 2) % n]),
            );
            (b - a).perp_dot(c - b) > 0.0
        });
        if convex {
            out.extend((1..n - 1).map(|i| [ring[0], ring[i], ring[i + 1]]));
            continue;
        }
        idx.clear();
        ear.earcut(flat.iter().copied(), &[] as &[u32], &mut idx);
        // The ear clipper winds all its triangles one way: keep it if it is the ring's
        // (summed, so that triangles of no area cannot mislead).
        let area = |[a, b, c]: [usize; 3]| {
            (DVec2::from(flat[b]) - DVec2::from(flat[a]))
                .perp_dot(DVec2::from(flat[c]) - DVec2::from(flat[a]))
        };
        let ring_area: f64 = (0..n)
            .map(|i| DVec2::from(flat[i]).perp_dot(DVec2::from(flat[(i + 1) % n])))
            .sum();
        let tris: Vec<[usize; 3]> = idx
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]].map(|i| i as usize))
            .collect();
        let same = tris.iter().map(|&t| area(t)).sum::<f64>() * ring_area > 0.0;
        for [a, b, c] in tris {
            let tri = if same { [a, b, c] } else { [a, c, b] };
            out.push(tri.map(|i| ring[i]));
        }
    }
    out
}
