//! Solid primitives: the seeds' MKCUBE and MKTETRA built through the Euler operators,
//! a closed polyhedron from vertex and face lists, the sweeps of WINGED.DOC III.B
//! (PYRAMID, PRISM, CWPRISMOID, CCWPRISMOID), solids of rotation, MKCOPY and FVDUAL.

mod copy;
mod cube;
mod dual;
mod error;
mod polyhedron;
mod rotation;
mod sweep;
mod tetra;

pub use copy::CopyMap;
pub use cube::mkcube;
pub use dual::DualLocus;
pub use error::{PolygonFault, SolidError};
pub use polyhedron::BuildError;
pub use rotation::{MAX_SWEEP_FACES, cone, cylinder, rotation_sweep, sphere, torus};
pub use sweep::{
    Lamina, MAX_POLYGON_POINTS, Swept, Twist, box_solid, lamina, prism_solid, pyramid_solid,
};
pub use tetra::mktetra;
