//! Booleans on closed winged-edge bodies: Baumgart's BIN (intersection of interiors),
//! BUN (union) and the difference A − B = A ∩ EVERT(B).
//!
//! (Approach: see the opening comment once the algorithm lands.)

use glam::{DAffine3, DVec3};

use crate::model::body::Body;
use crate::model::ids::Serial;

/// Which boolean to take of two bodies' interiors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Op {
    /// BIN: the points inside both bodies.
    Intersection,
    /// BUN: the points inside either body.
    Union,
    /// A − B: the points inside A and not inside B.
    Difference,
}

/// One body taken into a boolean: its records and the map from its own frame to the
/// frame the boolean is computed in.
#[derive(Clone, Copy, Debug)]
pub struct Operand<'a> {
    /// The body; it must be closed (a solid, possibly everted).
    pub body: &'a Body,
    /// Its own frame in the common frame (rigid; the identity for the first operand
    /// when the result is to stay in its frame).
    pub place: DAffine3,
}

/// Which operand an output face came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Which {
    /// The first operand (B1).
    A,
    /// The second operand (B2).
    B,
}

/// Where an output face came from: the input face it is a piece of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Source {
    /// The operand.
    pub operand: Which,
    /// The serial of that operand's face.
    pub face: Serial,
}

/// One connected, closed shell of the result, as polygons in the common frame.
///
/// Postconditions: [`Body::from_polygons`] accepts `positions` and `faces` (closed,
/// manifold, consistently oriented, one piece); face `i` is a piece (or the union of
/// connected pieces) of input face `sources[i]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Shell {
    /// Vertex loci, rounded to f64 from the exact result.
    pub positions: Vec<DVec3>,
    /// Faces, each a ring of indices into `positions`, counter-clockwise seen from the
    /// outside of the interior the shell bounds.
    pub faces: Vec<Vec<u32>>,
    /// The input face of each face.
    pub sources: Vec<Source>,
}

/// The result of a boolean: its shells (none when the result is empty).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Solution {
    /// The connected shells, largest first.
    pub shells: Vec<Shell>,
}

/// Why a boolean was refused. Faces are named by serial.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BooleanError {
    /// An operand is not a closed solid (a wire, a lamina, a seminal or empty body).
    #[error("{operand:?} is not a closed solid: {why}")]
    NotClosed {
        /// The operand.
        operand: Which,
        /// What is open about it.
        why: String,
    },
    /// An operand's surface crosses itself.
    #[error("{operand:?} intersects itself: faces {faces:?} cross")]
    SelfIntersecting {
        /// The operand.
        operand: Which,
        /// Two faces of that operand that cross.
        faces: [Serial; 2],
    },
    /// A coordinate is not finite once placed in the common frame.
    #[error("{operand:?} has a vertex that is not finite in the common frame")]
    NonFinite {
        /// The operand.
        operand: Which,
    },
}

/// Takes `op` of the interiors of `a` and `b`.
///
/// Preconditions: none on the geometry (refusals are errors). Postconditions: the
/// shells bound exactly the set `op(interior(a), interior(b))`, rounded to f64 at the
/// end; same inputs give bit-identical output.
pub fn boolean(a: Operand<'_>, b: Operand<'_>, op: Op) -> Result<Solution, BooleanError> {
    let _ = (a, b, op);
    todo!("boolean kernel")
}
