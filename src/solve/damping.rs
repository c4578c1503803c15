//! Levenberg–Marquardt's damped step over the six degrees of freedom of a pose, with
//! Nielsen's update of the damping: shared by the refinement on correspondences
//! ([`refine_pose`](super::refine::refine_pose)) and the alignment with an image's edges
//! ([`align_to_image`](super::align::align_to_image)).

use nalgebra::{Matrix6, Vector6};

/// The damping at the start, relative to the Hessian's diagonal: close to Gauss–Newton.
const INITIAL_MU: f64 = 1e-3;

/// Beyond this damping no step can be found worth taking: the search gives up.
const MAX_MU: f64 = 1e30;

/// A diagonal entry of the Hessian below this fraction of the largest is raised to it when
/// it scales the damping, so that a direction the data does not constrain is damped too.
const DIAGONAL_FLOOR: f64 = 1e-12;

/// A damped step and the decrease of the cost its quadratic model predicts.
pub(super) struct DampedStep {
    /// `δ = −(H + μ·D)⁻¹·g`, finite.
    pub(super) step: Vector6<f64>,
    /// `½·δᵀ(μ·D·δ − g)`, positive unless `g` is zero.
    pub(super) predicted: f64,
}

/// The damping `μ` and its growth factor `ν` of one Levenberg–Marquardt run.
#[derive(Debug, Clone, Copy)]
pub(super) struct Damping {
    mu: f64,
    nu: f64,
}

impl Damping {
    pub(super) fn new() -> Damping {
        Damping {
            mu: INITIAL_MU,
            nu: 2.0,
        }
    }

    /// The step for the Gauss–Newton Hessian `h` and gradient `g` of the cost (so that
    /// the cost's quadratic model is `c + gᵀδ + ½·δᵀHδ`), damped by `μ` times `H`'s
    /// diagonal `D` (floored, see [`DIAGONAL_FLOOR`]); `None` when the damped matrix is not
    /// positive definite or the step is not finite, in which case the caller should
    /// [`reject`](Self::reject).
    pub(super) fn step(&self, h: &Matrix6<f64>, g: &Vector6<f64>) -> Option<DampedStep> {
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
    pub(super) fn accept(&mut self, actual: f64, predicted: f64) {
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
    pub(super) fn reject(&mut self) -> bool {
        self.mu *= self.nu;
        self.nu *= 2.0;
        self.mu <= MAX_MU
    }

    /// Whether the steps are still close to Gauss–Newton's (not short steps forced by
    /// heavy damping), so that a change of cost at the level of rounding means the minimum
    /// is reached.
    pub(super) fn is_light(&self) -> bool {
        self.mu < 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_damping_steps_near_gauss_newton_and_predicts_the_quadratic_decrease() {
        // The cost ½·|x − a|² with H = I, g = −a at x = 0: Gauss–Newton's step is a, and
        // the model's decrease ½·|a|².
        let h = Matrix6::identity();
        let a = Vector6::new(1.0, -2.0, 0.5, 0.0, 3.0, -1.0);
        let d = Damping::new().step(&h, &(-a)).unwrap();
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
                .step(&Matrix6::zeros(), &Vector6::zeros())
                .is_none()
        );
        let bad = Vector6::from_element(f64::NAN);
        assert!(Damping::new().step(&Matrix6::identity(), &bad).is_none());
    }
}
