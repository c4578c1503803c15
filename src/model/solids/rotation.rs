//! Solids of rotation: a profile polyline in the (r, z) half plane swept around the z
//! axis, and the cylinder, cone, sphere and torus made that way.
//!
//! Where WINGED.DOC sweeps a wire into a shell face and completes it with ROTCOM, the
//! rotation solids here are laid out directly as vertex and face lists and built with
//! [`Body::from_polygons`]: the result is the same polyhedron, made in one pass.
//!
//! Profile point `j = (r, z)` becomes a ring of `segments` vertices at
//! `(r cos θk, r sin θk, z)`, `θk = 2πk/segments`, or, when `r = 0`, a single pole.
//! Each profile segment becomes a band of quadrilaterals (triangles next to a pole). An
//! open profile whose end is off the axis is closed there by a flat cap, one face with
//! `segments` edges.
//!
//! The quadrilateral between profile points `j`, `j+1` and meridians `k`, `k+1` is an
//! isosceles trapezoid, so every face is planar. The polyhedron's volume is exactly
//! `segments·sin(2π/segments)/(2π)` times the volume of the smooth solid swept by the
//! same polygonal profile, since each band is a frustum of a pyramid over a regular
//! polygon.

use glam::{DVec2, DVec3};

use super::error::{PolygonFault, SolidError, at_least, length};
use super::sweep::{MAX_POLYGON_POINTS, simple_polygon};
use crate::model::body::Body;
use crate::model::ids::Serials;

/// The most faces a rotation solid may have; more is refused with
/// [`SolidError::TooManyElements`] before anything is allocated.
pub const MAX_SWEEP_FACES: u128 = 10_000_000;

/// Sweeps `profile`, points `(r, z)` with `r ≥ 0`, around the z axis in `segments`
/// steps.
///
/// * `closed = false`: an open polyline. Its ends may lie on the axis (they become
///   poles, each with a fan of triangles) or off it (closed by a flat cap). The region
///   swept is the one bounded by the profile and the axis.
/// * `closed = true`: a closed polygon (the last point joins the first), wholly off the
///   axis: the solid has a handle (a torus-like ring).
///
/// The profile may run either way round; the faces always come out counter-clockwise
/// seen from outside. Faces: `segments` per profile segment, plus the caps.
///
/// Preconditions (refused otherwise, before anything is made): `segments ≥ 3`; at least
/// 2 points (3 when closed) and at most [`MAX_POLYGON_POINTS`]; finite coordinates;
/// `r ≥ 0`, and `r > 0` except at the ends of an open profile; the profile together
/// with its closing segments (along the caps and the axis) is a simple polygon of
/// non-zero area; at most [`MAX_SWEEP_FACES`] faces.
///
/// Serial numbers are taken as [`Body::from_polygons`] takes them: vertices (profile
/// point by point, each ring by increasing angle), then faces, then edges.
pub fn rotation_sweep(
    serials: &mut Serials,
    profile: &[DVec2],
    segments: usize,
    closed: bool,
) -> Result<Body, SolidError> {
    at_least("segments", segments, 3)?;
    let m = profile.len();
    let min = if closed { 3 } else { 2 };
    if m < min {
        return Err(SolidError::Profile(PolygonFault::TooFewPoints {
            count: m,
            min,
        }));
    }
    if m > MAX_POLYGON_POINTS {
        return Err(SolidError::Profile(PolygonFault::TooManyPoints {
            count: m,
            limit: MAX_POLYGON_POINTS,
        }));
    }
    if let Some(index) = profile.iter().position(|p| !p.is_finite()) {
        return Err(SolidError::Profile(PolygonFault::NotFinite { index }));
    }
    if let Some(index) = profile.iter().position(|p| p.x < 0.0) {
        return Err(SolidError::Profile(PolygonFault::NegativeRadius { index }));
    }
    let is_end = |i: usize| !closed && (i == 0 || i == m - 1);
    if let Some(index) = (0..m).find(|&i| profile[i].x == 0.0 && !is_end(i)) {
        return Err(SolidError::Profile(PolygonFault::OnAxis { index }));
    }
    let (first, last) = (profile[0], profile[m - 1]);
    let bands = if closed { m } else { m - 1 };
    let caps = if closed {
        0
    } else {
        usize::from(first.x > 0.0) + usize::from(last.x > 0.0)
    };
    let faces = segments as u128 * bands as u128 + caps as u128;
    if faces > MAX_SWEEP_FACES {
        return Err(SolidError::TooManyElements {
            what: "faces",
            count: faces,
            limit: MAX_SWEEP_FACES,
        });
    }
    // The region swept: the profile closed along the caps and the axis.
    let mut outline = profile.to_vec();
    if !closed {
        if last.x > 0.0 {
            outline.push(DVec2::new(0.0, last.y));
        }
        if first.x > 0.0 {
            outline.push(DVec2::new(0.0, first.y));
        }
    }
    let twice_area =
        simple_polygon(&outline, MAX_POLYGON_POINTS + 2).map_err(SolidError::Profile)?;
    // Counter-clockwise in the (r, z) plane keeps the region on the profile's left,
    // which makes the faces below counter-clockwise seen from outside.
    let mut pts = profile.to_vec();
    if twice_area < 0.0 {
        pts.reverse();
    }
    let (positions, face_list) = layout(&pts, segments, closed);
    Ok(Body::from_polygons(serials, &positions, &face_list)?)
}

/// The vertex and face lists of a checked, counter-clockwise profile.
fn layout(pts: &[DVec2], n: usize, closed: bool) -> (Vec<DVec3>, Vec<Vec<u32>>) {
    let m = pts.len();
    let angles: Vec<(f64, f64)> = (0..n)
        .map(|k| (std::f64::consts::TAU * k as f64 / n as f64).sin_cos())
        .collect();
    // First vertex index of each profile point's ring (or its pole).
    let mut start = Vec::with_capacity(m);
    let mut positions = Vec::new();
    for p in pts {
        start.push(positions.len() as u32);
        if p.x == 0.0 {
            positions.push(DVec3::new(0.0, 0.0, p.y));
        } else {
            positions.extend(
                angles
                    .iter()
                    .map(|&(s, c)| DVec3::new(p.x * c, p.x * s, p.y)),
            );
        }
    }
    let pole = |j: usize| pts[j].x == 0.0;
    let idx = |j: usize, k: usize| {
        if pole(j) {
            start[j]
        } else {
            start[j] + (k % n) as u32
        }
    };
    let bands = if closed { m } else { m - 1 };
    let mut faces: Vec<Vec<u32>> = Vec::with_capacity(n * bands + 2);
    for j in 0..bands {
        let j1 = (j + 1) % m;
        for k in 0..n {
            let k1 = k + 1;
            faces.push(if pole(j) {
                vec![idx(j, 0), idx(j1, k1), idx(j1, k)]
            } else if pole(j1) {
                vec![idx(j, k), idx(j, k1), idx(j1, 0)]
            } else {
                vec![idx(j, k), idx(j, k1), idx(j1, k1), idx(j1, k)]
            });
        }
    }
    if !closed {
        // The first point's cap has the region above it (faces down): clockwise seen
        // from above. The last point's cap faces up.
        if !pole(0) {
            faces.push((0..n).rev().map(|k| idx(0, k)).collect());
        }
        if !pole(m - 1) {
            faces.push((0..n).map(|k| idx(m - 1, k)).collect());
        }
    }
    (positions, faces)
}

/// A cylinder of `radius` and `height`, axis on z, centred on the origin: the prism over
/// a regular `segments`-gon inscribed in the circle, with one vertex on +x. F = n + 2,
/// E = 3n, V = 2n; volume `n/2·r²·sin(2π/n)·h`.
///
/// Preconditions: `radius`, `height` lengths in the world's range (finite, at least
/// [`crate::model::range::MIN_LENGTH`], at most [`crate::model::range::MAX_LENGTH`]);
/// `3 ≤ segments`, and at most [`MAX_SWEEP_FACES`] faces.
pub fn cylinder(
    serials: &mut Serials,
    radius: f64,
    height: f64,
    segments: usize,
) -> Result<Body, SolidError> {
    let r = length("radius", radius)?;
    let h = length("height", height)? / 2.0;
    rotation_sweep(
        serials,
        &[DVec2::new(r, -h), DVec2::new(r, h)],
        segments,
        false,
    )
}

/// A cone of base `radius` and `height`, axis on z, centred in height (base at
/// `−height/2`, apex at `+height/2`): the pyramid over a regular `segments`-gon.
/// F = n + 1, E = 2n, V = n + 1; volume `n/6·r²·sin(2π/n)·h`.
///
/// Preconditions: as for [`cylinder`].
pub fn cone(
    serials: &mut Serials,
    radius: f64,
    height: f64,
    segments: usize,
) -> Result<Body, SolidError> {
    let r = length("radius", radius)?;
    let h = length("height", height)? / 2.0;
    rotation_sweep(
        serials,
        &[DVec2::new(r, -h), DVec2::new(0.0, h)],
        segments,
        false,
    )
}

/// A sphere of `radius` centred on the origin, its vertices on the sphere: `segments`
/// meridians and `rings` bands of latitude between the poles (so `rings − 1` circles of
/// latitude, evenly spaced in angle, and triangle fans at the poles).
/// F = n·rings, E = n·(2·rings − 1), V = n·(rings − 1) + 2.
///
/// Preconditions: `radius` a length in the world's range; `segments ≥ 3`, `rings ≥ 2`;
/// `rings < MAX_POLYGON_POINTS`; at most [`MAX_SWEEP_FACES`] faces.
pub fn sphere(
    serials: &mut Serials,
    radius: f64,
    segments: usize,
    rings: usize,
) -> Result<Body, SolidError> {
    let r = length("radius", radius)?;
    at_least("segments", segments, 3)?;
    at_least("rings", rings, 2)?;
    check_grid(segments, rings, rings + 1)?;
    let mut profile = Vec::with_capacity(rings + 1);
    profile.push(DVec2::new(0.0, -r));
    for j in 1..rings {
        let lat = -std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * j as f64 / rings as f64;
        let (s, c) = lat.sin_cos();
        profile.push(DVec2::new(r * c, r * s));
    }
    profile.push(DVec2::new(0.0, r));
    rotation_sweep(serials, &profile, segments, false)
}

/// A torus around the z axis centred on the origin: its tube's centre line is the
/// circle of `major_radius` in the xy plane, its cross-section a regular `rings`-gon
/// inscribed in the circle of `minor_radius` (one vertex on the outer equator).
/// `segments` steps around the axis. F = n·rings, E = 2·n·rings, V = n·rings, one
/// handle.
///
/// Preconditions: radii lengths in the world's range, `minor_radius < major_radius`;
/// `segments ≥ 3`, `rings ≥ 3`, `rings ≤ MAX_POLYGON_POINTS`; at most
/// [`MAX_SWEEP_FACES`] faces.
pub fn torus(
    serials: &mut Serials,
    major_radius: f64,
    minor_radius: f64,
    segments: usize,
    rings: usize,
) -> Result<Body, SolidError> {
    let major = length("major_radius", major_radius)?;
    let minor = length("minor_radius", minor_radius)?;
    if minor >= major {
        return Err(SolidError::MinorNotBelowMajor { minor, major });
    }
    at_least("segments", segments, 3)?;
    at_least("rings", rings, 3)?;
    check_grid(segments, rings, rings)?;
    let profile: Vec<DVec2> = (0..rings)
        .map(|j| {
            let (s, c) = (std::f64::consts::TAU * j as f64 / rings as f64).sin_cos();
            DVec2::new(major + minor * c, minor * s)
        })
        .collect();
    rotation_sweep(serials, &profile, segments, true)
}

/// Refuses grids too large before their profile is allocated.
fn check_grid(segments: usize, rings: usize, points: usize) -> Result<(), SolidError> {
    let faces = segments as u128 * rings as u128;
    if faces > MAX_SWEEP_FACES {
        return Err(SolidError::TooManyElements {
            what: "faces",
            count: faces,
            limit: MAX_SWEEP_FACES,
        });
    }
    if points > MAX_POLYGON_POINTS {
        return Err(SolidError::TooManyElements {
            what: "profile points",
            count: points as u128,
            limit: MAX_POLYGON_POINTS as u128,
        });
    }
    Ok(())
}
