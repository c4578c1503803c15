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

mod boxes;
mod handles;
mod shaped;

use glam::DAffine3;
use winged::model::boolean::Operand;
use winged::model::solids::SolidError;
use winged::model::{Body, Serials, Violation, check_solid};

use super::draw::rng_for;
use boxes::{grid, rotated};
use handles::{everted, handles};
use shaped::{concave, same};

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

    /// The larger of the two bodies' bounding-box diagonals, at least 1 (the size the
    /// checks' tolerances scale with).
    pub fn scale(&self) -> f64 {
        let diagonal = |b: &Body| b.bounds().map_or(0.0, |b| b.diagonal());
        diagonal(&self.a).max(diagonal(self.body_b())).max(1.0)
    }
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
pub(crate) fn pair(what: String, a: (Body, DAffine3), b: (Body, DAffine3), exact: bool) -> Case {
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
