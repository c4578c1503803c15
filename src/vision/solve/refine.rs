//! Levenberg–Marquardt refinement of a camera pose over N ≥ 3 point correspondences.
//!
//! # What is minimised
//!
//! For world points `Xᵢ` observed at normalised image coordinates `mᵢ` (for a pixel
//! `(u, v)`: `((u − cx)/fx, (v − cy)/fy)`), the residual of point i under a pose `(R, t)`
//! is `rᵢ = π(R·Xᵢ + t) − mᵢ` with `π(x, y, z) = (x/z, y/z)`, and the cost is
//! `½·Σ ρ(|rᵢ|²)` for the chosen [`Loss`] ρ. Residuals, loss scales and the reported RMS are
//! all in normalised image units: multiply by the focal length for pixels (a 1 px scale at
//! f = 800 px is `1.0 / 800.0`). Working in normalised coordinates keeps the refinement
//! independent of the intrinsics; with `fx ≠ fy` it weighs x and y residuals by `1/fx` and
//! `1/fy`.
//!
//! # Parameterisation
//!
//! The rotation is updated on SO(3) by a **left-multiplied** rotation vector:
//! `R ← exp([δω]×)·R`, `t ← t + δt` (δω in radians, a rotation about axes of the camera
//! frame). The rotation is kept as a unit quaternion between steps, so it stays
//! orthonormal. Robust losses enter as iteratively reweighted least squares: each step
//! solves `(H + μ·diag H)·δ = −g` with `H = Σ wᵢ·JᵢᵀJᵢ`, `g = Σ wᵢ·Jᵢᵀrᵢ`, `wᵢ = ρ′(|rᵢ|²)`,
//! and a step is kept only if it lowers the robust cost (Nielsen's damping update).
//!
//! # Points behind the camera
//!
//! A point is counted as seen when its camera depth is positive and its residual is below
//! [`RESIDUAL_CAP`]; otherwise (behind the camera, or projected absurdly far away) it adds
//! the constant `ρ(RESIDUAL_CAP²)` and no gradient, which keeps the cost continuous as a
//! point crosses the camera's plane. Such points are left out of the RMS and counted in
//! [`Refined::unseen`].

use std::convert::Infallible;

use glam::{DMat3, DQuat, DVec2, DVec3};

use super::lm::{
    NormalEquations, PoseEstimate, PoseProblem, PoseStep, Readiness, RoundingTest, Settings,
    minimise,
};
use super::{CvPose, SolveError, check_pairs};

/// The fewest correspondences [`refine_pose`] accepts (six unknowns, two equations each).
pub const MIN_POINTS: usize = 3;

/// A step (lightly damped) that changes the cost by no more than this fraction of it ends
/// the refinement as converged: the change is at the level of rounding.
const COST_ROUNDING: f64 = 1e-13;

/// A residual (normalised image units) beyond which a point's cost stops growing: about
/// 89.94° off the optical axis, far outside any real image.
pub const RESIDUAL_CAP: f64 = 1e3;

/// The loss ρ applied to each point's squared residual `s = |rᵢ|²` (normalised units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Loss {
    /// Plain least squares: `ρ(s) = s`. Every point pulls in proportion to its error, so a
    /// single gross outlier can drag the pose away.
    Squared,
    /// Huber: `ρ(s) = s` for `√s ≤ scale`, `2·scale·√s − scale²` beyond: quadratic for
    /// inliers, linear (bounded pull) for outliers. `scale` is usually 1–3 times the
    /// expected noise.
    Huber {
        /// Where the loss turns linear, normalised image units; finite and positive.
        scale: f64,
    },
    /// Cauchy: `ρ(s) = scale²·ln(1 + s/scale²)`: the pull of a point falls off beyond
    /// `scale`, so gross outliers are nearly ignored (but the cost is not convex: start
    /// near the answer).
    Cauchy {
        /// The residual at which a point's weight has halved, normalised image units;
        /// finite and positive.
        scale: f64,
    },
}

impl Loss {
    /// `Ok` unless the scale is not finite and positive ([`SolveError::BadParameter`]).
    pub(crate) fn validate(&self) -> Result<(), SolveError> {
        match *self {
            Loss::Squared => Ok(()),
            Loss::Huber { scale } | Loss::Cauchy { scale } => {
                if scale.is_finite() && scale > 0.0 {
                    Ok(())
                } else {
                    Err(SolveError::BadParameter {
                        what: "the loss scale",
                        value: scale,
                    })
                }
            }
        }
    }

    /// `ρ(s)` and the weight `ρ′(s)` for a squared residual `s ≥ 0`.
    pub(crate) fn eval(&self, s: f64) -> (f64, f64) {
        match *self {
            Loss::Squared => (s, 1.0),
            Loss::Huber { scale } => {
                let r = s.sqrt();
                if r <= scale {
                    (s, 1.0)
                } else {
                    (2.0 * scale * r - scale * scale, scale / r)
                }
            }
            Loss::Cauchy { scale } => {
                let c2 = scale * scale;
                ((c2 * (s / c2).ln_1p()), 1.0 / (1.0 + s / c2))
            }
        }
    }
}

/// How [`refine_pose`] runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineOptions {
    /// The robust loss.
    pub loss: Loss,
    /// The most Levenberg–Marquardt iterations (each solves one damped system); at least 1.
    pub max_iterations: usize,
    /// Convergence: a step with `|δω| ≤ tolerance` (radians) and
    /// `|δt| ≤ tolerance·(1 + |t|)` ends the refinement as converged, and so does a step
    /// that changes the cost by no more than rounding (1e-13 of it). Finite and positive.
    pub tolerance: f64,
}

impl RefineOptions {
    /// `loss` with 100 iterations at most and a tolerance of 1e-9.
    pub fn new(loss: Loss) -> RefineOptions {
        RefineOptions {
            loss,
            max_iterations: 100,
            tolerance: 1e-9,
        }
    }

    fn validate(&self) -> Result<(), SolveError> {
        self.loss.validate()?;
        if self.max_iterations == 0 {
            return Err(SolveError::BadParameter {
                what: "max_iterations",
                value: 0.0,
            });
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(SolveError::BadParameter {
                what: "the tolerance",
                value: self.tolerance,
            });
        }
        Ok(())
    }
}

/// The outcome of [`refine_pose`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Refined {
    /// The refined pose: a proper rotation (kept as a unit quaternion) and finite numbers.
    pub pose: CvPose,
    /// Root mean square of `|rᵢ|` over the seen points (normalised image units; multiply
    /// by the focal length for pixels). Zero when no point is seen.
    pub rms: f64,
    /// How many points are behind the camera or beyond [`RESIDUAL_CAP`] at the refined
    /// pose (left out of `rms`).
    pub unseen: usize,
    /// Iterations taken (damped systems solved, kept or not).
    pub iterations: usize,
    /// Whether a convergence test was met (see [`RefineOptions::tolerance`]); `false` when
    /// the iteration limit was reached or the damping grew without a step being kept.
    pub converged: bool,
}

impl Refined {
    /// This outcome if it converged; otherwise [`SolveError::DidNotConverge`].
    pub fn require_converged(self) -> Result<Refined, SolveError> {
        if self.converged {
            Ok(self)
        } else {
            Err(SolveError::DidNotConverge {
                iterations: self.iterations,
            })
        }
    }
}

/// Refines `initial` to minimise the robust reprojection cost of the correspondences
/// `world[i] ↔ observed[i]` (see the [module docs](self) for the cost, units and update).
///
/// Preconditions, each refused with an error rather than assumed:
/// * `world.len() == observed.len()` ([`SolveError::LengthMismatch`]) and at least
///   [`MIN_POINTS`] of them ([`SolveError::TooFewPoints`]);
/// * every number finite ([`SolveError::NonFinite`]);
/// * `initial` a proper rotation ([`CvPose::validate`]);
/// * `options` in range ([`SolveError::BadParameter`]).
///
/// Postconditions: the returned pose has a cost no higher than `initial`'s (steps are kept
/// only when they lower it), a proper rotation and finite numbers. It is a local minimum
/// only if [`Refined::converged`]; with fewer than three well-spread points seen, or all
/// points on a line through the camera, the pose is not determined and the refinement
/// stops where the damping leaves it.
pub fn refine_pose(
    initial: &CvPose,
    world: &[DVec3],
    observed: &[DVec2],
    options: &RefineOptions,
) -> Result<Refined, SolveError> {
    check_pairs(world, observed)?;
    if world.len() < MIN_POINTS {
        return Err(SolveError::TooFewPoints {
            needed: MIN_POINTS,
            got: world.len(),
        });
    }
    initial.validate()?;
    options.validate()?;

    let problem = Problem {
        world,
        observed,
        loss: options.loss,
    };
    let pose = PoseEstimate::new(initial.rotation, initial.translation);
    let current = problem.evaluate(pose.rotation, pose.translation, true);
    if !current.cost.is_finite() {
        return Err(SolveError::NonFinite {
            what: "reprojection cost at the initial pose",
        });
    }
    let mut refinement = Refinement {
        problem,
        tolerance: options.tolerance,
        pose,
        current,
        tried: None,
    };
    let settings = Settings {
        max_iterations: options.max_iterations,
        cost_rounding: COST_ROUNDING,
        rounding_test: RoundingTest::EveryStep,
    };
    let Ok(outcome) = minimise(&mut refinement, &settings);

    let PoseEstimate {
        rotation: q,
        translation: t,
    } = refinement.pose;
    let pose = CvPose::new(DMat3::from_quat(q), t);
    let fit = refinement.problem.evaluate(q, t, false);
    Ok(Refined {
        pose,
        rms: fit.rms(),
        unseen: fit.unseen,
        iterations: outcome.iterations,
        converged: outcome.converged(),
    })
}

/// A refinement under way: the correspondences, the current pose and its evaluation, and
/// the pose last tried with its evaluation (kept, so that a step taken need not be
/// evaluated twice).
struct Refinement<'a> {
    problem: Problem<'a>,
    /// [`RefineOptions::tolerance`].
    tolerance: f64,
    pose: PoseEstimate,
    current: Evaluation,
    tried: Option<(PoseEstimate, Evaluation)>,
}

impl PoseProblem for Refinement<'_> {
    type Error = Infallible;

    fn cost(&self) -> f64 {
        self.current.cost
    }

    fn normal_equations(&self) -> &NormalEquations {
        &self.current.equations
    }

    /// A zero cost is the minimum: every point is seen exactly where it is observed.
    fn prepare(&mut self) -> Result<Readiness, Infallible> {
        Ok(if self.current.cost == 0.0 {
            Readiness::AtMinimum
        } else {
            Readiness::Ready
        })
    }

    /// `|δω| ≤ tolerance` (radians) and `|δt| ≤ tolerance·(1 + |t|)`.
    fn negligible(&self, step: &PoseStep) -> bool {
        let omega = DVec3::new(step[0], step[1], step[2]);
        let dt = DVec3::new(step[3], step[4], step[5]);
        omega.length() <= self.tolerance
            && dt.length() <= self.tolerance * (1.0 + self.pose.translation.length())
    }

    fn try_step(&mut self, step: &PoseStep) -> f64 {
        let next = self.pose.stepped(step);
        let trial = self.problem.evaluate(next.rotation, next.translation, true);
        let cost = trial.cost;
        self.tried = Some((next, trial));
        cost
    }

    fn accept(&mut self) {
        if let Some((pose, evaluation)) = self.tried.take() {
            (self.pose, self.current) = (pose, evaluation);
        }
    }
}

/// The correspondences and loss of one refinement.
struct Problem<'a> {
    world: &'a [DVec3],
    observed: &'a [DVec2],
    loss: Loss,
}

/// The cost (and, when asked, normal equations) at one pose.
struct Evaluation {
    /// `½·Σ ρ(|rᵢ|²)`.
    cost: f64,
    /// `Σ |rᵢ|²` over the seen points.
    squared: f64,
    seen: usize,
    unseen: usize,
    /// The normal equations of the cost (zero unless asked for).
    equations: NormalEquations,
}

impl Evaluation {
    fn rms(&self) -> f64 {
        if self.seen == 0 {
            0.0
        } else {
            (self.squared / self.seen as f64).sqrt()
        }
    }
}

impl Problem<'_> {
    fn evaluate(&self, q: DQuat, t: DVec3, with_normal_equations: bool) -> Evaluation {
        let rotation = DMat3::from_quat(q);
        let capped = self.loss.eval(RESIDUAL_CAP * RESIDUAL_CAP).0;
        let mut out = Evaluation {
            cost: 0.0,
            squared: 0.0,
            seen: 0,
            unseen: 0,
            equations: NormalEquations::zeros(),
        };
        for (x, m) in self.world.iter().zip(self.observed) {
            let a = rotation * *x;
            let p = a + t;
            let residual = if p.z > 0.0 {
                DVec2::new(p.x / p.z, p.y / p.z) - *m
            } else {
                DVec2::splat(f64::INFINITY)
            };
            let s = residual.length_squared();
            if s.is_nan() || s > RESIDUAL_CAP * RESIDUAL_CAP {
                out.cost += 0.5 * capped;
                out.unseen += 1;
                continue;
            }
            let (rho, weight) = self.loss.eval(s);
            out.cost += 0.5 * rho;
            out.squared += s;
            out.seen += 1;
            if !with_normal_equations {
                continue;
            }
            // The rows of ∂r/∂p, with a = R·X.
            let inv_z = 1.0 / p.z;
            let rows = [
                DVec3::new(inv_z, 0.0, -p.x * inv_z * inv_z),
                DVec3::new(0.0, inv_z, -p.y * inv_z * inv_z),
            ];
            for (row, r) in rows.into_iter().zip([residual.x, residual.y]) {
                out.equations.add(a, row, r, weight);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::vision::testing::Rng;

    const F: f64 = 800.0;

    /// The EPnP paper's set-up: a random pose, `n` points in [-2,2]²×[4,8] in front of the
    /// camera (with `near`: [-2,2]²×[2,5], a wider view), observed with `noise_px` Gaussian pixel noise at f = 800; a fraction
    /// `outliers` of the observations replaced by uniform points of a 640×480 image.
    fn scene(
        rng: &mut Rng,
        n: usize,
        noise_px: f64,
        outliers: f64,
        near: bool,
    ) -> (CvPose, Vec<DVec3>, Vec<DVec2>) {
        let (side, near_z, far_z) = if near {
            (2.0, 2.0, 5.0)
        } else {
            (2.0, 4.0, 8.0)
        };
        let rotation = DMat3::from_axis_angle(rng.unit_vector(), rng.range(-3.0, 3.0));
        let truth = CvPose::new(rotation, rng.vector(-1.0, 1.0));
        let mut world = Vec::with_capacity(n);
        let mut observed = Vec::with_capacity(n);
        let wrong = (n as f64 * outliers).round() as usize;
        for i in 0..n {
            let cam = DVec3::new(
                rng.range(-side, side),
                rng.range(-side, side),
                rng.range(near_z, far_z),
            );
            world.push(rotation.transpose() * (cam - truth.translation));
            let m = if i < wrong {
                DVec2::new(rng.range(-320.0, 320.0), rng.range(-240.0, 240.0)) / F
            } else {
                DVec2::new(cam.x / cam.z, cam.y / cam.z)
                    + DVec2::new(rng.normal(), rng.normal()) * (noise_px / F)
            };
            observed.push(m);
        }
        (truth, world, observed)
    }

    /// `truth` turned by `degrees` about a random axis and moved by `metres`.
    fn perturb(rng: &mut Rng, truth: &CvPose, degrees: f64, metres: f64) -> CvPose {
        let turn = DMat3::from_axis_angle(rng.unit_vector(), degrees.to_radians());
        CvPose::new(
            turn * truth.rotation,
            truth.translation + rng.unit_vector() * metres,
        )
    }

    fn errors(a: &CvPose, b: &CvPose) -> (f64, f64) {
        (
            a.rotation_angle_to(b).to_degrees(),
            (a.center() - b.center()).length(),
        )
    }

    #[test]
    fn refine_recovers_an_exact_pose_from_noise_free_data() {
        let mut rng = Rng(1);
        let (truth, world, observed) = scene(&mut rng, 20, 0.0, 0.0, false);
        let start = perturb(&mut rng, &truth, 5.0, 0.2);
        for loss in [
            Loss::Squared,
            Loss::Huber { scale: 2.0 / F },
            Loss::Cauchy { scale: 2.0 / F },
        ] {
            let out = refine_pose(&start, &world, &observed, &RefineOptions::new(loss)).unwrap();
            assert!(out.converged, "{loss:?}: {out:?}");
            let (angle, shift) = errors(&out.pose, &truth);
            assert!(
                angle < 1e-8 && shift < 1e-8,
                "{loss:?}: {angle}°, {shift} m"
            );
            assert!(out.rms < 1e-10, "{loss:?}: rms {}", out.rms);
            assert_eq!(out.unseen, 0);
            assert!(out.pose.validate().is_ok());
        }
    }

    #[test]
    fn refine_converges_under_pixel_noise() {
        let mut rng = Rng(2);
        for trial in 0..20 {
            let (truth, world, observed) = scene(&mut rng, 50, 1.0, 0.0, true);
            let start = perturb(&mut rng, &truth, 2.0, 0.05);
            let options = RefineOptions::new(Loss::Huber { scale: 2.0 / F });
            let out = refine_pose(&start, &world, &observed, &options).unwrap();
            assert!(out.converged, "trial {trial}: {out:?}");
            assert!(
                out.iterations < 30,
                "trial {trial}: {} iterations",
                out.iterations
            );
            let (angle, shift) = errors(&out.pose, &truth);
            // The same minimum as a refinement started at the true pose.
            let from_truth = refine_pose(&truth, &world, &observed, &options).unwrap();
            let (da, ds) = errors(&out.pose, &from_truth.pose);
            assert!(
                da < 1e-7 && ds < 1e-8,
                "trial {trial}: {da}° {ds} m from the optimum"
            );
            assert!(
                angle < 0.1 && shift < 0.01,
                "trial {trial}: {angle}°, {shift} m"
            );
            // 1 px noise on both axes: the RMS residual is about √2 px.
            let rms_px = out.rms * F;
            assert!(
                rms_px > 1.0 && rms_px < 1.8,
                "trial {trial}: rms {rms_px} px"
            );
        }
    }

    #[test]
    fn robust_losses_resist_gross_outliers_where_least_squares_does_not() {
        let mut rng = Rng(3);
        let mut worse = 0;
        for trial in 0..10 {
            let (truth, world, observed) = scene(&mut rng, 50, 1.0, 0.2, false);
            let start = perturb(&mut rng, &truth, 2.0, 0.05);
            let plain = refine_pose(
                &start,
                &world,
                &observed,
                &RefineOptions::new(Loss::Squared),
            )
            .unwrap();
            let (plain_angle, plain_shift) = errors(&plain.pose, &truth);
            for loss in [
                Loss::Huber { scale: 2.0 / F },
                Loss::Cauchy { scale: 2.0 / F },
            ] {
                let out =
                    refine_pose(&start, &world, &observed, &RefineOptions::new(loss)).unwrap();
                assert!(out.converged, "trial {trial} {loss:?}: {out:?}");
                let (angle, shift) = errors(&out.pose, &truth);
                assert!(angle < 0.5, "trial {trial} {loss:?}: {angle}°, {shift} m");
                assert!(
                    angle < plain_angle && shift < plain_shift,
                    "trial {trial} {loss:?}: robust {angle}° {shift} m, plain {plain_angle}° {plain_shift} m"
                );
            }
            if plain_angle > 0.5 {
                worse += 1;
            }
        }
        // Least squares is not just a little worse: it is usually dragged well off.
        assert!(worse >= 5, "least squares failed only {worse} of 10 times");
    }

    #[test]
    fn points_behind_the_camera_are_counted_not_fatal() {
        let mut rng = Rng(4);
        let (truth, mut world, observed) = scene(&mut rng, 20, 0.0, 0.0, false);
        // Move two points behind the camera (same observations: now gross outliers).
        for x in world.iter_mut().take(2) {
            let cam = truth.transform(*x);
            *x =
                truth.rotation.transpose() * (DVec3::new(cam.x, cam.y, -cam.z) - truth.translation);
        }
        let start = perturb(&mut rng, &truth, 1.0, 0.02);
        let out = refine_pose(
            &start,
            &world,
            &observed,
            &RefineOptions::new(Loss::Cauchy { scale: 2.0 / F }),
        )
        .unwrap();
        assert!(out.converged);
        assert_eq!(out.unseen, 2);
        let (angle, shift) = errors(&out.pose, &truth);
        assert!(angle < 1e-6 && shift < 1e-6, "{angle}°, {shift} m");
    }

    #[test]
    fn refine_refuses_bad_input() {
        let mut rng = Rng(5);
        let (truth, world, observed) = scene(&mut rng, 10, 0.5, 0.0, false);
        let options = RefineOptions::new(Loss::Huber { scale: 1.0 / F });
        assert_eq!(
            refine_pose(&truth, &world[..2], &observed[..2], &options),
            Err(SolveError::TooFewPoints { needed: 3, got: 2 })
        );
        assert_eq!(
            refine_pose(&truth, &world, &observed[..9], &options),
            Err(SolveError::LengthMismatch {
                points: 10,
                observations: 9
            })
        );
        let mut nan_world = world.clone();
        nan_world[3].z = f64::NAN;
        assert!(matches!(
            refine_pose(&truth, &nan_world, &observed, &options),
            Err(SolveError::NonFinite { .. })
        ));
        let mut nan_observed = observed.clone();
        nan_observed[0].x = f64::NEG_INFINITY;
        assert!(matches!(
            refine_pose(&truth, &world, &nan_observed, &options),
            Err(SolveError::NonFinite { .. })
        ));
        let skewed = CvPose::new(truth.rotation * 1.1, truth.translation);
        assert!(matches!(
            refine_pose(&skewed, &world, &observed, &options),
            Err(SolveError::NotARotation { .. })
        ));
        for scale in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let bad = RefineOptions::new(Loss::Cauchy { scale });
            assert!(matches!(
                refine_pose(&truth, &world, &observed, &bad),
                Err(SolveError::BadParameter { .. })
            ));
        }
        let no_iterations = RefineOptions {
            max_iterations: 0,
            ..options
        };
        assert!(matches!(
            refine_pose(&truth, &world, &observed, &no_iterations),
            Err(SolveError::BadParameter { .. })
        ));
    }

    #[test]
    fn an_iteration_limit_is_reported_as_not_converged() {
        let mut rng = Rng(6);
        let (truth, world, observed) = scene(&mut rng, 30, 1.0, 0.0, false);
        let start = perturb(&mut rng, &truth, 10.0, 0.5);
        let options = RefineOptions {
            max_iterations: 1,
            ..RefineOptions::new(Loss::Squared)
        };
        let out = refine_pose(&start, &world, &observed, &options).unwrap();
        assert!(!out.converged);
        assert_eq!(out.iterations, 1);
        assert_eq!(
            out.require_converged(),
            Err(SolveError::DidNotConverge { iterations: 1 })
        );
    }

    #[test]
    fn gradient_matches_finite_differences_of_the_cost() {
        let mut rng = Rng(8);
        let (truth, world, observed) = scene(&mut rng, 12, 3.0, 0.0, false);
        let start = perturb(&mut rng, &truth, 3.0, 0.1);
        for loss in [
            Loss::Squared,
            Loss::Huber { scale: 2.0 / F },
            Loss::Cauchy { scale: 2.0 / F },
        ] {
            let problem = Problem {
                world: &world,
                observed: &observed,
                loss,
            };
            let q = DQuat::from_mat3(&start.rotation).normalize();
            let t = start.translation;
            let at = problem.evaluate(q, t, true);
            for k in 0..6 {
                let h = 1e-7;
                let mut d = [0.0; 6];
                d[k] = h;
                let cost = |sign: f64| {
                    let omega = DVec3::new(d[0], d[1], d[2]) * sign;
                    let dt = DVec3::new(d[3], d[4], d[5]) * sign;
                    problem
                        .evaluate(DQuat::from_scaled_axis(omega) * q, t + dt, false)
                        .cost
                };
                let numeric = (cost(1.0) - cost(-1.0)) / (2.0 * h);
                let analytic = at.equations.gradient[k];
                assert!(
                    (numeric - analytic).abs() <= 1e-5 * analytic.abs().max(1e-3),
                    "{loss:?} parameter {k}: {numeric} vs {analytic}"
                );
            }
        }
    }

    #[test]
    fn losses_match_their_definitions() {
        let huber = Loss::Huber { scale: 2.0 };
        assert_eq!(huber.eval(1.0), (1.0, 1.0));
        assert_eq!(huber.eval(16.0), (2.0 * 2.0 * 4.0 - 4.0, 0.5));
        let cauchy = Loss::Cauchy { scale: 2.0 };
        let (rho, w) = cauchy.eval(4.0);
        assert!((rho - 4.0 * 2f64.ln()).abs() < 1e-15 && (w - 0.5).abs() < 1e-15);
        // ρ′ matches a finite difference of ρ.
        for loss in [Loss::Squared, huber, cauchy] {
            for s in [0.5, 3.0, 30.0] {
                let h = 1e-6;
                let numeric = (loss.eval(s + h).0 - loss.eval(s - h).0) / (2.0 * h);
                assert!((numeric - loss.eval(s).1).abs() < 1e-6, "{loss:?} at {s}");
            }
        }
    }
}
