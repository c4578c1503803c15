//! Camera solution: where a camera is, from what it sees.
//!
//! Given points whose world positions are known and the directions (or image positions)
//! in which a calibrated camera sees them, this module finds the camera's rotation and
//! translation. It is pure, synchronous numerics with no I/O:
//!
//! * [`p3p()`]: the minimal solver, Lambda Twist P3P (Persson & Nordberg, ECCV 2018): all
//!   poses (at most four) that put three world points exactly on three viewing rays.
//! * [`sqpnp()`]: the global solver, SQPnP (Terzakis & Lourakis, ECCV 2020): the pose of
//!   least (depth-weighted) squared reprojection error over N ≥ 3 correspondences, planar
//!   or not, found by sequential quadratic programming on the rotations from starts that
//!   provably include the global minimum.
//! * [`refine_pose`]: Levenberg–Marquardt refinement of a pose over N ≥ 3 correspondences,
//!   minimising a robust loss ([`Loss`]) of the reprojection error in
//!   normalised image coordinates.
//! * [`ransac_pnp`]: LO-RANSAC around P3P with adaptive stopping, for N ≥ 4
//!   correspondences of which many may be wrong: the pose with the largest consensus and
//!   its inliers, or [`SolveError::NoConsensus`].
//! * [`solve_pnp`]: the whole solve from pixels with known intrinsics: SQPnP on all the
//!   correspondences, taken as the consensus when it fits every one (else RANSAC), then
//!   refinement on the consensus, the answer in pixels and in OpenCV's `rvec`/`tvec`.
//! * [`solve_pnp_focal`]: the same with the focal length unknown (the principal point
//!   and pixel aspect known): RANSAC over direct linear transforms (or homographies, for
//!   planar points), refinement of pose and focal length together, and a refusal when the
//!   view does not determine the focal length.
//! * [`align_to_image`](align::align_to_image): the camera whose view of the world model
//!   best matches a picture's edges, from a camera roughly known.
//!
//! [`refine_pose`] and [`align_to_image`](align::align_to_image) share one
//! Levenberg–Marquardt driver over the six degrees of freedom of a pose (the private `lm`
//! module): the damped step, the damping's schedule and the stopping rules.
//!
//! # Convention
//!
//! Everything here speaks OpenCV's camera frame: x right, y *down*, z *forward* (points
//! in front of the camera have z > 0). A [`CvPose`] `(R, t)` maps world coordinates to
//! camera coordinates, `x_cam = R·x_world + t`; the camera centre is `c = −Rᵀ·t`. A camera
//! point `(x, y, z)` has normalised image coordinates `(x/z, y/z)` and, with intrinsics
//! `fx, fy, cx, cy`, pixels `u = fx·x/z + cx`, `v = fy·y/z + cy`. This is the frame of
//! [`Camera::to_opencv`](crate::model::camera::Camera::to_opencv) and
//! [`Camera::from_opencv`](crate::model::camera::Camera::from_opencv), which convert to and
//! from the world's own (OpenGL-style) cameras. Note that OpenCV puts integer pixel
//! coordinates at pixel centres (see [`crate::model::camera`]); converting pixels to
//! normalised coordinates is the caller's business, with the intrinsics it trusts.
//!
//! The interface uses glam's `f64` types like the rest of the crate; nalgebra is used
//! inside for the decompositions and solves glam does not have and for SQPnP's 9-vectors,
//! except in SQPnP's eigen-decomposition, 3×3 solves and nearest rotations, which use the
//! fixed-size routines of the private `small` module.

pub mod align;
pub mod focal;
mod lm;
pub mod p3p;
pub mod pnp;
pub mod ransac;
pub mod refine;
mod sampler;
mod small;
pub mod sqpnp;

pub use focal::{FocalSolution, solve_pnp_focal};
pub use p3p::{MAX_P3P_SOLUTIONS, p3p};
pub use pnp::{PixelIntrinsics, PnpOptions, PnpSolution, rotation_vector, solve_pnp};
pub use ransac::{Consensus, LocalOptimisation, MIN_CONSENSUS, RansacOptions, ransac_pnp};
pub use refine::{Loss, MIN_POINTS, RESIDUAL_CAP, RefineOptions, Refined, refine_pose};
pub use sqpnp::{SqpnpMinimum, SqpnpSolution, sqpnp};

use glam::{DMat3, DQuat, DVec2, DVec3};

use crate::model::camera::CameraError;

/// How far from orthonormal (largest entry of `RᵀR − I`) a rotation handed to or returned
/// by this module may be.
pub const ROTATION_TOL: f64 = 1e-6;

/// Why a configuration cannot determine a camera.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Degeneracy {
    /// Two world points coincide (to within rounding of the others' spread).
    CoincidentPoints,
    /// The world points lie on one line.
    CollinearPoints,
    /// A viewing direction is zero, or two viewing directions are (nearly) parallel.
    ParallelBearings,
    /// The points are seen with too little perspective to tell the focal length from
    /// the distance (a plane seen face-on, a small distant cluster).
    FocalUnobservable,
}

impl std::fmt::Display for Degeneracy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Degeneracy::CoincidentPoints => "two world points coincide",
            Degeneracy::CollinearPoints => "the world points lie on one line",
            Degeneracy::ParallelBearings => {
                "a viewing direction is zero or two viewing directions are parallel"
            }
            Degeneracy::FocalUnobservable => {
                "the points are seen with too little perspective to fix the focal length"
            }
        })
    }
}

/// Why a camera could not be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// Fewer correspondences than the solver needs.
    #[error("at least {needed} correspondences are needed (got {got})")]
    TooFewPoints {
        /// The solver's minimum.
        needed: usize,
        /// How many were given.
        got: usize,
    },
    /// The world points and the observations are not paired one to one.
    #[error("{points} world points but {observations} observations")]
    LengthMismatch {
        /// Number of world points.
        points: usize,
        /// Number of observations.
        observations: usize,
    },
    /// The configuration does not determine a camera.
    #[error("degenerate configuration: {0}")]
    Degenerate(Degeneracy),
    /// A number is NaN or infinite, or larger than [`MAX_INPUT`] in magnitude.
    #[error("the {what} must be finite numbers of magnitude at most {max:e}", max = MAX_INPUT)]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// A rotation that is not orthonormal with determinant +1.
    #[error("the rotation is not a rotation (largest error of RᵀR − I is {deviation:e})")]
    NotARotation {
        /// Largest absolute entry of `RᵀR − I`, or infinity for a reflection.
        deviation: f64,
    },
    /// A parameter out of its range (a loss scale that is not positive, say).
    #[error("{what} is out of range (got {value})")]
    BadParameter {
        /// Which parameter.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// No pose agreed with enough correspondences: too many are wrong, or the inlier
    /// threshold is too tight for the noise.
    #[error("no camera agrees with enough correspondences (best {best_inliers}, needed {needed})")]
    NoConsensus {
        /// The largest consensus found (0 when no pose was found at all).
        best_inliers: usize,
        /// The consensus required.
        needed: usize,
    },
    /// No pose the solver found puts the points in front of the camera (the observations
    /// are inconsistent with the world points).
    #[error("no pose puts the points in front of the camera")]
    NoPoseInFront,
    /// An iterative solve stopped without meeting its convergence test.
    #[error("the solve did not converge in {iterations} iterations")]
    DidNotConverge {
        /// Iterations taken.
        iterations: usize,
    },
    /// An image whose samples are not 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA)
    /// bytes per pixel.
    #[error("an image must have 1 to 4 channels (got {channels})")]
    ImageChannels {
        /// The channel count given.
        channels: u8,
    },
    /// An image whose sample buffer does not have width × height × channels bytes.
    #[error("the image needs {expected} samples (width × height × channels), got {got}")]
    ImageSamples {
        /// width × height × channels (`usize::MAX` when that overflows).
        expected: usize,
        /// The samples given.
        got: usize,
    },
    /// An image whose size is not the camera's.
    #[error(
        "the image is {image_width}×{image_height} pixels but the camera's is \
         {camera_width}×{camera_height}"
    )]
    ImageSizeMismatch {
        /// Image width, pixels.
        image_width: u32,
        /// Image height, pixels.
        image_height: u32,
        /// The camera's image width, pixels.
        camera_width: u32,
        /// The camera's image height, pixels.
        camera_height: u32,
    },
    /// The camera handed in is not a valid camera.
    #[error("bad camera: {0}")]
    BadCamera(#[from] CameraError),
    /// The image shows no edges: it is blank, or its contrast is below the noise.
    #[error("the image shows no edges (blank, or too faint for its noise)")]
    NoImageEdges,
    /// Too little of the model's edges is visible from the camera to place it.
    #[error(
        "only {samples} points on the model's visible edges are in view (at least {needed} \
         are needed)"
    )]
    NoEdgesVisible {
        /// Points sampled on the visible edges.
        samples: usize,
        /// The fewest accepted.
        needed: usize,
    },
    /// After alignment too few of the model's visible edges lie on edges of the image:
    /// the image does not show the model from near the starting camera.
    #[error(
        "only {:.1} % of the model's visible edges lie on image edges (at least {:.1} % are \
         needed)", fraction * 100.0, needed * 100.0
    )]
    TooFewInliers {
        /// The fraction of edge samples within the inlier distance of an image edge.
        fraction: f64,
        /// The fraction required.
        needed: f64,
    },
}

impl From<crate::vision::image::ImageError> for SolveError {
    fn from(e: crate::vision::image::ImageError) -> Self {
        use crate::vision::image::ImageError;
        match e {
            ImageError::Channels { channels } => SolveError::ImageChannels { channels },
            ImageError::Samples { expected, got } => SolveError::ImageSamples { expected, got },
            ImageError::BadParameter { what, value } => SolveError::BadParameter { what, value },
        }
    }
}

/// The largest magnitude of a world point's coordinate or an observation's: the
/// spatial query limit of [`crate::model::range`], far past the world's content, and
/// small enough that the solvers' sums of squares cannot overflow.
pub const MAX_INPUT: f64 = crate::model::range::QUERY_LIMIT;

/// Checks correspondences `world[i] ↔ observed[i]`: as many observations as world
/// points ([`SolveError::LengthMismatch`]) and every number finite and at most
/// [`MAX_INPUT`] in magnitude ([`SolveError::NonFinite`]).
pub(crate) fn check_pairs(world: &[DVec3], observed: &[DVec2]) -> Result<(), SolveError> {
    if world.len() != observed.len() {
        return Err(SolveError::LengthMismatch {
            points: world.len(),
            observations: observed.len(),
        });
    }
    let within = |v: f64| v.abs() <= MAX_INPUT;
    if world.iter().any(|x| !x.to_array().into_iter().all(within)) {
        return Err(SolveError::NonFinite {
            what: "world points",
        });
    }
    if observed
        .iter()
        .any(|m| !m.to_array().into_iter().all(within))
    {
        return Err(SolveError::NonFinite {
            what: "observations",
        });
    }
    Ok(())
}

/// A camera pose in OpenCV's convention: `x_cam = rotation·x_world + translation`.
///
/// A pose produced by this module has a proper rotation (orthonormal to within
/// [`ROTATION_TOL`], determinant +1) and finite numbers; one built by hand is checked by
/// [`CvPose::validate`] wherever this module takes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CvPose {
    /// `R`: rows are the camera's x, y, z axes in world coordinates.
    pub rotation: DMat3,
    /// `t`: the world origin in camera coordinates.
    pub translation: DVec3,
}

impl CvPose {
    /// The pose `(rotation, translation)`, unchecked.
    pub fn new(rotation: DMat3, translation: DVec3) -> CvPose {
        CvPose {
            rotation,
            translation,
        }
    }

    /// `Ok` when every number is finite and the rotation is orthonormal to within
    /// [`ROTATION_TOL`] with determinant +1; otherwise [`SolveError::NonFinite`] or
    /// [`SolveError::NotARotation`].
    pub fn validate(&self) -> Result<(), SolveError> {
        if !self.rotation.is_finite() {
            return Err(SolveError::NonFinite { what: "rotation" });
        }
        if !self.translation.is_finite() {
            return Err(SolveError::NonFinite {
                what: "translation",
            });
        }
        let deviation = orthonormality_error(self.rotation);
        if deviation > ROTATION_TOL {
            return Err(SolveError::NotARotation { deviation });
        }
        if self.rotation.determinant() <= 0.0 {
            return Err(SolveError::NotARotation {
                deviation: f64::INFINITY,
            });
        }
        Ok(())
    }

    /// Camera coordinates `R·x_world + t` of a world point.
    pub fn transform(&self, world: DVec3) -> DVec3 {
        self.rotation * world + self.translation
    }

    /// Normalised image coordinates `(x/z, y/z)` of a world point, or `None` when the point
    /// is not in front of the camera (z ≤ 0) or the result is not finite.
    pub fn project(&self, world: DVec3) -> Option<DVec2> {
        let p = self.transform(world);
        if p.z <= 0.0 {
            return None;
        }
        let n = DVec2::new(p.x / p.z, p.y / p.z);
        n.is_finite().then_some(n)
    }

    /// The camera centre in world coordinates, `−Rᵀ·t`.
    pub fn center(&self) -> DVec3 {
        -(self.rotation.transpose() * self.translation)
    }

    /// The angle (radians, in [0, π]) of the rotation `R₁·R₂ᵀ` between this pose's rotation
    /// and `other`'s. Both rotations should be orthonormal.
    pub fn rotation_angle_to(&self, other: &CvPose) -> f64 {
        rotation_angle(self.rotation * other.rotation.transpose())
    }
}

/// Largest absolute entry of `RᵀR − I`.
pub(crate) fn orthonormality_error(r: DMat3) -> f64 {
    let d = r.transpose() * r - DMat3::IDENTITY;
    d.to_cols_array()
        .iter()
        .fold(0.0_f64, |m, &e| m.max(e.abs()))
}

/// The rotation angle (radians) of a (nearly) orthonormal matrix, accurate for small and
/// large angles alike (from the quaternion, not the trace alone).
pub(crate) fn rotation_angle(r: DMat3) -> f64 {
    let q = DQuat::from_mat3(&r).normalize();
    2.0 * q.xyz().length().atan2(q.w.abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_validation_refuses_non_rotations() {
        let good = CvPose::new(DMat3::from_rotation_y(0.3), DVec3::new(0.1, 0.2, 3.0));
        assert_eq!(good.validate(), Ok(()));
        let scaled = CvPose::new(good.rotation * 1.01, good.translation);
        assert!(matches!(
            scaled.validate(),
            Err(SolveError::NotARotation { .. })
        ));
        let reflected = CvPose::new(DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0)), DVec3::Z);
        assert!(matches!(
            reflected.validate(),
            Err(SolveError::NotARotation { .. })
        ));
        let nan = CvPose::new(good.rotation, DVec3::new(f64::NAN, 0.0, 0.0));
        assert!(matches!(nan.validate(), Err(SolveError::NonFinite { .. })));
    }

    #[test]
    fn rotation_angle_is_accurate_small_and_large() {
        for angle in [1e-9, 1e-4, 0.5, 3.0] {
            let a = CvPose::new(
                DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 2.0) / 3.0, angle),
                DVec3::ZERO,
            );
            let b = CvPose::new(DMat3::IDENTITY, DVec3::ZERO);
            let got = a.rotation_angle_to(&b);
            assert!(
                (got - angle).abs() < 1e-12 * angle.max(1.0),
                "{angle}: {got}"
            );
        }
    }

    #[test]
    fn center_and_projection_follow_the_opencv_convention() {
        let pose = CvPose::new(DMat3::from_rotation_z(0.4), DVec3::new(0.5, -0.25, 4.0));
        let c = pose.center();
        assert!(pose.transform(c).length() < 1e-12);
        let ahead = pose.rotation.transpose() * (DVec3::new(0.2, -0.1, 2.0) - pose.translation);
        let n = pose.project(ahead).unwrap();
        assert!((n - DVec2::new(0.1, -0.05)).length() < 1e-12);
        let behind = pose.rotation.transpose() * (DVec3::new(0.0, 0.0, -1.0) - pose.translation);
        assert_eq!(pose.project(behind), None);
    }
}
