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
//!   is kept with the scene ([`ShadowCache`]): it depends on the scene and the light, not
//!   on the camera, so it is made by the first picture of a revision and shared by all
//!   the others. A picture that shows only a small part of the world (its texels would be
//!   more than [`REFIT`] times those of a map fitted to the light-space footprint of the
//!   visible pixels) gets a map fitted to it instead, made for it alone;
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

use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

use glam::{DMat3, DVec3};
use rayon::prelude::*;

use crate::camera::View;
use crate::model::{Camera, Intrinsics, Light};
use crate::render::image::RgbImage;
use crate::render::scene::Scene;

use super::fill::{self, Perspective, Scratch};
use super::sun::{FACE_DARK, FACE_LIT, Sight, SunMap};
use super::{Frame, NO_FACE, rasterize_with};
use crate::render::buffers;

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
    /// ([`ShadowCache`]: [`KEPT_SUN_SIDE`] texels over the whole scene for a sun,
    /// [`KEPT_CUBE_SIDE`] for a point light), except that a sun whose kept map would be
    /// coarser than [`REFIT`] times a fitted one gets a fitted map of ¾ of the picture's
    /// longer side (between 256 and 4096 texels).
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

/// Texels on the longer side of a sun's kept shadow map (which covers the whole scene).
pub const KEPT_SUN_SIDE: usize = 1024;

/// Texels on the side of each of the six kept shadow maps of a point light.
pub const KEPT_CUBE_SIDE: usize = 1024;

/// A sun's kept shadow map serves a picture as long as its texels are at most this many
/// times the size of those of a map fitted to what the picture shows.
pub const REFIT: f64 = 2.0;

/// The shadow maps of a scene's own lights, made on first use and kept with the scene:
/// they depend on the scene and the light, not on the camera, so every picture of one
/// revision shares them. A sun's kept map covers the whole scene; a point light's is a
/// cube around it.
///
/// Precondition: the scene does not change after its first shaded picture (a scene is
/// one revision of the world); a caller that edits a scene in place calls
/// [`ShadowCache::clear`]. A clone of a scene starts with no maps.
#[derive(Default)]
pub struct ShadowCache {
    /// Per light (index into [`Scene::lights`]), its map once made.
    kept: Mutex<Vec<(usize, Arc<OnceLock<Kept>>)>>,
}

/// A kept map: `None` when the light has nothing to shadow.
#[derive(Clone)]
enum Kept {
    Sun(Option<Arc<SunMap>>),
    Cube(Option<Arc<CubeMap>>),
}

impl ShadowCache {
    /// The map kept for light `light`, made by `make` if it is not there yet. Two pictures
    /// asking at once share one making.
    fn get(&self, light: usize, make: impl FnOnce() -> Kept) -> Kept {
        let cell = {
            let mut kept = self.kept.lock().unwrap_or_else(PoisonError::into_inner);
            match kept.iter().find(|(l, _)| *l == light) {
                Some((_, cell)) => Arc::clone(cell),
                None => {
                    let cell = Arc::new(OnceLock::new());
                    kept.push((light, Arc::clone(&cell)));
                    cell
                }
            }
        };
        cell.get_or_init(make).clone()
    }

    /// How many maps are kept.
    pub fn len(&self) -> usize {
        let kept = self.kept.lock().unwrap_or_else(PoisonError::into_inner);
        kept.iter().filter(|(_, cell)| cell.get().is_some()).count()
    }

    /// Whether no map is kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Forgets every kept map.
    pub fn clear(&mut self) {
        self.kept
            .get_mut()
            .unwrap_or_else(PoisonError::into_inner)
            .clear();
    }
}

impl Clone for ShadowCache {
    /// An empty cache: maps are made again for the copy.
    fn clone(&self) -> ShadowCache {
        ShadowCache::default()
    }
}

impl std::fmt::Debug for ShadowCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShadowCache")
            .field("maps", &self.len())
            .finish()
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
                let make = || Kept::Sun(SunMap::whole(scene, direction).map(Arc::new));
                if let Some(Kept::Sun(Some(m))) = kept.map(|l| scene.shadows.get(l, make)) {
                    *map = Some(Sight::new(m, rays));
                }
            }
            Lamp::Point { position, map, .. } => {
                let position = *position;
                let make = || {
                    CubeMap::new(scene, position, cube_side, &mut Scratch::default()).map(Arc::new)
                };
                *map = match kept.map(|l| scene.shadows.get(l, || Kept::Cube(make()))) {
                    Some(Kept::Cube(m)) => m,
                    Some(Kept::Sun(_)) => None,
                    None => make(),
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

/// Pixel rays of a camera in world coordinates.
pub(super) struct Rays {
    /// The lens centre.
    pub(super) eye: DVec3,
    /// The camera's i, j, k in world coordinates.
    frame: DMat3,
    /// Ray direction (scaled to unit depth) at pixel (0, 0).
    pub(super) d0: DVec3,
    /// Its change per pixel to the right.
    pub(super) du: DVec3,
    /// Its change per pixel down.
    pub(super) dv: DVec3,
}

impl Rays {
    fn new(view: &View) -> Rays {
        // Rows of the world-to-camera rotation are i, j, k.
        let r = DMat3::from_cols(
            view.direction_to_camera(DVec3::X),
            view.direction_to_camera(DVec3::Y),
            view.direction_to_camera(DVec3::Z),
        );
        let frame = r.transpose();
        let (i, j, k) = (frame.x_axis, frame.y_axis, frame.z_axis);
        let kk = &view.intrinsics;
        Rays {
            eye: view.eye(),
            frame,
            d0: -i * (kk.cx / kk.fx) + j * (kk.cy / kk.fy) - k,
            du: i / kk.fx,
            dv: -j / kk.fy,
        }
    }

    /// The world point at `depth` on the ray through pixel coordinates (`u`, `v`).
    #[inline]
    fn point(&self, u: f64, v: f64, depth: f64) -> DVec3 {
        self.eye + (self.d0 + self.du * u + self.dv * v) * depth
    }
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

/// Every this many rows are enough to decide whether a kept sun map is too coarse.
const SAMPLED_ROWS: usize = 4;

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

/// Pixels [`Sight::mark`] takes at a time.
pub(super) const MARK_CHUNK: usize = 64;

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

/// The slope-scaled part of the shadow bias, in texels, for a surface lit at incidence
/// cosine `nl` (> 0): ¾ texel of the surface's depth slope (capped at 3, past which the
/// light is dim and a larger bias would let light leak under bodies standing on the
/// surface), plus half a texel.
#[inline]
pub(super) fn bias_texels(nl: f64) -> f64 {
    let slope = ((1.0 - nl * nl).max(0.0).sqrt() / nl).min(3.0);
    0.75 * slope + 0.5
}

/// A sun's light-space axes `s`, `t` across its rays ([`sun_axes`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Axes {
    pub(super) s: DVec3,
    pub(super) t: DVec3,
}

impl Axes {
    /// The axes of the sun in direction `toward` (unit).
    pub(super) fn new(toward: DVec3) -> Axes {
        let (s, t) = sun_axes(-toward);
        Axes { s, t }
    }
}

/// An empty light-space box `[x_min, x_max, y_min, y_max]`.
pub(super) const EMPTY: [f64; 4] = [
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::INFINITY,
    f64::NEG_INFINITY,
];

/// The smallest box holding boxes `a` and `b`.
pub(super) fn union(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0].min(b[0]),
        a[1].max(b[1]),
        a[2].min(b[2]),
        a[3].max(b[3]),
    ]
}

/// For each of `suns` (`None` for a lamp that needs no fitting), the light-space box of
/// the points a band of the picture shows: rows from `y0`, `width` pixels wide, with the
/// frame's `depth` and `face` values; only the rows whose index is a multiple of `step`. (Points on faces turned away from a sun are
/// included; they make the box no smaller, and leaving them out would cost a look at
/// every face.)
///
/// Along a row, the pixels of one face show points on one straight line (the face's plane
/// meets the plane through the eye and the row), so only the two ends of each run of a
/// face need to be reconstructed.
fn footprints(
    rays: &Rays,
    suns: &[Option<Axes>],
    y0: usize,
    width: usize,
    depth: &[f32],
    face: &[u32],
    step: usize,
) -> Vec<[f64; 4]> {
    let mut acc = vec![EMPTY; suns.len()];
    for (r, (depths, faces)) in depth
        .chunks(width)
        .zip(face.chunks(width))
        .enumerate()
        .filter(|(r, _)| (y0 + r).is_multiple_of(step))
    {
        let py = (y0 + r) as f64 + 0.5;
        let mut x = 0;
        while x < faces.len() {
            let f = faces[x];
            let mut end = x + 1;
            while end < faces.len() && faces[end] == f {
                end += 1;
            }
            if f != NO_FACE {
                for xs in [x, end - 1] {
                    let p = rays.point(xs as f64 + 0.5, py, depths[xs] as f64);
                    if !p.is_finite() {
                        continue;
                    }
                    for (b, sun) in acc.iter_mut().zip(suns) {
                        if let Some(a) = sun {
                            let (u, v) = (a.s.dot(p), a.t.dot(p));
                            *b = union(*b, [u, u, v, v]);
                        }
                    }
                }
            }
            x = end;
        }
    }
    acc
}

/// [`footprints`] of every row of `frame`, band by band: per band, per sun.
fn frame_footprints(rays: &Rays, suns: &[Option<Axes>], frame: &Frame) -> Vec<Vec<[f64; 4]>> {
    let w = frame.width as usize;
    let rows = 16;
    frame
        .depth
        .par_chunks(w * rows)
        .zip(frame.face.par_chunks(w * rows))
        .enumerate()
        .map(|(b, (depth, face))| footprints(rays, suns, b * rows, w, depth, face, 1))
        .collect()
}

/// The light-space axes (s, t) across a sun's rays travelling along unit `direction`.
pub(super) fn sun_axes(direction: DVec3) -> (DVec3, DVec3) {
    direction.any_orthonormal_pair()
}

/// Texels at the edge of a sun's map, around its footprint.
pub(super) const PAD: f64 = 2.0;

/// The texel side (meters) of a sun map `side` texels long over light-space box
/// `footprint`, in a scene whose bounds' diagonal is `diag`.
pub(super) fn fitted_texel(footprint: [f64; 4], side: usize, diag: f64) -> f64 {
    let extent = (footprint[1] - footprint[0])
        .max(footprint[3] - footprint[2])
        .max(diag * 1e-9)
        .max(1e-9);
    extent / (side.max(8) as f64 - 2.0 * PAD)
}

/// A point light's shadow cube: six 90° views, +x, −x, +y, −y, +z, −z.
struct CubeMap {
    position: DVec3,
    views: Vec<View>,
    side: usize,
    /// Keys (1/depth) of the nearest far-side surface per texel of each view; 0 where
    /// none.
    keys: Vec<Vec<f32>>,
    /// Constant bias, meters.
    eps: f64,
}

impl Drop for CubeMap {
    fn drop(&mut self) {
        self.keys.drain(..).for_each(buffers::give);
    }
}

impl CubeMap {
    /// The cube of `side`-texel maps around `position`. `None` for a scene without
    /// geometry or a light whose views cannot be made (a non-finite position).
    fn new(scene: &Scene, position: DVec3, side: usize, scratch: &mut Scratch) -> Option<CubeMap> {
        let bounds = scene.bounds?;
        let side = side.clamp(2, crate::model::camera::MAX_IMAGE_SIDE as usize);
        let k = Intrinsics::centered(side as u32, side as u32, side as f64 / 2.0).ok()?;
        let axes = [
            (DVec3::X, DVec3::Z),
            (DVec3::NEG_X, DVec3::Z),
            (DVec3::Y, DVec3::Z),
            (DVec3::NEG_Y, DVec3::Z),
            (DVec3::Z, DVec3::Y),
            (DVec3::NEG_Z, DVec3::Y),
        ];
        let mut views = Vec::with_capacity(6);
        for (axis, up) in axes {
            let cam = Camera::look_at(position, position + axis, up, k).ok()?;
            views.push(View::new(&cam, 1e-4));
        }
        let keys = views
            .iter()
            .map(|view| {
                // Cleared band by band while drawing.
                let mut key = buffers::take::<f32>(side * side);
                let proj = Perspective {
                    view: *view,
                    front: false,
                };
                fill::draw_keys(scene, &proj, side, side, &mut key, scratch);
                key
            })
            .collect();
        let reach = (bounds.max - bounds.min).length()
            + (position - (bounds.min + bounds.max) / 2.0).length();
        Some(CubeMap {
            position,
            views,
            side,
            keys,
            eps: reach * 2e-6,
        })
    }

    /// Whether the light sees `p`, on a surface lit at incidence cosine `nl`.
    #[inline]
    fn lit(&self, p: DVec3, nl: f64) -> bool {
        let d = p - self.position;
        let a = d.abs();
        let f = if a.x >= a.y && a.x >= a.z {
            usize::from(d.x < 0.0)
        } else if a.y >= a.z {
            2 + usize::from(d.y < 0.0)
        } else {
            4 + usize::from(d.z < 0.0)
        };
        let view = &self.views[f];
        let c = view.to_camera(p);
        let depth = -c.z;
        if depth.is_nan() || depth <= 0.0 {
            return true;
        }
        let uv = view.project(c);
        let last = self.side as f64 - 1.0;
        let x = uv.x.floor().max(0.0).min(last) as usize;
        let y = uv.y.floor().max(0.0).min(last) as usize;
        let k = self.keys[f][y * self.side + x] as f64;
        if k.is_nan() || k <= 0.0 {
            return true;
        }
        let texel = depth * 2.0 / self.side as f64;
        1.0 / k >= depth - texel * bias_texels(nl) - self.eps
    }
}

/// Entries of the linear-to-sRGB table.
const ENCODE_STEPS: usize = 1 << 14;

/// 8-bit sRGB to linear light (the IEC 61966-2-1 curve), a table computed once.
fn srgb_to_linear() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| {
            let c = i as f64 / 255.0;
            let l = if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            };
            l as f32
        })
    })
}

/// Linear light in [0, 1] (sampled at [`ENCODE_STEPS`] points) to 8-bit sRGB, a table
/// computed once.
fn linear_to_srgb() -> &'static [u8] {
    static TABLE: OnceLock<Vec<u8>> = OnceLock::new();
    TABLE.get_or_init(|| {
        (0..ENCODE_STEPS)
            .map(|i| {
                let l = i as f64 / (ENCODE_STEPS - 1) as f64;
                let c = if l <= 0.003_130_8 {
                    12.92 * l
                } else {
                    1.055 * l.powf(1.0 / 2.4) - 0.055
                };
                (c * 255.0).round().clamp(0.0, 255.0) as u8
            })
            .collect()
    })
}

/// One linear value to 8-bit sRGB through `table` ([`linear_to_srgb`]); values above 1
/// clamp to 255, below 0 (or NaN) to 0.
#[inline(always)]
fn encode_one(table: &[u8], l: f32) -> u8 {
    let i = (l * (ENCODE_STEPS - 1) as f32 + 0.5).clamp(0.0, (ENCODE_STEPS - 1) as f32);
    table[i as usize]
}

#[cfg(test)]
pub(super) mod testing {
    //! Shading internals the module tests check against.

    use super::{Kept, PoisonError, Scene};

    /// [`super::SunMap::classify`]'s answer: the sun sees the whole face.
    pub const FACE_LIT: u8 = super::FACE_LIT;
    /// [`super::SunMap::classify`]'s answer: the sun sees none of the face.
    pub const FACE_DARK: u8 = super::FACE_DARK;

    /// The per-face classes of the sun map kept for light `light` of `scene` (every face
    /// worked out), once a picture has made the map.
    pub fn face_classes(scene: &Scene, light: usize) -> Option<Vec<u8>> {
        let kept = scene
            .shadows
            .kept
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let (_, cell) = kept.iter().find(|(l, _)| *l == light)?;
        match cell.get()? {
            Kept::Sun(Some(m)) => Some(
                (0..m.faces.len() as u32)
                    .map(|f| m.face(scene, f))
                    .collect(),
            ),
            _ => None,
        }
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
