//! winged: a world model of Baumgart's winged-edge polyhedra.
//!
//! [`model`] is the geometric kernel: pure, synchronous Rust with no I/O. It can be used
//! as a library on its own.

pub mod model;
pub mod server;

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
