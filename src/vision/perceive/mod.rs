//! Perception: new bodies from the silhouettes that solved cameras see, carved view after
//! view (Baumgart's fourth access mode).
//!
//! A silhouette region seen by a camera is a cone of rays from the camera's centre
//! through the region; a solid seen in every view lies in every view's cone, so the
//! intersection of the cones (the *visual hull*, Laurentini 1994) is the largest solid
//! consistent with them all. More views carve it closer to the object.
//!
//! * [`silhouette`]: masks to polygons with holes (regions widened by a tolerance, traced
//!   along pixel cracks and simplified within a fraction of a pixel).
//! * [`cone`]: one ring's cone between two depths as a closed polyhedron.
//! * [`bound`]: the convex polyhedron carving starts from, the intersection of every
//!   view's frustum about its silhouette's convex hull.
//! * [`carve`]: one view carves a polyhedron, with every decision made exactly in its
//!   image; where that meets a degenerate configuration, [`carve_by`] takes the general
//!   boolean of the polyhedron and the view's cone instead.
//!
//! * [`occlusion`]: pixels a modeled body covers next to a silhouette join it, so that a
//!   view does not carve away what a known body hides.
//! * [`views`]: a request's views (cameras and masks) to bodies.
//!
//! Every face of a result records the view and the silhouette edge that made it
//! ([`Maker`]).

pub mod bound;
pub mod carve;
pub mod cone;
pub mod holes;
pub mod mesh;
pub mod occlusion;
pub mod silhouette;
#[cfg(test)]
mod tests;
pub mod views;

use glam::DAffine3;

pub use carve::{Outline, Unsure};
pub use mesh::{Maker, Mesh};
pub use views::{MaskView, PerceiveOptions, ViewsError, carve_body, new_bodies, sights};

use crate::model::boolean::{self, BooleanError, Op, Operand, Which};
use crate::model::camera::Camera;
use crate::model::ids::Serials;
use crate::model::solids::BuildError;

/// One view of an object: a solved camera and the object's silhouette in its picture.
#[derive(Clone, Debug)]
pub struct Sight {
    /// The camera.
    pub camera: Camera,
    /// The silhouette, in the camera's pixels.
    pub outline: Outline,
    /// The view's number, recorded in the faces it makes.
    pub view: u32,
}

/// The depths between which cones are taken, metres along each view direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Depths {
    /// Nearest depth (> 0).
    pub near: f64,
    /// Farthest depth (> near).
    pub far: f64,
}

impl Default for Depths {
    /// 5 cm to 20 m.
    fn default() -> Self {
        Depths {
            near: 0.05,
            far: 20.0,
        }
    }
}

/// Why carving failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PerceiveError {
    /// A silhouette has no area.
    #[error("view {view}'s silhouette has no area")]
    NoArea {
        /// The view.
        view: u32,
    },
    /// The general boolean refused a carving the image method could not make.
    #[error("view {view} could not carve the body: {source}")]
    Boolean {
        /// The view.
        view: u32,
        /// The boolean's refusal.
        source: BooleanError,
    },
    /// A polyhedron could not be built.
    #[error("view {view} made a polyhedron that is not a solid: {source}")]
    Build {
        /// The view.
        view: u32,
        /// Why.
        source: BuildError,
    },
}

/// How a view carved: by the image method, or by the general boolean after the image
/// method was unsure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Tally {
    /// Pieces carved by the image method.
    pub exact_image: usize,
    /// Pieces carved by the general boolean.
    pub boolean: usize,
    /// Pieces that a view could not carve (the image method unsure, the general boolean
    /// refusing them as operands), kept whole: still holding everything the silhouettes
    /// allow, but not cut down by that view.
    pub uncarved: usize,
}

/// The visual hull of `sights` between `depths`: its connected pieces, largest volume
/// first; empty when the cones do not meet. Each piece's faces are made by the views'
/// walls (or their near and far ends).
pub fn visual_hull(
    sights: &[Sight],
    depths: Depths,
    tally: &mut Tally,
) -> Result<Vec<Mesh>, PerceiveError> {
    let mut frustums = Vec::with_capacity(sights.len());
    for s in sights {
        let points: Vec<glam::DVec2> = s.outline.rings.iter().flatten().copied().collect();
        let f = bound::frustum(&s.camera, &points, depths.near, depths.far, s.view)
            .ok_or(PerceiveError::NoArea { view: s.view })?;
        frustums.push(f);
    }
    let Some((first, others)) = frustums.split_first() else {
        return Ok(Vec::new());
    };
    let Some(start) = bound::start(first, others) else {
        return Ok(Vec::new());
    };
    carve_body(start, sights, depths, tally)
}

/// `pieces` carved by one more sight: their intersection with its cone between
/// `depths`. Pieces inside the depths and in front of the camera are carved in the
/// image ([`carve::carve`]); others, and those the image method is unsure of, by the
/// general boolean. A piece the boolean refuses (a face of it that is not a simple
/// polygon, or two that cross) is kept as it was and counted in `tally.uncarved`, so
/// that the result still holds every body the silhouettes allow.
pub fn carve_by(
    pieces: Vec<Mesh>,
    sight: &Sight,
    depths: Depths,
    tally: &mut Tally,
) -> Result<Vec<Mesh>, PerceiveError> {
    let mut out = Vec::new();
    for piece in pieces {
        if within(&piece, &sight.camera, depths) {
            match carve::carve(&piece, &sight.camera, &sight.outline, sight.view) {
                Ok(made) => {
                    tally.exact_image += 1;
                    out.extend(made);
                    continue;
                }
                Err(why) => {
                    tracing::debug!(view = sight.view, %why, "carving by the general boolean");
                }
            }
        }
        match carve_by_boolean(&piece, sight, depths) {
            Ok(made) => {
                tally.boolean += 1;
                out.extend(made);
            }
            Err(why) => {
                tracing::warn!(view = sight.view, %why, "a piece left uncarved by this view");
                tally.uncarved += 1;
                out.push(piece);
            }
        }
    }
    Ok(out)
}

/// Whether every vertex of `mesh` lies between the depths (within rounding).
fn within(mesh: &Mesh, camera: &Camera, depths: Depths) -> bool {
    let slack = 1e-9;
    mesh.positions.iter().all(|p| {
        let d = -camera.world_to_camera(*p).z;
        d >= depths.near * (1.0 - slack) && d <= depths.far * (1.0 + slack)
    })
}

/// `mesh ∩ cone(each outer ring) − cone(each hole)`, by the general boolean. Outer
/// rings (turning from +u toward +v) bound disjoint regions, so their cones are
/// disjoint and each gives its own pieces.
fn carve_by_boolean(
    mesh: &Mesh,
    sight: &Sight,
    depths: Depths,
) -> Result<Vec<Mesh>, PerceiveError> {
    let view = sight.view;
    let area = |ring: &[glam::DVec2]| -> f64 {
        (0..ring.len())
            .map(|k| ring[k].perp_dot(ring[(k + 1) % ring.len()]))
            .sum()
    };
    let mut pieces = Vec::new();
    for (r, ring) in sight.outline.rings.iter().enumerate() {
        if area(ring) > 0.0 {
            let tool = cone::cone(&sight.camera, ring, depths.near, depths.far, view, r as u32);
            pieces.extend(boolean_of(mesh, &tool, Op::Intersection, view)?);
        }
    }
    for (r, ring) in sight.outline.rings.iter().enumerate() {
        if area(ring) < 0.0 {
            // Longer than the outer cones, so that it cuts through their ends.
            let (near, far) = (depths.near * 0.5, depths.far * 2.0);
            let tool = cone::cone(&sight.camera, ring, near, far, view, r as u32);
            let mut next = Vec::new();
            for piece in &pieces {
                next.extend(boolean_of(piece, &tool, Op::Difference, view)?);
            }
            pieces = next;
        }
    }
    Ok(pieces)
}

/// One boolean of two meshes, the makers carried to the result's faces.
fn boolean_of(a: &Mesh, b: &Mesh, op: Op, view: u32) -> Result<Vec<Mesh>, PerceiveError> {
    let build = |source| PerceiveError::Build { view, source };
    let mut serials = Serials::new();
    let body_a = a.to_body(&mut serials).map_err(build)?;
    let body_b = b.to_body(&mut serials).map_err(build)?;
    let index_of = |body: &crate::model::Body| {
        let mut serials: Vec<_> = body.faces().map(|f| body.face_serial(f)).collect();
        serials.sort_unstable();
        serials
    };
    let (serials_a, serials_b) = (index_of(&body_a), index_of(&body_b));
    let solution = boolean::boolean(
        Operand {
            body: &body_a,
            place: DAffine3::IDENTITY,
        },
        Operand {
            body: &body_b,
            place: DAffine3::IDENTITY,
        },
        op,
    )
    .map_err(|source| PerceiveError::Boolean { view, source })?;
    let mut out = Vec::new();
    for shell in solution.shells {
        let makers = shell
            .sources
            .iter()
            .map(|s| {
                let (list, makers) = match s.operand {
                    Which::A => (&serials_a, &a.makers),
                    Which::B => (&serials_b, &b.makers),
                };
                list.binary_search(&s.face)
                    .map(|i| makers[i])
                    .unwrap_or(Maker::Bound { view })
            })
            .collect();
        out.push(Mesh {
            positions: shell.positions,
            faces: shell.faces,
            makers,
        });
    }
    Ok(out)
}
