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
//! Each light gets a shadow map, made fresh for each picture:
//!
//! * a sun, an orthographic depth map looking along its direction, fitted to the part of
//!   the world the picture shows (the light-space footprint of the visible lit pixels), so
//!   its texels are as fine as the picture needs; [`Shading::shadow_map_size`] texels on
//!   its longer side;
//! * a point light, a cube of six 90° perspective maps around it.
//!
//! The maps hold the *far* sides of occluders (the faces turned away from the light) —
//! second-depth shadow mapping (Wang and Molnar, 1994). A lit face is then compared with
//! the back of its own body, never with itself, so there is no shadow acne on lit faces;
//! a small slope-scaled bias (¾ texel times the tangent of the light's incidence, capped
//! at 3, plus half a texel) covers the rest. Bodies are closed, so every occluder has a far
//! side. One tap per pixel: shadow edges are as sharp as the map's texels.

use std::sync::OnceLock;

use glam::{DMat3, DVec3};
use rayon::prelude::*;

use crate::camera::View;
use crate::model::{Camera, Intrinsics, Light};
use crate::render::image::RgbImage;
use crate::render::scene::{Scene, SceneFace};

use super::fill::{self, Band, Keys, Perspective, Projection, Scratch};
use super::{NO_FACE, rasterize_with};

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
    /// point light's six maps; 0 (the default) chooses from the image size: ¾ of its
    /// longer side (between 256 and 4096) for suns, whose maps are fitted to what the
    /// picture shows, and half of it (between 128 and 2048) for point lights.
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
    let (width, height) = view.size();
    let (w, h) = (width as usize, height as usize);
    if w == 0 || h == 0 {
        return RgbImage::filled(width, height, shading.background);
    }
    let rays = Rays::new(view);
    let lights: Vec<Light> = if scene.lights.is_empty() {
        vec![default_light(&rays)]
    } else {
        scene.lights.iter().map(|(_, l)| *l).collect()
    };
    let mut lamps: Vec<Lamp> = lights
        .iter()
        .filter(|l| l.intensity() > 0.0)
        .map(|l| match *l {
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
        })
        .collect();
    // The suns' light-space axes, for fitting their shadow maps to what the picture shows.
    let suns: Vec<Option<Axes>> = lamps
        .iter()
        .map(|l| match l {
            Lamp::Sun { toward, .. } if shading.shadows => Some(Axes::new(*toward)),
            _ => None,
        })
        .collect();
    let fit = suns.iter().any(Option::is_some);
    let mut scratch = Scratch::default();
    let (frame, boxes) = rasterize_with(scene, view, &mut scratch, |y0, depth, face| {
        if fit {
            footprints(&rays, &suns, y0, w, depth, face)
        } else {
            Vec::new()
        }
    });
    if shading.shadows {
        let side = w.max(h) as f64;
        let (sun_side, cube_side) = if shading.shadow_map_size > 0 {
            let s = shading.shadow_map_size as usize;
            (s, s)
        } else {
            (
                (0.75 * side).clamp(256.0, 4096.0) as usize,
                (0.5 * side).clamp(128.0, 2048.0) as usize,
            )
        };
        for (k, lamp) in lamps.iter_mut().enumerate() {
            match lamp {
                Lamp::Sun { toward, map, .. } => {
                    let footprint = boxes
                        .iter()
                        .fold(EMPTY, |a, b| b.get(k).map_or(a, |b| union(a, *b)));
                    if footprint[0] <= footprint[1] && footprint[2] <= footprint[3] {
                        *map =
                            SunMap::new(scene, -*toward, footprint, sun_side, &rays, &mut scratch);
                    }
                }
                Lamp::Point { position, map, .. } => {
                    *map = CubeMap::new(scene, *position, cube_side, &mut scratch);
                }
            }
        }
    }
    let bases: Vec<[f32; 3]> = scene
        .bodies
        .iter()
        .map(|b| b.color.0.map(|c| srgb_to_linear()[c as usize]))
        .collect();
    let encode = linear_to_srgb();
    let ambient = shading.ambient;
    let background = shading.background;
    // Zeros, so fresh pages are first touched by the parallel rows.
    let mut data = vec![0u8; w * h * 3];
    data.par_chunks_mut(w * 3)
        .zip(frame.face.par_chunks(w))
        .zip(frame.depth.par_chunks(w))
        .enumerate()
        .for_each(|(y, ((out, faces), depths))| {
            let py = y as f64 + 0.5;
            let mut last = NO_FACE;
            let mut prep = vec![(0.0, 0.0); lamps.len()];
            let (mut n, mut base) = (DVec3::ZERO, [0.0f32; 3]);
            for (x, (&f, &depth)) in faces.iter().zip(depths).enumerate() {
                let o = &mut out[x * 3..x * 3 + 3];
                if f == NO_FACE {
                    o.copy_from_slice(&background);
                    continue;
                }
                if f != last {
                    last = f;
                    let face = &scene.faces[f as usize];
                    n = face.normal;
                    base = bases[face.body as usize];
                    for (p, lamp) in prep.iter_mut().zip(&lamps) {
                        *p = lamp.prepare(n);
                    }
                }
                let at = (x as f64 + 0.5, py, depth as f64);
                let mut light = ambient;
                for (lamp, &prep) in lamps.iter().zip(&prep) {
                    light += lamp.light(&rays, at, n, prep);
                }
                let l = light as f32;
                for k in 0..3 {
                    o[k] = encode_one(encode, base[k] * l);
                }
            }
        });
    RgbImage {
        width,
        height,
        data,
    }
}

/// Pixel rays of a camera in world coordinates.
struct Rays {
    /// The lens centre.
    eye: DVec3,
    /// The camera's i, j, k in world coordinates.
    frame: DMat3,
    /// Ray direction (scaled to unit depth) at pixel (0, 0).
    d0: DVec3,
    /// Its change per pixel to the right.
    du: DVec3,
    /// Its change per pixel down.
    dv: DVec3,
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
        map: Option<SunMap>,
    },
    /// A point light.
    Point {
        position: DVec3,
        intensity: f64,
        map: Option<CubeMap>,
    },
}

impl Lamp {
    /// What a face with unit normal `n` needs of this lamp at every pixel: for a sun, the
    /// incidence cosine and the shadow bias (meters); nothing for a point light.
    #[inline]
    fn prepare(&self, n: DVec3) -> (f64, f64) {
        match self {
            Lamp::Sun { toward, map, .. } => {
                let nl = n.dot(*toward);
                let bias = match map {
                    Some(m) if nl > 0.0 => m.texel * bias_texels(nl) + m.eps,
                    _ => 0.0,
                };
                (nl, bias)
            }
            Lamp::Point { .. } => (0.0, 0.0),
        }
    }

    /// The light this lamp gives the surface with unit normal `n` seen at depth `d` at
    /// pixel coordinates (`u`, `v`) (`at` = (u, v, d)); `prep` is [`Lamp::prepare`] of `n`.
    #[inline]
    fn light(&self, rays: &Rays, at: (f64, f64, f64), n: DVec3, (nl, bias): (f64, f64)) -> f64 {
        match self {
            Lamp::Sun { intensity, map, .. } => {
                if nl <= 0.0 || map.as_ref().is_some_and(|m| !m.lit_at(at, bias)) {
                    0.0
                } else {
                    nl * intensity
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

/// The slope-scaled part of the shadow bias, in texels, for a surface lit at incidence
/// cosine `nl` (> 0): ¾ texel of the surface's depth slope (capped at 3, past which the
/// light is dim and a larger bias would let light leak under bodies standing on the
/// surface), plus half a texel.
#[inline]
fn bias_texels(nl: f64) -> f64 {
    let slope = ((1.0 - nl * nl).max(0.0).sqrt() / nl).min(3.0);
    0.75 * slope + 0.5
}

/// A sun's light-space axes `s`, `t` across its rays ([`sun_axes`]).
#[derive(Clone, Copy, Debug)]
struct Axes {
    s: DVec3,
    t: DVec3,
}

impl Axes {
    /// The axes of the sun in direction `toward` (unit).
    fn new(toward: DVec3) -> Axes {
        let (s, t) = sun_axes(-toward);
        Axes { s, t }
    }
}

/// An empty light-space box `[x_min, x_max, y_min, y_max]`.
const EMPTY: [f64; 4] = [
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::INFINITY,
    f64::NEG_INFINITY,
];

/// The smallest box holding boxes `a` and `b`.
fn union(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0].min(b[0]),
        a[1].max(b[1]),
        a[2].min(b[2]),
        a[3].max(b[3]),
    ]
}

/// For each of `suns` (`None` for a lamp that needs no fitting), the light-space box of
/// the points a band of the picture shows: rows from `y0`, `width` pixels wide, with the
/// frame's `depth` and `face` values. (Points on faces turned away from a sun are
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
) -> Vec<[f64; 4]> {
    let mut acc = vec![EMPTY; suns.len()];
    for (r, (depths, faces)) in depth.chunks(width).zip(face.chunks(width)).enumerate() {
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

/// The light-space axes (s, t) across a sun's rays travelling along unit `direction`.
fn sun_axes(direction: DVec3) -> (DVec3, DVec3) {
    direction.any_orthonormal_pair()
}

/// An orthographic view along a sun's rays: pixel (u, v) is light-space
/// ((u/scale + x0)·s + (v/scale + y0)·t); the key is `zc − w·p` (nearer the sun larger,
/// and positive for every point of the scene).
#[derive(Clone, Copy, Debug)]
struct Ortho {
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

/// A sun's shadow map.
struct SunMap {
    width: usize,
    height: usize,
    /// Keys of the nearest far-side surface per texel; 0 where none.
    key: Vec<f32>,
    /// Texel side, meters.
    texel: f64,
    /// Constant bias, meters (covers the f32 keys' rounding).
    eps: f64,
    /// For the picture's pixels: texel u, texel v and key of the point at depth d on the
    /// ray through pixel coordinates (x, y), each `c + d·(d0 + x·dx + y·dy)` with
    /// `[c, d0, dx, dy]` from here (see [`SunMap::lit_at`]).
    camera: [[f64; 4]; 3],
}

impl SunMap {
    /// The map of the sun shining along unit `direction` over the light-space box
    /// `footprint` of its receivers, `side` texels on its longer side, for the picture
    /// whose pixel rays are `rays`. `None` for a scene without geometry.
    fn new(
        scene: &Scene,
        direction: DVec3,
        footprint: [f64; 4],
        side: usize,
        rays: &Rays,
        scratch: &mut Scratch,
    ) -> Option<SunMap> {
        let bounds = scene.bounds?;
        let (s, t) = sun_axes(direction);
        let diag = (bounds.max - bounds.min).length();
        // Beyond the scene's far end from the sun, so that every key is positive and a
        // texel left at zero holds nothing.
        let zc = direction.dot((bounds.min + bounds.max) / 2.0) + 0.5 * diag + 1e-3 * diag + 1e-6;
        let side = side.max(8);
        let pad = 2.0;
        let extent = (footprint[1] - footprint[0])
            .max(footprint[3] - footprint[2])
            .max(diag * 1e-9)
            .max(1e-9);
        let texel = extent / (side as f64 - 2.0 * pad);
        let width = (((footprint[1] - footprint[0]) / texel).ceil() as usize + 2 * pad as usize)
            .clamp(1, side);
        let height = (((footprint[3] - footprint[2]) / texel).ceil() as usize + 2 * pad as usize)
            .clamp(1, side);
        let view = Ortho {
            s,
            t,
            w: direction,
            x0: footprint[0] - pad * texel,
            y0: footprint[2] - pad * texel,
            scale: 1.0 / texel,
            zc,
        };
        let mut key = vec![0.0f32; width * height];
        let rows = |a: DVec3, c: f64, k: f64| {
            [
                c,
                k * a.dot(rays.d0),
                k * a.dot(rays.du),
                k * a.dot(rays.dv),
            ]
        };
        let camera = [
            rows(s, (s.dot(rays.eye) - view.x0) * view.scale, view.scale),
            rows(t, (t.dot(rays.eye) - view.y0) * view.scale, view.scale),
            rows(direction, zc - direction.dot(rays.eye), -1.0),
        ];
        fill::draw(
            scene,
            &view,
            width,
            height,
            scratch,
            |rows| {
                fill::split_rows(&mut key, width, rows)
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
        Some(SunMap {
            width,
            height,
            key,
            texel,
            eps: diag * 2e-6,
            camera,
        })
    }

    /// Whether the sun sees the point the picture shows at `at` = (x, y, depth), allowing
    /// `bias` meters toward the sun.
    #[inline]
    fn lit_at(&self, (x, y, d): (f64, f64, f64), bias: f64) -> bool {
        let [u, v, key] = self
            .camera
            .map(|[c, d0, dx, dy]| c + d * (d0 + x * dx + y * dy));
        if !(u >= 0.0 && v >= 0.0 && u < self.width as f64 && v < self.height as f64) {
            return true;
        }
        let k = self.key[v as usize * self.width + u as usize] as f64;
        k <= key + bias
    }
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
                let mut key = vec![0.0f32; side * side];
                let proj = Perspective {
                    view: *view,
                    front: false,
                };
                fill::draw(
                    scene,
                    &proj,
                    side,
                    side,
                    scratch,
                    |rows| {
                        fill::split_rows(&mut key, side, rows)
                            .into_iter()
                            .map(|(y0, k)| Band {
                                y0,
                                rows: k.len() / side,
                                width: side,
                                sink: Keys(k),
                            })
                            .collect()
                    },
                    |_| (),
                );
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
