//! (c) one body taken twice and (d) concave prisms.

use glam::{DAffine3, DQuat, DVec2, DVec3, IVec3};
use winged::model::solids::{SolidError, cone, cylinder, prism_solid, sphere, torus};
use winged::model::{Body, Serials};

use super::super::draw::Draw;
use super::super::rng::Rng;
use super::super::shapes::{
    comb_outline, extrude, frame, grid_box, l_outline, quarter_turns, star_outline,
};
use super::{Case, Family, pair};

/// One body from any family's shapes, for [`same`].
fn any_body(rng: &mut Rng, serials: &mut Serials) -> Result<(Body, &'static str), SolidError> {
    Ok(match rng.below(9) {
        0 => (
            grid_box(serials, IVec3::ZERO, IVec3::new(1, 2, 3))?.0,
            "box",
        ),
        1 => (
            prism_solid(serials, &l_outline(3.0, 2.0, 1.0), 1.0)?,
            "L prism",
        ),
        2 => (
            prism_solid(
                serials,
                &comb_outline(rng.int(2, 5) as usize, 1.0, 1.0, 2.0, 1.0),
                1.0,
            )?,
            "comb prism",
        ),
        3 => (
            prism_solid(
                serials,
                &star_outline(rng.int(5, 9) as usize, 2.0, 0.8),
                1.0,
            )?,
            "star prism",
        ),
        4 => (
            torus(
                serials,
                2.0,
                0.6,
                rng.int(6, 16) as usize,
                rng.int(3, 8) as usize,
            )?,
            "torus",
        ),
        5 => (
            sphere(
                serials,
                1.5,
                rng.int(6, 16) as usize,
                rng.int(3, 8) as usize,
            )?,
            "sphere",
        ),
        6 => (cone(serials, 1.0, 2.0, rng.int(3, 24) as usize)?, "cone"),
        7 => (
            cylinder(serials, 1.0, 2.0, rng.int(3, 24) as usize)?,
            "cylinder",
        ),
        _ => (frame(serials, 2.0, 1.0, 1.0)?, "frame"),
    })
}

/// (c) A op A: one body taken twice under one place (random or the identity).
pub(super) fn same(rng: &mut Rng, serials: &mut Serials) -> Result<Case, SolidError> {
    let (body, what) = any_body(rng, serials)?;
    let place = if rng.chance(0.3) {
        DAffine3::IDENTITY
    } else {
        DAffine3::from_rotation_translation(
            DQuat::from_axis_angle(rng.unit_vector(), rng.range(0.0, std::f64::consts::TAU)),
            rng.unit_vector() * rng.range(0.0, 3.0),
        )
    };
    Ok(Case {
        family: Family::Same,
        seed: 0,
        what: format!("same: {what} twice"),
        a: body,
        place_a: place,
        b: None,
        place_b: place,
        exact: false,
    })
}

/// A concave outline: an L, a comb or a star, with whether its points are integers.
fn concave_outline(rng: &mut Rng) -> (Vec<DVec2>, &'static str, bool) {
    match rng.below(3) {
        0 => {
            let (w, h) = (rng.int(2, 4) as f64, rng.int(2, 4) as f64);
            (l_outline(w, h, 1.0), "L", true)
        }
        1 => {
            let teeth = rng.int(2, 5) as usize;
            (
                comb_outline(teeth, 1.0, 1.0, rng.int(1, 3) as f64, 1.0),
                "comb",
                true,
            )
        }
        _ => {
            let points = rng.int(5, 9) as usize;
            (
                star_outline(points, 2.0, rng.range(0.5, 1.5)),
                "star",
                false,
            )
        }
    }
}

/// (d) Two prisms over concave outlines: B moved by whole units and turned by quarter
/// turns about z (exact), turned by a random angle about z, or laid on its side; or two
/// equal combs facing each other with their teeth interleaved (touching or overlapping).
pub(super) fn concave(rng: &mut Rng, serials: &mut Serials) -> Result<Case, SolidError> {
    let height_a = rng.int(1, 3) as f64;
    if rng.chance(0.2) {
        let teeth = rng.int(2, 6) as usize;
        let outline = comb_outline(teeth, 1.0, 1.0, 2.0, 1.0);
        let a = extrude(serials, &outline, height_a)?;
        let b = extrude(serials, &outline, height_a)?;
        // Turned half round about z, teeth down into A's gaps: x ↦ w − x + 1 puts B's
        // teeth in A's gaps; y ↦ 3 + 1 + depth − y overlaps the teeth by `depth`.
        let width = (2 * teeth - 1) as f64;
        let depth = rng.int(0, 2) as f64;
        let place_b = DAffine3::from_mat3_translation(
            quarter_turns(2, 2),
            DVec3::new(width + 1.0, 6.0 - depth, 0.0),
        );
        let what = format!("concave: interleaved combs of {teeth} teeth, overlap {depth}");
        return Ok(pair(what, (a, DAffine3::IDENTITY), (b, place_b), true));
    }
    let (pa, na, ea) = concave_outline(rng);
    let (pb, nb, eb) = concave_outline(rng);
    let height_b = rng.int(1, 3) as f64;
    // `prism_solid` sweeps about the face's mean point, which rounds; `extrude` keeps
    // integer outlines exact.
    let exact_build = rng.chance(0.5);
    let make = |serials: &mut Serials, p: &[DVec2], h: f64| {
        if exact_build {
            extrude(serials, p, h)
        } else {
            prism_solid(serials, p, h)
        }
    };
    let a = make(serials, &pa, height_a)?;
    let b = make(serials, &pb, height_b)?;
    let shift = DVec3::new(
        rng.int(-2, 2) as f64,
        rng.int(-2, 2) as f64,
        rng.int(-1, 1) as f64 * 0.5,
    );
    let (place_b, how, exact) = match rng.below(3) {
        0 => {
            let k = rng.int(0, 3) as i32;
            (
                DAffine3::from_mat3_translation(quarter_turns(2, k), shift),
                format!("{k} quarter turns"),
                true,
            )
        }
        1 => {
            let angle = rng.range(0.0, std::f64::consts::TAU);
            (
                DAffine3::from_rotation_translation(DQuat::from_rotation_z(angle), shift),
                format!("turned {angle:.3} rad"),
                false,
            )
        }
        _ => (
            DAffine3::from_mat3_translation(quarter_turns(0, 1), shift),
            "on its side".to_string(),
            true,
        ),
    };
    let what = format!("concave: {na} and {nb} ({how}, moved {shift})");
    let exact = exact_build && ea && eb && exact;
    Ok(pair(what, (a, DAffine3::IDENTITY), (b, place_b), exact))
}
