//! The hidden-line drawing: every edge of the model that can be seen from a camera, cut
//! exactly where it passes behind a face, as vector segments (after Baumgart's OCCULT).
//!
//! The drawing is computed in object space, not read back from a depth buffer, so its
//! segments end exactly (up to rounding) where an edge leaves the window, meets the near
//! plane or passes behind another face's silhouette.
//!
//! # Method
//!
//! * **Folds.** As in OCCULT, only edges with at least one face turned toward the eye are
//!   candidates; an edge whose two faces both look away is hidden by its own body. Every
//!   such edge is drawn, including edges between two coplanar front faces.
//! * **Clipping.** Each candidate is clipped by [`View::clip_segment`] (near plane and
//!   window), leaving a 3D segment `p(τ) = a + τ·(b − a)`, τ ∈ [0, 1], in camera
//!   coordinates.
//! * **Occluders.** Bodies are closed, so only front faces can hide anything: a ray that
//!   reaches a back face has passed through a front face first. Each front face is
//!   clipped at the near plane ([`View::clip_polygon_near`]); what lies in front of the
//!   near plane hides nothing, as in the raster modes.
//! * **Hidden intervals.** A point `p(τ)` is hidden by a face when (a) it lies strictly
//!   behind the face's plane as seen from the eye (its signed distance to the plane has
//!   the opposite sign to the eye's, beyond a small relative tolerance) and (b) the ray
//!   from the eye through it passes inside the face's polygon. Both conditions change
//!   only at parameters that are exact roots of linear functions of τ: the plane's signed
//!   distance, and the planes through the eye and each side of the polygon. For a convex
//!   polygon (every corner on the inner side of every side's eye plane) the inside is
//!   where all the side functions are negative, one interval. Otherwise, between
//!   consecutive roots nothing changes, so each sub-interval is classified once, at its
//!   midpoint, by the even-odd rule in the image (which holds for concave faces and for
//!   perimeters that run along a bridge edge twice). No perspective division enters the
//!   roots.
//! * **Visible pieces.** The union of the hidden intervals over all faces (except the
//!   edge's own two) is removed; the pieces that remain are the drawing. Gaps and pieces
//!   shorter than [`MIN_PIECE`] of the clipped segment are rounding noise and are
//!   dropped.
//!
//! # Acceleration
//!
//! Each front face's clipped polygon is projected once and its bounding box entered in
//! a uniform grid over the image, each cell listing its faces nearest first (with a copy
//! of the box, so passing a face over reads only the cell). A segment visits only the
//! cells it crosses, and in each only the faces whose nearest point is nearer than the
//! segment's farthest point (a face wholly beyond the segment cannot hide it) and whose
//! box meets the segment's line; it stops as soon as it is wholly hidden. Faces and edges
//! are prepared and processed in parallel runs (rayon).

use std::fmt::Write as _;
use std::ops::Range;

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::{Serialize, Serializer};

use super::image::RgbImage;
use super::lines::draw_line;
use super::scene::Scene;
use crate::camera::View;
use crate::model::BodyId;

/// Pieces (and gaps between hidden intervals) shorter than this fraction of their clipped
/// segment are rounding noise: dropped (closed).
pub const MIN_PIECE: f64 = 1e-9;

/// Relative tolerance of "strictly behind a face's plane": a point must lie behind it by
/// more than this times (the farthest distance of its segment from the eye + the plane's
/// distance from the eye), so edges lying in a face's plane (touching bodies, a face's own
/// corners) are not hidden by it.
const PLANE_TOL: f64 = 1e-9;

/// Polygons with more corners than this are treated as concave (the convexity test is
/// quadratic in the corners).
const MAX_CONVEX_TEST: usize = 16;

/// Relative tolerance of the convexity test: a corner may lie this far (relative to the
/// lengths involved) outside a side's eye plane. Corners that far out are rounding in
/// a planar face, and the error they cause is of the same order.
const CONVEX_TOL: f64 = 1e-10;

/// One visible piece of an edge, in pixel coordinates.
///
/// Serialises (serde) as `{"body": u64, "edge": u64, "a": [u, v], "b": [u, v],
/// "depth": [da, db]}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Segment {
    /// The body the edge belongs to.
    #[serde(serialize_with = "body_number")]
    pub body: BodyId,
    /// The edge's serial number.
    pub edge: u64,
    /// Start, pixels (the end nearer the edge's NVT).
    pub a: DVec2,
    /// End, pixels (the end nearer the edge's PVT).
    pub b: DVec2,
    /// Depth (−ZCC, meters, > 0) at `a` and at `b`.
    pub depth: [f64; 2],
}

/// A body id as the plain number the API shows.
fn body_number<S: Serializer>(id: &BodyId, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_u64(id.get())
}

/// The hidden-line drawing of `scene` seen through `view`.
///
/// Preconditions: `view` comes from a valid camera ([`View::new`]); the scene's bodies are
/// closed solids (or laminae) that do not interpenetrate for the drawing to be the true
/// one (interpenetrating bodies are cut where an edge enters another body's face, but
/// intersection curves are not drawn).
///
/// Postconditions: every segment is a visible piece of one edge with finite ends inside
/// the image window `[0, width] × [0, height]` (up to rounding) and depths ≥ the near
/// distance; pieces of one edge do not overlap; the order is deterministic: by body (id
/// order), then edge serial, then along the edge from NVT to PVT. Nothing panics for any
/// scene and view: a camera inside a body sees all its faces from behind, so that body
/// neither shows nor hides anything; a scene wholly behind the camera gives no segments.
pub fn hidden_lines(scene: &Scene, view: &View) -> Vec<Segment> {
    let eye = view.eye();
    let cam: Vec<DVec3> = scene
        .points
        .par_iter()
        .with_min_len(4096)
        .map(|&p| view.to_camera(p))
        .collect();
    let front: Vec<bool> = scene
        .faces
        .par_iter()
        .with_min_len(1024)
        .map(|f| f.faces_toward(eye))
        .collect();
    let occluders = Occluders::build(scene, view, &cam, &front);
    let grid = Grid::build(&occluders, view);

    let mut candidates: Vec<u32> = (0..scene.edges.len() as u32)
        .filter(|&e| {
            let f = scene.edges[e as usize].faces;
            front.get(f[0] as usize).copied().unwrap_or(false)
                || front.get(f[1] as usize).copied().unwrap_or(false)
        })
        .collect();
    let key = |e: &u32| {
        let edge = &scene.edges[*e as usize];
        (edge.body, edge.serial)
    };
    // Usually already in order (edge slots are numbered in creation order).
    if !candidates.is_sorted_by_key(key) {
        candidates.sort_unstable_by_key(key);
    }

    let ctx = Context {
        scene,
        view,
        cam: &cam,
        occ: &occluders,
        grid: &grid,
    };
    // Runs of edges in parallel, each into a vector of its own, joined in order.
    const RUN: usize = 256;
    let pieces: Vec<Vec<Segment>> = (0..candidates.len().div_ceil(RUN))
        .into_par_iter()
        .map_init(
            || Scratch::new(occluders.list.len()),
            |scratch, k| {
                let run = &candidates[k * RUN..((k + 1) * RUN).min(candidates.len())];
                let mut out = Vec::with_capacity(run.len());
                for &e in run {
                    ctx.edge(e as usize, scratch, &mut out);
                }
                out
            },
        )
        .collect();
    let mut segments = Vec::with_capacity(pieces.iter().map(Vec::len).sum());
    for p in pieces {
        segments.extend(p);
    }
    segments
}

/// The segments drawn as anti-aliased lines ([`draw_line`]) in `ink` on a `width ×
/// height` image filled with `background`.
///
/// Precondition: `width × height` is a size the caller is willing to allocate (the
/// server bounds it by the camera's limits).
pub fn draw(
    segments: &[Segment],
    width: u32,
    height: u32,
    background: [u8; 3],
    ink: [u8; 3],
) -> RgbImage {
    let mut img = RgbImage::filled(width, height, background);
    for s in segments {
        draw_line(&mut img, s.a, s.b, ink);
    }
    img
}

/// The segments as an SVG document: view box `0 0 width height` in pixels (the camera's
/// convention, v down), a white background, and one black `<line>` per segment carrying
/// `data-body` and `data-edge` (the body id and edge serial). Coordinates are written to
/// a thousandth of a pixel; segments with non-finite ends are left out.
pub fn to_svg(segments: &[Segment], width: u32, height: u32) -> String {
    let mut out = String::with_capacity(256 + segments.len() * 96);
    // Writing to a String cannot fail.
    let _ = write!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" \
         viewBox=\"0 0 {width} {height}\">\n\
         <rect width=\"{width}\" height=\"{height}\" fill=\"white\"/>\n\
         <g stroke=\"black\" stroke-width=\"1\" stroke-linecap=\"round\" fill=\"none\">\n"
    );
    for s in segments {
        if !(s.a.is_finite() && s.b.is_finite()) {
            continue;
        }
        out.push_str("<line x1=\"");
        number(&mut out, s.a.x);
        out.push_str("\" y1=\"");
        number(&mut out, s.a.y);
        out.push_str("\" x2=\"");
        number(&mut out, s.b.x);
        out.push_str("\" y2=\"");
        number(&mut out, s.b.y);
        let _ = writeln!(
            out,
            "\" data-body=\"{}\" data-edge=\"{}\"/>",
            s.body.get(),
            s.edge
        );
    }
    out.push_str("</g>\n</svg>\n");
    out
}

/// Writes `v` to a thousandth, without trailing zeros ("12.5", "3", "-0.125"), through
/// integer formatting (float formatting is several times slower).
fn number(out: &mut String, v: f64) {
    let milli = (v * 1000.0).round();
    if milli.is_nan() || milli.abs() >= 1e15 {
        // Beyond any image (or not finite): plain formatting.
        let _ = write!(out, "{v}");
        return;
    }
    let milli = milli as i64;
    if milli < 0 {
        out.push('-');
    }
    let m = milli.unsigned_abs();
    let (whole, frac) = (m / 1000, m % 1000);
    let _ = write!(out, "{whole}");
    if frac != 0 {
        out.push('.');
        let digits = [frac / 100, frac / 10 % 10, frac % 10];
        let n = if frac % 100 == 0 {
            1
        } else if frac % 10 == 0 {
            2
        } else {
            3
        };
        for d in &digits[..n] {
            out.push(char::from(b'0' + *d as u8));
        }
    }
}

/// One front face prepared as an occluder, in camera coordinates.
#[derive(Clone, Debug)]
struct Occluder {
    /// Index into [`Scene::faces`].
    face: u32,
    /// Unit outward normal, camera coordinates.
    normal: DVec3,
    /// Plane offset: `normal · c = offset` on the face (negative: the eye, at the
    /// origin, is on the outside).
    offset: f64,
    /// The smallest depth (−ZCC) of the near-clipped polygon.
    min_depth: f64,
    /// Bounding box of the projected polygon: u0, v0, u1, v1 (pixels, not clamped).
    bbox: [f64; 4],
    /// The polygon's range in [`Occluders::sides`] and [`Occluders::poly`].
    start: u32,
    /// Its number of corners (≥ 3).
    len: u32,
    /// Whether the polygon is convex as seen from the eye (every corner on the inner
    /// side of every side's eye plane), so that its inside along a segment is a single
    /// interval.
    convex: bool,
}

/// All occluders, nearest first (by `min_depth`, then face index).
struct Occluders {
    list: Vec<Occluder>,
    /// For each polygon side `c_i → c_{i+1}`, the normal `c_i × c_{i+1}` of the plane
    /// through the eye and that side.
    sides: Vec<DVec3>,
    /// The projected polygon, pixels.
    poly: Vec<DVec2>,
}

impl Occluders {
    fn build(scene: &Scene, view: &View, cam: &[DVec3], front: &[bool]) -> Occluders {
        // Runs of faces in parallel, each into flat arrays of its own, then joined.
        let parts = chunked(scene.faces.len(), 512, |faces| {
            let mut part = Occluders {
                list: Vec::new(),
                sides: Vec::new(),
                poly: Vec::new(),
            };
            let (mut corners, mut clipped) = (Vec::new(), Vec::new());
            for i in faces.filter(|&i| front[i]) {
                part.add(scene, view, cam, i, &mut corners, &mut clipped);
            }
            part
        });
        let total = |f: fn(&Occluders) -> usize| parts.iter().map(f).sum::<usize>();
        let mut out = Occluders {
            list: Vec::with_capacity(total(|p| p.list.len())),
            sides: Vec::with_capacity(total(|p| p.sides.len())),
            poly: Vec::with_capacity(total(|p| p.poly.len())),
        };
        for part in parts {
            let shift = out.sides.len() as u32;
            out.list.extend(part.list.into_iter().map(|o| Occluder {
                start: o.start + shift,
                ..o
            }));
            out.sides.extend(part.sides);
            out.poly.extend(part.poly);
        }
        // Nearest first; depths are positive, so their bits sort like them.
        let mut keys: Vec<(u64, u32, u32)> = out
            .list
            .iter()
            .enumerate()
            .map(|(k, o)| (o.min_depth.to_bits(), o.face, k as u32))
            .collect();
        keys.sort_unstable();
        out.list = keys
            .iter()
            .map(|k| out.list[k.2 as usize].clone())
            .collect();
        out
    }

    /// Prepares front face `i` (if it keeps a polygon beyond the near plane) and appends
    /// it. `corners` and `clipped` are working storage.
    fn add(
        &mut self,
        scene: &Scene,
        view: &View,
        cam: &[DVec3],
        i: usize,
        corners: &mut Vec<DVec3>,
        clipped: &mut Vec<DVec3>,
    ) {
        let f = &scene.faces[i];
        let ring = scene.ring(f);
        if ring.len() < 3 {
            return;
        }
        corners.clear();
        corners.extend(ring.iter().map(|&v| cam[v as usize]));
        let normal = view.direction_to_camera(f.normal);
        let centroid = corners.iter().sum::<DVec3>() / corners.len() as f64;
        let offset = normal.dot(centroid);
        view.clip_polygon_near(corners, clipped);
        let n = clipped.len();
        if n < 3 || !normal.is_finite() || !offset.is_finite() {
            return;
        }
        let start = self.sides.len();
        let mut bbox = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        let mut min_depth = f64::INFINITY;
        for k in 0..n {
            let c = clipped[k];
            let side = c.cross(clipped[(k + 1) % n]);
            let q = view.project(c);
            bbox = [
                bbox[0].min(q.x),
                bbox[1].min(q.y),
                bbox[2].max(q.x),
                bbox[3].max(q.y),
            ];
            min_depth = min_depth.min(-c.z);
            self.sides.push(side);
            self.poly.push(q);
        }
        let sides = &self.sides[start..];
        let finite = bbox.iter().all(|x| x.is_finite()) && sides.iter().all(|s| s.is_finite());
        if !finite {
            self.sides.truncate(start);
            self.poly.truncate(start);
            return;
        }
        let convex = n <= MAX_CONVEX_TEST
            && sides.iter().all(|m| {
                clipped.iter().all(|c| {
                    let g = m.dot(*c);
                    g <= 0.0
                        || g * g
                            <= CONVEX_TOL * CONVEX_TOL * m.length_squared() * c.length_squared()
                })
            });
        self.list.push(Occluder {
            face: i as u32,
            normal,
            offset,
            min_depth,
            bbox,
            start: start as u32,
            len: n as u32,
            convex,
        });
    }
}

/// `f` over consecutive runs of `0..n` of about `run` items, in parallel; the results in
/// order.
fn chunked<T: Send>(n: usize, run: usize, f: impl Fn(Range<usize>) -> T + Sync) -> Vec<T> {
    let runs = n.div_ceil(run.max(1));
    (0..runs)
        .into_par_iter()
        .map(|k| f(k * run..((k + 1) * run).min(n)))
        .collect()
}

/// A uniform grid of square cells over the image window; each cell lists (indices into
/// [`Occluders::list`], nearest first) the occluders whose bounding box meets it.
struct Grid {
    /// Cell side, pixels.
    cell: f64,
    /// Columns and rows.
    nx: usize,
    ny: usize,
    /// Window size, pixels.
    width: f64,
    height: f64,
    /// Cell `c` lists `items[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    items: Vec<Item>,
}

/// An occluder's entry in a grid cell: what is needed to pass it over without reading
/// the occluder itself.
#[derive(Clone, Copy, Debug, Default)]
struct Item {
    /// The occluder's `min_depth`.
    depth: f64,
    /// Its bounding box, clamped to the window widened by a pixel, then widened by
    /// [`Item::PAD`] and rounded to `f32` (so it still contains the polygon).
    bbox: [f32; 4],
    /// Index into [`Occluders::list`].
    occ: u32,
    /// Its face (index into [`Scene::faces`]).
    face: u32,
}

impl Item {
    /// Widening before rounding to `f32`: more than half a unit in the last place of any
    /// coordinate up to the largest image side plus a pixel.
    const PAD: f64 = 0.05;

    fn new(i: usize, o: &Occluder, width: f64, height: f64) -> Item {
        let b = o.bbox;
        let clamp = |x: f64, hi: f64| x.clamp(-1.0, hi + 1.0);
        Item {
            depth: o.min_depth,
            bbox: [
                (clamp(b[0], width) - Item::PAD) as f32,
                (clamp(b[1], height) - Item::PAD) as f32,
                (clamp(b[2], width) + Item::PAD) as f32,
                (clamp(b[3], height) + Item::PAD) as f32,
            ],
            occ: i as u32,
            face: o.face,
        }
    }
}

impl Grid {
    fn build(occ: &Occluders, view: &View) -> Grid {
        let (w, h) = view.size();
        let (width, height) = (w as f64, h as f64);
        // About one occluder per cell, between 8 and 64 pixels a side.
        let n = occ.list.len().max(1) as f64;
        let cell = (width * height / n).sqrt().clamp(8.0, 64.0);
        let nx = ((width / cell).ceil() as usize).max(1);
        let ny = ((height / cell).ceil() as usize).max(1);
        let mut grid = Grid {
            cell,
            nx,
            ny,
            width,
            height,
            start: vec![0; nx * ny + 1],
            items: Vec::new(),
        };
        let ranges: Vec<Option<[usize; 4]>> = occ
            .list
            .par_iter()
            .with_min_len(1024)
            .map(|o| grid.cells_of_box(o.bbox))
            .collect();
        for r in ranges.iter().flatten() {
            for y in r[1]..=r[3] {
                for x in r[0]..=r[2] {
                    grid.start[y * nx + x + 1] += 1;
                }
            }
        }
        for c in 0..nx * ny {
            grid.start[c + 1] += grid.start[c];
        }
        let mut fill = grid.start.clone();
        grid.items = vec![Item::default(); grid.start[nx * ny] as usize];
        for (i, r) in ranges.iter().enumerate() {
            let Some(r) = r else { continue };
            let item = Item::new(i, &occ.list[i], width, height);
            for y in r[1]..=r[3] {
                for x in r[0]..=r[2] {
                    let c = y * nx + x;
                    grid.items[fill[c] as usize] = item;
                    fill[c] += 1;
                }
            }
        }
        grid
    }

    /// The cell range `[x0, y0, x1, y1]` (inclusive) a pixel box meets, widened by a
    /// little against rounding, or `None` when it misses the window.
    fn cells_of_box(&self, b: [f64; 4]) -> Option<[usize; 4]> {
        const PAD: f64 = 1e-3;
        if b[2] < -PAD || b[3] < -PAD || b[0] > self.width + PAD || b[1] > self.height + PAD {
            return None;
        }
        // For x ≥ 0, `x as usize` is ⌊x⌋ (and the cast saturates).
        let col = |u: f64| (((u / self.cell).max(0.0)) as usize).min(self.nx - 1);
        let row = |v: f64| (((v / self.cell).max(0.0)) as usize).min(self.ny - 1);
        Some([
            col(b[0] - PAD),
            row(b[1] - PAD),
            col(b[2] + PAD),
            row(b[3] + PAD),
        ])
    }

    /// Calls `visit` with every cell the pixel segment `p`–`q` meets (conservatively:
    /// each column, or row, of cells the segment spans, and in it every cell between the
    /// segment's extremes there), until `visit` returns false. Returns false if stopped.
    fn walk(&self, p: DVec2, q: DVec2, mut visit: impl FnMut(usize) -> bool) -> bool {
        const PAD: f64 = 1e-6;
        let d = q - p;
        // Work along the major axis: index `along` picks a point's coordinate along it,
        // `across` the other one.
        let steep = d.y.abs() > d.x.abs();
        let (along, across) = if steep { (1, 0) } else { (0, 1) };
        let (n_along, n_across) = if steep {
            (self.ny, self.nx)
        } else {
            (self.nx, self.ny)
        };
        let (p0, p1) = (p[along], q[along]);
        let (lo, hi) = (p0.min(p1), p0.max(p1));
        // For x ≥ 0, `x as usize` is ⌊x⌋ (and the cast saturates).
        let index = |x: f64, n: usize| (((x / self.cell).max(0.0)) as usize).min(n.max(1) - 1);
        let (c0, c1) = (index(lo - PAD, n_along), index(hi + PAD, n_along));
        let slope = if p1 != p0 {
            (q[across] - p[across]) / (p1 - p0)
        } else {
            0.0
        };
        let at = |x: f64| p[across] + slope * (x - p0);
        for c in c0..=c1 {
            let x_lo = lo.max(c as f64 * self.cell);
            let x_hi = hi.min((c + 1) as f64 * self.cell);
            let (y_a, y_b) = (at(x_lo), at(x_hi));
            let (r0, r1) = (
                index(y_a.min(y_b) - PAD, n_across),
                index(y_a.max(y_b) + PAD, n_across),
            );
            for r in r0..=r1 {
                let cell = if steep {
                    c * self.nx + r
                } else {
                    r * self.nx + c
                };
                if !visit(cell) {
                    return false;
                }
            }
        }
        true
    }
}

/// Per-thread working storage.
struct Scratch {
    /// `seen[o] == stamp`: occluder `o` was already tried for the current segment.
    seen: Vec<u32>,
    stamp: u32,
    /// The hidden intervals found so far: sorted, disjoint, gaps ≥ [`MIN_PIECE`].
    hidden: Vec<(f64, f64)>,
    /// Parameters where one occluder's classification may change.
    breaks: Vec<f64>,
}

impl Scratch {
    fn new(occluders: usize) -> Scratch {
        Scratch {
            seen: vec![0; occluders],
            stamp: 0,
            hidden: Vec::new(),
            breaks: Vec::new(),
        }
    }

    /// A fresh stamp for a new segment.
    fn next_stamp(&mut self) -> u32 {
        if self.stamp == u32::MAX {
            self.seen.fill(0);
            self.stamp = 0;
        }
        self.stamp += 1;
        self.stamp
    }
}

/// Adds `[lo, hi]` to the sorted, disjoint list `hidden`, merging intervals that overlap
/// or are closer than [`MIN_PIECE`]. Intervals shorter than that are ignored.
fn add_interval(hidden: &mut Vec<(f64, f64)>, lo: f64, hi: f64) {
    if !at_least(hi - lo, MIN_PIECE) {
        return;
    }
    let i = hidden.partition_point(|&(_, h)| h < lo - MIN_PIECE);
    let mut j = i;
    let (mut lo, mut hi) = (lo, hi);
    while j < hidden.len() && hidden[j].0 <= hi + MIN_PIECE {
        lo = lo.min(hidden[j].0);
        hi = hi.max(hidden[j].1);
        j += 1;
    }
    hidden.splice(i..j, [(lo, hi)]);
}

/// `x ≥ min`, false when `x` is NaN.
#[inline]
fn at_least(x: f64, min: f64) -> bool {
    x >= min
}

/// Even-odd rule: whether pixel `q` lies inside the polygon `poly`.
fn inside(poly: &[DVec2], q: DVec2) -> bool {
    crate::model::geometry::point_in_polygon(q, poly)
}

/// What every edge's work shares.
struct Context<'a> {
    scene: &'a Scene,
    view: &'a View,
    cam: &'a [DVec3],
    occ: &'a Occluders,
    grid: &'a Grid,
}

/// One clipped candidate segment, camera coordinates, `p(τ) = a + τ·d`.
struct Piece {
    a: DVec3,
    b: DVec3,
    d: DVec3,
    /// max(|a|, |b|), for tolerances.
    scale: f64,
}

impl Piece {
    #[inline]
    fn at(&self, t: f64) -> DVec3 {
        if t <= 0.0 {
            self.a
        } else if t >= 1.0 {
            self.b
        } else {
            self.a + self.d * t
        }
    }
}

impl Context<'_> {
    /// Appends the visible pieces of scene edge `e` to `out`, along the edge.
    fn edge(&self, e: usize, scratch: &mut Scratch, out: &mut Vec<Segment>) {
        let edge = &self.scene.edges[e];
        let (Some(&ca), Some(&cb)) = (
            self.cam.get(edge.ends[0] as usize),
            self.cam.get(edge.ends[1] as usize),
        ) else {
            return;
        };
        let Some((t0, t1)) = self.view.clip_segment(ca, cb) else {
            return;
        };
        let a = if t0 > 0.0 { ca.lerp(cb, t0) } else { ca };
        let b = if t1 < 1.0 { ca.lerp(cb, t1) } else { cb };
        let piece = Piece {
            a,
            b,
            d: b - a,
            scale: a.length().max(b.length()),
        };
        if !at_least(piece.d.length(), MIN_PIECE * piece.scale) {
            return;
        }
        let (pa, pb) = (self.view.project(a), self.view.project(b));
        let far = (-a.z).max(-b.z);
        let lo = pa.min(pb);
        let hi = pa.max(pb);
        let own = edge.faces;
        // The segment's line: n·x = c; a box is off it when its extent along n misses c.
        let n = (pb - pa).perp();
        let c = n.dot(pa);
        let slack = 1e-3 * n.abs().element_sum();

        scratch.hidden.clear();
        let stamp = scratch.next_stamp();
        let Scratch {
            seen,
            hidden,
            breaks,
            ..
        } = scratch;
        let whole = self.grid.walk(pa, pb, |cell| {
            let items = &self.grid.items
                [self.grid.start[cell] as usize..self.grid.start[cell + 1] as usize];
            for item in items {
                if item.depth >= far {
                    break;
                }
                let [x0, y0, x1, y1] = item.bbox.map(f64::from);
                if x0 > hi.x
                    || x1 < lo.x
                    || y0 > hi.y
                    || y1 < lo.y
                    || item.face == own[0]
                    || item.face == own[1]
                {
                    continue;
                }
                let centre = n.x * (x0 + x1) + n.y * (y0 + y1);
                let reach = n.x.abs() * (x1 - x0) + n.y.abs() * (y1 - y0);
                if (centre - 2.0 * c).abs() > reach + 2.0 * slack {
                    continue;
                }
                let o = item.occ as usize;
                if seen[o] == stamp {
                    continue;
                }
                seen[o] = stamp;
                self.hide(&piece, &self.occ.list[o], hidden, breaks);
                if let [(h0, h1)] = hidden[..]
                    && h0 <= MIN_PIECE
                    && h1 >= 1.0 - MIN_PIECE
                {
                    return false;
                }
            }
            true
        });
        if !whole {
            return;
        }

        // The complement of the hidden intervals in [0, 1].
        let mut from = 0.0;
        let mut push = |t0: f64, t1: f64| {
            if t1 - t0 >= MIN_PIECE {
                let (p, q) = (piece.at(t0), piece.at(t1));
                out.push(Segment {
                    body: self.scene.bodies[edge.body as usize].id,
                    edge: edge.serial,
                    a: if t0 <= 0.0 { pa } else { self.view.project(p) },
                    b: if t1 >= 1.0 { pb } else { self.view.project(q) },
                    depth: [-p.z, -q.z],
                });
            }
        };
        for &(h0, h1) in hidden.iter() {
            push(from, h0.min(1.0));
            from = h1;
        }
        push(from, 1.0);
    }

    /// Adds to `hidden` the parameters of `piece` that `occ` hides.
    fn hide(
        &self,
        piece: &Piece,
        occ: &Occluder,
        hidden: &mut Vec<(f64, f64)>,
        breaks: &mut Vec<f64>,
    ) {
        // (a) Strictly behind the plane: s(τ) = n·p(τ) − offset < −tol (the eye, at the
        // origin, has s = −offset > 0).
        let sa = occ.normal.dot(piece.a) - occ.offset;
        let sb = occ.normal.dot(piece.b) - occ.offset;
        let tol = PLANE_TOL * (piece.scale + occ.offset.abs());
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        let ds = sb - sa;
        if ds == 0.0 {
            if sa.is_nan() || sa >= -tol {
                return;
            }
        } else {
            let t = (-tol - sa) / ds;
            if ds > 0.0 {
                hi = hi.min(t);
            } else {
                lo = lo.max(t);
            }
        }
        if !at_least(hi - lo, MIN_PIECE) {
            return;
        }
        let range = occ.start as usize..(occ.start + occ.len) as usize;
        if occ.convex {
            // (b) for a convex polygon: inside every side's eye plane, g(τ) = m·p(τ) < 0
            // (corners have m·c ≤ 0 and the eye plane's normal points out), an interval.
            for m in &self.occ.sides[range] {
                if *m == DVec3::ZERO {
                    continue;
                }
                let (ga, gb) = (m.dot(piece.a), m.dot(piece.b));
                let dg = gb - ga;
                if dg == 0.0 {
                    if ga.is_nan() || ga >= 0.0 {
                        return;
                    }
                } else {
                    let t = ga / (ga - gb);
                    if dg > 0.0 {
                        hi = hi.min(t);
                    } else {
                        lo = lo.max(t);
                    }
                }
                if !at_least(hi - lo, MIN_PIECE) {
                    return;
                }
            }
            add_interval(hidden, lo, hi);
            return;
        }
        // (b) Inside the polygon as seen from the eye: may change only where the segment
        // crosses a plane through the eye and a side of the polygon.
        breaks.clear();
        breaks.push(lo);
        for m in &self.occ.sides[range.clone()] {
            let (ga, gb) = (m.dot(piece.a), m.dot(piece.b));
            if (ga < 0.0) != (gb < 0.0) {
                let t = ga / (ga - gb);
                if t > lo && t < hi {
                    breaks.push(t);
                }
            }
        }
        breaks.push(hi);
        breaks.sort_unstable_by(f64::total_cmp);
        let poly = &self.occ.poly[range];
        for w in breaks.windows(2) {
            let (t0, t1) = (w[0], w[1]);
            if t1 - t0 < MIN_PIECE {
                continue;
            }
            let q = self.view.project(piece.at(0.5 * (t0 + t1)));
            if inside(poly, q) {
                add_interval(hidden, t0, t1);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Serial;

    #[test]
    fn intervals_merge_and_close_tiny_gaps() {
        let mut h = Vec::new();
        add_interval(&mut h, 0.5, 0.6);
        add_interval(&mut h, 0.1, 0.2);
        add_interval(&mut h, 0.6 + 1e-12, 0.7);
        add_interval(&mut h, 0.3, 0.3 + 1e-12);
        assert_eq!(h, vec![(0.1, 0.2), (0.5, 0.7)]);
        add_interval(&mut h, 0.15, 0.55);
        assert_eq!(h, vec![(0.1, 0.7)]);
    }

    #[test]
    fn even_odd_handles_a_concave_polygon() {
        let l = crate::render::sample::L_SHAPE;
        assert!(inside(&l, DVec2::new(0.5, 1.5)));
        assert!(inside(&l, DVec2::new(1.5, 0.5)));
        assert!(!inside(&l, DVec2::new(1.5, 1.5)));
        assert!(!inside(&l, DVec2::new(-0.5, 0.5)));
    }

    #[test]
    fn numbers_are_short() {
        let mut s = String::new();
        for v in [12.5, 3.0, -0.125, -0.0001, 1.23456, 1_279.999_9, 0.05, -7.0] {
            number(&mut s, v);
            s.push(' ');
        }
        assert_eq!(s, "12.5 3 -0.125 0 1.235 1280 0.05 -7 ");
    }

    #[test]
    fn segments_serialise_as_plain_numbers() {
        let s = Segment {
            body: BodyId(Serial(7)),
            edge: 12,
            a: DVec2::new(1.5, 2.0),
            b: DVec2::new(3.0, 4.25),
            depth: [5.0, 6.5],
        };
        let json = serde_json::to_value(s).unwrap();
        assert_eq!(
            json,
            serde_json::json!({
                "body": 7, "edge": 12, "a": [1.5, 2.0], "b": [3.0, 4.25], "depth": [5.0, 6.5]
            })
        );
    }

    #[test]
    fn svg_has_one_line_per_segment() {
        let s = Segment {
            body: BodyId(Serial(3)),
            edge: 9,
            a: DVec2::new(1.0, 2.0),
            b: DVec2::new(30.0, 4.5),
            depth: [1.0, 1.0],
        };
        let svg = to_svg(&[s, s], 64, 48);
        assert!(svg.starts_with("<svg"));
        assert!(svg.contains("viewBox=\"0 0 64 48\""));
        assert_eq!(svg.matches("<line ").count(), 2);
        assert!(svg.contains(
            "<line x1=\"1\" y1=\"2\" x2=\"30\" y2=\"4.5\" data-body=\"3\" data-edge=\"9\"/>"
        ));
        let img = draw(&[s], 64, 48, [255; 3], [0; 3]);
        assert!(img.data.iter().any(|&c| c < 128));
    }
}
