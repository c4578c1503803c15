//! Solid primitives: the seeds' MKCUBE and MKTETRA built through the Euler operators,
//! and a closed polyhedron from vertex and face lists.

mod cube;
mod polyhedron;
mod tetra;

pub use cube::mkcube;
pub use polyhedron::BuildError;
pub use tetra::mktetra;
