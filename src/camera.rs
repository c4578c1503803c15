//! The camera model at work: Baumgart's PROJECTOR (world to camera coordinates, then
//! perspective) and CLIPER (clipping at the near plane and to the image window).
//!
//! The camera itself, its conventions and its alternative forms (Baumgart's FOCAL, LDX,
//! LDY, PDX, PDY and i, j, k frame; `look_at`; OpenCV's frame) are data the world keeps:
//! see [`crate::model::camera`], re-exported here.
//!
//! A [`View`] caches one camera's world-to-camera transform in f64. Points in front of
//! the camera have ZCC < 0; the *near plane* is ZCC = −near. Everything that is drawn is
//! first clipped to ZCC ≤ −near, so no division by a depth near zero happens, and a
//! camera inside a body or behind everything gives a correct (possibly empty) image.
//!
//! Clipping works in camera coordinates, on the 3D segment's own parameter: the near plane
//! and the four planes through the lens centre and the window's sides are planes in
//! camera space, and a point's signed distance to each is linear along a 3D segment, so
//! the parameters where a segment crosses them are exact (no perspective division first).

use glam::{DMat3, DVec2, DVec3};

pub use crate::model::camera::{BaumgartRaster, Camera, CameraError, Intrinsics, Light};

/// The default distance of the near plane from the lens centre, meters.
pub const DEFAULT_NEAR: f64 = 0.01;

/// One camera prepared for projecting many points: PROJECTOR's matrix and scales.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// World to camera rotation: rows i, j, k.
    rotation: DMat3,
    /// The lens centre, world coordinates.
    eye: DVec3,
    /// Pixel geometry.
    pub intrinsics: Intrinsics,
    /// Near-plane distance, meters (> 0).
    pub near: f64,
}

impl View {
    /// The view of `camera` with the near plane at `near` meters. Precondition: the camera
    /// is valid ([`Camera::validated`]) and `near` is finite and positive.
    pub fn new(camera: &Camera, near: f64) -> View {
        debug_assert!(near.is_finite() && near > 0.0);
        View {
            rotation: DMat3::from_cols(camera.i(), camera.j(), camera.k()).transpose(),
            eye: camera.position(),
            intrinsics: camera.intrinsics,
            near,
        }
    }

    /// The lens centre in world coordinates.
    pub fn eye(&self) -> DVec3 {
        self.eye
    }

    /// Image width and height, pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.intrinsics.width, self.intrinsics.height)
    }

    /// World point to camera coordinates (XCC, YCC, ZCC).
    #[inline]
    pub fn to_camera(&self, p: DVec3) -> DVec3 {
        self.rotation * (p - self.eye)
    }

    /// World direction to camera coordinates.
    #[inline]
    pub fn direction_to_camera(&self, d: DVec3) -> DVec3 {
        self.rotation * d
    }

    /// The pixel of a point in camera coordinates. Precondition: `c.z < 0` (use only on
    /// clipped geometry, where `c.z ≤ −near`).
    #[inline]
    pub fn project(&self, c: DVec3) -> DVec2 {
        let k = &self.intrinsics;
        let d = -c.z;
        DVec2::new(k.cx + k.fx * c.x / d, k.cy - k.fy * c.y / d)
    }

    /// The point in camera coordinates at depth `depth` (> 0, along −k) that projects to
    /// pixel `uv`: the inverse of [`View::project`] for a known depth.
    #[inline]
    pub fn unproject(&self, uv: DVec2, depth: f64) -> DVec3 {
        let k = &self.intrinsics;
        DVec3::new(
            (uv.x - k.cx) / k.fx * depth,
            -(uv.y - k.cy) / k.fy * depth,
            -depth,
        )
    }

    /// The five clipping planes as linear functions `n·c + d` of camera coordinates,
    /// non-negative inside: the near plane, then the window's left, right, top and bottom
    /// sides (planes through the lens centre).
    fn planes(&self) -> [(DVec3, f64); 5] {
        let k = &self.intrinsics;
        let (w, h) = (k.width as f64, k.height as f64);
        // u = cx + fx·x/(−z) ≥ 0  ⇔  fx·x − cx·z ≥ 0 (for z < 0), and so on.
        [
            (DVec3::new(0.0, 0.0, -1.0), -self.near),
            (DVec3::new(k.fx, 0.0, -k.cx), 0.0),
            (DVec3::new(-k.fx, 0.0, k.cx - w), 0.0),
            (DVec3::new(0.0, -k.fy, -k.cy), 0.0),
            (DVec3::new(0.0, k.fy, k.cy - h), 0.0),
        ]
    }

    /// CLIPER for a segment: the parameter range `[t0, t1]` (0 ≤ t0 ≤ t1 ≤ 1) of the
    /// segment `a + t·(b − a)` (camera coordinates) that lies beyond the near plane and
    /// projects inside the image window, or `None` when no part of it does (or only a
    /// single point). Exact up to rounding: every plane is linear along the 3D segment.
    pub fn clip_segment(&self, a: DVec3, b: DVec3) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (n, d) in self.planes() {
            let fa = n.dot(a) + d;
            let fb = n.dot(b) + d;
            if fa < 0.0 && fb < 0.0 {
                return None;
            }
            if fa < 0.0 {
                t0 = t0.max(fa / (fa - fb));
            } else if fb < 0.0 {
                t1 = t1.min(fa / (fa - fb));
            }
            if t0 >= t1 {
                return None;
            }
        }
        Some((t0, t1))
    }

    /// CLIPER for a polygon (camera coordinates): the part beyond the near plane
    /// (Sutherland–Hodgman), appended to `out` after clearing it. A polygon wholly in
    /// front of the near plane leaves `out` empty. The window sides are not clipped;
    /// rasterizers bound their loops by the image instead.
    pub fn clip_polygon_near(&self, poly: &[DVec3], out: &mut Vec<DVec3>) {
        out.clear();
        let z_max = -self.near;
        let Some(&last) = poly.last() else {
            return;
        };
        let mut prev = last;
        let mut prev_in = prev.z <= z_max;
        for &cur in poly {
            let cur_in = cur.z <= z_max;
            if cur_in != prev_in {
                let t = (z_max - prev.z) / (cur.z - prev.z);
                let mut x = prev.lerp(cur, t);
                x.z = z_max;
                out.push(x);
            }
            if cur_in {
                out.push(cur);
            }
            prev = cur;
            prev_in = cur_in;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> View {
        let k = Intrinsics::centered(640, 480, 500.0).unwrap();
        let cam = Camera::look_at(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, k).unwrap();
        View::new(&cam, DEFAULT_NEAR)
    }

    #[test]
    fn project_agrees_with_the_camera() {
        let k = Intrinsics::new(640, 480, 500.0, 520.0, 300.0, 250.0).unwrap();
        let cam = Camera::look_at(
            DVec3::new(1.0, 2.0, 5.0),
            DVec3::new(0.1, -0.2, 0.3),
            DVec3::Z,
            k,
        )
        .unwrap();
        let v = View::new(&cam, DEFAULT_NEAR);
        let p = DVec3::new(0.3, 0.1, -0.4);
        let c = v.to_camera(p);
        assert!((v.project(c) - cam.project(p).unwrap()).length() < 1e-9);
        let back = v.unproject(v.project(c), -c.z);
        assert!((back - c).length() < 1e-9);
    }

    #[test]
    fn a_segment_through_the_near_plane_is_cut_there() {
        let v = view();
        // From behind the camera to in front of it, along the optical axis.
        let (a, b) = (DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 0.0, -3.0));
        let (t0, t1) = v.clip_segment(a, b).unwrap();
        let cut = a.lerp(b, t0);
        assert!((cut.z + DEFAULT_NEAR).abs() < 1e-12);
        assert_eq!(t1, 1.0);
        // Wholly behind: nothing.
        assert!(
            v.clip_segment(DVec3::Z, DVec3::new(1.0, 0.0, 2.0))
                .is_none()
        );
    }

    #[test]
    fn a_segment_is_cut_at_the_window_sides() {
        let v = view();
        // A horizontal line at depth 5 much wider than the view: cut at u = 0 and 640.
        let (a, b) = (DVec3::new(-100.0, 0.0, -5.0), DVec3::new(100.0, 0.0, -5.0));
        let (t0, t1) = v.clip_segment(a, b).unwrap();
        assert!((v.project(a.lerp(b, t0)).x - 0.0).abs() < 1e-9);
        assert!((v.project(a.lerp(b, t1)).x - 640.0).abs() < 1e-9);
        // Wholly outside to the left.
        let left = (DVec3::new(-100.0, 0.0, -5.0), DVec3::new(-90.0, 0.0, -5.0));
        assert!(v.clip_segment(left.0, left.1).is_none());
    }

    #[test]
    fn a_polygon_is_clipped_at_the_near_plane() {
        let v = view();
        let square = [
            DVec3::new(-1.0, -1.0, 1.0),
            DVec3::new(1.0, -1.0, 1.0),
            DVec3::new(1.0, -1.0, -1.0),
            DVec3::new(-1.0, -1.0, -1.0),
        ];
        let mut out = Vec::new();
        v.clip_polygon_near(&square, &mut out);
        assert_eq!(out.len(), 4);
        assert!(out.iter().all(|p| p.z <= -DEFAULT_NEAR + 1e-12));
        v.clip_polygon_near(&square[..2], &mut out);
        assert!(out.is_empty());
    }
}
