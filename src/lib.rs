//! winged: a world model of Baumgart's winged-edge polyhedra.
//!
//! [`model`] is the geometric kernel: pure, synchronous Rust with no I/O. It can be used
//! as a library on its own. [`camera`] projects and clips for a camera; [`render`] draws
//! what the world looks like from one; [`vision`] reads pictures and solves for the camera
//! that took them. [`server`] serves it over HTTP/JSON; [`store`] makes it
//! durable (a journal of applied edits plus snapshots).
//!
//! # Layers
//!
//! A module imports only from the layers below its own; `tests/layers.rs` fails on any
//! other import.
//!
//! | layer | may use |
//! |---|---|
//! | [`model`]: the kernel | — |
//! | [`spatial`]: the index and its queries | model |
//! | [`edit`]: the command language, in the journal's serde form; `plan` and `apply` | model |
//! | [`store`]: journal and snapshots | model, edit |
//! | [`mesh`]: mesh files in and out | model |
//! | [`camera`]: projection and clipping | model |
//! | [`render`]: appearance | model, spatial, camera |
//! | [`vision`]: image analysis and camera solution | model, spatial, camera, render |
//! | [`server`]: the owner, HTTP, events, auth, metrics | everything below |

pub mod camera;
pub mod edit;
pub mod mesh;
pub mod model;
pub mod render;
pub mod server;
pub mod spatial;
pub mod store;
pub mod vision;

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
