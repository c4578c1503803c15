//! Shaded pictures: each visible face in its body's colour, lit by the world's lights,
//! with shadows.
//!
//! # Light
//!
//! A pixel showing a face with unit outward normal `n` at world point `p` gets
//!
//! ```text
//! colour = base · (ambient + Σ_lights visible · max(n·l, 0) · intensity · falloff)
//! ```
//!
//! where for a sun `l = −direction` and `falloff = 1`, and for a point light
//! `l = (position − p)/|position − p|` and `falloff = 1/|position − p|²` (intensity is full
//! strength at 1 m). `visible` is 0 when the light cannot see `p` (Baumgart's SHADOW: what
//! a light cannot see is in shadow) and 1 otherwise. A face turned away from a light
//! (`n·l ≤ 0`) gets nothing from it, which alone makes a body shadow its own far side.
//!
//! The arithmetic is in linear light: the body's 8-bit sRGB colour is decoded to linear
//! values, multiplied by the light, and encoded back to sRGB (clamped at full scale), so
//! two lights of intensity ½ look like one of intensity 1 and shadows darken as they do in
//! a photograph. With the default ambient of 0.25 a face in shadow shows about 54 % of its
//! colour's sRGB value.
//!
//! A world with no lights is lit by a default sun of intensity 0.8 shining from behind
//! the camera, above and to its left (from the direction `−0.4·i + 0.6·j + k` in the
//! camera's frame), so a picture is never black.
//!
//! # Shadows
//!
//! Each light has a shadow map:
//!
//! * a sun, an orthographic depth map looking along its direction. The map of each of the
//!   world's suns covers the whole scene, [`KEPT_SUN_SIDE`] texels on its longer side, and
//!   is kept with the scene ([`ShadowCache`](super::ShadowCache)): it depends on the
//!   scene and the light, not on the camera, so it is made by the first picture of a
//!   revision and shared by all the others. A picture that shows only a small part of
//!   the world (its texels would be more than [`REFIT`] times those of a map fitted to
//!   the light-space footprint of the visible pixels) gets a map fitted to it instead,
//!   made for it alone;
//! * a point light, a cube of six 90° perspective maps around it, kept likewise.
//!
//! The maps hold the *far* sides of occluders (the faces turned away from the light) —
//! second-depth shadow mapping (Wang and Molnar, 1994). A lit face is then compared with
//! the back of its own body, never with itself, so there is no shadow acne on lit faces;
//! a small slope-scaled bias (¾ texel times the tangent of the light's incidence, capped
//! at 3, plus half a texel) covers the rest. Bodies are closed, so every occluder has a far
//! side. One tap per pixel: shadow edges are as sharp as the map's texels.
//!
//! A sun map stores 16-bit keys (a unit is 1/65535 of the scene's diagonal, rounded away
//! from the sun) in 8 × 8 tiles, so that the texels a row of the picture looks up share
//! cache lines, with a pyramid of per-block maxima and minima beside it. A run of pixels
//! of one face along a row sees the map along a segment, so one look at the pyramid
//! usually settles the whole run (all lit or all in shadow), and only runs that cross a
//! shadow's edge are tested pixel by pixel. Before that, a kept map has settled each
//! face as a whole where it can (made once with the map, `SunMap::classify`): a face
//! the sun sees entirely, or not at all, needs no test at any of its pixels. The pixels
//! are lit band by band as soon as the z-buffer's band is drawn, while it is in the cache.
//!
//! This module lights the pixels. The maps are made in `sun` (a sun's) and `cube` (a point
//! light's); their kept sizes, their fitting to a picture and the bias of a lookup are in
//! `shadow`; the sRGB tables in `srgb`; a camera's pixel rays in `rays`.

use std::cell::RefCell;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use crate::camera::View;
use crate::model::Light;
use crate::render::buffers;
use crate::render::image::RgbImage;
use crate::render::scene::Scene;

use super::cube::CubeMap;
use super::fill::Scratch;
use super::rays::Rays;
use super::shadow::{Axes, EMPTY, SAMPLED_ROWS, fitted_texel, footprints, frame_footprints, union};
pub use super::shadow::{KEPT_CUBE_SIDE, KEPT_SUN_SIDE, REFIT};
use super::srgb::{encode_one, linear_to_srgb, srgb_to_linear};
use super::sun::{FACE_DARK, FACE_LIT, MARK_CHUNK, Sight, SunMap};
use super::{Frame, NO_FACE, rasterize_with};

/// How [`shaded`] draws.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shading {
    /// Colour where no surface is seen (sRGB).
    pub background: [u8; 3],
    /// Light every face gets regardless of the lights (linear, 0.25 by default).
    pub ambient: f64,
    /// Whether lights cast shadows (true by default).
    pub shadows: bool,
    /// Texels on the longer side of a sun's shadow map and on the side of each of a
    /// point light's six maps, made fresh for the picture (a sun's fitted to what the
    /// picture shows). 0 (the default) uses the maps kept with the scene
    /// ([`ShadowCache`](super::ShadowCache): [`KEPT_SUN_SIDE`] texels over the whole
    /// scene for a sun, [`KEPT_CUBE_SIDE`] for a point light), except that a sun whose
    /// kept map would be coarser than [`REFIT`] times a fitted one gets a fitted map of ¾
    /// of the picture's longer side (between 256 and 4096 texels).
    pub shadow_map_size: u32,
}

impl Default for Shading {
    fn default() -> Shading {
        Shading {
            background: [40, 44, 52],
            ambient: 0.25,
            shadows: true,
            shadow_map_size: 0,
        }
    }
}

/// The shaded picture of `scene` from `view`: see the [module documentation](self).
///
/// Preconditions: `shading.ambient` is finite and non-negative (a negative or NaN value
/// darkens or blackens the picture; it never panics). Postcondition: the image has the
/// view's size; pixels showing no surface are `shading.background`; the others are the
/// face's body colour lit as described.
pub fn shaded(scene: &Scene, view: &View, shading: &Shading) -> RgbImage {
    shaded_with(scene, view, shading, RUN)
}

/// [`shaded`], testing runs of at least `run` pixels of one face for shadow as a whole
/// (`usize::MAX`: every pixel on its own, also of the faces a kept sun map has classified
/// as a whole).
pub(super) fn shaded_with(scene: &Scene, view: &View, shading: &Shading, run: usize) -> RgbImage {
    let (width, height) = view.size();
    let (w, h) = (width as usize, height as usize);
    if w == 0 || h == 0 {
        return RgbImage::filled(width, height, shading.background);
    }
    let rays = Rays::new(view);
    let side = w.max(h) as f64;
    let (fit_side, cube_side) = if shading.shadow_map_size > 0 {
        let s = shading.shadow_map_size as usize;
        (s, s)
    } else {
        ((0.75 * side).clamp(256.0, 4096.0) as usize, KEPT_CUBE_SIDE)
    };
    let keep = shading.shadows && shading.shadow_map_size == 0;
    let mut scratch = Scratch::default();
    let mut lamps = lamps(scene, &rays);
    if shading.shadows {
        attach_maps(scene, &rays, &mut lamps, keep, cube_side);
    }
    let lamps: Vec<Lamp> = lamps.into_iter().map(|(_, l)| l).collect();
    // The suns' light-space axes, for fitting shadow maps to what the picture shows.
    let suns: Vec<Option<Axes>> = lamps
        .iter()
        .map(|l| match l {
            Lamp::Sun { toward, .. } if shading.shadows => Some(Axes::new(*toward)),
            _ => None,
        })
        .collect();
    let fit = suns.iter().any(Option::is_some);
    // Every pixel is written below, by the bands or by the second lighting.
    let mut data = buffers::take::<u8>(w * h * 3);
    // With every map at hand, each band of rows is lit as soon as it is drawn, while it is
    // in the cache; otherwise the frame is drawn first, to see what the maps must cover.
    let ready = !lamps.iter().any(|l| l.needs_fitting(shading.shadows));
    let lit = Lighter::new(scene, &rays, &lamps, shading, run);
    let (frame, boxes) = rasterize_with(scene, view, &mut scratch, &mut data, 3, |band| {
        if ready {
            lit.rows(band.y0, w, band.depth, band.face, band.out);
        }
        if fit {
            // With maps at hand the footprint only decides whether to refit: every few
            // rows suffice.
            let step = if ready { SAMPLED_ROWS } else { 1 };
            footprints(&rays, &suns, band.y0, w, band.depth, band.face, step)
        } else {
            Vec::new()
        }
    });
    let diag = scene.bounds.map_or(0.0, |b| (b.max - b.min).length());
    let sum = |boxes: &[Vec<[f64; 4]>], k: usize| {
        boxes
            .iter()
            .fold(EMPTY, |a, b| b.get(k).map_or(a, |b| union(a, *b)))
    };
    let nonempty = |b: [f64; 4]| b[0] <= b[1] && b[2] <= b[3];
    let mut refit = !ready;
    let mut exact: Option<Vec<Vec<[f64; 4]>>> = None;
    let mut lamps = lamps;
    for (k, lamp) in lamps.iter_mut().enumerate() {
        let Lamp::Sun { toward, map, .. } = lamp else {
            continue;
        };
        if !shading.shadows || !nonempty(sum(&boxes, k)) {
            continue;
        }
        let coarse = map
            .as_ref()
            .is_none_or(|m| m.map.texel > REFIT * fitted_texel(sum(&boxes, k), fit_side, diag));
        if !coarse {
            continue;
        }
        // A fitted map covers every pixel: the footprint of every row.
        let footprint = if ready {
            let all = exact.get_or_insert_with(|| frame_footprints(&rays, &suns, &frame));
            sum(all, k)
        } else {
            sum(&boxes, k)
        };
        if let Some(fitted) = SunMap::new(scene, -*toward, footprint, fit_side, &mut scratch) {
            *map = Some(Sight::new(Arc::new(fitted), &rays));
            refit = true;
        }
    }
    if refit {
        Lighter::new(scene, &rays, &lamps, shading, run).frame(&frame, &mut data);
    }
    frame.recycle();
    RgbImage {
        width,
        height,
        data,
    }
}

/// Gives `lamps` (with their lights' indices) their shadow maps where they need no
/// fitting to the picture: every point light (kept with the scene when `keep`, else
/// made fresh with `cube_side` texels), and, when `keep`, every sun of the world's own
/// lights (its map over the whole scene, kept). Suns left without a map are fitted to
/// the picture later.
fn attach_maps(
    scene: &Scene,
    rays: &Rays,
    lamps: &mut [(Option<usize>, Lamp)],
    keep: bool,
    cube_side: usize,
) {
    for (light, lamp) in lamps {
        let kept = if keep { *light } else { None };
        match lamp {
            Lamp::Sun { toward, map, .. } => {
                let direction = -*toward;
                let make = || SunMap::whole(scene, direction);
                if let Some(m) = kept.and_then(|l| scene.shadows.get(l, make)) {
                    *map = Some(Sight::new(m, rays));
                }
            }
            Lamp::Point { position, map, .. } => {
                let position = *position;
                let make = || CubeMap::new(scene, position, cube_side, &mut Scratch::default());
                *map = match kept {
                    Some(l) => scene.shadows.get(l, make),
                    None => make().map(Arc::new),
                };
            }
        }
    }
}

/// The lamps of `scene` seen through `rays` (the default sun for a scene without
/// lights), each with the index of its light in [`Scene::lights`], without maps yet.
/// Lights of no intensity are left out.
fn lamps(scene: &Scene, rays: &Rays) -> Vec<(Option<usize>, Lamp)> {
    let lights: Vec<(Option<usize>, Light)> = if scene.lights.is_empty() {
        vec![(None, default_light(rays))]
    } else {
        scene
            .lights
            .iter()
            .enumerate()
            .map(|(i, (_, l))| (Some(i), *l))
            .collect()
    };
    lights
        .into_iter()
        .filter(|(_, l)| l.intensity() > 0.0)
        .map(|(i, l)| {
            let lamp = match l {
                Light::Sun {
                    direction,
                    intensity,
                } => Lamp::Sun {
                    toward: -direction,
                    intensity,
                    map: None,
                },
                Light::Point {
                    position,
                    intensity,
                } => Lamp::Point {
                    position,
                    intensity,
                    map: None,
                },
            };
            (i, lamp)
        })
        .collect()
}

/// The default sun: intensity 0.8, shining from behind the camera, above and to its left.
fn default_light(rays: &Rays) -> Light {
    let (i, j, k) = (rays.frame.x_axis, rays.frame.y_axis, rays.frame.z_axis);
    let toward = (-0.4 * i + 0.6 * j + k).normalize();
    Light::Sun {
        direction: -toward,
        intensity: 0.8,
    }
}

/// A light ready to shade pixels.
enum Lamp {
    /// A sun: unit direction toward it.
    Sun {
        toward: DVec3,
        intensity: f64,
        map: Option<Sight>,
    },
    /// A point light.
    Point {
        position: DVec3,
        intensity: f64,
        map: Option<Arc<CubeMap>>,
    },
}

impl Lamp {
    /// Whether this lamp still needs a shadow map fitted to the picture: a sun without a
    /// map when there are shadows.
    fn needs_fitting(&self, shadows: bool) -> bool {
        shadows && matches!(self, Lamp::Sun { map: None, .. })
    }

    /// What a face with unit normal `n` needs of this lamp at every pixel: for a sun, the
    /// light it gives where it is seen (0 on a face turned away) and the shadow bias
    /// (meters); nothing for a point light.
    #[inline]
    fn prepare(&self, n: DVec3) -> (f64, f64) {
        match self {
            Lamp::Sun {
                toward,
                intensity,
                map,
            } => {
                let nl = n.dot(*toward);
                if nl <= 0.0 {
                    return (0.0, 0.0);
                }
                let bias = map.as_ref().map_or(0.0, |m| m.map.bias(nl));
                (nl * intensity, bias)
            }
            Lamp::Point { .. } => (0.0, 0.0),
        }
    }

    /// Whether this lamp, a sun, sees the surface shown at `at` = (u, v, depth), allowing
    /// `bias` meters; true for a point light (see [`Lamp::light`]).
    #[inline]
    fn sees(&self, at: (f64, f64, f64), bias: f64) -> bool {
        match self {
            Lamp::Sun { map, .. } => map.as_ref().is_none_or(|m| m.lit_at(at, bias)),
            Lamp::Point { .. } => true,
        }
    }

    /// The light this lamp gives the surface with unit normal `n` seen at depth `d` at
    /// pixel coordinates (`u`, `v`) (`at` = (u, v, d)); `prep` is [`Lamp::prepare`] of `n`.
    #[inline]
    fn light(&self, rays: &Rays, at: (f64, f64, f64), n: DVec3, (gain, bias): (f64, f64)) -> f64 {
        match self {
            Lamp::Sun { .. } => {
                if gain > 0.0 && self.sees(at, bias) {
                    gain
                } else {
                    0.0
                }
            }
            Lamp::Point {
                position,
                intensity,
                map,
            } => {
                let p = rays.point(at.0, at.1, at.2);
                let d = *position - p;
                let d2 = d.length_squared();
                if d2.is_nan() || d2 <= 0.0 {
                    return 0.0;
                }
                let nl = n.dot(d) / d2.sqrt();
                if nl <= 0.0 || map.as_ref().is_some_and(|m| !m.lit(p, nl)) {
                    0.0
                } else {
                    nl * intensity / d2
                }
            }
        }
    }
}

/// Rows of a frame whose faces [`Lighter::fetch`] reads at a time.
const FETCH_ROWS: usize = 4;

/// Scenes with more faces than this (about 2 MB of them) have them fetched ahead.
const FETCH_FACES: usize = 1 << 15;

/// At most this many suns (and no point light) are lit through a per-face palette.
const PALETTE_SUNS: usize = 4;

/// Lights the pixels of a frame: see the [module documentation](self).
struct Lighter<'a> {
    scene: &'a Scene,
    rays: &'a Rays,
    lamps: &'a [Lamp],
    /// Each scene body's colour in linear light.
    bases: Vec<[f32; 3]>,
    ambient: f64,
    background: [u8; 3],
    encode: &'static [u8],
    /// Every lamp is a sun, at most [`PALETTE_SUNS`] of them: a face's colour for each
    /// set of suns that see a pixel is computed once per run of the face's pixels.
    palette: bool,
    /// Runs of a face's pixels at least this long are tested for shadow as a whole.
    run: usize,
    /// Faces the kept sun maps have classified as a whole ([`SunMap::classify`]) are not
    /// tested pixel by pixel.
    classified: bool,
    /// Unique to this lighter (never 0), so that palettes made for another are not used.
    id: u64,
}

thread_local! {
    /// Each thread's palettes, reused by every lighter that runs on it.
    static PALETTES: RefCell<Palettes> = RefCell::new(Palettes::new());
}

/// The next [`Lighter::id`].
static LIGHTERS: AtomicU64 = AtomicU64::new(1);

impl<'a> Lighter<'a> {
    fn new(
        scene: &'a Scene,
        rays: &'a Rays,
        lamps: &'a [Lamp],
        shading: &Shading,
        run: usize,
    ) -> Self {
        Lighter {
            scene,
            rays,
            lamps,
            bases: scene
                .bodies
                .iter()
                .map(|b| b.color.0.map(|c| srgb_to_linear()[c as usize]))
                .collect(),
            ambient: shading.ambient,
            background: shading.background,
            encode: linear_to_srgb(),
            palette: lamps.len() <= PALETTE_SUNS
                && lamps.iter().all(|l| matches!(l, Lamp::Sun { .. })),
            run,
            classified: run != usize::MAX,
            id: LIGHTERS.fetch_add(1, Ordering::Relaxed),
        }
    }

    /// Lights every pixel of `frame` into `data` (RGB, the frame's size), in parallel
    /// bands of rows.
    fn frame(&self, frame: &Frame, data: &mut [u8]) {
        let w = frame.width as usize;
        let rows = 16;
        data.par_chunks_mut(w * 3 * rows)
            .zip(frame.face.par_chunks(w * rows))
            .zip(frame.depth.par_chunks(w * rows))
            .enumerate()
            .for_each(|(b, ((out, faces), depths))| self.rows(b * rows, w, depths, faces, out));
    }

    /// Lights rows from `y0`, `width` pixels wide, of depths `depth` and faces `face`,
    /// into `out` (RGB).
    fn rows(&self, y0: usize, width: usize, depth: &[f32], face: &[u32], out: &mut [u8]) {
        if self.palette {
            // Each thread keeps its palettes from band to band and picture to picture.
            PALETTES.with(|kept| match kept.try_borrow_mut() {
                Ok(mut p) => self.rows_with(y0, width, depth, face, out, Some(&mut p)),
                Err(_) => self.rows_with(y0, width, depth, face, out, Some(&mut Palettes::new())),
            });
        } else {
            self.rows_with(y0, width, depth, face, out, None);
        }
    }

    /// [`Lighter::rows`], with `palettes` when every lamp is a sun ([`Lighter::palette`]).
    fn rows_with(
        &self,
        y0: usize,
        width: usize,
        depth: &[f32],
        face: &[u32],
        out: &mut [u8],
        mut palettes: Option<&mut Palettes>,
    ) {
        for (r, ((depths, faces), out)) in depth
            .chunks(width)
            .zip(face.chunks(width))
            .zip(out.chunks_mut(width * 3))
            .enumerate()
        {
            if r % FETCH_ROWS == 0 && self.scene.faces.len() > FETCH_FACES {
                self.fetch(&face[r * width..face.len().min((r + FETCH_ROWS) * width)]);
            }
            let py = (y0 + r) as f64 + 0.5;
            match &mut palettes {
                Some(p) => self.row_of_suns(py, depths, faces, out, p),
                None => self.row(py, depths, faces, out),
            }
        }
    }

    /// Reads the scene data of every face in `faces` (a few rows of the frame) once,
    /// ahead of lighting them. In a large world the faces a row shows are scattered
    /// through the scene's arrays; reading them in a loop where no read waits for another
    /// lets the processor fetch many at once, where lighting would wait for each in turn.
    fn fetch(&self, faces: &[u32]) {
        let mut last = NO_FACE;
        let mut sum = 0u32;
        for &f in faces {
            if f != last && f != NO_FACE {
                last = f;
                if let Some(face) = self.scene.faces.get(f as usize) {
                    let base = self.bases.get(face.body as usize).map_or(0.0, |b| b[0]);
                    sum = sum
                        .wrapping_add(face.normal.x.to_bits() as u32)
                        .wrapping_add(base.to_bits());
                }
            }
        }
        std::hint::black_box(sum);
    }

    /// Lights one row, at pixel-coordinate height `py`, lamp by lamp.
    fn row(&self, py: f64, depths: &[f32], faces: &[u32], out: &mut [u8]) {
        let mut last = NO_FACE;
        let mut prep = vec![(0.0, 0.0); self.lamps.len()];
        let (mut n, mut base) = (DVec3::ZERO, [0.0f32; 3]);
        for (x, ((&f, &depth), o)) in faces
            .iter()
            .zip(depths)
            .zip(out.chunks_exact_mut(3))
            .enumerate()
        {
            if f == NO_FACE {
                o.copy_from_slice(&self.background);
                continue;
            }
            if f != last {
                last = f;
                let face = &self.scene.faces[f as usize];
                n = face.normal;
                base = self.bases[face.body as usize];
                for (p, lamp) in prep.iter_mut().zip(self.lamps) {
                    *p = lamp.prepare(n);
                }
            }
            let at = (x as f64 + 0.5, py, depth as f64);
            let mut light = self.ambient;
            for (lamp, &prep) in self.lamps.iter().zip(&prep) {
                light += lamp.light(self.rays, at, n, prep);
            }
            let l = light as f32;
            for k in 0..3 {
                o[k] = encode_one(self.encode, base[k] * l);
            }
        }
    }

    /// [`Lighter::row`] when every lamp is a sun: per pixel only the shadow tests, whose
    /// outcome picks the face's colour from its palette (kept in `palettes` for the rows
    /// that follow).
    fn row_of_suns(
        &self,
        py: f64,
        depths: &[f32],
        faces: &[u32],
        out: &mut [u8],
        palettes: &mut Palettes,
    ) {
        let mut masks = [0u8; MARK_CHUNK];
        let mut x = 0;
        while x < faces.len() {
            let f = faces[x];
            let end = run_end(faces, x);
            let run = &mut out[x * 3..end * 3];
            if f == NO_FACE {
                fill_rgb(run, self.background);
                x = end;
                continue;
            }
            let slot = palettes.slot(self, f);
            let prep = palettes.prep[slot];
            let (lit, dark) = palettes.sure[slot];
            // Suns known to see the whole run, and those to be asked pixel by pixel.
            let (mut seen, mut ask) = (0u8, 0u8);
            let first = (x as f64 + 0.5, py, depths[x] as f64);
            let last = ((end - 1) as f64 + 0.5, py, depths[end - 1] as f64);
            for (k, (lamp, &(gain, bias))) in self.lamps.iter().zip(&prep).enumerate() {
                if gain <= 0.0 || dark & (1 << k) != 0 {
                    continue;
                }
                if lit & (1 << k) != 0 {
                    seen |= 1 << k;
                    continue;
                }
                let whole = match lamp {
                    Lamp::Sun { map: Some(m), .. } if end - x >= self.run => {
                        m.run(first, last, bias)
                    }
                    Lamp::Sun { map: Some(_), .. } => None,
                    _ => Some(true),
                };
                match whole {
                    Some(true) => seen |= 1 << k,
                    Some(false) => {}
                    None => ask |= 1 << k,
                }
            }
            if ask == 0 {
                fill_rgb(run, palettes.colour(self, slot, seen));
                x = end;
                continue;
            }
            for (c, run) in run.chunks_mut(3 * MARK_CHUNK).enumerate() {
                let from = x + c * MARK_CHUNK;
                let n = run.len() / 3;
                let masks = &mut masks[..n];
                masks.fill(seen);
                for (k, (lamp, &(_, bias))) in self.lamps.iter().zip(&prep).enumerate() {
                    if let Lamp::Sun { map: Some(m), .. } = lamp
                        && ask & (1 << k) != 0
                    {
                        m.mark(py, from, &depths[from..from + n], bias, masks, 1 << k);
                    }
                }
                for (o, &mask) in run.chunks_exact_mut(3).zip(masks.iter()) {
                    o.copy_from_slice(&palettes.colour(self, slot, mask));
                }
            }
            x = end;
        }
    }
}

/// The end of the run of equal values in `faces` that starts at `x`: the first index past
/// `x` holding another value, or `faces.len()`. Precondition: `x < faces.len()`.
#[inline]
fn run_end(faces: &[u32], x: usize) -> usize {
    const LANES: usize = 8;
    let f = faces[x];
    let mut i = x + 1;
    // Eight at a time, which the compiler turns into one vector comparison.
    while let Some(chunk) = faces.get(i..i + LANES) {
        let mut other = 0u32;
        for (k, &g) in chunk.iter().enumerate() {
            other |= u32::from(g != f) << k;
        }
        if other != 0 {
            return i + other.trailing_zeros() as usize;
        }
        i += LANES;
    }
    while i < faces.len() && faces[i] == f {
        i += 1;
    }
    i
}

/// Fills `run` (RGB pixels) with `colour`: eight pixels at a time as three 8-byte words.
#[inline]
fn fill_rgb(run: &mut [u8], colour: [u8; 3]) {
    let word = |o: usize| u64::from_ne_bytes(std::array::from_fn(|i| colour[(o + i) % 3]));
    let words = [word(0), word(8), word(16)];
    let mut chunks = run.chunks_exact_mut(24);
    for c in &mut chunks {
        for (part, w) in c.chunks_exact_mut(8).zip(words) {
            part.copy_from_slice(&w.to_ne_bytes());
        }
    }
    for o in chunks.into_remainder().chunks_exact_mut(3) {
        o.copy_from_slice(&colour);
    }
}

/// Runs of at least this many pixels of one face are first tested for shadow as a whole
/// ([`Sight::run`]).
const RUN: usize = 6;

/// Faces' palettes: direct-mapped by face index, each kept by one thread ([`PALETTES`])
/// for the rows it lights, tagged with the [`Lighter`] they were made for.
struct Palettes {
    /// The [`Lighter::id`] each slot was made for (0: none).
    owner: Vec<u64>,
    /// The face in each slot.
    face: Vec<u32>,
    /// Each sun's [`Lamp::prepare`] for the slot's face.
    prep: Vec<[(f64, f64); PALETTE_SUNS]>,
    /// The suns that see the whole of the slot's face (bit k for sun k), and those that see
    /// none of it, as their kept maps say ([`SunMap::classify`]).
    sure: Vec<(u8, u8)>,
    /// The face's base colour (linear).
    base: Vec<[f32; 3]>,
    /// The face's colour for each set of suns that see it (bit k for sun k), made when
    /// first asked for.
    colour: Vec<[[u8; 3]; 1 << PALETTE_SUNS]>,
    /// Which of the slot's colours are made (bit m for set m).
    made: Vec<u16>,
}

impl Palettes {
    /// Slots kept.
    const SLOTS: usize = 1024;

    fn new() -> Palettes {
        Palettes {
            owner: vec![0; Self::SLOTS],
            face: vec![NO_FACE; Self::SLOTS],
            prep: vec![[(0.0, 0.0); PALETTE_SUNS]; Self::SLOTS],
            sure: vec![(0, 0); Self::SLOTS],
            base: vec![[0.0; 3]; Self::SLOTS],
            colour: vec![[[0; 3]; 1 << PALETTE_SUNS]; Self::SLOTS],
            made: vec![0; Self::SLOTS],
        }
    }

    /// The slot holding face `f`, taken for it (with no colour made yet) if it is not
    /// there.
    #[inline]
    fn slot(&mut self, lighter: &Lighter<'_>, f: u32) -> usize {
        let slot = f as usize % Self::SLOTS;
        if self.face[slot] != f || self.owner[slot] != lighter.id {
            self.face[slot] = f;
            self.owner[slot] = lighter.id;
            let face = &lighter.scene.faces[f as usize];
            self.base[slot] = lighter.bases[face.body as usize];
            for (p, lamp) in self.prep[slot].iter_mut().zip(lighter.lamps) {
                *p = lamp.prepare(face.normal);
            }
            let (mut lit, mut dark) = (0u8, 0u8);
            if lighter.classified {
                for (k, lamp) in lighter.lamps.iter().enumerate() {
                    if let Lamp::Sun { map: Some(m), .. } = lamp {
                        match m.map.face(lighter.scene, f) {
                            FACE_LIT => lit |= 1 << k,
                            FACE_DARK => dark |= 1 << k,
                            _ => {}
                        }
                    }
                }
            }
            self.sure[slot] = (lit, dark);
            self.made[slot] = 0;
        }
        slot
    }

    /// The colour of the face in `slot` where the suns of set `mask` see it.
    #[inline]
    fn colour(&mut self, lighter: &Lighter<'_>, slot: usize, mask: u8) -> [u8; 3] {
        let m = mask as usize;
        if self.made[slot] & (1 << m) == 0 {
            self.made[slot] |= 1 << m;
            let prep = &self.prep[slot];
            let light = lighter.ambient
                + (0..lighter.lamps.len())
                    .filter(|k| m & (1 << k) != 0)
                    .map(|k| prep[k].0)
                    .sum::<f64>();
            let l = light as f32;
            self.colour[slot][m] = self.base[slot].map(|c| encode_one(lighter.encode, c * l));
        }
        self.colour[slot][m]
    }
}

#[cfg(test)]
pub(super) mod testing {
    //! Shading internals the module tests check against.

    use super::{Scene, SunMap};

    /// [`super::SunMap::classify`]'s answer: the sun sees the whole face.
    pub const FACE_LIT: u8 = super::FACE_LIT;
    /// [`super::SunMap::classify`]'s answer: the sun sees none of the face.
    pub const FACE_DARK: u8 = super::FACE_DARK;

    /// The per-face classes of the sun map kept for light `light` of `scene` (every face
    /// worked out), once a picture has made the map.
    pub fn face_classes(scene: &Scene, light: usize) -> Option<Vec<u8>> {
        let m = scene.shadows.made::<SunMap>(light)?;
        Some(
            (0..m.faces.len() as u32)
                .map(|f| m.face(scene, f))
                .collect(),
        )
    }

    /// [`super::run_end`].
    pub fn run_end(faces: &[u32], x: usize) -> usize {
        super::run_end(faces, x)
    }

    /// [`super::fill_rgb`].
    pub fn fill_rgb(run: &mut [u8], colour: [u8; 3]) {
        super::fill_rgb(run, colour)
    }

    /// [`super::slab_extent`].
    pub fn slab_extent(ring: &[[f64; 2]], lo: f64, hi: f64) -> Option<(f64, f64)> {
        super::super::sun::slab_extent(ring, lo, hi)
    }

    /// The 8-bit sRGB value of `color` (sRGB) times linear `light`, as [`super::shaded`]
    /// computes it.
    pub fn lit(color: [u8; 3], light: f64) -> [u8; 3] {
        color.map(|c| {
            super::encode_one(
                super::linear_to_srgb(),
                super::srgb_to_linear()[c as usize] * light as f32,
            )
        })
    }
}
