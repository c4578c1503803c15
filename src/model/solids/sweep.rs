//! The sweep primitives of WINGED.DOC III.B, built from Euler operators: PYRAMID, PRISM,
//! CWPRISMOID and CCWPRISMOID; the polygonal lamina they start from; and the box, prism
//! and pyramid solids made from them.
//!
//! A sweep copies the perimeter of a face `f` to a new ring of vertices and joins the old
//! ring to the new one with side faces. As in MKCUBE, `f` itself moves with the sweep and
//! ends as the far cap: a spur is made at every vertex of `f` (MKEV), then the spur tips
//! are tied together (MKFE), each tie cutting one side face off `f`. What was on the
//! other side of `f` (the rest of the body, or the other face of a lamina) does not move.
//!
//! Let `f` have `n` edges. Then
//!
//! | sweep | F | E | V |
//! |---|---|---|---|
//! | [`Body::pyramid`] | + n − 1 | + n | + 1 |
//! | [`Body::prism`] | + n | + 2n | + n |
//! | [`Body::prismoid`] | + 2n | + 3n | + n |
//!
//! The sweeps check the topology of the face and the direction of the sweep; they do not
//! check whether the new part runs into the rest of the body.
//!
//! Every sweep checks its whole input before the first Euler operator, so a refused sweep
//! returns a [`SolidError`], takes no serial number and leaves the body as it was. Its
//! inverse is a run of KLFEs, newest edge first, then KLEVs of the new vertices.

use glam::{DQuat, DVec2, DVec3};

use super::cube::mkcube;
use super::error::{PolygonFault, SolidError, finite, length, positive};
use crate::model::body::Body;
use crate::model::euler::EulerError;
use crate::model::geometry::Plane;
use crate::model::ids::{FaceId, Serials, VertexId};
use crate::model::range::{self, MAX_COORDINATE, MIN_LENGTH, RangeError};

/// The most points a polygon or a rotation profile may have: simplicity is checked by
/// testing every pair of segments.
pub const MAX_POLYGON_POINTS: usize = 4096;

/// Which way a prismoid's side quadrilaterals are cut into triangles.
///
/// Number the swept face's vertices `v0 … vn−1` counter-clockwise seen from outside,
/// and let `wi` be the new vertex swept from `vi`. The side face over edge `vi vi+1`
/// is the quadrilateral `vi vi+1 wi+1 wi`; seen from outside with the sweep pointing up,
/// `vi` is at its lower left and `vi+1` at its lower right.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Twist {
    /// CWPRISMOID: the diagonal runs from `vi` to `wi+1` (lower left to upper right,
    /// "/"), giving triangles `vi vi+1 wi+1` and `wi+1 wi vi`. This is the convex cut
    /// when the cap is turned clockwise (seen from outside, about the outward normal).
    Cw,
    /// CCWPRISMOID: the diagonal runs from `vi+1` to `wi` (lower right to upper left,
    /// "\"), giving triangles `wi vi vi+1` and `vi+1 wi+1 wi`. This is the convex cut
    /// when the cap is turned counter-clockwise, as in an antiprism.
    Ccw,
}

/// What a prism or prismoid sweep made.
#[derive(Clone, Debug, PartialEq)]
pub struct Swept {
    /// The far cap: the swept face itself, whose perimeter is now the new ring.
    pub cap: FaceId,
    /// The old perimeter `v0 … vn−1`, counter-clockwise about the face seen from
    /// outside, starting at the first vertex of the face's perimeter (VCW of its PED).
    pub base: Vec<VertexId>,
    /// The new ring: `ring[i]` was swept from `base[i]`.
    pub ring: Vec<VertexId>,
    /// The side faces in base order: for a prism, `sides[i]` is the quadrilateral over
    /// base edge `i`; for a prismoid, `sides[2i]` is the triangle on base edge `i` and
    /// `sides[2i + 1]` the one on ring edge `i` (see [`Twist`]).
    pub sides: Vec<FaceId>,
}

/// A lamina: a polygon as a two-faced body of zero volume, the stage a sweep starts from.
#[derive(Clone, Debug)]
pub struct Lamina {
    /// The body: F = 2, E = V = the number of polygon points.
    pub body: Body,
    /// The face whose outward normal is +z (its perimeter runs counter-clockwise seen
    /// from above). Sweep this one upward.
    pub top: FaceId,
    /// The face whose outward normal is −z.
    pub bottom: FaceId,
}

impl Body {
    /// PYRAMID(F): a pyramid on face `f` with its apex at `peak`, made as in WINGED.DOC
    /// figure 3.4: a spur from the first vertex `v0` of `f` (VCW of its PED) to the peak
    /// (MKEV), then MKFE from the peak to each other vertex in counter-clockwise order.
    /// Returns the peak vertex.
    ///
    /// Preconditions (refused otherwise, before any change): `f` is live, a simple
    /// polygon (no spurs, no vertex twice) of at least three edges, of non-zero area;
    /// `peak` is finite, within the world's range and at least
    /// [`range::MIN_LENGTH`] above `f`'s plane (on its outer side).
    ///
    /// Postconditions: F + n − 1, E + n, V + 1 for an `n`-edged face. The triangles are
    /// `peak vi−1 vi`; `f` survives as the last one, `peak vn−1 v0`. Every other face
    /// and vertex keeps its perimeter, plus the new edges at the old vertices.
    ///
    /// Inverse: [`Body::klfe`] of the `n − 1` edges from the peak other than its spur
    /// (PED(peak)), newest first, each killing the triangle on its NFACE side, then
    /// [`Body::klev`]`(peak)`: `f` is left with its old perimeter.
    pub fn pyramid(
        &mut self,
        serials: &mut Serials,
        f: FaceId,
        peak: DVec3,
    ) -> Result<VertexId, SolidError> {
        let base = self.simple_perimeter(f)?;
        let plane = self.sweep_plane(f)?;
        if !peak.is_finite() {
            return Err(SolidError::NotFinite { parameter: "peak" });
        }
        range::coordinate("the peak", peak)?;
        let distance = plane.distance(peak);
        if distance.is_nan() || distance <= 0.0 {
            return Err(SolidError::PeakNotAbove {
                face: self.face_serial(f),
                distance,
            });
        }
        if distance < MIN_LENGTH {
            return Err(RangeError::TooSmall {
                what: "the peak's height over the face",
                value: distance,
            }
            .into());
        }
        let (_, apex) = self.mkev(serials, f, base[0], peak)?;
        for &v in &base[1..] {
            self.mkfe(serials, apex, f, v)?;
        }
        Ok(apex)
    }

    /// PRISM(F): sweeps face `f` by `offset`, scaling the new ring by `scale` about the
    /// face centre: vertex `p` of `f` is copied to `c + scale·(p − c) + offset`, where
    /// `c` is [`Body::face_center`]`(f)`. `scale = 1` is Baumgart's PRISM; any other
    /// positive scale makes a frustum. Spurs are made at every vertex of `f` in
    /// counter-clockwise order (MKEV), then tied (MKFE `wi → wi+1` in `f`), as MKCUBE
    /// does; `f` ends as the far cap.
    ///
    /// Preconditions (refused otherwise, before any change): `f` is live, a simple
    /// polygon of at least three edges, of non-zero area; `offset` finite, at least
    /// [`range::MIN_LENGTH`] and at most [`range::MAX_LENGTH`] long, and pointing out of
    /// `f` (`offset · normal > 0`); `scale` finite and above zero; every new vertex within
    /// the world's range.
    ///
    /// Postconditions: F + n, E + 2n, V + n; each side face `vi vi+1 wi+1 wi` is planar
    /// (its top edge is parallel to its bottom edge).
    ///
    /// Inverse: [`Body::klfe`] of the n tie edges (ring to ring), newest first, each
    /// killing its side face, then [`Body::klev`] of the n ring vertices.
    pub fn prism(
        &mut self,
        serials: &mut Serials,
        f: FaceId,
        offset: DVec3,
        scale: f64,
    ) -> Result<Swept, SolidError> {
        self.sweep(serials, f, offset, scale, None, 0.0)
    }

    /// CWPRISMOID(F) and CCWPRISMOID(F): a [`Body::prism`] whose side quadrilaterals
    /// are each cut by a diagonal MKFE into two triangles, the diagonal chosen by
    /// `twist` (see [`Twist`]). Same preconditions as [`Body::prism`].
    ///
    /// Postconditions: F + 2n, E + 3n, V + n.
    ///
    /// Inverse: [`Body::klfe`] of the 2n edges made between the rings (diagonals and
    /// ties), newest first, then [`Body::klev`] of the ring vertices.
    pub fn prismoid(
        &mut self,
        serials: &mut Serials,
        f: FaceId,
        offset: DVec3,
        scale: f64,
        twist: Twist,
    ) -> Result<Swept, SolidError> {
        self.sweep(serials, f, offset, scale, Some(twist), 0.0)
    }

    /// A [`Body::prismoid`] whose new ring is also turned by `angle` radians about the
    /// face's outward normal through its centre, in the sense of `twist`
    /// (counter-clockwise seen from outside for [`Twist::Ccw`]): vertex `p` goes to
    /// `c + offset + R(±angle)·scale·(p − c)`. Turning a regular `n`-gon by `π/n` makes
    /// an antiprism. The side triangles stay planar whatever the angle; past about one
    /// vertex spacing they fold over each other.
    ///
    /// Preconditions: those of [`Body::prism`], and `0 ≤ angle < π`.
    pub fn prismoid_turned(
        &mut self,
        serials: &mut Serials,
        f: FaceId,
        offset: DVec3,
        scale: f64,
        twist: Twist,
        angle: f64,
    ) -> Result<Swept, SolidError> {
        if !(angle.is_finite() && (0.0..std::f64::consts::PI).contains(&angle)) {
            return Err(SolidError::TurnAngle { angle });
        }
        self.sweep(serials, f, offset, scale, Some(twist), angle)
    }

    /// The perimeter of `f` from VCW(PED), refusing faces that are not simple polygons
    /// of three or more edges.
    fn simple_perimeter(&self, f: FaceId) -> Result<Vec<VertexId>, SolidError> {
        self.check_face(f)?;
        let base: Vec<VertexId> = self.face_vertices(f).collect();
        if base.len() < 3 {
            return Err(EulerError::FaceTooSmall {
                face: self.face_serial(f),
                degree: base.len(),
            }
            .into());
        }
        let mut sorted = base.clone();
        sorted.sort_unstable();
        if sorted.windows(2).any(|w| w[0] == w[1]) {
            return Err(EulerError::FaceNotSimple {
                face: self.face_serial(f),
            }
            .into());
        }
        Ok(base)
    }

    fn sweep_plane(&self, f: FaceId) -> Result<Plane, SolidError> {
        self.face_plane(f).ok_or(SolidError::DegenerateFace {
            face: self.face_serial(f),
        })
    }

    fn sweep(
        &mut self,
        serials: &mut Serials,
        f: FaceId,
        offset: DVec3,
        scale: f64,
        twist: Option<Twist>,
        angle: f64,
    ) -> Result<Swept, SolidError> {
        // Plan: every check before the first Euler operator.
        let base = self.simple_perimeter(f)?;
        let plane = self.sweep_plane(f)?;
        if !offset.is_finite() {
            return Err(SolidError::NotFinite {
                parameter: "offset",
            });
        }
        if offset == DVec3::ZERO {
            return Err(SolidError::ZeroOffset);
        }
        range::length("the sweep offset's length", range::norm(offset))?;
        let along_normal = offset.dot(plane.normal);
        if along_normal.is_nan() || along_normal <= 0.0 {
            return Err(SolidError::OffsetNotOutward {
                face: self.face_serial(f),
                along_normal,
            });
        }
        positive("scale", scale)?;
        let center = self.face_center(f);
        let signed = match twist {
            Some(Twist::Cw) => -angle,
            _ => angle,
        };
        let turn = DQuat::from_axis_angle(plane.normal, signed);
        let targets: Vec<DVec3> = base
            .iter()
            .map(|&v| {
                let p = self.position(v) - center;
                let q = if angle == 0.0 { p } else { turn * p };
                center + offset + scale * q
            })
            .collect();
        if targets.iter().any(|p| !p.is_finite()) {
            return Err(SolidError::NotFinite {
                parameter: "swept vertex",
            });
        }
        if let Some(&p) = targets
            .iter()
            .find(|p| !range::is_within(**p, MAX_COORDINATE))
        {
            range::coordinate("a swept vertex", p)?;
        }

        // Apply: cannot fail after the checks above.
        let n = base.len();
        let mut ring = Vec::with_capacity(n);
        for (&v, &p) in base.iter().zip(&targets) {
            ring.push(self.mkev(serials, f, v, p)?.1);
        }
        let mut sides = Vec::with_capacity(if twist.is_some() { 2 * n } else { n });
        for i in 0..n {
            let j = (i + 1) % n;
            // The new face is f's perimeter from wi counter-clockwise to wj: wi vi vj wj.
            let (_, quad) = self.mkfe(serials, ring[i], f, ring[j])?;
            match twist {
                None => sides.push(quad),
                // The new face runs from the first vertex counter-clockwise to the second.
                Some(Twist::Ccw) => {
                    let (_, low) = self.mkfe(serials, ring[i], quad, base[j])?;
                    sides.extend([low, quad]);
                }
                Some(Twist::Cw) => {
                    let (_, low) = self.mkfe(serials, base[i], quad, ring[j])?;
                    sides.extend([low, quad]);
                }
            }
        }
        Ok(Swept {
            cap: f,
            base,
            ring,
            sides,
        })
    }
}

/// A lamina in the plane `z`: MKBFV at the first point, MKEVs along the polygon to a
/// wire, and MKFE closing it (the start of MKCUBE, for any polygon).
///
/// The polygon may be given in either orientation; the lamina's `top` face runs
/// counter-clockwise seen from above whatever the input order, so its vertex order is
/// the input's or its reverse.
///
/// Preconditions (refused otherwise): `z` finite; the polygon is simple (3 to
/// [`MAX_POLYGON_POINTS`] finite points, no zero-length, crossing, touching or
/// overlapping segments, non-zero area).
pub fn lamina(serials: &mut Serials, polygon: &[DVec2], z: f64) -> Result<Lamina, SolidError> {
    finite("z", z)?;
    let ccw = counter_clockwise(polygon)?;
    Ok(build_lamina(serials, &ccw, z)?)
}

/// The polygon's points counter-clockwise, after checking that it is simple.
fn counter_clockwise(polygon: &[DVec2]) -> Result<Vec<DVec2>, SolidError> {
    let twice_area = simple_polygon(polygon, MAX_POLYGON_POINTS).map_err(SolidError::Polygon)?;
    let mut pts = polygon.to_vec();
    if twice_area < 0.0 {
        pts.reverse();
    }
    Ok(pts)
}

/// The lamina of a checked, counter-clockwise polygon.
fn build_lamina(serials: &mut Serials, ccw: &[DVec2], z: f64) -> Result<Lamina, EulerError> {
    let (mut body, bottom, first) = Body::seminal(serials, ccw[0].extend(z));
    let mut last = first;
    for p in &ccw[1..] {
        last = body.mkev(serials, bottom, last, p.extend(z))?.1;
    }
    // The new face faces the side from which the wire runs counter-clockwise: up.
    let (_, top) = body.mkfe(serials, first, bottom, last)?;
    Ok(Lamina { body, top, bottom })
}

/// A right prism over `polygon` (in the xy plane, coordinates as given), `height` tall
/// and centred in height: a [`lamina`] at `z = −height/2` swept up by `height` with
/// [`Body::prism`]. F = n + 2, E = 3n, V = 2n.
///
/// Preconditions: those of [`lamina`], and `height` finite and above zero.
pub fn prism_solid(
    serials: &mut Serials,
    polygon: &[DVec2],
    height: f64,
) -> Result<Body, SolidError> {
    length("height", height)?;
    let ccw = counter_clockwise(polygon)?;
    polygon_extent(&ccw)?;
    let mut l = build_lamina(serials, &ccw, -height / 2.0)?;
    l.body.prism(serials, l.top, DVec3::Z * height, 1.0)?;
    Ok(l.body)
}

/// A pyramid over `polygon` (in the xy plane, coordinates as given), `height` tall and
/// centred in height: a [`lamina`] at `z = −height/2` and [`Body::pyramid`] with the
/// apex at `height/2` over the polygon's area centroid. F = n + 1, E = 2n, V = n + 1.
///
/// Preconditions: those of [`lamina`], `height` finite and above zero, and the polygon
/// star-shaped about its centroid (every edge seen counter-clockwise from it), so that
/// no side triangle folds.
pub fn pyramid_solid(
    serials: &mut Serials,
    polygon: &[DVec2],
    height: f64,
) -> Result<Body, SolidError> {
    length("height", height)?;
    let ccw = counter_clockwise(polygon)?;
    polygon_extent(&ccw)?;
    let c = area_centroid(&ccw);
    // Segment i of the input must turn about the centroid the way the whole polygon does.
    let (p, n) = (polygon, polygon.len());
    let sign = if ccw[0] == p[0] { 1.0 } else { -1.0 };
    if let Some(index) = (0..n).find(|&i| sign * (p[i] - c).perp_dot(p[(i + 1) % n] - c) <= 0.0) {
        return Err(SolidError::Polygon(PolygonFault::NotStarShaped { index }));
    }
    let mut l = build_lamina(serials, &ccw, -height / 2.0)?;
    l.body.pyramid(serials, l.top, c.extend(height / 2.0))?;
    Ok(l.body)
}

/// BOX(size): MKCUBE with checked sizes, a box `size.x × size.y × size.z` centred on
/// the origin. F = 6, E = 12, V = 8.
///
/// Preconditions: every size a length in the world's range (finite, at least
/// [`range::MIN_LENGTH`], at most [`range::MAX_LENGTH`]).
pub fn box_solid(serials: &mut Serials, size: DVec3) -> Result<Body, SolidError> {
    length("size.x", size.x)?;
    length("size.y", size.y)?;
    length("size.z", size.z)?;
    Ok(mkcube(serials, size.x, size.y, size.z)?)
}

/// Refuses a polygon whose bounding box is smaller than [`range::MIN_LENGTH`] on its
/// longer side, or whose points lie beyond the world's range.
fn polygon_extent(points: &[DVec2]) -> Result<(), SolidError> {
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for &p in points {
        range::coordinate("a polygon point", p.extend(0.0))?;
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let across = (hi - lo).max_element();
    if across < MIN_LENGTH {
        return Err(RangeError::TooSmall {
            what: "the polygon's extent",
            value: across,
        }
        .into());
    }
    Ok(())
}

/// The area centroid of a simple polygon of non-zero area.
fn area_centroid(p: &[DVec2]) -> DVec2 {
    let n = p.len();
    let (mut a2, mut c) = (0.0, DVec2::ZERO);
    for i in 0..n {
        let (u, v) = (p[i], p[(i + 1) % n]);
        let w = u.perp_dot(v);
        a2 += w;
        c += (u + v) * w;
    }
    c / (3.0 * a2)
}

/// Checks that `points` is a simple polygon and returns twice its signed area
/// (positive when counter-clockwise).
pub(crate) fn simple_polygon(points: &[DVec2], limit: usize) -> Result<f64, PolygonFault> {
    let n = points.len();
    if n < 3 {
        return Err(PolygonFault::TooFewPoints { count: n, min: 3 });
    }
    if n > limit {
        return Err(PolygonFault::TooManyPoints { count: n, limit });
    }
    if let Some(index) = points.iter().position(|p| !p.is_finite()) {
        return Err(PolygonFault::NotFinite { index });
    }
    let seg = |i: usize| (points[i], points[(i + 1) % n]);
    for i in 0..n {
        let (a, b) = seg(i);
        if a == b {
            return Err(PolygonFault::ZeroLengthSegment { index: i });
        }
    }
    for i in 0..n {
        // Adjacent segments i and i+1 meet at a point; they overlap only by folding back.
        let j = (i + 1) % n;
        let ((a, b), (_, c)) = (seg(i), seg(j));
        if orient(a, b, c) == 0.0 && (b - a).dot(c - b) < 0.0 {
            return Err(PolygonFault::Crossing { a: i, b: j });
        }
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            let ((a, b), (c, d)) = (seg(i), seg(j));
            if segments_meet(a, b, c, d) {
                return Err(PolygonFault::Crossing { a: i, b: j });
            }
        }
    }
    let twice_area: f64 = (0..n)
        .map(|i| {
            let (a, b) = seg(i);
            a.perp_dot(b)
        })
        .sum();
    if twice_area == 0.0 || !twice_area.is_finite() {
        return Err(PolygonFault::ZeroArea);
    }
    Ok(twice_area)
}

/// Twice the signed area of triangle `a b c` (positive when counter-clockwise).
fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Whether `p`, collinear with `a b`, lies within the segment.
fn within(a: DVec2, b: DVec2, p: DVec2) -> bool {
    p.x >= a.x.min(b.x) && p.x <= a.x.max(b.x) && p.y >= a.y.min(b.y) && p.y <= a.y.max(b.y)
}

/// Whether closed segments `a b` and `c d` have a point in common.
fn segments_meet(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    let opposite = |x: f64, y: f64| (x < 0.0 && y > 0.0) || (x > 0.0 && y < 0.0);
    if opposite(d1, d2) && opposite(d3, d4) {
        return true;
    }
    (d1 == 0.0 && within(c, d, a))
        || (d2 == 0.0 && within(c, d, b))
        || (d3 == 0.0 && within(a, b, c))
        || (d4 == 0.0 && within(a, b, d))
}
