//! Why a solid primitive refused, and the parameter checks the primitives share.

use crate::model::euler::EulerError;
use crate::model::ids::Serial;
use crate::model::range::{self, RangeError};

use super::polyhedron::BuildError;

/// Why a solid primitive (sweep, rotation solid, box, lamina, dual) refused.
///
/// Every primitive checks all of its input before it changes a body or takes a serial
/// number, so a refusal leaves the body exactly as it was. Entities are named by their
/// serial numbers; polygon and profile points by their index in the input list.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolidError {
    /// An Euler-level precondition failed: an unknown face, a face that is not a simple
    /// polygon ([`EulerError::FaceNotSimple`]) or has too few edges
    /// ([`EulerError::FaceTooSmall`]).
    #[error(transparent)]
    Euler(#[from] EulerError),
    /// Building from vertex and face lists refused (not expected from the primitives,
    /// whose lists are checked beforehand).
    #[error(transparent)]
    Build(#[from] BuildError),
    /// A number is NaN or infinite.
    #[error("{parameter} is not a finite number")]
    NotFinite {
        /// Which parameter.
        parameter: &'static str,
    },
    /// A size or a new locus outside the world's range (see [`crate::model::range`]).
    #[error(transparent)]
    OutOfRange(#[from] RangeError),
    /// A length, radius or scale that must be above zero.
    #[error("{parameter} must be above zero, not {value}")]
    NotPositive {
        /// Which parameter.
        parameter: &'static str,
        /// The value given.
        value: f64,
    },
    /// A count (segments, rings) below its minimum.
    #[error("{parameter} must be at least {min}, not {value}")]
    TooFew {
        /// Which parameter.
        parameter: &'static str,
        /// The value given.
        value: usize,
        /// The smallest value accepted.
        min: usize,
    },
    /// The torus's tube would cross the axis.
    #[error("the minor radius {minor} must be below the major radius {major}")]
    MinorNotBelowMajor {
        /// The minor (tube) radius.
        minor: f64,
        /// The major (centre-line) radius.
        major: f64,
    },
    /// The solid would have more elements than a primitive makes.
    #[error("{what} would be {count}, above the limit of {limit}")]
    TooManyElements {
        /// What was counted.
        what: &'static str,
        /// How many there would be.
        count: u128,
        /// The limit.
        limit: u128,
    },
    /// A sweep offset of zero length.
    #[error("the sweep offset is zero")]
    ZeroOffset,
    /// A sweep offset that does not leave the face on its outer side.
    #[error(
        "the sweep offset must point out of face {face}: its component along the outward normal is {along_normal:e}"
    )]
    OffsetNotOutward {
        /// The face.
        face: Serial,
        /// offset · outward unit normal.
        along_normal: f64,
    },
    /// A pyramid peak that is not strictly above the face.
    #[error("the peak must lie above face {face}: it is {distance:e} m from the face's plane")]
    PeakNotAbove {
        /// The face.
        face: Serial,
        /// Signed distance of the peak from the face's plane (positive outside).
        distance: f64,
    },
    /// A face of zero area: it has no plane to sweep from or to dualise through.
    #[error("face {face} has zero area, so it has no plane")]
    DegenerateFace {
        /// The face.
        face: Serial,
    },
    /// A prismoid turning angle out of range.
    #[error("the turning angle {angle} must be at least 0 and below pi")]
    TurnAngle {
        /// The angle given (radians).
        angle: f64,
    },
    /// A polygon (lamina, prism or pyramid base) that is not a simple polygon.
    #[error("bad polygon: {0}")]
    Polygon(PolygonFault),
    /// A rotation profile that does not bound a simple region of the half plane r ≥ 0.
    #[error("bad profile: {0}")]
    Profile(PolygonFault),
    /// FVDUAL of an edge with the same face on both sides (a wire or a spur) would be a
    /// loop edge.
    #[error("edge {edge} has face {face} on both sides: its dual would be a loop")]
    DualLoop {
        /// The edge.
        edge: Serial,
        /// The face on both sides.
        face: Serial,
    },
    /// The polar dual needs every face plane to pass strictly outside the polar centre.
    #[error(
        "face {face}'s plane passes {distance:e} m from the polar centre on the wrong side; the centre must be strictly inside every face plane"
    )]
    PolarCenter {
        /// The face.
        face: Serial,
        /// Signed distance of the centre below the face plane (must be above zero).
        distance: f64,
    },
}

impl SolidError {
    /// Whether the refusal is about the world's range (see [`crate::model::range`]).
    pub fn is_out_of_range(&self) -> bool {
        match self {
            SolidError::OutOfRange(_) => true,
            SolidError::Euler(e) => e.is_out_of_range(),
            SolidError::Build(e) => e.is_out_of_range(),
            _ => false,
        }
    }
}

/// What is wrong with a polygon or a rotation profile.
///
/// A polygon's segment `k` runs from point `k` to point `k + 1` (the last one back to
/// point 0). A profile is checked as the closed polygon it bounds together with the
/// axis: segments past the profile's own are the implicit closing segments along the
/// end caps and the axis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PolygonFault {
    /// Too few points.
    #[error("{count} points given; at least {min} are needed")]
    TooFewPoints {
        /// Points given.
        count: usize,
        /// The minimum.
        min: usize,
    },
    /// Too many points for the quadratic simplicity check.
    #[error("{count} points given; at most {limit} are accepted")]
    TooManyPoints {
        /// Points given.
        count: usize,
        /// The limit.
        limit: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("point {index} has a coordinate that is not a finite number")]
    NotFinite {
        /// The point.
        index: usize,
    },
    /// A profile point with a negative radius (left of the axis).
    #[error("point {index} has a negative radius")]
    NegativeRadius {
        /// The point.
        index: usize,
    },
    /// A profile point on the axis that is not an end of an open profile: the solid
    /// would be pinched to a point there.
    #[error("point {index} lies on the axis; only the ends of an open profile may")]
    OnAxis {
        /// The point.
        index: usize,
    },
    /// A point equal to the next one: a segment of zero length.
    #[error("segment {index} has zero length")]
    ZeroLengthSegment {
        /// The segment.
        index: usize,
    },
    /// Two segments cross, touch or overlap.
    #[error("segments {a} and {b} cross or touch")]
    Crossing {
        /// One segment.
        a: usize,
        /// The other.
        b: usize,
    },
    /// The polygon encloses no area.
    #[error("the polygon encloses no area")]
    ZeroArea,
    /// The polygon is not star-shaped about its centroid, so a pyramid over the
    /// centroid would fold.
    #[error(
        "segment {index} faces away from the centroid: the polygon is not star-shaped about it"
    )]
    NotStarShaped {
        /// The first offending segment.
        index: usize,
    },
}

/// `value`, if it is finite; [`SolidError::NotFinite`] otherwise.
pub(crate) fn finite(parameter: &'static str, value: f64) -> Result<f64, SolidError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(SolidError::NotFinite { parameter })
    }
}

/// `value`, if it is finite and above zero.
pub(crate) fn positive(parameter: &'static str, value: f64) -> Result<f64, SolidError> {
    if finite(parameter, value)? > 0.0 {
        Ok(value)
    } else {
        Err(SolidError::NotPositive { parameter, value })
    }
}

/// `value`, if it is a length above zero within the world's range: at least
/// [`range::MIN_LENGTH`] and at most [`range::MAX_LENGTH`].
pub(crate) fn length(parameter: &'static str, value: f64) -> Result<f64, SolidError> {
    positive(parameter, value)?;
    Ok(range::length(parameter, value)?)
}

/// `value`, if it is at least `min`.
pub(crate) fn at_least(
    parameter: &'static str,
    value: usize,
    min: usize,
) -> Result<usize, SolidError> {
    if value >= min {
        Ok(value)
    } else {
        Err(SolidError::TooFew {
            parameter,
            value,
            min,
        })
    }
}
