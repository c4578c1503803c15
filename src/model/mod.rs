//! The geometric kernel: Baumgart's winged-edge polyhedra.
//!
//! Pure, synchronous Rust with no I/O. A [`Body`] holds one polyhedron's faces, edges
//! and vertices in compact arenas; the Euler operators ([`euler`]) change its topology
//! while keeping F − E + V = 2(B − H); the validator ([`check`]) verifies every
//! invariant; [`geometry`] derives planes, areas and volumes from the vertex loci;
//! [`solids`] builds primitives; [`transform`] moves bodies, faces, edges and vertices;
//! [`range`] states the numbers the model accepts;
//! [`world`] holds the bodies in a parts tree ([`parts`], [`pose`]) with cameras and
//! lights ([`camera`]) and a revision counter.

mod arena;
pub mod body;
pub mod boolean;
pub mod camera;
pub mod check;
pub mod euler;
pub mod geometry;
pub mod ids;
pub mod parts;
pub mod perceived;
pub mod pose;
pub mod range;
pub mod solids;
pub mod topology;
pub mod transform;
pub mod triangulate;
pub mod world;

pub use body::{Body, Edge, Face, Vertex};
pub use camera::{BaumgartRaster, Camera, CameraError, Intrinsics, Light, LightError};
pub use check::{Report, Violation, check_solid, check_topology};
pub use euler::EulerError;
pub use geometry::{Bounds, Plane};
pub use ids::{EdgeId, FaceId, Serial, Serials, Side, VertexId};
pub use parts::{BodyId, BodyNode, Color, Entity, PartsTree, Size, default_color};
pub use perceived::{Maker, Perceived};
pub use pose::{Pose, PoseError};
pub use range::RangeError;
pub use topology::{Around, EdgeUse, Link};
pub use transform::{Frame, Moves, Transform, TransformError};
pub use world::{
    BooleanBasis, BooleanOutcome, Built, Entangled, Killed, Named, PerceivedShell, Piece, Register,
    ShellRef, UngluedBodies, World, WorldError,
};
