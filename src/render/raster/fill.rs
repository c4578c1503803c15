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
//! 1. *Per point and per face*: points are projected once (f64), faces get their key
//!    planes (NaN for faces the view does not draw: back faces, for instance).
//! 2. *Binning*, in chunks of triangles: a triangle of a drawn face whose bounding box
//!    holds no pixel centre is dropped at once (most triangles of a big world); the others
//!    are listed in every horizontal band of rows their box touches. A triangle with a
//!    corner not beyond the near plane is clipped there first ([`Projection::clip`]) and
//!    its pieces kept with explicit coordinates.
//! 3. *Bands*, in parallel: each band of rows walks its lists in triangle order and fills
//!    pixels with a depth test, so the result does not depend on the thread count.
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
//! unless it lies within about 1e-12 pixels of an edge.

use glam::DVec3;
use rayon::prelude::*;

use crate::camera::View;
use crate::render::scene::{Scene, SceneFace};

/// A point that cannot be projected directly (not beyond the near plane).
const HIDDEN: [f64; 2] = [f64::NAN, f64::NAN];

/// A face the view does not draw.
const CULLED: [f64; 3] = [f64::NAN, f64::NAN, f64::NAN];

/// Where a raster puts the scene: see the [module documentation](self).
pub(super) trait Projection: Sync {
    /// The pixel coordinates of world point `p`, or NaN coordinates when the point is not
    /// beyond the near plane (then its triangles go through [`Projection::clip`]).
    fn point(&self, p: DVec3) -> [f64; 2];

    /// The key plane `[a, b, c]` (key = a·u + b·v + c at pixel coordinates (u, v), larger
    /// nearer) of `face`, or `None` when this view does not draw the face.
    fn plane(&self, face: &SceneFace) -> Option<[f64; 3]>;

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

    fn plane(&self, face: &SceneFace) -> Option<[f64; 3]> {
        let eye = self.view.eye();
        let toward = face.faces_toward(eye);
        let away = face.normal.dot(eye) - face.offset < 0.0;
        if (self.front && !toward) || (!self.front && !away) {
            return None;
        }
        // The plane n·p = offset in camera coordinates is n_c·c = d_c. The ray through
        // pixel (u, v) is c = t·((u − cx)/fx, −(v − cy)/fy, −1) at depth t, so
        // 1/t = n_c·r / d_c: affine in (u, v).
        let k = &self.view.intrinsics;
        let n = self.view.direction_to_camera(face.normal);
        let d = face.offset - face.normal.dot(eye);
        let a = n.x / (k.fx * d);
        let b = -n.y / (k.fy * d);
        let c = -(n.x * k.cx / k.fx) / d + (n.y * k.cy / k.fy) / d - n.z / d;
        Some([a, b, c])
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
    /// `face`; the sink keeps it if it is nearer than what it holds.
    fn plot(&mut self, i: usize, key: f32, face: u32);
}

/// A z-buffer with face ids.
pub(super) struct Ids<'a> {
    /// Keys, nearer larger.
    pub key: &'a mut [f32],
    /// Face of each pixel.
    pub face: &'a mut [u32],
}

impl Sink for Ids<'_> {
    #[inline(always)]
    fn plot(&mut self, i: usize, key: f32, face: u32) {
        if key > self.key[i] {
            self.key[i] = key;
            self.face[i] = face;
        }
    }
}

/// A z-buffer alone (shadow maps).
pub(super) struct Keys<'a>(pub &'a mut [f32]);

impl Sink for Keys<'_> {
    #[inline(always)]
    fn plot(&mut self, i: usize, key: f32, _face: u32) {
        if key > self.0[i] {
            self.0[i] = key;
        }
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

/// The pixel-centre index range `[lo, hi]` (inclusive, clamped to `0..n`) of the interval
/// `[min, max]`, or `None` if it holds no pixel centre (also for NaN).
#[inline(always)]
fn centres(min: f64, max: f64, n: usize) -> Option<(usize, usize)> {
    let lo = (min - 0.5).ceil().max(0.0);
    let hi = (max - 0.5).floor().min(n as f64 - 1.0);
    if lo <= hi {
        Some((lo as usize, hi as usize))
    } else {
        None
    }
}

/// The pixel-centre box of triangle `v`: `(x0, x1, y0, y1)` inclusive, or `None` when it
/// holds no pixel centre of a `width × height` raster.
#[inline(always)]
fn pixel_box(
    v: &[[f64; 2]; 3],
    width: usize,
    height: usize,
) -> Option<(usize, usize, usize, usize)> {
    let (x0, x1) = centres(
        v[0][0].min(v[1][0]).min(v[2][0]),
        v[0][0].max(v[1][0]).max(v[2][0]),
        width,
    )?;
    let (y0, y1) = centres(
        v[0][1].min(v[1][1]).min(v[2][1]),
        v[0][1].max(v[1][1]).max(v[2][1]),
        height,
    )?;
    Some((x0, x1, y0, y1))
}

/// The edge function `[a, b, c]` of the directed edge `p → q`: `a·x + b·y + c` is zero on
/// the edge's line and positive to its left as seen in pixel coordinates (v down) —
/// computed from the lexicographically smaller end and negated if needed, so `edge(q, p)`
/// is exactly `−edge(p, q)`.
#[inline(always)]
fn edge(p: [f64; 2], q: [f64; 2]) -> [f64; 3] {
    let flip = q[0] < p[0] || (q[0] == p[0] && q[1] < p[1]);
    let (s, e) = if flip { (q, p) } else { (p, q) };
    let a = s[1] - e[1];
    let b = e[0] - s[0];
    let c = -(a * s[0] + b * s[1]);
    if flip { [-a, -b, -c] } else { [a, b, c] }
}

/// Fills triangle `v` (pixel coordinates) of `face` with key plane `plane` into the rows
/// of `band` (see the [module documentation](self) for the sampling rule). Degenerate
/// triangles (no area) and non-finite ones draw nothing.
#[inline]
pub(super) fn fill<S: Sink>(band: &mut Band<S>, v: [[f64; 2]; 3], plane: [f64; 3], face: u32) {
    let height = band.y0 + band.rows;
    let Some((x0, x1, y0, y1)) = pixel_box(&v, band.width, height) else {
        return;
    };
    let (y0, y1) = (y0.max(band.y0), y1);
    if y0 > y1 {
        return;
    }
    let mut e = [edge(v[0], v[1]), edge(v[1], v[2]), edge(v[2], v[0])];
    // Orientation: the inside is where every edge function has the sign it has at the
    // opposite corner.
    let s = e[0][0] * v[2][0] + (e[0][1] * v[2][1] + e[0][2]);
    if s < 0.0 {
        for k in &mut e {
            *k = k.map(|x| -x);
        }
    } else if s.is_nan() || s == 0.0 {
        return;
    }
    // Top-left rule: a centre exactly on an edge (value ±0) counts for a left edge
    // (value grows with x) or a top edge (constant in x, grows with y). For the others the
    // value must be positive, i.e. at least the smallest positive double.
    let lo = e.map(|[a, b, _]| {
        if a > 0.0 || (a == 0.0 && b > 0.0) {
            0.0
        } else {
            f64::from_bits(1)
        }
    });
    let inv = e.map(|[a, ..]| 1.0 / a);
    let (xf0, xf1) = (x0 as f64, x1 as f64);
    for y in y0..=y1 {
        let py = y as f64 + 0.5;
        let r = [
            e[0][1] * py + e[0][2],
            e[1][1] * py + e[1][2],
            e[2][1] * py + e[2][2],
        ];
        // The row's span from the three half-planes, widened by a pixel against rounding;
        // every pixel in it is still tested exactly.
        let (mut xl, mut xr) = (xf0, xf1);
        for k in 0..3 {
            let a = e[k][0];
            if a > 0.0 {
                xl = xl.max((-r[k] * inv[k] - 0.5).floor());
            } else if a < 0.0 {
                xr = xr.min((-r[k] * inv[k] - 0.5).ceil());
            } else if r[k] < lo[k] {
                xr = -1.0;
            }
        }
        if xl.partial_cmp(&xr).is_none_or(|o| o.is_gt()) {
            continue;
        }
        let (xs, xe) = (xl as usize, xr as usize);
        let row = (y - band.y0) * band.width;
        let krow = plane[1] * py + plane[2];
        for x in xs..=xe {
            let px = x as f64 + 0.5;
            if e[0][0] * px + r[0] >= lo[0]
                && e[1][0] * px + r[1] >= lo[1]
                && e[2][0] * px + r[2] >= lo[2]
            {
                let key = (plane[0] * px + krow) as f32;
                band.sink.plot(row + x, key, face);
            }
        }
    }
}

/// One chunk of triangles, binned by band.
struct Binned {
    /// First triangle of the chunk.
    base: usize,
    /// Per band: entries, either a triangle (offset from `base`) or, with [`EXTRA`] set,
    /// an index into `extra`.
    bins: Vec<Vec<u32>>,
    /// Pieces of triangles clipped at the near plane: corners and face.
    extra: Vec<([[f64; 2]; 3], u32)>,
}

/// Marks a bin entry as a clipped piece.
const EXTRA: u32 = 1 << 31;

/// Draws `scene` as `proj` sees it into a `width × height` raster: `sink(band)` gives
/// the sink for each band of rows (`y0`, row count). Returns the key plane of every face
/// (NaN for faces the view does not draw).
///
/// Preconditions: the sinks cover disjoint bands as the band layout passed to `sink`
/// describes. Postcondition: every pixel whose centre is inside a drawn triangle was
/// offered to its band's sink, triangles in scene order.
pub(super) fn draw<P, S, F>(
    scene: &Scene,
    proj: &P,
    width: usize,
    height: usize,
    sinks: F,
) -> Vec<[f64; 3]>
where
    P: Projection,
    S: Sink + Send,
    F: FnOnce(usize) -> Vec<Band<S>>,
{
    let planes: Vec<[f64; 3]> = scene
        .faces
        .par_iter()
        .with_min_len(4096)
        .map(|f| proj.plane(f).unwrap_or(CULLED))
        .collect();
    if width == 0 || height == 0 {
        return planes;
    }
    let screen: Vec<[f64; 2]> = scene
        .points
        .par_iter()
        .with_min_len(4096)
        .map(|&p| proj.point(p))
        .collect();
    let rows = band_rows(height);
    let nbands = height.div_ceil(rows);
    let threads = rayon::current_num_threads().max(1);
    let chunk = (scene.triangles.len() / (threads * 8)).clamp(2048, 1 << 16);
    let binned: Vec<Binned> = scene
        .triangles
        .par_chunks(chunk)
        .enumerate()
        .map(|(ci, tris)| {
            let base = ci * chunk;
            let mut out = Binned {
                base,
                bins: vec![Vec::new(); nbands],
                extra: Vec::new(),
            };
            let mut poly = Vec::new();
            for (k, tri) in tris.iter().enumerate() {
                let f = scene.triangle_faces[base + k];
                if planes[f as usize][0].is_nan() {
                    continue;
                }
                let v = tri.map(|i| screen[i as usize]);
                if v[0][0].is_nan() || v[1][0].is_nan() || v[2][0].is_nan() {
                    proj.clip(scene, *tri, &screen, &mut poly);
                    for j in 1..poly.len().saturating_sub(1) {
                        let piece = [poly[0], poly[j], poly[j + 1]];
                        if let Some((.., y0, y1)) = pixel_box(&piece, width, height) {
                            let id = EXTRA | out.extra.len() as u32;
                            out.extra.push((piece, f));
                            for b in y0 / rows..=y1 / rows {
                                out.bins[b].push(id);
                            }
                        }
                    }
                    continue;
                }
                if let Some((.., y0, y1)) = pixel_box(&v, width, height) {
                    for b in y0 / rows..=y1 / rows {
                        out.bins[b].push(k as u32);
                    }
                }
            }
            out
        })
        .collect();
    let bands = sinks(rows);
    bands.into_par_iter().enumerate().for_each(|(b, mut band)| {
        for chunk in &binned {
            for &entry in &chunk.bins[b] {
                if entry & EXTRA != 0 {
                    let (v, f) = chunk.extra[(entry & !EXTRA) as usize];
                    fill(&mut band, v, planes[f as usize], f);
                } else {
                    let t = chunk.base + entry as usize;
                    let f = scene.triangle_faces[t];
                    let v = scene.triangles[t].map(|i| screen[i as usize]);
                    fill(&mut band, v, planes[f as usize], f);
                }
            }
        }
    });
    planes
}

/// Splits a row-major buffer of `width`-pixel rows into bands of `rows` rows.
pub(super) fn split_rows<T>(buf: &mut [T], width: usize, rows: usize) -> Vec<(usize, &mut [T])> {
    buf.chunks_mut((width * rows).max(1))
        .enumerate()
        .map(|(b, c)| (b * rows, c))
        .collect()
}
