//! The triangle rasterizer shared by the camera's z-buffer and the shadow maps.
//!
//! A [`Projection`] says where each scene point lands in a raster (continuous pixel
//! coordinates, the camera's convention: the centre of pixel (x, y) is (x + ½, y + ½)),
//! which faces it draws, and, per drawn face, the *key plane*: a value `a·u + b·v + c`
//! that is affine in pixel coordinates and larger for surfaces nearer the viewer (1/depth
//! for a perspective view, minus the depth for an orthographic one). Because the key is
//! affine in screen space it is exact at every pixel centre, with no per-vertex
//! interpolation: for a perspective view, 1/depth of a plane is an affine function of the
//! pixel (the ray through the pixel meets the face's plane at that depth).
//!
//! [`draw`] then runs in three parallel passes:
//!
//! 1. *Points*: every point is projected once (f64).
//! 2. *Binning*, in fixed chunks of triangles, reading the scene in order: triangles of
//!    faces the view does not draw (back faces, for instance) and triangles whose
//!    bounding box holds no pixel centre are dropped at once. Small triangles (most
//!    triangles of a big world) are drawn right there, into *fragments* (pixel, key,
//!    face) listed by horizontal band of rows; the others are listed, by index, in every
//!    band their box touches. A triangle with a corner not beyond the near plane is
//!    clipped there first ([`Projection::clip`]) and its pieces kept with explicit
//!    coordinates.
//! 3. *Bands*, in parallel: each band of rows is cleared, then takes, chunk by chunk, its
//!    fragments and its triangles with a depth test, then is finished (keys turned into
//!    depths, say) while it is still in the cache. The order in which a pixel's
//!    candidates arrive depends only on the scene, so the result does not depend on the
//!    thread count.
//!
//! Inner loops are branch-free where the outcome is a coin toss (which end of an edge
//! comes first, whether a centre is inside, which surface is nearer), and floor and ceil
//! avoid libm calls, which the baseline x86-64 target would otherwise make.
//!
//! # The sampling rule
//!
//! A pixel belongs to a triangle when its centre is inside it, with the top-left rule for
//! centres exactly on an edge: a centre on an edge counts only if the edge is a *left*
//! edge (the inside is to its right) or a *top* edge (horizontal, inside below). Edge
//! functions are evaluated in f64 at each pixel centre, directly (not accumulated), and
//! each edge's coefficients are computed from its lexicographically smaller end, so two
//! triangles sharing an edge evaluate bit-for-bit opposite values there: a shared edge is
//! never drawn twice and never leaves a crack, and a centre is classified correctly
//! unless it lies within about 1e-12 pixels of an edge. (Fragments and band fills run
//! the same code, so they decide alike.)

use std::hint::select_unpredictable;

use glam::DVec3;
use rayon::prelude::*;

use crate::camera::View;
use crate::render::scene::{Scene, SceneFace};

/// A point that cannot be projected directly (not beyond the near plane).
const HIDDEN: [f64; 2] = [f64::NAN, f64::NAN];

/// Where a raster puts the scene: see the [module documentation](self).
pub(super) trait Projection: Sync {
    /// The pixel coordinates of world point `p`, or NaN coordinates when the point is not
    /// beyond the near plane (then its triangles go through [`Projection::clip`]).
    fn point(&self, p: DVec3) -> [f64; 2];

    /// Whether this view draws `face` (a front face, say).
    fn draws(&self, face: &SceneFace) -> bool;

    /// The key plane `[a, b, c]` (key = a·u + b·v + c at pixel coordinates (u, v), larger
    /// nearer) of `face`. Precondition: the view draws the face.
    fn plane(&self, face: &SceneFace) -> [f64; 3];

    /// The part of triangle `tri` (indices into the scene's points; `screen` is
    /// [`Projection::point`] of every point) beyond the near plane, as a convex polygon in
    /// pixel coordinates, into `out` (cleared first). Only called for a triangle with a
    /// corner whose screen position is NaN. The default draws nothing.
    fn clip(&self, scene: &Scene, tri: [u32; 3], screen: &[[f64; 2]], out: &mut Vec<[f64; 2]>) {
        let _ = (scene, tri, screen);
        out.clear();
    }
}

/// A camera's perspective projection, drawing the faces that look toward its eye
/// (`front`, for pictures) or those that look away from it (for the shadow map of a point
/// light, which keeps the far sides of occluders).
#[derive(Clone, Copy, Debug)]
pub(super) struct Perspective {
    /// The camera.
    pub view: View,
    /// Draw the faces whose outside looks toward the eye (else those looking away).
    pub front: bool,
}

impl Projection for Perspective {
    #[inline]
    fn point(&self, p: DVec3) -> [f64; 2] {
        let c = self.view.to_camera(p);
        if c.z <= -self.view.near {
            let uv = self.view.project(c);
            [uv.x, uv.y]
        } else {
            HIDDEN
        }
    }

    #[inline]
    fn draws(&self, face: &SceneFace) -> bool {
        let side = face.normal.dot(self.view.eye()) - face.offset;
        if self.front { side > 0.0 } else { side < 0.0 }
    }

    #[inline]
    fn plane(&self, face: &SceneFace) -> [f64; 3] {
        // The plane n·p = offset in camera coordinates is n_c·c = d_c. The ray through
        // pixel (u, v) is c = t·((u − cx)/fx, −(v − cy)/fy, −1) at depth t, so
        // 1/t = n_c·r / d_c: affine in (u, v).
        let k = &self.view.intrinsics;
        let n = self.view.direction_to_camera(face.normal);
        let d = face.offset - face.normal.dot(self.view.eye());
        let (a, b) = (n.x / k.fx, -n.y / k.fy);
        [a / d, b / d, -(a * k.cx + b * k.cy + n.z) / d]
    }

    /// Sutherland–Hodgman at the near plane like [`View::clip_polygon_near`], except that
    /// the crossing point of an edge is always computed from the end with the smaller
    /// point index, so the two triangles sharing a clipped edge get bit-identical points
    /// there (watertight at the cut as everywhere else).
    fn clip(&self, scene: &Scene, tri: [u32; 3], screen: &[[f64; 2]], out: &mut Vec<[f64; 2]>) {
        out.clear();
        let z_max = -self.view.near;
        let cam = tri.map(|i| self.view.to_camera(scene.points[i as usize]));
        let inside = cam.map(|c| c.z <= z_max);
        for k in 0..3 {
            let n = (k + 1) % 3;
            if inside[k] {
                out.push(screen[tri[k] as usize]);
            }
            if inside[k] != inside[n] {
                let (a, b) = if tri[k] < tri[n] { (k, n) } else { (n, k) };
                let t = (z_max - cam[a].z) / (cam[b].z - cam[a].z);
                let mut x = cam[a].lerp(cam[b], t);
                x.z = z_max;
                let uv = self.view.project(x);
                out.push([uv.x, uv.y]);
            }
        }
    }
}

/// Where a band's accepted pixels go.
pub(super) trait Sink {
    /// Offers pixel `i` (index within the band, row-major) with key `key` for face
    /// `face`; the sink keeps it if its key is larger than the one it holds (all keys
    /// start at 0, so a key of 0 or less, or NaN, is never kept).
    fn plot(&mut self, i: usize, key: f32, face: u32);

    /// Empties the sink (every key 0: nothing drawn). Drawing calls it first, in the
    /// band's own thread, so a fresh buffer's pages are first touched there, by a write.
    fn clear(&mut self);
}

/// A z-buffer with face ids, both cleared to zeros: a pixel holds face `f` as `f + 1`,
/// and 0 where no face was drawn; a key must be positive to be drawn.
pub(super) struct Ids<'a> {
    /// Keys, nearer larger.
    pub key: &'a mut [f32],
    /// Face of each pixel plus one.
    pub face: &'a mut [u32],
}

impl Sink for Ids<'_> {
    fn clear(&mut self) {
        self.key.fill(0.0);
        self.face.fill(0);
    }

    #[inline(always)]
    fn plot(&mut self, i: usize, key: f32, face: u32) {
        // Branch-free: which surface wins is hard to predict.
        let (k, f) = (&mut self.key[i], &mut self.face[i]);
        let take = key > *k;
        *k = select_unpredictable(take, key, *k);
        *f = select_unpredictable(take, face.wrapping_add(1), *f);
    }
}

/// A z-buffer alone (shadow maps).
pub(super) struct Keys<'a>(pub &'a mut [f32]);

impl Sink for Keys<'_> {
    fn clear(&mut self) {
        self.0.fill(0.0);
    }

    #[inline(always)]
    fn plot(&mut self, i: usize, key: f32, _face: u32) {
        // Branch-free, as for [`Ids`].
        let k = &mut self.0[i];
        *k = select_unpredictable(key > *k, key, *k);
    }
}

/// A horizontal band of rows of a raster.
pub(super) struct Band<S> {
    /// First row.
    pub y0: usize,
    /// Number of rows.
    pub rows: usize,
    /// Raster width, pixels.
    pub width: usize,
    /// The band's pixels.
    pub sink: S,
}

/// Rows per band for a raster `height` rows high: several bands per thread, so that
/// uneven bands balance.
fn band_rows(height: usize) -> usize {
    let threads = rayon::current_num_threads().max(1);
    height.div_ceil(threads * 8).clamp(8, 256)
}

/// ⌊x⌋ as an integer without a libm call (the baseline x86-64 target has no rounding
/// instruction). Saturates for huge values; precondition: `x` is not NaN.
#[inline(always)]
fn floor_i(x: f64) -> i64 {
    let i = x as i64;
    i.saturating_sub(i64::from((i as f64) > x))
}

/// ⌈x⌉ as an integer, like [`floor_i`].
#[inline(always)]
fn ceil_i(x: f64) -> i64 {
    let i = x as i64;
    i.saturating_add(i64::from((i as f64) < x))
}

/// The pixel-centre index range `[lo, hi]` (inclusive, clamped to `0..n`) of the interval
/// `[min, max]`, or `None` if it holds no pixel centre. Precondition: both finite.
#[inline(always)]
fn centres(min: f64, max: f64, n: usize) -> Option<(usize, usize)> {
    let lo = ceil_i(min - 0.5).max(0);
    let hi = floor_i(max - 0.5).min(n as i64 - 1);
    if lo <= hi {
        Some((lo as usize, hi as usize))
    } else {
        None
    }
}

/// The pixel-centre box of triangle `v`: `(x0, x1, y0, y1)` inclusive, or `None` when it
/// holds no pixel centre of a `width × height` raster or has a non-finite corner.
#[inline(always)]
fn pixel_box(
    v: &[[f64; 2]; 3],
    width: usize,
    height: usize,
) -> Option<(usize, usize, usize, usize)> {
    let [[ax, ay], [bx, by], [cx, cy]] = *v;
    if !(ax + ay + bx + by + cx + cy).is_finite() {
        return None;
    }
    let (y0, y1) = centres(ay.min(by).min(cy), ay.max(by).max(cy), height)?;
    let (x0, x1) = centres(ax.min(bx).min(cx), ax.max(bx).max(cx), width)?;
    Some((x0, x1, y0, y1))
}

/// The edge function `[a, b, c]` of the directed edge `p → q`: `a·x + b·y + c` is zero on
/// the edge's line and positive to its left as seen in pixel coordinates (v down) —
/// computed from the lexicographically smaller end and negated if needed, so `edge(q, p)`
/// is exactly `−edge(p, q)`.
#[inline(always)]
fn edge(p: [f64; 2], q: [f64; 2]) -> [f64; 3] {
    // Branch-free (which end is smaller is a coin toss): select with masks, negate by
    // flipping sign bits (an exact negation).
    let flip = (q[0] < p[0]) | ((q[0] == p[0]) & (q[1] < p[1]));
    let m = 0u64.wrapping_sub(u64::from(flip));
    let sel = |x: f64, y: f64| f64::from_bits((x.to_bits() & m) | (y.to_bits() & !m));
    let (sx, sy, ex, ey) = (
        sel(q[0], p[0]),
        sel(q[1], p[1]),
        sel(p[0], q[0]),
        sel(p[1], q[1]),
    );
    let a = sy - ey;
    let b = ex - sx;
    let c = -(a * sx + b * sy);
    let sign = m & (1 << 63);
    [a, b, c].map(|v| f64::from_bits(v.to_bits() ^ sign))
}

/// Boxes of at most this many pixel centres are tested centre by centre, branch-free,
/// without the per-row span set-up.
const SMALL_BOX: usize = 128;

/// Fills triangle `v` (pixel coordinates) of `face` with key plane `plane` into the rows
/// of `band` (see the [module documentation](self) for the sampling rule). Degenerate
/// triangles (no area) and non-finite ones draw nothing.
#[inline]
pub(super) fn fill<S: Sink>(band: &mut Band<S>, v: [[f64; 2]; 3], plane: [f64; 3], face: u32) {
    if let Some(bbox) = pixel_box(&v, band.width, band.y0 + band.rows) {
        fill_box(band, v, plane, face, bbox);
    }
}

/// [`fill`] for a triangle whose [`pixel_box`] in a raster as wide as the band and
/// reaching at least to its last row is `(x0, x1, y0, y1)`.
#[inline]
fn fill_box<S: Sink>(
    band: &mut Band<S>,
    v: [[f64; 2]; 3],
    plane: [f64; 3],
    face: u32,
    (x0, x1, y0, y1): (usize, usize, usize, usize),
) {
    let (y0, y1) = (y0.max(band.y0), y1.min(band.y0 + band.rows - 1));
    if y0 > y1 {
        return;
    }
    let e = [edge(v[0], v[1]), edge(v[1], v[2]), edge(v[2], v[0])];
    // Orientation: the inside is where every edge function has the sign it has at the
    // opposite corner.
    let s = e[0][0] * v[2][0] + (e[0][1] * v[2][1] + e[0][2]);
    if s == 0.0 || s.is_nan() {
        return;
    }
    let sign = s.to_bits() & (1 << 63);
    let e = e.map(|k| k.map(|x| f64::from_bits(x.to_bits() ^ sign)));
    // Top-left rule: a centre exactly on an edge (value ±0) counts for a left edge
    // (value grows with x) or a top edge (constant in x, grows with y). For the others the
    // value must be positive, which is tested as at least the smallest normal double
    // (edge values between 0 and 2.2e-308 do not occur at pixel scales, and a subnormal
    // constant would slow the comparisons).
    let lo = e.map(|[a, b, _]| {
        let top_left = (a > 0.0) | ((a == 0.0) & (b > 0.0));
        f64::from_bits(f64::MIN_POSITIVE.to_bits() & u64::from(top_left).wrapping_sub(1))
    });
    if (x1 - x0 + 1) * (y1 - y0 + 1) <= SMALL_BOX {
        let [[a0, b0, c0], [a1, b1, c1], [a2, b2, c2]] = e;
        for y in y0..=y1 {
            let py = y as f64 + 0.5;
            let (r0, r1, r2) = (b0 * py + c0, b1 * py + c1, b2 * py + c2);
            let row = (y - band.y0) * band.width;
            let krow = plane[1] * py + plane[2];
            // x + 0.5 is exact, and so is adding 1 to it.
            let mut px = x0 as f64 + 0.5;
            for x in x0..=x1 {
                let inside = u8::from(a0 * px + r0 >= lo[0])
                    & u8::from(a1 * px + r1 >= lo[1])
                    & u8::from(a2 * px + r2 >= lo[2]);
                // Outside, the key becomes 0, which never wins: arithmetic rather than a
                // condition, so that the loop has no branch to mispredict.
                let key = (plane[0] * px + krow) as f32 * f32::from(inside);
                band.sink.plot(row + x, key, face);
                px += 1.0;
            }
        }
        return;
    }
    // Each edge function is monotonic along a row, so the inside of a row is an interval:
    // edges whose function grows with x bound it on the left, those whose function falls
    // bound it on the right, and those constant in x admit the whole row or none of it.
    // Per row, each bound is estimated from where the edge crosses the row: with t the
    // crossing's column (fractional), the first column inside is ⌊t⌋, ⌊t⌋ + 1 or
    // ⌊t⌋ + 2 as long as t is off by less than a pixel (it is off by about 1e-12), and
    // the last one likewise from ⌈t⌉. So the two columns at each end of the estimated
    // span are tested exactly and the columns between them are inside without a test.
    let inv = e.map(|[a, ..]| if a != 0.0 { 1.0 / a } else { 0.0 });
    let row_ok = |r: &[f64; 3]| -> (i64, i64) {
        let (mut xa, mut xb) = (x0 as i64, x1 as i64);
        for k in 0..3 {
            let a = e[k][0];
            let t = -r[k] * inv[k] - 0.5;
            if a > 0.0 {
                xa = xa.max(floor_i(t));
            } else if a < 0.0 {
                xb = xb.min(ceil_i(t));
            } else if r[k] < lo[k] {
                xb = -1;
            }
        }
        (xa, xb)
    };
    let [[a0, b0, c0], [a1, b1, c1], [a2, b2, c2]] = e;
    for y in y0..=y1 {
        let py = y as f64 + 0.5;
        let r = [b0 * py + c0, b1 * py + c1, b2 * py + c2];
        let (xa, xb) = row_ok(&r);
        if xa > xb {
            continue;
        }
        let row = (y - band.y0) * band.width;
        let krow = plane[1] * py + plane[2];
        let mut tested = |x: i64| {
            let px = x as f64 + 0.5;
            if a0 * px + r[0] >= lo[0] && a1 * px + r[1] >= lo[1] && a2 * px + r[2] >= lo[2] {
                band.sink
                    .plot(row + x as usize, (plane[0] * px + krow) as f32, face);
            }
        };
        let head = xb.min(xa + 1);
        for x in xa..=head {
            tested(x);
        }
        for x in (head + 1).max(xb - 1)..=xb {
            tested(x);
        }
        if xb - xa >= 4 {
            let (from, to) = ((xa + 2) as usize, (xb - 2) as usize);
            let mut px = from as f64 + 0.5;
            for x in from..=to {
                band.sink.plot(row + x, (plane[0] * px + krow) as f32, face);
                px += 1.0;
            }
        }
    }
}

/// A pixel of a small triangle, found while binning: index within its band, key, face.
#[derive(Clone, Copy, Debug)]
struct Fragment {
    i: u32,
    key: f32,
    face: u32,
}

/// One chunk of triangles, binned by band.
#[derive(Default)]
struct Binned {
    /// Per band: the pixels of the chunk's small triangles, in triangle order.
    fragments: Vec<Vec<Fragment>>,
    /// Per band: the other triangles, either a triangle (offset from the chunk's first)
    /// or, with [`EXTRA`] set, an index into `extra`.
    bins: Vec<Vec<u32>>,
    /// Pieces of triangles clipped at the near plane: corners and face.
    extra: Vec<([[f64; 2]; 3], u32)>,
}

impl Binned {
    /// Empties the bins for `bands` bands, keeping their memory.
    fn reset(&mut self, bands: usize) {
        self.fragments.resize_with(bands, Vec::new);
        self.fragments.truncate(bands);
        self.fragments.iter_mut().for_each(Vec::clear);
        self.bins.resize_with(bands, Vec::new);
        self.bins.truncate(bands);
        self.bins.iter_mut().for_each(Vec::clear);
        self.extra.clear();
    }
}

/// Marks a bin entry as a clipped piece.
const EXTRA: u32 = 1 << 31;

/// Triangles per binning chunk. Fixed, so that the drawing order (and so which of two
/// surfaces at exactly the same depth wins) does not depend on the number of threads.
const CHUNK: usize = 8192;

/// Triangles whose box holds at most this many pixel centres are drawn into fragments
/// while binning, where the scene is read in order, rather than in the bands.
const FRAGMENT_BOX: usize = 32;

/// A sink that turns a small triangle's pixels into fragments in the bands' lists.
struct Fragments<'a> {
    lists: &'a mut [Vec<Fragment>],
    /// Pixels per band.
    band_pixels: usize,
}

impl Sink for Fragments<'_> {
    #[inline]
    fn plot(&mut self, i: usize, key: f32, face: u32) {
        if key > 0.0 {
            let b = i / self.band_pixels;
            let i = (i - b * self.band_pixels) as u32;
            self.lists[b].push(Fragment { i, key, face });
        }
    }

    fn clear(&mut self) {}
}

/// Memory one picture's views can share: the projected points and the bins.
#[derive(Default)]
pub(super) struct Scratch {
    screen: Vec<[f64; 2]>,
    binned: Vec<Binned>,
}

/// Draws `scene` as `proj` sees it into a `width × height` raster: `sinks(rows)` gives
/// the bands of `rows` rows each, top to bottom, that cover the raster; each band is
/// cleared, drawn, then handed to `finish` while it is still in the cache, and what
/// `finish` returns is collected, band by band. `scratch` is working memory (reused, so
/// that drawing several views in turn allocates once). A raster of zero size draws nothing
/// and returns no results.
///
/// Postcondition: every pixel whose centre is inside a drawn triangle (after clipping)
/// was offered to its band's sink, with the triangle's key there and its face. The order
/// in which a pixel's candidates are offered depends only on the scene (fixed chunks of
/// triangles in scene order; within a chunk, small triangles first), not on the threads.
pub(super) fn draw<P, S, F, R, G>(
    scene: &Scene,
    proj: &P,
    width: usize,
    height: usize,
    scratch: &mut Scratch,
    sinks: F,
    finish: G,
) -> Vec<R>
where
    P: Projection,
    S: Sink + Send,
    F: FnOnce(usize) -> Vec<Band<S>>,
    G: Fn(&mut Band<S>) -> R + Sync,
    R: Send,
{
    if width == 0 || height == 0 {
        return Vec::new();
    }
    let Scratch { screen, binned } = scratch;
    screen.clear();
    screen.par_extend(
        scene
            .points
            .par_iter()
            .with_min_len(4096)
            .map(|&p| proj.point(p)),
    );
    let screen = &screen[..];
    let rows = band_rows(height);
    let nbands = height.div_ceil(rows);
    let chunks = scene.triangles.len().div_ceil(CHUNK);
    binned.resize_with(chunks, Binned::default);
    binned.truncate(chunks);
    binned
        .par_iter_mut()
        .zip(scene.triangles.par_chunks(CHUNK))
        .enumerate()
        .for_each(|(ci, (out, tris))| {
            let base = ci * CHUNK;
            out.reset(nbands);
            let Binned {
                fragments,
                bins,
                extra,
            } = out;
            let mut small = Band {
                y0: 0,
                rows: height,
                width,
                sink: Fragments {
                    lists: fragments,
                    band_pixels: rows * width,
                },
            };
            let mut poly = Vec::new();
            let (mut last, mut drawn, mut plane) = (u32::MAX, false, None);
            for (k, tri) in tris.iter().enumerate() {
                let f = scene.triangle_faces[base + k];
                if f != last {
                    last = f;
                    drawn = proj.draws(&scene.faces[f as usize]);
                    plane = None;
                }
                if !drawn {
                    continue;
                }
                let v = tri.map(|i| screen[i as usize]);
                if v[0][0].is_nan() || v[1][0].is_nan() || v[2][0].is_nan() {
                    proj.clip(scene, *tri, screen, &mut poly);
                    for j in 1..poly.len().saturating_sub(1) {
                        let piece = [poly[0], poly[j], poly[j + 1]];
                        if let Some((.., y0, y1)) = pixel_box(&piece, width, height) {
                            let id = EXTRA | extra.len() as u32;
                            extra.push((piece, f));
                            for bin in &mut bins[y0 / rows..=y1 / rows] {
                                bin.push(id);
                            }
                        }
                    }
                    continue;
                }
                let Some((x0, x1, y0, y1)) = pixel_box(&v, width, height) else {
                    continue;
                };
                if (x1 - x0 + 1) * (y1 - y0 + 1) <= FRAGMENT_BOX {
                    let plane = *plane.get_or_insert_with(|| proj.plane(&scene.faces[f as usize]));
                    fill_box(&mut small, v, plane, f, (x0, x1, y0, y1));
                } else {
                    for bin in &mut bins[y0 / rows..=y1 / rows] {
                        bin.push(k as u32);
                    }
                }
            }
        });
    let binned = &binned[..];
    let bands = sinks(rows);
    bands
        .into_par_iter()
        .enumerate()
        .map(|(b, mut band)| {
            band.sink.clear();
            let (mut last, mut plane) = (u32::MAX, [0.0; 3]);
            for (ci, chunk) in binned.iter().enumerate() {
                for p in &chunk.fragments[b] {
                    band.sink.plot(p.i as usize, p.key, p.face);
                }
                for &entry in &chunk.bins[b] {
                    let (v, f) = if entry & EXTRA != 0 {
                        chunk.extra[(entry & !EXTRA) as usize]
                    } else {
                        let t = ci * CHUNK + entry as usize;
                        let v = scene.triangles[t].map(|i| screen[i as usize]);
                        (v, scene.triangle_faces[t])
                    };
                    if f != last {
                        last = f;
                        plane = proj.plane(&scene.faces[f as usize]);
                    }
                    fill(&mut band, v, plane, f);
                }
            }
            finish(&mut band)
        })
        .collect()
}

/// Draws `scene` as `proj` sees it into `key`, a `width × height` z-buffer of keys alone
/// (a shadow map): [`draw`] into [`Keys`] bands. Precondition: `key.len()` is
/// `width · height`; every value is overwritten (0 where nothing is drawn).
pub(super) fn draw_keys<P: Projection>(
    scene: &Scene,
    proj: &P,
    width: usize,
    height: usize,
    key: &mut [f32],
    scratch: &mut Scratch,
) {
    draw(
        scene,
        proj,
        width,
        height,
        scratch,
        |rows| {
            split_rows(key, width, rows)
                .into_iter()
                .map(|(y0, k)| Band {
                    y0,
                    rows: k.len() / width,
                    width,
                    sink: Keys(k),
                })
                .collect()
        },
        |_| (),
    );
}

/// Splits a row-major buffer of `width`-pixel rows into bands of `rows` rows.
pub(super) fn split_rows<T>(buf: &mut [T], width: usize, rows: usize) -> Vec<(usize, &mut [T])> {
    buf.chunks_mut((width * rows).max(1))
        .enumerate()
        .map(|(b, c)| (b * rows, c))
        .collect()
}
