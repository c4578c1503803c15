//! Vision: image analysis, camera solution and recognition, what pictures and the points
//! seen in them say about the world and the camera that took them.
//!
//! * [`image`]: image analysis shared by whatever reads pictures: grey levels, a
//!   coarse-to-fine pyramid, edges with sub-pixel positions and normals, and their distance
//!   transform.
//! * [`solve`]: camera solution: where a camera is, from points whose world positions are
//!   known and where it sees them (P3P, SQPnP, LO-RANSAC, robust Levenberg–Marquardt, the
//!   focal length), or from a picture's edges and the world model
//!   ([`align_to_image`](solve::align::align_to_image)), and where one body of the model
//!   now is ([`align_body`](solve::align::align_body)).
//! * [`recognize`]: which modeled bodies a picture shows (seen, moved, absent, occluded),
//!   their visible fractions by exact polygon clipping, and the regions nothing modeled
//!   explains.
//! * [`perceive`]: new bodies from silhouettes seen by solved cameras: the cones through
//!   them intersected view after view (the visual hull).
//!
//! Pure, synchronous numerics with no I/O. The layer reads the world through [`model`]
//! (cameras, poses), [`camera`] (projection) and [`render`] (the scene and its exact
//! hidden-line drawing), and nothing above them.
//!
//! [`model`]: crate::model
//! [`camera`]: crate::camera
//! [`render`]: crate::render

pub mod image;
pub mod perceive;
pub mod recognize;
pub mod solve;
#[cfg(test)]
mod testing;
