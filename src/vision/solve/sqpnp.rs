//! SQPnP: the globally best camera pose from N ≥ 3 point correspondences.
//!
//! After G. Terzakis and M. Lourakis, "A Consistently Fast and Globally Optimal Solution to
//! the Perspective-n-Point Problem", ECCV 2020.
//!
//! # What is minimised
//!
//! For world points `Xᵢ` observed at normalised image coordinates `mᵢ = (uᵢ, vᵢ)` with
//! weights `wᵢ ≥ 0`, and camera points `pᵢ = R·Xᵢ + t`, the cost is
//!
//! ```text
//! E(R, t) = Σ wᵢ·((pᵢ.x − uᵢ·pᵢ.z)² + (pᵢ.y − vᵢ·pᵢ.z)²) = Σ wᵢ·pᵢ.z²·|π(pᵢ) − mᵢ|²,
//! ```
//!
//! the reprojection error of each point scaled by its depth (an "algebraic" error, in world
//! units squared). It is quadratic in `(r, t)` with `r` the nine entries of `R` row by row,
//! so the best `t` for a given `r` is linear, `t = P·r`, and what remains is
//! `E = rᵀ·Ω·r` with a 9×9 symmetric positive semi-definite `Ω` built once from the data
//! (in one pass over the points: `Ω` needs only four weighted sums of `Xᵢ·Xᵢᵀ`).
//!
//! # The search
//!
//! Minimising `rᵀΩr` over rotations (`R·Rᵀ = I`, `det R = 1`) is a quadratic programme on
//! the rotation manifold. The paper shows that every minimum lies close to an eigenvector
//! of `Ω` with a small eigenvalue, scaled by √3 (a rotation has `|r|² = 3`). So:
//!
//! 1. `Ω` is eigen-decomposed. Its null space (eigenvalues below `1e-7` of the largest;
//!    at least one vector) gives the start points: for each vector `e`, the nearest
//!    rotations to `√3·e` and to `−√3·e` (only the first when `√3·e` is already a
//!    rotation up to sign).
//! 2. From each start, sequential quadratic programming: at `r`, the step `δ` minimises
//!    `(r + δ)ᵀΩ(r + δ)` subject to the linearised orthonormality constraints
//!    `h(r) + J(r)·δ = 0` (`h`: the six entries of `R·Rᵀ − I` on and above the diagonal).
//!    Writing `δ = δₕ + D·y` with `δₕ` the least step in `J`'s row space that satisfies
//!    the constraints and `D` a basis of `J`'s null space, `y` minimises the cost in the
//!    tangent space. The iteration stops when `|δ|² ≤ 1e-10` (the reference
//!    implementation's test) or after 15 steps, and the result is projected on the
//!    nearest rotation (after a sign flip if its determinant is negative). A run whose
//!    iterate comes within 1e-3 (in the rotation's entries) of a minimum an earlier run
//!    found is on its way there and stops: with few points the null space holds several
//!    starts, and most of their runs end at a minimum already found.
//! 3. The SQP above converges only linearly where the cost is not zero (it leaves out the
//!    constraints' curvature), so its stopping point can be ~1e-6 off the minimum. Up to
//!    three Newton steps on the rotation manifold, `R ← exp([ω]×)·R` with the exact
//!    gradient and Hessian of `rᵀΩr` in `ω`, finish the job to rounding (quadratically);
//!    a step is taken only where the Hessian is positive definite, the step small and the
//!    cost not higher.
//! 4. While the best cost so far exceeds `3·λ` for the next larger eigenvalue `λ`, a
//!    rotation near that eigenvector could still do better: it is tried too.
//!
//! Each candidate's translation is `t = P·r`. A candidate counts only if it puts the points
//! in front of the camera: the (weighted) centroid of the world points at positive depth,
//! or failing that, at least half the points. The candidate of least cost is the answer;
//! the others found are reported as alternatives.
//!
//! # Conditioning
//!
//! The world points are centred on their weighted centroid and scaled to unit RMS radius
//! before `Ω` is built, and the weights are scaled to mean one, so the thresholds above do
//! not depend on the world's units or position; the pose and cost are given back in the
//! caller's units.
//!
//! The fixed-size algebra (the 9×9 eigen-decomposition, the 6×6 and 3×3 solves, the
//! nearest rotation) is done on plain arrays by the private `small` module: no allocation
//! per iteration, and a solve of a few hundred points takes some microseconds.

use glam::{DMat3, DQuat, DVec2, DVec3};

use super::small::{
    MAX_QL_SWEEPS, Mat9, Vec9, axpy, distance_squared, dot, multiply, nearest_rotation,
    orthonormalise, quadratic, scaled, solve_spd3, symmetric_eigen,
};
use super::{CvPose, Degeneracy, SolveError, check_pairs};

/// The fewest correspondences [`sqpnp()`] accepts (with positive weight).
pub const MIN_POINTS: usize = 3;

/// Eigenvalues of `Ω` below this fraction of the largest are taken as zero (its null space).
const RANK_TOLERANCE: f64 = 1e-7;

/// A null-space vector `√3·e` whose squared orthogonality error `Σ (e·eᵀ − I)²` is below
/// this is a rotation up to sign, and only that sign is tried.
const ORTHOGONAL_SQUARED: f64 = 1e-8;

/// The SQP stops when the step's squared length falls to this (the reference
/// implementation's default); the Newton steps that follow finish the convergence.
const STEP_SQUARED_TOLERANCE: f64 = 1e-10;

/// The most SQP steps from one start.
const MAX_SQP_STEPS: usize = 15;

/// The most Newton steps on the rotation manifold after the SQP.
const MAX_NEWTON_STEPS: usize = 3;

/// A Newton step (radians) of at most this squared length ends the polishing once taken:
/// Newton's method converges quadratically, so what remains is of the order of its square,
/// below rounding.
const NEWTON_SQUARED_TOLERANCE: f64 = 1e-16;

/// The longest Newton step (radians) taken: a longer one means the SQP did not end near a
/// minimum, where Newton's quadratic model is not to be trusted.
const NEWTON_MAX_STEP: f64 = 0.05;

/// An SQP run whose iterate comes this close (squared sum over the rotation's entries:
/// 1e-3 apart, about 0.06°) to a minimum already found is taken to be on its way there.
/// Distinct local minima of `rᵀΩr` on the rotations lie much farther apart.
const KNOWN_MINIMUM_SQUARED: f64 = 1e-6;

/// Two rotations whose entries differ by less than this in squared sum are one minimum.
const SAME_ROTATION_SQUARED: f64 = 1e-10;

/// World points spread across their principal line by less than this fraction of their
/// spread along it (as a variance ratio: the square) are taken to be on one line.
const COLLINEAR_VARIANCE: f64 = 1e-12;

/// World points whose RMS distance from their centroid is below this fraction of their
/// largest coordinate coincide.
const COINCIDENT: f64 = 1e-12;

/// Observations whose RMS distance from their mean is below this (normalised image units,
/// about 1e-6 px at f = 1000 px) are one direction.
const IMAGE_SPREAD_MIN: f64 = 1e-9;

/// A symmetric 3×3 matrix by its six distinct entries, for accumulating sums of `w·x·xᵀ`.
#[derive(Debug, Clone, Copy, Default)]
struct Sym3 {
    xx: f64,
    xy: f64,
    xz: f64,
    yy: f64,
    yz: f64,
    zz: f64,
}

impl Sym3 {
    /// Adds `w·x·xᵀ`.
    fn add_outer(&mut self, x: DVec3, w: f64) {
        let wx = x * w;
        self.xx += wx.x * x.x;
        self.xy += wx.x * x.y;
        self.xz += wx.x * x.z;
        self.yy += wx.y * x.y;
        self.yz += wx.y * x.z;
        self.zz += wx.z * x.z;
    }

    /// The scatter about the mean `mean` of points whose weighted sum of `x·xᵀ` (about
    /// any origin, the mean's too) is `self` and whose weights total `total`:
    /// `self/total − mean·meanᵀ`.
    fn central(self, total: f64, mean: DVec3) -> Sym3 {
        Sym3 {
            xx: self.xx / total - mean.x * mean.x,
            xy: self.xy / total - mean.x * mean.y,
            xz: self.xz / total - mean.x * mean.z,
            yy: self.yy / total - mean.y * mean.y,
            yz: self.yz / total - mean.y * mean.z,
            zz: self.zz / total - mean.z * mean.z,
        }
    }

    fn to_rows(self) -> [[f64; 3]; 3] {
        [
            [self.xx, self.xy, self.xz],
            [self.xy, self.yy, self.yz],
            [self.xz, self.yz, self.zz],
        ]
    }
}
/// One local minimum of the SQPnP cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SqpnpMinimum {
    /// The pose: a proper rotation (orthonormal to within
    /// [`ROTATION_TOL`](super::ROTATION_TOL)) and finite numbers.
    pub pose: CvPose,
    /// The cost `Σ wᵢ·pᵢ.z²·|π(pᵢ) − mᵢ|²` at this pose (see the [module docs](self)), in
    /// the world's units squared times the weights' units. Zero for exact data.
    pub cost: f64,
    /// Root mean square of the (unweighted) reprojection error `|π(pᵢ) − mᵢ|` over the
    /// points in front of the camera, normalised image units (multiply by the focal
    /// length for pixels). Zero when no point is in front.
    pub rms: f64,
    /// How many points are not in front of the camera (depth ≤ 0) at this pose.
    pub behind: usize,
}

/// The outcome of [`sqpnp()`].
#[derive(Debug, Clone, PartialEq)]
pub struct SqpnpSolution {
    /// The minimum of least cost that puts the points in front of the camera: the answer.
    pub best: SqpnpMinimum,
    /// The other distinct minima found that also put the points in front, by increasing
    /// cost (possibly none). With three points (up to four exact poses) or a near-ambiguous
    /// planar target some can be as good as `best`; the caller can tell them apart with
    /// more points or a prior.
    pub alternatives: Vec<SqpnpMinimum>,
}

/// The globally best pose for the correspondences `world[i] ↔ observed[i]`, by SQPnP (see
/// the [module docs](self) for the cost and the search).
///
/// * `world[i]`: a world point.
/// * `observed[i]`: where it is seen, in normalised image coordinates `(x/z, y/z)` of
///   OpenCV's camera frame (for a pixel `(u, v)`: `((u − cx)/fx, (v − cy)/fy)`).
/// * `weights`: optional, one per correspondence, each finite and ≥ 0 (a zero weight leaves
///   the point out); `None` weighs all alike.
///
/// Planar and non-planar point sets are both handled.
///
/// # Errors
///
/// Each precondition is checked, never assumed:
/// * [`SolveError::LengthMismatch`] when `world` and `observed` differ in length;
///   [`SolveError::BadParameter`] when `weights` has another length, or a weight is negative
///   or not finite;
/// * [`SolveError::TooFewPoints`] with fewer than [`MIN_POINTS`] correspondences of
///   positive weight;
/// * [`SolveError::NonFinite`] when a coordinate is NaN or infinite;
/// * [`SolveError::Degenerate`]: [`Degeneracy::CoincidentPoints`] when the (weighted) world
///   points all coincide, [`Degeneracy::CollinearPoints`] when they lie on one line
///   (across it, within 1e-6 of their spread along it), [`Degeneracy::ParallelBearings`]
///   when all observations are one direction (spread below 1e-9);
/// * [`SolveError::NoPoseInFront`] when no minimum found puts the points in front of the
///   camera (inconsistent data).
///
/// Postconditions: every returned pose has a proper rotation and finite numbers, and puts
/// the weighted centroid of the world points, or at least half the points, in front of the
/// camera. For exact data from a non-degenerate configuration with a unique solution,
/// `best` is that pose to rounding.
pub fn sqpnp(
    world: &[DVec3],
    observed: &[DVec2],
    weights: Option<&[f64]>,
) -> Result<SqpnpSolution, SolveError> {
    check_pairs(world, observed)?;
    if let Some(w) = weights {
        if w.len() != world.len() {
            return Err(SolveError::BadParameter {
                what: "the number of weights",
                value: w.len() as f64,
            });
        }
        if let Some(&bad) = w.iter().find(|w| !(w.is_finite() && **w >= 0.0)) {
            return Err(SolveError::BadParameter {
                what: "a weight",
                value: bad,
            });
        }
    }
    let used = weights.map_or(world.len(), |w| w.iter().filter(|&&w| w > 0.0).count());
    if used < MIN_POINTS {
        return Err(SolveError::TooFewPoints {
            needed: MIN_POINTS,
            got: used,
        });
    }

    let frame = Normalisation::new(world, weights)?;
    let problem = Problem::new(world, observed, weights, frame)?;
    let (values, vectors) = symmetric_eigen(&problem.omega).ok_or(SolveError::DidNotConverge {
        iterations: MAX_QL_SWEEPS,
    })?;
    // Eigenvector k, scaled to the length of a rotation's entries.
    let start = |k: usize| -> Vec9 { vectors[k].map(|x| x * 3f64.sqrt()) };

    let mut search = Search {
        problem: &problem,
        minima: Vec::new(),
    };
    let largest = values[8].max(0.0);
    let nullity = values
        .iter()
        .take_while(|&&l| l < RANK_TOLERANCE * largest)
        .count();
    if nullity > 6 {
        // More than six free directions: the rotation is not pinned down (points on a line,
        // to within what the image spread can tell apart).
        return Err(SolveError::Degenerate(Degeneracy::CollinearPoints));
    }
    let starts = nullity.max(1);
    for k in 0..starts {
        let e = start(k);
        if orthogonality_squared(&e) < ORTHOGONAL_SQUARED {
            search.from(&scaled(&e, determinant(&e).signum()));
        } else {
            search.from(&e);
            search.from(&scaled(&e, -1.0));
        }
    }
    for (k, &value) in values.iter().enumerate().skip(starts) {
        if search.best_cost() <= 3.0 * value {
            break;
        }
        let e = start(k);
        search.from(&e);
        search.from(&scaled(&e, -1.0));
    }

    let mut minima = search.minima;
    minima.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    let mut out = minima
        .into_iter()
        .filter_map(|c| problem.report(&c, observed));
    let best = out.next().ok_or(SolveError::NoPoseInFront)?;
    Ok(SqpnpSolution {
        best,
        alternatives: out.collect(),
    })
}

/// The similarity that centres the world points on their weighted centroid and scales them
/// to unit RMS radius, and the weights' mean.
#[derive(Debug, Clone, Copy)]
struct Normalisation {
    centroid: DVec3,
    scale: f64,
    /// `1 / scale`.
    inverse_scale: f64,
    mean_weight: f64,
}

impl Normalisation {
    /// The frame of the points of positive weight (`weights`: `None` for all one), or
    /// [`SolveError::Degenerate`] when they coincide or lie on one line.
    fn new(world: &[DVec3], weights: Option<&[f64]>) -> Result<Normalisation, SolveError> {
        let weight = |i: usize| weights.map_or(1.0, |w| w[i]);
        // One pass of sums about the first point of positive weight (so that equal points
        // give exactly zero spread, and the sums stay on the scale of the spread), from
        // which the centroid and the scatter about it follow.
        let origin = (0..world.len())
            .find(|&i| weight(i) > 0.0)
            .map_or(DVec3::ZERO, |i| world[i]);
        let (mut total, mut first, mut second) = (0.0, DVec3::ZERO, Sym3::default());
        let mut magnitude = 0.0_f64;
        for (i, x) in world.iter().enumerate() {
            let w = weight(i);
            if w > 0.0 {
                let d = *x - origin;
                total += w;
                first += d * w;
                second.add_outer(d, w);
                magnitude = magnitude.max(x.abs().max_element());
            }
        }
        let mean = first / total;
        let centroid = origin + mean;
        let scatter = second.central(total, mean);
        let variance = scatter.xx + scatter.yy + scatter.zz;
        if !variance.is_finite() || !total.is_finite() {
            return Err(SolveError::NonFinite {
                what: "world points",
            });
        }
        if variance <= 0.0 || variance.sqrt() <= COINCIDENT * magnitude {
            return Err(SolveError::Degenerate(Degeneracy::CoincidentPoints));
        }
        let (spread, _) = symmetric_eigen(&scatter.to_rows()).ok_or(SolveError::NonFinite {
            what: "world points",
        })?;
        if spread[1] <= COLLINEAR_VARIANCE * spread[2] {
            return Err(SolveError::Degenerate(Degeneracy::CollinearPoints));
        }
        Ok(Normalisation {
            centroid,
            scale: variance.sqrt(),
            inverse_scale: 1.0 / variance.sqrt(),
            mean_weight: total / world.len() as f64,
        })
    }

    /// A world point in the normalised frame.
    fn apply(&self, x: DVec3) -> DVec3 {
        (x - self.centroid) * self.inverse_scale
    }
}

/// `Ω` and `P` of one problem, in the normalised frame, and the correspondences they came
/// from.
struct Problem<'a> {
    omega: Mat9,
    /// `t = P·r` (normalised frame), as three rows.
    p: [Vec9; 3],
    /// The world points, their weights (`None`: all one) and the normalised frame, for the
    /// cheirality test.
    world: &'a [DVec3],
    weights: Option<&'a [f64]>,
    frame: Normalisation,
}

/// One minimum in the normalised frame: the rotation's entries row by row, its cost, and
/// whether it puts the points in front of the camera.
struct Candidate {
    r: Vec9,
    cost: f64,
    in_front: bool,
}

impl<'a> Problem<'a> {
    fn new(
        world: &'a [DVec3],
        observed: &[DVec2],
        weights: Option<&'a [f64]>,
        frame: Normalisation,
    ) -> Result<Problem<'a>, SolveError> {
        let weight = |i: usize| weights.map_or(1.0, |w| w[i]);
        // With Qᵢ = wᵢ·BᵀB, B = [1 0 −u; 0 1 −v] (so |B·p|² = (x − u·z)² + (y − v·z)²), and
        // R·X = Aᵢ·r with Aᵢ = I₃ ⊗ Xᵀ: Aᵢᵀ·Qᵢ·Aᵢ = Qᵢ ⊗ X·Xᵀ and Qᵢ·Aᵢ = Qᵢ ⊗ Xᵀ. Qᵢ has
        // four distinct entries (1, −u, −v, u² + v², times wᵢ), so Σ Aᵢᵀ·Qᵢ·Aᵢ needs only
        // four weighted sums of X·Xᵀ and Σ Qᵢ·Aᵢ four of X, gathered in one pass.
        let mut xx = [Sym3::default(); 4];
        let mut xs = [DVec3::ZERO; 4];
        let mut q = [0.0; 4];
        // The observations' weighted sums about the first one of positive weight, for their
        // spread (equal observations give exactly zero).
        let image_origin = (0..observed.len())
            .find(|&i| weight(i) > 0.0)
            .map_or(DVec2::ZERO, |i| observed[i]);
        let (mut image_first, mut image_second) = (DVec2::ZERO, 0.0);
        let inverse_mean_weight = 1.0 / frame.mean_weight;
        for (i, (x, m)) in world.iter().zip(observed).enumerate() {
            let given = weight(i);
            if given == 0.0 {
                continue;
            }
            let d = *m - image_origin;
            image_first += d * given;
            image_second += d.length_squared() * given;
            let w = given * inverse_mean_weight;
            let x = frame.apply(*x);
            let f = [w, w * m.x, w * m.y, w * m.length_squared()];
            for k in 0..4 {
                xx[k].add_outer(x, f[k]);
                xs[k] += x * f[k];
                q[k] += f[k];
            }
        }
        // The given weights total q₀ times their mean.
        let image_total = q[0] * frame.mean_weight;
        let image_mean = image_first / image_total;
        let image_variance = image_second / image_total - image_mean.length_squared();
        if image_variance.is_nan() || image_variance <= IMAGE_SPREAD_MIN * IMAGE_SPREAD_MIN {
            return Err(SolveError::Degenerate(Degeneracy::ParallelBearings));
        }

        // Σ Aᵢᵀ·Qᵢ·Aᵢ: 3×3 blocks (j, k) = Σ (Qᵢ)ⱼₖ·X·Xᵀ.
        let [x0, xu, xv, xq] = xx.map(Sym3::to_rows);
        let mut omega = [[0.0; 9]; 9];
        for (j, k, block, sign) in [
            (0, 0, &x0, 1.0),
            (1, 1, &x0, 1.0),
            (2, 2, &xq, 1.0),
            (0, 2, &xu, -1.0),
            (2, 0, &xu, -1.0),
            (1, 2, &xv, -1.0),
            (2, 1, &xv, -1.0),
        ] {
            for a in 0..3 {
                for b in 0..3 {
                    omega[3 * j + a][3 * k + b] = sign * block[a][b];
                }
            }
        }
        // Σ Qᵢ·Aᵢ: row j, block k = Σ (Qᵢ)ⱼₖ·Xᵀ.
        let [s0, su, sv, sq] = xs;
        let z = DVec3::ZERO;
        let qa = [stack(s0, z, -su), stack(z, s0, -sv), stack(-su, -sv, sq)];
        let q_sum = [[q[0], 0.0, -q[1]], [0.0, q[0], -q[2]], [-q[1], -q[2], q[3]]];
        // t minimising Σ (Aᵢ·r + t)ᵀQᵢ(Aᵢ·r + t): t = −(ΣQᵢ)⁻¹·(ΣQᵢAᵢ)·r.
        let mut q_inv = [[0.0; 3]; 3];
        for (k, unit) in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
            .iter()
            .enumerate()
        {
            let column = solve_spd3(&q_sum, unit)
                .ok_or(SolveError::Degenerate(Degeneracy::ParallelBearings))?;
            for (row, c) in q_inv.iter_mut().zip(column) {
                row[k] = c;
            }
        }
        let p: [Vec9; 3] = std::array::from_fn(|j| {
            std::array::from_fn(|c| -(0..3).map(|k| q_inv[j][k] * qa[k][c]).sum::<f64>())
        });
        for (i, row) in omega.iter_mut().enumerate() {
            for (j, entry) in row.iter_mut().enumerate() {
                *entry += (0..3).map(|k| qa[k][i] * p[k][j]).sum::<f64>();
            }
        }
        // Exactly symmetric: the mean of each entry and its mirror.
        #[allow(clippy::needless_range_loop)] // two indices into one matrix
        for i in 0..9 {
            for j in 0..i {
                let mean = 0.5 * (omega[i][j] + omega[j][i]);
                omega[i][j] = mean;
                omega[j][i] = mean;
            }
        }
        if !omega.iter().flatten().all(|v| v.is_finite())
            || !p.iter().flatten().all(|v| v.is_finite())
        {
            return Err(SolveError::NonFinite {
                what: "observations",
            });
        }
        Ok(Problem {
            omega,
            p,
            world,
            weights,
            frame,
        })
    }

    fn cost(&self, r: &Vec9) -> f64 {
        quadratic(&self.omega, r).max(0.0)
    }

    /// `t = P·r` (normalised frame).
    fn translation(&self, r: &Vec9) -> DVec3 {
        let [x, y, z] = self.p.map(|row| dot(&row, r));
        DVec3::new(x, y, z)
    }

    /// The pose, cost and fit of a candidate in the caller's frame, or `None` when it does
    /// not put the points in front or is not a proper finite pose.
    fn report(&self, c: &Candidate, observed: &[DVec2]) -> Option<SqpnpMinimum> {
        let frame = &self.frame;
        let rotation = to_mat3(&c.r);
        // X = c + s·X̃: R·X + t' = s·(R·X̃ + t̃) when t' = s·t̃ − R·c.
        let translation = self.translation(&c.r) * frame.scale - rotation * frame.centroid;
        let pose = CvPose::new(rotation, translation);
        if !c.in_front {
            return None;
        }
        pose.validate().ok()?;
        let mut squared = 0.0;
        let mut seen = 0usize;
        for (x, m) in self.world.iter().zip(observed) {
            let p = pose.transform(*x);
            if p.z > 0.0 {
                let r = DVec2::new(p.x, p.y) * (1.0 / p.z) - *m;
                if r.is_finite() {
                    squared += r.length_squared();
                    seen += 1;
                }
            }
        }
        Some(SqpnpMinimum {
            pose,
            cost: c.cost * frame.mean_weight * frame.scale * frame.scale,
            rms: if seen == 0 {
                0.0
            } else {
                (squared / seen as f64).sqrt()
            },
            behind: self.world.len() - seen,
        })
    }

    /// Cheirality: whether the rotation `r` (with its best translation) puts the weighted
    /// centroid of the points (the normalised origin, at depth `t̃.z`) in front of the
    /// camera, or failing that, at least half the points.
    fn in_front(&self, r: &Vec9) -> bool {
        let t = self.translation(r);
        if t.z > 0.0 {
            return true;
        }
        let third = DVec3::new(r[6], r[7], r[8]);
        let (mut ahead, mut used) = (0usize, 0usize);
        for (i, x) in self.world.iter().enumerate() {
            if self.weights.is_some_and(|w| w[i] == 0.0) {
                continue;
            }
            used += 1;
            ahead += usize::from(third.dot(self.frame.apply(*x)) + t.z > 0.0);
        }
        2 * ahead >= used
    }
}

/// The SQP runs of one solve and the distinct minima they found.
struct Search<'a> {
    problem: &'a Problem<'a>,
    minima: Vec<Candidate>,
}

impl Search<'_> {
    /// The least cost so far among minima with the centroid in front (∞ when none).
    fn best_cost(&self) -> f64 {
        self.minima
            .iter()
            .filter(|c| c.in_front)
            .fold(f64::INFINITY, |m, c| m.min(c.cost))
    }

    /// Runs the SQP from the nearest rotation to `e` and records the minimum it reaches.
    fn from(&mut self, e: &Vec9) {
        let Some(r0) = nearest_rotation(&rows(e)) else {
            return;
        };
        let Some(r) = run_sqp(&self.problem.omega, flatten(&r0), &self.minima) else {
            return;
        };
        let r = match r {
            Reached::Known => return,
            Reached::New(r) => r,
        };
        let cost = self.problem.cost(&r);
        let in_front = self.problem.in_front(&r);
        if let Some(same) = self
            .minima
            .iter_mut()
            .find(|c| distance_squared(&c.r, &r) < SAME_ROTATION_SQUARED)
        {
            if cost < same.cost {
                *same = Candidate { r, cost, in_front };
            }
        } else {
            self.minima.push(Candidate { r, cost, in_front });
        }
    }
}

/// Where an SQP run ended.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Reached {
    /// A rotation that (locally) minimises `rᵀΩr`, its entries row by row.
    New(Vec9),
    /// On its way to a minimum already known (see [`run_sqp`]), so stopped.
    Known,
}

/// Sequential quadratic programming from the rotation `r0` to a rotation that (locally)
/// minimises `rᵀΩr`, finished by Newton steps on the rotations; `None` if the result is
/// not a finite matrix.
///
/// A run that comes within [`KNOWN_MINIMUM_SQUARED`] of a minimum in `known` (found by
/// an earlier run, polished) would end there: it stops, without the steps and the
/// polishing that would find that minimum again.
fn run_sqp(omega: &Mat9, r0: Vec9, known: &[Candidate]) -> Option<Reached> {
    let mut r = r0;
    for _ in 0..MAX_SQP_STEPS {
        let Some(delta) = sqp_step(omega, &r) else {
            break;
        };
        for (x, d) in r.iter_mut().zip(&delta) {
            *x += d;
        }
        if dot(&delta, &delta) <= STEP_SQUARED_TOLERANCE {
            break;
        }
        if known
            .iter()
            .any(|c| distance_squared(&c.r, &r) < KNOWN_MINIMUM_SQUARED)
        {
            return Some(Reached::Known);
        }
    }
    if determinant(&r) < 0.0 {
        r = scaled(&r, -1.0);
    }
    let rotation = orthonormalise(&rows(&r))?;
    Some(Reached::New(newton_polish(omega, rotation)))
}

/// One SQP step at `r`: `δ` minimising `(r + δ)ᵀΩ(r + δ)` subject to `h(r) + J(r)·δ = 0`
/// (`h`: the six entries of `R·Rᵀ − I` on and above the diagonal); `None` when `R` is
/// singular or the step is not finite.
///
/// The step is `δ = δₕ + D·y`: `δₕ = Jᵀ·(J·Jᵀ)⁻¹·(−h)`, the least step that satisfies the
/// linearised constraints, and `D·y` the best move along `J`'s null space, spanned by the
/// columns of `D`: `δR = [eₖ]×·cof(R)` (`cof(R) = det R · R⁻ᵀ`) keeps `R·Rᵀ` fixed to first
/// order, since `δR·Rᵀ = det R · [eₖ]×` is skew. `y` solves the 3×3 system
/// `(DᵀΩD)·y = −DᵀΩ(r + δₕ)`; the step does not depend on which basis of the null space
/// is used, so `D` need not be orthonormal (near a rotation it nearly is, up to √2).
fn sqp_step(omega: &Mat9, r: &Vec9) -> Option<Vec9> {
    let [a, b, c] = row_vectors(r);
    let (aa, bb, cc) = (a.dot(a), b.dot(b), c.dot(c));
    let (ab, ac, bc) = (a.dot(b), a.dot(c), b.dot(c));
    // The gradients of h's entries, as the columns of Jᵀ: (2a,0,0), (0,2b,0), (0,0,2c),
    // (b,a,0), (c,0,a), (0,c,b). J·Jᵀ is their Gram matrix, [[P, B], [Bᵀ, C]] in 3×3
    // blocks with P = 4·diag(|a|², |b|², |c|²); J·Jᵀ·l = −h is solved through the Schur
    // complement S = C − Bᵀ·P⁻¹·B (positive definite when J·Jᵀ is).
    let p_inv = [0.25 / aa, 0.25 / bb, 0.25 / cc];
    let b_block = [
        [2.0 * ab, 2.0 * ac, 0.0],
        [2.0 * ab, 0.0, 2.0 * bc],
        [0.0, 2.0 * ac, 2.0 * bc],
    ];
    let c_block = [[aa + bb, bc, ac], [bc, aa + cc, ab], [ac, ab, bb + cc]];
    let h_top = [1.0 - aa, 1.0 - bb, 1.0 - cc];
    let h_bottom = [-ab, -ac, -bc];
    let schur: [[f64; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            c_block[i][j]
                - (0..3)
                    .map(|k| b_block[k][i] * b_block[k][j] * p_inv[k])
                    .sum::<f64>()
        })
    });
    let rhs: [f64; 3] = std::array::from_fn(|i| {
        h_bottom[i]
            - (0..3)
                .map(|k| b_block[k][i] * h_top[k] * p_inv[k])
                .sum::<f64>()
    });
    let l_bottom = solve_spd3(&schur, &rhs)?;
    let l_top: [f64; 3] = std::array::from_fn(|k| {
        (h_top[k] - (0..3).map(|j| b_block[k][j] * l_bottom[j]).sum::<f64>()) * p_inv[k]
    });
    let l = [
        l_top[0],
        l_top[1],
        l_top[2],
        l_bottom[0],
        l_bottom[1],
        l_bottom[2],
    ];
    let da = a * (2.0 * l[0]) + b * l[3] + c * l[4];
    let db = b * (2.0 * l[1]) + a * l[3] + c * l[5];
    let dc = c * (2.0 * l[2]) + a * l[4] + b * l[5];
    let mut delta = stack(da, db, dc);

    // The rows of cof(R) are b×c, c×a, a×b.
    let d = tangent_basis([b.cross(c), c.cross(a), a.cross(b)]);
    let omega_d = omega_tangent(omega, &d);
    let mut ahead = *r;
    for (x, dx) in ahead.iter_mut().zip(&delta) {
        *x += dx;
    }
    let w = gram(&d, &omega_d);
    let rhs = [0, 1, 2].map(|k| -dot(&omega_d[k], &ahead));
    let y = solve_spd3(&w, &rhs).or_else(|| least_squares_3(&w, &rhs))?;
    for (k, dk) in d.iter().enumerate() {
        for (x, dx) in delta.iter_mut().zip(dk) {
            *x += y[k] * dx;
        }
    }
    delta.iter().all(|v| v.is_finite()).then_some(delta)
}

/// Newton steps on the rotation manifold from `rotation`, `R ← exp([ω]×)·R`, towards the
/// nearest minimum of `f(R) = rᵀΩr` (see the [module docs](self)); the rotation's entries
/// row by row.
///
/// With `Dₖ = [eₖ]×·R` (the derivative of `exp([ω]×)·R` in `ωₖ`) and `G = Ω·r` as a 3×3
/// matrix, `½∇f = Dᵀ·Ω·r` and `½∇²f = DᵀΩD + sym(M) − tr(M)·I` with `M = R·Gᵀ` (the
/// second derivative of `exp` contributes `½([eₖ]×[eₗ]× + [eₗ]×[eₖ]×) = sym(eₗ·eₖᵀ) − δₖₗ·I`).
/// A step is taken only when the Hessian is positive definite, the step at most
/// [`NEWTON_MAX_STEP`] and the cost not higher after it; the polishing ends after
/// [`MAX_NEWTON_STEPS`], or after a step short enough that what remains is below rounding.
fn newton_polish(omega: &Mat9, rotation: [[f64; 3]; 3]) -> Vec9 {
    let mut r = flatten(&rotation);
    // g = Ω·r, and the cost rᵀ·g.
    let mut g = multiply(omega, &r);
    let mut cost = dot(&g, &r);
    for _ in 0..MAX_NEWTON_STEPS {
        let d = tangent_basis(row_vectors(&r));
        let omega_d = omega_tangent(omega, &d);
        let dtod = gram(&d, &omega_d);
        let rr = rows(&r);
        let gg = rows(&g);
        let m: [[f64; 3]; 3] = std::array::from_fn(|a| {
            std::array::from_fn(|b| (0..3).map(|j| rr[a][j] * gg[b][j]).sum())
        });
        let trace = m[0][0] + m[1][1] + m[2][2];
        let hessian: [[f64; 3]; 3] = std::array::from_fn(|k| {
            std::array::from_fn(|l| {
                dtod[k][l] + 0.5 * (m[k][l] + m[l][k]) - if k == l { trace } else { 0.0 }
            })
        });
        let gradient = d.map(|dk| -dot(&dk, &g));
        let Some(step) = solve_spd3(&hessian, &gradient) else {
            break;
        };
        let omega_step = DVec3::from_array(step);
        let length2 = omega_step.length_squared();
        if length2.is_nan() || length2 > NEWTON_MAX_STEP * NEWTON_MAX_STEP {
            break;
        }
        let turned = DMat3::from_quat(DQuat::from_scaled_axis(omega_step)) * to_mat3(&r);
        let next = from_mat3(&turned);
        if length2 <= NEWTON_SQUARED_TOLERANCE {
            // A change of cost this small is below the rounding of its evaluation, so it
            // cannot be checked: the step is taken on the Hessian's word, and is the last.
            return next;
        }
        let next_g = multiply(omega, &next);
        let next_cost = dot(&next_g, &next);
        if next_cost.is_nan() || next_cost > cost {
            break;
        }
        (r, g, cost) = (next, next_g, next_cost);
    }
    r
}

/// The columns `[eₖ]×·C` (k = 0, 1, 2) for the 3×3 matrix `C` with rows `c`, as entries row
/// by row: `(0, −c₂, c₁)`, `(c₂, 0, −c₀)`, `(−c₁, c₀, 0)`.
fn tangent_basis(c: [DVec3; 3]) -> [Vec9; 3] {
    let z = DVec3::ZERO;
    [
        stack(z, -c[2], c[1]),
        stack(c[2], z, -c[0]),
        stack(-c[1], c[0], z),
    ]
}

/// `Ω·dₖ` for the three columns `d` of [`tangent_basis`], as [`multiply`] would give
/// them. Column `k` is zero in its block `k`, so the products take two thirds of the work
/// of three full ones.
fn omega_tangent(omega: &Mat9, d: &[Vec9; 3]) -> [Vec9; 3] {
    let mut out = [[0.0; 9]; 3];
    for (k, (o, dk)) in out.iter_mut().zip(d).enumerate() {
        for (j, (row, &s)) in omega.iter().zip(dk).enumerate() {
            if j / 3 != k {
                axpy(o, s, row);
            }
        }
    }
    out
}

/// The least-squares (minimum-norm) solution of the symmetric positive semi-definite 3×3
/// system `w·y = rhs`, eigenvalues below `1e-14` of the largest taken as zero; `None` if
/// the decomposition fails.
fn least_squares_3(w: &[[f64; 3]; 3], rhs: &[f64; 3]) -> Option<[f64; 3]> {
    let (values, vectors) = symmetric_eigen(w)?;
    let floor = 1e-14 * values.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let mut y = [0.0; 3];
    for (k, &value) in values.iter().enumerate() {
        if value.abs() <= floor {
            continue;
        }
        let along = (0..3).map(|i| vectors[k][i] * rhs[i]).sum::<f64>() / value;
        for (yi, vi) in y.iter_mut().zip(&vectors[k]) {
            *yi += along * vi;
        }
    }
    Some(y)
}

/// `Dᵀ·(Ω·D)` for the columns `d` of D and `omega_d` of Ω·D (symmetric: six products).
fn gram(d: &[Vec9; 3], omega_d: &[Vec9; 3]) -> [[f64; 3]; 3] {
    let (a, b, c) = (
        dot(&d[0], &omega_d[1]),
        dot(&d[0], &omega_d[2]),
        dot(&d[1], &omega_d[2]),
    );
    [
        [dot(&d[0], &omega_d[0]), a, b],
        [a, dot(&d[1], &omega_d[1]), c],
        [b, c, dot(&d[2], &omega_d[2])],
    ]
}

/// The nine entries of the matrix with rows `a`, `b`, `c`, row by row.
fn stack(a: DVec3, b: DVec3, c: DVec3) -> Vec9 {
    [a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z]
}

/// The entries of the matrix with rows `m`, row by row.
fn flatten(m: &[[f64; 3]; 3]) -> Vec9 {
    std::array::from_fn(|k| m[k / 3][k % 3])
}

/// The rows of the matrix with entries `r` row by row.
fn rows(r: &Vec9) -> [[f64; 3]; 3] {
    [[r[0], r[1], r[2]], [r[3], r[4], r[5]], [r[6], r[7], r[8]]]
}

fn row_vectors(r: &Vec9) -> [DVec3; 3] {
    rows(r).map(DVec3::from_array)
}

/// `Σ (E·Eᵀ − I)²` over the entries, for `E` with entries `e` row by row.
fn orthogonality_squared(e: &Vec9) -> f64 {
    let [a, b, c] = row_vectors(e);
    let diagonal = [a.dot(a), b.dot(b), c.dot(c)].map(|x| (x - 1.0) * (x - 1.0));
    let off = [a.dot(b), a.dot(c), b.dot(c)].map(|x| x * x);
    diagonal.iter().sum::<f64>() + 2.0 * off.iter().sum::<f64>()
}

/// The determinant of the 3×3 matrix with entries `e` row by row.
fn determinant(e: &Vec9) -> f64 {
    let [a, b, c] = row_vectors(e);
    a.dot(b.cross(c))
}

/// The glam matrix with entries `r` row by row.
fn to_mat3(r: &Vec9) -> DMat3 {
    DMat3::from_cols_array(&[r[0], r[3], r[6], r[1], r[4], r[7], r[2], r[5], r[8]])
}

/// The entries of a glam matrix, row by row.
fn from_mat3(m: &DMat3) -> Vec9 {
    let [a, b, c] = [m.row(0), m.row(1), m.row(2)];
    stack(a, b, c)
}

#[cfg(test)]
mod tests {
    use super::super::{Loss, RefineOptions, refine_pose};
    use super::*;

    use crate::vision::testing::Rng;

    const F: f64 = 800.0;

    /// The EPnP paper's set-up: a random camera rotation and translation, `n` points
    /// uniform in [-2,2]²×[4,8] in the camera frame, observed with `noise_px` Gaussian pixel
    /// noise at f = 800.
    fn scene(rng: &mut Rng, n: usize, noise_px: f64) -> (CvPose, Vec<DVec3>, Vec<DVec2>) {
        let rotation = rng.uniform_rotation();
        let truth = CvPose::new(rotation, rng.vector(-10.0, 10.0));
        let mut world = Vec::with_capacity(n);
        let mut observed = Vec::with_capacity(n);
        for _ in 0..n {
            let cam = DVec3::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(4.0, 8.0),
            );
            world.push(rotation.transpose() * (cam - truth.translation));
            observed.push(
                DVec2::new(cam.x / cam.z, cam.y / cam.z)
                    + DVec2::new(rng.normal(), rng.normal()) * (noise_px / F),
            );
        }
        (truth, world, observed)
    }

    /// `n` points uniform in the square [-2,2]² of the world plane z = 0, seen from 5–9 m
    /// away at 15°–65° from the plane's normal (from either side), looking at a point near
    /// the square's centre, with a random roll.
    fn planar_scene(rng: &mut Rng, n: usize, noise_px: f64) -> (CvPose, Vec<DVec3>, Vec<DVec2>) {
        let tilt = rng.range(15.0, 65.0).to_radians();
        let azimuth = rng.range(0.0, std::f64::consts::TAU);
        let side = if rng.range(0.0, 1.0) < 0.5 { 1.0 } else { -1.0 };
        let centre = DVec3::new(
            tilt.sin() * azimuth.cos(),
            tilt.sin() * azimuth.sin(),
            side * tilt.cos(),
        ) * rng.range(5.0, 9.0);
        let target = DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 0.0);
        let z = (target - centre).normalize();
        let x = z.any_orthonormal_vector();
        let roll = rng.range(0.0, std::f64::consts::TAU);
        let x = x * roll.cos() + z.cross(x) * roll.sin();
        let y = z.cross(x);
        let rotation = DMat3::from_cols(x, y, z).transpose();
        let truth = CvPose::new(rotation, -(rotation * centre));
        let mut world = Vec::with_capacity(n);
        let mut observed = Vec::with_capacity(n);
        for _ in 0..n {
            let point = DVec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 0.0);
            let cam = truth.transform(point);
            assert!(cam.z > 0.0);
            world.push(point);
            observed.push(
                DVec2::new(cam.x / cam.z, cam.y / cam.z)
                    + DVec2::new(rng.normal(), rng.normal()) * (noise_px / F),
            );
        }
        (truth, world, observed)
    }

    /// Rotation error (radians) and translation error (world units).
    fn errors(a: &CvPose, b: &CvPose) -> (f64, f64) {
        (
            a.rotation_angle_to(b),
            (a.translation - b.translation).length(),
        )
    }

    fn median(mut v: Vec<f64>) -> f64 {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    }

    #[test]
    fn sqpnp_recovers_exact_poses_of_random_point_sets() {
        let mut rng = Rng(11);
        for n in [4, 6, 10, 50, 200] {
            let mut worst = (0.0_f64, 0.0_f64);
            for trial in 0..100 {
                let (truth, world, observed) = scene(&mut rng, n, 0.0);
                let out = sqpnp(&world, &observed, None).unwrap();
                let (angle, shift) = errors(&out.best.pose, &truth);
                assert!(
                    angle < 1e-6 && shift < 1e-6,
                    "n = {n}, trial {trial}: {angle} rad, {shift} m; {out:?}"
                );
                assert!(out.best.rms < 1e-9, "n = {n}, trial {trial}: {out:?}");
                assert_eq!(out.best.behind, 0);
                assert!(out.best.pose.validate().is_ok());
                worst = (worst.0.max(angle), worst.1.max(shift));
            }
            eprintln!("n = {n}: worst {:e} rad, {:e} m", worst.0, worst.1);
        }
    }

    #[test]
    fn sqpnp_finds_the_true_pose_among_its_minima_for_three_points() {
        // Three points are consistent with up to four exact poses: the true one must be
        // among those returned, each of them exact.
        let mut rng = Rng(12);
        let mut found = 0;
        let trials = 100;
        for trial in 0..trials {
            let (truth, world, observed) = scene(&mut rng, 3, 0.0);
            let out = sqpnp(&world, &observed, None).unwrap();
            let all: Vec<&SqpnpMinimum> = std::iter::once(&out.best)
                .chain(&out.alternatives)
                .collect();
            for m in &all {
                assert!(m.pose.validate().is_ok());
            }
            let exact: Vec<_> = all.iter().filter(|m| m.rms < 1e-9).collect();
            assert!(!exact.is_empty(), "trial {trial}: {out:?}");
            if exact.iter().any(|m| {
                let (angle, shift) = errors(&m.pose, &truth);
                angle < 1e-6 && shift < 1e-6
            }) {
                found += 1;
            }
        }
        eprintln!("three points: true pose among the minima in {found} of {trials}");
        assert!(
            found >= 90,
            "true pose among the minima in {found} of {trials}"
        );
    }

    #[test]
    fn sqpnp_recovers_exact_poses_of_planar_targets() {
        let mut rng = Rng(13);
        for n in [4, 6, 10, 50] {
            for trial in 0..100 {
                let (truth, world, observed) = planar_scene(&mut rng, n, 0.0);
                let out = sqpnp(&world, &observed, None).unwrap();
                let (angle, shift) = errors(&out.best.pose, &truth);
                assert!(
                    angle < 1e-6 && shift < 1e-6,
                    "n = {n}, trial {trial}: {angle} rad, {shift} m; {out:?}"
                );
            }
        }
    }

    #[test]
    fn sqpnp_is_accurate_under_pixel_noise_and_close_to_the_reprojection_optimum() {
        let mut rng = Rng(14);
        let mut rotation_errors = Vec::new();
        let mut refined_errors = Vec::new();
        let mut moves = Vec::new();
        for trial in 0..100 {
            let (truth, world, observed) = scene(&mut rng, 50, 1.0);
            let out = sqpnp(&world, &observed, None).unwrap();
            let (angle, shift) = errors(&out.best.pose, &truth);
            let degrees = angle.to_degrees();
            assert!(degrees < 1.0, "trial {trial}: {degrees}°, {shift} m");
            rotation_errors.push(degrees);
            // 1 px on each axis: an RMS residual near √2 px.
            let rms_px = out.best.rms * F;
            assert!(rms_px > 1.0 && rms_px < 1.8, "trial {trial}: {rms_px} px");
            let refined = refine_pose(
                &out.best.pose,
                &world,
                &observed,
                &RefineOptions::new(Loss::Squared),
            )
            .unwrap();
            assert!(refined.converged, "trial {trial}: {refined:?}");
            let moved = out.best.pose.rotation_angle_to(&refined.pose).to_degrees();
            moves.push(moved);
            refined_errors.push(refined.pose.rotation_angle_to(&truth).to_degrees());
        }
        let median_error = median(rotation_errors);
        let median_refined = median(refined_errors);
        let median_move = median(moves.clone());
        let largest_move = moves.iter().copied().fold(0.0, f64::max);
        eprintln!(
            "n = 50, σ = 1 px: median rotation error {median_error}° (reprojection optimum: \
             {median_refined}°); refinement moved {median_move}° (median), {largest_move}° \
             (largest)"
        );
        // The bound of the brief (OpenCV's SQPnP: 0.03°–0.05°), and no worse than a quarter
        // above the reprojection (maximum likelihood) optimum on the same data.
        assert!(median_error < 0.1, "median rotation error {median_error}°");
        assert!(
            median_error < 1.25 * median_refined,
            "median {median_error}° against {median_refined}° for the reprojection optimum"
        );
        // The algebraic cost weighs each point by its squared depth (4–8 m here: a factor
        // of up to 4), so its optimum is not the reprojection optimum, but it is a small
        // fraction of the noise's own effect away.
        assert!(
            median_move < 0.04,
            "refinement moved {median_move}° (median)"
        );
        assert!(largest_move < 0.1, "refinement moved {largest_move}°");
    }

    #[test]
    fn sqp_runs_end_at_stationary_points_to_rounding() {
        // The SQP alone stops a little short of the minimum (|δ|² ≤ 1e-10 with linear
        // convergence); the Newton steps after it must leave no gradient beyond rounding at
        // the minimum the solve reports.
        let mut rng = Rng(21);
        for trial in 0..50 {
            let (_, world, observed) = scene(&mut rng, 30, 2.0);
            let frame = Normalisation::new(&world, None).unwrap();
            let problem = Problem::new(&world, &observed, None, frame).unwrap();
            let (values, vectors) = symmetric_eigen(&problem.omega).unwrap();
            let e = vectors[0].map(|x| x * 3f64.sqrt());
            // Of the two starts, the run that reaches the lower cost (a run from the other
            // may stop at its step limit far from any minimum).
            let r = [e, scaled(&e, -1.0)]
                .map(|start| {
                    let r0 = flatten(&nearest_rotation(&rows(&start)).unwrap());
                    match run_sqp(&problem.omega, r0, &[]).unwrap() {
                        Reached::New(r) => r,
                        Reached::Known => unreachable!("no minimum is known"),
                    }
                })
                .into_iter()
                .min_by(|a, b| problem.cost(a).total_cmp(&problem.cost(b)))
                .unwrap();
            {
                assert!(orthogonality_squared(&r) < 1e-28, "trial {trial}");
                // ½∇f in ω: Dᵀ·Ω·r with Dₖ = [eₖ]×·R.
                let g = multiply(&problem.omega, &r);
                let gradient = tangent_basis(row_vectors(&r)).map(|d| dot(&d, &g));
                let size = gradient.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
                assert!(
                    size < 1e-12 * values[8],
                    "trial {trial}: gradient {gradient:?}, largest eigenvalue {}",
                    values[8]
                );
            }
        }
    }

    #[test]
    fn runs_stopped_on_the_way_to_a_known_minimum_lose_no_minimum() {
        // Every eigenvector of Ω, both signs, as a start: once run to the end each (the
        // oracle) and once through a search that stops runs heading for a minimum it
        // already has. The search must find only minima the oracle finds, every one of
        // them that is a stationary point (a run can also end at its step limit), and
        // actually stop some runs early.
        let mut rng = Rng(33);
        let mut stopped = 0;
        for trial in 0..40 {
            let n = [4, 5, 6, 12][trial % 4];
            let (_, world, observed) = scene(&mut rng, n, 2.0);
            let frame = Normalisation::new(&world, None).unwrap();
            let problem = Problem::new(&world, &observed, None, frame).unwrap();
            let (values, vectors) = symmetric_eigen(&problem.omega).unwrap();
            let starts: Vec<Vec9> = vectors
                .iter()
                .flat_map(|v| [1.0, -1.0].map(|s| v.map(|x| x * s * 3f64.sqrt())))
                .filter_map(|e| nearest_rotation(&rows(&e)).map(|r| flatten(&r)))
                .collect();
            let oracle: Vec<Vec9> = starts
                .iter()
                .filter_map(|&r0| match run_sqp(&problem.omega, r0, &[])? {
                    Reached::New(r) => Some(r),
                    Reached::Known => None,
                })
                .collect();
            let mut search = Search {
                problem: &problem,
                minima: Vec::new(),
            };
            for &r0 in &starts {
                if matches!(
                    run_sqp(&problem.omega, r0, &search.minima),
                    Some(Reached::Known)
                ) {
                    stopped += 1;
                }
                search.from(&r0);
            }
            let close = |a: &Vec9, b: &Vec9| distance_squared(a, b) < 1e-12;
            for m in &search.minima {
                assert!(oracle.iter().any(|o| close(o, &m.r)), "trial {trial}");
            }
            let stationary = |r: &Vec9| {
                let g = multiply(&problem.omega, r);
                let gradient = tangent_basis(row_vectors(r)).map(|d| dot(&d, &g));
                gradient.iter().all(|x| x.abs() < 1e-10 * values[8])
            };
            for o in oracle.iter().filter(|o| stationary(o)) {
                assert!(
                    search.minima.iter().any(|m| close(&m.r, o)),
                    "trial {trial}: a minimum was lost"
                );
            }
        }
        assert!(stopped > 40, "only {stopped} runs stopped early");
    }

    #[test]
    fn sqpnp_does_not_fail_on_few_noisy_points() {
        // The issue's robustness goal: no rotation error above 5° for n ≥ 6 at σ = 2 px.
        let mut rng = Rng(20);
        for n in [6, 10] {
            let mut worst = 0.0_f64;
            for trial in 0..100 {
                let (truth, world, observed) = scene(&mut rng, n, 2.0);
                let out = sqpnp(&world, &observed, None).unwrap();
                let degrees = out.best.pose.rotation_angle_to(&truth).to_degrees();
                assert!(degrees < 5.0, "n = {n}, trial {trial}: {degrees}°");
                worst = worst.max(degrees);
            }
            eprintln!("n = {n}, σ = 2 px: worst rotation error {worst}°");
        }
    }

    #[test]
    fn sqpnp_handles_noisy_planar_targets() {
        let mut rng = Rng(15);
        let mut rotation_errors = Vec::new();
        for trial in 0..100 {
            let (truth, world, observed) = planar_scene(&mut rng, 50, 1.0);
            let out = sqpnp(&world, &observed, None).unwrap();
            let (angle, shift) = errors(&out.best.pose, &truth);
            let degrees = angle.to_degrees();
            assert!(degrees < 2.0, "trial {trial}: {degrees}°, {shift} m");
            rotation_errors.push(degrees);
        }
        let median_error = median(rotation_errors);
        eprintln!("planar n = 50, σ = 1 px: median rotation error {median_error}°");
        assert!(median_error < 0.3, "median rotation error {median_error}°");
    }

    #[test]
    fn weights_leave_points_out_and_pull_the_pose() {
        let mut rng = Rng(16);
        let (truth, world, mut observed) = scene(&mut rng, 20, 0.0);
        // Two gross outliers: weight zero makes the solve exact again.
        observed[0] += DVec2::new(0.2, -0.1);
        observed[1] += DVec2::new(-0.15, 0.1);
        let plain = sqpnp(&world, &observed, None).unwrap();
        let (plain_angle, _) = errors(&plain.best.pose, &truth);
        assert!(
            plain_angle > 1e-3,
            "outliers moved the pose only {plain_angle} rad"
        );
        let mut weights = vec![1.0; 20];
        weights[0] = 0.0;
        weights[1] = 0.0;
        let out = sqpnp(&world, &observed, Some(&weights)).unwrap();
        let (angle, shift) = errors(&out.best.pose, &truth);
        assert!(angle < 1e-6 && shift < 1e-6, "{angle} rad, {shift} m");
        // Uniform weights of any scale give the same pose as none, and a cost scaled alike.
        let doubled = sqpnp(&world, &observed, Some(&[2.0; 20])).unwrap();
        let (da, ds) = errors(&doubled.best.pose, &plain.best.pose);
        assert!(da < 1e-9 && ds < 1e-9);
        assert!((doubled.best.cost - 2.0 * plain.best.cost).abs() < 1e-9 * plain.best.cost);
    }

    #[test]
    fn sqpnp_does_not_depend_on_world_units_or_position() {
        let mut rng = Rng(17);
        let (truth, world, observed) = scene(&mut rng, 12, 0.5);
        let out = sqpnp(&world, &observed, None).unwrap();
        // The same scene 1000× larger and 1e5 units off the origin.
        let offset = DVec3::new(1e5, -2e5, 3e5);
        let far: Vec<DVec3> = world.iter().map(|x| *x * 1000.0 + offset).collect();
        let moved = sqpnp(&far, &observed, None).unwrap();
        let expected_t = out.best.pose.translation * 1000.0 - out.best.pose.rotation * offset;
        let da = moved.best.pose.rotation_angle_to(&out.best.pose);
        let dt = (moved.best.pose.translation - expected_t).length() / expected_t.length();
        assert!(da < 1e-9 && dt < 1e-9, "{da} rad, {dt} relative");
        assert!((moved.best.cost / out.best.cost - 1e6).abs() < 1e-3);
        assert!(errors(&out.best.pose, &truth).0.to_degrees() < 1.0);
    }

    #[test]
    fn sqpnp_refuses_bad_input() {
        let mut rng = Rng(18);
        let (_, world, observed) = scene(&mut rng, 10, 0.5);
        assert_eq!(
            sqpnp(&world[..2], &observed[..2], None),
            Err(SolveError::TooFewPoints { needed: 3, got: 2 })
        );
        assert_eq!(
            sqpnp(&[], &[], None),
            Err(SolveError::TooFewPoints { needed: 3, got: 0 })
        );
        assert_eq!(
            sqpnp(&world, &observed[..9], None),
            Err(SolveError::LengthMismatch {
                points: 10,
                observations: 9
            })
        );
        let mut nan_world = world.clone();
        nan_world[3].z = f64::NAN;
        assert!(matches!(
            sqpnp(&nan_world, &observed, None),
            Err(SolveError::NonFinite { .. })
        ));
        let mut nan_observed = observed.clone();
        nan_observed[0].y = f64::INFINITY;
        assert!(matches!(
            sqpnp(&world, &nan_observed, None),
            Err(SolveError::NonFinite { .. })
        ));
        // Weights: wrong count, negative, NaN, or too few positive.
        assert!(matches!(
            sqpnp(&world, &observed, Some(&[1.0; 9])),
            Err(SolveError::BadParameter { .. })
        ));
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            let mut w = vec![1.0; 10];
            w[4] = bad;
            assert!(matches!(
                sqpnp(&world, &observed, Some(&w)),
                Err(SolveError::BadParameter { .. })
            ));
        }
        let mut sparse = vec![0.0; 10];
        sparse[1] = 1.0;
        sparse[7] = 1.0;
        assert_eq!(
            sqpnp(&world, &observed, Some(&sparse)),
            Err(SolveError::TooFewPoints { needed: 3, got: 2 })
        );
    }

    #[test]
    fn sqpnp_refuses_degenerate_configurations() {
        let mut rng = Rng(19);
        let truth = CvPose::new(rng.uniform_rotation(), DVec3::new(0.3, -0.2, 6.0));
        let project = |x: DVec3| {
            let p = truth.transform(x);
            DVec2::new(p.x / p.z, p.y / p.z)
        };
        // All points on one line (noise-free and noisy observations alike).
        let base = DVec3::new(0.5, -0.3, 0.2);
        let direction = rng.unit_vector();
        let line: Vec<DVec3> = (0..12)
            .map(|_| base + direction * rng.range(-2.0, 2.0))
            .collect();
        let exact: Vec<DVec2> = line.iter().map(|x| project(*x)).collect();
        assert_eq!(
            sqpnp(&line, &exact, None),
            Err(SolveError::Degenerate(Degeneracy::CollinearPoints))
        );
        let noisy: Vec<DVec2> = exact
            .iter()
            .map(|m| *m + DVec2::new(rng.normal(), rng.normal()) / F)
            .collect();
        assert_eq!(
            sqpnp(&line, &noisy, None),
            Err(SolveError::Degenerate(Degeneracy::CollinearPoints))
        );
        // All points the same.
        let same = vec![base; 5];
        let seen = vec![project(base); 5];
        assert_eq!(
            sqpnp(&same, &seen, None),
            Err(SolveError::Degenerate(Degeneracy::CoincidentPoints))
        );
        // Well-spread points all seen in one direction.
        let (_, world, _) = scene(&mut rng, 8, 0.0);
        assert_eq!(
            sqpnp(&world, &[DVec2::new(0.1, 0.2); 8], None),
            Err(SolveError::Degenerate(Degeneracy::ParallelBearings))
        );
    }
}
