//! Small convex solids as flat records in world coordinates, for the sphere query at
//! `bodies` detail: the face planes, the vertex loci and the edges of each
//! [`convex`](BodyShape::convex) body, laid out one body after another in one array, in
//! the order of the world hierarchy's leaves, so that the bodies a query meets are read
//! from a few neighbouring cache lines instead of from each body's own allocations.
//!
//! A [cuboid](BodyShape::cuboid) (a box, turned or not) gets a shorter record, its
//! centre, axes and half extents, and its distance is the box distance in its own frame:
//! one aligned pair of cache lines instead of planes, loci and edges. Cuboid records
//! live in an array of their own, with the body-frame centre and axes a move reads kept
//! in a parallel array, so that a query's cuboids lie densely, two lines each.
//!
//! A record is rewritten in place when its body moves; a body that changes shape gets a
//! new record at the end and its old one becomes garbage, reclaimed when the index lays
//! the records out again (see [`Hulls::garbage`]).

use glam::DVec3;

use super::exact::segment_closest;
use super::shape::{BodyShape, next_corner};
use crate::model::Pose;

/// Where one body's record lies in [`Hulls`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HullRef {
    /// A cuboid's place in [`Hulls::boxes`]; for another solid, the first number of its
    /// record in [`Hulls::data`]: the surface tolerance, then 4 numbers per plane
    /// (normal, offset) and 3 per vertex.
    at: u32,
    /// First edge in [`Hulls::edges`] (none for a cuboid).
    edges_at: u32,
    faces: u16,
    points: u16,
    edges: u16,
    /// Whether the record is a cuboid's.
    cuboid: bool,
}

impl HullRef {
    /// Numbers in the record.
    fn len(&self) -> usize {
        if self.cuboid {
            CUBOID_LEN
        } else {
            self.queried()
        }
    }

    /// Numbers in the part of the record a query reads (its start).
    fn queried(&self) -> usize {
        if self.cuboid {
            CUBOID_QUERIED
        } else {
            1 + 4 * self.faces as usize + 3 * self.points as usize
        }
    }
}

/// Numbers a query reads of a cuboid's record ([`Cuboid`]).
const CUBOID_QUERIED: usize = 1 + 3 + 9 + 3;
/// Numbers held for a cuboid: its record, then its [`Frame`].
const CUBOID_LEN: usize = CUBOID_QUERIED + 3 + 9;

/// What a query reads of a cuboid, in world coordinates: the surface tolerance, the
/// centre, the three axes and the three half extents. Aligned so that it fills exactly
/// two cache lines.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct Cuboid {
    eps: f64,
    centre: [f64; 3],
    axes: [[f64; 3]; 3],
    half: [f64; 3],
}

const _: () = assert!(std::mem::size_of::<Cuboid>() == 8 * CUBOID_QUERIED);

/// A cuboid's centre and axes in its body's frame, from which a move rewrites its
/// [`Cuboid`] without reading the shape.
#[derive(Clone, Copy, Debug, Default)]
struct Frame {
    centre: DVec3,
    axes: [DVec3; 3],
}

/// The records of the convex bodies of an index.
#[derive(Default)]
pub struct Hulls {
    /// The records of convex solids other than cuboids, one after another.
    data: Vec<f64>,
    edges: Vec<[u16; 2]>,
    /// The cuboids' records, and (same index) their frames.
    boxes: Vec<Cuboid>,
    frames: Vec<Frame>,
    /// Numbers and edges held by records no longer in use.
    garbage: usize,
}

/// The most vertices a record holds (its edges index them with `u16`).
const MAX_POINTS: usize = u16::MAX as usize;

impl Hulls {
    /// Adds the record of `shape` posed at `pose`; `None` when the shape is not convex
    /// (or too large for a record).
    pub fn add(&mut self, shape: &BodyShape, pose: &Pose) -> Option<HullRef> {
        let room = u32::MAX as usize - 4 * MAX_POINTS;
        if !shape.convex
            || shape.points.len() > MAX_POINTS
            || self.data.len() > room
            || self.edges.len() > room
        {
            return None;
        }
        let (at, edges_at) = (self.data.len(), self.edges.len());
        if let Some(b) = &shape.cuboid {
            if self.boxes.len() >= u32::MAX as usize {
                return None;
            }
            let h = HullRef {
                at: self.boxes.len() as u32,
                edges_at: 0,
                faces: 0,
                points: 0,
                edges: 0,
                cuboid: true,
            };
            self.boxes.push(Cuboid {
                eps: shape.surface_eps(),
                half: b.half,
                ..Cuboid::default()
            });
            self.frames.push(Frame {
                centre: b.centre,
                axes: b.axes,
            });
            self.pose(h, shape, pose);
            return Some(h);
        }
        for k in 0..shape.faces.len() {
            let cs = shape.corners_of(k);
            let canonical = cs.iter().enumerate().filter(|(_, c)| c.reports_edge());
            self.edges.extend(
                canonical.map(|(i, c)| [c.vertex as u16, next_corner(cs, i).vertex as u16]),
            );
        }
        // A convex shape has at most `CONVEX_MAX_FACES` faces, so its counts fit.
        let h = HullRef {
            at: at as u32,
            edges_at: edges_at as u32,
            faces: shape.faces.len() as u16,
            points: shape.points.len() as u16,
            edges: (self.edges.len() - edges_at) as u16,
            cuboid: false,
        };
        self.data.resize(at + h.len(), 0.0);
        self.pose(h, shape, pose);
        Some(h)
    }

    /// Rewrites record `h` (of `shape`) for the body posed at `pose`. Precondition: `h`
    /// was made by [`Hulls::add`] for `shape`.
    pub fn pose(&mut self, h: HullRef, shape: &BodyShape, pose: &Pose) {
        if h.cuboid {
            // From the body-frame centre and axes kept beside the record: the shape is
            // not read.
            let frame = &self.frames[h.at as usize];
            let rec = &mut self.boxes[h.at as usize];
            rec.centre = pose.transform_point(frame.centre).to_array();
            for (out, a) in rec.axes.iter_mut().zip(frame.axes) {
                *out = pose.transform_vector(a).to_array();
            }
            return;
        }
        let rec = &mut self.data[h.at as usize..h.at as usize + h.len()];
        rec[0] = shape.surface_eps();
        let (planes, points) = rec[1..].split_at_mut(4 * h.faces as usize);
        for (out, f) in planes.chunks_exact_mut(4).zip(&shape.faces) {
            let n = pose.transform_vector(f.normal);
            out[..3].copy_from_slice(&n.to_array());
            out[3] = f.offset + n.dot(pose.position);
        }
        for (out, &p) in points.chunks_exact_mut(3).zip(&shape.points) {
            out.copy_from_slice(&pose.transform_point(p).to_array());
        }
    }

    /// Reads the first and the last number a query reads of record `h`, which brings a
    /// cuboid's record (its two cache lines) wholly into the cache, and the ends of a
    /// longer one. The answer means nothing; a caller reads many records so, one after
    /// another, for their cache misses to overlap before it tests them.
    #[inline]
    pub fn touch(&self, h: HullRef) -> f64 {
        let at = h.at as usize;
        if h.cuboid {
            let b = &self.boxes[at];
            return b.eps + b.half[2];
        }
        self.data[at] + self.data[at + h.queried() - 1]
    }

    /// Gives back spare capacity (after a body-by-body build).
    pub fn shrink_to_fit(&mut self) {
        self.data.shrink_to_fit();
        self.edges.shrink_to_fit();
        self.boxes.shrink_to_fit();
        self.frames.shrink_to_fit();
    }

    /// Drops record `h` (it becomes garbage).
    pub fn release(&mut self, h: HullRef) {
        self.garbage += h.len() + h.edges as usize;
    }

    /// Numbers and edges held by released records: the index lays the records out
    /// again when these outweigh the live ones.
    pub fn garbage(&self) -> usize {
        self.garbage
    }

    /// Numbers and edges held in all.
    pub fn size(&self) -> usize {
        self.data.len() + self.edges.len() + self.boxes.len() * CUBOID_LEN
    }

    /// Heap bytes held.
    pub fn heap_bytes(&self) -> usize {
        self.data.capacity() * 8
            + self.edges.capacity() * 4
            + self.boxes.capacity() * std::mem::size_of::<Cuboid>()
            + self.frames.capacity() * std::mem::size_of::<Frame>()
    }

    /// The ball of centre `c` and radius `r` (world frame) against the body of record
    /// `h`, as [`reach::ball`](super::reach::ball) answers it at `bodies` detail:
    /// `Some(Some((distance, inside)))` when the solid meets the ball, `Some(None)` when
    /// it does not, and `None` when the centre lies within the surface tolerance of the
    /// surface or the solid's distance within rounding of `r`, for the general test to
    /// decide.
    ///
    /// The centre is inside exactly when it is behind every face plane. Outside, its
    /// distance to the solid is at least the largest plane distance; the foot of the
    /// centre on a face plane it is in front of, when behind every other plane, is the
    /// closest point; otherwise the closest point lies on an edge (or at a vertex), and
    /// the least distance to an edge segment is the distance. For a cuboid, with `q` the
    /// centre in the cuboid's frame, the plane distances are `|qₖ| − halfₖ` and the
    /// distance is the length of their positive parts.
    pub fn ball(&self, h: HullRef, c: DVec3, r: f64) -> Option<Option<(f64, bool)>> {
        if h.cuboid {
            let b = &self.boxes[h.at as usize];
            let d = c - DVec3::from_array(b.centre);
            let along = |k: usize| d.dot(DVec3::from_array(b.axes[k])).abs() - b.half[k];
            let out = [along(0), along(1), along(2)];
            // The largest plane distance: each pair of opposite planes gives
            // |(c − centre)·axis| − half.
            let side = out[0].max(out[1]).max(out[2]);
            return settle(side, b.eps, r, || {
                out.iter()
                    .map(|x| x.max(0.0) * x.max(0.0))
                    .sum::<f64>()
                    .sqrt()
            });
        }
        let rec = &self.data[h.at as usize..h.at as usize + h.len()];
        let eps = rec[0];
        let (planes, points) = rec[1..].split_at(4 * h.faces as usize);
        let side_of = |p: DVec3, q: &[f64]| q[0] * p.x + q[1] * p.y + q[2] * p.z - q[3];
        let side = planes
            .chunks_exact(4)
            .map(|q| side_of(c, q))
            .fold(f64::NEG_INFINITY, f64::max);
        settle(side, eps, r, || {
            // A foot counts as on its face when no other plane has it in front by more
            // than a thousandth of the surface tolerance.
            let on_face = eps * 1e-3;
            for (k, q) in planes.chunks_exact(4).enumerate() {
                let pd = side_of(c, q);
                if pd <= 0.0 {
                    continue;
                }
                let foot = c - DVec3::new(q[0], q[1], q[2]) * pd;
                let behind_all = planes
                    .chunks_exact(4)
                    .enumerate()
                    .all(|(j, o)| j == k || side_of(foot, o) <= on_face);
                if behind_all {
                    return pd;
                }
            }
            let point = |i: u16| {
                let i = 3 * i as usize;
                DVec3::new(points[i], points[i + 1], points[i + 2])
            };
            let edges = &self.edges[h.edges_at as usize..][..h.edges as usize];
            edges
                .iter()
                .map(|&[a, b]| segment_closest(c, point(a), point(b)).0)
                .fold(f64::INFINITY, f64::min)
                .sqrt()
        })
    }
}

/// The answer of [`Hulls::ball`] for a convex solid whose largest plane distance from
/// the centre is `side` (inside exactly when it is not positive), of surface tolerance
/// `eps`, and whose distance from an outside centre `distance` computes.
fn settle(
    side: f64,
    eps: f64,
    r: f64,
    distance: impl FnOnce() -> f64,
) -> Option<Option<(f64, bool)>> {
    if side <= 0.0 {
        return Some(Some((0.0, true)));
    }
    if side <= eps {
        return None;
    }
    // Slack for the rounding of distances computed two ways.
    let slack = eps + r * 1e-9;
    if side > r + slack {
        return Some(None);
    }
    let d = distance();
    if d < r - slack {
        Some(Some((d, false)))
    } else if d > r + slack {
        Some(None)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use glam::{DQuat, DVec2};

    use super::*;
    use crate::model::Serials;
    use crate::model::solids::{box_solid, lamina, mktetra, prism_solid};
    use crate::spatial::query::Detail;
    use crate::spatial::reach::{self, Features};

    fn shape(body: crate::model::Body) -> BodyShape {
        BodyShape::build(Arc::new(body))
    }

    #[test]
    fn only_solid_convex_bodies_get_records() {
        let mut s = Serials::new();
        let pose = Pose::IDENTITY;
        let mut hulls = Hulls::default();
        let cube = shape(box_solid(&mut s, DVec3::new(2.0, 3.0, 4.0)).expect("a box"));
        let tetra = shape(mktetra(&mut s, 1.0).expect("a tetrahedron"));
        assert!(hulls.add(&cube, &pose).is_some());
        assert!(hulls.add(&tetra, &pose).is_some());
        let l = [
            (0.0, 0.0),
            (2.0, 0.0),
            (2.0, 1.0),
            (1.0, 1.0),
            (1.0, 2.0),
            (0.0, 2.0),
        ]
        .map(|(x, y)| DVec2::new(x, y));
        let l_prism = shape(prism_solid(&mut s, &l, 1.0).expect("an L prism"));
        assert!(!l_prism.convex && hulls.add(&l_prism, &pose).is_none());
        // Flat: every vertex on both faces' planes, no volume.
        let flat = shape(lamina(&mut s, &l[..3], 0.0).expect("a lamina").body);
        assert!(!flat.convex && hulls.add(&flat, &pose).is_none());
    }

    /// The record's answers against the general walk, around a turned, moved box (a
    /// cuboid's record), a tetrahedron and a hexagonal prism: inside, in front of faces,
    /// beside edges and beyond vertices.
    #[test]
    fn records_answer_as_the_general_walk_does() {
        let mut s = Serials::new();
        let pose = Pose::new(
            DVec3::new(3.0, -1.0, 2.0),
            DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1),
        )
        .expect("a pose");
        let inverse = pose.inverse();
        let mut hulls = Hulls::default();
        let mut decided = 0;
        let hexagon: Vec<DVec2> = (0..6)
            .map(|k| DVec2::from_angle(k as f64 * std::f64::consts::FRAC_PI_3) * 1.5)
            .collect();
        for (body, cuboid) in [
            (
                box_solid(&mut s, DVec3::new(2.0, 3.0, 4.0)).expect("a box"),
                true,
            ),
            (mktetra(&mut s, 1.5).expect("a tetrahedron"), false),
            (prism_solid(&mut s, &hexagon, 2.0).expect("a prism"), false),
        ] {
            let shape = shape(body);
            let h = hulls.add(&shape, &pose).expect("a record");
            assert_eq!(h.cuboid, cuboid);
            let mut seed = 17u64;
            let mut next = || {
                seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                (seed >> 11) as f64 / (1u64 << 53) as f64
            };
            for _ in 0..2000 {
                let c = pose.transform_point(DVec3::new(
                    next() * 10.0 - 5.0,
                    next() * 10.0 - 5.0,
                    next() * 10.0 - 5.0,
                ));
                let r = next() * 4.0;
                let general = reach::ball(
                    &shape,
                    &pose,
                    inverse.transform_point(c),
                    r,
                    Detail::Bodies,
                    0.0,
                    &mut Features::default(),
                );
                let Some(fast) = hulls.ball(h, c, r) else {
                    continue;
                };
                decided += 1;
                match (fast, general) {
                    (None, None) => {}
                    (Some((d, i)), Some((dg, ig))) => {
                        assert_eq!(i, ig, "inside at {c}");
                        assert!((d - dg).abs() <= 1e-12 * (1.0 + dg), "{d} vs {dg} at {c}");
                    }
                    other => panic!("{other:?} at {c} r {r}"),
                }
            }
        }
        assert!(decided > 5900, "only {decided} answers decided");
    }

    #[test]
    fn a_moved_record_follows_its_body() {
        let mut s = Serials::new();
        let cube = shape(box_solid(&mut s, DVec3::splat(2.0)).expect("a box"));
        let mut hulls = Hulls::default();
        let h = hulls.add(&cube, &Pose::IDENTITY).expect("a record");
        let far = DVec3::new(10.0, 0.0, 0.0);
        assert_eq!(hulls.ball(h, far, 1.0), Some(None));
        hulls.pose(h, &cube, &Pose::from_translation(far));
        assert_eq!(hulls.ball(h, far, 1.0), Some(Some((0.0, true))));
        // Beside the moved box's edge x = 11, y = 1: √2 away from (12, 2, 0).
        let (d, inside) = hulls
            .ball(h, DVec3::new(12.0, 2.0, 0.0), 2.0)
            .expect("decided")
            .expect("met");
        assert!(!inside && (d - 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(hulls.garbage(), 0);
        hulls.release(h);
        assert_eq!(hulls.garbage(), hulls.size());
    }
}
