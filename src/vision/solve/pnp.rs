//! The camera from 2D–3D correspondences in pixels, start to finish: pixels to
//! normalised coordinates with known intrinsics; the global SQPnP solve of all the
//! correspondences ([`sqpnp()`]), which is the consensus when it fits every one of them
//! within the threshold (no outlier: RANSAC is skipped); otherwise LO-RANSAC around P3P
//! for the consensus ([`ransac_pnp`]) and the global solve on it (kept when it reprojects
//! the consensus better than RANSAC's camera); then Levenberg–Marquardt with a robust loss
//! on the consensus ([`refine_pose`]), the inliers counted again with the refined pose,
//! and the answer in pixels and in OpenCV's `rvec`/`tvec`.

use glam::{DMat3, DQuat, DVec2, DVec3};

use super::ransac::{RansacOptions, ransac_pnp};
use super::refine::{Loss, RefineOptions, refine_pose};
use super::sqpnp::sqpnp;
use super::{CvPose, SolveError};

/// Pinhole intrinsics in OpenCV's convention: `u = fx·x/z + cx`, `v = fy·y/z + cy`, with
/// integer pixel coordinates at pixel centres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelIntrinsics {
    /// Focal length along u, pixels.
    pub fx: f64,
    /// Focal length along v, pixels.
    pub fy: f64,
    /// Principal point u.
    pub cx: f64,
    /// Principal point v.
    pub cy: f64,
}

impl PixelIntrinsics {
    /// The normalised image coordinates `(x/z, y/z)` of pixel `p`.
    pub fn normalise(&self, p: DVec2) -> DVec2 {
        DVec2::new((p.x - self.cx) / self.fx, (p.y - self.cy) / self.fy)
    }

    /// The pixel of normalised image coordinates `m`: the inverse of
    /// [`PixelIntrinsics::normalise`].
    pub fn pixel(&self, m: DVec2) -> DVec2 {
        DVec2::new(self.fx * m.x + self.cx, self.fy * m.y + self.cy)
    }

    fn validate(&self) -> Result<(), SolveError> {
        let bad = |what, value| Err(SolveError::BadParameter { what, value });
        for (what, f) in [("fx", self.fx), ("fy", self.fy)] {
            if !(f.is_finite() && f > 0.0) {
                return bad(what, f);
            }
        }
        if !(self.cx.is_finite() && self.cy.is_finite()) {
            return Err(SolveError::NonFinite {
                what: "principal point",
            });
        }
        Ok(())
    }

    /// The mean focal length, to turn pixel distances into normalised ones.
    fn focal(&self) -> f64 {
        0.5 * (self.fx + self.fy)
    }
}

/// How [`solve_pnp`] runs; [`PnpOptions::default`] suits a calibrated camera with a
/// pixel or so of noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PnpOptions {
    /// Reprojection error, in pixels, up to which a correspondence is an inlier
    /// (default 8, as OpenCV's `solvePnPRansac`: four deviations of 2 px noise, so that
    /// a genuine match is kept with probability 0.9997; wrong matches are seldom within
    /// that distance of where their point is seen).
    pub threshold_px: f64,
    /// Confidence that RANSAC has drawn an all-inlier sample when it stops (default
    /// 0.999).
    pub confidence: f64,
    /// The most RANSAC iterations (default 10,000).
    pub max_iterations: usize,
    /// The fewest inliers a camera may rest on (default 6, at least 4).
    pub min_inliers: usize,
    /// Seed of RANSAC's sampling: the same seed gives the same answer.
    pub seed: u64,
}

impl Default for PnpOptions {
    fn default() -> Self {
        PnpOptions {
            threshold_px: 8.0,
            confidence: 0.999,
            max_iterations: 10_000,
            min_inliers: 6,
            seed: 0,
        }
    }
}

/// A solved camera.
#[derive(Debug, Clone, PartialEq)]
pub struct PnpSolution {
    /// World to camera: `x_cam = R·x_world + t` (OpenCV's frame).
    pub pose: CvPose,
    /// OpenCV's `rvec`: the rotation's axis times its angle (radians).
    pub rvec: DVec3,
    /// OpenCV's `tvec`: the translation.
    pub tvec: DVec3,
    /// Root mean square reprojection error over the inliers, pixels.
    pub rms_px: f64,
    /// Indices of the inliers, ascending.
    pub inliers: Vec<usize>,
    /// RANSAC iterations: 0 when the global solve of all the correspondences fitted every
    /// one of them, so that there was no outlier to look for.
    pub ransac_iterations: usize,
    /// Levenberg–Marquardt iterations.
    pub refine_iterations: usize,
    /// Whether the consensus is trusted: RANSAC stopped at its confidence (rather than at
    /// `max_iterations`), or every correspondence agreed with the global solve.
    pub confident: bool,
}

/// The camera that sees `world[i]` at pixel `pixels[i]`, with intrinsics `k`.
///
/// Preconditions, each refused with a typed error: equal lengths, at least
/// `options.min_inliers` (and at least 4) correspondences, finite numbers, positive focal
/// lengths and an inlier threshold above zero.
///
/// Postconditions: the camera rests on at least `options.min_inliers` inliers, each in
/// front of it and within `threshold_px` of where it is seen; the refinement on them
/// converged. Otherwise an error ([`SolveError::NoConsensus`],
/// [`SolveError::Degenerate`], [`SolveError::DidNotConverge`]), never a camera.
pub fn solve_pnp(
    world: &[DVec3],
    pixels: &[DVec2],
    k: &PixelIntrinsics,
    options: &PnpOptions,
) -> Result<PnpSolution, SolveError> {
    k.validate()?;
    if !(options.threshold_px.is_finite() && options.threshold_px > 0.0) {
        return Err(SolveError::BadParameter {
            what: "the inlier threshold",
            value: options.threshold_px,
        });
    }
    if pixels.iter().any(|p| !p.is_finite()) {
        return Err(SolveError::NonFinite { what: "pixels" });
    }
    let observed: Vec<DVec2> = pixels.iter().map(|&p| k.normalise(p)).collect();
    let threshold = options.threshold_px / k.focal();
    let needed = options.min_inliers.max(super::MIN_CONSENSUS);
    let mut ransac = RansacOptions::new(threshold);
    ransac.confidence = options.confidence;
    ransac.max_iterations = options.max_iterations;
    ransac.min_iterations = ransac.min_iterations.min(options.max_iterations);
    ransac.min_inliers = options.min_inliers;
    ransac.seed = options.seed;
    ransac.validate()?;
    // The camera to refine, the consensus it rests on, and how it was found.
    let (start, w, m, ransac_iterations, confident) =
        match everyone_agrees(world, &observed, pixels, k, options) {
            Some(start) => (start, world.to_vec(), observed, 0, true),
            None => {
                let consensus = ransac_pnp(world, &observed, &ransac)?;
                let (w, m): (Vec<DVec3>, Vec<DVec2>) = consensus
                    .inliers
                    .iter()
                    .map(|&i| (world[i], observed[i]))
                    .unzip();
                // The global optimum of the consensus, when it fits it better than the
                // sample's camera (a degenerate consensus leaves RANSAC's camera as it is).
                let squared_error = |pose: &CvPose| -> f64 {
                    w.iter()
                        .zip(&m)
                        .map(|(&x, &o)| {
                            pose.project(x)
                                .map_or(f64::INFINITY, |q| (q - o).length_squared())
                        })
                        .sum()
                };
                let start = match sqpnp(&w, &m, None) {
                    Ok(global)
                        if squared_error(&global.best.pose) < squared_error(&consensus.pose) =>
                    {
                        global.best.pose
                    }
                    _ => consensus.pose,
                };
                (start, w, m, consensus.iterations, consensus.confident)
            }
        };
    let refine = RefineOptions::new(Loss::Huber { scale: threshold });
    let refined = refine_pose(&start, &w, &m, &refine)?.require_converged()?;
    let pose = refined.pose;

    // The inliers of the refined camera, and their error in pixels.
    let mut inliers = Vec::new();
    let mut sum2 = 0.0;
    for (i, (&x, &p)) in world.iter().zip(pixels).enumerate() {
        let Some(q) = pose.project(x) else { continue };
        let e2 = (k.pixel(q) - p).length_squared();
        if e2 <= options.threshold_px * options.threshold_px {
            inliers.push(i);
            sum2 += e2;
        }
    }
    if inliers.len() < needed {
        return Err(SolveError::NoConsensus {
            best_inliers: inliers.len(),
            needed,
        });
    }
    let rms_px = (sum2 / inliers.len() as f64).sqrt();
    Ok(PnpSolution {
        rvec: rotation_vector(&pose.rotation),
        tvec: pose.translation,
        pose,
        rms_px,
        inliers,
        ransac_iterations,
        refine_iterations: refined.iterations,
        confident,
    })
}

/// The global optimum of all the correspondences, when there are at least
/// `options.min_inliers` of them and it puts every world point in front of the camera and
/// within `options.threshold_px` of its pixel: then no correspondence is an outlier and
/// the consensus is all of them. `None` otherwise (an outlier, noise beyond the threshold,
/// or a configuration SQPnP refuses), and RANSAC looks for the consensus.
fn everyone_agrees(
    world: &[DVec3],
    observed: &[DVec2],
    pixels: &[DVec2],
    k: &PixelIntrinsics,
    options: &PnpOptions,
) -> Option<CvPose> {
    if world.len() < options.min_inliers.max(super::MIN_CONSENSUS) {
        return None;
    }
    let pose = sqpnp(world, observed, None).ok()?.best.pose;
    let limit = options.threshold_px * options.threshold_px;
    world
        .iter()
        .zip(pixels)
        .all(|(&x, &p)| {
            pose.project(x)
                .is_some_and(|q| (k.pixel(q) - p).length_squared() <= limit)
        })
        .then_some(pose)
}

/// OpenCV's `rvec` of a rotation: its axis times its angle in `[0, π]`.
pub fn rotation_vector(r: &DMat3) -> DVec3 {
    let (axis, angle) = DQuat::from_mat3(r).normalize().to_axis_angle();
    // `to_axis_angle` may answer an angle above π about the opposite axis.
    if angle > std::f64::consts::PI {
        -axis * (2.0 * std::f64::consts::PI - angle)
    } else {
        axis * angle
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::vision::testing::Rng;

    const K: PixelIntrinsics = PixelIntrinsics {
        fx: 800.0,
        fy: 800.0,
        cx: 320.0,
        cy: 240.0,
    };

    /// A random camera and `n` points in [-2,2]×[-2,2]×[4,8] in front of it, seen with
    /// `noise` px of Gaussian noise; the first `outliers` pixels replaced by uniform ones.
    fn problem(
        rng: &mut Rng,
        n: usize,
        noise: f64,
        outliers: usize,
    ) -> (CvPose, Vec<DVec3>, Vec<DVec2>) {
        let axis = DVec3::new(rng.normal(), rng.normal(), rng.normal()).normalize();
        let rotation = DMat3::from_quat(DQuat::from_axis_angle(axis, rng.range(0.0, 3.0)));
        let translation = rng.vector(-1.0, 1.0);
        let pose = CvPose::new(rotation, translation);
        let mut world = Vec::new();
        let mut pixels = Vec::new();
        for i in 0..n {
            let cam = DVec3::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(4.0, 8.0),
            );
            world.push(rotation.transpose() * (cam - translation));
            let seen = K.pixel(DVec2::new(cam.x / cam.z, cam.y / cam.z));
            pixels.push(if i < outliers {
                DVec2::new(rng.range(0.0, 640.0), rng.range(0.0, 480.0))
            } else {
                seen + DVec2::new(rng.normal(), rng.normal()) * noise
            });
        }
        (pose, world, pixels)
    }

    #[test]
    fn without_outliers_the_global_solve_is_the_consensus_and_ransac_is_skipped() {
        let mut rng = Rng(31);
        for n in [6, 10, 200] {
            for _ in 0..20 {
                let (truth, world, pixels) = problem(&mut rng, n, 0.5, 0);
                let s = solve_pnp(&world, &pixels, &K, &PnpOptions::default()).expect("a camera");
                assert_eq!(s.ransac_iterations, 0, "n = {n}");
                assert!(s.confident);
                assert_eq!(s.inliers, (0..n).collect::<Vec<_>>());
                assert!(s.pose.rotation_angle_to(&truth).to_degrees() < 1.0);
            }
        }
        // One wrong match among them: RANSAC looks for the consensus, and leaves it out.
        let (truth, world, mut pixels) = problem(&mut rng, 50, 0.5, 0);
        pixels[7] += DVec2::new(40.0, -25.0);
        let s = solve_pnp(&world, &pixels, &K, &PnpOptions::default()).expect("a camera");
        assert!(s.ransac_iterations >= 1);
        assert!(!s.inliers.contains(&7) && s.inliers.len() == 49);
        assert!(s.pose.rotation_angle_to(&truth).to_degrees() < 0.2);
        // Options out of range are refused even where RANSAC would not run.
        let (_, world, pixels) = problem(&mut rng, 20, 0.5, 0);
        let bad = PnpOptions {
            confidence: 1.5,
            ..PnpOptions::default()
        };
        assert!(matches!(
            solve_pnp(&world, &pixels, &K, &bad),
            Err(SolveError::BadParameter { .. })
        ));
    }

    #[test]
    fn the_camera_is_found_through_noise_and_outliers() {
        let mut rng = Rng(7);
        for (outliers, trials) in [(0usize, 10), (60, 10), (140, 10)] {
            for _ in 0..trials {
                let (truth, world, pixels) = problem(&mut rng, 200, 1.0, outliers);
                let s = solve_pnp(&world, &pixels, &K, &PnpOptions::default()).expect("a camera");
                let angle = s.pose.rotation_angle_to(&truth).to_degrees();
                let shift = (s.pose.center() - truth.center()).length();
                assert!(
                    angle < 0.2 && shift < 0.05,
                    "{angle}° {shift} m at {outliers}"
                );
                assert!(s.rms_px > 0.5 && s.rms_px < 2.0, "rms {}", s.rms_px);
                let true_inliers = s.inliers.iter().filter(|&&i| i >= outliers).count();
                assert!(
                    true_inliers >= 190 - outliers,
                    "{true_inliers} of {}",
                    200 - outliers
                );
                assert!(s.inliers.len() - true_inliers <= 2);
                assert!(s.confident);
                // OpenCV's rvec names the same rotation.
                let back = DMat3::from_axis_angle(s.rvec.normalize(), s.rvec.length());
                assert!(CvPose::new(back, s.tvec).rotation_angle_to(&s.pose) < 1e-9);
            }
        }
    }

    #[test]
    fn rotation_vectors_stay_within_half_a_turn() {
        let r = DMat3::from_axis_angle(DVec3::Z, 3.0);
        let v = rotation_vector(&r);
        assert!((v.length() - 3.0).abs() < 1e-12 && (v.normalize() - DVec3::Z).length() < 1e-12);
        let v = rotation_vector(&DMat3::from_axis_angle(DVec3::X, -0.5));
        assert!((v - DVec3::X * -0.5).length() < 1e-12);
        assert_eq!(rotation_vector(&DMat3::IDENTITY), DVec3::ZERO);
    }

    #[test]
    fn no_camera_is_made_up_from_noise_or_bad_input() {
        let mut rng = Rng(11);
        let (_, world, _) = problem(&mut rng, 50, 0.0, 0);
        let noise: Vec<DVec2> = (0..50)
            .map(|_| DVec2::new(rng.range(0.0, 640.0), rng.range(0.0, 480.0)))
            .collect();
        let opts = PnpOptions {
            min_inliers: 20,
            ..PnpOptions::default()
        };
        assert!(matches!(
            solve_pnp(&world, &noise, &K, &opts),
            Err(SolveError::NoConsensus { .. })
        ));
        let mut nan = noise.clone();
        nan[3].x = f64::NAN;
        assert!(matches!(
            solve_pnp(&world, &nan, &K, &opts),
            Err(SolveError::NonFinite { .. })
        ));
        assert!(matches!(
            solve_pnp(&world[..3], &noise[..3], &K, &PnpOptions::default()),
            Err(SolveError::TooFewPoints { .. })
        ));
        assert!(matches!(
            solve_pnp(&world, &noise[..10], &K, &opts),
            Err(SolveError::LengthMismatch { .. })
        ));
        let flat = PixelIntrinsics { fx: 0.0, ..K };
        assert!(matches!(
            solve_pnp(&world, &noise, &flat, &opts),
            Err(SolveError::BadParameter { .. })
        ));
    }
}
