//! Image analysis: what an 8-bit picture says about where edges are. The alignment of a
//! camera with a picture ([`align_to_image`](super::solve::align::align_to_image)) reads
//! its edges here.
//!
//! * [`Luma`]: a grey-level picture, made from the samples a PNG decoder gives (1 to 4
//!   channels), halved for a coarse-to-fine pyramid.
//! * [`EdgeMap`]: Sobel gradients, non-maximum suppression along the gradient and a
//!   threshold set from the picture's own noise; each edge pixel (an [`Edgel`]) carries
//!   a sub-pixel position on the edge and the edge's unit normal.
//! * [`ImageError`]: why a picture, or what is asked of it, was refused; the camera
//!   solution wraps it in its own error.
//! * [`DistanceField`]: the exact Euclidean distance transform of a set of pixels
//!   (Felzenszwalb–Huttenlocher), with the nearest of those pixels for every pixel, so an
//!   edge can be found from any point of the image in constant time.
//! * [`trace_regions`]: the 4-connected regions of a binary [`Mask`] as polygons with
//!   holes ([`Region`]), traced along pixel cracks and simplified ([`ContourOptions`]).
//!
//! # Why hand-written
//!
//! The one well-kept Rust crate with Canny edges and distance transforms, `imageproc`,
//! brings the `image` crate and a dozen more (fonts, random numbers, `num`, `itertools`)
//! into the build for three short routines, and its distance transform returns distances
//! but not the nearest edge pixel, which the alignment needs. The routines here are
//! small, and each is tested against a brute-force or analytic answer.

mod contour;
mod distance;
mod edges;
mod error;
mod luma;

pub use contour::{ContourOptions, Mask, Region, trace_regions};
pub use distance::{DistanceField, NO_SITE};
pub use edges::{EdgeMap, EdgeOptions, Edgel};
pub use error::ImageError;
pub use luma::Luma;
