//! The box families: (a) integer-grid boxes and (b) turned and nudged boxes.

use glam::{DAffine3, DQuat, DVec3, IVec3};
use winged::model::Serials;
use winged::model::solids::{SolidError, box_solid};

use super::super::draw::Draw;
use super::super::rng::Rng;
use super::super::shapes::{grid_box, turn_about};
use super::{Case, pair};

/// A random grid box inside 0..=4 on every axis.
fn random_grid_box(rng: &mut Rng) -> (IVec3, IVec3) {
    let mut lo = IVec3::ZERO;
    let mut hi = IVec3::ZERO;
    for k in 0..3 {
        lo[k] = rng.int(0, 3) as i32;
        hi[k] = rng.int(i64::from(lo[k]) + 1, 4) as i32;
    }
    (lo, hi)
}

/// (a) Two boxes with integer corners in 0..=4: independent, touching A from outside
/// on one to three axes (sharing a face, an edge or a vertex), inside A, or equal to A.
pub(super) fn grid(rng: &mut Rng, serials: &mut Serials) -> Result<Case, SolidError> {
    let (alo, ahi) = random_grid_box(rng);
    let (mut blo, mut bhi) = random_grid_box(rng);
    let kind = rng.below(8);
    let what = match kind {
        0..=3 => "independent",
        4 | 5 => {
            // Touch A from outside across a random set of one to three axes.
            let axes = rng.int(1, 7) as usize;
            for k in (0..3).filter(|k| axes & (1 << k) != 0) {
                if ahi[k] < 4 && (alo[k] == 0 || rng.chance(0.5)) {
                    blo[k] = ahi[k];
                    bhi[k] = rng.int(i64::from(blo[k]) + 1, 4) as i32;
                } else if alo[k] > 0 {
                    bhi[k] = alo[k];
                    blo[k] = rng.int(0, i64::from(bhi[k]) - 1) as i32;
                }
            }
            "touching"
        }
        6 => {
            // Inside A (often sharing faces with it).
            for k in 0..3 {
                blo[k] = rng.int(i64::from(alo[k]), i64::from(ahi[k]) - 1) as i32;
                bhi[k] = rng.int(i64::from(blo[k]) + 1, i64::from(ahi[k])) as i32;
            }
            "inside"
        }
        _ => {
            (blo, bhi) = (alo, ahi);
            "equal"
        }
    };
    let a = grid_box(serials, alo, ahi)?;
    let b = grid_box(serials, blo, bhi)?;
    let what = format!("grid {what}: A {alo}..{ahi}, B {blo}..{bhi}");
    Ok(pair(what, a, b, true))
}

/// The angles (degrees) the `rotated` family turns by; the last stands for a random one.
const ANGLES: [f64; 5] = [0.0, 1e-12, 1e-9, 1e-6, f64::NAN];

/// (b) A box and a second box (the same size, or with one or two sides changed) turned
/// about A's centre, a corner or an edge's midpoint by one of [`ANGLES`] about a
/// coordinate or random axis, then moved by 0 or 1e-12 (and sometimes by half a side).
pub(super) fn rotated(rng: &mut Rng, serials: &mut Serials) -> Result<Case, SolidError> {
    let size = if rng.chance(0.5) {
        DVec3::new(
            rng.int(1, 3) as f64,
            rng.int(1, 3) as f64,
            rng.int(1, 3) as f64,
        )
    } else {
        DVec3::new(
            rng.range(0.5, 3.0),
            rng.range(0.5, 3.0),
            rng.range(0.5, 3.0),
        )
    };
    let mut size_b = size;
    for k in 0..3 {
        if rng.chance(0.25) {
            size_b[k] *= rng.pick(&[0.5, 1.5, 2.0]);
        }
    }
    let half = size * 0.5;
    let pivot = match rng.below(3) {
        0 => DVec3::ZERO,
        1 => {
            half * DVec3::new(
                rng.pick(&[-1.0, 1.0]),
                rng.pick(&[-1.0, 1.0]),
                rng.pick(&[-1.0, 1.0]),
            )
        }
        _ => {
            let mut p = half
                * DVec3::new(
                    rng.pick(&[-1.0, 1.0]),
                    rng.pick(&[-1.0, 1.0]),
                    rng.pick(&[-1.0, 1.0]),
                );
            p[rng.below(3)] = 0.0;
            p
        }
    };
    let degrees = match rng.pick(&ANGLES) {
        d if d.is_nan() => rng.range(0.0, 360.0),
        d => d,
    };
    let axis = if rng.chance(0.6) {
        [DVec3::X, DVec3::Y, DVec3::Z][rng.below(3)]
    } else {
        rng.unit_vector()
    };
    let nudge = if rng.chance(0.5) { 1e-12 } else { 0.0 };
    let mut shift = if rng.chance(0.5) {
        [DVec3::X, DVec3::Y, DVec3::Z][rng.below(3)] * nudge
    } else {
        rng.unit_vector() * nudge
    };
    if rng.chance(0.3) {
        let k = rng.below(3);
        shift[k] += half[k];
    }
    // B's own box is centred like A's, so its faces are A's where the sizes agree.
    let a = box_solid(serials, size)?;
    let b = box_solid(serials, size_b)?;
    let place_a = if rng.chance(0.5) {
        DAffine3::IDENTITY
    } else {
        DAffine3::from_rotation_translation(
            DQuat::from_axis_angle(rng.unit_vector(), rng.range(0.0, std::f64::consts::TAU)),
            rng.unit_vector() * rng.range(0.0, 3.0),
        )
    };
    let turn = turn_about(
        pivot,
        DQuat::from_axis_angle(axis, degrees.to_radians()),
        shift,
    );
    let what = format!(
        "rotated: A {size}, B {size_b}, {degrees:e}° about {axis} through {pivot}, moved {shift}"
    );
    Ok(pair(what, (a, place_a), (b, place_a * turn), false))
}
