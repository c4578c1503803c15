//! Booleans on closed winged-edge bodies: Baumgart's BIN (intersection of interiors),
//! BUN (union) and the difference A − B = A ∩ EVERT(B).
//!
//! # Approach: exact decisions on the input points, constructions never rounded
//!
//! Every decision is the sign of a polynomial in input coordinates, which are f64 and
//! hence exact dyadic rationals. The points the boolean makes are kept as their
//! definitions in input points, never as rounded coordinates ([`point`]): the line
//! through two input points meeting the plane through three (an edge piercing a
//! triangle), or two coplanar segments crossing. Predicates on such points are
//! Attene's *indirect predicates*: evaluated through homogeneous coordinates, first in
//! f64 with a running error bound, then, when the bound cannot decide the sign, in
//! double-double with a bound ([`double`]), and only then in exact dyadic arithmetic
//! ([`exact`]); predicates on input points alone are Shewchuk's
//! adaptive `orient2d`/`orient3d` (the `robust` crate). Because each boolean starts from
//! f64 inputs and rounds only its output, constructions never nest, so the degree of
//! every predicate is bounded. (EMBER's plane-based representation, which would keep
//! results exact across successive booleans, is not used: results are rounded once, and
//! a later boolean starts afresh from those f64 loci.)
//!
//! 1. **Triangles** ([`mesh`]): each face is cut into triangles of its own vertices by
//!    exact ear clipping; a triangle is exactly planar where a polygon, once rounded,
//!    need not be. Loci equal in both operands become one point.
//! 2. **Traces** ([`intersect`]): each pair of triangles whose boxes overlap ([`broad`])
//!    meets in a segment (or, coplanar, in the boundary of their overlap). Each end is
//!    named by the smallest elements of the two surfaces that hold it (vertex, edge or
//!    triangle), so the same point reached from different pairs is made once, and
//!    shared faces, edges and vertices of touching bodies are ordinary cases.
//! 3. **Cuts** ([`split`]): each triangle the traces touch is triangulated with the
//!    traces as constraints, with exact orientations in its dominant projection.
//! 4. **Classes** ([`classify`]): pieces joined across edges that are not traces form
//!    regions the other surface does not cross. One point inside each region is
//!    classified exactly: on the other surface (facing the same way or not), or inside
//!    or outside by the winding number of a ray whose direction is perturbed
//!    symbolically. Everted operands (an unbounded interior) are followed the same way.
//! 5. **Assembly** ([`assemble`]): the pieces each operation keeps are sewn along their
//!    edges into shells (where bodies touch along an edge, the pieces about it are
//!    ordered exactly and paired across the solid's wedges); loci are rounded, once, to
//!    the nearest f64, and what the rounding cannot keep (edges and slivers narrower
//!    than a few hundred units in the last place, shells as thin) is cleared
//!    ([`round`]); pieces of one input face merge back into polygons (a face with a
//!    hole becomes two polygons, since a winged-edge face is one ring); vertices where
//!    two faces meet in a straight line are dropped; cavities are matched with the
//!    shell that holds them.
//!
//! Every output face records the input face it is a piece of ([`Source`]).

use glam::{DAffine3, DVec3};

/// The boolean's hash maps: foldhash's fixed-seed hasher, fast on the small integer keys
/// used here, and the same in every run.
pub(crate) type Map<K, V> = std::collections::HashMap<K, V, foldhash::fast::FixedState>;
/// The boolean's hash sets (see [`Map`]).
pub(crate) type Set<K> = std::collections::HashSet<K, foldhash::fast::FixedState>;

use crate::model::body::Body;
use crate::model::ids::{Serial, Serials};
use crate::model::solids::BuildError;

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
    /// For a cavity (a shell facing inward, inside another shell that faces outward):
    /// the index of the shell it is a cavity of. The two bound one body.
    pub cavity_of: Option<usize>,
}

impl Shell {
    /// Six times the signed volume the shell bounds (negative for a cavity or for an
    /// everted shell).
    pub fn six_volume(&self) -> f64 {
        crate::model::geometry::six_volume(&self.positions, &self.faces)
    }

    /// The winding number of the shell about point `x` (1 inside an outward shell, −1
    /// inside an inward one, 0 outside), by summing the solid angles its faces subtend.
    /// A fan of each planar face gives the right signed sum even for concave faces.
    fn winding(&self, x: DVec3) -> f64 {
        crate::model::geometry::winding_number(&self.positions, &self.faces, x)
    }
}

/// The result of a boolean: its shells (none when the result is empty).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Solution {
    /// The connected shells, largest first.
    pub shells: Vec<Shell>,
    /// Whether the result's interior reaches infinity (it holds the points far from
    /// both operands): with no shells, the result is all of space rather than nothing.
    pub unbounded: bool,
}

/// One body of a result: the body and the input face of each of its faces.
#[derive(Clone, Debug)]
pub struct Piece {
    /// The body (serials taken from the counter passed to [`Solution::bodies`]).
    pub body: Body,
    /// For each face (by serial), the input face it is a piece of.
    pub sources: Vec<(Serial, Source)>,
}

impl Solution {
    /// The result as bodies: one per shell that is not a cavity, each holding its
    /// cavities (as further connected polyhedra of the same body). Serials are taken in
    /// order: a shell's vertices, faces, edges, then its cavities'.
    pub fn bodies(&self, serials: &mut Serials) -> Result<Vec<Piece>, BuildError> {
        let mut out = Vec::new();
        for (i, shell) in self.shells.iter().enumerate() {
            if shell.cavity_of.is_some() {
                continue;
            }
            let (mut body, mut sources) = shell.build(serials)?;
            for cavity in self.shells.iter().filter(|c| c.cavity_of == Some(i)) {
                let (inner, more) = cavity.build(serials)?;
                body.absorb(inner);
                sources.extend(more);
            }
            out.push(Piece { body, sources });
        }
        Ok(out)
    }
}

impl Shell {
    fn build(&self, serials: &mut Serials) -> Result<(Body, Vec<(Serial, Source)>), BuildError> {
        let body = build_shell(serials, &self.positions, &self.faces)?;
        let faces: Vec<_> = body.faces().map(|f| body.face_serial(f)).collect();
        let mut sorted = faces;
        sorted.sort_unstable();
        Ok((
            body,
            sorted
                .into_iter()
                .zip(self.sources.iter().copied())
                .collect(),
        ))
    }
}

/// Builds one shell as a body, as [`Body::from_polygons`] does, but also when it faces
/// inward (a cavity, or an everted result): such a surface is built facing outward and
/// everted, so face `i` still has the `i`-th face serial.
pub fn build_shell<F: AsRef<[u32]>>(
    serials: &mut Serials,
    positions: &[DVec3],
    faces: &[F],
) -> Result<Body, BuildError> {
    let mut six = 0.0;
    for f in faces {
        let f = f.as_ref();
        if f.len() < 3 || f.iter().any(|&i| i as usize >= positions.len()) {
            continue;
        }
        let a = positions[f[0] as usize];
        for k in 1..f.len() - 1 {
            six += a.dot(positions[f[k] as usize].cross(positions[f[k + 1] as usize]));
        }
    }
    if six < 0.0 {
        let reversed: Vec<Vec<u32>> = faces
            .iter()
            .map(|f| f.as_ref().iter().rev().copied().collect())
            .collect();
        let mut b = Body::from_polygons(serials, positions, &reversed)?;
        b.evert();
        Ok(b)
    } else {
        Body::from_polygons(serials, positions, faces)
    }
}

/// Marks each inward shell lying inside an outward one as that shell's cavity (the
/// innermost such shell).
fn nest(shells: &mut [Shell]) {
    let outward: Vec<bool> = shells.iter().map(|s| s.six_volume() > 0.0).collect();
    for i in 0..shells.len() {
        if outward[i] {
            continue;
        }
        let probe = |x: DVec3| -> Option<Vec<usize>> {
            let mut inside = Vec::new();
            for (j, s) in shells.iter().enumerate() {
                if j == i || !outward[j] {
                    continue;
                }
                let w = s.winding(x);
                if (w - w.round()).abs() > 0.25 {
                    return None; // on or too near that shell: try another point
                }
                if w.round() >= 1.0 {
                    inside.push(j);
                }
            }
            Some(inside)
        };
        let Some(holders) = shells[i].positions.iter().find_map(|&x| probe(x)) else {
            continue;
        };
        // The innermost holder: the one inside every other holder.
        let innermost = holders.iter().copied().find(|&j| {
            holders.iter().all(|&k| {
                k == j
                    || shells[j]
                        .positions
                        .iter()
                        .any(|&x| shells[k].winding(x).round() >= 1.0)
            })
        });
        shells[i].cavity_of = innermost;
    }
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
    /// A face that is not a simple polygon (it repeats a vertex, or its outline crosses
    /// itself or has no area seen along its normal).
    #[error("face {face} of {operand:?} is not a simple polygon")]
    BadFace {
        /// The operand.
        operand: Which,
        /// The face.
        face: Serial,
    },
    /// The result encloses a cavity: a hollow solid, which one body (one connected
    /// surface) cannot hold.
    #[error("the result encloses a cavity, which one body cannot hold")]
    Cavity,
    /// The result is all of space: nothing bounds it.
    #[error("the result fills all of space: no surface bounds it")]
    Unbounded,
    /// A configuration the algorithm could not resolve. No input that passes the other
    /// checks should reach it; it is reported instead of a wrong result.
    #[error("the boolean could not be resolved: {what}")]
    Unresolved {
        /// What failed.
        what: &'static str,
    },
}

/// Takes `op` of the interiors of `a` and `b`.
///
/// Preconditions: none on the geometry (refusals are errors). Postconditions: the
/// shells bound exactly the set `op(interior(a), interior(b))`, rounded to f64 at the
/// end; the same inputs give bit-identical output.
pub fn boolean(a: Operand<'_>, b: Operand<'_>, op: Op) -> Result<Solution, BooleanError> {
    let mut laps = Laps::start();
    let (mut pts, ma, mb) = mesh::meshes(a, b)?;
    laps.mark("mesh");
    let (cull_a, cull_b) = (Culling::new(&pts, &ma), Culling::new(&pts, &mb));
    check_self(&mut pts, &ma, &cull_a, Which::A)?;
    check_self(&mut pts, &mb, &cull_b, Which::B)?;
    laps.mark("check");
    let mut traces = intersect::Traces::default();
    let pairs = candidates((&ma, &cull_a), (&mb, &cull_b));
    let candidates = pairs.len();
    for (ta, tb) in pairs {
        traces.pair(&mut pts, &ma, ta, &mb, tb);
    }
    laps.mark("traces");
    let pa = classify::pieces(&pts, &ma, &traces.segs_a, &traces)?;
    let pb = classify::pieces(&pts, &mb, &traces.segs_b, &traces)?;
    laps.mark("pieces");
    let ca = classify::classify(&mut pts, &pa, &ma, &mb)?;
    let cb = classify::classify(&mut pts, &pb, &mb, &ma)?;
    laps.mark("classify");
    let mut kept = Vec::new();
    for (i, c) in ca.iter().enumerate() {
        if keeps_a(op, *c) {
            kept.push(assemble::Kept {
                tri: pa.tris[i],
                source: Source {
                    operand: Which::A,
                    face: ma.face[pa.source[i] as usize],
                },
            });
        }
    }
    for (i, c) in cb.iter().enumerate() {
        if keeps_b(op, *c) {
            let [p, q, r] = pb.tris[i];
            kept.push(assemble::Kept {
                tri: if op == Op::Difference {
                    [p, r, q]
                } else {
                    [p, q, r]
                },
                source: Source {
                    operand: Which::B,
                    face: mb.face[pb.source[i] as usize],
                },
            });
        }
    }
    let mut shells = assemble::assemble(&pts, &kept)?;
    laps.mark("assemble");
    tracing::debug!(
        ?op,
        triangles = ma.tris.len() + mb.tris.len(),
        candidates,
        points = pts.defs.len(),
        shells = shells.len(),
        phases = %laps,
        "boolean"
    );
    nest(&mut shells);
    let unbounded = match op {
        Op::Union => ma.everted || mb.everted,
        Op::Intersection => ma.everted && mb.everted,
        Op::Difference => ma.everted && !mb.everted,
    };
    Ok(Solution { shells, unbounded })
}

/// The time each phase of one boolean took, for the log.
struct Laps {
    start: std::time::Instant,
    marks: Vec<(&'static str, std::time::Duration)>,
}

impl Laps {
    fn start() -> Laps {
        Laps {
            start: std::time::Instant::now(),
            marks: Vec::with_capacity(8),
        }
    }

    /// Notes that phase `name` ended now.
    fn mark(&mut self, name: &'static str) {
        self.marks.push((name, self.start.elapsed()));
    }
}

impl std::fmt::Display for Laps {
    /// Each phase's own time in milliseconds: `mesh 1.2, check 3.4, …`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut before = std::time::Duration::ZERO;
        for (k, (name, at)) in self.marks.iter().enumerate() {
            let sep = if k == 0 { "" } else { ", " };
            write!(f, "{sep}{name} {:.3}", (*at - before).as_secs_f64() * 1e3)?;
            before = *at;
        }
        Ok(())
    }
}

/// Whether a piece of A in class `c` bounds the result.
fn keeps_a(op: Op, c: Class) -> bool {
    match op {
        Op::Union => matches!(c, Class::Out | Class::OnSame),
        Op::Intersection => matches!(c, Class::In | Class::OnSame),
        Op::Difference => matches!(c, Class::Out | Class::OnOpposite),
    }
}

/// Whether a piece of B in class `c` bounds the result (turned over for a difference).
/// Pieces on A's surface are represented by A's.
fn keeps_b(op: Op, c: Class) -> bool {
    match op {
        Op::Union => c == Class::Out,
        Op::Intersection | Op::Difference => c == Class::In,
    }
}

/// One operand's triangles ready for culling, made once for the self-check and the
/// pairing: their corners, their planes and the tree of their boxes.
struct Culling {
    corners: Vec<[DVec3; 3]>,
    planes: Vec<broad::Plane>,
    tree: broad::Tree,
}

impl Culling {
    fn new(pts: &Points, m: &mesh::Mesh) -> Culling {
        let corners: Vec<[DVec3; 3]> = m.tris.iter().map(|t| t.map(|p| pts.input_at(p))).collect();
        let planes = corners
            .iter()
            .map(|&[a, b, c]| broad::Plane::new(a, b, c))
            .collect();
        Culling {
            corners,
            planes,
            tree: broad::Tree::new(&m.boxes),
        }
    }

    /// Whether triangle `i` of this operand and triangle `j` of `other` may meet: neither
    /// lies strictly on one side of the other's plane.
    fn may_meet(&self, i: usize, other: &Culling, j: usize) -> bool {
        !other.planes[j].apart(&self.corners[i]) && !self.planes[i].apart(&other.corners[j])
    }
}

/// The triangle pairs of `a` and `b` that may meet: their boxes meet and neither
/// triangle lies strictly on one side of the other's plane. In ascending order.
fn candidates(
    (a, ca): (&mesh::Mesh, &Culling),
    (b, cb): (&mesh::Mesh, &Culling),
) -> Vec<(u32, u32)> {
    let mut pairs = Vec::new();
    ca.tree.pairs(
        &a.boxes,
        &cb.tree,
        &b.boxes,
        |i, j| ca.may_meet(i as usize, cb, j as usize),
        &mut pairs,
    );
    pairs.sort_unstable();
    pairs
}

/// Refuses an operand whose triangles cross each other (other than along the edges and
/// at the vertices they share).
fn check_self(
    pts: &mut Points,
    m: &mesh::Mesh,
    cull: &Culling,
    which: Which,
) -> Result<(), BooleanError> {
    let mut pairs = Vec::new();
    cull.tree.self_pairs(
        &m.boxes,
        |i, j| {
            let (i, j) = (i as usize, j as usize);
            let (t, u) = (m.tris[i], m.tris[j]);
            !t.iter().any(|p| u.contains(p)) && cull.may_meet(i, cull, j)
        },
        &mut pairs,
    );
    pairs.sort_unstable();
    for (i, j) in pairs {
        let (i, j) = (i as usize, j as usize);
        let mut probe = intersect::Traces::default();
        let before = pts.defs.len();
        probe.pair(pts, m, i as u32, m, j as u32);
        // Triangles of a valid body that share no corner may still touch at one
        // point: where a face's triangle has a side through a vertex of the face
        // (collinear vertices). Only a contact of positive length is a crossing.
        let crossing = probe
            .segs_a
            .values()
            .flatten()
            .any(|&[p, q]| distinct(pts, p, q));
        pts.truncate(before);
        if crossing {
            return Err(BooleanError::SelfIntersecting {
                operand: which,
                faces: [m.face[i], m.face[j]],
            });
        }
    }
    Ok(())
}

/// Whether points `p` and `q` differ in some coordinate (exactly).
fn distinct(pts: &Points, p: Pid, q: Pid) -> bool {
    p != q && (0..3).any(|k| split::coord_cmp_at(pts, k, p, q) != 0)
}

mod assemble;
mod broad;
mod classify;
pub mod crossing;
mod double;
pub(crate) mod exact;
mod holes;
mod incidence;
mod intersect;
mod mesh;
mod point;
mod round;
mod sets;
mod split;

use classify::Class;
use point::{Pid, Points};

#[cfg(test)]
mod tests;
