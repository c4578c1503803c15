//! The points of a boolean, input and constructed, and the exact predicates on them.
//!
//! An input point is an f64 locus. A constructed point is never rounded while the
//! boolean runs: it is kept as the input points that define it (a line through two
//! input points meeting the plane through three, or two coplanar segments crossing), and
//! every predicate on it is a polynomial in those inputs' coordinates, evaluated through
//! homogeneous coordinates `(X, Y, Z, W)` with the filter and exact fallback of
//! [`super::exact`]. Only the result's loci are rounded, once, to the nearest f64.

use glam::DVec3;

use super::exact::{Dy, Fx, Poly, Ring, quotient_to_f64};

/// A point's id in [`Points`]; input points come first.
pub(crate) type Pid = u32;

/// How a point is defined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Def {
    /// An input locus (index into [`Points::input`]).
    Input(u32),
    /// The line through input points `line` meets the plane through input points
    /// `plane` (precondition: they are not parallel).
    Lpi { line: [Pid; 2], plane: [Pid; 3] },
    /// Two segments in one plane cross: the line through `a` meets the line through `b`
    /// in the projection that drops coordinate `axis` (precondition: they cross there).
    Ssi { a: [Pid; 2], b: [Pid; 2], axis: u8 },
    /// The point `Σ w_i p_i / Σ w_i` of three points (a point inside a triangle).
    Mix { p: [Pid; 3], w: [u8; 3] },
}

/// Every point of one boolean.
#[derive(Debug, Default)]
pub(crate) struct Points {
    /// Input loci, each distinct.
    pub input: Vec<DVec3>,
    /// Every point's definition; ids `0..input.len()` are the inputs.
    pub defs: Vec<Def>,
    /// An f64 approximation of every point (for bounding boxes and projections only;
    /// never for decisions).
    pub approx: Vec<DVec3>,
    /// A bound on each approximation's error (per coordinate; infinite if unknown).
    pub slack: Vec<f64>,
    /// Each point's homogeneous coordinates in the filter, computed once.
    pub filtered: Vec<[Fx; 4]>,
    /// The sign of each point's W, decided once.
    w: Vec<i8>,
}

impl Points {
    /// Adds an input locus, returning its id. Precondition: finite, and no input point
    /// added so far has the same locus.
    pub fn add_input(&mut self, p: DVec3) -> Pid {
        let id = self.defs.len() as Pid;
        self.defs.push(Def::Input(self.input.len() as u32));
        self.input.push(p);
        self.approx.push(p);
        self.slack.push(0.0);
        self.filtered
            .push([Fx::of(p.x), Fx::of(p.y), Fx::of(p.z), Fx::of(1.0)]);
        self.w.push(1);
        id
    }

    /// Adds a constructed point, returning its id.
    pub fn add(&mut self, def: Def) -> Pid {
        let id = self.defs.len() as Pid;
        let h = self.homog::<Fx>(def);
        let w = h[3].v;
        let x = DVec3::new(h[0].v / w, h[1].v / w, h[2].v / w);
        let w_sign = h[3].sign().unwrap_or_else(|| self.w_sign_def(def));
        self.filtered.push(h);
        self.defs.push(def);
        self.w.push(w_sign);
        // x = X / W with |ΔX| ≤ e_X, |ΔW| ≤ e_W: |Δx| ≤ (e_X + |x| e_W) / (|W| − e_W).
        if w.abs() > 2.0 * h[3].e && x.is_finite() {
            let ex = h[0].e.max(h[1].e).max(h[2].e);
            let slack = ((ex + x.abs().max_element() * h[3].e) / (w.abs() - h[3].e)) * 2.0
                + x.abs().max_element() * 4.0 * f64::EPSILON;
            self.approx.push(x);
            self.slack.push(slack);
        } else {
            // The filter cannot bound the quotient (W is nearly zero: a line nearly
            // parallel to the plane it meets): the locus rounded exactly, within half
            // a unit in the last place.
            let x = self.rounded(id);
            self.approx.push(x);
            self.slack.push(x.abs().max_element() * f64::EPSILON);
        }
        id
    }

    /// Forgets every point from `len` on (constructions made only to test).
    pub fn truncate(&mut self, len: usize) {
        self.filtered.truncate(len);
        self.w.truncate(len);
        self.defs.truncate(len);
        self.approx.truncate(len);
        self.slack.truncate(len);
    }

    /// The input locus of an input point.
    #[inline]
    fn at(&self, p: Pid) -> DVec3 {
        match self.defs[p as usize] {
            Def::Input(i) => self.input[i as usize],
            _ => unreachable!("a construction's definition names input points only"),
        }
    }

    /// Homogeneous coordinates of point `p` in `R`: the filter's are kept from when the
    /// point was made.
    #[inline]
    pub fn homog_of<R: Ring>(&self, p: Pid) -> [R; 4] {
        match R::from_filter(&self.filtered[p as usize]) {
            Some(h) => h,
            None => self.homog(self.defs[p as usize]),
        }
    }

    /// Homogeneous coordinates `[X, Y, Z, W]` of `def` in `R` (W is not zero).
    pub fn homog<R: Ring>(&self, def: Def) -> [R; 4] {
        match def {
            Def::Input(i) => {
                let p = self.input[i as usize];
                [R::of(p.x), R::of(p.y), R::of(p.z), R::of(1.0)]
            }
            Def::Lpi { line, plane } => {
                let p = vec3::<R>(self.at(line[0]));
                let q = vec3::<R>(self.at(line[1]));
                let a = vec3::<R>(self.at(plane[0]));
                let b = vec3::<R>(self.at(plane[1]));
                let c = vec3::<R>(self.at(plane[2]));
                let n = cross(&sub(&b, &a), &sub(&c, &a));
                let d = sub(&q, &p);
                let w = dot(&n, &d);
                let t = dot(&n, &sub(&a, &p));
                [
                    p[0].clone() * w.clone() + d[0].clone() * t.clone(),
                    p[1].clone() * w.clone() + d[1].clone() * t.clone(),
                    p[2].clone() * w.clone() + d[2].clone() * t,
                    w,
                ]
            }
            Def::Ssi { a, b, axis } => {
                let p = vec3::<R>(self.at(a[0]));
                let q = vec3::<R>(self.at(a[1]));
                let r = vec3::<R>(self.at(b[0]));
                let s = vec3::<R>(self.at(b[1]));
                let (i, j) = others(axis);
                let d1 = sub(&q, &p);
                let d2 = sub(&s, &r);
                let rp = sub(&r, &p);
                let w = d1[i].clone() * d2[j].clone() - d1[j].clone() * d2[i].clone();
                let t = rp[i].clone() * d2[j].clone() - rp[j].clone() * d2[i].clone();
                [
                    p[0].clone() * w.clone() + d1[0].clone() * t.clone(),
                    p[1].clone() * w.clone() + d1[1].clone() * t.clone(),
                    p[2].clone() * w.clone() + d1[2].clone() * t,
                    w,
                ]
            }
            Def::Mix { p, w } => {
                let h: [[R; 4]; 3] = [
                    self.homog_of(p[0]),
                    self.homog_of(p[1]),
                    self.homog_of(p[2]),
                ];
                let ws = [R::of(w[0] as f64), R::of(w[1] as f64), R::of(w[2] as f64)];
                let w01 = h[0][3].clone() * h[1][3].clone();
                let w02 = h[0][3].clone() * h[2][3].clone();
                let w12 = h[1][3].clone() * h[2][3].clone();
                let coord = |k: usize| {
                    ws[0].clone() * h[0][k].clone() * w12.clone()
                        + ws[1].clone() * h[1][k].clone() * w02.clone()
                        + ws[2].clone() * h[2][k].clone() * w01.clone()
                };
                let total = R::of((w[0] as u32 + w[1] as u32 + w[2] as u32) as f64);
                [coord(0), coord(1), coord(2), total * w01 * h[2][3].clone()]
            }
        }
    }

    /// The point's locus rounded to the nearest f64 in each coordinate.
    pub fn rounded(&self, p: Pid) -> DVec3 {
        match self.defs[p as usize] {
            Def::Input(i) => self.input[i as usize],
            def => {
                let h = self.homog::<Dy>(def);
                DVec3::new(
                    quotient_to_f64(&h[0], &h[3]),
                    quotient_to_f64(&h[1], &h[3]),
                    quotient_to_f64(&h[2], &h[3]),
                )
            }
        }
    }

    /// The locus of input point `p`. Precondition: `p` is an input point.
    #[inline]
    pub fn input_at(&self, p: Pid) -> DVec3 {
        self.at(p)
    }

    /// The normal `(b − a) × (c − a)` of the triangle through input points `tri`, in `R`.
    pub fn normal<R: Ring>(&self, tri: [Pid; 3]) -> [R; 3] {
        let [a, b, c] = tri.map(|q| vec3::<R>(self.at(q)));
        cross(&sub(&b, &a), &sub(&c, &a))
    }

    /// Sign of W of a point defined by `def`.
    pub fn w_sign_def(&self, def: Def) -> i8 {
        match def {
            Def::Input(_) => 1,
            def => WSign { pts: self, def }.sign(),
        }
    }

    /// Whether `p` is an input point.
    #[inline]
    pub fn is_input(&self, p: Pid) -> bool {
        matches!(self.defs[p as usize], Def::Input(_))
    }

    /// Sign of W of point `p` (1 for an input point).
    #[inline]
    pub fn w_sign(&self, p: Pid) -> i8 {
        self.w[p as usize]
    }

    /// Which side of the plane through input points `tri` (counter-clockwise seen from
    /// the front) the point `p` lies: 1 in front, −1 behind, 0 on it.
    pub fn side(&self, tri: [Pid; 3], p: Pid) -> i8 {
        if tri.contains(&p) {
            return 0;
        }
        if self.is_input(p) {
            // Shewchuk's orient3d is positive when the fourth point is behind.
            let o = robust::orient3d(
                c3(self.at(tri[0])),
                c3(self.at(tri[1])),
                c3(self.at(tri[2])),
                c3(self.at(p)),
            );
            return -(o.partial_cmp(&0.0).map_or(0, |o| o as i8));
        }
        Side { pts: self, tri, p }.sign() * self.w_sign(p)
    }

    /// Which side of the plane through `tri` (counter-clockwise seen from the front)
    /// the point `p` lies, for any points: 1 in front, −1 behind, 0 on it (or when
    /// `tri` is collinear). Slower than [`Points::side`], which needs input corners.
    pub fn side_any(&self, tri: [Pid; 3], p: Pid) -> i8 {
        if tri.iter().all(|&q| self.is_input(q)) {
            return self.side(tri, p);
        }
        let four = [tri[0], tri[1], tri[2], p];
        if (0..4).any(|i| four[i + 1..].contains(&four[i])) {
            return 0;
        }
        let w: i8 = four.iter().map(|&q| self.w_sign(q)).product();
        -(Orient4 { pts: self, p: four }.sign() * w)
    }

    /// The orientation of three points in the projection dropping coordinate `axis`:
    /// 1 counter-clockwise, −1 clockwise, 0 collinear (axes in cyclic order, so the
    /// projection along +axis keeps the sense of rotation seen from +axis).
    pub fn orient2d(&self, axis: u8, p: [Pid; 3]) -> i8 {
        if p[0] == p[1] || p[1] == p[2] || p[2] == p[0] {
            return 0;
        }
        if p.iter().all(|&q| self.is_input(q)) {
            let (i, j) = others(axis);
            let c = |q: Pid| {
                let v = self.at(q);
                robust::Coord { x: v[i], y: v[j] }
            };
            let o = robust::orient2d(c(p[0]), c(p[1]), c(p[2]));
            return o.partial_cmp(&0.0).map_or(0, |o| o as i8);
        }
        let w = p.iter().map(|&q| self.w_sign(q)).product::<i8>();
        Orient2 { pts: self, axis, p }.sign() * w
    }

    /// The ray from `x` along the symbolically perturbed direction `(1, ε, ε²)` and the
    /// triangle `tri` of input points: `Some(σ)` if the ray crosses the triangle, σ the
    /// sign of its normal's dot product with the direction, `None` if it misses.
    /// Precondition: `x` is not in the triangle's plane.
    pub fn ray_crosses(&self, x: Pid, tri: [Pid; 3]) -> Option<i8> {
        let s = self.side(tri, x);
        debug_assert!(s != 0);
        // σ: the first nonzero component of the normal, exactly.
        let sigma = (0..3)
            .map(|k| NormalComponent { pts: self, tri, k }.sign())
            .find(|&v| v != 0)?;
        // The ray goes forward from x: it meets the plane ahead iff x is behind the
        // plane with respect to the direction, i.e. side(x) = −σ.
        if s != -sigma {
            return None;
        }
        let mut first = 0;
        for e in 0..3 {
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            // sign of ((a − x) × (b − x)) · (1, ε, ε²) scaled by W² > 0.
            let v = (0..3)
                .map(|k| {
                    RayMinor {
                        pts: self,
                        x,
                        a,
                        b,
                        k,
                    }
                    .sign()
                })
                .find(|&v| v != 0)
                .unwrap_or(0);
            if v == 0 {
                return None;
            }
            if first == 0 {
                first = v;
            } else if v != first {
                return None;
            }
        }
        Some(sigma)
    }
}

/// The projection that drops `axis`: the other two axes in cyclic order.
#[inline]
pub(crate) fn others(axis: u8) -> (usize, usize) {
    match axis {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    }
}

#[inline]
fn c3(v: DVec3) -> robust::Coord3D<f64> {
    robust::Coord3D {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

fn vec3<R: Ring>(v: DVec3) -> [R; 3] {
    [R::of(v.x), R::of(v.y), R::of(v.z)]
}

fn sub<R: Ring>(a: &[R; 3], b: &[R; 3]) -> [R; 3] {
    [
        a[0].clone() - b[0].clone(),
        a[1].clone() - b[1].clone(),
        a[2].clone() - b[2].clone(),
    ]
}

fn cross<R: Ring>(a: &[R; 3], b: &[R; 3]) -> [R; 3] {
    [
        a[1].clone() * b[2].clone() - a[2].clone() * b[1].clone(),
        a[2].clone() * b[0].clone() - a[0].clone() * b[2].clone(),
        a[0].clone() * b[1].clone() - a[1].clone() * b[0].clone(),
    ]
}

fn dot<R: Ring>(a: &[R; 3], b: &[R; 3]) -> R {
    a[0].clone() * b[0].clone() + a[1].clone() * b[1].clone() + a[2].clone() * b[2].clone()
}

/// W of a constructed point.
struct WSign<'a> {
    pts: &'a Points,
    def: Def,
}

impl Poly for WSign<'_> {
    fn eval<R: Ring>(&self) -> R {
        let [_, _, _, w] = self.pts.homog::<R>(self.def);
        w
    }
}

/// n · (X − a W) for the plane through `tri`, times nothing: the caller multiplies by
/// the sign of W.
struct Side<'a> {
    pts: &'a Points,
    tri: [Pid; 3],
    p: Pid,
}

impl Poly for Side<'_> {
    fn known_zero(&self) -> bool {
        self.pts.known_on_plane(self.p, self.tri)
    }

    fn eval<R: Ring>(&self) -> R {
        let [a, b, c] = self.tri.map(|q| vec3::<R>(self.pts.at(q)));
        let n = cross(&sub(&b, &a), &sub(&c, &a));
        let [x, y, z, w] = self.pts.homog_of::<R>(self.p);
        let d = [
            x - a[0].clone() * w.clone(),
            y - a[1].clone() * w.clone(),
            z - a[2].clone() * w,
        ];
        dot(&n, &d)
    }
}

/// det [[X_i, Y_i, W_i]] in a projection.
struct Orient2<'a> {
    pts: &'a Points,
    axis: u8,
    p: [Pid; 3],
}

impl Poly for Orient2<'_> {
    fn known_zero(&self) -> bool {
        self.pts.known_collinear(self.p)
    }

    fn eval<R: Ring>(&self) -> R {
        let (i, j) = others(self.axis);
        let h = self.p.map(|q| self.pts.homog_of::<R>(q));
        let m = |r: usize| [h[r][i].clone(), h[r][j].clone(), h[r][3].clone()];
        let (a, b, c) = (m(0), m(1), m(2));
        a[0].clone() * (b[1].clone() * c[2].clone() - b[2].clone() * c[1].clone())
            - a[1].clone() * (b[0].clone() * c[2].clone() - b[2].clone() * c[0].clone())
            + a[2].clone() * (b[0].clone() * c[1].clone() - b[1].clone() * c[0].clone())
    }
}

/// det [[X_i, Y_i, Z_i, W_i]] of four points: for points of positive W, Shewchuk's
/// orient3d of the first three and the fourth.
struct Orient4<'a> {
    pts: &'a Points,
    p: [Pid; 4],
}

impl Poly for Orient4<'_> {
    fn known_zero(&self) -> bool {
        self.pts.known_coplanar(self.p)
    }

    fn eval<R: Ring>(&self) -> R {
        let h = self.p.map(|q| self.pts.homog_of::<R>(q));
        // Laplace expansion by the 2×2 minors of the first two rows and of the last two.
        let minor = |r: usize, s: usize, i: usize, j: usize| {
            h[r][i].clone() * h[s][j].clone() - h[r][j].clone() * h[s][i].clone()
        };
        let pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
        let mut total = R::of(0.0);
        for (k, &(i, j)) in pairs.iter().enumerate() {
            let (a, b) = pairs[5 - k];
            let term = minor(0, 1, i, j) * minor(2, 3, a, b);
            // The sign of the permutation (i, j, a, b).
            total = if k == 1 || k == 4 {
                total - term
            } else {
                total + term
            };
        }
        total
    }
}

/// Component `k` of the normal of the triangle through input points `tri`.
struct NormalComponent<'a> {
    pts: &'a Points,
    tri: [Pid; 3],
    k: usize,
}

impl Poly for NormalComponent<'_> {
    fn eval<R: Ring>(&self) -> R {
        let [a, b, c] = self.tri.map(|q| vec3::<R>(self.pts.at(q)));
        let n = cross(&sub(&b, &a), &sub(&c, &a));
        n[self.k].clone()
    }
}

/// Component `k` of (a W − X) × (b W − X), for input points a, b and a point x.
struct RayMinor<'a> {
    pts: &'a Points,
    x: Pid,
    a: Pid,
    b: Pid,
    k: usize,
}

impl Poly for RayMinor<'_> {
    fn eval<R: Ring>(&self) -> R {
        let [x, y, z, w] = self.pts.homog_of::<R>(self.x);
        let xv = [x, y, z];
        let rel = |q: Pid| {
            let v = vec3::<R>(self.pts.at(q));
            [
                v[0].clone() * w.clone() - xv[0].clone(),
                v[1].clone() * w.clone() - xv[1].clone(),
                v[2].clone() * w.clone() - xv[2].clone(),
            ]
        };
        let c = cross(&rel(self.a), &rel(self.b));
        c[self.k].clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(loci: &[DVec3]) -> Points {
        let mut p = Points::default();
        for &x in loci {
            p.add_input(x);
        }
        p
    }

    /// The orientation of four points, some constructed, agrees with Shewchuk's on
    /// their (here exact) loci, in every order of the four.
    #[test]
    fn four_points_orient_as_their_loci() {
        let mut p = points(&[
            DVec3::new(0.25, 0.5, -1.0),
            DVec3::new(0.25, 0.5, 3.0),
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(-2.0, 0.5, 0.75),
        ]);
        // x = (0.25, 0.5, 0), on the plane z = 0.
        let x = p.add(Def::Lpi {
            line: [0, 1],
            plane: [2, 3, 4],
        });
        let at = |q: Pid| {
            if q == x {
                DVec3::new(0.25, 0.5, 0.0)
            } else {
                p.input[q as usize]
            }
        };
        let ids = [x, 2, 3, 5, 6, 4];
        for &a in &ids {
            for &b in &ids {
                for &c in &ids {
                    for &d in &ids {
                        let o = robust::orient3d(c3(at(a)), c3(at(b)), c3(at(c)), c3(at(d)));
                        let want = -(o.partial_cmp(&0.0).map_or(0, |o| o as i8));
                        assert_eq!(p.side_any([a, b, c], d), want, "{a} {b} {c} {d}");
                    }
                }
            }
        }
        // x lies on the plane of corners 2, 3 and 4.
        assert_eq!(p.side_any([x, 3, 4], 2), 0);
        assert_eq!(p.side_any([3, x, 5], 4), -p.side_any([x, 3, 5], 4));
    }

    #[test]
    fn a_line_meets_a_plane_where_it_should() {
        let mut p = points(&[
            DVec3::new(0.25, 0.25, -1.0),
            DVec3::new(0.25, 0.25, 3.0),
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
        ]);
        let x = p.add(Def::Lpi {
            line: [0, 1],
            plane: [2, 3, 4],
        });
        assert_eq!(p.rounded(x), DVec3::new(0.25, 0.25, 0.0));
        assert_eq!(p.side([2, 3, 4], x), 0);
        // In the projection along z it lies inside the triangle.
        assert_eq!(p.orient2d(2, [2, 3, x]), 1);
        assert_eq!(p.orient2d(2, [3, 4, x]), 1);
        assert_eq!(p.orient2d(2, [4, 2, x]), 1);
    }

    #[test]
    fn a_constructed_point_a_hair_off_a_plane_is_seen_off_it() {
        // The line crosses z = 0 at x = 1/3; the plane through (1/3 ± tiny) differs.
        let third = 1.0 / 3.0;
        let mut p = points(&[
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(1.0, 0.0, 2.0),
            DVec3::new(third, -1.0, -1.0),
            DVec3::new(third, 1.0, -1.0),
            DVec3::new(third, 0.0, 1.0),
        ]);
        let x = p.add(Def::Lpi {
            line: [0, 1],
            plane: [2, 3, 4],
        });
        // The exact crossing of the line with the plane x = 1/3 (rounded) is on it.
        assert_eq!(p.side([2, 3, 4], x), 0);
        let z0 = p.add(Def::Lpi {
            line: [0, 1],
            plane: [2, 3, 4],
        });
        assert_eq!(p.rounded(z0).x, third);
    }

    #[test]
    fn rays_count_crossings() {
        let mut p = points(&[
            DVec3::new(1.0, -1.0, -1.0),
            DVec3::new(1.0, 1.0, -1.0),
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
        ]);
        let _ = &mut p;
        // Normal of (0,1,2) points to +x: a ray along +x from the origin exits it.
        assert_eq!(p.ray_crosses(3, [0, 1, 2]), Some(1));
        assert_eq!(p.ray_crosses(3, [0, 2, 1]), Some(-1));
        assert_eq!(p.ray_crosses(4, [0, 1, 2]), None);
    }
}
