//! The pixel renderer: a z-buffer of the scene from a camera, and the images made from it
//! (`shaded`, `wire`, `depth`, `ids`).
//!
//! [`rasterize`] makes a [`Frame`]: for every pixel, the nearest surface's depth and face.
//! A pixel shows a triangle when the pixel's *centre* is inside the projected triangle
//! (top-left rule on edges, so shared edges are neither drawn twice nor cracked); its depth
//! comes from the face's plane along the ray through the pixel centre (1/depth is an
//! affine function of the pixel, evaluated in f64 and kept in f32: the depth is exact to
//! within an ulp or two of f32). Triangles are clipped at the camera's near plane before
//! projection; back faces (those whose outside does not look toward the eye) are culled.
//! The rasterizer itself and how it runs in parallel are described in the `fill` module's
//! source.
//!
//! From the frame: [`shaded`] lights each pixel (Lambert, with shadows from shadow maps;
//! see [`Shading`]), [`depth_image`] and [`ids_image`] encode depth and bodies as 16-bit
//! images. [`wire`] draws every edge, front or back, as an anti-aliased line.
//!
//! Everything is computed per call from the scene and the view, except the shadow maps of
//! the world's lights, which depend on the scene alone and are kept with it (see
//! [`ShadowCache`]); any number of cameras can render the same scene at once.

mod cube;
mod fill;
mod rays;
pub mod shade;
mod shadow;
mod srgb;
mod sun;
#[cfg(test)]
mod tests;

use glam::DVec2;
use rayon::prelude::*;

use crate::camera::View;
use crate::model::BodyId;

use super::buffers;
pub use super::cache::ShadowCache;
use super::image::{Gray16, RgbImage};
use super::lines::draw_line;
use super::scene::Scene;
use fill::{Band, Ids, Perspective, Scratch, Sink};

pub use shade::{Shading, shaded};

/// The face value of a pixel that shows no surface.
pub const NO_FACE: u32 = u32::MAX;

/// The z-buffer of one camera: per pixel the nearest surface's depth and face. Rows run
/// top to bottom, pixels left to right (index `y·width + x`).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Depth (−ZCC, meters, along the camera's view direction, not along the ray) of the
    /// surface at each pixel centre; `f32::INFINITY` where nothing is seen.
    pub depth: Vec<f32>,
    /// Index into [`Scene::faces`] of the surface at each pixel; [`NO_FACE`] where
    /// nothing is seen.
    pub face: Vec<u32>,
}

impl Frame {
    /// Gives the frame's buffers back for later pictures (see [`crate::render`]'s
    /// buffer pool): a caller done with a frame may call this instead of dropping it.
    pub fn recycle(self) {
        buffers::give(self.depth);
        buffers::give(self.face);
    }

    /// The face at column `x`, row `y`, if any. Precondition: inside the frame.
    pub fn face_at(&self, x: u32, y: u32) -> Option<u32> {
        let f = self.face[y as usize * self.width as usize + x as usize];
        (f != NO_FACE).then_some(f)
    }

    /// The depth at column `x`, row `y` (infinite where nothing is seen). Precondition:
    /// inside the frame.
    pub fn depth_at(&self, x: u32, y: u32) -> f32 {
        self.depth[y as usize * self.width as usize + x as usize]
    }
}

/// The z-buffer of `scene` seen from `view`.
///
/// Postconditions: `face[i]` is the face of the nearest front-facing triangle whose
/// projection (after clipping at `view.near`) contains pixel `i`'s centre, or [`NO_FACE`];
/// `depth[i]` is the depth of that face's plane along the ray through the pixel centre
/// (relative error below 2e-7), or infinity. Never panics: a camera inside a body or
/// facing away from everything gives an empty frame, and a zero-sized image an empty one.
pub fn rasterize(scene: &Scene, view: &View) -> Frame {
    let mut none: [(); 0] = [];
    rasterize_with(scene, view, &mut Scratch::default(), &mut none, 0, |_| ()).0
}

/// One finished band of rows of a frame, as [`rasterize_with`] hands it on.
pub(super) struct FrameBand<'a, T> {
    /// First row.
    pub y0: usize,
    /// Depths, as in [`Frame::depth`], `rows × width`.
    pub depth: &'a [f32],
    /// Faces, as in [`Frame::face`].
    pub face: &'a [u32],
    /// The band's rows of the caller's output raster.
    pub out: &'a mut [T],
}

/// A z-buffer band that also carries the band's rows of an output raster.
struct WithOutput<'a, T> {
    ids: Ids<'a>,
    out: &'a mut [T],
}

impl<T: Send> Sink for WithOutput<'_, T> {
    #[inline(always)]
    fn plot(&mut self, i: usize, key: f32, face: u32) {
        self.ids.plot(i, key, face);
    }

    fn clear(&mut self) {
        self.ids.clear();
    }
}

/// [`rasterize`] with working memory `scratch`, also handing each finished band of rows
/// to `per_band` while it is still in the cache, together with the same rows of `out`
/// (an output raster of `per_pixel` values per pixel; empty, with `per_pixel` 0, when
/// there is none), and returning what `per_band` returns, band by band.
///
/// Precondition: `out.len()` is `width · height · per_pixel`.
fn rasterize_with<T, R, G>(
    scene: &Scene,
    view: &View,
    scratch: &mut Scratch,
    out: &mut [T],
    per_pixel: usize,
    per_band: G,
) -> (Frame, Vec<R>)
where
    T: Send,
    G: Fn(FrameBand<'_, T>) -> R + Sync,
    R: Send,
{
    let (width, height) = view.size();
    let (w, h) = (width as usize, height as usize);
    // Both buffers are cleared band by band in the drawing threads; faces are stored plus
    // one (0 for none) until each band is finished.
    let mut key = buffers::take::<f32>(w * h);
    let mut face = buffers::take::<u32>(w * h);
    let proj = Perspective {
        view: *view,
        front: true,
    };
    let results = fill::draw(
        scene,
        &proj,
        w,
        h,
        scratch,
        |rows| {
            let bands = fill::split_rows(&mut key, w, rows)
                .into_iter()
                .zip(fill::split_rows(&mut face, w, rows));
            let mut outs: Vec<&mut [T]> = if per_pixel == 0 {
                Vec::new()
            } else {
                out.chunks_mut(w * rows * per_pixel).collect()
            };
            outs.resize_with(h.div_ceil(rows), Default::default);
            bands
                .zip(outs)
                .map(|(((y0, key), (_, face)), out)| Band {
                    y0,
                    rows: key.len() / w.max(1),
                    width: w,
                    sink: WithOutput {
                        ids: Ids { key, face },
                        out,
                    },
                })
                .collect()
        },
        |band| {
            // Keys to depths. The key is 1/depth from the face's plane along the pixel
            // centre's ray, rounded to f32 (6e-8 relative), so the depth is as exact as
            // an f32 depth can be, to within an ulp or two.
            let WithOutput {
                ids: Ids { key, face },
                out,
            } = &mut band.sink;
            for (d, f) in key.iter_mut().zip(face.iter_mut()) {
                if *f == 0 {
                    *f = NO_FACE;
                    *d = f32::INFINITY;
                } else {
                    *f -= 1;
                    *d = 1.0 / *d;
                }
            }
            per_band(FrameBand {
                y0: band.y0,
                depth: key,
                face,
                out,
            })
        },
    );
    let frame = Frame {
        width,
        height,
        depth: key,
        face,
    };
    (frame, results)
}

/// The depth image of `frame`: 0 where nothing is seen, else the depth in units of
/// `meters_per_unit` rounded and clamped to `1..=65535` (so a surface is never 0).
///
/// Precondition: `meters_per_unit` is finite and positive. Otherwise every surface pixel
/// is 1 (non-positive or NaN scale) or 65535 (infinite quotients) — never 0.
pub fn depth_image(frame: &Frame, meters_per_unit: f64) -> Gray16 {
    let mut img = Gray16::zeros(frame.width, frame.height);
    let scale = 1.0 / meters_per_unit;
    img.data
        .par_chunks_mut(4096)
        .zip(frame.depth.par_chunks(4096))
        .for_each(|(out, depth)| {
            for (o, &d) in out.iter_mut().zip(depth) {
                if d.is_finite() {
                    let v = (d as f64 * scale).round();
                    *o = if v >= 65535.0 {
                        65535
                    } else if v >= 1.0 {
                        v as u16
                    } else {
                        1
                    };
                }
            }
        });
    img
}

/// Why an ids image could not be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum IdsError {
    /// More bodies appear than a 16-bit image can number (65535; 0 is the background).
    #[error("{count} bodies appear in the image; an ids image can number at most 65535")]
    TooManyBodies {
        /// How many bodies appear.
        count: usize,
    },
}

/// The body-ids image of `frame` (made from `scene` with [`rasterize`]) and its legend:
/// pixel value `v ≥ 1` shows body `legend[v − 1]`, 0 is the background. The legend lists
/// the bodies that appear, in id order.
///
/// Refused with [`IdsError::TooManyBodies`] when more than 65535 bodies appear.
/// Precondition: `frame` was made from `scene` (face indices in range; others count as
/// background).
pub fn ids_image(scene: &Scene, frame: &Frame) -> Result<(Gray16, Vec<BodyId>), IdsError> {
    let body_of = |f: u32| {
        scene
            .faces
            .get(f as usize)
            .map(|face| face.body as usize)
            .filter(|&b| b < scene.bodies.len())
    };
    // Which bodies appear.
    let seen = frame
        .face
        .par_chunks(1 << 16)
        .map(|faces| {
            let mut seen = vec![false; scene.bodies.len()];
            let mut last = NO_FACE;
            for &f in faces {
                if f != last {
                    last = f;
                    if let Some(b) = body_of(f) {
                        seen[b] = true;
                    }
                }
            }
            seen
        })
        .reduce(
            || vec![false; scene.bodies.len()],
            |mut a, b| {
                a.iter_mut().zip(b).for_each(|(x, y)| *x |= y);
                a
            },
        );
    // Scene bodies are in id order, so numbering them in index order keeps the legend
    // in id order.
    let mut number = vec![0u16; scene.bodies.len()];
    let mut legend = Vec::new();
    let count = seen.iter().filter(|&&s| s).count();
    if count > 65535 {
        return Err(IdsError::TooManyBodies { count });
    }
    for (b, &s) in seen.iter().enumerate() {
        if s {
            legend.push(scene.bodies[b].id);
            number[b] = legend.len() as u16;
        }
    }
    let mut img = Gray16::zeros(frame.width, frame.height);
    img.data
        .par_chunks_mut(4096)
        .zip(frame.face.par_chunks(4096))
        .for_each(|(out, faces)| {
            for (o, &f) in out.iter_mut().zip(faces) {
                if let Some(b) = body_of(f) {
                    *o = number[b];
                }
            }
        });
    Ok((img, legend))
}

/// One chunk of edges for [`wire`]: the visible ones' segments (pixel coordinates) and,
/// per band of rows, the segments that reach it.
type WireChunk = (Vec<(DVec2, DVec2)>, Vec<Vec<u32>>);

/// The wireframe of `scene` from `view`: every edge, front or back, clipped at the near
/// plane and the window ([`View::clip_segment`]), drawn anti-aliased in `ink` on
/// `background` ([`draw_line`]), in scene order.
///
/// Drawing runs in parallel bands of rows; each band draws the segments that reach it, in
/// order, so the picture is the one a single sequential pass would draw (up to rounding
/// of the band offset). A zero-sized view gives an empty image.
pub fn wire(scene: &Scene, view: &View, background: [u8; 3], ink: [u8; 3]) -> RgbImage {
    let (width, height) = view.size();
    let (w, h) = (width as usize, height as usize);
    if w == 0 || h == 0 {
        return RgbImage::filled(width, height, background);
    }
    let threads = rayon::current_num_threads().max(1);
    let rows = h.div_ceil(threads * 8).clamp(8, 256);
    let nbands = h.div_ceil(rows);
    // In chunks of edges, in parallel: each visible edge's clipped, projected segment,
    // listed in every band of rows its drawing may reach (a row either side for the
    // anti-aliasing, half a pixel more for the end caps).
    let chunks: Vec<WireChunk> = scene
        .edges
        .par_chunks(8192)
        .map(|edges| {
            let mut segments = Vec::with_capacity(edges.len());
            let mut bins: Vec<Vec<u32>> = vec![Vec::new(); nbands];
            for e in edges {
                let a = view.to_camera(scene.points[e.ends[0] as usize]);
                let b = view.to_camera(scene.points[e.ends[1] as usize]);
                let Some((t0, t1)) = view.clip_segment(a, b) else {
                    continue;
                };
                let (p, q) = (view.project(a.lerp(b, t0)), view.project(a.lerp(b, t1)));
                // Clipped to the window, so the rows are in range (NaN ends give 0).
                let lo = (p.y.min(q.y) - 2.0).max(0.0) as usize;
                let hi = ((p.y.max(q.y) + 2.0).max(0.0) as usize).min(h - 1);
                if lo > hi {
                    continue;
                }
                for bin in &mut bins[lo / rows..=hi / rows] {
                    bin.push(segments.len() as u32);
                }
                segments.push((p, q));
            }
            (segments, bins)
        })
        .collect();
    let bands: Vec<RgbImage> = (0..nbands)
        .into_par_iter()
        .map(|b| {
            let y0 = b * rows;
            let n = rows.min(h - y0);
            let mut img = RgbImage::filled(width, n as u32, background);
            let shift = DVec2::new(0.0, y0 as f64);
            for (segments, bins) in &chunks {
                for &i in &bins[b] {
                    let (a, c) = segments[i as usize];
                    draw_line(&mut img, a - shift, c - shift, ink);
                }
            }
            img
        })
        .collect();
    let mut data = Vec::with_capacity(w * h * 3);
    for band in bands {
        data.extend_from_slice(&band.data);
    }
    RgbImage {
        width,
        height,
        data,
    }
}
