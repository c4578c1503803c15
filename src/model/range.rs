//! The world's range: the numbers the model accepts, so that every figure derived from
//! them (areas, volumes, distances, projections) is finite and every world the server
//! accepted can be written, read back and replayed.
//!
//! The rules, which every write of the model keeps and the snapshot loader checks:
//!
//! 1. **Loci**: every vertex's locus, in its body's own frame, lies within
//!    ±[`MAX_COORDINATE`] meters on each axis.
//! 2. **Placements**: every body's origin, in world coordinates, lies within
//!    ±[`MAX_COORDINATE`] on each axis; so do cameras and point lights.
//! 3. **Sizes**: a shape's lengths (a box's sides, a radius, a height, a sweep's
//!    distance) are at least [`MIN_LENGTH`] and at most [`MAX_LENGTH`]; a dilation may
//!    not shrink a body or feature below [`MIN_LENGTH`] across.
//! 4. **Directions** (rotation axes, mirror normals, sun directions, camera frames) are
//!    any finite vector but zero; they are scaled before they are normalised, so a
//!    direction of huge or tiny components is as good as any.
//!
//! Together 1 and 2 keep every vertex within ±[`WORLD_EXTENT`] of the world origin on
//! each axis (a locus turned by its body's rotation reaches √3 times its largest
//! coordinate). Squares of such coordinates are about 10¹⁹, products of three about
//! 10²⁸ and sums of millions of them far below `f64::MAX`, so nothing derived from a
//! world in range overflows.
//!
//! Queries, which change nothing, accept points out to ±[`QUERY_LIMIT`]; a body made by
//! one write (a shape, a polyhedron, a boolean's result) has at most [`MAX_BODY_FACES`]
//! faces.

use glam::DVec3;

/// The largest coordinate, in meters, of a vertex locus in its body's frame and of a
/// body's, camera's or point light's position in the world: a million kilometers.
pub const MAX_COORDINATE: f64 = 1e9;

/// The smallest length, in meters, of a shape's size parameters and of a dilated
/// body's extent: a nanometer.
pub const MIN_LENGTH: f64 = 1e-9;

/// The largest length, in meters, of a shape's size parameters: the width of the range.
pub const MAX_LENGTH: f64 = 2.0 * MAX_COORDINATE;

/// How far from the world origin, along each axis, a vertex can be: a body origin at
/// [`MAX_COORDINATE`] plus a locus of [`MAX_COORDINATE`] on every axis turned onto one.
pub const WORLD_EXTENT: f64 = MAX_COORDINATE * (1.0 + 1.732_050_807_568_877_2);

/// The largest coordinate, in meters, a spatial query's centre, point or origin may
/// have. A box's corners and a radius may be larger: they are clamped, which changes no
/// answer, since nothing lies beyond [`WORLD_EXTENT`].
pub const QUERY_LIMIT: f64 = 1e12;

/// The most faces a body made by one write may have (for a boolean, all the pieces of
/// its result together).
pub const MAX_BODY_FACES: usize = 2_000_000;

/// Why a number is outside the range.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum RangeError {
    /// A NaN or infinite number.
    #[error("{what} is not a finite number")]
    NotFinite {
        /// What the number is.
        what: &'static str,
    },
    /// A coordinate farther out than the limit.
    #[error("{what} has a coordinate of {value:e} m, beyond the range of ±{limit:e} m")]
    Beyond {
        /// What the point is.
        what: &'static str,
        /// The coordinate farthest out.
        value: f64,
        /// The limit it passes.
        limit: f64,
    },
    /// A length below [`MIN_LENGTH`].
    #[error("{what} is {value:e} m, below the smallest length of {MIN_LENGTH:e} m")]
    TooSmall {
        /// What the length is.
        what: &'static str,
        /// The length.
        value: f64,
    },
    /// A length above [`MAX_LENGTH`].
    #[error("{what} is {value:e} m, above the largest length of {MAX_LENGTH:e} m")]
    TooLarge {
        /// What the length is.
        what: &'static str,
        /// The length.
        value: f64,
    },
    /// A direction of zero length.
    #[error("{what} has zero length")]
    ZeroVector {
        /// What the direction is.
        what: &'static str,
    },
}

/// The coordinate of `p` farthest from zero (its largest absolute component); NaN if a
/// component is NaN.
#[inline]
pub fn reach(p: DVec3) -> f64 {
    p.x.abs().max(p.y.abs()).max(p.z.abs())
}

/// Whether every coordinate of `p` is finite and within ±`limit`.
#[inline]
pub fn is_within(p: DVec3, limit: f64) -> bool {
    // Written so that NaN fails.
    p.x.abs() <= limit && p.y.abs() <= limit && p.z.abs() <= limit
}

/// `p`, if its coordinates are finite and within ±`limit`.
pub fn point_within(what: &'static str, p: DVec3, limit: f64) -> Result<DVec3, RangeError> {
    if !p.is_finite() {
        return Err(RangeError::NotFinite { what });
    }
    if is_within(p, limit) {
        Ok(p)
    } else {
        Err(RangeError::Beyond {
            what,
            value: farthest(p),
            limit,
        })
    }
}

/// `p`, if it is a locus or position in range (rules 1 and 2): finite, within
/// ±[`MAX_COORDINATE`] on each axis.
pub fn coordinate(what: &'static str, p: DVec3) -> Result<DVec3, RangeError> {
    point_within(what, p, MAX_COORDINATE)
}

/// `x`, if it is a length in range (rule 3): finite, at least [`MIN_LENGTH`], at most
/// [`MAX_LENGTH`].
pub fn length(what: &'static str, x: f64) -> Result<f64, RangeError> {
    if !x.is_finite() {
        return Err(RangeError::NotFinite { what });
    }
    if x < MIN_LENGTH {
        return Err(RangeError::TooSmall { what, value: x });
    }
    if x > MAX_LENGTH {
        return Err(RangeError::TooLarge { what, value: x });
    }
    Ok(x)
}

/// The unit vector along `v` (rule 4), for any finite `v` but zero: `v` is first scaled
/// by its largest component, so neither its length nor its square can overflow or
/// vanish. A unit vector comes back with its bits unchanged, so normalising twice
/// changes nothing.
pub fn unit(what: &'static str, v: DVec3) -> Result<DVec3, RangeError> {
    if !v.is_finite() {
        return Err(RangeError::NotFinite { what });
    }
    let m = reach(v);
    if m == 0.0 {
        return Err(RangeError::ZeroVector { what });
    }
    if (v.length_squared() - 1.0).abs() <= 4.0 * f64::EPSILON {
        return Ok(v);
    }
    let scaled = v / m;
    Ok(scaled / scaled.length())
}

/// The Euclidean length of `v`, computed without overflow or underflow on the way
/// (`v` scaled by its largest component first). Infinite only if `v` is.
pub fn norm(v: DVec3) -> f64 {
    let m = reach(v);
    if m == 0.0 || !m.is_finite() {
        return m;
    }
    m * (v / m).length()
}

/// The signed coordinate of `p` with the largest magnitude (NaN first).
fn farthest(p: DVec3) -> f64 {
    let mut best = p.x;
    for c in [p.y, p.z] {
        if c.is_nan() || c.abs() > best.abs() {
            best = c;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coordinates_are_bounded_on_each_axis() {
        assert!(coordinate("p", DVec3::splat(MAX_COORDINATE)).is_ok());
        assert!(coordinate("p", DVec3::new(0.0, -MAX_COORDINATE, 0.0)).is_ok());
        assert_eq!(
            coordinate("p", DVec3::new(0.0, -8e307, 1.0)),
            Err(RangeError::Beyond {
                what: "p",
                value: -8e307,
                limit: MAX_COORDINATE
            })
        );
        assert_eq!(
            coordinate("p", DVec3::new(f64::NAN, 0.0, 0.0)),
            Err(RangeError::NotFinite { what: "p" })
        );
        assert!(!is_within(DVec3::new(f64::NAN, 0.0, 0.0), 1.0));
    }

    #[test]
    fn lengths_have_a_floor_and_a_ceiling() {
        assert_eq!(length("size", 1.0), Ok(1.0));
        assert_eq!(length("size", MIN_LENGTH), Ok(MIN_LENGTH));
        assert!(matches!(
            length("size", 1e-12),
            Err(RangeError::TooSmall { .. })
        ));
        assert!(matches!(
            length("size", 0.0),
            Err(RangeError::TooSmall { .. })
        ));
        assert!(matches!(
            length("size", -1.0),
            Err(RangeError::TooSmall { .. })
        ));
        assert!(matches!(
            length("size", 1e308),
            Err(RangeError::TooLarge { .. })
        ));
        assert!(matches!(
            length("size", f64::INFINITY),
            Err(RangeError::NotFinite { .. })
        ));
    }

    #[test]
    fn directions_of_any_magnitude_normalise() {
        // Its squared length overflows: a plain normalisation gives zero or NaN.
        let huge = unit("axis", DVec3::new(-6e16, 1.5e158, -6.6e15)).unwrap();
        assert!((huge - DVec3::Y).length() < 1e-12, "{huge}");
        // Its squared length underflows to zero.
        let tiny = unit("axis", DVec3::new(0.0, 3e-200, 4e-200)).unwrap();
        assert!(
            (tiny - DVec3::new(0.0, 0.6, 0.8)).length() < 1e-15,
            "{tiny}"
        );
        let u = DVec3::new(0.6, 0.8, 0.0);
        assert_eq!(unit("axis", u).unwrap().to_array(), u.to_array());
        assert_eq!(
            unit("axis", DVec3::ZERO),
            Err(RangeError::ZeroVector { what: "axis" })
        );
        assert!(matches!(
            unit("axis", DVec3::new(f64::INFINITY, 0.0, 0.0)),
            Err(RangeError::NotFinite { .. })
        ));
    }

    #[test]
    fn norms_neither_overflow_nor_vanish() {
        assert_eq!(norm(DVec3::new(3e300, 4e300, 0.0)), 5e300);
        assert!((norm(DVec3::new(0.0, 3e-200, 4e-200)) - 5e-200).abs() < 1e-214);
        assert_eq!(norm(DVec3::ZERO), 0.0);
    }

    #[test]
    fn the_world_extent_bounds_a_turned_locus_on_a_far_origin() {
        let corner = DVec3::splat(MAX_COORDINATE);
        let onto_x = glam::DQuat::from_rotation_arc(corner.normalize(), DVec3::X);
        let p = DVec3::splat(MAX_COORDINATE) + onto_x * corner;
        assert!(reach(p) <= WORLD_EXTENT * (1.0 + 1e-15), "{p}");
        assert!(reach(p) >= WORLD_EXTENT * (1.0 - 1e-12), "{p}");
    }
}
