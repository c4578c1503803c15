//! Triangles of one planar polygon face, for the renderer and the mesh writers.

use glam::{DVec2, DVec3};

/// Cuts planar faces into triangles of their own corners: a strictly convex face into a
/// fan, any other into the triangles of georust's port of mapbox's ear clipper (the
/// `earcut` crate), which takes concave faces with any number of sides. Keeps its
/// buffers between faces.
pub struct FaceTriangulator {
    ear: earcut::Earcut<f64>,
    flat: Vec<[f64; 2]>,
    idx: Vec<u32>,
}

impl Default for FaceTriangulator {
    fn default() -> Self {
        Self::new()
    }
}

impl FaceTriangulator {
    /// A triangulator with empty buffers.
    pub fn new() -> Self {
        FaceTriangulator {
            ear: earcut::Earcut::new(),
            flat: Vec::new(),
            idx: Vec::new(),
        }
    }

    /// Replaces `out` with the triangles of the face whose corners (indices into
    /// `points`) run counter-clockwise about `normal`.
    ///
    /// Precondition: `normal` is not zero and the corners lie near one plane across it.
    /// Postcondition: each triangle is three of the face's corners, wound like the face
    /// (counter-clockwise about `normal`); a face of `n` corners gives `n − 2` triangles
    /// when the ear clipper succeeds (it gives fewer for a face that is not simple).
    pub fn triangulate(
        &mut self,
        points: &[DVec3],
        corners: &[u32],
        normal: DVec3,
        out: &mut Vec<[u32; 3]>,
    ) {
        out.clear();
        // Coordinates in the face's plane, right-handed about the normal.
        let (u, v) = normal.any_orthonormal_pair();
        self.flat.clear();
        self.flat.extend(corners.iter().map(|&c| {
            let p = points[c as usize];
            [p.dot(u), p.dot(v)]
        }));
        if is_convex(&self.flat) {
            out.extend((1..corners.len() - 1).map(|i| [corners[0], corners[i], corners[i + 1]]));
            return;
        }
        self.idx.clear();
        self.ear
            .earcut(self.flat.iter().copied(), &[] as &[u32], &mut self.idx);
        for t in self.idx.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| i as usize);
            let (pa, pb, pc) = (
                DVec2::from(self.flat[a]),
                DVec2::from(self.flat[b]),
                DVec2::from(self.flat[c]),
            );
            let ccw = (pb - pa).perp_dot(pc - pa) > 0.0;
            let tri = if ccw { [a, b, c] } else { [a, c, b] };
            out.push(tri.map(|i| corners[i]));
        }
    }
}

/// Whether a polygon (in the plane, counter-clockwise) is strictly convex: every turn is
/// to the left and it winds once. Repeated corners (bridge edges) make it not convex.
fn is_convex(poly: &[[f64; 2]]) -> bool {
    let n = poly.len();
    let mut turning = 0.0;
    for i in 0..n {
        let a = DVec2::from(poly[i]);
        let b = DVec2::from(poly[(i + 1) % n]);
        let c = DVec2::from(poly[(i + 2) % n]);
        let (d1, d2) = (b - a, c - b);
        if d1.perp_dot(d2) <= 0.0 {
            return false;
        }
        turning += d1.perp_dot(d2).atan2(d1.dot(d2));
    }
    (turning - std::f64::consts::TAU).abs() < 1e-6
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_l_shaped_face_gives_four_triangles_wound_like_it() {
        let points: Vec<DVec3> = [[0., 0.], [2., 0.], [2., 1.], [1., 1.], [1., 2.], [0., 2.]]
            .iter()
            .map(|&[x, y]| DVec3::new(x, y, 0.0))
            .collect();
        let corners: Vec<u32> = (0..6).collect();
        let mut out = Vec::new();
        FaceTriangulator::new().triangulate(&points, &corners, DVec3::Z, &mut out);
        assert_eq!(out.len(), 4);
        let mut area = 0.0;
        for t in &out {
            let [a, b, c] = t.map(|i| points[i as usize]);
            let z = (b - a).cross(c - a).z;
            assert!(z > 0.0, "{t:?} is wound clockwise");
            area += z / 2.0;
        }
        assert!((area - 3.0).abs() < 1e-12, "area {area}");
    }
}
