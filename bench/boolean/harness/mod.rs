//! The correctness harness for `winged::model::boolean`, shared by the property tests
//! (`tests/boolean_props.rs`) and the 100,000-case program (`bench/boolean/cases.rs`),
//! which both include it with `#[path]`.
//!
//! * [`cases`]: deterministic case generators from a seed (bodies and their places);
//! * [`shapes`]: the bodies and rigid places the generators draw from;
//! * [`verify`]: the checks of one boolean's output (shells build, are valid solids,
//!   have faces of non-zero area, satisfy Euler's formula and name real source faces);
//! * [`identity`]: the volume identities between ∩, ∪ and − of the same operands;
//! * [`run`]: one case through the three operations, with panics caught and the
//!   determinism checks (twice, and on rayon pools of 1 and 2 threads);
//! * [`grid`] and [`carve`]: exact box-set arithmetic on the 1/1024 grid and the run of
//!   successive differences checked against it.

#[path = "../../rng.rs"]
pub mod rng;

pub mod carve;
pub mod cases;
pub mod draw;
pub mod grid;
pub mod identity;
pub mod quiet;
pub mod run;
pub mod shapes;
pub mod verify;
