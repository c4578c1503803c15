//! Geometry derived from vertex loci: face planes (Newell's method), edge line
//! coefficients, areas, volume, centroid, bounds and convexity.
//!
//! Everything here is computed on demand in the body's own frame; nothing is cached, so
//! moving a vertex can never leave a stale plane behind.

use glam::{DVec2, DVec3};

use super::body::Body;
use super::ids::{EdgeId, FaceId};

/// A plane `normal · x = offset` with a unit `normal` (Baumgart's AA, BB, CC and KK).
/// For a face, the normal points out of the solid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Unit normal (AA, BB, CC).
    pub normal: DVec3,
    /// Distance of the plane from the origin along the normal (KK).
    pub offset: f64,
}

impl Plane {
    /// Signed distance of `p` from the plane: positive above (outside), negative below.
    #[inline]
    pub fn distance(&self, p: DVec3) -> f64 {
        self.normal.dot(p) - self.offset
    }
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Smallest corner.
    pub min: DVec3,
    /// Largest corner.
    pub max: DVec3,
}

impl Bounds {
    /// The box's centre.
    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }
    /// The length of its diagonal.
    pub fn diagonal(&self) -> f64 {
        (self.max - self.min).length()
    }
}

/// 2D line coefficients `aa·x + bb·y + cc = 0` of the line through `p1` and `p2`,
/// normalised so that `aa·x + bb·y + cc` is the signed distance of a point from the line,
/// positive on the left of a walker going from `p1` to `p2` (Baumgart's edge AA, BB, CC).
/// `None` when the points coincide.
pub fn line_coefficients(p1: DVec2, p2: DVec2) -> Option<(f64, f64, f64)> {
    let (aa, bb, cc) = (p1.y - p2.y, p2.x - p1.x, p1.x * p2.y - p2.x * p1.y);
    let l = (aa * aa + bb * bb).sqrt();
    (l > 0.0).then(|| (aa / l, bb / l, cc / l))
}

/// Even-odd rule: whether `p` lies inside the closed polygon `poly` (by the parity of
/// the edges a ray toward +x crosses). Points on the boundary may answer either way; a
/// segment walked twice (a bridge or a spur) cancels itself.
pub fn point_in_polygon(p: DVec2, poly: &[DVec2]) -> bool {
    let Some(&last) = poly.last() else {
        return false;
    };
    let mut odd = false;
    let mut prev = last;
    for &q in poly {
        if (prev.y > p.y) != (q.y > p.y) {
            let x = prev.x + (p.y - prev.y) * (q.x - prev.x) / (q.y - prev.y);
            if p.x < x {
                odd = !odd;
            }
        }
        prev = q;
    }
    odd
}

/// Six times the signed volume that closed polygons bound (negative for inward ones), by
/// the divergence theorem over a fan of each face. Faces are rings of indices into
/// `positions`, counter-clockwise seen from outside for a positive volume.
pub fn six_volume<F: AsRef<[u32]>>(positions: &[DVec3], faces: &[F]) -> f64 {
    let mut v = 0.0;
    for f in faces {
        let f = f.as_ref();
        let a = positions[f[0] as usize];
        for k in 1..f.len() - 1 {
            let (b, c) = (positions[f[k] as usize], positions[f[k + 1] as usize]);
            v += a.dot(b.cross(c));
        }
    }
    v
}

/// The winding number of closed polygons about point `x` (1 inside an outward surface,
/// −1 inside an inward one, 0 outside), by summing the solid angles the faces subtend
/// (Van Oosterom and Strackee's formula over a fan of each face, which gives the right
/// signed sum for concave planar faces too). Precondition: `x` is not on the surface.
pub fn winding_number<F: AsRef<[u32]>>(positions: &[DVec3], faces: &[F], x: DVec3) -> f64 {
    let mut omega = 0.0;
    for f in faces {
        let f = f.as_ref();
        let a = positions[f[0] as usize] - x;
        for k in 1..f.len() - 1 {
            let b = positions[f[k] as usize] - x;
            let c = positions[f[k + 1] as usize] - x;
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let num = a.dot(b.cross(c));
            let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
            omega += 2.0 * num.atan2(den);
        }
    }
    omega / (4.0 * std::f64::consts::PI)
}

impl Body {
    /// Newell's area vector of face `f`: its direction is the outward normal and its
    /// length twice the face's area. Right for concave and slightly non-planar faces.
    pub fn newell(&self, f: FaceId) -> DVec3 {
        // Summed about the face's first vertex, so a long thin face far from the origin
        // keeps its normal (the terms are small, and exactly zero along an axis the face
        // is flat in).
        let origin = self
            .face_uses(f)
            .next()
            .map_or(DVec3::ZERO, |u| self.position(self.origin(u)));
        let mut n = DVec3::ZERO;
        for u in self.face_uses(f) {
            let a = self.position(self.origin(u)) - origin;
            let b = self.position(self.dest(u)) - origin;
            n += DVec3::new(
                (a.y - b.y) * (a.z + b.z),
                (a.z - b.z) * (a.x + b.x),
                (a.x - b.x) * (a.y + b.y),
            );
        }
        n
    }

    /// Newell's area vector of face `f` summed in double-double arithmetic (each product
    /// split exactly, the sums compensated): accurate to a few units in the last place of
    /// the result even for a sliver face, whose plain Newell sum loses most of its digits
    /// to cancellation. Slower than [`Body::newell`]; for the validator.
    pub fn newell_accurate(&self, f: FaceId) -> DVec3 {
        let origin = self
            .face_uses(f)
            .next()
            .map_or(DVec3::ZERO, |u| self.position(self.origin(u)));
        let mut acc = [DoubleDouble::default(); 3];
        for u in self.face_uses(f) {
            // p × q about the origin vertex: each component a difference of products.
            let p = self.position(self.origin(u)) - origin;
            let q = self.position(self.dest(u)) - origin;
            add_cross(&mut acc, p, q);
        }
        DVec3::new(acc[0].value(), acc[1].value(), acc[2].value())
    }

    /// The mean of face `f`'s perimeter vertices (each use counted once).
    pub fn face_center(&self, f: FaceId) -> DVec3 {
        let (mut sum, mut k) = (DVec3::ZERO, 0usize);
        for v in self.face_vertices(f) {
            sum += self.position(v);
            k += 1;
        }
        if k == 0 { DVec3::ZERO } else { sum / k as f64 }
    }

    /// The plane of face `f` (Newell normal through the perimeter's mean point), or
    /// `None` for a face of zero area.
    pub fn face_plane(&self, f: FaceId) -> Option<Plane> {
        self.plane_with_normal(f, self.newell(f))
    }

    /// The plane of face `f` as [`Body::face_plane`], its normal from
    /// [`Body::newell_accurate`]: right for sliver faces too.
    pub fn face_plane_accurate(&self, f: FaceId) -> Option<Plane> {
        self.plane_with_normal(f, self.newell_accurate(f))
    }

    /// The plane through three vertices of face `f` that span it widely: the first
    /// vertex `a`, the vertex `b` farthest from it, and the vertex `c` farthest from the
    /// line `ab`; its normal from their cross product, computed as
    /// [`Body::newell_accurate`] computes its terms, and turned to agree with the Newell
    /// normal. `None` when every vertex lies on one line.
    ///
    /// For a sliver face (far longer than wide), whose Newell sum is a difference of
    /// nearly equal areas, this plane is the better witness of planarity: a vertex off
    /// the true plane by δ tilts it by about δ over the face's width or length, so
    /// vertices stay within a few δ of it.
    pub fn face_plane_spanning(&self, f: FaceId) -> Option<Plane> {
        let ps: Vec<DVec3> = self.face_vertices(f).map(|v| self.position(v)).collect();
        let a = *ps.first()?;
        let b = *ps
            .iter()
            .max_by(|p, q| p.distance_squared(a).total_cmp(&q.distance_squared(a)))?;
        let ab = b - a;
        let c = *ps.iter().max_by(|p, q| {
            ab.cross(**p - a)
                .length_squared()
                .total_cmp(&ab.cross(**q - a).length_squared())
        })?;
        let ac = c - a;
        let mut acc = [DoubleDouble::default(); 3];
        add_cross(&mut acc, ab, ac);
        let mut n = DVec3::new(acc[0].value(), acc[1].value(), acc[2].value());
        let len = n.length();
        if len <= f64::MIN_POSITIVE || !len.is_finite() {
            return None;
        }
        if n.dot(self.newell_accurate(f)) < 0.0 {
            n = -n;
        }
        let normal = n / len;
        Some(Plane {
            normal,
            offset: normal.dot(a),
        })
    }

    fn plane_with_normal(&self, f: FaceId, n: DVec3) -> Option<Plane> {
        let len = n.length();
        if len <= f64::MIN_POSITIVE || !len.is_finite() {
            return None;
        }
        let normal = n / len;
        Some(Plane {
            normal,
            offset: normal.dot(self.face_center(f)),
        })
    }

    /// Area of face `f` (of its projection on its own plane).
    pub fn face_area(&self, f: FaceId) -> f64 {
        self.newell(f).length() * 0.5
    }

    /// Total area of the body's faces.
    pub fn surface_area(&self) -> f64 {
        self.faces().map(|f| self.face_area(f)).sum()
    }

    /// Length of edge `e`.
    pub fn edge_length(&self, e: EdgeId) -> f64 {
        let r = self.edge(e);
        self.position(r.vt[0]).distance(self.position(r.vt[1]))
    }

    /// Signed volume enclosed by the surface (divergence theorem over each face's fan of
    /// triangles). Positive for a closed body whose faces run counter-clockwise seen
    /// from outside; negative after EVERT; meaningless for an open body.
    pub fn volume(&self) -> f64 {
        self.volume_and_moment().0
    }

    /// The centroid of the enclosed volume, or `None` when the volume is zero.
    pub fn centroid(&self) -> Option<DVec3> {
        let (vol, moment) = self.volume_and_moment();
        (vol.abs() > f64::MIN_POSITIVE).then(|| moment / vol)
    }

    /// (volume, first moment): sums over tetrahedra from the origin to each triangle of
    /// each face's fan.
    fn volume_and_moment(&self) -> (f64, DVec3) {
        let mut vol = 0.0;
        let mut moment = DVec3::ZERO;
        for f in self.faces() {
            let mut it = self.face_vertices(f).map(|v| self.position(v));
            let Some(a) = it.next() else { continue };
            let Some(mut b) = it.next() else { continue };
            for c in it {
                let v6 = a.dot(b.cross(c));
                vol += v6;
                moment += v6 * (a + b + c);
                b = c;
            }
        }
        (vol / 6.0, moment / 24.0)
    }

    /// The axis-aligned bounds of the body's vertices, or `None` when it has none.
    pub fn bounds(&self) -> Option<Bounds> {
        let mut it = self.vertices().map(|v| self.position(v));
        let first = it.next()?;
        let (min, max) = it.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
        Some(Bounds { min, max })
    }

    /// Whether the body is convex: at every edge, each face's plane has the whole of
    /// the neighbouring face on or below it (within `tol` meters). For a closed body
    /// without handles, local convexity at every edge means convexity.
    pub fn is_convex(&self, tol: f64) -> bool {
        if self.handles() > 0 {
            return false;
        }
        self.edges().all(|e| {
            let r = self.edge(e);
            let [fa, fb] = r.face;
            if fa == fb {
                return false;
            }
            match (self.face_plane(fa), self.face_plane(fb)) {
                (Some(pa), Some(pb)) => {
                    self.face_vertices(fb)
                        .all(|v| pa.distance(self.position(v)) <= tol)
                        && self
                            .face_vertices(fa)
                            .all(|v| pb.distance(self.position(v)) <= tol)
                }
                _ => false,
            }
        })
    }
}

/// Adds `p × q` to `acc`, each component a difference of products split exactly.
fn add_cross(acc: &mut [DoubleDouble; 3], p: DVec3, q: DVec3) {
    for (k, (i, j)) in [(1, 2), (2, 0), (0, 1)].into_iter().enumerate() {
        acc[k].add_product(p[i], q[j]);
        acc[k].add_product(-p[j], q[i]);
    }
}

/// A sum kept as an unevaluated pair `hi + lo` (double-double): products are added
/// exactly split (Dekker), sums with Knuth's TwoSum.
#[derive(Clone, Copy, Debug, Default)]
struct DoubleDouble {
    hi: f64,
    lo: f64,
}

impl DoubleDouble {
    fn add(&mut self, x: f64) {
        let s = self.hi + x;
        let bv = s - self.hi;
        let err = (self.hi - (s - bv)) + (x - bv);
        self.hi = s;
        self.lo += err;
    }

    fn add_product(&mut self, a: f64, b: f64) {
        let p = a * b;
        let split = |x: f64| {
            let c = 134_217_729.0 * x;
            let hi = c - (c - x);
            (hi, x - hi)
        };
        let ((ah, al), (bh, bl)) = (split(a), split(b));
        let e = al * bl - (((p - ah * bh) - al * bh) - ah * bl);
        self.add(p);
        self.lo += e;
    }

    fn value(self) -> f64 {
        self.hi + self.lo
    }
}

/// `n` unit vectors spread evenly over the sphere: the Fibonacci lattice, point `i` at
/// height `z = 1 − (2i + 1)/n` and turned by the golden angle from the one before.
/// Deterministic; empty for `n = 0`.
pub fn fibonacci_sphere(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let a = golden * i as f64;
            DVec3::new(r * a.cos(), r * a.sin(), z)
        })
        .collect()
}
