//! Deterministic boolean cases: each [`Family`] and seed gives the same two bodies and
//! places on every run and every machine (the draws come from `bench/rng.rs`).
//!
//! | family | what it makes |
//! |---|---|
//! | `grid` | axis-aligned boxes with corners on the integer grid 0..=4, often sharing faces, edges or vertices (exact volumes) |
//! | `rotated` | boxes turned by 0, 1e-12, 1e-9, 1e-6 degrees or a random angle and moved by 0 or 1e-12: near-coincident pairs |
//! | `same` | A op A: one body taken twice, under the same place |
//! | `concave` | prisms over L, comb and star outlines, many shells where combs interleave |
//! | `handles` | tori and square frames (genus 1) crossing boxes, bars, each other |
//! | `everted` | a case of another family with A, B or both everted (infinite interiors) |

use glam::{DAffine3, DQuat, DVec2, DVec3, IVec3};
use winged::model::boolean::Operand;
use winged::model::solids::{SolidError, box_solid, cone, cylinder, prism_solid, sphere, torus};
use winged::model::{Body, Serials, Violation, check_solid};

use super::draw::{Draw, rng_for};
use super::rng::Rng;
use super::shapes::{
    comb_outline, extrude, frame, grid_box, l_outline, quarter_turns, star_outline, turn_about,
};

/// A family of cases (see the module's table).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    /// Integer-grid boxes.
    Grid,
    /// Turned and nudged boxes.
    Rotated,
    /// One body twice.
    Same,
    /// Concave prisms.
    Concave,
    /// Bodies with handles.
    Handles,
    /// Everted operands.
    Everted,
}

impl Family {
    /// Every family, in table order.
    pub const ALL: [Family; 6] = [
        Family::Grid,
        Family::Rotated,
        Family::Same,
        Family::Concave,
        Family::Handles,
        Family::Everted,
    ];

    /// The family's short name.
    pub fn name(self) -> &'static str {
        match self {
            Family::Grid => "grid",
            Family::Rotated => "rotated",
            Family::Same => "same",
            Family::Concave => "concave",
            Family::Handles => "handles",
            Family::Everted => "everted",
        }
    }

    /// The family named `name`, if any.
    pub fn parse(name: &str) -> Option<Family> {
        Family::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// One case: two bodies and their places in the common frame.
#[derive(Clone, Debug)]
pub struct Case {
    /// The family it was drawn from.
    pub family: Family,
    /// The seed it was drawn with.
    pub seed: u64,
    /// A short description of the pair.
    pub what: String,
    /// Operand A's body.
    pub a: Body,
    /// Operand A's place.
    pub place_a: DAffine3,
    /// Operand B's body; `None` when B is A itself (the same body twice).
    pub b: Option<Body>,
    /// Operand B's place.
    pub place_b: DAffine3,
    /// Whether every volume in the case is exact in f64 (loci on a grid of halves and
    /// exact places), so that the volume identities must hold exactly.
    pub exact: bool,
}

impl Case {
    /// Operand B's body.
    pub fn body_b(&self) -> &Body {
        self.b.as_ref().unwrap_or(&self.a)
    }

    /// The two operands.
    pub fn operands(&self) -> (Operand<'_>, Operand<'_>) {
        (
            Operand {
                body: &self.a,
                place: self.place_a,
            },
            Operand {
                body: self.body_b(),
                place: self.place_b,
            },
        )
    }

    /// The largest extent of the two placed bodies' bounds (for tolerances).
    pub fn scale(&self) -> f64 {
        let (a, b) = self.operands();
        placed_extent(a).max(placed_extent(b)).max(1.0)
    }
}

/// The largest side of an operand's placed bounding box (the corners of its own box,
/// placed).
fn placed_extent(o: Operand<'_>) -> f64 {
    o.body.bounds().map_or(0.0, |b| {
        let p = |v: DVec3| o.place.transform_point3(v);
        let (lo, hi) = (p(b.min), p(b.max));
        (hi - lo).abs().max_element() + b.diagonal() * 0.0
    })
}

/// Draws the case of `family` for `seed`.
pub fn generate(family: Family, seed: u64) -> Result<Case, SolidError> {
    let mut rng = rng_for(family as u64 + 1, seed);
    let mut serials = Serials::new();
    let mut case = match family {
        Family::Grid => grid(&mut rng, &mut serials)?,
        Family::Rotated => rotated(&mut rng, &mut serials)?,
        Family::Same => same(&mut rng, &mut serials)?,
        Family::Concave => concave(&mut rng, &mut serials)?,
        Family::Handles => handles(&mut rng, &mut serials)?,
        Family::Everted => everted(&mut rng, &mut serials)?,
    };
    case.family = family;
    case.seed = seed;
    Ok(case)
}

/// Checks the generated bodies: each must pass `check_solid(_, 1e-9)`, except that an
/// everted body (negative volume) may and must fail only the `Inward` check.
pub fn validate(case: &Case) -> Result<(), String> {
    let mut bodies = vec![("A", &case.a)];
    if let Some(b) = &case.b {
        bodies.push(("B", b));
    }
    for (name, body) in bodies {
        let report = check_solid(body, 1e-9);
        let everted = body.volume() < 0.0;
        let bad: Vec<&Violation> = report
            .violations
            .iter()
            .filter(|v| !(everted && matches!(v, Violation::Inward { .. })))
            .collect();
        if !bad.is_empty() {
            return Err(format!("{name} ({}): {bad:?}", case.what));
        }
        if everted && report.is_ok() {
            return Err(format!("{name} ({}): everted but not inward", case.what));
        }
    }
    Ok(())
}

/// A pair without family and seed yet (filled in by [`generate`]).
fn pair(what: String, a: (Body, DAffine3), b: (Body, DAffine3), exact: bool) -> Case {
    Case {
        family: Family::Grid,
        seed: 0,
        what,
        a: a.0,
        place_a: a.1,
        b: Some(b.0),
        place_b: b.1,
        exact,
    }
}

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
fn grid(rng: &mut Rng, serials: &mut Serials) -> Result<Case, SolidError> {
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
fn rotated(rng: &mut Rng, serials: &mut Serials) -> Result<Case, SolidError> {
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
fn same(rng: &mut Rng, serials: &mut Serials) -> Result<Case, SolidError> {
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
fn concave(rng: &mut Rng, serials: &mut Serials) -> Result<Case, SolidError> {
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

/// (e) Bodies with handles: a frame and a bar through its hole (or cutting one side),
/// two frames linked like a chain, a torus and a box, two linked tori, a torus inside
/// a frame's hole.
fn handles(rng: &mut Rng, serials: &mut Serials) -> Result<Case, SolidError> {
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
fn everted(rng: &mut Rng, serials: &mut Serials) -> Result<Case, SolidError> {
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
