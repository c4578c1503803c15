//! A camera's pixel rays in world coordinates: the world point a pixel shows at a given
//! depth.

use glam::{DMat3, DVec3};

use crate::camera::View;

/// Pixel rays of a camera in world coordinates.
pub(super) struct Rays {
    /// The lens centre.
    pub(super) eye: DVec3,
    /// The camera's i, j, k in world coordinates.
    pub(super) frame: DMat3,
    /// Ray direction (scaled to unit depth) at pixel (0, 0).
    pub(super) d0: DVec3,
    /// Its change per pixel to the right.
    pub(super) du: DVec3,
    /// Its change per pixel down.
    pub(super) dv: DVec3,
}

impl Rays {
    /// The rays of the camera of `view`.
    pub(super) fn new(view: &View) -> Rays {
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
    pub(super) fn point(&self, u: f64, v: f64, depth: f64) -> DVec3 {
        self.eye + (self.d0 + self.du * u + self.dv * v) * depth
    }
}
