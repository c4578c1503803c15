//! Occlusion: where a modeled body hides part of the new object from a view, that view
//! must not carve there.
//!
//! The pixels the model covers (its z-buffer through the view's camera) that touch the
//! silhouette, directly or through other covered pixels, join the silhouette: the
//! object may continue behind them. A cup half hidden behind a known box keeps its
//! hidden half, because the view that sees only its visible half carves with the box's
//! region added. Covered regions that do not touch the silhouette are left out, so
//! that unrelated bodies do not widen it.

use std::collections::VecDeque;

use crate::camera::{Camera, DEFAULT_NEAR, View};
use crate::render::Scene;
use crate::render::raster::rasterize;
use crate::vision::image::Mask;

/// `mask` with the pixels `scene` covers through `camera` that are joined to it
/// (4-connected through covered pixels) added. `mask` must be the camera's size.
///
/// Postconditions: the result holds `mask`; every pixel added is covered by the model.
pub fn with_occluders(mask: &Mask, scene: &Scene, camera: &Camera) -> Mask {
    let view = View::new(camera, DEFAULT_NEAR);
    let frame = rasterize(scene, &view);
    let (w, h) = (mask.width(), mask.height());
    if (frame.width, frame.height) != (w, h) {
        return mask.clone();
    }
    let covered = |x: u32, y: u32| frame.face_at(x, y).is_some();
    let mut out = mask.clone();
    let mut queue: VecDeque<(u32, u32)> = VecDeque::new();
    for y in 0..h {
        for x in 0..w {
            if mask.get(x, y) {
                queue.push_back((x, y));
            }
        }
    }
    while let Some((x, y)) = queue.pop_front() {
        let mut visit = |nx: u32, ny: u32| {
            if nx < w && ny < h && !out.get(nx, ny) && covered(nx, ny) {
                out.set(nx, ny, true);
                queue.push_back((nx, ny));
            }
        };
        visit(x.wrapping_sub(1), y);
        visit(x + 1, y);
        visit(x, y.wrapping_sub(1));
        visit(x, y + 1);
    }
    frame.recycle();
    out
}
