//! The exact tests under every spatial query: points, segments and polygons against a
//! ball, an axis-aligned box and a ray.
//!
//! "Exact" means each answer comes from the closed-form test (the segment–sphere
//! quadratic, the slab clip, the point-in-polygon crossing count), never from a bounding
//! volume. Tests are closed: touching counts as meeting. The tests are arranged so that
//! their answers agree with each other: a segment whose endpoint is inside the ball is
//! entered, and a polygon one of whose boundary segments is entered meets the ball.

use glam::{DVec2, DVec3};

use crate::model::geometry::point_in_polygon;

/// The parameters `[t0, t1] ⊆ [0, 1]` of the part of segment `a`–`b` inside the closed
/// ball of centre `c` and radius `r` (the roots of |a + t(b − a) − c|² = r², clipped),
/// or `None` when the segment misses the ball.
///
/// An endpoint inside the ball (|p − c|² ≤ r²) is always in the answer: its parameter
/// is exactly 0 or 1. A tangent segment answers `t0 == t1`.
pub fn clip_segment_ball(a: DVec3, b: DVec3, c: DVec3, r: f64) -> Option<(f64, f64)> {
    SegmentFrom::new(a, b, c).clip_ball(r * r)
}

/// A segment `a`–`b` seen from a point `p`: the products that both its closest point
/// to `p` ([`SegmentFrom::closest`]) and its clip against a ball about `p`
/// ([`SegmentFrom::clip_ball`]) are made of, computed once. Their answers are those of
/// [`segment_closest`] and [`clip_segment_ball`], bit for bit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentFrom {
    /// Where the segment starts.
    pub a: DVec3,
    /// Where it ends.
    pub b: DVec3,
    /// |b − a|².
    pub l2: f64,
    /// (a − p)·(b − a).
    pub fd: f64,
    /// |a − p|².
    pub fa: f64,
    /// |b − p|².
    pub fb: f64,
}

impl SegmentFrom {
    /// Segment `a`–`b` seen from `p`.
    #[inline]
    pub fn new(a: DVec3, b: DVec3, p: DVec3) -> SegmentFrom {
        SegmentFrom::with_ends(a, b, p, (a - p).length_squared(), (b - p).length_squared())
    }

    /// Segment `a`–`b` seen from `p`, given `fa = |a − p|²` and `fb = |b − p|²` (as
    /// [`SegmentFrom::new`] computes them: a polygon's sides share them).
    #[inline]
    pub fn with_ends(a: DVec3, b: DVec3, p: DVec3, fa: f64, fb: f64) -> SegmentFrom {
        let d = b - a;
        SegmentFrom {
            a,
            b,
            l2: d.length_squared(),
            fd: (a - p).dot(d),
            fa,
            fb,
        }
    }

    /// Squared distance from `p` (the point the segment is seen from) to the segment,
    /// and the closest point: [`segment_closest`]'s answer.
    #[inline]
    pub fn closest(&self, p: DVec3) -> (f64, DVec3) {
        // (p − a)·d is −fd exactly: negation commutes with IEEE rounding.
        closest_at(p, self.a, self.b, self.l2, -self.fd)
    }

    /// The parameters of the part of the segment inside the closed ball of squared
    /// radius `r2` about the point it is seen from: [`clip_segment_ball`]'s answer.
    #[inline]
    pub fn clip_ball(&self, r2: f64) -> Option<(f64, f64)> {
        clip_quadratic(self.l2, 2.0 * self.fd, self.fa - r2, self.fb - r2)
    }
}

/// The same clip as [`clip_segment_ball`] for a segment and a disc in the plane.
pub fn clip_segment_disc(a: DVec2, b: DVec2, c: DVec2, r: f64) -> Option<(f64, f64)> {
    let r2 = r * r;
    let f = a - c;
    let d = b - a;
    clip_quadratic(
        d.length_squared(),
        2.0 * f.dot(d),
        f.length_squared() - r2,
        (b - c).length_squared() - r2,
    )
}

/// The interval of `t ∈ [0, 1]` where `qa t² + qb t + ca ≤ 0`, given also the value
/// `cb` at `t = 1` (computed directly, so that an endpoint test never disagrees with
/// the roots).
fn clip_quadratic(qa: f64, qb: f64, ca: f64, cb: f64) -> Option<(f64, f64)> {
    let (a_in, b_in) = (ca <= 0.0, cb <= 0.0);
    if a_in && b_in {
        // Both ends inside a convex ball: the whole segment is.
        return Some((0.0, 1.0));
    }
    if qa <= 0.0 {
        // A zero-length segment outside the ball.
        return None;
    }
    let disc = qb * qb - 4.0 * qa * ca;
    let (t0, t1) = if disc < 0.0 {
        // Rounding can only make this disagree with an endpoint test, which wins.
        (f64::INFINITY, f64::NEG_INFINITY)
    } else {
        // The stable form of the quadratic formula (no cancellation).
        let s = disc.sqrt();
        let q = -0.5 * (qb + if qb >= 0.0 { s } else { -s });
        let (x, y) = if q == 0.0 {
            (0.0, 0.0)
        } else {
            (q / qa, ca / q)
        };
        (x.min(y), x.max(y))
    };
    match (a_in, b_in) {
        (true, false) => Some((0.0, t1.clamp(0.0, 1.0))),
        (false, true) => Some((t0.clamp(0.0, 1.0), 1.0)),
        _ => {
            // Both ends outside: the segment is entered only if both roots fall inside.
            (t0 <= t1 && t0 >= 0.0 && t1 <= 1.0).then_some((t0, t1))
        }
    }
}

/// The point at parameter `t` of segment `a`–`b`, exactly `a` at 0 and `b` at 1.
#[inline]
pub fn lerp_exact(a: DVec3, b: DVec3, t: f64) -> DVec3 {
    if t <= 0.0 {
        a
    } else if t >= 1.0 {
        b
    } else {
        a + (b - a) * t
    }
}

/// The parameters `[t0, t1] ⊆ [0, 1]` of the part of segment `a`–`b` inside the closed
/// box `lo..=hi` (the slab clip), or `None` when the segment misses it. An endpoint
/// inside the box is always in the answer (parameter exactly 0 or 1).
pub fn clip_segment_box(a: DVec3, b: DVec3, lo: DVec3, hi: DVec3) -> Option<(f64, f64)> {
    let inside = |p: DVec3| p.cmpge(lo).all() && p.cmple(hi).all();
    let (a_in, b_in) = (inside(a), inside(b));
    if a_in && b_in {
        return Some((0.0, 1.0));
    }
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        if d[k] == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return None;
            }
            continue;
        }
        let inv = 1.0 / d[k];
        let (mut n, mut f) = ((lo[k] - a[k]) * inv, (hi[k] - a[k]) * inv);
        if n > f {
            std::mem::swap(&mut n, &mut f);
        }
        t0 = t0.max(n);
        t1 = t1.min(f);
    }
    if a_in {
        t0 = 0.0;
    }
    if b_in {
        t1 = 1.0;
    }
    (t0 <= t1).then_some((t0, t1))
}

/// Squared distance from `p` to segment `a`–`b`, and the closest point.
#[inline]
pub fn segment_closest(p: DVec3, a: DVec3, b: DVec3) -> (f64, DVec3) {
    let d = b - a;
    closest_at(p, a, b, d.length_squared(), (p - a).dot(d))
}

/// [`segment_closest`] given `l2 = |b − a|²` and `pd = (p − a)·(b − a)`.
#[inline]
fn closest_at(p: DVec3, a: DVec3, b: DVec3, l2: f64, pd: f64) -> (f64, DVec3) {
    let t = if l2 > 0.0 {
        (pd / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = lerp_exact(a, b, t);
    ((p - q).length_squared(), q)
}

/// The two coordinates kept when a polygon with normal `n` is projected on the
/// coordinate plane it is most nearly parallel to (dropping the dominant axis keeps
/// inside and outside as they are).
#[inline]
pub fn drop_axis(n: DVec3) -> (usize, usize) {
    let a = n.abs();
    if a.x >= a.y && a.x >= a.z {
        (1, 2)
    } else if a.y >= a.z {
        (2, 0)
    } else {
        (0, 1)
    }
}

/// Whether `p` is inside the closed polygon loop `pts` (projected on axes `(i, j)`), by
/// the crossing count. Points exactly on the boundary may answer either way; callers
/// test the boundary separately. A segment walked twice (a bridge or spur) cancels.
pub fn in_polygon(
    p: DVec3,
    pts: impl Iterator<Item = DVec3> + Clone,
    (i, j): (usize, usize),
) -> bool {
    let (px, py) = (p[i], p[j]);
    let mut inside = false;
    let mut it = pts.clone();
    let Some(first) = it.next() else {
        return false;
    };
    let mut prev = first;
    for q in it.chain(std::iter::once(first)) {
        inside ^= crosses((px, py), prev, q, (i, j));
        prev = q;
    }
    inside
}

/// Whether side `a`–`b` of a polygon (projected on axes `(i, j)`) crosses the ray from
/// `(px, py)` towards +i: one step of [`in_polygon`]'s crossing count.
#[inline]
pub fn crosses((px, py): (f64, f64), a: DVec3, b: DVec3, (i, j): (usize, usize)) -> bool {
    let (ax, ay, bx, by) = (a[i], a[j], b[i], b[j]);
    (ay > py) != (by > py) && px < ax + (py - ay) * (bx - ax) / (by - ay)
}

/// How far a point `p` found on a polygon's plane is from the polygon's boundary,
/// relative to the polygon's size: used to decide whether a ray crossing is too close
/// to an edge for its parity to be trusted.
pub fn boundary_margin(p: DVec3, pts: impl Iterator<Item = DVec3> + Clone) -> f64 {
    let mut it = pts.clone();
    let Some(first) = it.next() else {
        return 0.0;
    };
    let mut prev = first;
    let mut best = f64::INFINITY;
    for q in it.chain(std::iter::once(first)) {
        best = best.min(segment_closest(p, prev, q).0);
        prev = q;
    }
    best.sqrt()
}

/// Sutherland–Hodgman: the polygon `poly` clipped to the closed box `lo..=hi`. Exact
/// for a convex polygon; for a concave one the parts are joined along the box's faces.
/// Empty when the polygon misses the box; a touching polygon keeps its touching points.
pub fn clip_polygon_box(poly: &[DVec3], lo: DVec3, hi: DVec3) -> Vec<DVec3> {
    let mut cur = poly.to_vec();
    let mut next = Vec::with_capacity(poly.len() + 6);
    for k in 0..3 {
        for (bound, keep_below) in [(hi[k], true), (lo[k], false)] {
            if cur.is_empty() {
                return cur;
            }
            next.clear();
            let inside = |p: DVec3| {
                if keep_below {
                    p[k] <= bound
                } else {
                    p[k] >= bound
                }
            };
            let mut prev = cur[cur.len() - 1];
            for &q in &cur {
                let (pi, qi) = (inside(prev), inside(q));
                if pi != qi {
                    let t = (bound - prev[k]) / (q[k] - prev[k]);
                    let mut x = prev + (q - prev) * t;
                    x[k] = bound;
                    next.push(x);
                }
                if qi {
                    next.push(q);
                }
                prev = q;
            }
            std::mem::swap(&mut cur, &mut next);
        }
    }
    cur.dedup();
    if cur.len() > 1 && cur.first() == cur.last() {
        cur.pop();
    }
    cur
}

/// The portion of a planar polygon inside a disc: the loops bounding polygon ∩ disc,
/// where the disc's circle is followed by chords no farther than `tolerance` from it.
///
/// `poly` is the polygon in 2D (counter-clockwise, possibly concave, possibly with
/// bridges walked twice), the disc is centred on the origin with radius `rho`. Returns
/// the loops of the intersection, each counter-clockwise; a polygon touching the circle
/// at one point answers that point as a one-point loop. Empty when they are apart.
pub fn polygon_disc(poly: &[DVec2], rho: f64, tolerance: f64) -> Vec<Vec<DVec2>> {
    let n = poly.len();
    if n == 0 {
        return Vec::new();
    }
    let r2 = rho * rho;
    let inside = |p: DVec2| p.length_squared() <= r2;
    let Some(start) = (0..n).find(|&i| !inside(poly[i])) else {
        return vec![poly.to_vec()];
    };
    // Runs of the boundary inside the disc: each from an entry point to an exit point.
    let mut runs: Vec<Vec<DVec2>> = Vec::new();
    let mut touches: Vec<DVec2> = Vec::new();
    let mut open: Option<Vec<DVec2>> = None;
    for k in 0..n {
        let i = (start + k) % n;
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let (a_in, b_in) = (inside(a), inside(b));
        let clip = clip_segment_disc(a, b, DVec2::ZERO, rho);
        let at = |t: f64| {
            if t <= 0.0 {
                a
            } else if t >= 1.0 {
                b
            } else {
                a + (b - a) * t
            }
        };
        match (a_in, b_in, clip) {
            (true, true, _) => {
                if let Some(run) = open.as_mut() {
                    run.push(b);
                }
            }
            (true, false, Some((_, t1))) => {
                if let Some(mut run) = open.take() {
                    run.push(at(t1));
                    runs.push(run);
                }
            }
            (false, true, Some((t0, _))) => {
                open = Some(vec![at(t0), b]);
            }
            (false, false, Some((t0, t1))) => {
                if t0 < t1 {
                    runs.push(vec![at(t0), at(t1)]);
                } else {
                    touches.push(at(t0));
                }
            }
            _ => {}
        }
    }
    if runs.is_empty() {
        if point_in_polygon(DVec2::ZERO, poly) {
            return vec![circle_arc(
                rho,
                0.0,
                std::f64::consts::TAU,
                tolerance,
                false,
            )];
        }
        return touches.into_iter().take(1).map(|p| vec![p]).collect();
    }
    // Join each run's exit to the next entry counter-clockwise along the circle.
    let angle = |p: DVec2| p.y.atan2(p.x);
    let entries: Vec<f64> = runs.iter().map(|r| angle(r[0])).collect();
    let mut used = vec![false; runs.len()];
    let mut loops = Vec::new();
    for first in 0..runs.len() {
        if used[first] {
            continue;
        }
        let mut out: Vec<DVec2> = Vec::new();
        let mut cur = first;
        loop {
            used[cur] = true;
            out.extend_from_slice(&runs[cur]);
            let exit = angle(runs[cur][runs[cur].len() - 1]);
            let next = (0..runs.len())
                .min_by(|&x, &y| ccw_from(exit, entries[x]).total_cmp(&ccw_from(exit, entries[y])))
                .unwrap_or(first);
            let sweep = ccw_from(exit, entries[next]);
            out.extend(circle_arc(rho, exit, sweep, tolerance, true));
            if used[next] {
                break;
            }
            cur = next;
        }
        loops.push(out);
    }
    loops
}

/// The counter-clockwise angle from `from` to `to`, in `[0, 2π)`.
fn ccw_from(from: f64, to: f64) -> f64 {
    (to - from).rem_euclid(std::f64::consts::TAU)
}

/// Points on the circle of radius `rho` from angle `start` sweeping `sweep`
/// counter-clockwise, spaced so that no chord is farther than `tolerance` from the arc.
/// With `interior_only` the two ends are left out (they are already on the boundary).
fn circle_arc(rho: f64, start: f64, sweep: f64, tolerance: f64, interior_only: bool) -> Vec<DVec2> {
    let step = chord_angle(rho, tolerance);
    let pieces = ((sweep / step).ceil() as usize).clamp(1, MAX_ARC_POINTS);
    let (from, to) = if interior_only {
        (1, pieces)
    } else {
        (0, pieces)
    };
    (from..to)
        .map(|k| {
            let a = start + sweep * k as f64 / pieces as f64;
            DVec2::new(rho * a.cos(), rho * a.sin())
        })
        .collect()
}

/// The most points any arc is drawn with.
pub const MAX_ARC_POINTS: usize = 4096;

/// The largest angle whose chord on a circle of radius `rho` strays at most `tolerance`
/// from the arc (sagitta ρ(1 − cos(θ/2)) ≤ tolerance).
pub fn chord_angle(rho: f64, tolerance: f64) -> f64 {
    if rho <= tolerance {
        return std::f64::consts::PI;
    }
    2.0 * (1.0 - tolerance / rho).clamp(-1.0, 1.0).acos()
}

/// How far the chords of an arc of radius `rho` drawn by [`polygon_disc`] stray from the
/// circle at most, for a requested `tolerance` (more than asked only when the arc would
/// need more than [`MAX_ARC_POINTS`] points).
pub fn achieved_tolerance(rho: f64, tolerance: f64) -> f64 {
    let wanted = chord_angle(rho, tolerance);
    let least = std::f64::consts::TAU / MAX_ARC_POINTS as f64;
    if wanted >= least {
        // The chords are as asked (their sagitta is at most the tolerance, up to rounding).
        return tolerance.min(rho);
    }
    rho * (1.0 - (least * 0.5).cos())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_segment_through_the_ball_is_clipped_at_the_roots() {
        let (t0, t1) = clip_segment_ball(
            DVec3::new(-2.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::ZERO,
            1.0,
        )
        .unwrap();
        assert_eq!((t0, t1), (0.25, 0.75));
    }

    /// The shared products answer as the separate tests did: the closest point from
    /// (p − a)·d and the clip from |a − c|² − r², |b − c|² − r², 2 (a − c)·d.
    #[test]
    fn a_segment_seen_from_a_point_answers_bit_for_bit_as_the_separate_tests() {
        let mut next = crate::spatial::testing::unit(0x9e37_79b9_7f4a_7c15);
        let mut point = || DVec3::new(next(), next(), next()) * 4.0 - 2.0;
        for _ in 0..10_000 {
            let (a, b, p) = (point(), point(), point());
            let r = p.x.abs() + 0.5;
            let s = SegmentFrom::new(a, b, p);
            let d = b - a;
            let l2 = d.length_squared();
            let t = if l2 > 0.0 {
                ((p - a).dot(d) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let q = lerp_exact(a, b, t);
            let want = ((p - q).length_squared(), q);
            assert_eq!(s.closest(p), want);
            let f = a - p;
            let r2 = r * r;
            let clip = clip_quadratic(
                l2,
                2.0 * f.dot(d),
                f.length_squared() - r2,
                (b - p).length_squared() - r2,
            );
            assert_eq!(s.clip_ball(r2), clip);
            assert_eq!(clip_segment_ball(a, b, p, r), clip);
        }
    }

    #[test]
    fn a_tangent_segment_touches_at_one_point_and_a_near_miss_misses() {
        let a = DVec3::new(-1.0, 1.0, 0.0);
        let b = DVec3::new(1.0, 1.0, 0.0);
        assert_eq!(clip_segment_ball(a, b, DVec3::ZERO, 1.0), Some((0.5, 0.5)));
        assert_eq!(clip_segment_ball(a, b, DVec3::ZERO, 0.999_999), None);
    }

    #[test]
    fn an_endpoint_on_the_sphere_is_inside() {
        let a = DVec3::new(1.0, 0.0, 0.0);
        let b = DVec3::new(3.0, 0.0, 0.0);
        assert_eq!(clip_segment_ball(a, b, DVec3::ZERO, 1.0), Some((0.0, 0.0)));
        assert_eq!(clip_segment_ball(b, a, DVec3::ZERO, 1.0), Some((1.0, 1.0)));
    }

    #[test]
    fn the_slab_clip_keeps_touching_points() {
        let lo = DVec3::splat(-1.0);
        let hi = DVec3::splat(1.0);
        let c = clip_segment_box(
            DVec3::new(-3.0, 0.0, 0.0),
            DVec3::new(3.0, 0.0, 0.0),
            lo,
            hi,
        );
        assert_eq!(c, Some((1.0 / 3.0, 2.0 / 3.0)));
        let touch = clip_segment_box(
            DVec3::new(1.0, -3.0, 0.0),
            DVec3::new(1.0, 3.0, 0.0),
            lo,
            hi,
        );
        assert!(touch.is_some());
        let miss = clip_segment_box(
            DVec3::new(1.5, -3.0, 0.0),
            DVec3::new(1.5, 3.0, 0.0),
            lo,
            hi,
        );
        assert_eq!(miss, None);
    }

    fn area(l: &[DVec2]) -> f64 {
        let mut a = 0.0;
        for i in 0..l.len() {
            let (p, q) = (l[i], l[(i + 1) % l.len()]);
            a += p.x * q.y - q.x * p.y;
        }
        a * 0.5
    }

    #[test]
    fn a_square_and_a_disc_meet_in_the_expected_area() {
        let sq = [
            DVec2::new(0.0, -2.0),
            DVec2::new(2.0, -2.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(0.0, 2.0),
        ];
        // Half the unit disc lies in x ≥ 0.
        let loops = polygon_disc(&sq, 1.0, 1e-6);
        assert_eq!(loops.len(), 1);
        let a = area(&loops[0]);
        assert!((a - std::f64::consts::FRAC_PI_2).abs() < 1e-5, "{a}");
        // The disc inside the square: a full circle.
        let big = [
            DVec2::new(-2.0, -2.0),
            DVec2::new(2.0, -2.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(-2.0, 2.0),
        ];
        let loops = polygon_disc(&big, 1.0, 1e-6);
        assert!((area(&loops[0]) - std::f64::consts::PI).abs() < 1e-5);
        // The square inside a large disc: itself.
        assert_eq!(polygon_disc(&big, 10.0, 1e-6), vec![big.to_vec()]);
    }

    #[test]
    fn a_concave_polygon_can_meet_a_disc_in_two_pieces() {
        // A U shape whose two arms cross the disc and whose base is outside it.
        let u = [
            DVec2::new(-3.0, -3.0),
            DVec2::new(3.0, -3.0),
            DVec2::new(3.0, 3.0),
            DVec2::new(0.5, 3.0),
            DVec2::new(0.5, -2.0),
            DVec2::new(-0.5, -2.0),
            DVec2::new(-0.5, 3.0),
            DVec2::new(-3.0, 3.0),
        ];
        let loops = polygon_disc(&u, 1.0, 1e-4);
        assert_eq!(loops.len(), 2);
        let total: f64 = loops.iter().map(|l| area(l)).sum();
        // The disc minus the strip |x| < 0.5: π − (2·(asin(0.5)·1 + 0.5·cos(asin 0.5))).
        let strip = 2.0 * (0.5f64.asin() + 0.5 * (1.0 - 0.25f64).sqrt());
        assert!(
            (total - (std::f64::consts::PI - strip)).abs() < 1e-3,
            "{total}"
        );
    }

    #[test]
    fn chords_stay_within_the_tolerance() {
        let rho = 2.0;
        for tol in [1e-1, 1e-3, 1e-6] {
            let step = chord_angle(rho, tol);
            let sag = rho * (1.0 - (step / 2.0).cos());
            assert!(sag <= tol * (1.0 + 1e-9));
            assert!(achieved_tolerance(rho, tol) <= tol * (1.0 + 1e-9));
        }
    }
}
