//! Appearance: what the world looks like from a camera.
//!
//! Rendering reads a [`Scene`], the world flattened for drawing at one revision, and
//! never touches the shared world. [`scene`] builds it; [`image`] holds the raster
//! images and their PNG encoding; [`lines`] draws anti-aliased lines; [`hidden`] computes
//! the exact hidden-line drawing as vector segments (and draws it, or writes it as SVG).
//!
//! Every mode starts from the same camera ([`crate::camera::View`]) and the same clipping
//! at the near plane, so a pixel of the `ids` image, a depth value and a hidden-line
//! segment all describe the same picture.

pub mod hidden;
pub mod image;
pub mod lines;
pub mod sample;
pub mod scene;

pub use image::{Gray16, RgbImage};
pub use scene::{Scene, SceneBody, SceneEdge, SceneFace, default_color};
