//! Image-based camera refinement: moving a roughly known camera until the model's visible
//! edges lie on the edges of the picture it took.
//!
//! A robot whose odometry has drifted knows its camera only roughly; one picture and the
//! world model correct it. [`align_to_image`] takes the model ([`Scene`]), the rough
//! camera and the picture ([`Luma`]) and returns the camera whose exact hidden-line
//! drawing ([`hidden_lines`]) best matches the picture's edges.
//!
//! # Method
//!
//! Model-based edge alignment with a distance transform (as in chamfer matching and
//! model-based edge tracking), refined to sub-pixel precision:
//!
//! 1. **Image edges.** The picture and its halvings form a pyramid of
//!    [`AlignOptions::levels`] levels; each level's edges are found ([`EdgeMap`]: Sobel,
//!    non-maximum suppression, a threshold from the picture's noise, sub-pixel positions
//!    and normals) together with their distance transform, so the nearest edge pixel to
//!    any point is one look-up.
//! 2. **Model edges.** From the current camera, the exact hidden-line drawing gives the
//!    visible pieces of the model's edges. Points are sampled along each piece every
//!    [`AlignOptions::sample_spacing_px`] pixels of the level, and lifted to the 3D points
//!    of the edge they show: a piece is the image of a straight 3D segment, whose ends are
//!    known from the drawn depths, and the image fraction `s` along it is the 3D fraction
//!    `τ = s·d_a / ((1 − s)·d_b + s·d_a)` (d_a, d_b the depths of the ends). The samples
//!    are drawn again every [`AlignOptions::visibility_every`] iterations, as the camera
//!    moves and edges come into view or go behind faces. Edges of a face seen nearly
//!    edge-on are left out ([`AlignOptions::grazing_cosine`]).
//! 3. **Matching.** Each sample projects through the current camera to a point `p`; the
//!    distance transform gives the nearest edge pixel, with sub-pixel position `e` and
//!    unit normal `n`. The match is kept when `|p − e|` is at most
//!    [`AlignOptions::capture_px`] ([`AlignOptions::match_px`] on the finest of several
//!    levels) and the image edge runs within [`AlignOptions::max_angle_deg`] of the model
//!    edge's projected direction (a shadow boundary across an edge does not count); its
//!    residual is the point-to-line distance `r = n·(p − e)`.
//! 4. **Pose.** As in ICP, matching and moving alternate. The cost of the matches,
//!    `½·Σ ρ(r²)` with the robust [`Loss`] ρ in pixels of the level, is lowered by a
//!    Levenberg–Marquardt step over the six degrees of freedom, the rotation on SO(3) as in
//!    [`refine_pose`](super::refine_pose): `R ← exp([δω]×)·R`, `t ← t + δt` in OpenCV's
//!    camera frame. A step is kept when it lowers the cost of the matches it was computed
//!    from (otherwise the damping grows and a shorter one is tried); the samples are then
//!    matched anew at the new pose. The nearest edge pixel changes in jumps as a point
//!    moves, so the iteration need not reach a fixed point: a level ends when a step would
//!    move no matched sample by more than [`AlignOptions::tolerance_px`] (or the cost
//!    changes by rounding only). Judging a step by the cost of fresh matches instead
//!    stalls at those jumps, short of the minimum; judging it by the matches it came from
//!    converges to the same pose from every start near it.
//! 5. **Coarse to fine.** The coarsest level runs first: a pixel there spans `2^ℓ` pixels
//!    of the picture, so the matching distance and the loss scale reach that much
//!    farther, and small or close edges merge. The finest level starts within a pixel or
//!    two of the answer and matches only nearby edges, so that an edge the model does not
//!    show (a shadow, the far side of a table leg) cannot pull the answer off. A start 2°
//!    and 5 cm off at 2 m (15–35 pixels at f = 600) is a few pixels at the coarsest of
//!    three levels.
//!
//! # What is trusted
//!
//! The answer is returned only when the finest level met its convergence test and, at the
//! final camera, at least [`AlignOptions::min_inlier_fraction`] of the model's visible
//! edge samples lie within [`AlignOptions::inlier_px`] of an image edge of the right
//! direction; otherwise the caller gets a typed error, never a camera. A start from which
//! a wrong alignment also explains that much of the model (a repetitive scene, a start far
//! outside the capture range) cannot be told from a right one by this test.

use std::collections::HashMap;

use glam::{DMat3, DQuat, DVec2, DVec3};

use super::SolveError;
use super::lm::{
    NormalEquations, PoseEstimate, PoseProblem, PoseStep, Readiness, RoundingTest, Settings,
    minimise,
};
use super::refine::Loss;
use crate::camera::{Camera, DEFAULT_NEAR, Intrinsics, View};
use crate::render::Scene;
use crate::render::hidden::{Segment, hidden_lines};
use crate::vision::image::{EdgeMap, EdgeOptions, Luma};

/// The most pyramid levels [`align_to_image`] accepts.
pub const MAX_LEVELS: usize = 6;

/// A pyramid level is made only while both its sides keep at least this many pixels.
const MIN_LEVEL_SIDE: u32 = 40;

/// A kept step (lightly damped) that lowers the cost of its matches by no more than this
/// fraction of it ends a level as converged.
const COST_ROUNDING: f64 = 1e-12;

/// The fewest matched samples with which a level takes a step (six unknowns).
const MIN_MATCHED: usize = 6;

/// How [`align_to_image`] runs. Distances are in pixels *of the pyramid level* being
/// worked on unless stated otherwise (a pixel of level ℓ is `2^ℓ` pixels of the
/// picture), so the same numbers reach farther on coarser levels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlignOptions {
    /// Pyramid levels, 1 to [`MAX_LEVELS`] (fewer are used when the picture is too small
    /// to halve that often: each side stays at least 40 pixels).
    pub levels: usize,
    /// The most Levenberg–Marquardt iterations on each level; at least 1.
    pub max_iterations: usize,
    /// Distance between samples along a visible edge, level pixels; finite, at least ½.
    pub sample_spacing_px: f64,
    /// The robust loss of the point-to-line residual, level pixels.
    pub loss: Loss,
    /// The farthest a sample may be from its nearest image edge and still be matched,
    /// level pixels, on every level but the finest; finite and positive. With the
    /// coarsest level's size, this is the capture range.
    pub capture_px: f64,
    /// The same on the finest level when there are several: it starts from the previous
    /// level's answer, within a pixel of that level (two of its own), so a match farther
    /// away is an edge the model does not show (a shadow, the far side of a thin part)
    /// and would only pull the answer off. Finite and positive.
    pub match_px: f64,
    /// The largest angle between a model edge's projected direction and a matched image
    /// edge, degrees, in (0, 90].
    pub max_angle_deg: f64,
    /// Iterations between drawings of the model's visible edges; at least 1.
    pub visibility_every: usize,
    /// Convergence: a step that moves no matched sample's projection by more than this
    /// many level pixels ends the level, as does a step changing the cost by rounding
    /// only. Matches are found anew after every step and the nearest edge pixel changes
    /// in jumps, so the iteration may end in a cycle of steps this small rather than at
    /// a fixed point. Finite and positive.
    pub tolerance_px: f64,
    /// A sample within this distance of a matched image edge at the final camera is an
    /// inlier, pixels of the picture; finite and positive.
    pub inlier_px: f64,
    /// The smallest fraction of inliers among the final samples for the answer to be
    /// trusted, in [0, 1].
    pub min_inlier_fraction: f64,
    /// The fewest samples on the model's visible edges, at the start and at the end.
    pub min_samples: usize,
    /// Edges of a face that the camera sees this close to edge-on (the cosine of the
    /// angle between the face's normal and the direction to the eye is below it) are not
    /// sampled. Such a face is a sliver about a pixel wide in the picture, its two edges
    /// merge into one image edge, and where that edge is found depends on how the sliver
    /// was rendered or blurred. In [0, 1); 0 samples every visible edge.
    pub grazing_cosine: f64,
    /// Answer only a pose at which the finest level converged. A caller that judges the
    /// pose by evidence of its own may take the last pose of an iteration that ran out of
    /// iterations cycling between the jumps of the nearest edges; it is still held to the
    /// inlier fraction.
    pub converged_only: bool,
    /// Edges between two faces seen from in front whose normals are within this many
    /// degrees (the sides of a many-sided cylinder) are not sampled: their faces are lit
    /// almost alike and a picture may not show them. In [0, 90); 0 samples them all.
    pub smooth_deg: f64,
    /// The near plane of the hidden-line drawing, meters; finite and positive.
    pub near: f64,
    /// How image edges are detected.
    pub edges: EdgeOptions,
}

impl Default for AlignOptions {
    /// Three levels, 30 iterations a level, a sample every 4 pixels, a Cauchy loss of
    /// scale 1.5 pixels, matches within 10 pixels (3 on the finest level) and 30°,
    /// visibility every 4 iterations, steps down to 0.01 pixel, inliers within 2 pixels,
    /// at least 60 % of them and 30 samples, faces seen within about 3° of edge-on
    /// (cosine 0.05) left out, the renderer's near plane, default edge detection.
    ///
    /// The inlier fraction of 60 % comes from trials on the demo scene (three views,
    /// pixel noise of deviation 6 to 20 grey levels): right alignments kept 62–94 % of
    /// the samples, wrong ones (from starts beyond the capture range, or in the heaviest
    /// noise) at most 49 %.
    fn default() -> Self {
        AlignOptions {
            levels: 3,
            max_iterations: 30,
            sample_spacing_px: 4.0,
            loss: Loss::Cauchy { scale: 1.5 },
            capture_px: 10.0,
            match_px: 3.0,
            max_angle_deg: 30.0,
            visibility_every: 4,
            tolerance_px: 0.01,
            inlier_px: 2.0,
            min_inlier_fraction: 0.6,
            min_samples: 30,
            grazing_cosine: 0.05,
            converged_only: true,
            smooth_deg: 0.0,
            near: DEFAULT_NEAR,
            edges: EdgeOptions::default(),
        }
    }
}

impl AlignOptions {
    fn validate(&self) -> Result<(), SolveError> {
        let bad = |what: &'static str, value: f64| Err(SolveError::BadParameter { what, value });
        if !(1..=MAX_LEVELS).contains(&self.levels) {
            return bad("the number of pyramid levels", self.levels as f64);
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", 0.0);
        }
        if self.visibility_every == 0 {
            return bad("visibility_every", 0.0);
        }
        let positive = [
            (self.capture_px, "capture_px"),
            (self.match_px, "match_px"),
            (self.tolerance_px, "tolerance_px"),
            (self.inlier_px, "inlier_px"),
            (self.near, "the near plane"),
        ];
        for (value, what) in positive {
            if !(value.is_finite() && value > 0.0) {
                return bad(what, value);
            }
        }
        if !(self.sample_spacing_px.is_finite() && self.sample_spacing_px >= 0.5) {
            return bad("sample_spacing_px", self.sample_spacing_px);
        }
        if !(self.max_angle_deg > 0.0 && self.max_angle_deg <= 90.0) {
            return bad("max_angle_deg", self.max_angle_deg);
        }
        if !(0.0..90.0).contains(&self.smooth_deg) {
            return bad("smooth_deg", self.smooth_deg);
        }
        if !(0.0..1.0).contains(&self.grazing_cosine) {
            return bad("grazing_cosine", self.grazing_cosine);
        }
        if !(0.0..=1.0).contains(&self.min_inlier_fraction) {
            return bad("min_inlier_fraction", self.min_inlier_fraction);
        }
        self.loss.validate()?;
        Ok(self.edges.validate()?)
    }
}

/// The outcome of [`align_to_image`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aligned {
    /// The refined camera: the starting camera's intrinsics, a valid pose.
    pub camera: Camera,
    /// Levenberg–Marquardt iterations over all levels (damped systems solved, kept or
    /// not).
    pub iterations: usize,
    /// Root mean square of the point-to-line distance of the inliers at the final
    /// camera, pixels of the picture.
    pub rms_px: f64,
    /// Samples on the model's visible edges at the final camera.
    pub samples: usize,
    /// The fraction of those samples that are inliers (within
    /// [`AlignOptions::inlier_px`] of a matched image edge).
    pub inlier_fraction: f64,
    /// Whether the finest level met its convergence test: always true in a returned
    /// value with [`AlignOptions::converged_only`] (otherwise
    /// [`SolveError::DidNotConverge`] is returned instead).
    pub converged: bool,
}

/// Refines `start` so that the model's visible edges seen through it lie on the edges of
/// `image` (see the [module documentation](self) for the method).
///
/// Preconditions, each refused with an error rather than assumed:
/// * `start` is a valid camera ([`SolveError::BadCamera`]);
/// * `image` is `start.intrinsics.width × height` pixels
///   ([`SolveError::ImageSizeMismatch`]);
/// * `options` are in range ([`SolveError::BadParameter`]);
/// * the image has edges ([`SolveError::NoImageEdges`]) and at least
///   [`AlignOptions::min_samples`] samples of the model's edges are visible from `start`
///   ([`SolveError::NoEdgesVisible`]).
///
/// The start should be within the capture range: roughly, the model's edges as `start`
/// sees them within [`AlignOptions::capture_px`] pixels of the coarsest level (40
/// pixels of the picture with the defaults) of where the picture shows them, and no
/// nearer to another edge of the same direction.
///
/// Postconditions: on success the camera has `start`'s intrinsics, the finest level
/// converged, at least [`AlignOptions::min_samples`] samples are visible from it and at
/// least [`AlignOptions::min_inlier_fraction`] of them are inliers. Otherwise
/// [`SolveError::DidNotConverge`], [`SolveError::NoEdgesVisible`] or
/// [`SolveError::TooFewInliers`]: no camera is returned that failed these tests.
pub fn align_to_image(
    scene: &Scene,
    start: &Camera,
    image: &Luma,
    options: &AlignOptions,
) -> Result<Aligned, SolveError> {
    let start = start.validated()?;
    let k = start.intrinsics;
    if (image.width(), image.height()) != (k.width, k.height) {
        return Err(SolveError::ImageSizeMismatch {
            image_width: image.width(),
            image_height: image.height(),
            camera_width: k.width,
            camera_height: k.height,
        });
    }
    let pyramid = EdgePyramid::new(image, options)?;
    align_camera(scene, &start, &pyramid, options)
}

/// [`align_to_image`] on a picture whose edges are already found: the same method,
/// preconditions and postconditions, with the pyramid's levels and edges in place of
/// `options.levels` and `options.edges`. The pyramid must be of a picture of the
/// camera's size ([`SolveError::ImageSizeMismatch`] otherwise).
pub fn align_camera(
    scene: &Scene,
    start: &Camera,
    pyramid: &EdgePyramid,
    options: &AlignOptions,
) -> Result<Aligned, SolveError> {
    let start = start.validated()?;
    let k = start.intrinsics;
    pyramid.check(&k, options)?;
    let (rotation, translation) = start.to_opencv();
    let start_pose = PoseEstimate::new(rotation, translation);
    let drawing = SceneDrawing {
        scene,
        edge_faces: EdgeFaces::of(scene),
        k,
        options,
    };
    let found = pyramid.align(&drawing, start_pose, options)?;
    let camera = camera_at(&found.pose, k)?;
    Ok(Aligned {
        camera,
        iterations: found.iterations,
        rms_px: found.rms_px,
        samples: found.samples,
        inlier_fraction: found.inlier_fraction,
        converged: found.converged,
    })
}

/// What [`EdgePyramid::align`] found: a pose of the drawing that converged on the finest
/// level and how well its samples lie on the picture's edges.
struct Found {
    pose: PoseEstimate,
    converged: bool,
    iterations: usize,
    rms_px: f64,
    samples: usize,
    inlier_fraction: f64,
}

/// The world's camera at `pose` (OpenCV's frame) with intrinsics `k`.
fn camera_at(pose: &PoseEstimate, k: Intrinsics) -> Result<Camera, SolveError> {
    Ok(Camera::from_opencv(
        DMat3::from_quat(pose.rotation),
        pose.translation,
        k,
    )?)
}

/// A point on a visible model edge, with the edge's direction (world coordinates).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Sample {
    point: DVec3,
    direction: DVec3,
}

/// The two faces of every edge of a scene, found by body and edge serial (as the
/// hidden-line drawing names them).
struct EdgeFaces(HashMap<(u64, u64), [u32; 2]>);

impl EdgeFaces {
    fn of(scene: &Scene) -> EdgeFaces {
        EdgeFaces(
            scene
                .edges
                .iter()
                .filter_map(|e| {
                    let body = scene.bodies.get(e.body as usize)?.id.get();
                    Some(((body, e.serial), e.faces))
                })
                .collect(),
        )
    }

    /// Whether the edge named by `piece` is smooth: its two faces are both seen from in
    /// front by an eye at `eye` and their normals are within `degrees` of each other
    /// (never, for `degrees` 0).
    fn smooth(&self, scene: &Scene, piece: &Segment, eye: DVec3, degrees: f64) -> bool {
        if degrees <= 0.0 {
            return false;
        }
        let Some(&[f, g]) = self.0.get(&(piece.body.get(), piece.edge)) else {
            return false;
        };
        let (Some(f), Some(g)) = (scene.faces.get(f as usize), scene.faces.get(g as usize)) else {
            return false;
        };
        f.faces_toward(eye)
            && g.faces_toward(eye)
            && f.normal.dot(g.normal) > degrees.to_radians().cos()
    }

    /// Whether the edge named by `piece` borders a face seen from in front, at `point`
    /// (a point of the edge), at an angle whose cosine is below `grazing` (nearly
    /// edge-on) by an eye at `eye`.
    fn grazes(
        &self,
        scene: &Scene,
        piece: &Segment,
        point: DVec3,
        eye: DVec3,
        grazing: f64,
    ) -> bool {
        let Some(faces) = self.0.get(&(piece.body.get(), piece.edge)) else {
            return false;
        };
        let to_eye = eye - point;
        faces.iter().any(|&f| {
            scene.faces.get(f as usize).is_some_and(|face| {
                let toward = face.normal.dot(to_eye);
                toward > 0.0 && toward < grazing * to_eye.length()
            })
        })
    }
}

/// Points every `spacing_px` pixels (of the camera's image) along the visible pieces of
/// the model's edges seen by `camera`; pieces shorter than one spacing give none, and
/// neither do edges of faces seen nearly edge-on ([`AlignOptions::grazing_cosine`]).
/// Each sample is the 3D point of the edge that its image point shows (see the module
/// documentation).
fn sample_edges(
    scene: &Scene,
    edge_faces: &EdgeFaces,
    camera: &Camera,
    options: &AlignOptions,
    spacing_px: f64,
) -> Vec<Sample> {
    sample_pieces(scene, edge_faces, camera, options, spacing_px, |_| true)
}

/// [`sample_edges`] on the visible pieces for which `keep` holds.
fn sample_pieces(
    scene: &Scene,
    edge_faces: &EdgeFaces,
    camera: &Camera,
    options: &AlignOptions,
    spacing_px: f64,
    keep: impl Fn(&Segment) -> bool,
) -> Vec<Sample> {
    let view = View::new(camera, options.near);
    let eye = camera.position();
    let mut samples = Vec::new();
    for piece in hidden_lines(scene, &view).into_iter().filter(|p| keep(p)) {
        let length = piece.a.distance(piece.b);
        let n = (length / spacing_px).floor();
        if !(n.is_finite() && n >= 1.0) {
            continue;
        }
        let [da, db] = piece.depth;
        let a = camera.camera_to_world(view.unproject(piece.a, da));
        let b = camera.camera_to_world(view.unproject(piece.b, db));
        let middle = a.lerp(b, 0.5);
        if edge_faces.grazes(scene, &piece, middle, eye, options.grazing_cosine)
            || edge_faces.smooth(scene, &piece, eye, options.smooth_deg)
        {
            continue;
        }
        let Some(direction) = (b - a).try_normalize() else {
            continue;
        };
        let n = n as usize;
        samples.extend((0..n).map(|i| {
            let s = (i as f64 + 0.5) / n as f64;
            let tau = s * da / ((1.0 - s) * db + s * da);
            Sample {
                point: a.lerp(b, tau),
                direction,
            }
        }));
    }
    samples
}

/// A picture's edges at several scales, found once and used by every alignment with
/// that picture ([`align_to_image`], and the alignment of single bodies in recognition).
pub struct EdgePyramid {
    /// Finest (the picture itself) first.
    levels: Vec<Level>,
}

impl EdgePyramid {
    /// The edges of `image` and of its halvings: at most `options.levels` levels, each
    /// side at least 40 pixels (the picture itself is always a level), edges found with
    /// `options.edges`. Alignments need edges: a picture without any is refused.
    ///
    /// Refused with [`SolveError::NoImageEdges`] when the picture has no edges, and with
    /// [`SolveError::BadParameter`] for options out of range.
    pub fn new(image: &Luma, options: &AlignOptions) -> Result<EdgePyramid, SolveError> {
        let pyramid = EdgePyramid::of(image, options)?;
        if pyramid.finest().edgels().is_empty() {
            return Err(SolveError::NoImageEdges);
        }
        Ok(pyramid)
    }

    /// [`EdgePyramid::new`] that takes a picture without edges too (a blank picture
    /// is evidence as well: of nothing there).
    pub fn of(image: &Luma, options: &AlignOptions) -> Result<EdgePyramid, SolveError> {
        options.validate()?;
        let mut levels = Vec::with_capacity(options.levels);
        let mut current = Some(image.clone());
        let mut scale = 1.0;
        while let Some(picture) = current.take() {
            let edges = EdgeMap::detect(&picture, &options.edges)?;
            levels.push(Level { scale, edges });
            if levels.len() < options.levels
                && picture.width() / 2 >= MIN_LEVEL_SIDE
                && picture.height() / 2 >= MIN_LEVEL_SIDE
            {
                current = picture.half();
                scale *= 0.5;
            }
        }
        Ok(EdgePyramid { levels })
    }

    /// The edges of the picture itself (the finest level).
    pub fn finest(&self) -> &EdgeMap {
        &self.levels[0].edges
    }

    /// Refuses an alignment with this pyramid of a camera of intrinsics `k`: the picture
    /// must be of the camera's size ([`SolveError::ImageSizeMismatch`]) and have edges
    /// ([`SolveError::NoImageEdges`]), and `options` must be in range.
    fn check(&self, k: &Intrinsics, options: &AlignOptions) -> Result<(), SolveError> {
        let (width, height) = self.size();
        if (width, height) != (k.width, k.height) {
            return Err(SolveError::ImageSizeMismatch {
                image_width: width,
                image_height: height,
                camera_width: k.width,
                camera_height: k.height,
            });
        }
        options.validate()?;
        if self.finest().edgels().is_empty() {
            return Err(SolveError::NoImageEdges);
        }
        Ok(())
    }

    /// The picture's size, pixels.
    pub fn size(&self) -> (u32, u32) {
        let edges = self.finest();
        (edges.width(), edges.height())
    }

    /// Aligns `drawing` from `start` on the finest `options.levels` levels, coarsest
    /// first, and judges the pose it ends at (see the module documentation). Errors as
    /// [`align_to_image`] gives them.
    fn align<D: Drawing>(
        &self,
        drawing: &D,
        start: PoseEstimate,
        options: &AlignOptions,
    ) -> Result<Found, SolveError> {
        let spacing = options.sample_spacing_px;
        let first = drawing.samples(&start, spacing)?;
        if first.len() < options.min_samples {
            return Err(SolveError::NoEdgesVisible {
                samples: first.len(),
                needed: options.min_samples,
            });
        }
        let k = drawing.intrinsics();
        let mut pose = start;
        let mut iterations = 0;
        let mut converged = false;
        // The finest `options.levels` of the pyramid's levels.
        let levels = &self.levels[..options.levels.min(self.levels.len())];
        for (i, level) in levels.iter().enumerate().rev() {
            let tracking = i == 0 && levels.len() > 1;
            let outcome = level.refine(drawing, &k, pose, options, tracking)?;
            pose = outcome.pose;
            iterations += outcome.iterations;
            converged = outcome.converged;
        }
        if !converged && options.converged_only {
            return Err(SolveError::DidNotConverge { iterations });
        }
        let samples = drawing.samples(&pose, spacing)?;
        if samples.len() < options.min_samples {
            return Err(SolveError::NoEdgesVisible {
                samples: samples.len(),
                needed: options.min_samples,
            });
        }
        let matcher = self.levels[0].matcher(&k, options, levels.len() > 1);
        let fit = matcher.fit(&matcher.associate(&samples, pose), pose, false);
        let inlier_fraction = fit.inliers as f64 / samples.len() as f64;
        if inlier_fraction < options.min_inlier_fraction {
            return Err(SolveError::TooFewInliers {
                fraction: inlier_fraction,
                needed: options.min_inlier_fraction,
            });
        }
        Ok(Found {
            pose,
            converged,
            iterations,
            rms_px: if fit.inliers == 0 {
                0.0
            } else {
                (fit.inlier_squares / fit.inliers as f64).sqrt()
            },
            samples: samples.len(),
            inlier_fraction,
        })
    }
}

/// One level of the pyramid: its edges and its scale.
struct Level {
    /// Level pixels per picture pixel, `2^−ℓ`.
    scale: f64,
    edges: EdgeMap,
}

/// The result of refining on one level.
struct LevelOutcome {
    pose: PoseEstimate,
    iterations: usize,
    converged: bool,
}

impl Level {
    /// The matcher of this level for a camera of intrinsics `k`; `tracking` on the
    /// finest of several levels, which matches only nearby edges
    /// ([`AlignOptions::match_px`]).
    fn matcher(&self, k: &Intrinsics, options: &AlignOptions, tracking: bool) -> Matcher<'_> {
        Matcher {
            edges: &self.edges,
            scale: self.scale,
            fx: k.fx * self.scale,
            fy: k.fy * self.scale,
            cx: k.cx * self.scale,
            cy: k.cy * self.scale,
            loss: options.loss,
            max_match: if tracking {
                options.match_px
            } else {
                options.capture_px
            },
            min_cos: options.max_angle_deg.to_radians().cos(),
            near: options.near,
            inlier: options.inlier_px * self.scale,
        }
    }

    /// Levenberg–Marquardt on this level from `start`, the matches found again after
    /// every kept step (see the module documentation).
    fn refine<D: Drawing>(
        &self,
        drawing: &D,
        k: &Intrinsics,
        start: PoseEstimate,
        options: &AlignOptions,
        tracking: bool,
    ) -> Result<LevelOutcome, SolveError> {
        let matcher = self.matcher(k, options, tracking);
        let spacing_px = options.sample_spacing_px / self.scale;
        let samples = drawing.samples(&start, spacing_px)?;
        let matches = matcher.associate(&samples, start);
        let current = fit_with_prior(&matcher, drawing, &matches, start, true);
        let mut alignment = LevelAlignment {
            matcher,
            drawing,
            spacing_px,
            visibility_every: options.visibility_every,
            tolerance_px: options.tolerance_px,
            pose: start,
            samples,
            matches,
            current,
            since_drawn: 0,
            tried: start,
        };
        let settings = Settings {
            max_iterations: options.max_iterations,
            cost_rounding: COST_ROUNDING,
            rounding_test: RoundingTest::KeptSteps,
        };
        let outcome = minimise(&mut alignment, &settings)?;
        Ok(LevelOutcome {
            pose: alignment.pose,
            iterations: outcome.iterations,
            converged: outcome.converged(),
        })
    }
}

/// What an alignment moves and draws: for a pose (OpenCV's world-to-camera rotation and
/// translation of the points sampled), the points on the visible edges it shows.
trait Drawing {
    /// The intrinsics of the camera the picture was taken with.
    fn intrinsics(&self) -> Intrinsics;

    /// Points every `spacing_px` pixels of the picture along the visible edges at `pose`,
    /// in the frame that `pose` maps to the camera.
    fn samples(&self, pose: &PoseEstimate, spacing_px: f64) -> Result<Vec<Sample>, SolveError>;

    /// Priors on the pose, added to the cost of the matches. None (the default) for no
    /// prior.
    fn priors(&self) -> Priors {
        Priors::default()
    }
}

/// The priors a drawing puts on the pose.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Priors {
    /// Holds a point near a plane.
    plane: Option<PlanePrior>,
    /// Holds a turn near none.
    turn: Option<TurnPrior>,
}

impl Priors {
    /// Adds the priors' cost at `pose` to `fit` (and their normal equations when asked).
    fn add_to(&self, fit: &mut Fit, pose: PoseEstimate, with_normal_equations: bool) {
        if let Some(p) = &self.plane {
            p.add_to(fit, pose, with_normal_equations);
        }
        if let Some(p) = &self.turn {
            p.add_to(fit, pose, with_normal_equations);
        }
    }
}

/// A prior that holds a point `X` near a plane of the camera's frame: its residual is
/// `(normal·(R·X + t) − offset)/deviation` (`normal` a unit vector, `deviation` meters),
/// counted as a residual of that many pixels is, without the robust loss.
#[derive(Debug, Clone, Copy, PartialEq)]
struct PlanePrior {
    point: DVec3,
    normal: DVec3,
    offset: f64,
    deviation: f64,
}

impl PlanePrior {
    /// Adds the prior's cost at `pose` to `fit` (and its normal equations when asked).
    fn add_to(&self, fit: &mut Fit, pose: PoseEstimate, with_normal_equations: bool) {
        let a = DMat3::from_quat(pose.rotation) * self.point;
        let residual = (self.normal.dot(a + pose.translation) - self.offset) / self.deviation;
        fit.cost += 0.5 * residual * residual;
        if with_normal_equations {
            fit.equations
                .add(a, self.normal / self.deviation, residual, 1.0);
        }
    }
}

/// A prior that holds the turn between a fixed rotation `R₀` (world to camera) and the
/// pose's `R` near none: with `φ` the rotation vector of `R₀ᵀ·R` (world axes), its three
/// residuals are `φᵢ/deviationᵢ` (radians), each counted as a residual of that many
/// pixels is, without the robust loss. The step `R ← exp([δω]×)·R` changes `φ` by
/// `R₀ᵀ·δω` to first order.
#[derive(Debug, Clone, Copy, PartialEq)]
struct TurnPrior {
    rotation: DQuat,
    deviation: DVec3,
}

impl TurnPrior {
    /// Adds the prior's cost at `pose` to `fit` (and its normal equations when asked).
    fn add_to(&self, fit: &mut Fit, pose: PoseEstimate, with_normal_equations: bool) {
        let mut turn = self.rotation.conjugate() * pose.rotation;
        if turn.w < 0.0 {
            turn = -turn;
        }
        let phi = turn.to_scaled_axis();
        let back = DMat3::from_quat(self.rotation);
        for i in 0..3 {
            let residual = phi[i] / self.deviation[i];
            fit.cost += 0.5 * residual * residual;
            if with_normal_equations {
                fit.equations
                    .add_turn(back.col(i) / self.deviation[i], residual, 1.0);
            }
        }
    }
}

/// The whole scene, seen by a camera at the pose: camera alignment.
struct SceneDrawing<'a> {
    scene: &'a Scene,
    edge_faces: EdgeFaces,
    k: Intrinsics,
    options: &'a AlignOptions,
}

impl Drawing for SceneDrawing<'_> {
    fn intrinsics(&self) -> Intrinsics {
        self.k
    }

    fn samples(&self, pose: &PoseEstimate, spacing_px: f64) -> Result<Vec<Sample>, SolveError> {
        let camera = camera_at(pose, self.k)?;
        Ok(sample_edges(
            self.scene,
            &self.edge_faces,
            &camera,
            self.options,
            spacing_px,
        ))
    }
}

/// The alignment on one level under way: the samples drawn at some recent pose, their
/// matches at the current pose and the cost of those matches. A step is judged by the cost
/// of the matches it was computed from; once kept, the samples are matched anew at the new
/// pose, and every [`AlignOptions::visibility_every`] iterations drawn anew.
struct LevelAlignment<'a, D> {
    matcher: Matcher<'a>,
    drawing: &'a D,
    /// Sample spacing, pixels of the picture.
    spacing_px: f64,
    visibility_every: usize,
    tolerance_px: f64,
    pose: PoseEstimate,
    samples: Vec<Sample>,
    matches: Vec<Match>,
    current: Fit,
    /// Iterations since the samples were drawn.
    since_drawn: usize,
    /// The pose of the last step tried.
    tried: PoseEstimate,
}

impl<D: Drawing> PoseProblem for LevelAlignment<'_, D> {
    type Error = SolveError;

    fn cost(&self) -> f64 {
        self.current.cost
    }

    fn normal_equations(&self) -> &NormalEquations {
        &self.current.equations
    }

    /// Draws the samples anew when [`AlignOptions::visibility_every`] iterations have run
    /// since they were drawn; stalls with fewer than [`MIN_MATCHED`] matches.
    fn prepare(&mut self) -> Result<Readiness, SolveError> {
        if self.since_drawn == self.visibility_every {
            self.samples = self.drawing.samples(&self.pose, self.spacing_px)?;
            self.matches = self.matcher.associate(&self.samples, self.pose);
            self.current =
                fit_with_prior(&self.matcher, self.drawing, &self.matches, self.pose, true);
            self.since_drawn = 0;
        }
        if self.matches.len() < MIN_MATCHED {
            return Ok(Readiness::Stalled);
        }
        self.since_drawn += 1;
        Ok(Readiness::Ready)
    }

    /// No matched sample's projection moves by more than [`AlignOptions::tolerance_px`].
    fn negligible(&self, step: &PoseStep) -> bool {
        let next = self.pose.stepped(step);
        self.matcher.largest_motion(&self.matches, self.pose, next) <= self.tolerance_px
    }

    /// The cost of the current matches at the stepped pose.
    fn try_step(&mut self, step: &PoseStep) -> f64 {
        self.tried = self.pose.stepped(step);
        fit_with_prior(
            &self.matcher,
            self.drawing,
            &self.matches,
            self.tried,
            false,
        )
        .cost
    }

    /// Moves to the pose tried and matches the samples anew there.
    fn accept(&mut self) {
        self.pose = self.tried;
        self.matches = self.matcher.associate(&self.samples, self.pose);
        self.current = fit_with_prior(&self.matcher, self.drawing, &self.matches, self.pose, true);
    }
}

/// The cost of `matches` at `pose` with the drawing's priors.
fn fit_with_prior<D: Drawing>(
    matcher: &Matcher<'_>,
    drawing: &D,
    matches: &[Match],
    pose: PoseEstimate,
    with_normal_equations: bool,
) -> Fit {
    let mut fit = matcher.fit(matches, pose, with_normal_equations);
    drawing
        .priors()
        .add_to(&mut fit, pose, with_normal_equations);
    fit
}

/// Matches samples to one level's edges, and sums the cost of matches.
struct Matcher<'a> {
    edges: &'a EdgeMap,
    /// Level pixels per picture pixel.
    scale: f64,
    /// The intrinsics at the level's scale.
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    loss: Loss,
    /// Level pixels.
    max_match: f64,
    /// Cosine of the largest angle between matched directions.
    min_cos: f64,
    near: f64,
    /// The inlier distance, level pixels.
    inlier: f64,
}

/// A sample matched to an image edge: its residual at a pose with camera coordinates
/// `p = R·point + t` is `normal·π(p) − offset` (level pixels), the distance of its
/// projection from the line through the edge pixel along the edge.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Match {
    point: DVec3,
    normal: DVec2,
    offset: f64,
}

/// The cost of a set of matches at one pose, and the normal equations when asked.
struct Fit {
    /// `½·Σ ρ(r²)`; a match behind the near plane counts `½·ρ(max_match²)`.
    cost: f64,
    inliers: usize,
    /// `Σ r²` over the inliers, picture pixels squared.
    inlier_squares: f64,
    /// The normal equations of the cost (zero unless asked for).
    equations: NormalEquations,
}

impl Matcher<'_> {
    /// The level pixel of camera coordinates `p` (`p.z > 0`).
    #[inline]
    fn pixel(&self, p: DVec3) -> DVec2 {
        DVec2::new(self.cx + self.fx * p.x / p.z, self.cy + self.fy * p.y / p.z)
    }

    /// The samples at `pose` that have an image edge near enough and running the same
    /// way, each with that edge.
    fn associate(&self, samples: &[Sample], pose: PoseEstimate) -> Vec<Match> {
        let rotation = DMat3::from_quat(pose.rotation);
        let mut matches = Vec::with_capacity(samples.len());
        for sample in samples {
            let p = rotation * sample.point + pose.translation;
            if p.z <= self.near {
                continue;
            }
            let pixel = self.pixel(p);
            let Some(edgel) = self.edges.nearest(pixel.x, pixel.y) else {
                continue;
            };
            let edge = edgel.position.as_dvec2();
            if pixel.distance_squared(edge) > self.max_match * self.max_match {
                continue;
            }
            // The model edge's direction in the image: the derivative of the projection
            // along the edge's 3D direction.
            let d = rotation * sample.direction;
            let (x, y) = (p.x / p.z, p.y / p.z);
            let along = DVec2::new(
                self.fx * (d.x - x * d.z) / p.z,
                self.fy * (d.y - y * d.z) / p.z,
            );
            let normal = edgel.normal.as_dvec2();
            let length = along.length();
            // The image edge runs along perp(n), so |perp(n)·along|/|along| =
            // |n × along|/|along| is the |cosine| of the angle between the two directions.
            if !(length.is_finite() && length > 0.0)
                || normal.perp_dot(along).abs() < self.min_cos * length
            {
                continue;
            }
            matches.push(Match {
                point: sample.point,
                normal,
                offset: normal.dot(edge),
            });
        }
        matches
    }

    /// The largest distance (level pixels) that a match's projection moves between `from`
    /// and `to`; infinite when one goes behind the near plane.
    fn largest_motion(&self, matches: &[Match], from: PoseEstimate, to: PoseEstimate) -> f64 {
        let (r0, r1) = (
            DMat3::from_quat(from.rotation),
            DMat3::from_quat(to.rotation),
        );
        matches.iter().fold(0.0, |largest, m| {
            let (p0, p1) = (
                r0 * m.point + from.translation,
                r1 * m.point + to.translation,
            );
            if p0.z <= self.near || p1.z <= self.near {
                return f64::INFINITY;
            }
            largest.max(self.pixel(p0).distance(self.pixel(p1)))
        })
    }

    /// The cost of `matches` at `pose`.
    fn fit(&self, matches: &[Match], pose: PoseEstimate, with_normal_equations: bool) -> Fit {
        let rotation = DMat3::from_quat(pose.rotation);
        let behind = 0.5 * self.loss.eval(self.max_match * self.max_match).0;
        let mut fit = Fit {
            cost: 0.0,
            inliers: 0,
            inlier_squares: 0.0,
            equations: NormalEquations::zeros(),
        };
        for m in matches {
            let a = rotation * m.point;
            let p = a + pose.translation;
            if p.z <= self.near {
                fit.cost += behind;
                continue;
            }
            let residual = m.normal.dot(self.pixel(p)) - m.offset;
            let s = residual * residual;
            let (rho, weight) = self.loss.eval(s);
            fit.cost += 0.5 * rho;
            if residual.abs() <= self.inlier {
                fit.inliers += 1;
                fit.inlier_squares += s / (self.scale * self.scale);
            }
            if with_normal_equations {
                // ∂r/∂p, with a = R·X.
                let inv_z = 1.0 / p.z;
                let (nx, ny) = (m.normal.x * self.fx, m.normal.y * self.fy);
                let row = DVec3::new(
                    nx * inv_z,
                    ny * inv_z,
                    -(nx * p.x + ny * p.y) * inv_z * inv_z,
                );
                fit.equations.add(a, row, residual, weight);
            }
        }
        fit
    }
}

mod body;
#[cfg(test)]
mod tests;

pub use body::{AlignedBody, HEIGHT_DEVIATION_M, Motion, align_body};
