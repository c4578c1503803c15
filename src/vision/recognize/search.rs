//! Looking for a body near where the model has it: a body the picture does not show in
//! place may have been pushed, turned or knocked over a little.
//!
//! 1. **Shift.** The body's predicted visible edge points are shifted over a grid of
//!    image offsets covering the farthest it may have moved ([`SearchBounds`], at the
//!    body's depth), and the offset at which most of them lie on image edges running
//!    their way is kept. A move across the line of sight is an image shift to first
//!    order; a turn of a few degrees moves a small body's edges by a few pixels.
//! 2. **Pose.** From the motion that the best offset stands for (a slide at the height
//!    of the body's centre), turned about the body's vertical axis by none and by half
//!    the rotation bound either way, the body's pose is aligned with the picture's edges
//!    ([`align_body`]), the rest of the scene in place.
//! 3. **Bounds.** Of the poses found, the one with most of its edge samples on image
//!    edges is answered, among those that carry the body's centre no farther than
//!    [`SearchBounds::translation_m`] and turn it by no more than
//!    [`SearchBounds::rotation_deg`].

use glam::{DQuat, DVec2, DVec3};

use super::evidence::{EdgePoint, Matching};
use crate::camera::Camera;
use crate::model::Pose;
use crate::render::Scene;
use crate::vision::solve::align::{AlignOptions, EdgePyramid, Motion, align_body};

/// How far a body may have moved and still be looked for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchBounds {
    /// The farthest its centre may have moved, meters; finite and positive.
    pub translation_m: f64,
    /// The largest turn, degrees, in (0, 180].
    pub rotation_deg: f64,
}

impl Default for SearchBounds {
    /// 10 cm and 10°.
    fn default() -> Self {
        SearchBounds {
            translation_m: 0.1,
            rotation_deg: 10.0,
        }
    }
}

/// The largest image offset tried, pixels, whatever the bounds and depth give.
const MAX_SHIFT_PX: f64 = 160.0;

/// The most grid steps across the shift search in each direction.
const SHIFT_STEPS: f64 = 24.0;

/// A body found moved: the motion and the fraction of its visible edge samples on image
/// edges once aligned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Moved {
    /// World points `X ↦ motion·X`: from where the scene has the body to where it is.
    pub motion: Motion,
    /// The fraction of its visible edge samples within the inlier distance of an image
    /// edge of their direction, at the motion found.
    pub inlier_fraction: f64,
}

/// What the search for one body needs.
pub struct Search<'a> {
    /// The model, bodies where it has them.
    pub scene: &'a Scene,
    /// The camera that took the picture.
    pub camera: &'a Camera,
    /// The picture's edges.
    pub pyramid: &'a EdgePyramid,
    /// How edge points are matched in the shift search.
    pub matching: Matching,
    /// How far a body may have moved.
    pub bounds: SearchBounds,
    /// How the body's pose is aligned from the best shift.
    pub align: &'a AlignOptions,
}

impl Search<'_> {
    /// Looks for body `body` (an index into the scene's bodies), whose visible edge
    /// points where the model has it are `points`, near there (see the module
    /// documentation). `None` when no pose within the bounds lays its edges on the
    /// picture's.
    pub fn find(&self, body: usize, points: &[EdgePoint]) -> Option<Moved> {
        let corners = self.scene.body_points(body);
        if corners.is_empty() || points.is_empty() {
            return None;
        }
        let centre = corners
            .iter()
            .map(|&i| self.scene.points[i as usize])
            .sum::<DVec3>()
            / corners.len() as f64;
        let (rotation, translation) = self.camera.to_opencv();
        let in_camera = rotation * centre + translation;
        if in_camera.z.is_nan() || in_camera.z <= 0.0 {
            return None;
        }
        let k = self.camera.intrinsics;
        let reach = (k.fx.max(k.fy) * self.bounds.translation_m / in_camera.z).min(MAX_SHIFT_PX);
        let Some(shift) = self.best_shift(points, reach) else {
            tracing::debug!(body = ?self.scene.bodies[body].name, reach, "no shift lays any edge point on the picture's");
            return None;
        };
        // The slide at the centre's height that shows the centre `shift` away: where the
        // ray through the shifted image of the centre meets that level (or, for a ray
        // nearly level, the translation parallel to the image at the centre's depth).
        let back = rotation.transpose();
        let eye = self.camera.position();
        let pixel = DVec2::new(
            k.cx + k.fx * in_camera.x / in_camera.z,
            k.cy + k.fy * in_camera.y / in_camera.z,
        ) + shift;
        let ray = back * DVec3::new((pixel.x - k.cx) / k.fx, (pixel.y - k.cy) / k.fy, 1.0);
        let across = back
            * DVec3::new(
                shift.x * in_camera.z / k.fx,
                shift.y * in_camera.z / k.fy,
                0.0,
            );
        let slide = if ray.z.abs() > 1e-3 {
            let s = (centre.z - eye.z) / ray.z;
            let at = eye + ray * s;
            if s > 0.0 && (at - centre).length() <= 2.0 * across.length() + 1e-9 {
                at - centre
            } else {
                across
            }
        } else {
            across
        };
        // Starts turned about the body's vertical axis through its centre by none, and
        // by half the bound either way: a turn of a few degrees moves the corners of a
        // larger body by more than the alignment's reach, and the best fit is kept.
        let half = 0.5 * self.bounds.rotation_deg.to_radians();
        let mut best: Option<Moved> = None;
        for turn in [0.0, half, -half] {
            let q = DQuat::from_rotation_z(turn);
            let start = Pose {
                position: slide + centre - q * centre,
                rotation: q,
            };
            let aligned = match align_body(
                self.scene,
                body,
                self.camera,
                self.pyramid,
                &start,
                self.align,
            ) {
                Ok(aligned) => aligned,
                Err(e) => {
                    tracing::debug!(body = ?self.scene.bodies[body].name, ?shift, turn, error = %e, "the body's pose did not align");
                    continue;
                }
            };
            let moved = aligned.motion.transform_point(centre) - centre;
            let turned = aligned.motion.angle_to(&Pose::IDENTITY);
            let within = moved.length() <= self.bounds.translation_m
                && turned <= self.bounds.rotation_deg.to_radians();
            tracing::debug!(
                body = ?self.scene.bodies[body].name,
                ?shift,
                start_turn_deg = turn.to_degrees(),
                moved_m = moved.length(),
                turn_deg = turned.to_degrees(),
                inliers = aligned.inlier_fraction,
                within,
                "aligned"
            );
            if within && best.is_none_or(|b| aligned.inlier_fraction > b.inlier_fraction) {
                best = Some(Moved {
                    motion: aligned.motion,
                    inlier_fraction: aligned.inlier_fraction,
                });
            }
        }
        best
    }

    /// The image offset within `reach` pixels at which most of `points` are supported,
    /// the smaller offset among equals; `None` when none is supported anywhere.
    fn best_shift(&self, points: &[EdgePoint], reach: f64) -> Option<DVec2> {
        let step = (reach / SHIFT_STEPS).max(1.0);
        // A point counts within half a step more, so that an edge between grid offsets
        // is not missed.
        let loose = Matching {
            tolerance_px: self.matching.tolerance_px + 0.5 * step,
            ..self.matching
        };
        let edges = self.pyramid.finest();
        let n = (reach / step).floor() as i64;
        let mut best: Option<(usize, f64, DVec2)> = None;
        for j in -n..=n {
            for i in -n..=n {
                let shift = DVec2::new(i as f64 * step, j as f64 * step);
                let distance = shift.length();
                if distance > reach {
                    continue;
                }
                let hits = points
                    .iter()
                    .filter(|p| loose.supported_at(edges, p, shift))
                    .count();
                let better = match best {
                    None => hits > 0,
                    Some((h, d, _)) => hits > h || (hits == h && distance < d),
                };
                if better {
                    best = Some((hits, distance, shift));
                }
            }
        }
        best.map(|(_, _, shift)| shift)
    }
}
