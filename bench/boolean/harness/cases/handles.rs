//! (e) bodies with handles and (f) everted operands.

use glam::{DAffine3, DQuat, DVec3, IVec3};
use winged::model::Serials;
use winged::model::solids::{SolidError, box_solid, torus};

use super::super::draw::Draw;
use super::super::rng::Rng;
use super::super::shapes::{frame, grid_box, quarter_turns};
use super::boxes::{grid, rotated};
use super::shaped::concave;
use super::{Case, pair};

/// (e) Bodies with handles: a frame and a bar through its hole (or cutting one side),
/// two frames linked like a chain, a torus and a box, two linked tori, a torus inside
/// a frame's hole.
pub(super) fn handles(rng: &mut Rng, serials: &mut Serials) -> Result<Case, SolidError> {
    let id = DAffine3::IDENTITY;
    Ok(match rng.below(6) {
        0 => {
            // A bar along z through the hole, as wide as the hole or narrower.
            let inner = rng.int(1, 2);
            let f = frame(serials, (inner + 2) as f64, inner as f64, 2.0)?;
            let w = rng.int(1, 2 * inner);
            let x0 = rng.int(-inner, inner - w) as i32;
            let w = w as i32;
            let bar = grid_box(
                serials,
                IVec3::new(x0, x0, -3),
                IVec3::new(x0 + w, x0 + w, 3),
            )?;
            pair(
                format!("handles: frame and a bar {w} wide at {x0}"),
                (f, id),
                bar,
                true,
            )
        }
        1 => {
            // A box cutting through one side of the frame (or reaching into it).
            let f = frame(serials, 3.0, 1.0, 2.0)?;
            let reach = rng.int(1, 3) as i32;
            let cut = grid_box(
                serials,
                IVec3::new(-1, 3 - reach, -2),
                IVec3::new(1, 4, rng.int(0, 2) as i32),
            )?;
            pair(
                format!("handles: frame and a cut {reach} deep"),
                (f, id),
                cut,
                true,
            )
        }
        2 => {
            // Two frames linked like chain links: B stood up about x and moved along x.
            let f = frame(serials, 3.0, 1.0, 1.0)?;
            let g = frame(serials, 3.0, 1.0, 1.0)?;
            let dx = rng.int(2, 4) as f64;
            let place =
                DAffine3::from_mat3_translation(quarter_turns(0, 1), DVec3::new(dx, 0.0, 0.0));
            pair(
                format!("handles: linked frames {dx} apart"),
                (f, id),
                (g, place),
                true,
            )
        }
        3 => {
            let t = torus(
                serials,
                2.0,
                rng.range(0.3, 0.9),
                rng.int(6, 24) as usize,
                rng.int(3, 8) as usize,
            )?;
            let lo = DVec3::new(
                rng.range(-3.0, 1.0),
                rng.range(-3.0, 1.0),
                rng.range(-1.0, 0.5),
            );
            let hi = lo
                + DVec3::new(
                    rng.range(0.5, 4.0),
                    rng.range(0.5, 4.0),
                    rng.range(0.2, 2.0),
                );
            let b = box_solid(serials, hi - lo)?;
            pair(
                "handles: torus and box".into(),
                (t, id),
                (b, DAffine3::from_translation((lo + hi) * 0.5)),
                false,
            )
        }
        4 => {
            let t = torus(
                serials,
                2.0,
                0.5,
                rng.int(6, 24) as usize,
                rng.int(3, 8) as usize,
            )?;
            let u = torus(
                serials,
                2.0,
                0.5,
                rng.int(6, 24) as usize,
                rng.int(3, 8) as usize,
            )?;
            let place = DAffine3::from_rotation_translation(
                DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2 + rng.range(-0.2, 0.2)),
                DVec3::new(2.0 + rng.range(-0.5, 0.5), 0.0, 0.0),
            );
            pair("handles: linked tori".into(), (t, id), (u, place), false)
        }
        _ => {
            let f = frame(serials, 4.0, 3.0, 1.0)?;
            let t = torus(
                serials,
                rng.range(2.6, 3.4),
                rng.range(0.3, 0.8),
                rng.int(6, 24) as usize,
                rng.int(3, 8) as usize,
            )?;
            pair(
                "handles: torus about the frame's hole".into(),
                (f, id),
                (t, id),
                false,
            )
        }
    })
}

/// (f) A case of the grid, rotated, concave or handles family with A, B or both
/// everted: their interiors are the complements of the solids.
pub(super) fn everted(rng: &mut Rng, serials: &mut Serials) -> Result<Case, SolidError> {
    let mut case = match rng.below(4) {
        0 => grid(rng, serials)?,
        1 => rotated(rng, serials)?,
        2 => concave(rng, serials)?,
        _ => handles(rng, serials)?,
    };
    let which = rng.below(3);
    if which != 1 {
        case.a.evert();
    }
    if which != 0
        && let Some(b) = case.b.as_mut()
    {
        b.evert();
    }
    case.what = format!("everted {}: {}", ["A", "B", "A and B"][which], case.what);
    Ok(case)
}
