//! Shadow maps as a picture uses them: the sizes of the maps kept with a scene and when a
//! kept sun map is too coarse for a picture ([`REFIT`]); fitting a sun map to what a
//! picture shows (the light-space footprint of its pixels, and the texel that gives);
//! and the bias of a lookup in any map ([`bias_texels`]). The maps themselves are sun
//! maps (`sun`) and point lights' cubes (`cube`); the [shading module](super::shade)
//! tells how a picture uses them.

use glam::DVec3;
use rayon::prelude::*;

use super::rays::Rays;
use super::{Frame, NO_FACE};

/// Texels on the longer side of a sun's kept shadow map (which covers the whole scene).
pub const KEPT_SUN_SIDE: usize = 1024;

/// Texels on the side of each of the six kept shadow maps of a point light.
pub const KEPT_CUBE_SIDE: usize = 1024;

/// A sun's kept shadow map serves a picture as long as its texels are at most this many
/// times the size of those of a map fitted to what the picture shows.
pub const REFIT: f64 = 2.0;

/// Every this many rows are enough to decide whether a kept sun map is too coarse.
pub(super) const SAMPLED_ROWS: usize = 4;

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
#[inline]
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
pub(super) fn footprints(
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
pub(super) fn frame_footprints(
    rays: &Rays,
    suns: &[Option<Axes>],
    frame: &Frame,
) -> Vec<Vec<[f64; 4]>> {
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
