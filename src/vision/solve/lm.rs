//! Levenberg–Marquardt over the six degrees of freedom of a camera pose: the driver that
//! the refinement on correspondences ([`refine_pose`](super::refine::refine_pose)) and the
//! alignment with an image's edges ([`align_to_image`](super::align::align_to_image)) run.
//!
//! A problem ([`PoseProblem`]) holds its current pose and gives the cost there and the
//! Gauss–Newton normal equations of that cost; [`minimise`] takes damped steps, keeps a
//! step only when it lowers the cost, and stops on the rules of [`Settings`] and of the
//! problem.
//!
//! # The update
//!
//! The pose is in OpenCV's camera frame and moves by a **left-multiplied** rotation vector
//! ([`PoseEstimate::stepped`]): `R ← exp([δω]×)·R`, `t ← t + δt`, δω in radians about
//! the camera's axes. A residual `r(p)` of the camera point `p = R·X + t = a + t` then has
//! the Jacobian `∂r/∂p·[−[a]× | I]` in `(δω, δt)` ([`NormalEquations::add`]).
//!
//! # The damping
//!
//! Each iteration solves `(H + μ·D)·δ = −g` for the Hessian `H` and gradient `g` of the
//! normal equations and `D` the diagonal of `H` (floored, so that a direction the data does
//! not constrain is damped too). The damping `μ` starts at 1e-3, near Gauss–Newton; after a
//! kept step it falls by Nielsen's rule, the more the better the quadratic model predicted
//! the decrease; after a refused step (or a damped matrix that is not positive definite)
//! it grows, faster each time in a row, and past 1e30 the run gives up.

use glam::{DMat3, DQuat, DVec3};
use nalgebra::{Matrix6, Vector6};

/// A step `(δω, δt)`: the rotation vector (radians) then the translation.
pub(super) type PoseStep = Vector6<f64>;

/// The damping at the start, relative to the Hessian's diagonal: close to Gauss–Newton.
const INITIAL_MU: f64 = 1e-3;

/// Beyond this damping no step can be found worth taking: the search gives up.
const MAX_MU: f64 = 1e30;

/// A diagonal entry of the Hessian below this fraction of the largest is raised to it when
/// it scales the damping, so that a direction the data does not constrain is damped too.
const DIAGONAL_FLOOR: f64 = 1e-12;

/// A camera pose in OpenCV's frame (`x_cam = R·x_world + t`) as the driver moves it: the
/// rotation kept as a unit quaternion, so that it stays orthonormal from step to step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PoseEstimate {
    /// `R`, a unit quaternion.
    pub(super) rotation: DQuat,
    /// `t`.
    pub(super) translation: DVec3,
}

impl PoseEstimate {
    /// The pose with rotation matrix `rotation` (a proper rotation, to within rounding) and
    /// translation `translation`.
    pub(super) fn new(rotation: DMat3, translation: DVec3) -> PoseEstimate {
        PoseEstimate {
            rotation: DQuat::from_mat3(&rotation).normalize(),
            translation,
        }
    }

    /// The pose after the left-multiplied update `step = (δω, δt)`: `R ← exp([δω]×)·R`,
    /// `t ← t + δt`.
    pub(super) fn stepped(&self, step: &PoseStep) -> PoseEstimate {
        let omega = DVec3::new(step[0], step[1], step[2]);
        PoseEstimate {
            rotation: (DQuat::from_scaled_axis(omega) * self.rotation).normalize(),
            translation: self.translation + DVec3::new(step[3], step[4], step[5]),
        }
    }
}

/// The Gauss–Newton normal equations of a cost `½·Σ ρ(rᵢ²)` at one pose, iteratively
/// reweighted: `H = Σ wᵢ·JᵢᵀJᵢ`, `g = Σ wᵢ·rᵢ·Jᵢ` with `wᵢ = ρ′(rᵢ²)`. The cost's
/// quadratic model about the pose is `c + gᵀδ + ½·δᵀHδ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct NormalEquations {
    pub(super) hessian: Matrix6<f64>,
    pub(super) gradient: Vector6<f64>,
}

impl NormalEquations {
    /// No residuals yet: both zero.
    pub(super) fn zeros() -> NormalEquations {
        NormalEquations {
            hessian: Matrix6::zeros(),
            gradient: Vector6::zeros(),
        }
    }

    /// Adds the scalar residual `residual` of weight `weight`, whose derivative in the
    /// camera point `p = a + t` is `d_dp` (`a = R·X`): its Jacobian in the step is
    /// `d_dpᵀ·[−[a]× | I] = (a × d_dp, d_dp)`.
    #[inline]
    pub(super) fn add(&mut self, a: DVec3, d_dp: DVec3, residual: f64, weight: f64) {
        let w = a.cross(d_dp);
        let j = Vector6::new(w.x, w.y, w.z, d_dp.x, d_dp.y, d_dp.z);
        self.hessian.syger(weight, &j, &j, 1.0);
        self.gradient.axpy(weight * residual, &j, 1.0);
    }

    /// Adds the scalar residual `residual` of weight `weight` that depends on the
    /// rotation alone, with derivative `d_domega` in the rotation step `δω`: its Jacobian
    /// in the step is `(d_domega, 0)`.
    #[inline]
    pub(super) fn add_turn(&mut self, d_domega: DVec3, residual: f64, weight: f64) {
        let j = Vector6::new(d_domega.x, d_domega.y, d_domega.z, 0.0, 0.0, 0.0);
        self.hessian.syger(weight, &j, &j, 1.0);
        self.gradient.axpy(weight * residual, &j, 1.0);
    }
}

/// What a problem says before an iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Readiness {
    /// A step may be taken from the current pose.
    Ready,
    /// The current pose is a minimum (a zero cost, say): the run has converged.
    AtMinimum,
    /// No step can be taken (too little data at the current pose): the run ends, not
    /// converged.
    Stalled,
}

/// A robust least-squares problem over a camera pose, as [`minimise`] drives it. The
/// problem holds its current pose, the cost there and the normal equations of that cost.
pub(super) trait PoseProblem {
    /// Why the problem cannot go on (refreshing its data failed).
    type Error;

    /// The cost at the current pose: finite and not negative.
    fn cost(&self) -> f64;

    /// The normal equations of the cost at the current pose.
    fn normal_equations(&self) -> &NormalEquations;

    /// Called before each iteration, once the iteration limit is known not to be reached:
    /// the problem may refresh what it works on, and says whether a step may be taken.
    /// [`Readiness::Ready`] means the iteration will run (and count).
    fn prepare(&mut self) -> Result<Readiness, Self::Error>;

    /// Whether `step` is too small to matter: the run has converged.
    fn negligible(&self, step: &PoseStep) -> bool;

    /// The cost at the current pose moved by `step`, to compare with [`cost`](Self::cost);
    /// NaN or infinite when it cannot be evaluated. The problem remembers the pose tried.
    fn try_step(&mut self, step: &PoseStep) -> f64;

    /// Makes the pose last tried by [`try_step`](Self::try_step) the current one, with its
    /// cost and normal equations.
    fn accept(&mut self);
}

/// Which steps can end a run as converged by changing the cost by rounding only (see
/// [`Settings::cost_rounding`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum RoundingTest {
    /// Every step tried, kept or refused, by the size of the change `|Δ|` and with the
    /// damping the step was computed with. For a cost that is one smooth function of the
    /// pose throughout the run: a refused step that changes it by rounding only shows the
    /// minimum reached as well as a kept one.
    EveryStep,
    /// Kept steps only, with the damping as updated for the step. For a cost whose terms
    /// are chosen anew at each kept pose (matches found again): only a kept step's change
    /// says anything of the minimum.
    KeptSteps,
}

/// How [`minimise`] runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Settings {
    /// The most iterations (damped systems solved, steps kept or not); at least 1.
    pub(super) max_iterations: usize,
    /// A step taken with light damping (`μ < 1`, steps still close to Gauss–Newton's) that
    /// changes the cost by no more than this fraction of it ends the run as converged.
    pub(super) cost_rounding: f64,
    /// Which steps that test applies to.
    pub(super) rounding_test: RoundingTest,
}

/// Why a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Ending {
    /// The problem found the step negligible ([`PoseProblem::negligible`]).
    SmallStep,
    /// A step changed the cost by rounding only ([`Settings::cost_rounding`]).
    Flat,
    /// The problem said the current pose is a minimum ([`Readiness::AtMinimum`]).
    AtMinimum,
    /// The problem could take no step ([`Readiness::Stalled`]).
    Stalled,
    /// [`Settings::max_iterations`] were run.
    IterationLimit,
    /// The damping grew past its limit without a step being kept.
    DampingExhausted,
}

/// The outcome of [`minimise`]; the final pose and its cost are the problem's current ones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Outcome {
    /// Iterations run (damped systems solved, steps kept or not).
    pub(super) iterations: usize,
    /// Why the run ended.
    pub(super) ending: Ending,
}

impl Outcome {
    /// Whether a convergence test was met: a negligible step, a change of cost at the
    /// level of rounding, or a minimum the problem recognised.
    pub(super) fn converged(&self) -> bool {
        matches!(
            self.ending,
            Ending::SmallStep | Ending::Flat | Ending::AtMinimum
        )
    }
}

/// Runs Levenberg–Marquardt on `problem` from its current pose (see the
/// [module documentation](self) for the step and the damping).
///
/// Each iteration: [`PoseProblem::prepare`]; the damped step (a damped matrix that is not
/// positive definite, or a step that is not finite, counts as refused); the run ends as
/// converged when the step is [negligible](PoseProblem::negligible); otherwise the step is
/// tried and kept when it lowers the cost, and the rounding test of `settings` applies.
///
/// Precondition: `settings.max_iterations ≥ 1` (with 0 no iteration runs).
/// Postcondition: the problem's pose has a cost no higher than at the start (only steps that
/// lower it are kept); errors come only from [`PoseProblem::prepare`].
pub(super) fn minimise<P: PoseProblem>(
    problem: &mut P,
    settings: &Settings,
) -> Result<Outcome, P::Error> {
    let mut damping = Damping::new();
    let mut iterations = 0;
    let ending = loop {
        if iterations >= settings.max_iterations {
            break Ending::IterationLimit;
        }
        match problem.prepare()? {
            Readiness::Ready => {}
            Readiness::AtMinimum => break Ending::AtMinimum,
            Readiness::Stalled => break Ending::Stalled,
        }
        iterations += 1;
        let Some(DampedStep { step, predicted }) = damping.step(problem.normal_equations()) else {
            if !damping.reject() {
                break Ending::DampingExhausted;
            }
            continue;
        };
        if problem.negligible(&step) {
            break Ending::SmallStep;
        }
        let cost = problem.cost();
        let trial = problem.try_step(&step);
        let actual = cost - trial;
        let rounding = settings.cost_rounding * cost;
        let flat_tried = settings.rounding_test == RoundingTest::EveryStep
            && damping.is_light()
            && actual.abs() <= rounding;
        if trial.is_finite() && actual > 0.0 {
            damping.accept(actual, predicted);
            let flat_kept = settings.rounding_test == RoundingTest::KeptSteps
                && damping.is_light()
                && actual <= rounding;
            problem.accept();
            if flat_tried || flat_kept {
                break Ending::Flat;
            }
        } else if !damping.reject() {
            break Ending::DampingExhausted;
        } else if flat_tried {
            break Ending::Flat;
        }
    };
    Ok(Outcome { iterations, ending })
}

/// A damped step and the decrease of the cost its quadratic model predicts.
struct DampedStep {
    /// `δ = −(H + μ·D)⁻¹·g`, finite.
    step: PoseStep,
    /// `½·δᵀ(μ·D·δ − g)`, positive unless `g` is zero.
    predicted: f64,
}

/// The damping `μ` and its growth factor `ν` of one run.
#[derive(Debug, Clone, Copy)]
struct Damping {
    mu: f64,
    nu: f64,
}

impl Damping {
    fn new() -> Damping {
        Damping {
            mu: INITIAL_MU,
            nu: 2.0,
        }
    }

    /// The step for the normal equations `e`, damped by `μ` times the Hessian's diagonal
    /// `D` (floored, see [`DIAGONAL_FLOOR`]); `None` when the damped matrix is not positive
    /// definite or the step is not finite, in which case the caller should
    /// [`reject`](Self::reject).
    fn step(&self, e: &NormalEquations) -> Option<DampedStep> {
        let (h, g) = (&e.hessian, &e.gradient);
        let largest = h.diagonal().max();
        let diagonal = Vector6::from_fn(|i, _| h[(i, i)].max(DIAGONAL_FLOOR * largest));
        let damped = h + Matrix6::from_diagonal(&(diagonal * self.mu));
        let step = -damped.cholesky()?.solve(g);
        if !step.iter().all(|v| v.is_finite()) {
            return None;
        }
        let predicted = 0.5 * step.dot(&(step.component_mul(&diagonal) * self.mu - g));
        Some(DampedStep { step, predicted })
    }

    /// After a step that lowered the cost by `actual` where `predicted` was expected: the
    /// damping falls (at most threefold) the better the model predicted.
    fn accept(&mut self, actual: f64, predicted: f64) {
        let gain = if predicted > 0.0 {
            actual / predicted
        } else {
            1.0
        };
        self.mu *= (1.0 - (2.0 * gain - 1.0).powi(3)).max(1.0 / 3.0);
        self.nu = 2.0;
    }

    /// After a refused step: the damping grows, faster each time in a row. Returns `false`
    /// once it is so large that the search should give up.
    fn reject(&mut self) -> bool {
        self.mu *= self.nu;
        self.nu *= 2.0;
        self.mu <= MAX_MU
    }

    /// Whether the steps are still close to Gauss–Newton's (not short steps forced by
    /// heavy damping), so that a change of cost at the level of rounding means the minimum
    /// is reached.
    fn is_light(&self) -> bool {
        self.mu < 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn equations(h: Matrix6<f64>, g: Vector6<f64>) -> NormalEquations {
        NormalEquations {
            hessian: h,
            gradient: g,
        }
    }

    #[test]
    fn light_damping_steps_near_gauss_newton_and_predicts_the_quadratic_decrease() {
        // The cost ½·|x − a|² with H = I, g = −a at x = 0: Gauss–Newton's step is a, and
        // the model's decrease ½·|a|².
        let h = Matrix6::identity();
        let a = Vector6::new(1.0, -2.0, 0.5, 0.0, 3.0, -1.0);
        let d = Damping::new().step(&equations(h, -a)).unwrap();
        assert!((d.step - a / (1.0 + INITIAL_MU)).norm() < 1e-12);
        let model = a.dot(&d.step) - 0.5 * d.step.norm_squared();
        assert!(
            (d.predicted - model).abs() < 1e-12,
            "{} {model}",
            d.predicted
        );
    }

    #[test]
    fn damping_grows_on_refusals_until_it_gives_up_and_falls_on_good_steps() {
        let mut d = Damping::new();
        d.accept(1.0, 1.0);
        assert!((d.mu - INITIAL_MU / 3.0).abs() < 1e-18);
        let mut refusals = 0;
        while d.reject() {
            refusals += 1;
            assert!(refusals < 100);
        }
        assert!(refusals > 5 && !d.is_light());
        assert!(
            Damping::new()
                .step(&equations(Matrix6::zeros(), Vector6::zeros()))
                .is_none()
        );
        let bad = Vector6::from_element(f64::NAN);
        assert!(
            Damping::new()
                .step(&equations(Matrix6::identity(), bad))
                .is_none()
        );
    }

    /// The cost `½·|x − target|²` over six parameters (the step's own coordinates), its
    /// normal equations exact: a quadratic, which Levenberg–Marquardt solves in a few
    /// steps.
    struct Quadratic {
        target: Vector6<f64>,
        x: Vector6<f64>,
        tried: Vector6<f64>,
        equations: NormalEquations,
        /// What `prepare` answers once `x` is the target.
        at_target: Readiness,
        prepared: usize,
    }

    impl Quadratic {
        fn new(target: Vector6<f64>, at_target: Readiness) -> Quadratic {
            let mut q = Quadratic {
                target,
                x: Vector6::zeros(),
                tried: Vector6::zeros(),
                equations: NormalEquations::zeros(),
                at_target,
                prepared: 0,
            };
            q.linearise();
            q
        }

        fn cost_at(&self, x: &Vector6<f64>) -> f64 {
            0.5 * (x - self.target).norm_squared()
        }

        fn linearise(&mut self) {
            self.equations = equations(Matrix6::identity(), self.x - self.target);
        }
    }

    impl PoseProblem for Quadratic {
        type Error = ();

        fn cost(&self) -> f64 {
            self.cost_at(&self.x)
        }

        fn normal_equations(&self) -> &NormalEquations {
            &self.equations
        }

        fn prepare(&mut self) -> Result<Readiness, ()> {
            self.prepared += 1;
            Ok(if self.x == self.target {
                self.at_target
            } else {
                Readiness::Ready
            })
        }

        fn negligible(&self, step: &PoseStep) -> bool {
            step.norm() <= 1e-12
        }

        fn try_step(&mut self, step: &PoseStep) -> f64 {
            self.tried = self.x + step;
            self.cost_at(&self.tried)
        }

        fn accept(&mut self) {
            self.x = self.tried;
            self.linearise();
        }
    }

    #[test]
    fn a_quadratic_is_minimised_and_the_ending_says_why() {
        let target = Vector6::new(1.0, -2.0, 0.5, 0.0, 3.0, -1.0);
        for rounding_test in [RoundingTest::EveryStep, RoundingTest::KeptSteps] {
            let settings = Settings {
                max_iterations: 50,
                cost_rounding: 1e-13,
                rounding_test,
            };
            let mut q = Quadratic::new(target, Readiness::Ready);
            let start = q.cost();
            let out = minimise(&mut q, &settings).unwrap();
            assert!(out.converged(), "{rounding_test:?}: {out:?}");
            assert!((q.x - target).norm() < 1e-9, "{rounding_test:?}: {}", q.x);
            assert!(q.cost() < 1e-18 * start, "{rounding_test:?}: {}", q.cost());
            assert!(out.iterations < 20 && out.iterations <= q.prepared);
        }
        // A problem that stalls ends the run unconverged; one at its minimum, converged.
        let settings = Settings {
            max_iterations: 50,
            cost_rounding: 1e-13,
            rounding_test: RoundingTest::EveryStep,
        };
        let mut there = Quadratic::new(Vector6::zeros(), Readiness::Stalled);
        let out = minimise(&mut there, &settings).unwrap();
        assert_eq!((out.ending, out.iterations), (Ending::Stalled, 0));
        assert!(!out.converged());
        let mut there = Quadratic::new(Vector6::zeros(), Readiness::AtMinimum);
        let out = minimise(&mut there, &settings).unwrap();
        assert_eq!((out.ending, out.iterations), (Ending::AtMinimum, 0));
        assert!(out.converged());
        // An iteration limit is not convergence.
        let mut q = Quadratic::new(target, Readiness::Ready);
        let one = Settings {
            max_iterations: 1,
            ..settings
        };
        let out = minimise(&mut q, &one).unwrap();
        assert_eq!((out.ending, out.iterations), (Ending::IterationLimit, 1));
        assert!(!out.converged());
    }
}
