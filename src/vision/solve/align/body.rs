//! Aligning one body with a picture, the camera fixed: where a body that moved is now.
//!
//! The alignment of a camera ([`align_to_image`](super::align_to_image)) moves the
//! camera until the model's edges lie on the picture's. Moving one body by a rigid motion
//! `M` (world points `X ↦ M·X`) under a fixed camera `(R, t)` (OpenCV's world-to-camera
//! rotation and translation) shows the body exactly as the camera `(R·M_R, R·M_t + t)`
//! shows it unmoved, so the same Levenberg–Marquardt iteration on the same matches finds
//! `M`, with two differences in what is drawn at each pose:
//!
//! * only the body's own edges are sampled (the rest of the scene stays where the model
//!   has it);
//! * visibility comes from the whole scene with the body moved by the current `M`, seen
//!   by the fixed camera, so the edges that other bodies hide, and the edges of other
//!   bodies that the moved body hides, are those of the pose being tried.
//!
//! The samples are then carried back into the body's unmoved frame (`X = M⁻¹·X'`), where
//! the pose being solved maps them into the camera.
//!
//! A body a few tens of pixels wide shows a move along the line of sight only as a
//! change of scale, a fraction of a pixel per centimetre: its edges alone leave its depth
//! nearly free, and noise moves it by centimetres. Bodies that move mostly slide on what
//! they stand on, so the height (world z, which is up) of the body's centre is held to
//! the height the start gives it by a prior, a residual of one (as a pixel of distance
//! counts) per [`HEIGHT_DEVIATION_M`]. Seen from above the horizon, a slide across the
//! line of sight and one along it then differ in the image, and the depth is fixed; a
//! change of height that the edges show clearly (a body knocked over) still wins.
//!
//! A second prior holds the body's turn near none: its tilt (about the horizontal axes)
//! with a deviation of [`UPRIGHT_DEVIATION_DEG`], its turn about the vertical with one of
//! [`TURN_DEVIATION_DEG`]. A body standing on a table stays upright when it is pushed,
//! and the turn of a body whose outline does not fix it (a many-sided cylinder, whose
//! sides are smooth and not drawn) stays near the model's instead of wandering; a turn the
//! edges show outweighs the prior by far.

use glam::{DMat3, DQuat, DVec3};

use super::{
    AlignOptions, Drawing, EdgeFaces, EdgePyramid, PlanePrior, PoseEstimate, Priors, Sample,
    SolveError, TurnPrior, camera_at, sample_pieces,
};

/// The deviation of the prior on the height of a body's centre, meters.
pub const HEIGHT_DEVIATION_M: f64 = 0.01;

/// The deviation of the prior on the tilt of a body's vertical axis, degrees.
pub const UPRIGHT_DEVIATION_DEG: f64 = 1.0;

/// The deviation of the prior on a body's turn about the vertical, degrees.
pub const TURN_DEVIATION_DEG: f64 = 10.0;
use crate::camera::{Camera, Intrinsics};
use crate::model::Pose;
use crate::render::Scene;

/// A rigid motion of world points, `X ↦ rotation·X + position` (a [`Pose`] read as a
/// transformation).
pub type Motion = Pose;

/// The outcome of [`align_body`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlignedBody {
    /// The motion that carries the body from where the scene has it to where the picture
    /// shows it.
    pub motion: Motion,
    /// Levenberg–Marquardt iterations over all levels.
    pub iterations: usize,
    /// Root mean square of the point-to-line distance of the inliers, pixels.
    pub rms_px: f64,
    /// Samples on the moved body's visible edges.
    pub samples: usize,
    /// The fraction of those samples within [`AlignOptions::inlier_px`] of an image edge
    /// of their direction.
    pub inlier_fraction: f64,
}

/// Finds the motion of body `body` (an index into [`Scene::bodies`]) that lays its visible
/// edges, seen by `camera` with the rest of `scene` in place, on the edges of the picture
/// whose edges `pyramid` holds, starting from `start` (the identity when the body is
/// looked for near where the scene has it). The priors hold the centre to the height the
/// scene gives it and the body's turn near none (see the module documentation), whatever
/// the start.
///
/// Preconditions, refused with errors: `camera` is valid and of the pyramid's size,
/// `body` is a body of the scene ([`SolveError::BadParameter`]), the options are in
/// range, and at least [`AlignOptions::min_samples`] samples of the body's edges are
/// visible at `start`.
///
/// Postconditions as [`align_to_image`](super::align_to_image)'s: the finest level
/// converged and at least [`AlignOptions::min_inlier_fraction`] of the body's visible
/// samples lie on image edges at the answered motion; otherwise an error, never a motion.
/// How far the motion may carry the body is the caller's to bound.
pub fn align_body(
    scene: &Scene,
    body: usize,
    camera: &Camera,
    pyramid: &EdgePyramid,
    start: &Motion,
    options: &AlignOptions,
) -> Result<AlignedBody, SolveError> {
    let camera = camera.validated()?;
    pyramid.check(&camera.intrinsics, options)?;
    let mut drawing = BodyDrawing::new(scene, body, camera, options)?;
    drawing.hold_upright_at(&drawing.pose_of(&Pose::IDENTITY));
    let start = drawing.pose_of(start);
    let found = pyramid.align(&drawing, start, options)?;
    Ok(AlignedBody {
        motion: drawing.motion_of(&found.pose),
        iterations: found.iterations,
        rms_px: found.rms_px,
        samples: found.samples,
        inlier_fraction: found.inlier_fraction,
    })
}

/// One body of a scene moved, seen by a fixed camera.
struct BodyDrawing<'a> {
    scene: &'a Scene,
    /// Index into the scene's bodies.
    body: usize,
    /// The body's id, as the hidden-line drawing names it.
    id: u64,
    /// The body's points: indices into the scene's points.
    points: Vec<u32>,
    camera: Camera,
    /// OpenCV's world-to-camera rotation and translation of the fixed camera.
    rotation: DMat3,
    translation: DVec3,
    edge_faces: EdgeFaces,
    options: &'a AlignOptions,
    /// Where the priors hold the body's centre (its height at the start) and its
    /// vertical axis (upright as the start has it).
    priors: Priors,
}

impl<'a> BodyDrawing<'a> {
    fn new(
        scene: &'a Scene,
        body: usize,
        camera: Camera,
        options: &'a AlignOptions,
    ) -> Result<BodyDrawing<'a>, SolveError> {
        let Some(id) = scene.bodies.get(body).map(|b| b.id.get()) else {
            return Err(SolveError::BadParameter {
                what: "the body's index in the scene",
                value: body as f64,
            });
        };
        let points = scene.body_points(body);
        let (rotation, translation) = camera.to_opencv();
        Ok(BodyDrawing {
            scene,
            body,
            id,
            points,
            camera,
            rotation,
            translation,
            edge_faces: EdgeFaces::of(scene),
            options,
            priors: Priors::default(),
        })
    }

    /// Holds the body's centre, unmoved, to the height (world z) it has at `pose`, and its
    /// vertical axis to the direction `pose` gives it.
    fn hold_upright_at(&mut self, pose: &PoseEstimate) {
        if self.points.is_empty() {
            return;
        }
        let centre = self
            .points
            .iter()
            .map(|&i| self.scene.points[i as usize])
            .sum::<DVec3>()
            / self.points.len() as f64;
        // World z in the camera's frame: the height of a camera point p is
        // up·(p − t), with up = R·ẑ.
        let up = self.rotation * DVec3::Z;
        let start = DMat3::from_quat(pose.rotation) * centre + pose.translation;
        self.priors = Priors {
            plane: Some(PlanePrior {
                point: centre,
                normal: up,
                offset: up.dot(start),
                deviation: HEIGHT_DEVIATION_M,
            }),
            turn: Some(TurnPrior {
                rotation: pose.rotation,
                deviation: DVec3::new(
                    UPRIGHT_DEVIATION_DEG.to_radians(),
                    UPRIGHT_DEVIATION_DEG.to_radians(),
                    TURN_DEVIATION_DEG.to_radians(),
                ),
            }),
        };
    }

    /// The pose that shows the unmoved body as the fixed camera shows it moved by
    /// `motion`.
    fn pose_of(&self, motion: &Motion) -> PoseEstimate {
        let m = motion.rotation_matrix();
        PoseEstimate::new(
            self.rotation * m,
            self.rotation * motion.position + self.translation,
        )
    }

    /// The motion that [`BodyDrawing::pose_of`] maps to `pose`: `M_R = Rᵀ·R'`,
    /// `M_t = Rᵀ·(t' − t)`.
    fn motion_of(&self, pose: &PoseEstimate) -> Motion {
        let back = self.rotation.transpose();
        Pose {
            position: back * (pose.translation - self.translation),
            rotation: (DQuat::from_mat3(&self.rotation).conjugate() * pose.rotation).normalize(),
        }
    }

    /// The scene with the body moved by `motion`.
    fn moved(&self, motion: &Motion) -> Scene {
        self.scene.with_body_moved(self.body, &self.points, motion)
    }
}

impl Drawing for BodyDrawing<'_> {
    fn intrinsics(&self) -> Intrinsics {
        self.camera.intrinsics
    }

    fn priors(&self) -> Priors {
        self.priors
    }

    fn samples(&self, pose: &PoseEstimate, spacing_px: f64) -> Result<Vec<Sample>, SolveError> {
        let motion = self.motion_of(pose);
        let scene = self.moved(&motion);
        let mut samples = sample_pieces(
            &scene,
            &self.edge_faces,
            &self.camera,
            self.options,
            spacing_px,
            |piece| piece.body.get() == self.id,
        );
        let back = motion.inverse();
        for s in &mut samples {
            s.point = back.transform_point(s.point);
            s.direction = back.transform_vector(s.direction);
        }
        // The pose maps unmoved points to the camera; checking it is a valid camera keeps
        // the iteration's poses as the camera alignment's are.
        camera_at(pose, self.camera.intrinsics)?;
        Ok(samples)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Intrinsics as K;
    use crate::render::{Mode, Options, Picture, SHADED_BACKGROUND, render};
    use crate::server::demo::demo_world;
    use crate::vision::image::Luma;

    /// 640 × 480, f = 600, 2 m from the blocks on the demo table.
    fn camera() -> Camera {
        let target = DVec3::new(0.0, 0.0, 0.8);
        let eye = target + DVec3::new(0.55, -0.65, 0.52).normalize() * 2.0;
        let k = K::centered(640, 480, 600.0).expect("intrinsics");
        Camera::look_at(eye, target, DVec3::Z, k).expect("a camera")
    }

    /// The shaded picture of `scene` through `camera`, grey.
    fn picture(scene: &Scene, camera: &Camera) -> Luma {
        let options = Options {
            background: SHADED_BACKGROUND,
            ..Options::default()
        };
        let Ok(Picture::Rgb(rgb)) = render(scene, camera, Mode::Shaded, &options) else {
            panic!("a shaded picture is RGB");
        };
        Luma::from_samples(rgb.width, rgb.height, 3, &rgb.data).expect("a picture")
    }

    #[test]
    fn the_pose_and_the_motion_are_inverse() {
        let scene = Scene::build(&demo_world().expect("the demo"));
        let options = AlignOptions::default();
        let drawing = BodyDrawing::new(&scene, 0, camera(), &options).expect("a drawing");
        let motion = Pose::new(
            DVec3::new(0.03, -0.05, 0.01),
            DQuat::from_axis_angle(DVec3::new(0.2, 0.3, 0.9).normalize(), 0.1),
        )
        .expect("a pose");
        let back = drawing.motion_of(&drawing.pose_of(&motion));
        assert!(
            back.approx_eq(&motion, 1e-12, 1e-12),
            "{back:?} vs {motion:?}"
        );
    }

    #[test]
    fn a_moved_block_is_found_where_the_picture_shows_it() {
        let world = demo_world().expect("the demo");
        let scene = Scene::build(&world);
        let camera = camera();
        // Blocks 10–16 cm wide span 30–50 pixels: samples every pixel of a level.
        let options = AlignOptions {
            levels: 2,
            sample_spacing_px: 1.0,
            min_samples: 12,
            ..AlignOptions::default()
        };
        let blocks = ["cube", "wedge", "pyramid", "drum"];
        for name in blocks {
            let body = scene
                .bodies
                .iter()
                .position(|b| b.name.as_deref() == Some(name))
                .expect("a block of the demo");
            let drawing = BodyDrawing::new(&scene, body, camera, &options).expect("a drawing");
            let centre = drawing
                .points
                .iter()
                .map(|&i| scene.points[i as usize])
                .sum::<DVec3>()
                / drawing.points.len() as f64;
            // Pushed 4 cm and turned 6° about its own vertical axis, as a robot would.
            let turn = DQuat::from_rotation_z(6f64.to_radians());
            let truth = Pose {
                position: DVec3::new(0.04, -0.03, 0.0) + centre - turn * centre,
                rotation: turn,
            };
            let image = picture(&drawing.moved(&truth), &camera);
            let pyramid = EdgePyramid::new(&image, &options).expect("edges");
            let found = align_body(&scene, body, &camera, &pyramid, &Pose::IDENTITY, &options)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            // The drum is a 24-sided prism: turns by 15° show the same body, so
            // placements are compared by where its corners are, up to that symmetry.
            let corners: Vec<DVec3> = drawing
                .points
                .iter()
                .map(|&i| scene.points[i as usize])
                .collect();
            let placement = corners
                .iter()
                .map(|&c| {
                    let got = found.motion.transform_point(c);
                    corners
                        .iter()
                        .map(|&t| got.distance(truth.transform_point(t)))
                        .fold(f64::INFINITY, f64::min)
                })
                .fold(0.0, f64::max);
            let turn = found.motion.angle_to(&truth).to_degrees();
            assert!(
                placement < 0.01 && (name == "drum" || turn < 1.0),
                "{name}: corners {:.1} mm off, turned {turn:.2}° off ({:?} vs {truth:?})",
                placement * 1e3,
                found.motion
            );
        }
    }
}
