//! Spatial access, Baumgart's fifth access mode: given a locus and a radius, the
//! portions of objects in that sphere; and the companions users of other world models
//! ask for: the portions in an axis-aligned box, the body nearest a point and the first
//! surface along a ray.
//!
//! [`Spatial`] indexes one world revision: a hierarchy over each body's faces in the
//! body's own frame ([`shape`]) and a hierarchy over the bodies' world bounds
//! ([`index`]). Moving a body refits one path of the top hierarchy; editing a body's
//! geometry rebuilds that body's shape only. Small convex bodies also keep flat
//! world-frame records (the `hull` module) that answer the sphere query at `bodies` detail without
//! reading their shapes. Every answer comes from exact tests
//! ([`exact`]) on the candidates the hierarchies leave, in world coordinates, and
//! carries the revision it was computed at.
//!
//! Like rendering, queries read a snapshot and never touch the shared world.

pub mod aabb;
pub mod bvh;
pub mod exact;
mod hits;
mod hull;
pub mod index;
mod prefetch;
pub mod query;
mod reach;
pub mod shape;
#[cfg(test)]
mod testing;

pub use index::{Fork, Spatial, SyncStats};
pub use query::{
    BodyHit, BoxAnswer, BoxQuery, DEFAULT_MAX_FEATURES, DEFAULT_TOLERANCE, Detail, EdgeHit,
    FaceHit, Found, Nearest, QueryError, RayHit, SphereAnswer, SphereQuery, VertexHit,
};
