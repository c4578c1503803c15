//! Occlusion: where a modeled body hides part of the new object from a view, that view
//! must not carve there.
//!
//! The pixels the model covers (its z-buffer through the view's camera) that touch the
//! silhouette, directly or through other such pixels, join the silhouette: the object
//! may continue behind them. A cup half hidden behind a known box keeps its hidden
//! half, because the view that sees only its visible half carves with the box's region
//! added. Covered regions that do not touch the silhouette are left out, so that
//! unrelated bodies do not widen it.
//!
//! Which covering bodies lie *in front* of the object is not known before the object
//! is: a first carving adds every touching covered pixel. Given that first result (which
//! holds the object), a second carving adds only the pixels where the model's surface is
//! nearer than the far side of the first result along the pixel's ray: a body behind
//! the object hides nothing of it, and where the first result does not reach, the
//! object is not.

use std::collections::VecDeque;

use glam::{DVec2, DVec3};

use super::mesh::Mesh;
use crate::camera::{Camera, DEFAULT_NEAR, View};
use crate::render::Scene;
use crate::render::raster::rasterize;
use crate::vision::image::Mask;

/// `mask` with the pixels `scene` covers through `camera` that are joined to it
/// (4-connected through such pixels) added; with `hull` (a solid holding the object),
/// only the covered pixels whose surface is nearer than the hull's farthest surface
/// along the pixel's ray. `mask` must be the camera's size.
///
/// Postconditions: the result holds `mask`; every pixel added is covered by the model.
pub fn with_occluders(mask: &Mask, scene: &Scene, camera: &Camera, hull: Option<&[Mesh]>) -> Mask {
    let view = View::new(camera, DEFAULT_NEAR);
    let frame = rasterize(scene, &view);
    let (w, h) = (mask.width(), mask.height());
    if (frame.width, frame.height) != (w, h) {
        return mask.clone();
    }
    let reach = hull.map(|h| Reach::new(h, camera));
    let hides = |x: u32, y: u32| {
        frame.face_at(x, y).is_some()
            && reach.as_ref().is_none_or(|r| {
                r.far(camera, x, y)
                    .is_some_and(|far| f64::from(frame.depth_at(x, y)) < far)
            })
    };
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
            if nx < w && ny < h && !out.get(nx, ny) && hides(nx, ny) {
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

/// A solid's faces as the camera sees them: each face's projected ring, its box, and
/// its plane, to find how far along a pixel's ray the solid reaches.
struct Reach {
    faces: Vec<(Vec<DVec2>, [DVec2; 2], DVec3, f64)>,
}

impl Reach {
    fn new(hull: &[Mesh], camera: &Camera) -> Reach {
        let mut faces = Vec::new();
        for mesh in hull {
            for f in &mesh.faces {
                let pts: Vec<DVec3> = f.iter().map(|&v| mesh.positions[v as usize]).collect();
                let Some(ring) = pts
                    .iter()
                    .map(|p| camera.project(*p))
                    .collect::<Option<Vec<_>>>()
                else {
                    continue;
                };
                let lo = ring.iter().fold(ring[0], |a, b| a.min(*b));
                let hi = ring.iter().fold(ring[0], |a, b| a.max(*b));
                let mut n = DVec3::ZERO;
                for k in 0..pts.len() {
                    n += pts[k].cross(pts[(k + 1) % pts.len()]);
                }
                faces.push((ring, [lo, hi], n, n.dot(pts[0])));
            }
        }
        Reach { faces }
    }

    /// The greatest depth (metres along the view direction) at which the ray through
    /// pixel `(x, y)`'s centre meets the solid's surface; `None` where it misses.
    fn far(&self, camera: &Camera, x: u32, y: u32) -> Option<f64> {
        let q = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
        let ray = camera.pixel_ray(q);
        let eye = camera.position();
        let along = -camera.k().dot(ray);
        let mut far: Option<f64> = None;
        for (ring, [lo, hi], n, d) in &self.faces {
            if q.cmplt(*lo).any() || q.cmpgt(*hi).any() || !inside(ring, q) {
                continue;
            }
            let t = (d - n.dot(eye)) / n.dot(ray);
            if t.is_finite() && t > 0.0 {
                let depth = t * along;
                far = Some(far.map_or(depth, |f: f64| f.max(depth)));
            }
        }
        far
    }
}

/// Whether `q` is inside `ring` (even-odd).
fn inside(ring: &[DVec2], q: DVec2) -> bool {
    let mut odd = false;
    for k in 0..ring.len() {
        let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
        if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            odd = !odd;
        }
    }
    odd
}
