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
//! `E = rᵀ·Ω·r` with a 9×9 symmetric positive semi-definite `Ω` built once from the data.
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
//!    Writing `δ = H·x + N·y` with `H` an orthonormal basis of `J`'s row space and `N` of
//!    its null space, `x` restores orthonormality and `y` minimises the cost in the tangent
//!    space. The iteration stops when `|δ|² ≤ 1e-20` or after 15 steps, and the result is
//!    projected on the nearest rotation (after a sign flip if its determinant is
//!    negative).
//! 3. While the best cost so far exceeds `3·λ` for the next larger eigenvalue `λ`, a
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

use glam::{DMat3, DVec2, DVec3};
use nalgebra::{Matrix3, SMatrix, SVector, SymmetricEigen, Vector3, Vector6};

use super::{CvPose, Degeneracy, SolveError, check_pairs};

/// The fewest correspondences [`sqpnp()`] accepts (with positive weight).
pub const MIN_POINTS: usize = 3;

/// Eigenvalues of `Ω` below this fraction of the largest are taken as zero (its null space).
const RANK_TOLERANCE: f64 = 1e-7;

/// A null-space vector `√3·e` whose squared orthogonality error `Σ (e·eᵀ − I)²` is below
/// this is a rotation up to sign, and only that sign is tried.
const ORTHOGONAL_SQUARED: f64 = 1e-8;

/// The SQP stops when the step's squared length falls to this.
const STEP_SQUARED_TOLERANCE: f64 = 1e-20;

/// The most SQP steps from one start.
const MAX_SQP_STEPS: usize = 15;

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

type Vec9 = SVector<f64, 9>;
type Mat9 = SMatrix<f64, 9, 9>;
type Mat39 = SMatrix<f64, 3, 9>;

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
    let weight = |i: usize| weights.map_or(1.0, |w| w[i]);
    let used = (0..world.len()).filter(|&i| weight(i) > 0.0).count();
    if used < MIN_POINTS {
        return Err(SolveError::TooFewPoints {
            needed: MIN_POINTS,
            got: used,
        });
    }

    let frame = Normalisation::new(world, &weight)?;
    let problem = Problem::new(world, observed, &weight, &frame)?;

    let mut search = Search {
        problem: &problem,
        minima: Vec::new(),
    };
    let eigen = SymmetricEigen::new(problem.omega);
    let mut order: Vec<usize> = (0..9).collect();
    order.sort_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
    let largest = eigen.eigenvalues[order[8]].max(0.0);
    let nullity = order
        .iter()
        .take_while(|&&k| eigen.eigenvalues[k] < RANK_TOLERANCE * largest)
        .count();
    if nullity > 6 {
        // More than six free directions: the rotation is not pinned down (points on a line,
        // to within what the image spread can tell apart).
        return Err(SolveError::Degenerate(Degeneracy::CollinearPoints));
    }
    let starts = nullity.max(1);
    for &k in &order[..starts] {
        let e = eigen.eigenvectors.column(k) * 3f64.sqrt();
        if orthogonality_squared(&e) < ORTHOGONAL_SQUARED {
            let sign = determinant(&e).signum();
            search.from(&(e * sign));
        } else {
            search.from(&e);
            search.from(&-e);
        }
    }
    for &k in &order[starts..] {
        if search.best_cost() <= 3.0 * eigen.eigenvalues[k] {
            break;
        }
        let e = eigen.eigenvectors.column(k) * 3f64.sqrt();
        search.from(&e);
        search.from(&-e);
    }

    let mut minima = search.minima;
    minima.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    let mut out = minima
        .into_iter()
        .filter_map(|c| problem.report(&c, world, observed, &frame));
    let best = out.next().ok_or(SolveError::NoPoseInFront)?;
    Ok(SqpnpSolution {
        best,
        alternatives: out.collect(),
    })
}

/// The similarity that centres the world points on their weighted centroid and scales them
/// to unit RMS radius, and the weights' mean.
struct Normalisation {
    centroid: DVec3,
    scale: f64,
    mean_weight: f64,
}

impl Normalisation {
    fn new(world: &[DVec3], weight: &dyn Fn(usize) -> f64) -> Result<Normalisation, SolveError> {
        let total: f64 = (0..world.len()).map(weight).sum();
        let centroid = world
            .iter()
            .enumerate()
            .fold(DVec3::ZERO, |s, (i, x)| s + *x * weight(i))
            / total;
        let mut scatter = Matrix3::zeros();
        for (i, x) in world.iter().enumerate() {
            let d = *x - centroid;
            let d = Vector3::new(d.x, d.y, d.z);
            scatter += d * d.transpose() * (weight(i) / total);
        }
        let magnitude = world
            .iter()
            .enumerate()
            .filter(|&(i, _)| weight(i) > 0.0)
            .fold(0.0_f64, |m, (_, x)| m.max(x.abs().max_element()));
        let variance = scatter.trace();
        if !variance.is_finite() || !total.is_finite() {
            return Err(SolveError::NonFinite {
                what: "world points",
            });
        }
        if variance.sqrt() <= COINCIDENT * magnitude || variance == 0.0 {
            return Err(SolveError::Degenerate(Degeneracy::CoincidentPoints));
        }
        let mut spread: Vec<f64> = scatter.symmetric_eigenvalues().iter().copied().collect();
        spread.sort_by(f64::total_cmp);
        if spread[1] <= COLLINEAR_VARIANCE * spread[2] {
            return Err(SolveError::Degenerate(Degeneracy::CollinearPoints));
        }
        Ok(Normalisation {
            centroid,
            scale: variance.sqrt(),
            mean_weight: total / world.len() as f64,
        })
    }

    /// A world point in the normalised frame.
    fn apply(&self, x: DVec3) -> Vector3<f64> {
        let y = (x - self.centroid) / self.scale;
        Vector3::new(y.x, y.y, y.z)
    }
}

/// `Ω` and `P` of one problem, in the normalised frame.
struct Problem {
    omega: Mat9,
    /// `t = P·r` (normalised frame).
    p: Mat39,
    /// The world points of positive weight, normalised (for the cheirality test).
    points: Vec<Vector3<f64>>,
}

/// One minimum in the normalised frame: the rotation's entries row by row, its cost, and
/// whether it puts the points in front of the camera.
struct Candidate {
    r: Vec9,
    cost: f64,
    in_front: bool,
}

impl Problem {
    fn new(
        world: &[DVec3],
        observed: &[DVec2],
        weight: &dyn Fn(usize) -> f64,
        frame: &Normalisation,
    ) -> Result<Problem, SolveError> {
        let mut omega = Mat9::zeros();
        let mut qa = Mat39::zeros();
        let mut q_sum = Matrix3::zeros();
        let mut points = Vec::with_capacity(world.len());
        for (i, (x, m)) in world.iter().zip(observed).enumerate() {
            let w = weight(i) / frame.mean_weight;
            if w == 0.0 {
                continue;
            }
            // Qᵢ = wᵢ·BᵀB with B = [1 0 −u; 0 1 −v]: |B·p|² = (x − u·z)² + (y − v·z)².
            let (u, v) = (m.x, m.y);
            let q = Matrix3::new(1.0, 0.0, -u, 0.0, 1.0, -v, -u, -v, u * u + v * v) * w;
            // R·X = Aᵢ·r with Aᵢ = I₃ ⊗ Xᵀ, so Aᵢᵀ·Qᵢ·Aᵢ = Qᵢ ⊗ X·Xᵀ and Qᵢ·Aᵢ = Qᵢ ⊗ Xᵀ.
            let xn = frame.apply(*x);
            points.push(xn);
            let xx = xn * xn.transpose();
            for j in 0..3 {
                for k in 0..3 {
                    let mut block = omega.fixed_view_mut::<3, 3>(3 * j, 3 * k);
                    block += xx * q[(j, k)];
                    let mut row = qa.fixed_view_mut::<1, 3>(j, 3 * k);
                    row += xn.transpose() * q[(j, k)];
                }
            }
            q_sum += q;
        }
        // The weighted spread of the observations, from their mean (two passes, so that equal
        // observations give exactly zero).
        let weighted = || {
            observed
                .iter()
                .enumerate()
                .map(|(i, m)| (*m, weight(i)))
                .filter(|&(_, w)| w > 0.0)
        };
        let total: f64 = weighted().map(|(_, w)| w).sum();
        let image_mean = weighted().fold(DVec2::ZERO, |s, (m, w)| s + m * w) / total;
        let image_variance = weighted()
            .map(|(m, w)| (m - image_mean).length_squared() * w)
            .sum::<f64>()
            / total;
        if image_variance.is_nan() || image_variance <= IMAGE_SPREAD_MIN * IMAGE_SPREAD_MIN {
            return Err(SolveError::Degenerate(Degeneracy::ParallelBearings));
        }
        let Some(q_chol) = q_sum.cholesky() else {
            return Err(SolveError::Degenerate(Degeneracy::ParallelBearings));
        };
        // t minimising Σ (Aᵢ·r + t)ᵀQᵢ(Aᵢ·r + t): t = −(ΣQᵢ)⁻¹·(ΣQᵢAᵢ)·r.
        let p = -q_chol.solve(&qa);
        omega += qa.transpose() * p;
        let omega = (omega + omega.transpose()) * 0.5;
        if !omega.iter().all(|v| v.is_finite()) || !p.iter().all(|v| v.is_finite()) {
            return Err(SolveError::NonFinite {
                what: "observations",
            });
        }
        Ok(Problem { omega, p, points })
    }

    fn cost(&self, r: &Vec9) -> f64 {
        (self.omega * r).dot(r).max(0.0)
    }

    /// The pose, cost and fit of a candidate in the caller's frame, or `None` when it does
    /// not put the points in front or is not a proper finite pose.
    fn report(
        &self,
        c: &Candidate,
        world: &[DVec3],
        observed: &[DVec2],
        frame: &Normalisation,
    ) -> Option<SqpnpMinimum> {
        let rotation = to_mat3(&c.r);
        let t = self.p * c.r;
        // X = c + s·X̃: R·X + t' = s·(R·X̃ + t̃) when t' = s·t̃ − R·c.
        let translation = DVec3::new(t[0], t[1], t[2]) * frame.scale - rotation * frame.centroid;
        let pose = CvPose::new(rotation, translation);
        if !c.in_front {
            return None;
        }
        pose.validate().ok()?;
        let mut squared = 0.0;
        let mut seen = 0usize;
        for (x, m) in world.iter().zip(observed) {
            let p = pose.transform(*x);
            if p.z > 0.0 {
                let r = DVec2::new(p.x / p.z, p.y / p.z) - *m;
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
            behind: world.len() - seen,
        })
    }

    /// Cheirality: whether the rotation `r` (with its best translation) puts the weighted
    /// centroid of the points (the normalised origin, at depth `t̃.z`) in front of the
    /// camera, or failing that, at least half the points.
    fn in_front(&self, r: &Vec9) -> bool {
        let t = self.p * r;
        if t[2] > 0.0 {
            return true;
        }
        let third = Vector3::new(r[6], r[7], r[8]);
        let ahead = self
            .points
            .iter()
            .filter(|x| third.dot(x) + t[2] > 0.0)
            .count();
        2 * ahead >= self.points.len()
    }
}

/// The SQP runs of one solve and the distinct minima they found.
struct Search<'a> {
    problem: &'a Problem,
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
        let Some(r0) = nearest_rotation(e) else {
            return;
        };
        let Some(r) = run_sqp(&self.problem.omega, r0) else {
            return;
        };
        let cost = self.problem.cost(&r);
        let in_front = self.problem.in_front(&r);
        if let Some(same) = self
            .minima
            .iter_mut()
            .find(|c| (c.r - r).norm_squared() < SAME_ROTATION_SQUARED)
        {
            if cost < same.cost {
                *same = Candidate { r, cost, in_front };
            }
        } else {
            self.minima.push(Candidate { r, cost, in_front });
        }
    }
}

/// Sequential quadratic programming from the rotation `r0` to a rotation that (locally)
/// minimises `rᵀΩr`; `None` if the iteration breaks down (a singular iterate).
fn run_sqp(omega: &Mat9, r0: Vec9) -> Option<Vec9> {
    let mut r = r0;
    for _ in 0..MAX_SQP_STEPS {
        let Some(delta) = sqp_step(omega, &r) else {
            break;
        };
        r += delta;
        if delta.norm_squared() <= STEP_SQUARED_TOLERANCE {
            break;
        }
    }
    if determinant(&r) < 0.0 {
        r = -r;
    }
    nearest_rotation(&r)
}

/// One SQP step at `r`: `δ` minimising `(r + δ)ᵀΩ(r + δ)` subject to `h(r) + J(r)·δ = 0`.
fn sqp_step(omega: &Mat9, r: &Vec9) -> Option<Vec9> {
    let row = |i: usize| Vector3::new(r[3 * i], r[3 * i + 1], r[3 * i + 2]);
    let (a, b, c) = (row(0), row(1), row(2));
    let h = Vector6::new(
        a.dot(&a) - 1.0,
        b.dot(&b) - 1.0,
        c.dot(&c) - 1.0,
        a.dot(&b),
        a.dot(&c),
        b.dot(&c),
    );
    // Columns 0–5: the constraints' gradients (Jᵀ); columns 6–8: tangent directions
    // δR = [eₖ]×·R⁻ᵀ, which keep R·Rᵀ fixed to first order (δR·Rᵀ is skew), so they span
    // J's null space. A QR of the whole gives orthonormal bases of both.
    let mut m = Mat9::zeros();
    let mut put = |col: usize, block: usize, v: &Vector3<f64>| {
        m.fixed_view_mut::<3, 1>(3 * block, col).copy_from(v);
    };
    put(0, 0, &(a * 2.0));
    put(1, 1, &(b * 2.0));
    put(2, 2, &(c * 2.0));
    put(3, 0, &b);
    put(3, 1, &a);
    put(4, 0, &c);
    put(4, 2, &a);
    put(5, 1, &c);
    put(5, 2, &b);
    let rm = Matrix3::from_fn(|i, j| r[3 * i + j]);
    let inv_t = rm.try_inverse()?.transpose();
    for k in 0..3 {
        let d = Vector3::ith(k, 1.0).cross_matrix() * inv_t;
        for i in 0..3 {
            for j in 0..3 {
                m[(3 * i + j, 6 + k)] = d[(i, j)];
            }
        }
    }
    let qr = m.qr();
    let q = qr.q();
    let upper = qr.r();
    let range = q.fixed_columns::<6>(0);
    let null = q.fixed_columns::<3>(6);
    // J = R₆ᵀ·Hᵀ, so J·H·x = R₆ᵀ·x = −h.
    let x = upper
        .fixed_view::<6, 6>(0, 0)
        .transpose()
        .solve_lower_triangular(&(-h))?;
    let mut delta = range * x;
    let nt_omega = null.transpose() * omega;
    let w = nt_omega * null;
    let rhs = -(nt_omega * (r + delta));
    let y = match w.cholesky() {
        Some(ch) => ch.solve(&rhs),
        None => w.pseudo_inverse(1e-14 * w.norm()).ok()? * rhs,
    };
    delta += null * y;
    delta.iter().all(|v| v.is_finite()).then_some(delta)
}

/// The rotation nearest (in Frobenius norm) to the 3×3 matrix with entries `e` row by row,
/// as entries row by row; `None` if the SVD fails or `e` is not finite.
fn nearest_rotation(e: &Vec9) -> Option<Vec9> {
    if !e.iter().all(|v| v.is_finite()) {
        return None;
    }
    let m = Matrix3::from_fn(|i, j| e[3 * i + j]);
    let svd = m.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let sign = (u.determinant() * v_t.determinant()).signum();
    let r = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, sign)) * v_t;
    Some(Vec9::from_fn(|k, _| r[(k / 3, k % 3)]))
}

/// `Σ (E·Eᵀ − I)²` over the entries, for `E` with entries `e` row by row.
fn orthogonality_squared(e: &Vec9) -> f64 {
    let m = Matrix3::from_fn(|i, j| e[3 * i + j]);
    (m * m.transpose() - Matrix3::identity()).norm_squared()
}

/// The determinant of the 3×3 matrix with entries `e` row by row.
fn determinant(e: &Vec9) -> f64 {
    Matrix3::from_fn(|i, j| e[3 * i + j]).determinant()
}

/// The glam matrix with entries `r` row by row.
fn to_mat3(r: &Vec9) -> DMat3 {
    DMat3::from_cols_array(&[r[0], r[3], r[6], r[1], r[4], r[7], r[2], r[5], r[8]])
}

#[cfg(test)]
mod tests {
    use super::super::{Loss, RefineOptions, refine_pose};
    use super::*;

    use crate::solve::testing::Rng;

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
