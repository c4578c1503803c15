//! One body's faces, edges and vertices laid out for spatial queries, in the body's own
//! frame: compact loci, each face's plane and perimeter, and a hierarchy over the faces.
//!
//! A shape is built once per body geometry (the `Arc<Body>` it was built from is kept,
//! so an unchanged body is recognised by pointer) and reused however the body moves.
//!
//! Every edge and every vertex is reported from exactly one face perimeter corner (its
//! *canonical* corner): an edge from its use on side N, a vertex from the outgoing use
//! of its PED. An edge that enters a ball has both its faces meet the ball, and a vertex
//! inside a ball has the edge of its canonical use enter it, so walking the faces that
//! meet a ball finds every edge and vertex, each once.

use std::sync::Arc;

use glam::DVec3;

use super::aabb::Aabb;
use super::bvh::Bvh;
use super::exact::{SegmentFrom, boundary_margin, crosses, drop_axis, in_polygon};
use super::prefetch::{prefetch, staged};
use rayon::prelude::*;

use crate::model::{Body, EdgeUse, FaceId, Side};

/// The low 30 bits of a word: a corner's edge index, a face record's corner count; the
/// two bits above them hold a few flags. Counts and indices stay far below it (the
/// server refuses bodies of more than two million faces).
const LOW_30: u32 = (1 << 30) - 1;
/// No edge: the corner of an edgeless face (a seminal body's). Compact edge indices
/// are below it.
pub const NO_EDGE: u32 = LOW_30;
/// Corner flag: this corner reports its edge.
pub const REPORT_EDGE: u8 = 1;
/// Corner flag: this corner reports its starting vertex.
pub const REPORT_VERTEX: u8 = 2;
/// Faces laid out per task when a large body's shape is built in parallel.
const PARALLEL_FACES: usize = 1 << 14;
/// The most faces a body may have for its convexity to be checked and used: the
/// check costs faces × vertices, and the convex tests visit every face.
pub const CONVEX_MAX_FACES: usize = 64;

/// One corner of a face perimeter: the use of an edge starting at `vertex`. Eight
/// bytes: the edge's index and the flags share a word.
#[derive(Clone, Copy, Debug)]
pub struct Corner {
    /// Compact index of the vertex the use starts at.
    pub vertex: u32,
    /// The edge's compact index (or [`NO_EDGE`]) in the low 30 bits, the flags above.
    edge_flags: u32,
}

impl Corner {
    /// The corner starting at `vertex` on `edge` (below [`NO_EDGE`], or it), with
    /// [`REPORT_EDGE`] and/or [`REPORT_VERTEX`] in `flags`.
    #[inline]
    pub fn new(vertex: u32, edge: u32, flags: u8) -> Corner {
        debug_assert!(edge <= NO_EDGE && flags <= (REPORT_EDGE | REPORT_VERTEX));
        Corner {
            vertex,
            edge_flags: edge.min(NO_EDGE) | u32::from(flags & 3) << 30,
        }
    }

    /// Compact index of the edge, or [`NO_EDGE`].
    #[inline]
    pub fn edge(&self) -> u32 {
        self.edge_flags & LOW_30
    }

    /// Whether this corner reports its edge (the edge's canonical corner, of an edge).
    #[inline]
    pub fn reports_edge(&self) -> bool {
        self.edge_flags & (u32::from(REPORT_EDGE) << 30) != 0 && self.edge() != NO_EDGE
    }

    /// Whether this corner reports its starting vertex (the vertex's canonical corner).
    #[inline]
    pub fn reports_vertex(&self) -> bool {
        self.edge_flags & (u32::from(REPORT_VERTEX) << 30) != 0
    }
}

const _: () = assert!(std::mem::size_of::<Corner>() == 8);

/// The corner after corner `i` of a face's corners `cs` (the first after the last):
/// side `i` of the face runs from `cs[i]` to it. Found without the division of
/// `(i + 1) % cs.len()`. Precondition: `i < cs.len()`.
#[inline]
pub fn next_corner(cs: &[Corner], i: usize) -> &Corner {
    cs.get(i + 1).unwrap_or(&cs[0])
}

/// One face: its plane, where its corners are and its serial number. In C's layout,
/// so that the normal begins the record and the serial number ends it (see
/// [`BodyShape::touch_all`]).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct FaceRec {
    /// Unit outward normal (zero for a face of no area).
    pub normal: DVec3,
    /// Plane offset: `normal · x = offset`.
    pub offset: f64,
    /// First corner in [`BodyShape::corners`].
    pub start: u32,
    /// The number of corners in the low 30 bits; above them, the axis [`drop_axis`]
    /// drops for the face's normal (0, 1 or 2).
    len_dropped: u32,
    /// The face's serial number.
    pub serial: u64,
}

const _: () = assert!(
    std::mem::size_of::<FaceRec>() == 48
        && std::mem::offset_of!(FaceRec, normal) == 0
        && std::mem::offset_of!(FaceRec, serial) == 40
);

/// The coordinates [`drop_axis`] keeps when it drops axis 0, 1 or 2.
const KEPT_AXES: [(usize, usize); 3] = [(1, 2), (2, 0), (0, 1)];

impl FaceRec {
    /// The face of plane `normal · x = offset`, serial number `serial`, whose `len`
    /// corners start at `start`. Precondition: `len` is below 2³⁰.
    fn new(normal: DVec3, offset: f64, start: u32, len: u32, serial: u64) -> FaceRec {
        let kept = drop_axis(normal);
        let dropped = KEPT_AXES.iter().position(|&a| a == kept).unwrap_or(2) as u32;
        debug_assert!(len <= LOW_30);
        FaceRec {
            normal,
            offset,
            start,
            len_dropped: len | dropped << 30,
            serial,
        }
    }

    /// The number of corners.
    #[inline]
    pub fn corner_count(&self) -> u32 {
        self.len_dropped & LOW_30
    }

    /// The two coordinates kept when projecting the face for point-in-polygon tests:
    /// [`drop_axis`] of its normal, found when the face was laid out.
    #[inline]
    pub fn axes(&self) -> (usize, usize) {
        KEPT_AXES[(self.len_dropped >> 30) as usize % 3]
    }
}

/// Where on a face the closest point to a query point lies.
#[derive(Clone, Copy, Debug)]
pub struct Closest {
    /// Squared distance.
    pub d2: f64,
    /// The closest point (body frame).
    pub point: DVec3,
    /// Whether it is inside the face (not on its perimeter), so that the side of the
    /// face plane tells inside from outside.
    pub interior: bool,
    /// Signed distance from the face plane.
    pub plane_distance: f64,
}

/// A body laid out for queries. Positions are in the body's own frame.
pub struct BodyShape {
    body: Arc<Body>,
    /// Vertex loci.
    pub points: Vec<DVec3>,
    /// Vertex serial numbers.
    pub vertex_serials: Vec<u64>,
    /// Edge serial numbers.
    pub edge_serials: Vec<u64>,
    /// Faces, in the hierarchy's leaf order.
    pub faces: Vec<FaceRec>,
    /// Every face's corners, face after face.
    pub corners: Vec<Corner>,
    /// The hierarchy over the faces (leaf position `k` is `faces[k]`).
    pub bvh: Bvh,
    /// Bounds of the vertices.
    pub bounds: Aabb,
    /// Length of the bounds' diagonal (the scale of tolerances).
    pub size: f64,
    /// Whether the solid is a convex polytope of at most [`CONVEX_MAX_FACES`] faces:
    /// one shell of genus 0, no face without a plane, every vertex on or behind every
    /// face plane (within [`BodyShape::surface_eps`]) and some vertex well behind each
    /// (so that the solid has volume). The solid is then the intersection of its faces'
    /// half-spaces, which [`BodyShape::plane_side`] tests.
    pub convex: bool,
    /// The cuboid the solid is, when it is one: a convex solid of six faces and eight
    /// vertices whose faces pair off into three opposite pairs at right angles.
    pub cuboid: Option<Cuboid>,
}

/// Two unit normals whose dot product is within this of −1 are opposite, and two whose
/// dot product is within this of 0 are at right angles, for [`Cuboid::of`].
const SQUARE: f64 = 1e-12;

/// A cuboid in its body's frame: `|(x − centre)·axes[k]| ≤ half[k]` for k = 0, 1, 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cuboid {
    /// The centre.
    pub centre: DVec3,
    /// Three unit axes at right angles.
    pub axes: [DVec3; 3],
    /// The half extents along them.
    pub half: [f64; 3],
}

impl Cuboid {
    /// The cuboid a shape of faces `f` over `points` vertices is, if it is one: a convex
    /// shape of six faces and eight vertices whose faces pair off into three opposite pairs with normals at right
    /// angles (within [`SQUARE`]). The slab between a pair, `−o₂ ≤ n·x ≤ o₁` for the
    /// planes `n·x = o₁` and `−n·x = o₂`, has centre `(o₁ − o₂)/2` and half width
    /// `(o₁ + o₂)/2` along `n`.
    fn of(f: &[FaceRec], points: usize, convex: bool) -> Option<Cuboid> {
        if !convex || f.len() != 6 || points != 8 {
            return None;
        }
        let opposite =
            |i: usize| (0..6).find(|&j| j != i && f[i].normal.dot(f[j].normal) < -1.0 + SQUARE);
        let mut pairs = [(0, 0); 3];
        let mut found = 0;
        for i in 0..6 {
            let j = opposite(i)?;
            if opposite(j) != Some(i) {
                return None;
            }
            if i < j {
                *pairs.get_mut(found)? = (i, j);
                found += 1;
            }
        }
        if found != 3 {
            return None;
        }
        let axes = pairs.map(|(i, _)| f[i].normal);
        if (0..3).any(|a| axes[a].dot(axes[(a + 1) % 3]).abs() > SQUARE) {
            return None;
        }
        let centre = (0..3)
            .map(|k| {
                let (i, j) = pairs[k];
                axes[k] * (0.5 * (f[i].offset - f[j].offset))
            })
            .sum();
        let half = pairs.map(|(i, j)| 0.5 * (f[i].offset + f[j].offset));
        Some(Cuboid { centre, axes, half })
    }
}

impl BodyShape {
    /// The shape of `body`.
    pub fn build(body: Arc<Body>) -> BodyShape {
        let b = &*body;
        let mut vix = vec![u32::MAX; b.vertices().map(|v| v.index() + 1).max().unwrap_or(0)];
        let mut points = Vec::with_capacity(b.vertex_count());
        let mut vertex_serials = Vec::with_capacity(b.vertex_count());
        for v in b.vertices() {
            vix[v.index()] = points.len() as u32;
            points.push(b.position(v));
            vertex_serials.push(b.vertex_serial(v).get());
        }
        let mut eix = vec![u32::MAX; b.edges().map(|e| e.index() + 1).max().unwrap_or(0)];
        let mut edge_serials = Vec::with_capacity(b.edge_count());
        for e in b.edges() {
            eix[e.index()] = edge_serials.len() as u32;
            edge_serials.push(b.edge_serial(e).get());
        }
        let canonical_vertex_use = |u: EdgeUse| {
            let v = b.origin(u);
            b.vertex_first_use(v) == Some(u)
        };
        let lone: Vec<u32> = b
            .vertices()
            .filter(|&v| b.vertex(v).ped.is_none())
            .map(|v| vix[v.index()])
            .collect();
        // Faces, their corners (`start` counted from the first face given) and boxes.
        let lay = |ids: &[FaceId]| -> Laid {
            let mut faces = Vec::with_capacity(ids.len());
            let mut corners = Vec::with_capacity(4 * ids.len());
            let mut boxes = Vec::with_capacity(ids.len());
            for &f in ids {
                let start = corners.len() as u32;
                for u in b.face_uses(f) {
                    let mut flags = 0;
                    if u.side == Side::N {
                        flags |= REPORT_EDGE;
                    }
                    if canonical_vertex_use(u) {
                        flags |= REPORT_VERTEX;
                    }
                    corners.push(Corner::new(
                        vix[b.origin(u).index()],
                        eix[u.edge.index()],
                        flags,
                    ));
                }
                if corners.len() as u32 == start {
                    // An edgeless face (a seminal body): its polygon is the lone vertex.
                    if let Some(&v) = lone.first() {
                        corners.push(Corner::new(v, NO_EDGE, REPORT_VERTEX));
                    }
                }
                let len = corners.len() as u32 - start;
                let (normal, offset) = match b.face_plane(f) {
                    Some(p) => (p.normal, p.offset),
                    None => (DVec3::ZERO, 0.0),
                };
                boxes.push(Aabb::of_points(
                    corners[start as usize..]
                        .iter()
                        .map(|c| points[c.vertex as usize]),
                ));
                faces.push(FaceRec::new(
                    normal,
                    offset,
                    start,
                    len,
                    b.face_serial(f).get(),
                ));
            }
            Laid {
                faces,
                corners,
                boxes,
            }
        };
        let ids: Vec<FaceId> = b.faces().collect();
        // Laid out in chunks of PARALLEL_FACES faces (on rayon's threads when there are
        // several), each with its own corners, and read where they lie.
        let chunks: Vec<Laid> = if ids.len() <= PARALLEL_FACES {
            vec![lay(&ids)]
        } else {
            ids.par_chunks(PARALLEL_FACES).map(lay).collect()
        };
        let bvh = Bvh::build_by(ids.len(), |i| {
            chunks[i / PARALLEL_FACES].boxes[i % PARALLEL_FACES]
        });
        let (ordered, ordered_corners) = in_leaf_order(&bvh, &chunks);
        let bounds = Aabb::of_points(points.iter().copied());
        let size = if bounds.is_empty() {
            0.0
        } else {
            (bounds.max - bounds.min).length()
        };
        let convex = is_convex(b, &ordered, &points, surface_eps(size));
        let cuboid = Cuboid::of(&ordered, points.len(), convex);
        BodyShape {
            body,
            points,
            vertex_serials,
            edge_serials,
            faces: ordered,
            corners: ordered_corners,
            bvh,
            bounds,
            size,
            convex,
            cuboid,
        }
    }

    /// How near the surface a point counts as on it: a billionth of the body's size.
    #[inline]
    pub fn surface_eps(&self) -> f64 {
        surface_eps(self.size)
    }

    /// The largest signed distance of `p` from a face plane, and that face: for a
    /// [`convex`](BodyShape::convex) shape, `p` is inside the solid exactly when it is
    /// not positive, and outside by at least it otherwise. `None` for a shape without
    /// faces.
    #[inline]
    pub fn plane_side(&self, p: DVec3) -> Option<(f64, usize)> {
        let mut best: Option<(f64, usize)> = None;
        for (k, f) in self.faces.iter().enumerate() {
            let pd = f.normal.dot(p) - f.offset;
            if best.is_none_or(|(b, _)| pd > b) {
                best = Some((pd, k));
            }
        }
        best
    }

    /// The body this shape was built from.
    pub fn body(&self) -> &Arc<Body> {
        &self.body
    }

    /// Heap bytes held by the shape (not counting the body).
    pub fn heap_bytes(&self) -> usize {
        self.points.capacity() * 24
            + (self.vertex_serials.capacity() + self.edge_serials.capacity()) * 8
            + self.faces.capacity() * std::mem::size_of::<FaceRec>()
            + self.corners.capacity() * std::mem::size_of::<Corner>()
            + self.bvh.heap_bytes()
    }

    /// Face `k`'s corners.
    #[inline]
    pub fn corners_of(&self, k: usize) -> &[Corner] {
        let f = &self.faces[k];
        &self.corners[f.start as usize..(f.start + f.corner_count()) as usize]
    }

    /// Calls `visit(k)` for each face `k` of `faces`, in order, with what the tests of
    /// the faces `FACES_AHEAD` to three times that further on read prefetched in
    /// three stages: their records, then their corners (found through the records),
    /// then their loci and serial numbers (found through the corners). On a large
    /// shape out of cache each face's misses then overlap the tests of the faces before
    /// it. (Queries test a [small](BodyShape::is_small) shape's faces as their walk
    /// finds them instead: they read such shapes whole before their tests, see
    /// [`BodyShape::touch_all`].)
    ///
    /// Precondition: every index in `faces` is a face of the shape.
    #[inline(always)]
    pub fn visit_ahead(&self, faces: &[u32], mut visit: impl FnMut(usize)) {
        staged(
            faces,
            FACES_AHEAD,
            |k| self.prefetch_face(k as usize),
            |k| self.prefetch_corners(k as usize),
            |k| self.prefetch_loci(k as usize),
            |k| {
                visit(k as usize);
                true
            },
        );
    }

    /// Prefetches face `k`'s record (see [`prefetch`]): the first of the three stages
    /// of [`BodyShape::visit_ahead`].
    #[inline(always)]
    fn prefetch_face(&self, k: usize) {
        prefetch(&self.faces[k]);
    }

    /// Prefetches face `k`'s corners; reads its record, best prefetched a while before
    /// by [`BodyShape::prefetch_face`].
    #[inline(always)]
    fn prefetch_corners(&self, k: usize) {
        let cs = self.corners_of(k);
        if let (Some(first), Some(last)) = (cs.first(), cs.last()) {
            prefetch(first);
            prefetch(last);
        }
    }

    /// Prefetches the loci and serial numbers face `k`'s tests read: each corner's
    /// vertex locus and serial number, and its edge's serial number; reads its corners,
    /// best prefetched a while before by [`BodyShape::prefetch_corners`].
    #[inline(always)]
    fn prefetch_loci(&self, k: usize) {
        for c in self.corners_of(k) {
            let v = c.vertex as usize;
            prefetch(&self.points[v]);
            prefetch(&self.vertex_serials[v]);
            if let Some(e) = self.edge_serials.get(c.edge() as usize) {
                prefetch(e);
            }
        }
    }

    /// Reads where the shape's lists lie, and its size: the shape's own record, which
    /// [`BodyShape::touch_all`] and the tests read through. The answer means nothing;
    /// a caller reads many shapes so, one after another, for their cache misses to
    /// overlap.
    #[inline]
    pub fn touch_header(&self) -> u64 {
        (self.faces.as_ptr() as u64)
            ^ (self.corners.as_ptr() as u64)
            ^ (self.points.as_ptr() as u64)
            ^ (self.vertex_serials.as_ptr() as u64)
            ^ (self.edge_serials.as_ptr() as u64)
            ^ self.size.to_bits()
    }

    /// Whether the shape has at most [`TOUCH_ALL_FACES`] faces: few enough for queries
    /// to read it whole before they test it (see [`BodyShape::touch_all`]).
    #[inline]
    pub fn is_small(&self) -> bool {
        self.faces.len() <= TOUCH_ALL_FACES
    }

    /// Reads a word of every cache line of the shape's records: its hierarchy's nodes,
    /// faces, corners, loci and serial numbers, when it is
    /// [small](BodyShape::is_small) (nothing otherwise). The answer means nothing; a
    /// caller reads many small shapes so, one after another, for their cache misses to
    /// overlap before it tests them.
    #[inline]
    pub fn touch_all(&self) -> u64 {
        if !self.is_small() {
            return 0;
        }
        self.bvh.touch()
            ^ touch_lines(&self.faces, |f| f.normal.x.to_bits() ^ f.serial)
            ^ touch_lines(&self.corners, |c| u64::from(c.vertex))
            ^ touch_lines(&self.points, |p| p.x.to_bits() ^ p.z.to_bits())
            ^ touch_lines(&self.vertex_serials, |&s| s)
            ^ touch_lines(&self.edge_serials, |&s| s)
    }

    /// Face `k`'s perimeter loci, in order.
    #[inline]
    pub fn loop_points(&self, k: usize) -> impl Iterator<Item = DVec3> + Clone + '_ {
        self.corners_of(k)
            .iter()
            .map(|c| self.points[c.vertex as usize])
    }

    /// Face `k`'s sides, in order, each seen from `p` (see [`SegmentFrom`]): side `i`
    /// runs from corner `i` to the next. Each corner's squared distance from `p` is
    /// computed once, for the side it ends and the side it starts.
    #[inline]
    pub fn sides_from(&self, k: usize, p: DVec3) -> impl Iterator<Item = SegmentFrom> + '_ {
        let cs = self.corners_of(k);
        let seen = move |c: &Corner| {
            let q = self.points[c.vertex as usize];
            (q, (q - p).length_squared())
        };
        let first = cs.first().map_or((p, 0.0), seen);
        let mut a = first;
        cs.iter().enumerate().map(move |(i, _)| {
            let b = cs.get(i + 1).map_or(first, seen);
            let side = SegmentFrom::with_ends(a.0, b.0, p, a.1, b.1);
            a = b;
            side
        })
    }

    /// [`BodyShape::sides_from`] for a face whose `N` corners are `cs` (as
    /// [`BodyShape::corners_of`] gives them), as an array.
    #[inline(always)]
    pub fn sides_of<const N: usize>(&self, cs: &[Corner; N], p: DVec3) -> [SegmentFrom; N] {
        let seen: [(DVec3, f64); N] = std::array::from_fn(|i| {
            let q = self.points[cs[i].vertex as usize];
            (q, (q - p).length_squared())
        });
        std::array::from_fn(|i| {
            let (a, b) = (seen[i], seen[if i + 1 == N { 0 } else { i + 1 }]);
            SegmentFrom::with_ends(a.0, b.0, p, a.1, b.1)
        })
    }

    /// The point of face `k` closest to `p`: the foot of `p` on the face's plane when
    /// it lies inside the face's loop (by [`in_polygon`]'s crossing count, taken in the
    /// same pass over the sides), else the nearest point of a side.
    #[inline]
    pub fn closest_on_face(&self, k: usize, p: DVec3) -> Closest {
        self.closest_of_sides(k, p, self.sides_from(k, p))
    }

    /// [`BodyShape::closest_on_face`] from the face's `sides` as
    /// [`BodyShape::sides_from`] gives them (a caller that needs them again keeps them).
    #[inline(always)]
    pub fn closest_of_sides(
        &self,
        k: usize,
        p: DVec3,
        sides: impl Iterator<Item = SegmentFrom>,
    ) -> Closest {
        let f = &self.faces[k];
        let pd = f.normal.dot(p) - f.offset;
        let foot = p - f.normal * pd;
        let axes = f.axes();
        let projected = (foot[axes.0], foot[axes.1]);
        let mut best = Closest {
            d2: f64::INFINITY,
            point: p,
            interior: false,
            plane_distance: pd,
        };
        let mut inside = false;
        for side in sides {
            let (d2, q) = side.closest(p);
            if d2 < best.d2 {
                best.d2 = d2;
                best.point = q;
            }
            inside ^= crosses(projected, side.a, side.b, axes);
        }
        if f.normal != DVec3::ZERO && pd * pd < best.d2 && inside {
            best.d2 = pd * pd;
            best.point = foot;
            best.interior = true;
        }
        best
    }

    /// Where the ray `o + t·d` crosses face `k` (t ≥ 0), if it does, and how far the
    /// crossing is from the face's perimeter (small margins make parity untrustworthy).
    pub fn ray_face(&self, k: usize, o: DVec3, d: DVec3) -> Option<(f64, f64)> {
        let f = &self.faces[k];
        let denom = f.normal.dot(d);
        if denom == 0.0 {
            return None;
        }
        let t = (f.offset - f.normal.dot(o)) / denom;
        if t.is_nan() || t < 0.0 {
            return None;
        }
        let h = o + d * t;
        let axes = f.axes();
        in_polygon(h, self.loop_points(k), axes)
            .then(|| (t, boundary_margin(h, self.loop_points(k))))
    }

    /// Whether `p` is inside the closed body (on its surface counts as inside), by the
    /// parity of a ray's crossings; a ray passing too near an edge, or along a face, is
    /// cast again in another direction.
    pub fn contains(&self, p: DVec3) -> bool {
        if !self.bounds.contains_point(p) {
            return false;
        }
        let eps = self.surface_eps();
        if self.convex {
            // Inside every half-space, or beyond one by more than the surface's
            // thickness; between, the general test below decides.
            match self.plane_side(p) {
                Some((pd, _)) if pd <= 0.0 => return true,
                Some((pd, _)) if pd > eps => return false,
                _ => {}
            }
        }
        // On an edge or at a vertex a point is on no face's interior, which the crossing
        // count cannot see: a point on the surface is found first, as inside.
        if self
            .nearest_face(p, eps * eps)
            .is_some_and(|(_, c)| c.d2 <= eps * eps)
        {
            return true;
        }
        for d in PROBES {
            let d = DVec3::from_array(d).normalize();
            let mut crossings = 0u32;
            let mut doubtful = false;
            let mut on_surface = false;
            self.bvh.ray(p, d, f64::INFINITY, |k, t_best| {
                let f = &self.faces[k];
                let pd = f.normal.dot(p) - f.offset;
                if f.normal.dot(d).abs() < 1e-9 && pd.abs() <= eps {
                    // Running along a face's plane: parity means nothing.
                    let axes = f.axes();
                    if in_polygon(p, self.loop_points(k), axes)
                        || boundary_margin(p, self.loop_points(k)) <= eps
                    {
                        on_surface |= pd == 0.0;
                    }
                    doubtful = true;
                    return t_best;
                }
                if let Some((t, margin)) = self.ray_face(k, p, d) {
                    if t * f.normal.dot(d).abs() <= eps {
                        on_surface = true;
                    }
                    if margin <= eps {
                        doubtful = true;
                    }
                    crossings += 1;
                }
                t_best
            });
            if on_surface {
                return true;
            }
            if !doubtful {
                return crossings % 2 == 1;
            }
        }
        // Every probe grazed something: take the closest face's side.
        let best = self.nearest_face(p, f64::INFINITY);
        best.is_some_and(|(_, c)| c.plane_distance <= 0.0)
    }

    /// The face closest to `p` within squared distance `bound2`, with where on it.
    pub fn nearest_face(&self, p: DVec3, bound2: f64) -> Option<(usize, Closest)> {
        let mut found: Option<(usize, Closest)> = None;
        self.bvh.nearest(p, bound2, |k, best| {
            let c = self.closest_on_face(k, p);
            if c.d2 < best || (c.d2 == best && found.is_none()) {
                found = Some((k, c));
                c.d2
            } else {
                best
            }
        });
        found
    }
}

/// How many faces ahead of the one tested [`BodyShape::visit_ahead`] prefetches loci:
/// a face's tests take about 0.1 µs, a miss to memory about as much again, and each
/// stage of the prefetch waits on the one before.
const FACES_AHEAD: usize = 4;

/// The most faces a shape has for [`BodyShape::touch_all`] to read it whole.
pub const TOUCH_ALL_FACES: usize = 64;

/// `word` of the items of `items` at most a cache line apart, and of the last one,
/// folded. When `word` reads an item's first and last words, every cache line the
/// items span holds a word read (an item is at most a line long).
#[inline]
fn touch_lines<T>(items: &[T], word: impl Fn(&T) -> u64) -> u64 {
    let step = (64 / std::mem::size_of::<T>().max(1)).max(1);
    let last = items.last().map_or(0, &word);
    items
        .iter()
        .step_by(step)
        .fold(last, |acc, t| acc ^ word(t))
}

/// How near the surface of a body of diagonal `size` a point counts as on it.
#[inline]
fn surface_eps(size: f64) -> f64 {
    size * 1e-9
}

/// Whether `body` (laid out as `faces` over `points`) is a convex polytope of at most
/// [`CONVEX_MAX_FACES`] faces: see [`BodyShape::convex`]. A solid with volume, of one
/// shell and genus 0, whose every vertex lies behind every face plane is the convex hull
/// of its vertices (a second shell, a cavity, a dent or a tunnel would put some vertex
/// in front of some face; a flat lamina has no vertex behind its faces).
fn is_convex(body: &Body, faces: &[FaceRec], points: &[DVec3], eps: f64) -> bool {
    faces.len() <= CONVEX_MAX_FACES
        && !faces.is_empty()
        && body.euler_characteristic() == 2
        && faces.iter().all(|f| {
            let side = |p: &DVec3| f.normal.dot(*p) - f.offset;
            f.normal != DVec3::ZERO
                && points.iter().all(|p| side(p) <= eps)
                && points.iter().any(|p| side(p) < -eps)
        })
}

/// Directions tried in turn by [`BodyShape::contains`]: skew to every axis and every
/// diagonal, so that axis-aligned models rarely graze an edge. (The digits are those of
/// familiar constants only as a source of unremarkable numbers.)
const PROBES: [[f64; 3]; 6] = [
    [0.577_215_664_9, 0.311_029_995_6, 0.759_134_123_1],
    [-0.414_213_562_3, 0.865_255_979_4, 0.281_718_171_5],
    [0.692_147_180_5, -0.367_879_441_2, -0.620_981_038_7],
    [-0.328_309_886_2, -0.779_482_100_2, 0.539_423_105_3],
    [0.852_395_851_1, 0.123_456_789_1, -0.508_295_867_4],
    [-0.231_049_060_2, 0.105_360_515_7, -0.967_078_543_2],
];

/// One chunk of a body's faces, laid out: the faces (each `start` counted within the
/// chunk's `corners`), their corners, and each face's box.
struct Laid {
    faces: Vec<FaceRec>,
    corners: Vec<Corner>,
    boxes: Vec<Aabb>,
}

/// The faces of `chunks` (face `i` is the `i % PARALLEL_FACES`-th of chunk
/// `i / PARALLEL_FACES`) and their corners laid out in `bvh`'s leaf order, each face's
/// `start` renumbered: on rayon's threads when there are many.
fn in_leaf_order(bvh: &Bvh, chunks: &[Laid]) -> (Vec<FaceRec>, Vec<Corner>) {
    let order = bvh.order();
    let face = |i: usize| &chunks[i / PARALLEL_FACES].faces[i % PARALLEL_FACES];
    let corners_of = |i: usize| {
        let f = face(i);
        let s = f.start as usize;
        &chunks[i / PARALLEL_FACES].corners[s..s + f.corner_count() as usize]
    };
    if order.len() <= PARALLEL_FACES {
        let mut faces = Vec::with_capacity(order.len());
        let mut corners = Vec::with_capacity(chunks.iter().map(|c| c.corners.len()).sum());
        for &i in order {
            let f = face(i as usize);
            faces.push(FaceRec {
                start: corners.len() as u32,
                ..*f
            });
            corners.extend_from_slice(corners_of(i as usize));
        }
        return (faces, corners);
    }
    // Where each face's corners start, then faces and corners written in place, a range
    // of leaf positions per task.
    let mut starts = Vec::with_capacity(order.len() + 1);
    let mut at = 0u32;
    for &i in order {
        starts.push(at);
        at += face(i as usize).corner_count();
    }
    starts.push(at);
    let mut faces = Vec::with_capacity(order.len());
    (0..order.len())
        .into_par_iter()
        .map(|k| FaceRec {
            start: starts[k],
            ..*face(order[k] as usize)
        })
        .collect_into_vec(&mut faces);
    let blank = Corner::new(0, NO_EDGE, 0);
    let mut corners = vec![blank; at as usize];
    let mut ranges = Vec::new();
    let mut rest = corners.as_mut_slice();
    for k in (0..order.len()).step_by(PARALLEL_FACES) {
        let end = (k + PARALLEL_FACES).min(order.len());
        let (mine, more) = rest.split_at_mut((starts[end] - starts[k]) as usize);
        ranges.push((k..end, mine));
        rest = more;
    }
    ranges.into_par_iter().for_each(|(ks, out)| {
        let mut at = 0;
        for k in ks {
            let c = corners_of(order[k] as usize);
            out[at..at + c.len()].copy_from_slice(c);
            at += c.len();
        }
    });
    (faces, corners)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Serial;
    use crate::model::Serials;
    use crate::model::solids::sphere;

    /// A corner keeps its vertex, edge and flags apart in its eight bytes, and a face
    /// record its corner count and projection axes in one word.
    #[test]
    fn packed_corners_and_faces_give_back_what_they_were_made_of() {
        for edge in [0, 1, 12_345, NO_EDGE - 1, NO_EDGE] {
            for flags in 0..=(REPORT_EDGE | REPORT_VERTEX) {
                let c = Corner::new(u32::MAX, edge, flags);
                assert_eq!((c.vertex, c.edge()), (u32::MAX, edge));
                assert_eq!(c.reports_vertex(), flags & REPORT_VERTEX != 0);
                assert_eq!(
                    c.reports_edge(),
                    flags & REPORT_EDGE != 0 && edge != NO_EDGE
                );
            }
        }
        for normal in [
            DVec3::X,
            -DVec3::Y,
            DVec3::Z,
            DVec3::new(0.3, -0.9, 0.3),
            DVec3::new(-0.6, 0.0, 0.8),
            DVec3::ZERO,
        ] {
            for len in [1, 3, 4, (1 << 30) - 1] {
                let f = FaceRec::new(normal, 2.5, 7, len, u64::MAX);
                assert_eq!(f.axes(), drop_axis(normal), "{normal}");
                assert_eq!((f.corner_count(), f.start, f.serial), (len, 7, u64::MAX));
            }
        }
    }

    /// Reading each visited item's first and last words, `touch_lines` reads a word in
    /// every cache line its items span, for items of 8 bytes (a corner, a serial
    /// number), 24 (a locus) and 48 (a face record), wherever the items start.
    #[test]
    fn touch_lines_reads_every_line_the_items_span() {
        fn check<T: Clone>(item: T, first: impl Fn(&T) -> usize, last: impl Fn(&T) -> usize) {
            let size = std::mem::size_of::<T>();
            let backing = vec![item; 80];
            for skip in 0..8 {
                for len in 0..40 {
                    let items = &backing[skip..skip + len];
                    let read = std::cell::RefCell::new(std::collections::BTreeSet::new());
                    touch_lines(items, |t| {
                        let mut read = read.borrow_mut();
                        read.insert(first(t) / 64);
                        read.insert(last(t) / 64);
                        0
                    });
                    let start = items.as_ptr() as usize;
                    let spanned: std::collections::BTreeSet<usize> =
                        (start..start + len * size).map(|a| a / 64).collect();
                    assert_eq!(*read.borrow(), spanned, "{size}-byte items, {skip} {len}");
                }
            }
        }
        let at = |p: *const u8| p as usize;
        check(
            0u64,
            |s: &u64| at(std::ptr::from_ref(s).cast()),
            |s| at(std::ptr::from_ref(s).cast()),
        );
        check(
            DVec3::ZERO,
            |p: &DVec3| at(std::ptr::from_ref(&p.x).cast()),
            |p| at(std::ptr::from_ref(&p.z).cast()),
        );
        let face = FaceRec::new(DVec3::Z, 1.0, 0, 4, 9);
        check(
            face,
            |f: &FaceRec| at(std::ptr::from_ref(&f.normal.x).cast()),
            |f| at(std::ptr::from_ref(&f.serial).cast()),
        );
    }

    /// A face's sides in an array are those the iterator gives, bit for bit, and so is
    /// the closest point made from them; over triangles, quadrilaterals and pentagons.
    #[test]
    fn sides_in_an_array_are_the_sides_the_iterator_gives() {
        use crate::model::solids::prism_solid;
        let mut serials = Serials::new();
        let ball = sphere(&mut serials, 2.0, 7, 5).expect("a sphere");
        let pentagon: Vec<glam::DVec2> = (0..5)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 5.0;
                glam::DVec2::new(1.5 * a.cos(), 1.5 * a.sin())
            })
            .collect();
        let prism = prism_solid(&mut serials, &pentagon, 3.0).expect("a prism");
        let mut lengths = std::collections::BTreeSet::new();
        for body in [ball, prism] {
            let shape = BodyShape::build(Arc::new(body));
            for p in [DVec3::ZERO, DVec3::new(0.3, -1.7, 2.9), DVec3::splat(5.0)] {
                for k in 0..shape.faces.len() {
                    let cs = shape.corners_of(k);
                    lengths.insert(cs.len());
                    let want: Vec<SegmentFrom> = shape.sides_from(k, p).collect();
                    assert_eq!(want.len(), cs.len());
                    let got: Vec<SegmentFrom> = match cs.len() {
                        3 => shape
                            .sides_of(<&[Corner; 3]>::try_from(cs).unwrap(), p)
                            .to_vec(),
                        4 => shape
                            .sides_of(<&[Corner; 4]>::try_from(cs).unwrap(), p)
                            .to_vec(),
                        5 => shape
                            .sides_of(<&[Corner; 5]>::try_from(cs).unwrap(), p)
                            .to_vec(),
                        n => panic!("a face of {n} corners"),
                    };
                    assert_eq!(got, want, "face {k} from {p}");
                    let c = shape.closest_of_sides(k, p, got.iter().copied());
                    let d = shape.closest_on_face(k, p);
                    assert_eq!((c.d2, c.point, c.interior), (d.d2, d.point, d.interior));
                }
            }
        }
        assert_eq!(lengths.into_iter().collect::<Vec<_>>(), vec![3, 4, 5]);
    }

    /// `visit_ahead` visits exactly the faces it is given, in their order, however few
    /// (fewer than its prefetch distance included) or many, and in any order.
    #[test]
    fn visit_ahead_visits_each_face_given_in_order() {
        let body = sphere(&mut Serials::new(), 1.0, 12, 7).expect("a sphere");
        let shape = BodyShape::build(Arc::new(body));
        // Large enough for its faces to be prefetched ahead.
        assert!(!shape.is_small());
        let n = shape.faces.len() as u32;
        let mut lists: Vec<Vec<u32>> = [0, 1, 2, FACES_AHEAD, 3 * FACES_AHEAD + 1, 40]
            .iter()
            .map(|&len| (0..len as u32).map(|i| (i * 7) % n).collect())
            .collect();
        lists.push((0..n).rev().collect());
        lists.push(vec![3, 3, 3, 0, n - 1, 3]);
        for faces in lists {
            let mut seen = Vec::new();
            shape.visit_ahead(&faces, |k| seen.push(k as u32));
            assert_eq!(seen, faces);
        }
    }

    /// A body large enough to be laid out in parallel chunks keeps every face's plane and
    /// perimeter, in the body's own order, whichever chunk the face fell in.
    #[test]
    fn a_large_shape_lays_out_every_face_as_the_body_has_it() {
        let body = sphere(&mut Serials::new(), 3.0, 400, 100).expect("a sphere");
        assert!(body.face_count() > 2 * PARALLEL_FACES);
        let shape = BodyShape::build(Arc::new(body));
        let b = shape.body().clone();
        assert_eq!(shape.faces.len(), b.face_count());
        let mut seen = std::collections::HashSet::new();
        for (k, rec) in shape.faces.iter().enumerate() {
            assert!(seen.insert(rec.serial), "face {} twice", rec.serial);
            let f = b.face_by_serial(Serial(rec.serial)).expect("a face");
            let want: Vec<DVec3> = b.face_uses(f).map(|u| b.position(b.origin(u))).collect();
            let got: Vec<DVec3> = shape.loop_points(k).collect();
            assert_eq!(got, want, "face {}", rec.serial);
            let plane = b.face_plane(f).expect("a plane");
            assert_eq!((rec.normal, rec.offset), (plane.normal, plane.offset));
        }
        // And each face sits at its leaf position: its leaf's box holds it.
        let mut placed = 0;
        for n in shape.bvh.leaves() {
            let lo = DVec3::from_array(n.min.map(f64::from));
            let hi = DVec3::from_array(n.max.map(f64::from));
            for k in n.first..n.first + n.count {
                placed += 1;
                let inside = |p: DVec3| p.cmpge(lo).all() && p.cmple(hi).all();
                assert!(shape.loop_points(k as usize).all(inside), "position {k}");
            }
        }
        assert_eq!(placed, shape.faces.len());
    }
}
