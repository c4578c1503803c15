//! Sun shadow maps: an orthographic depth map of the far sides of occluders along a
//! sun's rays, stored in tiles with a min/max pyramid, the per-face classes worked out
//! from it, and its use by one picture ([`Sight`]). See the
//! [shading module](super::shade) for how pictures use them.

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use crate::render::buffers;
use crate::render::scene::{Scene, SceneFace};

use super::fill::{self, Projection, Scratch};
use super::rays::Rays;
use super::shadow::{Axes, EMPTY, KEPT_SUN_SIDE, PAD, bias_texels, fitted_texel, sun_axes, union};

/// An orthographic view along a sun's rays: pixel (u, v) is light-space
/// ((u/scale + x0)·s + (v/scale + y0)·t); the key is `zc − w·p` (nearer the sun larger,
/// and positive for every point of the scene).
#[derive(Clone, Copy, Debug)]
pub(super) struct Ortho {
    s: DVec3,
    t: DVec3,
    w: DVec3,
    x0: f64,
    y0: f64,
    scale: f64,
    zc: f64,
}

impl Projection for Ortho {
    #[inline]
    fn point(&self, p: DVec3) -> [f64; 2] {
        [
            (self.s.dot(p) - self.x0) * self.scale,
            (self.t.dot(p) - self.y0) * self.scale,
        ]
    }

    /// Draws the faces turned away from the sun (the far sides of occluders), skipping
    /// those within 1e-6 of edge-on, which cover next to nothing.
    #[inline]
    fn draws(&self, f: &SceneFace) -> bool {
        f.normal.dot(self.w) > 1e-6
    }

    #[inline]
    fn plane(&self, f: &SceneFace) -> [f64; 3] {
        self.key_plane(f)
    }
}

impl Ortho {
    /// The key plane `[a, b, c]` of face `f`: key = a·u + b·v + c at texel coordinates
    /// (u, v). Precondition: the face is not edge-on to the sun (`f.normal · w ≠ 0`), else
    /// the values are infinite or NaN.
    #[inline]
    fn key_plane(&self, f: &SceneFace) -> [f64; 3] {
        let nw = f.normal.dot(self.w);
        let (ns, nt) = (f.normal.dot(self.s), f.normal.dot(self.t));
        // On the plane, w·p = (offset − ns·X − nt·Y)/nw with X = u/scale + x0, Y = v/scale + y0.
        [
            ns / (nw * self.scale),
            nt / (nw * self.scale),
            self.zc - (f.offset - ns * self.x0 - nt * self.y0) / nw,
        ]
    }
}

/// Texels on the side of a square tile of a sun map's storage.
pub(super) const TILE: usize = 8;

/// A sun's shadow map.
pub(super) struct SunMap {
    width: usize,
    height: usize,
    /// Keys of the nearest far-side surface per texel in units of `unit` meters, rounded
    /// down (so never nearer the sun than the surface); 0 where none. Stored in [`TILE`] ×
    /// [`TILE`] tiles, row-major within a tile and tiles row-major (see [`SunMap::at`]),
    /// so that the texels a picture's row looks up, which run along a line through the
    /// map in any direction, share cache lines.
    key: Vec<u16>,
    /// Meters per key unit.
    unit: f64,
    /// Maxima and minima of the keys over blocks of texels.
    pyramid: Pyramid,
    /// Tiles per row of tiles.
    tiles: usize,
    /// Texel side, meters.
    pub(super) texel: f64,
    /// Constant bias, meters (covers the f32 keys' rounding).
    eps: f64,
    /// Where the map looks from.
    view: Ortho,
    /// Per face of the scene, what the map says of the whole face ([`FACE_LIT`],
    /// [`FACE_DARK`] or [`FACE_ASK`]; see [`SunMap::classify`]), worked out when a
    /// picture first shows the face ([`FACE_UNKNOWN`] until then). Empty for a map
    /// fitted to one picture: then every face is asked about pixel by pixel.
    pub(super) faces: Vec<AtomicU8>,
}

/// [`SunMap::faces`]: the sun sees every point of the face.
pub(super) const FACE_LIT: u8 = 1;
/// [`SunMap::faces`]: the sun sees no point of the face.
pub(super) const FACE_DARK: u8 = 2;
/// [`SunMap::faces`]: the face's pixels must be asked about (or the face is turned away
/// from the sun, which then gives it nothing anyway).
pub(super) const FACE_ASK: u8 = 0;
/// [`SunMap::faces`]: not worked out yet.
pub(super) const FACE_UNKNOWN: u8 = 3;

/// Texels of a face's box past which [`SunMap::classify`] leaves it to the pixels (a kept
/// map has at most [`KEPT_SUN_SIDE`]² texels, so only a face seen edge-on by the sun
/// reaches this).
const CLASSIFY_TEXELS: usize = 1 << 21;

/// Corners of a face [`SunMap::classify`] keeps on the stack.
const SMALL_RING: usize = 16;

/// Texels by which [`SunMap::classify`] widens a face, to cover the rounding of the
/// points its pixels show.
const WIDEN: f64 = 0.5;

/// The least and greatest `u` of the polygon `ring` (a closed loop of (u, v) points) over
/// the slab `lo ≤ v ≤ hi`, or `None` when it does not reach into the slab. The extremes of
/// a polygon within a slab lie on its edges, so the edges clipped to the slab give them.
pub(super) fn slab_extent(ring: &[[f64; 2]], lo: f64, hi: f64) -> Option<(f64, f64)> {
    let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
    for (i, &[ua, va]) in ring.iter().enumerate() {
        let [ub, vb] = ring[(i + 1) % ring.len()];
        let (vmin, vmax) = (va.min(vb), va.max(vb));
        if vmax < lo || vmin > hi {
            continue;
        }
        if va == vb {
            (min, max) = (min.min(ua.min(ub)), max.max(ua.max(ub)));
            continue;
        }
        // The edge's u at heights lo and hi, clamped to the edge.
        let at = |y: f64| ua + (ub - ua) * ((y - va) / (vb - va)).clamp(0.0, 1.0);
        let (x0, x1) = (at(lo.max(vmin)), at(hi.min(vmax)));
        (min, max) = (min.min(x0.min(x1)), max.max(x0.max(x1)));
    }
    (min <= max).then_some((min, max))
}

impl SunMap {
    /// The map of the sun shining along unit `direction` over the whole scene,
    /// [`KEPT_SUN_SIDE`] texels on its longer side. `None` for a scene without geometry.
    pub(super) fn whole(scene: &Scene, direction: DVec3) -> Option<SunMap> {
        let axes = Axes::new(-direction);
        let footprint = scene
            .points
            .par_iter()
            .with_min_len(4096)
            .fold(
                || EMPTY,
                |b, p| {
                    let (u, v) = (axes.s.dot(*p), axes.t.dot(*p));
                    union(b, [u, u, v, v])
                },
            )
            .reduce(|| EMPTY, union);
        if !(footprint[0] <= footprint[1] && footprint[2] <= footprint[3]) {
            return None;
        }
        let mut map = SunMap::new(
            scene,
            direction,
            footprint,
            KEPT_SUN_SIDE,
            &mut Scratch::default(),
        )?;
        map.faces = (0..scene.faces.len())
            .map(|_| AtomicU8::new(FACE_UNKNOWN))
            .collect();
        Some(map)
    }

    /// The map of the sun shining along unit `direction` over the light-space box
    /// `footprint` of its receivers, `side` texels on its longer side. `None` for a scene
    /// without geometry.
    pub(super) fn new(
        scene: &Scene,
        direction: DVec3,
        footprint: [f64; 4],
        side: usize,
        scratch: &mut Scratch,
    ) -> Option<SunMap> {
        let bounds = scene.bounds?;
        let (s, t) = sun_axes(direction);
        let diag = (bounds.max - bounds.min).length();
        // Beyond the scene's far end from the sun, so that every key is positive and a
        // texel left at zero holds nothing.
        let zc = direction.dot((bounds.min + bounds.max) / 2.0) + 0.5 * diag + 1e-3 * diag + 1e-6;
        let side = side.max(8);
        let texel = fitted_texel(footprint, side, diag);
        let width = (((footprint[1] - footprint[0]) / texel).ceil() as usize + 2 * PAD as usize)
            .clamp(1, side);
        let height = (((footprint[3] - footprint[2]) / texel).ceil() as usize + 2 * PAD as usize)
            .clamp(1, side);
        let view = Ortho {
            s,
            t,
            w: direction,
            x0: footprint[0] - PAD * texel,
            y0: footprint[2] - PAD * texel,
            scale: 1.0 / texel,
            zc,
        };
        // Cleared band by band while drawing.
        let mut key = buffers::take::<f32>(width * height);
        fill::draw_keys(scene, &view, width, height, &mut key, scratch);
        // Every key is below zc + diag (the nearest point to the sun is at most a diagonal
        // from the far end) and above 1e-3·diag (zc's margin), so above 65 units: a
        // surface never rounds to 0.
        let unit = (zc - direction.dot((bounds.min + bounds.max) / 2.0) + 0.5 * diag) / 65535.0;
        let (tiles, tiled) = tile(&key, width, height, unit);
        buffers::give(key);
        let mut map = SunMap {
            width,
            height,
            key: tiled,
            unit,
            pyramid: Pyramid::default(),
            tiles,
            texel,
            eps: diag * 2e-6 + unit,
            view,
            faces: Vec::new(),
        };
        map.pyramid = Pyramid::new(&map);
        Some(map)
    }

    /// The shadow bias (meters) of a surface lit at incidence cosine `nl` (> 0): the
    /// slope-scaled part ([`bias_texels`]) in this map's texels, plus the constant part.
    /// Every test against the map, by pixel or by face, uses this one value.
    #[inline]
    pub(super) fn bias(&self, nl: f64) -> f64 {
        self.texel * bias_texels(nl) + self.eps
    }

    /// What this map says of `face` (of `scene`) as a whole, so that a picture need not
    /// test the face's pixels one by one: [`FACE_LIT`] when every pixel showing the face
    /// passes [`Sight::lit_at`] with the face's bias (`Lamp::prepare`), [`FACE_DARK`]
    /// when none does, else [`FACE_ASK`] (always for a face turned away from the sun or
    /// seen edge-on, and for one whose box covers more than [`CLASSIFY_TEXELS`] texels).
    ///
    /// A pixel showing the face shows a point of the face's plane, which lies in a texel
    /// the face reaches in light space when widened by [`WIDEN`] texels (the widening
    /// covers the rounding of the pixel's depth), or off the map, where it is lit. In texel T that point's key is
    /// at least the least key of the plane over T, and at most the greatest. So the face is
    /// lit if every texel of the box holds a key no nearer the sun than the plane's least
    /// key over it plus the bias, with `margin` to spare for the rounding of the pixel's
    /// key; and dark if every texel lies on the map and holds one nearer than the plane's
    /// greatest key plus the bias, again with the margin. A convex body's own far side lies
    /// behind each of its faces' planes, so only other bodies make a face [`FACE_ASK`].
    fn classify(&self, scene: &Scene, face: &SceneFace) -> u8 {
        let view = self.view;
        let toward = -view.w;
        let margin = 8.0 * self.unit;
        let nl = face.normal.dot(toward);
        let ring = &scene.rings[face.ring.start as usize..face.ring.end as usize];
        if nl.is_nan() || nl <= 1e-6 || ring.is_empty() {
            return FACE_ASK;
        }
        let bias = self.bias(nl);
        // The corners in texel coordinates; on the stack for all but large faces.
        let mut near = [[0.0; 2]; SMALL_RING];
        let mut far = Vec::new();
        let uv: &mut [[f64; 2]] = if ring.len() <= SMALL_RING {
            &mut near[..ring.len()]
        } else {
            far.resize(ring.len(), [0.0; 2]);
            &mut far
        };
        for (c, &i) in uv.iter_mut().zip(ring) {
            *c = view.point(scene.points[i as usize]);
        }
        let uv = &*uv;
        let b = uv.iter().fold(EMPTY, |b, &[u, v]| union(b, [u, u, v, v]));
        if !(b[0].is_finite() && b[1].is_finite() && b[2].is_finite() && b[3].is_finite()) {
            return FACE_ASK;
        }
        let (w, h) = (self.width as f64, self.height as f64);
        let on_map =
            b[0] - WIDEN >= 0.0 && b[2] - WIDEN >= 0.0 && b[1] + WIDEN < w && b[3] + WIDEN < h;
        let (v0, v1) = (
            (b[2] - WIDEN).floor().max(0.0),
            (b[3] + WIDEN).floor().min(h - 1.0),
        );
        let texels = (b[1] - b[0] + 2.0 * WIDEN + 1.0) * (v1 - v0 + 1.0);
        if texels > CLASSIFY_TEXELS as f64 {
            return FACE_ASK;
        }
        let [a, pb, c] = view.key_plane(face);
        let (lo, hi) = (a.min(0.0) + pb.min(0.0), a.max(0.0) + pb.max(0.0));
        let (mut lit, mut dark) = (true, on_map);
        let mut v = v0;
        while v <= v1 {
            // The face's points whose texel may be in row v lie in this slab.
            let Some((ua, ub)) = slab_extent(uv, v - WIDEN, v + 1.0 + WIDEN) else {
                v += 1.0;
                continue;
            };
            let (u0, u1) = (
                (ua - WIDEN).floor().max(0.0),
                (ub + WIDEN).floor().min(w - 1.0),
            );
            let row = c + pb * v;
            let mut u = u0;
            while u <= u1 {
                let plane = row + a * u;
                let key = self.units_at(u as usize, v as usize) as f64 * self.unit;
                lit &= key <= plane + lo + bias - margin;
                dark &= key > plane + hi + bias + margin;
                u += 1.0;
            }
            if !lit && !dark {
                return FACE_ASK;
            }
            v += 1.0;
        }
        if lit {
            FACE_LIT
        } else if dark {
            FACE_DARK
        } else {
            FACE_ASK
        }
    }

    /// What the map says of face `f` of `scene` as a whole ([`SunMap::classify`]),
    /// worked out on first asking. Precondition: `scene` is the scene the map was made
    /// for. Threads asking at once may both work it out; they get the same answer.
    #[inline]
    pub(super) fn face(&self, scene: &Scene, f: u32) -> u8 {
        let Some(known) = self.faces.get(f as usize) else {
            return FACE_ASK;
        };
        match known.load(Ordering::Relaxed) {
            FACE_UNKNOWN => {
                let class = scene
                    .faces
                    .get(f as usize)
                    .map_or(FACE_ASK, |face| self.classify(scene, face));
                known.store(class, Ordering::Relaxed);
                class
            }
            class => class,
        }
    }

    /// The key at texel (`u`, `v`) in key units. Precondition: inside the map.
    #[inline(always)]
    fn units_at(&self, u: usize, v: usize) -> u16 {
        let tile = (v / TILE) * self.tiles + u / TILE;
        self.key[tile * TILE * TILE + (v % TILE) * TILE + u % TILE]
    }

    /// The key at texel (`u`, `v`), meters. Precondition: inside the map.
    #[inline(always)]
    fn at(&self, u: usize, v: usize) -> f64 {
        self.units_at(u, v) as f64 * self.unit
    }
}

impl Drop for SunMap {
    fn drop(&mut self) {
        buffers::give(std::mem::take(&mut self.key));
    }
}

/// The maxima and minima of a sun map's keys (in key units) over square blocks of
/// 2, 4, 8, … texels on a side: level ℓ holds blocks of 2^(ℓ+1). Texels beyond the map's
/// edge count as 0 (nothing there).
#[derive(Default)]
struct Pyramid {
    levels: Vec<Level>,
}

/// One level of a [`Pyramid`]: per block, row-major, the largest and smallest key.
struct Level {
    width: usize,
    height: usize,
    max: Vec<u16>,
    min: Vec<u16>,
}

impl Pyramid {
    /// The pyramid of `map`, up to a single block.
    pub(super) fn new(map: &SunMap) -> Pyramid {
        let mut levels: Vec<Level> = Vec::new();
        let (mut w, mut h) = (map.width, map.height);
        while w > 1 || h > 1 {
            let (nw, nh) = (w.div_ceil(2), h.div_ceil(2));
            let below = levels.last();
            let read = |u: usize, v: usize| -> (u16, u16) {
                if u >= w || v >= h {
                    return (0, 0);
                }
                match below {
                    Some(l) => (l.max[v * w + u], l.min[v * w + u]),
                    None => {
                        let k = map.units_at(u, v);
                        (k, k)
                    }
                }
            };
            let mut max = vec![0u16; nw * nh];
            let mut min = vec![0u16; nw * nh];
            max.par_chunks_mut(nw)
                .zip(min.par_chunks_mut(nw))
                .enumerate()
                .for_each(|(y, (max, min))| {
                    for x in 0..nw {
                        let four = [
                            read(2 * x, 2 * y),
                            read(2 * x + 1, 2 * y),
                            read(2 * x, 2 * y + 1),
                            read(2 * x + 1, 2 * y + 1),
                        ];
                        max[x] = four.iter().map(|k| k.0).max().unwrap_or(0);
                        min[x] = four.iter().map(|k| k.1).min().unwrap_or(0);
                    }
                });
            levels.push(Level {
                width: nw,
                height: nh,
                max,
                min,
            });
            (w, h) = (nw, nh);
        }
        Pyramid { levels }
    }

    /// The largest and the smallest key (key units) over a set of texels covering the box
    /// `[u0, u1, v0, v1]` (inclusive texel indices inside `map`): at most 2 × 2 blocks
    /// of the finest level that covers it so, or the box's own texels when they are at
    /// most 2 × 2.
    #[inline]
    fn range(&self, map: &SunMap, [u0, u1, v0, v1]: [usize; 4]) -> (u16, u16) {
        let (mut hi, mut lo) = (0u16, u16::MAX);
        if u1 - u0 <= 1 && v1 - v0 <= 1 {
            for v in v0..=v1 {
                for u in u0..=u1 {
                    let k = map.units_at(u, v);
                    (hi, lo) = (hi.max(k), lo.min(k));
                }
            }
            return (hi, lo);
        }
        let mut shift = 1;
        while ((u1 >> shift) - (u0 >> shift) > 1 || (v1 >> shift) - (v0 >> shift) > 1)
            && shift < self.levels.len()
        {
            shift += 1;
        }
        let Some(level) = self.levels.get(shift - 1) else {
            return (u16::MAX, 0);
        };
        for v in (v0 >> shift)..=(v1 >> shift).min(level.height - 1) {
            for u in (u0 >> shift)..=(u1 >> shift).min(level.width - 1) {
                let i = v * level.width + u;
                (hi, lo) = (hi.max(level.max[i]), lo.min(level.min[i]));
            }
        }
        (hi, lo)
    }
}

/// A row-major `width × height` raster of keys (meters) in units of `unit`, rounded down
/// and saturating at 65535, laid out in [`TILE`] × [`TILE`] tiles (the edge tiles padded
/// with values never read): tiles per row, and the tiled values.
fn tile(key: &[f32], width: usize, height: usize, unit: f64) -> (usize, Vec<u16>) {
    let tiles = width.div_ceil(TILE);
    let per_unit = (1.0 / unit) as f32;
    // The padding of the edge tiles is never read.
    let mut out = buffers::take::<u16>(tiles * height.div_ceil(TILE) * TILE * TILE);
    out.par_chunks_mut(tiles * TILE * TILE)
        .enumerate()
        .for_each(|(ty, strip)| {
            for r in 0..TILE {
                let v = ty * TILE + r;
                if v >= height {
                    break;
                }
                let row = &key[v * width..(v + 1) * width];
                for (tx, chunk) in row.chunks(TILE).enumerate() {
                    let at = tx * TILE * TILE + r * TILE;
                    for (o, &k) in strip[at..at + chunk.len()].iter_mut().zip(chunk) {
                        // Float-to-integer casts floor positive values and saturate.
                        *o = (k * per_unit) as u16;
                    }
                }
            }
        });
    (tiles, out)
}

/// Pixels [`Sight::mark`] takes at a time.
pub(super) const MARK_CHUNK: usize = 64;

/// A sun map as one picture uses it.
pub(super) struct Sight {
    pub(super) map: Arc<SunMap>,
    /// For the picture's pixels: texel u, texel v and key of the point at depth d on the
    /// ray through pixel coordinates (x, y), each `c + d·(d0 + x·dx + y·dy)` with
    /// `[c, d0, dx, dy]` from here (see [`Sight::lit_at`]).
    camera: [[f64; 4]; 3],
}

impl Sight {
    /// `map` for the picture whose pixel rays are `rays`.
    pub(super) fn new(map: Arc<SunMap>, rays: &Rays) -> Sight {
        let o = map.view;
        let rows = |a: DVec3, c: f64, k: f64| {
            [
                c,
                k * a.dot(rays.d0),
                k * a.dot(rays.du),
                k * a.dot(rays.dv),
            ]
        };
        let camera = [
            rows(o.s, (o.s.dot(rays.eye) - o.x0) * o.scale, o.scale),
            rows(o.t, (o.t.dot(rays.eye) - o.y0) * o.scale, o.scale),
            rows(o.w, o.zc - o.w.dot(rays.eye), -1.0),
        ];
        Sight { map, camera }
    }

    /// Texel coordinates (u, v) and key (meters) of the point the picture shows at
    /// `at` = (x, y, depth).
    #[inline(always)]
    fn project(&self, (x, y, d): (f64, f64, f64)) -> [f64; 3] {
        self.camera
            .map(|[c, d0, dx, dy]| c + d * (d0 + x * dx + y * dy))
    }

    /// Whether the sun sees every pixel of a run of one face's pixels along a row, from
    /// `first` to `last` (each (x, y, depth)), allowing `bias` meters: `Some(true)` if it
    /// sees them all, `Some(false)` if it sees none, `None` when they must be asked one by
    /// one ([`Sight::lit_at`], whose answers these agree with).
    ///
    /// The run's points lie on a segment of the face, which the map sees as a segment
    /// from texel `first` to texel `last`, with keys between those of the ends. So if no
    /// key of the map in a box around that segment ([`Pyramid`]) is nearer the sun than
    /// the nearest point (with the bias), every pixel is lit; if every texel in it holds a
    /// key nearer than the farthest point, none is.
    #[inline]
    pub(super) fn run(
        &self,
        first: (f64, f64, f64),
        last: (f64, f64, f64),
        bias: f64,
    ) -> Option<bool> {
        let [ua, va, ka] = self.project(first);
        let [ub, vb, kb] = self.project(last);
        let m = &*self.map;
        let (w, h) = (m.width as f64, m.height as f64);
        let (u0, u1) = (ua.min(ub), ua.max(ub));
        let (v0, v1) = (va.min(vb), va.max(vb));
        // Also false for NaN: then ask pixel by pixel.
        if !(u0 >= 0.0 && v0 >= 0.0 && u1 < w && v1 < h && (ka + kb).is_finite()) {
            return None;
        }
        let (hi, lo) = m
            .pyramid
            .range(m, [u0 as usize, u1 as usize, v0 as usize, v1 as usize]);
        if hi as f64 * m.unit <= ka.min(kb) + bias {
            Some(true)
        } else if lo as f64 * m.unit > ka.max(kb) + bias {
            Some(false)
        } else {
            None
        }
    }

    /// For each pixel of a run along the row at height `py`, from column `x0`, with
    /// depths `depths` (at most [`MARK_CHUNK`]): sets `bit` in its entry of `masks` when
    /// the sun sees it, allowing `bias` meters — what [`Sight::lit_at`] answers, pixel for
    /// pixel. First every texel and threshold is computed, then the map is read, so that
    /// the reads do not wait for one another.
    #[inline]
    pub(super) fn mark(
        &self,
        py: f64,
        x0: usize,
        depths: &[f32],
        bias: f64,
        masks: &mut [u8],
        bit: u8,
    ) {
        let m = &*self.map;
        let (w, h) = (m.width as f64, m.height as f64);
        let mut at = [0u32; MARK_CHUNK];
        let mut most = [0.0f64; MARK_CHUNK];
        for (i, &d) in depths.iter().enumerate().take(MARK_CHUNK) {
            let [u, v, key] = self.project(((x0 + i) as f64 + 0.5, py, d as f64));
            let inside = u >= 0.0 && v >= 0.0 && u < w && v < h;
            // Saturating casts; a point off the map reads texel 0 against an infinite
            // threshold: lit.
            let (u, v) = (u as u32, v as u32);
            let texel = ((v / TILE as u32) * m.tiles as u32 + u / TILE as u32)
                * (TILE * TILE) as u32
                + (v % TILE as u32) * TILE as u32
                + u % TILE as u32;
            at[i] = if inside { texel } else { 0 };
            most[i] = if inside { key + bias } else { f64::INFINITY };
        }
        for ((mask, &at), &most) in masks.iter_mut().zip(&at).zip(&most) {
            if m.key[at as usize] as f64 * m.unit <= most {
                *mask |= bit;
            }
        }
    }

    /// Whether the sun sees the point the picture shows at `at` = (x, y, depth), allowing
    /// `bias` meters toward the sun.
    #[inline]
    pub(super) fn lit_at(&self, at: (f64, f64, f64), bias: f64) -> bool {
        let [u, v, key] = self.project(at);
        let m = &*self.map;
        if !(u >= 0.0 && v >= 0.0 && u < m.width as f64 && v < m.height as f64) {
            return true;
        }
        m.at(u as usize, v as usize) <= key + bias
    }
}
