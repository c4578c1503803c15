//! Point lights' shadow maps: a cube of six 90° perspective depth maps around the light,
//! of the far sides of occluders, and whether the light sees a point.

use glam::DVec3;

use crate::camera::View;
use crate::model::{Camera, Intrinsics};
use crate::render::buffers;
use crate::render::scene::Scene;

use super::fill::{self, Perspective, Scratch};
use super::shadow::bias_texels;

/// A point light's shadow cube: six 90° views, +x, −x, +y, −y, +z, −z.
pub(super) struct CubeMap {
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
    pub(super) fn new(
        scene: &Scene,
        position: DVec3,
        side: usize,
        scratch: &mut Scratch,
    ) -> Option<CubeMap> {
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
    pub(super) fn lit(&self, p: DVec3, nl: f64) -> bool {
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
