//! Cameras and lights: plain, validated data the world keeps by name.
//!
//! # The camera frame
//!
//! Baumgart's camera (WINGED.DOC I.B) is a lens centre and a right-handed frame of unit
//! vectors: **i** maps to the rightward x of the display, **j** to the upward y, and **k**
//! comes out of the screen toward the viewer, so the camera looks along **−k** (the
//! OpenGL convention). A [`Camera`]'s [`Pose`] places that frame in the world: its
//! position is the lens centre, and its rotation maps the camera's x, y, z axes to i, j,
//! k. A world point `p` has camera coordinates (Baumgart's XCC, YCC, ZCC)
//! `(i·(p−c), j·(p−c), k·(p−c))`; points in front of the camera have ZCC < 0.
//!
//! # Pixels
//!
//! [`Intrinsics`] are `{width, height, fx, fy, cx, cy}` in pixels. Pixel coordinates
//! `(u, v)` run right and down from the top-left *corner* of the top-left pixel (so that
//! pixel's centre is (0.5, 0.5)). A point with camera coordinates (x, y, z), z < 0,
//! projects to `u = cx + fx·x/(−z)`, `v = cy − fy·y/(−z)`.
//!
//! # Baumgart's form
//!
//! WINGED.DOC gives the scales `SCALEX = −FOCAL·LDX/PDX`, `SCALEY = −FOCAL·LDY/PDY` and
//! `XPP = SCALEX·XCC/ZCC`, `YPP = SCALEY·YCC/ZCC`, with LDX × LDY the logical raster
//! (pixels), PDX × PDY the physical raster and FOCAL the focal distance (both in the same
//! unit, e.g. millimetres). With the image origin at the raster centre this is
//! `fx = FOCAL·LDX/PDX`, `fy = FOCAL·LDY/PDY`, `cx = LDX/2`, `cy = LDY/2`,
//! `width = LDX`, `height = LDY`, `u = cx + XPP`, `v = cy − YPP`
//! ([`Intrinsics::from_baumgart`], [`Intrinsics::to_baumgart`]).
//!
//! # OpenCV's frame
//!
//! OpenCV (and most camera-solution code) uses x right, y *down*, z *forward*: its axes
//! are (i, −j, −k). [`Camera::to_opencv`] gives the rotation `R` (rows i, −j, −k) and
//! translation `t = −R·c` with `x_cv = R·p + t`, and [`Camera::from_opencv`] goes back.
//! OpenCV also puts integer pixel coordinates at pixel *centres*, half a pixel from ours:
//! [`Intrinsics::opencv_matrix`] subtracts ½ from cx and cy, and
//! [`Intrinsics::from_opencv_matrix`] adds it back.

use glam::{DMat3, DQuat, DVec2, DVec3};
use serde::{Deserialize, Serialize};

use super::pose::{Pose, PoseError};
use super::range::{self, RangeError};

/// The largest image side, in pixels, that intrinsics may have.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// The largest focal length, and the farthest a principal point may lie from the
/// image's corner on either axis, in pixels.
pub const MAX_PIXELS: f64 = 1e9;

/// The largest light intensity.
pub const MAX_INTENSITY: f64 = 1e6;

/// How far from orthonormal (largest entry of `RᵀR − I`) a rotation matrix may be.
pub const ORTHONORMAL_TOL: f64 = 1e-6;

/// Why a camera was refused.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// A number is NaN or infinite.
    #[error("the camera's {what} is not finite")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// The camera's pose is not a valid pose.
    #[error("bad camera pose: {0}")]
    Pose(#[from] PoseError),
    /// The i, j, k rows do not form an orthonormal matrix.
    #[error("the camera rotation is not orthonormal (largest error {deviation:e})")]
    NotOrthonormal {
        /// Largest absolute entry of RᵀR − I.
        deviation: f64,
    },
    /// The i, j, k rows form a left-handed frame (a reflection, not a rotation).
    #[error("the camera frame i, j, k is left-handed")]
    LeftHanded,
    /// Width or height is zero or larger than [`MAX_IMAGE_SIDE`].
    #[error("image size {width}×{height} is not between 1 and 16384 pixels a side")]
    BadImageSize {
        /// Width, pixels.
        width: u32,
        /// Height, pixels.
        height: u32,
    },
    /// A focal length that is not positive.
    #[error("focal lengths fx = {fx}, fy = {fy} must be positive")]
    BadFocal {
        /// fx, pixels.
        fx: f64,
        /// fy, pixels.
        fy: f64,
    },
    /// A Baumgart raster parameter (FOCAL, PDX, PDY) that is not positive.
    #[error("Baumgart's {what} must be positive")]
    BadRaster {
        /// "FOCAL", "PDX" or "PDY".
        what: &'static str,
    },
    /// A field of view outside (0, π).
    #[error("field of view {fov_rad} rad is not between 0 and π")]
    BadFieldOfView {
        /// The angle given, radians.
        fov_rad: f64,
    },
    /// look_at with the eye on the target: no view direction.
    #[error("look_at: the eye is at the target")]
    EyeAtTarget,
    /// look_at with an up vector that is zero or along the view direction.
    #[error("look_at: the up vector is zero or parallel to the view direction")]
    UpParallel,
    /// A focal length or principal point beyond [`MAX_PIXELS`].
    #[error("the camera's {what} is {value:e} pixels, beyond ±{MAX_PIXELS:e}")]
    PixelsBeyond {
        /// Which input.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// The camera's position is outside the world's range.
    #[error(transparent)]
    OutOfRange(#[from] RangeError),
}

impl CameraError {
    /// Whether the refusal is about the world's range (see [`crate::model::range`]).
    pub fn is_out_of_range(&self) -> bool {
        matches!(self, CameraError::OutOfRange(_))
    }
}

/// A pinhole camera's pixel geometry. See the [module documentation](self) for the pixel
/// convention.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Intrinsics {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Horizontal focal length, pixels.
    pub fx: f64,
    /// Vertical focal length, pixels.
    pub fy: f64,
    /// Principal point, pixels from the left edge.
    pub cx: f64,
    /// Principal point, pixels from the top edge.
    pub cy: f64,
}

/// Baumgart's raster form of a camera's intrinsics (WINGED.DOC I.B): the logical raster
/// LDX × LDY in pixels, the physical raster PDX × PDY and the focal distance FOCAL in one
/// physical unit (millimetres, say). The principal point is the raster centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaumgartRaster {
    /// FOCAL: focal plane distance (physical unit).
    pub focal: f64,
    /// LDX: logical raster width, pixels.
    pub ldx: u32,
    /// LDY: logical raster height, pixels.
    pub ldy: u32,
    /// PDX: physical raster width (physical unit).
    pub pdx: f64,
    /// PDY: physical raster height (physical unit).
    pub pdy: f64,
}

impl Intrinsics {
    /// Checked intrinsics. Refused unless 1 ≤ width, height ≤ [`MAX_IMAGE_SIDE`], fx and
    /// fy are finite, positive and at most [`MAX_PIXELS`], and cx, cy are finite and
    /// within ±[`MAX_PIXELS`].
    pub fn new(
        width: u32,
        height: u32,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
    ) -> Result<Intrinsics, CameraError> {
        let k = Intrinsics {
            width,
            height,
            fx,
            fy,
            cx,
            cy,
        };
        k.validate()?;
        Ok(k)
    }

    /// Square pixels of focal length `focal_px`, principal point at the image centre.
    pub fn centered(width: u32, height: u32, focal_px: f64) -> Result<Intrinsics, CameraError> {
        Intrinsics::new(
            width,
            height,
            focal_px,
            focal_px,
            width as f64 / 2.0,
            height as f64 / 2.0,
        )
    }

    /// Square pixels with a vertical field of view of `fov_y_rad` (0 < fov < π),
    /// principal point at the image centre.
    pub fn from_fov_y(width: u32, height: u32, fov_y_rad: f64) -> Result<Intrinsics, CameraError> {
        if !fov_y_rad.is_finite() {
            return Err(CameraError::NonFinite {
                what: "field of view",
            });
        }
        if fov_y_rad <= 0.0 || fov_y_rad >= std::f64::consts::PI {
            return Err(CameraError::BadFieldOfView { fov_rad: fov_y_rad });
        }
        Intrinsics::centered(width, height, height as f64 / 2.0 / (fov_y_rad / 2.0).tan())
    }

    /// Checks the conditions [`Intrinsics::new`] states.
    pub fn validate(&self) -> Result<(), CameraError> {
        let side = 1..=MAX_IMAGE_SIDE;
        if !side.contains(&self.width) || !side.contains(&self.height) {
            return Err(CameraError::BadImageSize {
                width: self.width,
                height: self.height,
            });
        }
        if !self.fx.is_finite() || !self.fy.is_finite() {
            return Err(CameraError::NonFinite {
                what: "focal length",
            });
        }
        if self.fx <= 0.0 || self.fy <= 0.0 {
            return Err(CameraError::BadFocal {
                fx: self.fx,
                fy: self.fy,
            });
        }
        if !self.cx.is_finite() || !self.cy.is_finite() {
            return Err(CameraError::NonFinite {
                what: "principal point",
            });
        }
        for (what, value) in [
            ("focal length fx", self.fx),
            ("focal length fy", self.fy),
            ("principal point cx", self.cx),
            ("principal point cy", self.cy),
        ] {
            if value.abs() > MAX_PIXELS {
                return Err(CameraError::PixelsBeyond { what, value });
            }
        }
        Ok(())
    }

    /// From Baumgart's raster form: `fx = FOCAL·LDX/PDX`, `fy = FOCAL·LDY/PDY`, principal
    /// point at the raster centre. Refused for non-positive FOCAL, PDX or PDY or a bad
    /// raster size.
    pub fn from_baumgart(r: &BaumgartRaster) -> Result<Intrinsics, CameraError> {
        for (x, what) in [(r.focal, "FOCAL"), (r.pdx, "PDX"), (r.pdy, "PDY")] {
            if !x.is_finite() {
                return Err(CameraError::NonFinite { what });
            }
            if x <= 0.0 {
                return Err(CameraError::BadRaster { what });
            }
        }
        Intrinsics::new(
            r.ldx,
            r.ldy,
            r.focal * r.ldx as f64 / r.pdx,
            r.focal * r.ldy as f64 / r.pdy,
            r.ldx as f64 / 2.0,
            r.ldy as f64 / 2.0,
        )
    }

    /// To Baumgart's raster form for a chosen `focal` distance (the form has one free
    /// scale): `PDX = FOCAL·width/fx`, `PDY = FOCAL·height/fy`. The form cannot express
    /// an off-centre principal point; cx and cy are dropped. `from_baumgart(to_baumgart(k,
    /// f))` gives back `k` when its principal point is the image centre.
    pub fn to_baumgart(&self, focal: f64) -> Result<BaumgartRaster, CameraError> {
        self.validate()?;
        if !focal.is_finite() {
            return Err(CameraError::NonFinite { what: "FOCAL" });
        }
        if focal <= 0.0 {
            return Err(CameraError::BadRaster { what: "FOCAL" });
        }
        Ok(BaumgartRaster {
            focal,
            ldx: self.width,
            ldy: self.height,
            pdx: focal * self.width as f64 / self.fx,
            pdy: focal * self.height as f64 / self.fy,
        })
    }

    /// OpenCV's camera matrix K (columns), with its principal point moved half a pixel
    /// (OpenCV's integer pixel coordinates are pixel centres).
    pub fn opencv_matrix(&self) -> DMat3 {
        DMat3::from_cols(
            DVec3::new(self.fx, 0.0, 0.0),
            DVec3::new(0.0, self.fy, 0.0),
            DVec3::new(self.cx - 0.5, self.cy - 0.5, 1.0),
        )
    }

    /// From OpenCV's camera matrix K (skew ignored) and image size: the inverse of
    /// [`Intrinsics::opencv_matrix`].
    pub fn from_opencv_matrix(
        k: DMat3,
        width: u32,
        height: u32,
    ) -> Result<Intrinsics, CameraError> {
        Intrinsics::new(
            width,
            height,
            k.x_axis.x,
            k.y_axis.y,
            k.z_axis.x + 0.5,
            k.z_axis.y + 0.5,
        )
    }
}

/// A pinhole camera: the pose of Baumgart's i, j, k frame in the world and its pixel
/// geometry. See the [module documentation](self) for the conventions.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// The camera frame in the world: position is the lens centre, rotation maps the
    /// camera's x, y, z axes to i (right), j (up), k (toward the viewer).
    pub pose: Pose,
    /// Pixel geometry.
    pub intrinsics: Intrinsics,
}

impl Camera {
    /// A checked camera: the pose is validated (finite, its position within the world's
    /// range; quaternion renormalised, so the rotation is orthonormal) and so are the
    /// intrinsics.
    pub fn new(pose: Pose, intrinsics: Intrinsics) -> Result<Camera, CameraError> {
        let pose = pose.validated()?;
        range::coordinate("the camera's position", pose.position)?;
        intrinsics.validate()?;
        Ok(Camera { pose, intrinsics })
    }

    /// This camera checked, as [`Camera::new`] does (returns the renormalised copy).
    pub fn validated(&self) -> Result<Camera, CameraError> {
        Camera::new(self.pose, self.intrinsics)
    }

    /// From Baumgart's eighteen numbers: lens centre `position` and the rows `i`, `j`,
    /// `k` of his rotation matrix (each in world coordinates). Refused unless the rows
    /// are orthonormal within [`ORTHONORMAL_TOL`] and right-handed (i × j = k).
    pub fn from_ijk(
        position: DVec3,
        i: DVec3,
        j: DVec3,
        k: DVec3,
        intrinsics: Intrinsics,
    ) -> Result<Camera, CameraError> {
        if !position.is_finite() {
            return Err(CameraError::NonFinite { what: "position" });
        }
        if !(i.is_finite() && j.is_finite() && k.is_finite()) {
            return Err(CameraError::NonFinite { what: "rotation" });
        }
        let m = DMat3::from_cols(i, j, k);
        let e = m.transpose() * m - DMat3::IDENTITY;
        let deviation = e.to_cols_array().iter().fold(0.0f64, |a, x| a.max(x.abs()));
        if deviation > ORTHONORMAL_TOL {
            return Err(CameraError::NotOrthonormal { deviation });
        }
        if m.determinant() < 0.0 {
            return Err(CameraError::LeftHanded);
        }
        Camera::new(
            Pose {
                position,
                rotation: DQuat::from_mat3(&m),
            },
            intrinsics,
        )
    }

    /// A camera at `eye` looking at `target`, with `up` pointing up in the image as far
    /// as it can: `k = (eye − target)/|eye − target|` (so the view direction −k points at
    /// the target), `i = up × k` normalised, `j = k × i`. The target projects to the
    /// principal point.
    ///
    /// Refused when an input is not finite, the eye is at the target, or `up` is zero or
    /// parallel to the view direction.
    pub fn look_at(
        eye: DVec3,
        target: DVec3,
        up: DVec3,
        intrinsics: Intrinsics,
    ) -> Result<Camera, CameraError> {
        for (v, what) in [(eye, "eye"), (target, "target"), (up, "up")] {
            if !v.is_finite() {
                return Err(CameraError::NonFinite { what });
            }
        }
        // Halved so that the difference cannot overflow; a unit vector is the same.
        let k = range::unit("the view direction", eye * 0.5 - target * 0.5)
            .map_err(|_| CameraError::EyeAtTarget)?;
        let up = range::unit("up", up).map_err(|_| CameraError::UpParallel)?;
        let i = up.cross(k);
        if i.length() < 1e-9 {
            return Err(CameraError::UpParallel);
        }
        let i = i.normalize();
        let j = k.cross(i);
        Camera::from_ijk(eye, i, j, k, intrinsics)
    }

    /// The lens centre (CX, CY, CZ).
    pub fn position(&self) -> DVec3 {
        self.pose.position
    }
    /// Unit vector i: image right, in world coordinates.
    pub fn i(&self) -> DVec3 {
        self.pose.rotation * DVec3::X
    }
    /// Unit vector j: image up, in world coordinates.
    pub fn j(&self) -> DVec3 {
        self.pose.rotation * DVec3::Y
    }
    /// Unit vector k: out of the image toward the viewer, in world coordinates.
    pub fn k(&self) -> DVec3 {
        self.pose.rotation * DVec3::Z
    }
    /// The direction the camera looks: −k.
    pub fn view_direction(&self) -> DVec3 {
        -self.k()
    }

    /// World point to camera coordinates (Baumgart's XCC, YCC, ZCC); in front of the
    /// camera ZCC < 0.
    pub fn world_to_camera(&self, p: DVec3) -> DVec3 {
        self.pose.inverse().transform_point(p)
    }

    /// Camera coordinates to a world point.
    pub fn camera_to_world(&self, p: DVec3) -> DVec3 {
        self.pose.transform_point(p)
    }

    /// The pixel a world point projects to, or `None` when it is not in front of the
    /// camera (ZCC ≥ 0). The pixel may lie outside the image.
    pub fn project(&self, p: DVec3) -> Option<DVec2> {
        let c = self.world_to_camera(p);
        if c.z >= 0.0 {
            return None;
        }
        let d = -c.z;
        let k = &self.intrinsics;
        Some(DVec2::new(k.cx + k.fx * c.x / d, k.cy - k.fy * c.y / d))
    }

    /// The unit world direction of the ray from the lens centre through pixel `uv`.
    pub fn pixel_ray(&self, uv: DVec2) -> DVec3 {
        let k = &self.intrinsics;
        let c = DVec3::new((uv.x - k.cx) / k.fx, -(uv.y - k.cy) / k.fy, -1.0);
        self.pose.transform_vector(c).normalize()
    }

    /// The extrinsics in OpenCV's frame (x right, y down, z forward): `(R, t)` with
    /// `x_cv = R·p + t` for a world point `p`. R's rows are i, −j, −k; `t = −R·c`.
    pub fn to_opencv(&self) -> (DMat3, DVec3) {
        let r = DMat3::from_cols(self.i(), -self.j(), -self.k()).transpose();
        (r, -(r * self.position()))
    }

    /// The inverse of [`Camera::to_opencv`]: a camera from OpenCV's `(R, t)` (world to
    /// camera) and intrinsics. Refused unless R is orthonormal and right-handed.
    pub fn from_opencv(r: DMat3, t: DVec3, intrinsics: Intrinsics) -> Result<Camera, CameraError> {
        if !r.is_finite() {
            return Err(CameraError::NonFinite { what: "rotation" });
        }
        if !t.is_finite() {
            return Err(CameraError::NonFinite {
                what: "translation",
            });
        }
        let rt = r.transpose();
        let (i, j, k) = (rt.x_axis, -rt.y_axis, -rt.z_axis);
        Camera::from_ijk(-(rt * t), i, j, k, intrinsics)
    }
}

/// Why a light was refused.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum LightError {
    /// A number is NaN or infinite.
    #[error("the light's {what} is not finite")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// A sun direction of zero length.
    #[error("the sun's direction has zero length")]
    ZeroDirection,
    /// An intensity below zero or above [`MAX_INTENSITY`].
    #[error("light intensity {intensity} is not between 0 and {MAX_INTENSITY}")]
    BadIntensity {
        /// The intensity given.
        intensity: f64,
    },
    /// A point light outside the world's range.
    #[error(transparent)]
    OutOfRange(#[from] RangeError),
}

impl LightError {
    /// Whether the refusal is about the world's range (see [`crate::model::range`]).
    pub fn is_out_of_range(&self) -> bool {
        matches!(self, LightError::OutOfRange(_))
    }
}

/// A light source (Baumgart's SUN for SHADOW, and a point lamp).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Light {
    /// A light at infinity: parallel rays travelling along `direction` (unit, from the
    /// sun toward the scene; a noon sun is `[0, 0, -1]`).
    Sun {
        /// Direction the light travels, unit length.
        direction: DVec3,
        /// Intensity (dimensionless, ≥ 0; 1 is full strength).
        intensity: f64,
    },
    /// A point lamp at `position` (world coordinates, meters).
    Point {
        /// Where the lamp is.
        position: DVec3,
        /// Intensity (dimensionless, ≥ 0; 1 is full strength at 1 m).
        intensity: f64,
    },
}

impl Light {
    /// A checked sun light; `direction` is normalised.
    pub fn sun(direction: DVec3, intensity: f64) -> Result<Light, LightError> {
        Light::Sun {
            direction,
            intensity,
        }
        .validated()
    }

    /// A checked point light.
    pub fn point(position: DVec3, intensity: f64) -> Result<Light, LightError> {
        Light::Point {
            position,
            intensity,
        }
        .validated()
    }

    /// The intensity.
    pub fn intensity(&self) -> f64 {
        match *self {
            Light::Sun { intensity, .. } | Light::Point { intensity, .. } => intensity,
        }
    }

    /// This light checked (finite numbers, nonzero sun direction, intensity from 0 to
    /// [`MAX_INTENSITY`], a point light's position within the world's range), with the
    /// sun direction normalised.
    pub fn validated(&self) -> Result<Light, LightError> {
        let intensity = self.intensity();
        if !intensity.is_finite() {
            return Err(LightError::NonFinite { what: "intensity" });
        }
        if !(0.0..=MAX_INTENSITY).contains(&intensity) {
            return Err(LightError::BadIntensity { intensity });
        }
        match *self {
            Light::Sun { direction, .. } => {
                if !direction.is_finite() {
                    return Err(LightError::NonFinite { what: "direction" });
                }
                // A unit vector keeps its bits, so validating twice changes nothing.
                let direction = range::unit("the sun's direction", direction)
                    .map_err(|_| LightError::ZeroDirection)?;
                Ok(Light::Sun {
                    direction,
                    intensity,
                })
            }
            Light::Point { position, .. } => {
                if !position.is_finite() {
                    return Err(LightError::NonFinite { what: "position" });
                }
                range::coordinate("the light's position", position)?;
                Ok(*self)
            }
        }
    }
}
