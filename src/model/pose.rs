//! Poses: a rigid placement (position and unit-quaternion rotation) of one frame in
//! another.
//!
//! In the parts tree a body's pose places the body's own frame (in which its vertex loci
//! are given) in the frame of its supart; the body's world pose is the composition of the
//! poses on the path from the world body down to it. A camera's pose places the camera
//! frame (Baumgart's i, j, k) in the world.
//!
//! A pose `P` maps a point `x` given in the child frame to `P(x) = rotation · x + position`
//! in the parent frame. Composition follows the tree: if `A` places frame 1 in frame 0 and
//! `B` places frame 2 in frame 1, then `A.compose(&B)` (also written `A * B`) places frame
//! 2 in frame 0, and `(A * B)(x) = A(B(x))`.

use std::ops::Mul;

use glam::{DAffine3, DMat3, DQuat, DVec3};
use serde::{Deserialize, Serialize};

/// The smallest quaternion length that [`Pose::new`] will normalise; anything shorter
/// (or non-finite) names no rotation.
pub const MIN_QUATERNION_LENGTH: f64 = 1e-9;

/// Why a pose was refused.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum PoseError {
    /// A position or rotation component is NaN or infinite.
    #[error("the pose's {what} has a component that is not a finite number")]
    NonFinite {
        /// "position" or "rotation".
        what: &'static str,
    },
    /// The rotation quaternion is (nearly) zero, so it names no rotation.
    #[error("the rotation quaternion has length {length}, too small to normalise")]
    ZeroRotation {
        /// Its length.
        length: f64,
    },
}

/// A rigid placement of a child frame in a parent frame: `x ↦ rotation · x + position`.
///
/// Invariant (kept by [`Pose::new`] and every operation here): both parts are finite and
/// `rotation` is a unit quaternion. The fields are public for reading and for building
/// constant poses; a pose assembled by hand from untrusted numbers should go through
/// [`Pose::new`] or [`Pose::validated`]. Read from serde, a missing part is the
/// identity's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Pose {
    /// The child frame's origin, in the parent frame (meters).
    pub position: DVec3,
    /// The child frame's orientation in the parent frame (unit quaternion).
    pub rotation: DQuat,
}

impl Default for Pose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Pose {
    /// The identity: the child frame coincides with the parent frame.
    pub const IDENTITY: Pose = Pose {
        position: DVec3::ZERO,
        rotation: DQuat::IDENTITY,
    };

    /// A checked pose. The quaternion is renormalised to unit length.
    ///
    /// Refused when a component is not finite ([`PoseError::NonFinite`]) or the
    /// quaternion is shorter than [`MIN_QUATERNION_LENGTH`] ([`PoseError::ZeroRotation`]).
    pub fn new(position: DVec3, rotation: DQuat) -> Result<Pose, PoseError> {
        if !position.is_finite() {
            return Err(PoseError::NonFinite { what: "position" });
        }
        if !rotation.is_finite() {
            return Err(PoseError::NonFinite { what: "rotation" });
        }
        // Measured after scaling by the largest component, so that a huge quaternion's
        // length cannot overflow (nor a tiny one's underflow).
        let largest = glam::DVec4::from(rotation).abs().max_element();
        let scaled = if largest > 0.0 {
            rotation / largest
        } else {
            rotation
        };
        let length = largest * scaled.length();
        if length < MIN_QUATERNION_LENGTH {
            return Err(PoseError::ZeroRotation { length });
        }
        // Leave a unit quaternion's bits alone, so validating twice changes nothing.
        let rotation = if (length - 1.0).abs() <= 4.0 * f64::EPSILON {
            rotation
        } else {
            scaled / scaled.length()
        };
        Ok(Pose { position, rotation })
    }

    /// A pure translation. Precondition: `position` is finite (use [`Pose::new`] for
    /// untrusted input).
    pub fn from_translation(position: DVec3) -> Pose {
        Pose {
            position,
            rotation: DQuat::IDENTITY,
        }
    }

    /// A pure rotation about the origin. The quaternion is renormalised; precondition:
    /// it is finite and not zero (use [`Pose::new`] for untrusted input).
    pub fn from_rotation(rotation: DQuat) -> Pose {
        Pose {
            position: DVec3::ZERO,
            rotation: rotation.normalize(),
        }
    }

    /// This pose checked and renormalised, as [`Pose::new`] does.
    pub fn validated(&self) -> Result<Pose, PoseError> {
        Pose::new(self.position, self.rotation)
    }

    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        self.position.is_finite() && self.rotation.is_finite()
    }

    /// `self * child`: places `child`'s child frame in `self`'s parent frame. Applying
    /// the result equals applying `child` and then `self`. Associative; [`Pose::IDENTITY`]
    /// is its unit. The rotation is renormalised so long chains do not drift.
    pub fn compose(&self, child: &Pose) -> Pose {
        Pose {
            position: self.position + self.rotation * child.position,
            rotation: (self.rotation * child.rotation).normalize(),
        }
    }

    /// The inverse placement (parent frame in child frame):
    /// `p.compose(&p.inverse())` and `p.inverse().compose(&p)` are the identity (up to
    /// rounding).
    pub fn inverse(&self) -> Pose {
        let r = self.rotation.conjugate();
        Pose {
            position: -(r * self.position),
            rotation: r,
        }
    }

    /// Maps a point given in the child frame to the parent frame.
    #[inline]
    pub fn transform_point(&self, p: DVec3) -> DVec3 {
        self.rotation * p + self.position
    }

    /// Maps a direction given in the child frame to the parent frame (rotation only).
    #[inline]
    pub fn transform_vector(&self, v: DVec3) -> DVec3 {
        self.rotation * v
    }

    /// The same map as an affine matrix.
    pub fn to_affine(&self) -> DAffine3 {
        DAffine3::from_rotation_translation(self.rotation, self.position)
    }

    /// The rotation as a 3×3 matrix whose columns are the child frame's axes expressed
    /// in the parent frame.
    pub fn rotation_matrix(&self) -> DMat3 {
        DMat3::from_quat(self.rotation)
    }

    /// Whether two poses place the frame at the same place within `position_tol` meters
    /// and `angle_tol` radians (q and −q are the same rotation).
    pub fn approx_eq(&self, other: &Pose, position_tol: f64, angle_tol: f64) -> bool {
        self.position.distance(other.position) <= position_tol && self.angle_to(other) <= angle_tol
    }

    /// The angle (radians, 0 to π) of the rotation taking this pose's orientation to
    /// `other`'s. Computed as `2·atan2(|v|, |w|)` of the relative quaternion, which stays
    /// accurate for tiny angles (unlike `acos` of a dot product).
    pub fn angle_to(&self, other: &Pose) -> f64 {
        let d = self.rotation.conjugate() * other.rotation;
        2.0 * d.xyz().length().atan2(d.w.abs())
    }
}

impl Mul for Pose {
    type Output = Pose;
    /// [`Pose::compose`].
    fn mul(self, rhs: Pose) -> Pose {
        self.compose(&rhs)
    }
}

impl Mul<DVec3> for Pose {
    type Output = DVec3;
    /// [`Pose::transform_point`].
    fn mul(self, rhs: DVec3) -> DVec3 {
        self.transform_point(rhs)
    }
}

impl From<Pose> for DAffine3 {
    fn from(p: Pose) -> DAffine3 {
        p.to_affine()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn compose_applies_the_child_first() {
        let a = Pose::new(DVec3::X, DQuat::from_rotation_z(FRAC_PI_2)).unwrap();
        let b = Pose::from_translation(DVec3::X);
        let p = DVec3::new(0.0, 1.0, 0.0);
        let ab = a * b;
        assert!(ab.transform_point(p).abs_diff_eq(a * (b * p), 1e-12));
        // b moves (0,1,0) to (1,1,0); a turns that to (-1,1,0) and shifts it to (0,1,0).
        assert!(
            ab.transform_point(p)
                .abs_diff_eq(DVec3::new(0.0, 1.0, 0.0), 1e-12)
        );
    }

    #[test]
    fn inverse_undoes() {
        let a = Pose::new(
            DVec3::new(1.0, -2.0, 3.0),
            DQuat::from_xyzw(0.1, 0.2, 0.3, 0.9),
        )
        .unwrap();
        assert!((a * a.inverse()).approx_eq(&Pose::IDENTITY, 1e-12, 1e-7));
        assert!((a.inverse() * a).approx_eq(&Pose::IDENTITY, 1e-12, 1e-7));
        let m = a.to_affine() * a.inverse().to_affine();
        assert!(m.abs_diff_eq(DAffine3::IDENTITY, 1e-12));
    }

    #[test]
    fn new_renormalises_and_refuses_garbage() {
        let p = Pose::new(DVec3::ZERO, DQuat::from_xyzw(0.0, 0.0, 0.0, 2.0)).unwrap();
        assert_eq!(p.rotation, DQuat::IDENTITY);
        assert!(matches!(
            Pose::new(DVec3::new(f64::NAN, 0.0, 0.0), DQuat::IDENTITY),
            Err(PoseError::NonFinite { what: "position" })
        ));
        assert!(matches!(
            Pose::new(DVec3::ZERO, DQuat::from_xyzw(0.0, 0.0, 0.0, f64::INFINITY)),
            Err(PoseError::NonFinite { what: "rotation" })
        ));
        assert!(matches!(
            Pose::new(DVec3::ZERO, DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0)),
            Err(PoseError::ZeroRotation { .. })
        ));
    }
}
