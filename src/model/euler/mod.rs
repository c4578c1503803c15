//! Baumgart's Euler operators: every change of topology goes through one of these, and
//! each keeps F − E + V = 2(B − H).
//!
//! | operator | F | E | V | B | H | inverse |
//! |---|---|---|---|---|---|---|
//! | [`MKBFV`](crate::model::Body::seminal) | +1 | | +1 | +1 | | KLBFEV |
//! | [`MKEV`](crate::model::Body::mkev), [`ESPLIT`](crate::model::Body::esplit) | | +1 | +1 | | | KLEV |
//! | [`MKFE`](crate::model::Body::mkfe) | +1 | +1 | | | | KLFE |
//! | [`GLUEE`](crate::model::Body::gluee) | −1 | +1 | | −1 or | +1 | |
//! | [`GLUE`](crate::model::Body::glue) (two N-gons) | −2 | −N | −N | −1 or | +1 | UNGLUE |
//! | [`KLEV`](crate::model::Body::klev), [`KLVE`](crate::model::Body::klve) | | −1 | −1 | | | ESPLIT / MKEV |
//! | [`KLFE`](crate::model::Body::klfe) | −1 | −1 | | | | MKFE |
//! | [`UNGLUE`](crate::model::Body::unglue) (N-edge seam) | +2 | +N | +N | +1 or | −1 | GLUE |
//!
//! Every operator first checks all its preconditions and only then changes the body, so
//! an operator that refuses returns an [`EulerError`] and leaves the body exactly as it
//! was.

mod esplit;
mod glue;
mod klev;
mod klfe;
mod mkbfv;
mod mkev;
mod mkfe;
mod unglue;

pub use unglue::Unglued;

use super::body::Body;
use super::ids::{EdgeId, FaceId, Serial, VertexId};
use super::topology::EdgeUse;

/// Why an Euler operator refused. Entities are named by their serial numbers.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EulerError {
    /// A face id that is not live in this body.
    #[error("face {0:?} is not a live face of this body")]
    UnknownFace(FaceId),
    /// An edge id that is not live in this body.
    #[error("edge {0:?} is not a live edge of this body")]
    UnknownEdge(EdgeId),
    /// A vertex id that is not live in this body.
    #[error("vertex {0:?} is not a live vertex of this body")]
    UnknownVertex(VertexId),
    /// The vertex is not on the face's perimeter.
    #[error("vertex {vertex} is not on the perimeter of face {face}")]
    VertexNotOnFace {
        /// The vertex.
        vertex: Serial,
        /// The face.
        face: Serial,
    },
    /// The vertex occurs more than once on the face's perimeter (a wire's inner vertex,
    /// a spur's base, a wasp waist), so the corner meant is ambiguous.
    #[error(
        "vertex {vertex} occurs {corners} times on the perimeter of face {face}; the corner is ambiguous"
    )]
    AmbiguousCorner {
        /// The vertex.
        vertex: Serial,
        /// The face.
        face: Serial,
        /// How many corners of the face are at the vertex.
        corners: usize,
    },
    /// MKEV on a wire only extends the wire at its negative (newest) end.
    #[error("vertex {vertex} is the positive end of a wire; a wire grows only at its negative end")]
    WirePositiveEnd {
        /// The vertex.
        vertex: Serial,
    },
    /// Two vertices were given where two different ones are needed.
    #[error("the two vertices are the same vertex {vertex}")]
    SameVertex {
        /// The vertex.
        vertex: Serial,
    },
    /// Two faces were given where two different ones are needed.
    #[error("the two faces are the same face {face}")]
    SameFace {
        /// The face.
        face: Serial,
    },
    /// KLFE needs two different faces on the edge's sides.
    #[error("edge {edge} has face {face} on both sides; KLFE would disconnect its perimeter")]
    SameFaceBothSides {
        /// The edge.
        edge: Serial,
        /// The face on both sides.
        face: Serial,
    },
    /// KLEV kills only vertices of valence one (spur tips) or two (edge splits).
    #[error("vertex {vertex} has {valence} edges; KLEV kills vertices with one or two")]
    Valence {
        /// The vertex.
        vertex: Serial,
        /// Its valence.
        valence: usize,
    },
    /// The operation would make an edge whose two ends are the same vertex.
    #[error(
        "vertices {a} and {b} are already joined by edge {edge}; merging them would make a loop"
    )]
    WouldMakeLoop {
        /// One vertex.
        a: Serial,
        /// The other vertex.
        b: Serial,
        /// The edge that would become a loop.
        edge: Serial,
    },
    /// A seminal vertex: it has no edges, and the operation needs one.
    #[error("vertex {vertex} has no edges")]
    NoEdges {
        /// The vertex.
        vertex: Serial,
    },
    /// GLUE needs faces with the same number of edges.
    #[error("face {face1} has {n1} edges and face {face2} has {n2}; GLUE needs equal counts")]
    DegreeMismatch {
        /// First face.
        face1: Serial,
        /// Its edge count.
        n1: usize,
        /// Second face.
        face2: Serial,
        /// Its edge count.
        n2: usize,
    },
    /// The face's perimeter visits a vertex twice (spur or wasp waist).
    #[error("face {face} is not a simple polygon: its perimeter visits a vertex twice")]
    FaceNotSimple {
        /// The face.
        face: Serial,
    },
    /// The face has too few edges for the operation.
    #[error("face {face} has {degree} edges; at least 3 are needed")]
    FaceTooSmall {
        /// The face.
        face: Serial,
        /// Its edge count.
        degree: usize,
    },
    /// Faces to be glued share a vertex or an edge.
    #[error("faces {face1} and {face2} share vertex {vertex}; glued faces must be apart")]
    FacesTouch {
        /// First face.
        face1: Serial,
        /// Second face.
        face2: Serial,
        /// A shared vertex.
        vertex: Serial,
    },
    /// A locus with a NaN or infinite coordinate.
    #[error("the locus {x}, {y}, {z} is not finite")]
    NonFiniteLocus {
        /// x coordinate.
        x: f64,
        /// y coordinate.
        y: f64,
        /// z coordinate.
        z: f64,
    },
    /// A locus beyond the world's range (see [`crate::model::range`]).
    #[error(transparent)]
    OutOfRange(#[from] crate::model::range::RangeError),
    /// The seam for UNGLUE is not one simple closed loop of edges.
    #[error("the seam is not one simple closed loop of edges: {reason}")]
    BadSeam {
        /// What is wrong with it.
        reason: String,
    },
}

impl EulerError {
    /// Whether the refusal is about the world's range (see [`crate::model::range`]).
    pub fn is_out_of_range(&self) -> bool {
        matches!(self, EulerError::OutOfRange(_))
    }
}

impl Body {
    /// Checks a new locus: finite ([`EulerError::NonFiniteLocus`]) and within the
    /// world's range ([`EulerError::OutOfRange`], see [`crate::model::range`]).
    pub(crate) fn check_locus(p: glam::DVec3) -> Result<(), EulerError> {
        if !p.is_finite() {
            return Err(EulerError::NonFiniteLocus {
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
        crate::model::range::coordinate("the locus", p)?;
        Ok(())
    }
    pub(crate) fn check_face(&self, f: FaceId) -> Result<(), EulerError> {
        if self.has_face(f) {
            Ok(())
        } else {
            Err(EulerError::UnknownFace(f))
        }
    }
    pub(crate) fn check_edge(&self, e: EdgeId) -> Result<(), EulerError> {
        if self.has_edge(e) {
            Ok(())
        } else {
            Err(EulerError::UnknownEdge(e))
        }
    }
    pub(crate) fn check_vertex(&self, v: VertexId) -> Result<(), EulerError> {
        if self.has_vertex(v) {
            Ok(())
        } else {
            Err(EulerError::UnknownVertex(v))
        }
    }

    /// The corner of face `f` at vertex `v`: the outgoing use at `v` whose face is `f`
    /// (the incoming use is its `prev`). Refuses when `v` is not on `f`, or is on it more
    /// than once.
    ///
    /// Precondition: `f` and `v` are live and `v` has at least one edge.
    pub(crate) fn corner(&self, v: VertexId, f: FaceId) -> Result<EdgeUse, EulerError> {
        let mut found = None;
        let mut count = 0;
        for u in self.vertex_uses(v) {
            if self.use_face(u) == f {
                count += 1;
                found.get_or_insert(u);
            }
        }
        match (found, count) {
            (Some(u), 1) => Ok(u),
            (None, _) => Err(EulerError::VertexNotOnFace {
                vertex: self.vertex_serial(v),
                face: self.face_serial(f),
            }),
            (Some(_), n) => Err(EulerError::AmbiguousCorner {
                vertex: self.vertex_serial(v),
                face: self.face_serial(f),
                corners: n,
            }),
        }
    }

    /// An edge other than `except` joining `a` and `b`, if any.
    pub(crate) fn other_edge_joining(
        &self,
        a: VertexId,
        b: VertexId,
        except: EdgeId,
    ) -> Option<EdgeId> {
        self.vertex_edges(a)
            .find(|&e| e != except && self.other_vertex(e, a) == Some(b))
    }

    /// If face `f`'s PED is `dead`, makes it `alive`. Precondition: `f` is live.
    #[inline]
    pub(crate) fn repoint_face_ped(&mut self, f: FaceId, dead: EdgeId, alive: EdgeId) {
        let r = self.face_mut(f);
        if r.ped == dead {
            r.ped = alive;
        }
    }

    /// If vertex `v`'s PED is `dead`, makes it `alive`. Precondition: `v` is live.
    #[inline]
    pub(crate) fn repoint_vertex_ped(&mut self, v: VertexId, dead: EdgeId, alive: EdgeId) {
        let r = self.vertex_mut(v);
        if r.ped == dead {
            r.ped = alive;
        }
    }
}
