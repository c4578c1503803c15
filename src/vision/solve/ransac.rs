//! LO-RANSAC around P3P: a camera pose from N correspondences of which many may be wrong.
//!
//! # The loop
//!
//! Each iteration draws three distinct correspondences at random, solves them with
//! [`p3p()`] (up to four poses; a sample whose world points coincide or lie on a line is
//! refused by `p3p` and skipped) and scores every pose on all N correspondences. A point is
//! an **inlier** of a pose when it is in front of the camera and its reprojection error
//! `|π(R·Xᵢ + t) − mᵢ|` (normalised image units) is at most the threshold τ; poses are
//! ranked by inlier count, ties broken by the MSAC cost `Σ min(eᵢ², τ²)` (points behind
//! the camera cost τ²).
//!
//! # Local optimisation
//!
//! Whenever a pose beats the best so far it is locally optimised (Chum, Matas & Kittler,
//! "Locally Optimized RANSAC", DAGM 2003, in the iterated least-squares form of Lebeda,
//! Matas & Chum, "Fixing the Locally Optimized RANSAC", BMVC 2012): the inliers at a
//! looser threshold are collected, the pose is refined on them with [`refine_pose`]
//! (Huber loss at scale τ), and this repeats a few times with the threshold shrinking to τ.
//! Every refined pose is scored like a sampled one and the best is kept. A minimal sample
//! of three noisy inliers gives a pose that is slightly off and so misses some true
//! inliers; the refinement recovers them, which both sharpens the pose and raises the
//! inlier ratio that decides when to stop.
//!
//! # Stopping
//!
//! With w the best inlier ratio found so far, a sample of three inliers is drawn with
//! probability w³, so after `k = log(1 − confidence) / log(1 − w³)` iterations at least one
//! all-inlier sample has been drawn with the requested confidence. The loop stops after
//! `max(k, min_iterations)` iterations, and never after more than `max_iterations`
//! ([`Consensus::confident`] tells which happened).
//!
//! # Units
//!
//! Observations and the threshold are in normalised image coordinates (for a pixel
//! `(u, v)` with intrinsics `fx, fy, cx, cy`: `((u − cx)/fx, (v − cy)/fy)`). A threshold of
//! `p` pixels is `p / f`; about three times the pixel noise keeps 99% of true inliers
//! (`3.0 / 800.0` for 1 px noise at f = 800).

use glam::{DVec2, DVec3};

use super::p3p::p3p;
use super::refine::{Loss, RefineOptions, refine_pose};
use super::sampler::Sampler;
use super::{CvPose, Degeneracy, SolveError, check_pairs};

/// The fewest correspondences [`ransac_pnp`] accepts, and the smallest consensus it will
/// report: three determine (up to four) poses, the fourth is the first that checks them.
pub const MIN_CONSENSUS: usize = 4;

/// Correspondences in one minimal sample.
const SAMPLE_SIZE: usize = 3;

/// How the local optimisation of a new best pose runs (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalOptimisation {
    /// Refinements per new best pose; 0 turns local optimisation off.
    pub steps: usize,
    /// The inlier threshold of the first refinement, as a multiple of the RANSAC threshold
    /// (finite, at least 1); later refinements shrink it linearly to 1.
    pub loose_factor: f64,
    /// The most Levenberg–Marquardt iterations of each refinement; at least 1.
    pub refine_iterations: usize,
}

impl Default for LocalOptimisation {
    /// Four refinements, the first at three times the threshold, 10 Levenberg–Marquardt
    /// iterations each.
    fn default() -> LocalOptimisation {
        LocalOptimisation {
            steps: 4,
            loose_factor: 3.0,
            refine_iterations: 10,
        }
    }
}

/// How [`ransac_pnp`] runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RansacOptions {
    /// The inlier threshold τ on the reprojection error, in **normalised image units**
    /// (pixels divided by the focal length); finite and positive.
    pub threshold: f64,
    /// The probability wanted of having drawn at least one all-inlier sample before
    /// stopping; strictly between 0 and 1.
    pub confidence: f64,
    /// The most iterations (samples drawn, degenerate ones included); at least 1.
    pub max_iterations: usize,
    /// The fewest iterations, even when the stopping criterion is met earlier; at most
    /// `max_iterations`.
    pub min_iterations: usize,
    /// The smallest consensus accepted as an answer, in points; at least
    /// [`MIN_CONSENSUS`].
    pub min_inliers: usize,
    /// The smallest consensus accepted as an answer, as a fraction of all points, in
    /// [0, 1]. The consensus needed is the larger of this and `min_inliers`.
    pub min_inlier_ratio: f64,
    /// The seed of the sampler: the same seed and input give the same answer.
    pub seed: u64,
    /// Local optimisation of each new best pose.
    pub local: LocalOptimisation,
}

impl RansacOptions {
    /// `threshold` (normalised units: pixels / f) with confidence 0.999, 10 to 10,000
    /// iterations, a consensus of at least [`MIN_CONSENSUS`] points and 5% of them, seed 0
    /// and the default [`LocalOptimisation`].
    pub fn new(threshold: f64) -> RansacOptions {
        RansacOptions {
            threshold,
            confidence: 0.999,
            max_iterations: 10_000,
            min_iterations: 10,
            min_inliers: MIN_CONSENSUS,
            min_inlier_ratio: 0.05,
            seed: 0,
            local: LocalOptimisation::default(),
        }
    }

    /// Refuses options out of their ranges with [`SolveError::BadParameter`].
    pub(super) fn validate(&self) -> Result<(), SolveError> {
        let bad = |what, value| Err(SolveError::BadParameter { what, value });
        if !(self.threshold.is_finite() && self.threshold > 0.0) {
            return bad("the inlier threshold", self.threshold);
        }
        if !(self.confidence > 0.0 && self.confidence < 1.0) {
            return bad("the confidence", self.confidence);
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", 0.0);
        }
        if self.min_iterations > self.max_iterations {
            return bad("min_iterations", self.min_iterations as f64);
        }
        if self.min_inliers < MIN_CONSENSUS {
            return bad("min_inliers", self.min_inliers as f64);
        }
        if !(0.0..=1.0).contains(&self.min_inlier_ratio) {
            return bad("min_inlier_ratio", self.min_inlier_ratio);
        }
        let local = &self.local;
        if !(local.loose_factor.is_finite() && local.loose_factor >= 1.0) {
            return bad("the local optimisation's loose_factor", local.loose_factor);
        }
        if local.steps > 0 && local.refine_iterations == 0 {
            return bad("the local optimisation's refine_iterations", 0.0);
        }
        Ok(())
    }
}

/// The outcome of [`ransac_pnp`].
#[derive(Debug, Clone, PartialEq)]
pub struct Consensus {
    /// The pose with the largest consensus: a proper rotation and finite numbers.
    pub pose: CvPose,
    /// Indices of the correspondences that are inliers of `pose` (in front of the camera,
    /// reprojection error at most the threshold), ascending.
    pub inliers: Vec<usize>,
    /// Root mean square reprojection error over the inliers (normalised image units).
    pub rms: f64,
    /// Iterations taken (samples drawn, degenerate ones included).
    pub iterations: usize,
    /// Whether the loop stopped because the stopping criterion was met (enough iterations
    /// for the requested confidence at the inlier ratio found); `false` when it ran out of
    /// `max_iterations` first.
    pub confident: bool,
}

/// The camera pose that agrees with the most correspondences `world[i] ↔ observed[i]`,
/// found by LO-RANSAC around [`p3p()`] (see the [module docs](self)).
///
/// `observed[i]` is the normalised image position (OpenCV's frame: x right, y down) at
/// which the world point `world[i]` is seen; the returned pose maps world to camera
/// coordinates, `x_cam = R·x_world + t`.
///
/// Preconditions, each refused with an error rather than assumed:
/// * `world.len() == observed.len()` ([`SolveError::LengthMismatch`]) and at least
///   [`MIN_CONSENSUS`] of them, and at least `options.min_inliers`
///   ([`SolveError::TooFewPoints`]);
/// * every number finite ([`SolveError::NonFinite`]);
/// * `options` in range ([`SolveError::BadParameter`]).
///
/// Postconditions: the pose has at least `max(min_inliers, ⌈min_inlier_ratio·N⌉)` inliers;
/// otherwise the answer is an error, never a camera:
/// * [`SolveError::NoConsensus`] when no pose reached that many;
/// * [`SolveError::Degenerate`] when every sample drawn was degenerate (all world points on
///   a line, say).
///
/// With few points and many outliers a wrong pose can gather a small consensus by chance
/// (three outliers always fit some pose exactly): raise `min_inliers` or
/// `min_inlier_ratio` when a small consensus should not be trusted.
pub fn ransac_pnp(
    world: &[DVec3],
    observed: &[DVec2],
    options: &RansacOptions,
) -> Result<Consensus, SolveError> {
    check_pairs(world, observed)?;
    let n = world.len();
    if n < MIN_CONSENSUS {
        return Err(SolveError::TooFewPoints {
            needed: MIN_CONSENSUS,
            got: n,
        });
    }
    options.validate()?;
    if n < options.min_inliers {
        return Err(SolveError::TooFewPoints {
            needed: options.min_inliers,
            got: n,
        });
    }
    let needed = options
        .min_inliers
        .max((options.min_inlier_ratio * n as f64).ceil() as usize);

    let scorer = Scorer {
        world,
        observed,
        tau2: options.threshold * options.threshold,
    };
    let mut rng = Sampler::new(options.seed);
    let mut best: Option<(CvPose, Score)> = None;
    let mut degenerate: Option<Degeneracy> = None;
    let mut iterations = 0;
    let mut required = usize::MAX;
    let mut confident = false;

    while iterations < options.max_iterations {
        if iterations >= required.max(options.min_iterations) {
            confident = true;
            break;
        }
        iterations += 1;
        let [a, b, c] = rng.sample3(n);
        let bearings = [a, b, c].map(|i| observed[i].extend(1.0));
        let points = [world[a], world[b], world[c]];
        let poses = match p3p(&bearings, &points) {
            Ok(poses) => poses,
            Err(SolveError::Degenerate(why)) => {
                degenerate = Some(why);
                continue;
            }
            // The inputs were checked above; any other refusal just skips the sample.
            Err(_) => continue,
        };
        for pose in poses {
            // A pose that cannot at least tie the best count is abandoned mid-score.
            let floor = best.as_ref().map_or(0, |(_, s)| s.inliers);
            let Some(score) = scorer.score(&pose, floor) else {
                continue;
            };
            if best.as_ref().is_some_and(|(_, s)| !score.beats(s)) {
                continue;
            }
            let improved = if score.inliers > SAMPLE_SIZE && options.local.steps > 0 {
                scorer.local_optimisation(pose, score, options)
            } else {
                (pose, score)
            };
            let w = improved.1.inliers as f64 / n as f64;
            required = iterations_needed(w, options.confidence);
            best = Some(improved);
        }
    }
    if !confident && iterations >= required.max(options.min_iterations) {
        // The criterion was met by the last iteration itself.
        confident = true;
    }

    let Some((pose, score)) = best else {
        return Err(match degenerate {
            Some(why) => SolveError::Degenerate(why),
            None => SolveError::NoConsensus {
                best_inliers: 0,
                needed,
            },
        });
    };
    if score.inliers < needed {
        return Err(SolveError::NoConsensus {
            best_inliers: score.inliers,
            needed,
        });
    }
    let inliers = scorer.inliers(&pose, 1.0);
    let squared: f64 = inliers
        .iter()
        .filter_map(|&i| scorer.error2(&pose, i))
        .sum();
    let rms = (squared / inliers.len() as f64).sqrt();
    Ok(Consensus {
        pose,
        inliers,
        rms,
        iterations,
        confident,
    })
}

/// `log(1 − confidence) / log(1 − w³)` rounded up: the iterations after which an
/// all-inlier sample has been drawn with the given confidence at inlier ratio `w`;
/// `usize::MAX` when no number of iterations will do (w = 0).
fn iterations_needed(w: f64, confidence: f64) -> usize {
    let all_inliers = w.powi(SAMPLE_SIZE as i32);
    if all_inliers >= 1.0 {
        return 0;
    }
    let k = (-confidence).ln_1p() / (-all_inliers).ln_1p();
    if k.is_finite() && k < usize::MAX as f64 {
        k.ceil().max(0.0) as usize
    } else {
        usize::MAX
    }
}

/// How well a pose agrees with the correspondences.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Score {
    /// Points in front of the camera with a reprojection error at most τ.
    inliers: usize,
    /// MSAC cost `Σ min(eᵢ², τ²)`, τ² for points behind the camera.
    cost: f64,
}

impl Score {
    /// More inliers, or as many at a lower MSAC cost.
    fn beats(&self, other: &Score) -> bool {
        self.inliers > other.inliers || (self.inliers == other.inliers && self.cost < other.cost)
    }
}

/// The correspondences and squared threshold of one run.
struct Scorer<'a> {
    world: &'a [DVec3],
    observed: &'a [DVec2],
    tau2: f64,
}

impl Scorer<'_> {
    /// Squared reprojection error of point `i`, or `None` when it is not in front of the
    /// camera (or the error is not finite).
    fn error2(&self, pose: &CvPose, i: usize) -> Option<f64> {
        let p = pose.transform(self.world[i]);
        if p.z <= 0.0 {
            return None;
        }
        let e = (DVec2::new(p.x / p.z, p.y / p.z) - self.observed[i]).length_squared();
        e.is_finite().then_some(e)
    }

    /// The score of `pose`, or `None` once it is certain to have fewer than `floor`
    /// inliers.
    fn score(&self, pose: &CvPose, floor: usize) -> Option<Score> {
        let n = self.world.len();
        let allowed_outliers = n.saturating_sub(floor);
        let mut inliers = 0;
        let mut outliers = 0;
        let mut cost = 0.0;
        for i in 0..n {
            match self.error2(pose, i) {
                Some(e) if e <= self.tau2 => {
                    inliers += 1;
                    cost += e;
                }
                _ => {
                    outliers += 1;
                    cost += self.tau2;
                    if outliers > allowed_outliers {
                        return None;
                    }
                }
            }
        }
        Some(Score { inliers, cost })
    }

    /// Indices of the points within `factor·τ` of their observations, ascending.
    fn inliers(&self, pose: &CvPose, factor: f64) -> Vec<usize> {
        let limit = self.tau2 * factor * factor;
        (0..self.world.len())
            .filter(|&i| self.error2(pose, i).is_some_and(|e| e <= limit))
            .collect()
    }

    /// Iterated refinement of `pose` on its inliers at a threshold shrinking from
    /// `loose_factor·τ` to τ; the best-scoring pose met, `start` included.
    fn local_optimisation(
        &self,
        start: CvPose,
        start_score: Score,
        options: &RansacOptions,
    ) -> (CvPose, Score) {
        let local = &options.local;
        let refine_options = RefineOptions {
            loss: Loss::Huber {
                scale: options.threshold,
            },
            max_iterations: local.refine_iterations,
            tolerance: 1e-9,
        };
        let mut best = (start, start_score);
        let mut pose = start;
        let mut world = Vec::new();
        let mut observed = Vec::new();
        for step in 0..local.steps {
            let factor = if local.steps > 1 {
                let shrink = step as f64 / (local.steps - 1) as f64;
                local.loose_factor + (1.0 - local.loose_factor) * shrink
            } else {
                1.0
            };
            let inliers = self.inliers(&pose, factor);
            if inliers.len() < MIN_CONSENSUS {
                break;
            }
            world.clear();
            observed.clear();
            world.extend(inliers.iter().map(|&i| self.world[i]));
            observed.extend(inliers.iter().map(|&i| self.observed[i]));
            let Ok(refined) = refine_pose(&pose, &world, &observed, &refine_options) else {
                break;
            };
            pose = refined.pose;
            if let Some(score) = self.score(&pose, 0)
                && score.beats(&best.1)
            {
                best = (pose, score);
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DMat3;

    use crate::vision::testing::Rng as SceneRng;

    const F: f64 = 800.0;

    /// One EPnP-protocol problem with its ground truth.
    struct Scene {
        truth: CvPose,
        world: Vec<DVec3>,
        observed: Vec<DVec2>,
        /// Which observations were replaced by outliers.
        outlier: Vec<bool>,
    }

    /// The EPnP paper's set-up: a random pose, `n` points in [-2,2]²×[4,8] in front of the
    /// camera, observed with `noise_px` Gaussian pixel noise at f = 800; a fraction
    /// `outliers` of the observations (chosen at random) replaced by uniform points of a
    /// 640×480 image.
    fn scene(rng: &mut SceneRng, n: usize, noise_px: f64, outliers: f64) -> Scene {
        let rotation = DMat3::from_axis_angle(rng.unit_vector(), rng.range(-3.0, 3.0));
        let truth = CvPose::new(rotation, rng.vector(-1.0, 1.0));
        let wrong = (n as f64 * outliers).round() as usize;
        // A random choice of `wrong` indices (partial Fisher–Yates).
        let mut order: Vec<usize> = (0..n).collect();
        for i in 0..wrong {
            let j = i + (rng.next_u64() % (n - i) as u64) as usize;
            order.swap(i, j);
        }
        let mut outlier = vec![false; n];
        for &i in &order[..wrong] {
            outlier[i] = true;
        }
        let mut world = Vec::with_capacity(n);
        let mut observed = Vec::with_capacity(n);
        for &bad in &outlier {
            let cam = DVec3::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(4.0, 8.0),
            );
            world.push(rotation.transpose() * (cam - truth.translation));
            observed.push(if bad {
                DVec2::new(rng.range(-320.0, 320.0), rng.range(-240.0, 240.0)) / F
            } else {
                DVec2::new(cam.x / cam.z, cam.y / cam.z)
                    + DVec2::new(rng.normal(), rng.normal()) * (noise_px / F)
            });
        }
        Scene {
            truth,
            world,
            observed,
            outlier,
        }
    }

    fn options() -> RansacOptions {
        RansacOptions::new(3.0 / F)
    }

    fn median(mut v: Vec<f64>) -> f64 {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    }

    #[test]
    fn ransac_finds_the_camera_through_up_to_80_percent_outliers() {
        let mut rng = SceneRng(7);
        for outliers in [0.1, 0.3, 0.5, 0.7, 0.8] {
            let mut angles = Vec::new();
            let mut shifts = Vec::new();
            for trial in 0..20 {
                let s = scene(&mut rng, 200, 1.0, outliers);
                let opts = RansacOptions {
                    seed: trial,
                    ..options()
                };
                let out = ransac_pnp(&s.world, &s.observed, &opts)
                    .unwrap_or_else(|e| panic!("{outliers} trial {trial}: {e}"));
                assert!(out.pose.validate().is_ok());
                let angle = out.pose.rotation_angle_to(&s.truth).to_degrees();
                assert!(angle < 5.0, "{outliers} trial {trial}: failure, {angle}°");
                angles.push(angle);
                shifts.push((out.pose.center() - s.truth.center()).length());

                assert!(out.inliers.windows(2).all(|w| w[0] < w[1]), "sorted");
                let true_inliers = s.outlier.iter().filter(|&&o| !o).count();
                let found = out.inliers.iter().filter(|&&i| !s.outlier[i]).count();
                let wrong = out.inliers.len() - found;
                assert!(
                    found as f64 >= 0.95 * true_inliers as f64,
                    "{outliers} trial {trial}: {found} of {true_inliers} true inliers"
                );
                assert!(
                    wrong <= 2,
                    "{outliers} trial {trial}: {wrong} outliers taken as inliers"
                );
                assert!(out.confident, "{outliers} trial {trial}: {out:?}");
                let rms_px = out.rms * F;
                assert!(rms_px < 2.0, "{outliers} trial {trial}: rms {rms_px} px");
            }
            let (angle, shift) = (median(angles), median(shifts));
            assert!(angle < 0.2, "{outliers}: median {angle}°");
            assert!(shift < 0.05, "{outliers}: median {shift} m");
        }
    }

    #[test]
    fn adaptive_stopping_takes_fewer_iterations_with_fewer_outliers() {
        let mut rng = SceneRng(8);
        let mut few = Vec::new();
        let mut many = Vec::new();
        for trial in 0..5 {
            for (outliers, out_list) in [(0.1, &mut few), (0.7, &mut many)] {
                let s = scene(&mut rng, 200, 1.0, outliers);
                let opts = RansacOptions {
                    seed: trial,
                    min_iterations: 0,
                    ..options()
                };
                let out = ransac_pnp(&s.world, &s.observed, &opts).unwrap();
                assert!(out.confident, "{outliers}: {out:?}");
                assert!(out.iterations < opts.max_iterations);
                // The criterion at the true inlier ratio (less a little for noise).
                let w = (1.0 - outliers) * 0.97;
                let bound = iterations_needed(w, opts.confidence);
                assert!(
                    out.iterations <= bound,
                    "{outliers}: {} iterations, bound {bound}",
                    out.iterations
                );
                out_list.push(out.iterations as f64);
            }
        }
        let (few, many) = (median(few), median(many));
        // About 6 against about 250 at confidence 0.999.
        assert!(few <= 10.0, "10% outliers: {few} iterations");
        assert!(many >= 10.0 * few, "70%: {many} iterations, 10%: {few}");
    }

    #[test]
    fn running_out_of_iterations_is_not_confident() {
        let mut rng = SceneRng(13);
        let s = scene(&mut rng, 200, 1.0, 0.7);
        let mut answers = 0;
        for seed in 0..10 {
            let opts = RansacOptions {
                seed,
                max_iterations: 30,
                min_iterations: 0,
                ..options()
            };
            match ransac_pnp(&s.world, &s.observed, &opts) {
                // At 30% inliers about 250 iterations are needed for 0.999.
                Ok(out) => {
                    answers += 1;
                    assert!(!out.confident, "seed {seed}: {out:?}");
                    assert_eq!(out.iterations, 30);
                    assert!(out.pose.rotation_angle_to(&s.truth).to_degrees() < 5.0);
                }
                Err(SolveError::NoConsensus { needed, .. }) => assert_eq!(needed, 10),
                Err(e) => panic!("seed {seed}: {e}"),
            }
        }
        // P(an all-inlier sample in 30) = 1 − 0.973³⁰ ≈ 56%.
        assert!(answers > 0);
    }

    #[test]
    fn iterations_needed_follows_the_formula() {
        assert_eq!(iterations_needed(1.0, 0.999), 0);
        // log(0.001)/log(1 − 0.5³) = 51.7; log(0.01)/log(1 − 0.2³) = 573.3.
        assert_eq!(iterations_needed(0.5, 0.999), 52);
        assert_eq!(iterations_needed(0.2, 0.99), 574);
        assert_eq!(iterations_needed(0.0, 0.999), usize::MAX);
        assert!(iterations_needed(1e-9, 0.999) > 1_000_000_000);
    }

    #[test]
    fn all_outliers_give_no_consensus() {
        let mut rng = SceneRng(9);
        let s = scene(&mut rng, 200, 1.0, 1.0);
        let opts = RansacOptions {
            max_iterations: 2000,
            ..options()
        };
        match ransac_pnp(&s.world, &s.observed, &opts) {
            Err(SolveError::NoConsensus {
                best_inliers,
                needed,
            }) => {
                assert_eq!(needed, 10);
                assert!(best_inliers < needed);
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn bad_input_is_refused_with_typed_errors() {
        let mut rng = SceneRng(10);
        let s = scene(&mut rng, 20, 0.0, 0.0);
        let opts = options();
        assert_eq!(
            ransac_pnp(&s.world[..3], &s.observed[..3], &opts),
            Err(SolveError::TooFewPoints { needed: 4, got: 3 })
        );
        assert_eq!(
            ransac_pnp(&s.world, &s.observed[..19], &opts),
            Err(SolveError::LengthMismatch {
                points: 20,
                observations: 19
            })
        );
        let mut world = s.world.clone();
        world[5].y = f64::NAN;
        assert!(matches!(
            ransac_pnp(&world, &s.observed, &opts),
            Err(SolveError::NonFinite { .. })
        ));
        let mut observed = s.observed.clone();
        observed[7].x = f64::INFINITY;
        assert!(matches!(
            ransac_pnp(&s.world, &observed, &opts),
            Err(SolveError::NonFinite { .. })
        ));
        for bad in [
            RansacOptions::new(0.0),
            RansacOptions::new(f64::NAN),
            RansacOptions {
                confidence: 1.0,
                ..opts
            },
            RansacOptions {
                max_iterations: 0,
                min_iterations: 0,
                ..opts
            },
            RansacOptions {
                min_iterations: opts.max_iterations + 1,
                ..opts
            },
            RansacOptions {
                min_inliers: 3,
                ..opts
            },
            RansacOptions {
                min_inlier_ratio: 1.5,
                ..opts
            },
            RansacOptions {
                local: LocalOptimisation {
                    loose_factor: 0.5,
                    ..opts.local
                },
                ..opts
            },
        ] {
            assert!(
                matches!(
                    ransac_pnp(&s.world, &s.observed, &bad),
                    Err(SolveError::BadParameter { .. })
                ),
                "{bad:?}"
            );
        }
        assert_eq!(
            ransac_pnp(
                &s.world,
                &s.observed,
                &RansacOptions {
                    min_inliers: 21,
                    ..opts
                }
            ),
            Err(SolveError::TooFewPoints {
                needed: 21,
                got: 20
            })
        );
    }

    #[test]
    fn collinear_world_points_are_degenerate() {
        let pose = CvPose::new(DMat3::from_rotation_y(0.2), DVec3::new(0.0, 0.0, 5.0));
        let world: Vec<DVec3> = (0..10)
            .map(|i| DVec3::new(i as f64 * 0.1 - 0.5, 0.0, 0.0))
            .collect();
        let observed: Vec<DVec2> = world.iter().map(|&x| pose.project(x).unwrap()).collect();
        assert_eq!(
            ransac_pnp(&world, &observed, &options()),
            Err(SolveError::Degenerate(Degeneracy::CollinearPoints))
        );
    }

    #[test]
    fn exact_data_gives_the_exact_camera() {
        let mut rng = SceneRng(11);
        let s = scene(&mut rng, 6, 0.0, 0.0);
        let out = ransac_pnp(&s.world, &s.observed, &options()).unwrap();
        assert_eq!(out.inliers, (0..6).collect::<Vec<_>>());
        assert!(out.pose.rotation_angle_to(&s.truth) < 1e-9);
        assert!((out.pose.center() - s.truth.center()).length() < 1e-9);
        assert!(out.rms < 1e-12);
    }

    #[test]
    fn the_same_seed_gives_the_same_answer() {
        let mut rng = SceneRng(12);
        let s = scene(&mut rng, 200, 1.0, 0.6);
        let opts = RansacOptions {
            seed: 42,
            ..options()
        };
        let first = ransac_pnp(&s.world, &s.observed, &opts).unwrap();
        let second = ransac_pnp(&s.world, &s.observed, &opts).unwrap();
        assert_eq!(first, second);
        // Another seed draws other samples, and the answer is (nearly) the same camera.
        let other = ransac_pnp(&s.world, &s.observed, &RansacOptions { seed: 43, ..opts }).unwrap();
        assert!(other.pose.rotation_angle_to(&first.pose).to_degrees() < 0.05);
    }
}
