//! MKTETRA: the regular tetrahedron built through the Euler operators, as in the seeds.

use glam::{DQuat, DVec3};

use crate::model::body::Body;
use crate::model::euler::EulerError;
use crate::model::ids::Serials;

/// MKTETRA(R): a regular tetrahedron with its vertices at distance `r` from the origin,
/// apex up, made as GEOMED's example 4 makes it: a wire of three edges around the base
/// and up to the apex, closed into a skew quadrilateral lamina by MKFE, then split by two
/// more MKFEs. F = 4, E = 6, V = 4.
pub fn mktetra(serials: &mut Serials, r: f64) -> Result<Body, EulerError> {
    let r = r.abs();
    let third = DQuat::from_rotation_z(2.0 * std::f64::consts::PI / 3.0);
    let p1 = DVec3::new(r * (8.0f64).sqrt() / 3.0, 0.0, -r / 3.0);
    let (mut b, f1, v1) = Body::seminal(serials, p1);
    let (_, v2) = b.mkev(serials, f1, v1, third * p1)?;
    let (_, v3) = b.mkev(serials, f1, v2, third * third * p1)?;
    let (_, v4) = b.mkev(serials, f1, v3, DVec3::new(0.0, 0.0, r))?;
    let (_, f2) = b.mkfe(serials, v1, f1, v4)?;
    b.mkfe(serials, v1, f1, v3)?;
    b.mkfe(serials, v2, f2, v4)?;
    Ok(b)
}
