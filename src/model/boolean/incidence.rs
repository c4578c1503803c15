//! What the points' definitions give without arithmetic on constructed points: a
//! coordinate fixed by an axis-aligned plane or line, a point in a plane, three points on
//! a line, four points in a plane (the last three decided with exact orientations of
//! input points alone).
//!
//! A predicate on constructed points that is exactly zero defeats every filter and costs
//! an evaluation in exact arithmetic; it is common (points made in the quad faces of a
//! box, on the line where two faces meet). These tests are tried first, where the filters
//! gave up: each answer `true` is a proof that the predicate is zero, and `false` only
//! means "not known", so the exact evaluation still has the last word.

use super::point::{Def, Pid, Points};

impl Points {
    /// Coordinate `k` of the point `def` defines, when its definition alone gives it
    /// exactly: an input point's; a point on a line or in a plane whose defining input
    /// points share that coordinate; a mixture of points that share it.
    pub(crate) fn known(&self, def: Def, k: usize) -> Option<f64> {
        let shared = |ps: &[Pid]| {
            let c = self.input_at(ps[0])[k];
            ps[1..]
                .iter()
                .all(|&q| self.input_at(q)[k] == c)
                .then_some(c)
        };
        match def {
            Def::Input(i) => Some(self.input[i as usize][k]),
            Def::Lpi { line, plane } => shared(&plane).or_else(|| shared(&line)),
            Def::Ssi { a, b, .. } => shared(&a).or_else(|| shared(&b)),
            Def::Mix { p, .. } => {
                let c = self.known(self.defs[p[0] as usize], k)?;
                p[1..]
                    .iter()
                    .all(|&q| self.known(self.defs[q as usize], k) == Some(c))
                    .then_some(c)
            }
        }
    }

    /// Whether the exact orientation of input points `tri` and input point `q` is zero.
    fn input_on(&self, tri: [Pid; 3], q: Pid) -> bool {
        tri.contains(&q) || self.side(tri, q) == 0
    }

    /// Whether the planes through input points `a` and `b` are one plane (precondition:
    /// `b` is not collinear, which holds for every triangle of a mesh).
    fn same_plane(&self, a: [Pid; 3], b: [Pid; 3]) -> bool {
        b.iter().all(|&q| self.input_on(a, q))
    }

    /// Whether point `p` is known to lie in the plane through input points `tri`
    /// (precondition: `tri` is not collinear). `false` means "not known".
    pub(crate) fn known_on_plane(&self, p: Pid, tri: [Pid; 3]) -> bool {
        match self.defs[p as usize] {
            Def::Input(_) => self.input_on(tri, p),
            Def::Lpi { line, plane } => {
                self.same_plane(tri, plane) || line.iter().all(|&q| self.input_on(tri, q))
            }
            Def::Ssi { a, b, .. } => {
                a.iter().all(|&q| self.input_on(tri, q)) || b.iter().all(|&q| self.input_on(tri, q))
            }
            Def::Mix { p, .. } => p.iter().all(|&q| self.known_on_plane(q, tri)),
        }
    }

    /// The planes the definitions of `points` name (a line–plane point's plane).
    fn named_planes(&self, points: &[Pid]) -> Vec<[Pid; 3]> {
        let mut planes: Vec<[Pid; 3]> = Vec::with_capacity(points.len());
        for &p in points {
            if let Def::Lpi { plane, .. } = self.defs[p as usize]
                && !planes.contains(&plane)
            {
                planes.push(plane);
            }
        }
        planes
    }

    /// Whether the three points are known to lie on one line: all on one defining line,
    /// or all in two different planes that their definitions name.
    pub(crate) fn known_collinear(&self, p: [Pid; 3]) -> bool {
        let on_line = |line: [Pid; 2], q: Pid| {
            line.contains(&q)
                || matches!(self.defs[q as usize], Def::Lpi { line: l, .. } if same_line(l, line))
        };
        for &x in &p {
            if let Def::Lpi { line, .. } = self.defs[x as usize]
                && p.iter().all(|&q| on_line(line, q))
            {
                return true;
            }
        }
        let planes: Vec<[Pid; 3]> = self
            .named_planes(&p)
            .into_iter()
            .filter(|&plane| p.iter().all(|&q| self.known_on_plane(q, plane)))
            .collect();
        // Two planes both holding the points, not one plane twice: they meet in a line.
        planes
            .iter()
            .enumerate()
            .any(|(i, &a)| planes[i + 1..].iter().any(|&b| !self.same_plane(a, b)))
    }

    /// Whether the four points are known to lie in one plane that a definition names.
    pub(crate) fn known_coplanar(&self, p: [Pid; 4]) -> bool {
        self.named_planes(&p)
            .into_iter()
            .any(|plane| p.iter().all(|&q| self.known_on_plane(q, plane)))
    }
}

/// Whether two segments of input points name one line by the same two points.
fn same_line(a: [Pid; 2], b: [Pid; 2]) -> bool {
    a == b || a == [b[1], b[0]]
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    /// The points made where the quad faces of a turned box meet a plane are known in
    /// their faces and on the lines where those faces meet; a point off them is not.
    #[test]
    fn points_in_quads_are_known_collinear_and_coplanar() {
        let mut p = Points::default();
        // A quad face z = 0 (two triangles 0 1 2 and 0 2 3) and a plane x = 0.25 (4 5 6).
        for x in [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.25, -1.0, -1.0),
            DVec3::new(0.25, 2.0, -1.0),
            DVec3::new(0.25, 0.5, 1.0),
        ] {
            p.add_input(x);
        }
        // Where the plane x = 0.25 meets the quad's sides 0–1 and 3–2, and where the
        // quad's plane (by its other triangle) meets the edge 4–6 of the plane's triangle.
        let a = p.add(Def::Lpi {
            line: [0, 1],
            plane: [4, 5, 6],
        });
        let b = p.add(Def::Lpi {
            line: [3, 2],
            plane: [4, 5, 6],
        });
        let c = p.add(Def::Lpi {
            line: [4, 6],
            plane: [0, 2, 3],
        });
        // a = (0.25, 0, 0): x and z fixed by the plane x = 0.25 and the line along z = 0.
        assert_eq!(p.known(p.defs[a as usize], 0), Some(0.25));
        assert_eq!(p.known(p.defs[a as usize], 2), Some(0.0));
        assert_eq!(p.known(p.defs[c as usize], 1), None);
        assert!(p.known_on_plane(a, [0, 1, 2]));
        assert!(p.known_on_plane(c, [0, 1, 2]));
        assert!(p.known_collinear([a, b, c]));
        assert_eq!(p.orient2d(2, [a, b, c]), 0);
        assert!(p.known_coplanar([a, b, c, 1]));
        // Corner 2 is in the quad's plane but not on the line a–b; corner 5 is in the
        // plane x = 0.25 but not in the quad's.
        assert!(!p.known_collinear([a, b, 2]));
        assert_ne!(p.orient2d(2, [a, b, 2]), 0);
        assert!(!p.known_on_plane(5, [0, 1, 2]));
    }
}
