//! winged: a world model of Baumgart's winged-edge polyhedra.
//!
//! [`model`] is the geometric kernel: pure, synchronous Rust with no I/O. It can be used
//! as a library on its own. [`camera`] projects and clips for a camera; [`render`] draws
//! what the world looks like from one. [`server`] serves it over HTTP/JSON; [`store`] makes it
//! durable (a journal of applied edits plus snapshots).

pub mod camera;
pub mod model;
pub mod render;
pub mod server;
pub mod solve;
pub mod spatial;
pub mod store;

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
