//! Safe rounding: the kept pieces, their loci rounded to f64, cleared of the features
//! narrower than the rounding can keep.
//!
//! The exact result is right, but where the operands nearly coincide (a face turned by
//! 1e-12°, a vertex 1e-16 m off another's plane) it holds edges and triangles far
//! narrower than the distance between neighbouring f64 values. Rounded, such a triangle
//! may flatten to a segment or turn over, and a face made of such pieces has no plane.
//! So, on the rounded triangles, before they merge into polygons:
//!
//! - an edge no longer than `eps` **collapses**: its second end is replaced by its first
//!   wherever it is used, and the two triangles on the edge disappear;
//! - a triangle whose corner lies within `eps` of the line through its longest edge
//!   (a *cap*) has that edge **flipped** with the triangle across it: the two new
//!   triangles lie, within `eps`, in the neighbour's plane and take its source.
//!
//! Neither moves a vertex, so every vertex stays within a few `eps` of the plane of each
//! face it ends up in. An operation that would break the surface (a collapse whose ends
//! share a neighbour besides the two triangles' third corners, a flip onto an edge that
//! exists) is skipped. Shells thinner than `eps` (volume over area) are dropped by
//! [`thin`].
//!
//! `eps` is [`EPS_ULPS`] units in the last place of the largest coordinate: far below the
//! kernel's planarity tolerance, far above the rounding error of a locus.

use glam::DVec3;

use super::Source;

/// The width below which a feature is cleared, in units in the last place of the
/// largest coordinate magnitude (2⁸ ulps, about 5.7e-14 of that magnitude).
pub(crate) const EPS_ULPS: f64 = 256.0;

/// How many sweeps over the triangles are made at most; each sweep that changes
/// nothing ends the cleaning early.
const MAX_SWEEPS: usize = 16;

const DEAD: u32 = u32::MAX;

/// A closed triangle mesh under cleaning. Half-edge `h` is corner `h % 3` of triangle
/// `h / 3` and runs from that corner to the next.
pub(crate) struct Tris {
    /// The vertex at each corner.
    pub corner: Vec<u32>,
    /// The opposite half-edge of each half-edge.
    pub twin: Vec<u32>,
    /// The input face of each triangle.
    pub source: Vec<Source>,
    /// Whether each triangle is still part of the surface.
    pub alive: Vec<bool>,
}

/// The half-edge after `h` in its triangle.
#[inline]
pub(crate) fn next(h: usize) -> usize {
    h - h % 3 + (h % 3 + 1) % 3
}

/// The half-edge before `h` in its triangle.
#[inline]
pub(crate) fn prev(h: usize) -> usize {
    h - h % 3 + (h % 3 + 2) % 3
}

/// The clearing width for loci `pos`.
pub(crate) fn eps_for(pos: &[DVec3]) -> f64 {
    let m = pos
        .iter()
        .map(|p| p.abs().max_element())
        .fold(f64::MIN_POSITIVE, f64::max);
    m * f64::EPSILON * 0.5 * EPS_ULPS
}

impl Tris {
    fn from(&self, h: usize) -> u32 {
        self.corner[h]
    }

    fn to(&self, h: usize) -> u32 {
        self.corner[next(h)]
    }

    /// The half-edges leaving the origin of `h`, starting with `h`; `None` if the walk
    /// about the vertex does not close (the surface is not a disc there).
    fn fan(&self, h: usize) -> Option<Vec<usize>> {
        let mut out = vec![h];
        let mut g = self.twin[prev(h)] as usize;
        while g != h {
            if out.len() > self.corner.len() || g == DEAD as usize {
                return None;
            }
            out.push(g);
            g = self.twin[prev(g)] as usize;
        }
        Some(out)
    }

    /// Collapses the edge of half-edge `h` (from `a` to `b`) onto `a`, unless that would
    /// break the surface. Returns whether it did.
    fn collapse(&mut self, h: usize) -> bool {
        let g = self.twin[h] as usize;
        let (a, b) = (self.from(h), self.to(h));
        let (c0, c1) = (self.from(prev(h)), self.from(prev(g)));
        if a == b || c0 == c1 {
            return false;
        }
        let (Some(fan_a), Some(fan_b)) = (self.fan(h), self.fan(g)) else {
            return false;
        };
        let around_a: Vec<u32> = fan_a.iter().map(|&x| self.to(x)).collect();
        let around_b: Vec<u32> = fan_b.iter().map(|&x| self.to(x)).collect();
        // The link condition: a and b share no neighbour but c0 and c1.
        let shared = around_a.iter().filter(|v| around_b.contains(v)).count();
        if shared != 2 {
            return false;
        }
        // c0 and c1 each lose an edge; they must keep three.
        for c in [prev(h), prev(g)] {
            match self.fan(c) {
                Some(f) if f.len() >= 4 => {}
                _ => return false,
            }
        }
        for &x in &fan_b {
            self.corner[x] = a;
        }
        for k in [h, g] {
            let (x, y) = (self.twin[next(k)], self.twin[prev(k)]);
            self.twin[x as usize] = y;
            self.twin[y as usize] = x;
            let t = k / 3;
            self.alive[t] = false;
            for j in 0..3 {
                self.twin[3 * t + j] = DEAD;
            }
        }
        true
    }

    /// Flips the edge of half-edge `h` (from `a` to `b`, in the cap `a b c`) with the
    /// triangle `b a d` across it, into `c a d` and `d b c`, both of that triangle's
    /// source. Returns whether it did.
    fn flip(&mut self, h: usize) -> bool {
        let g = self.twin[h] as usize;
        let (a, b, c) = (self.from(h), self.to(h), self.from(prev(h)));
        let d = self.from(prev(g));
        if c == d || a == b {
            return false;
        }
        let Some(fan_c) = self.fan(prev(h)) else {
            return false;
        };
        if fan_c.iter().any(|&x| self.to(x) == d) {
            return false; // the edge c d exists
        }
        let (t0, t1) = (h / 3, g / 3);
        let (x1, x2) = (self.twin[prev(h)], self.twin[next(g)]); // c→a, a→d
        let (x3, x4) = (self.twin[prev(g)], self.twin[next(h)]); // d→b, b→c
        let (s0, s1) = (3 * t0, 3 * t1);
        self.corner[s0..s0 + 3].copy_from_slice(&[c, a, d]);
        self.corner[s1..s1 + 3].copy_from_slice(&[d, b, c]);
        for (k, x) in [(s0, x1), (s0 + 1, x2), (s1, x3), (s1 + 1, x4)] {
            self.twin[k] = x;
            self.twin[x as usize] = k as u32;
        }
        self.twin[s0 + 2] = (s1 + 2) as u32;
        self.twin[s1 + 2] = (s0 + 2) as u32;
        self.source[t0] = self.source[t1];
        true
    }

    /// Clears the edges no longer than `eps` and the caps narrower than `eps`, sweep
    /// after sweep, until a sweep changes nothing (at most [`MAX_SWEEPS`]).
    pub(crate) fn clean(&mut self, pos: &[DVec3], eps: f64) {
        let at = |v: u32| pos[v as usize];
        for _ in 0..MAX_SWEEPS {
            let mut changed = false;
            for h in 0..self.corner.len() {
                if self.alive[h / 3]
                    && at(self.from(h)).distance(at(self.to(h))) <= eps
                    && self.collapse(h)
                {
                    changed = true;
                }
            }
            for t in 0..self.alive.len() {
                if !self.alive[t] {
                    continue;
                }
                let s = 3 * t;
                // The longest edge and the corner across it.
                let h = (s..s + 3)
                    .max_by(|&x, &y| {
                        let lx = at(self.from(x)).distance_squared(at(self.to(x)));
                        let ly = at(self.from(y)).distance_squared(at(self.to(y)));
                        lx.total_cmp(&ly)
                    })
                    .unwrap_or(s);
                let (a, b, c) = (at(self.from(h)), at(self.to(h)), at(self.from(prev(h))));
                let ab = b - a;
                let len = ab.length();
                if len > eps && ab.cross(c - a).length() <= eps * len && self.flip(h) {
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
    }
}

/// Whether the shell of faces `faces` over `pos` is thinner than `eps`: a sheet (its
/// volume no more than `eps` times its area) or a needle (its area no more than `eps`
/// times its diameter). Such a shell is what rounding leaves of a piece of the exact
/// result narrower than the f64 grid. Volume and area are summed about one of the
/// shell's own vertices, so that a tiny shell far from the origin is measured at its
/// own scale.
pub(crate) fn thin(pos: &[DVec3], faces: &[Vec<u32>], eps: f64) -> bool {
    let Some(&o) = pos.first() else {
        return true;
    };
    let (mut area, mut six_volume) = (0.0, 0.0);
    for f in faces {
        let a = pos[f[0] as usize] - o;
        let mut n = DVec3::ZERO;
        for k in 1..f.len().saturating_sub(1) {
            let (b, c) = (pos[f[k] as usize] - o, pos[f[k + 1] as usize] - o);
            n += (b - a).cross(c - a);
            six_volume += a.dot(b.cross(c));
        }
        area += n.length() * 0.5;
    }
    let (lo, hi) = pos.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let diameter = (hi - lo).length();
    six_volume.abs() / 6.0 <= eps * area || area <= eps * diameter
}
