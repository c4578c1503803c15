//! How far one posed body reaches into a ball or a box: its faces, edges and vertices
//! there, exactly, in world coordinates.

use glam::{DAffine3, DVec2, DVec3};

use super::aabb::Aabb;
use super::exact::{
    SegmentFrom, achieved_tolerance, clip_polygon_box, clip_segment_box, lerp_exact, polygon_disc,
};
use super::query::{Detail, EdgeHit, FaceHit, VertexHit};
use super::shape::{BodyShape, Closest, Corner};
use crate::model::Pose;

/// The features of one body found by a query, in world coordinates.
#[derive(Default)]
pub struct Features {
    /// Faces meeting the region.
    pub faces: Vec<FaceHit>,
    /// Edges entering it, clipped.
    pub edges: Vec<EdgeHit>,
    /// Vertices inside it.
    pub vertices: Vec<VertexHit>,
    /// The largest chord deviation of the portions drawn.
    pub tolerance: f64,
}

impl Features {
    /// How many features were found.
    pub fn count(&self) -> usize {
        self.faces.len() + self.edges.len() + self.vertices.len()
    }

    /// Sorts each list by id.
    pub fn sort(&mut self) {
        sort_by_id(
            &mut self.faces,
            |f| f.id,
            |f| {
                // A face's portion is moved out, not copied.
                let portion = f.portion.take();
                FaceHit { portion, ..*f }
            },
        );
        sort_by_id(&mut self.edges, |e| e.id, |e| *e);
        sort_by_id(&mut self.vertices, |v| v.id, |v| *v);
    }
}

/// Sorts `items` by `id`, distinct for each item; `take` moves an item out of its slot
/// (each slot is taken once, and the slots are then dropped).
///
/// At most [`SORT_IN_PLACE`] items are sorted where they lie. For more, when the ids
/// span less than `2^(64 − b)`, with `b` the bits of an index into `items` (always,
/// for the features of one body), each item's key is one `u64`: its id less the least
/// id, shifted, with its index in the low bits. The keys sort without branches, and
/// the items are gathered in their order. Otherwise the items are sorted by id
/// directly.
fn sort_by_id<T>(items: &mut Vec<T>, id: impl Fn(&T) -> u64, take: impl Fn(&mut T) -> T) {
    let n = items.len();
    if n <= SORT_IN_PLACE {
        // A few items (a small body's): sorted where they lie, without the keys' and
        // the gathered list's allocations.
        items.sort_unstable_by_key(id);
        return;
    }
    let (lo, hi) = items
        .iter()
        .map(&id)
        .fold((u64::MAX, 0), |(lo, hi), i| (lo.min(i), hi.max(i)));
    let index_bits = usize::BITS - (n - 1).leading_zeros();
    if index_bits >= 32 || (hi - lo) >> (64 - index_bits) != 0 {
        items.sort_unstable_by_key(id);
        return;
    }
    let low = (1u64 << index_bits) - 1;
    let mut keys: Vec<u64> = items
        .iter()
        .enumerate()
        .map(|(k, t)| (id(t) - lo) << index_bits | k as u64)
        .collect();
    keys.sort_unstable();
    *items = keys
        .iter()
        .map(|&k| take(&mut items[(k & low) as usize]))
        .collect();
}

/// Items at most that [`sort_by_id`] sorts in place.
const SORT_IN_PLACE: usize = 20;

/// How much a squared cull radius is widened so that rounding in box distances never
/// drops a face that the exact test would keep.
#[inline]
pub fn cull_radius2(r: f64) -> f64 {
    let r2 = r * r;
    r2 + r2 * 1e-9 + f64::MIN_POSITIVE
}

/// The ball of centre `c` (body frame) and radius `r` against `shape` posed at `pose`:
/// `Some((distance, inside))` when the body's solid meets the ball, with its features
/// (at `detail` above `bodies`) appended to `out` in world coordinates.
pub fn ball(
    shape: &BodyShape,
    pose: &Pose,
    c: DVec3,
    r: f64,
    detail: Detail,
    tolerance: f64,
    out: &mut Features,
) -> Option<(f64, bool)> {
    let r2 = r * r;
    let features = detail != Detail::Bodies;
    let cull2 = cull_radius2(r);
    let ball = Ball {
        shape,
        // A matrix maps the many points reported faster than the quaternion.
        world: pose.to_affine(),
        c,
        r,
        r2,
        cull2,
        detail,
        tolerance,
    };
    // Each face's sides seen from the centre, made once for its closest point and its
    // clips (see `Ball::test`).
    let mut sides: Vec<SegmentFrom> = Vec::new();
    if !features && shape.faces.len() > NEAREST_FIRST {
        // At `bodies` detail the answer is the nearest of the faces that meet the ball.
        // When the face nearest the centre meets it, that is the answer: the hierarchy's
        // nearest walk finds it in a few leaves, where testing every face in the ball
        // would read them all. When no face is that near, none meets the ball.
        match shape.nearest_face(c, cull2) {
            None => return conclude(shape, c, None),
            Some((k, _)) => {
                let mut nearest = None;
                ball.test(k, &mut sides, &mut nearest, out);
                if nearest.is_some() {
                    return conclude(shape, c, nearest);
                }
                // The nearest face is within rounding of the ball but misses it: the
                // faces are tried one by one below.
            }
        }
    }
    let mut nearest: Option<Closest> = None;
    if shape.is_small() {
        // A small shape's faces are tested as the walk finds them: its records are
        // read whole before its tests (see `BodyShape::touch_all`). At `features`
        // detail, room is made for all its features at once.
        if features {
            out.faces.reserve(shape.faces.len());
            out.edges.reserve(shape.edge_serials.len());
            out.vertices.reserve(shape.points.len());
        }
        shape
            .bvh
            .within(c, cull2, |k| ball.test(k, &mut sides, &mut nearest, out));
        return conclude(shape, c, nearest);
    }
    // A large shape's candidate faces are gathered first and tested with their records
    // prefetched a few faces ahead (`BodyShape::visit_ahead`), so that the cache misses
    // of a query on a large shape overlap the tests instead of stalling them.
    let mut candidates: Vec<u32> = Vec::with_capacity(256);
    shape.bvh.within(c, cull2, |k| candidates.push(k as u32));
    if features {
        // Most candidate faces meet the ball, with about as many edges as faces (each
        // edge reported by one of its two faces) and half as many vertices.
        let n = candidates.len();
        out.faces.reserve(n);
        out.edges.reserve(n * 3 / 2);
        out.vertices.reserve(n / 2 + 1);
    }
    shape.visit_ahead(&candidates, |k| ball.test(k, &mut sides, &mut nearest, out));
    conclude(shape, c, nearest)
}

/// Faces above which a body's answer at `bodies` detail starts from its face nearest the
/// centre (see [`ball`]); a body of fewer has them all tested, as cheaply.
const NEAREST_FIRST: usize = 64;

/// The answer of [`ball`] for `shape` and centre `c` (body frame), from the closest
/// point of the nearest face meeting the ball (`None`: no face meets it).
fn conclude(shape: &BodyShape, c: DVec3, nearest: Option<Closest>) -> Option<(f64, bool)> {
    match nearest {
        Some(n) => {
            // The nearest point inside a face: the face plane's side tells; on an edge
            // or a vertex it does not, so count crossings.
            let inside = if n.interior {
                n.plane_distance <= 0.0
            } else {
                shape.contains(c)
            };
            Some((if inside { 0.0 } else { n.d2.sqrt() }, inside))
        }
        // No face meets the ball: either it is wholly inside the solid or apart from it.
        None => shape.contains(c).then_some((0.0, true)),
    }
}

/// A ball query against one posed shape, as [`ball`] runs it face by face.
struct Ball<'a> {
    shape: &'a BodyShape,
    /// The shape's pose, as a matrix.
    world: DAffine3,
    /// Centre (body frame).
    c: DVec3,
    r: f64,
    /// `r²`.
    r2: f64,
    /// [`cull_radius2`] of `r`.
    cull2: f64,
    detail: Detail,
    tolerance: f64,
}

impl Ball<'_> {
    /// [`Ball::face`] for face `k`, its sides made on the stack for a triangle or a
    /// quadrilateral (the loops over them then unroll), in `sides` otherwise.
    #[inline(always)]
    fn test(
        &self,
        k: usize,
        sides: &mut Vec<SegmentFrom>,
        nearest: &mut Option<Closest>,
        out: &mut Features,
    ) {
        let (shape, c) = (self.shape, self.c);
        let cs = shape.corners_of(k);
        if let Ok(cs) = <&[Corner; 3]>::try_from(cs) {
            self.face(k, cs, &shape.sides_of(cs, c), nearest, out);
        } else if let Ok(cs) = <&[Corner; 4]>::try_from(cs) {
            self.face(k, cs, &shape.sides_of(cs, c), nearest, out);
        } else {
            sides.clear();
            sides.extend(shape.sides_from(k, c));
            self.face(k, cs, sides, nearest, out);
        }
    }

    /// Face `k`, of corners `cs` and sides `sides` (seen from the centre, as
    /// [`BodyShape::sides_from`] makes them), against the ball: when it meets the ball,
    /// its closest point is kept in `nearest` if nearer than what is there, and at
    /// `detail` above `bodies` the face, the edges and the vertices it reports are
    /// appended to `out`.
    #[inline(always)]
    fn face(
        &self,
        k: usize,
        cs: &[Corner],
        sides: &[SegmentFrom],
        nearest: &mut Option<Closest>,
        out: &mut Features,
    ) {
        let Ball {
            shape,
            world,
            c,
            r,
            r2,
            cull2,
            detail,
            tolerance,
        } = *self;
        let features = detail != Detail::Bodies;
        // A face whose bounds are farther than the ball (beyond rounding) has no point
        // in it; the bounds are cheaper than the closest point.
        if Aabb::of_points(sides.iter().map(|s| s.a)).distance_squared(c) > cull2 {
            return;
        }
        let closest = shape.closest_of_sides(k, c, sides.iter().copied());
        if closest.d2 > cull2 {
            return;
        }
        let mut meets = closest.interior && closest.d2 <= r2;
        for (side, corner) in sides.iter().zip(cs) {
            let a_in = features && side.fa <= r2;
            // Once the face is known to meet the ball, a side is clipped only for what
            // its corner reports.
            if meets && !(features && reports(corner, a_in)) {
                continue;
            }
            let Some((t0, t1)) = side.clip_ball(r2) else {
                continue;
            };
            meets = true;
            if features {
                report(
                    shape,
                    corner,
                    [side.a, side.b],
                    (t0, t1),
                    a_in,
                    |p| world.transform_point3(p),
                    out,
                );
            }
        }
        if !meets {
            return;
        }
        if nearest.is_none_or(|n| closest.d2 < n.d2) {
            *nearest = Some(closest);
        }
        if features {
            let portion = (detail == Detail::Portions).then(|| {
                let (loops, tol) = disc_portion(shape, k, c, r, tolerance);
                out.tolerance = out.tolerance.max(tol);
                loops
                    .into_iter()
                    .map(|l| l.into_iter().map(|p| world.transform_point3(p)).collect())
                    .collect()
            });
            out.faces.push(FaceHit {
                id: shape.faces[k].serial,
                distance: Some(closest.d2.sqrt()),
                portion,
            });
        }
    }
}

/// Whether [`report`] appends anything for `corner` (with `a_in` whether its starting
/// vertex is inside the region) when its side enters the region.
#[inline]
fn reports(corner: &Corner, a_in: bool) -> bool {
    corner.reports_edge() || (corner.reports_vertex() && a_in)
}

/// Appends what a perimeter corner reports of a region its segment `ab` enters over
/// `t0..=t1`: its edge, clipped (if the corner is the edge's canonical one), and its
/// starting vertex `a` when `a_in` (if the corner is the vertex's canonical one).
/// `world` maps the segment's frame to the world.
fn report(
    shape: &BodyShape,
    corner: &Corner,
    [a, b]: [DVec3; 2],
    (t0, t1): (f64, f64),
    a_in: bool,
    world: impl Fn(DVec3) -> DVec3,
    out: &mut Features,
) {
    if corner.reports_edge() {
        out.edges.push(EdgeHit {
            id: shape.edge_serials[corner.edge() as usize],
            segment: [world(lerp_exact(a, b, t0)), world(lerp_exact(a, b, t1))],
        });
    }
    if corner.reports_vertex() && a_in {
        out.vertices.push(VertexHit {
            id: shape.vertex_serials[corner.vertex as usize],
            position: world(a),
        });
    }
}

/// The part of face `k` inside the ball (body frame) and the chord deviation drawn with.
fn disc_portion(
    shape: &BodyShape,
    k: usize,
    c: DVec3,
    r: f64,
    tolerance: f64,
) -> (Vec<Vec<DVec3>>, f64) {
    let f = &shape.faces[k];
    let n = f.normal;
    if n == DVec3::ZERO {
        return (Vec::new(), 0.0);
    }
    let pd = n.dot(c) - f.offset;
    let rho = (r * r - pd * pd).max(0.0).sqrt();
    let o = c - n * pd;
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let poly: Vec<DVec2> = shape
        .loop_points(k)
        .map(|p| DVec2::new((p - o).dot(u), (p - o).dot(v)))
        .collect();
    let loops = polygon_disc(&poly, rho, tolerance)
        .into_iter()
        .map(|l| l.into_iter().map(|q| o + u * q.x + v * q.y).collect())
        .collect();
    (loops, achieved_tolerance(rho, tolerance))
}

/// The closed world box `lo..=hi` against `shape` posed at `pose` (`inverse` its
/// inverse): `Some(inside)` when the body's solid meets the box (inside: the box's
/// centre is in the solid), with its features (at `detail` above `bodies`) appended to
/// `out` in world coordinates.
pub fn aabb(
    shape: &BodyShape,
    pose: &Pose,
    inverse: &Pose,
    lo: DVec3,
    hi: DVec3,
    detail: Detail,
    out: &mut Features,
) -> Option<bool> {
    let features = detail != Detail::Bodies;
    let local = Aabb::new(lo, hi).transformed(inverse);
    let mut pts: Vec<DVec3> = Vec::new();
    let in_box = |p: DVec3| p.cmpge(lo).all() && p.cmple(hi).all();
    let region = Aabb::new(lo, hi);
    // A matrix maps the corners faster than the quaternion.
    let world = pose.to_affine();
    // Whether face `k` meets the box; at `features` detail and above, what it reports
    // is appended to `out`.
    let mut face = |k: usize| -> bool {
        let cs = shape.corners_of(k);
        pts.clear();
        pts.extend(shape.loop_points(k).map(|p| world.transform_point3(p)));
        // A face whose world bounds miss the box has no point in it (the hierarchy's
        // boxes are in the body's frame, so their leaves can reach past the box).
        if !Aabb::of_points(pts.iter().copied()).overlaps(&region) {
            return false;
        }
        let mut meets = false;
        for (i, corner) in cs.iter().enumerate() {
            let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
            let Some((t0, t1)) = clip_segment_box(a, b, lo, hi) else {
                continue;
            };
            meets = true;
            if features {
                report(shape, corner, [a, b], (t0, t1), in_box(a), |p| p, out);
            }
        }
        let clipped =
            (!meets || detail == Detail::Portions).then(|| clip_polygon_box(&pts, lo, hi));
        meets |= clipped.as_ref().is_some_and(|c| !c.is_empty());
        if !meets {
            return false;
        }
        if features {
            let portion = (detail == Detail::Portions).then(|| {
                clipped
                    .filter(|c| !c.is_empty())
                    .map_or_else(Vec::new, |c| vec![c])
            });
            out.faces.push(FaceHit {
                id: shape.faces[k].serial,
                distance: None,
                portion,
            });
        }
        true
    };
    let mut met = false;
    if !features {
        // At `bodies` detail the walk stops at the first face that meets the box.
        shape.bvh.overlapping_until(local.min, local.max, |k| {
            met = face(k);
            !met
        });
    } else if shape.is_small() {
        // Every face in the box is wanted. A small shape's are tested as the walk finds
        // them, a large shape's gathered first and tested with their records prefetched
        // ahead (as in `ball`).
        shape
            .bvh
            .overlapping(local.min, local.max, |k| met |= face(k));
    } else {
        let mut candidates: Vec<u32> = Vec::with_capacity(256);
        shape
            .bvh
            .overlapping(local.min, local.max, |k| candidates.push(k as u32));
        shape.visit_ahead(&candidates, |k| met |= face(k));
    }
    let centre = inverse.transform_point((lo + hi) * 0.5);
    let inside = shape.contains(centre);
    (met || inside).then_some(inside)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Serials;
    use crate::model::solids::{sphere, torus};
    use crate::spatial::testing::{unit, xorshift};
    use std::sync::Arc;

    /// Two shapes of more than [`NEAREST_FIRST`] faces: a sphere (convex; triangles and
    /// quadrilaterals) and a torus (of genus 1, with saddles).
    fn large_shapes() -> [BodyShape; 2] {
        let mut serials = Serials::new();
        [
            sphere(&mut serials, 2.0, 12, 7).expect("a sphere"),
            torus(&mut serials, 3.0, 1.0, 16, 8).expect("a torus"),
        ]
        .map(|b| BodyShape::build(Arc::new(b)))
    }

    /// How many answers met a body with the centre outside it, met it with the centre
    /// inside, and missed it: a test's cases must cover all three.
    #[derive(Default)]
    struct Tally {
        met: usize,
        inside: usize,
        missed: usize,
    }

    impl Tally {
        /// Counts an answer: `Some(inside)` when the body was met.
        fn count(&mut self, answer: Option<bool>) {
            match answer {
                Some(true) => self.inside += 1,
                Some(false) => self.met += 1,
                None => self.missed += 1,
            }
        }

        /// Asserts that each kind of answer came more often than the floor given.
        fn assert_over(&self, met: usize, missed: usize, inside: usize) {
            assert!(
                self.met > met && self.missed > missed && self.inside > inside,
                "met {}, missed {}, inside {}",
                self.met,
                self.missed,
                self.inside
            );
        }
    }

    /// A large body's answer at `bodies` detail, which starts from its face nearest the
    /// centre, is the answer of testing every face in the ball (as `features` detail
    /// does): the same bodies met, distances and inside flags, over centres inside,
    /// outside and on the surface, and radii from a grazing touch to the whole body.
    #[test]
    fn the_nearest_face_first_answers_as_every_face_tested() {
        let mut next = unit(0x853c_49e6_748f_ea9b);
        let mut tally = Tally::default();
        for shape in large_shapes() {
            assert!(shape.faces.len() > NEAREST_FIRST);
            let corners: Vec<DVec3> = shape.points.clone();
            for i in 0..600 {
                // Some centres at a vertex (on the surface), the rest anywhere about.
                let c = if i % 10 == 0 {
                    corners[i % corners.len()]
                } else {
                    DVec3::new(next(), next(), next()) * 10.0 - 5.0
                };
                let r = [0.0, 1e-9, 0.3, 1.0, 2.5, 9.0][i % 6];
                let answer = |detail| {
                    let mut out = Features::default();
                    ball(&shape, &Pose::IDENTITY, c, r, detail, 1e-3, &mut out)
                };
                let quick = answer(Detail::Bodies);
                assert_eq!(quick, answer(Detail::Features), "at {c}, r {r}");
                tally.count(quick.map(|(_, inside)| inside));
            }
        }
        tally.assert_over(100, 100, 50);
    }

    /// A box query at `bodies` detail, which stops at the first face that meets the
    /// box, answers as `features` detail, which tests every face: the same bodies met
    /// and the same inside flags, over boxes inside, outside, across and around bodies.
    #[test]
    fn a_box_at_bodies_detail_answers_as_every_face_tested() {
        let mut next = unit(0x2545_f491_4f6c_dd1d);
        let pose = Pose::new(
            DVec3::new(0.5, -0.25, 1.0),
            glam::DQuat::from_rotation_z(0.3),
        )
        .expect("a pose");
        let inverse = pose.inverse();
        let mut tally = Tally::default();
        for shape in large_shapes() {
            for i in 0..600 {
                let c = DVec3::new(next(), next(), next()) * 10.0 - 5.0;
                let half = DVec3::new(next(), next(), next()) * [0.05, 0.5, 2.0, 6.0][i % 4];
                let (lo, hi) = (c - half, c + half);
                let answer = |detail| {
                    let mut out = Features::default();
                    aabb(&shape, &pose, &inverse, lo, hi, detail, &mut out)
                };
                let quick = answer(Detail::Bodies);
                assert_eq!(quick, answer(Detail::Features), "box {lo}..{hi}");
                tally.count(quick);
            }
        }
        tally.assert_over(100, 100, 20);
    }

    #[test]
    fn features_sort_by_id_over_narrow_and_wide_id_ranges() {
        let mut next = xorshift(0x2545_f491_4f6c_dd1d);
        // Few ids (sorted in place); ids close together (packed keys); and ids spanning
        // all of u64 (the direct sort).
        for spread in [1_000u64, u64::MAX] {
            for n in [0, 1, 2, 5, SORT_IN_PLACE, SORT_IN_PLACE + 1, 120, 1000] {
                let mut ids: Vec<u64> = (0..n).map(|_| next() % spread).collect();
                ids.sort_unstable();
                ids.dedup();
                let mut shuffled = ids.clone();
                for i in (1..shuffled.len()).rev() {
                    shuffled.swap(i, (next() % (i as u64 + 1)) as usize);
                }
                // Each face carries a portion naming its id, to see that it moves whole.
                let mut f = Features {
                    faces: shuffled
                        .iter()
                        .map(|&id| FaceHit {
                            id,
                            distance: Some(id as f64),
                            portion: Some(vec![vec![DVec3::splat(id as f64)]]),
                        })
                        .collect(),
                    vertices: shuffled
                        .iter()
                        .map(|&id| VertexHit {
                            id,
                            position: DVec3::splat(id as f64),
                        })
                        .collect(),
                    ..Features::default()
                };
                f.sort();
                let faces: Vec<(u64, f64)> = f
                    .faces
                    .iter()
                    .map(|h| {
                        let p = h.portion.as_ref().expect("a portion");
                        assert_eq!(h.distance, Some(p[0][0].x));
                        (h.id, p[0][0].x)
                    })
                    .collect();
                let want: Vec<(u64, f64)> = ids.iter().map(|&i| (i, i as f64)).collect();
                assert_eq!(faces, want, "{n} faces under {spread}");
                let vertices: Vec<(u64, f64)> =
                    f.vertices.iter().map(|v| (v.id, v.position.y)).collect();
                assert_eq!(vertices, want, "{n} vertices under {spread}");
            }
        }
    }
}
