//! The camera and its focal length together, from 2D–3D correspondences in pixels whose
//! principal point and pixel aspect are known (Baumgart's camera has one focal ratio; a
//! zoom lens or an uncalibrated camera needs it solved).
//!
//! # Method
//!
//! Pixels are moved to the principal point and the pixel aspect taken out: `q = (u − cx,
//! (v − cy)/a)` with `a = fy/fx`, so that `q = f·(x/z, y/z)` with one unknown `f = fx`.
//!
//! * **Hypotheses.** LO-RANSAC with adaptive stopping draws minimal sets:
//!   - when the world points are spread in three dimensions, six of them, and the
//!     direct linear transform (Hartley-normalised) gives the 3×4 projection `P ≃
//!     diag(f, f, 1)·[R | t]`, from which `f` is the mean length of the first two rows of
//!     its left 3×3 block over the third's, and `R` the nearest rotation to the rows;
//!   - when they lie on one plane (the smallest spread below [`PLANAR_RATIO`] of the
//!     largest), four of them, and the plane-to-image homography `H ≃ diag(f, f, 1)·[r₁ r₂
//!     t]`, from which `1/f²` is the least-squares root of the two constraints `r₁·r₂ = 0`
//!     and `|r₁| = |r₂|` (Zhang's, with the principal point known).
//!
//!   When there are at most 64 distinct minimal sets (six to eight
//!   points in space, up to seven on a plane), each is tried once instead.
//! * **Scoring** counts the correspondences within `threshold_px` in pixels.
//! * **Local optimisation** of every new best, and the final answer: Levenberg–Marquardt
//!   over the rotation (left-multiplied rotation-vector steps), the translation and
//!   `ln f`, with a Huber loss of scale `threshold_px`, on the consensus.
//! * **Observability.** The focal length is only determined when the points are seen
//!   with enough perspective: a plane seen face-on, or a small distant cluster, trades
//!   focal length for distance. From the Gauss–Newton covariance of `ln f` at the answer,
//!   with the residuals' noise taken as at least [`NOISE_FLOOR_PX`], the focal length's
//!   standard deviation is estimated; above [`MAX_FOCAL_SPREAD`] of the focal length the
//!   solve is refused ([`Degeneracy::FocalUnobservable`]) rather than answered with a
//!   focal length it cannot vouch for.

use glam::{DMat3, DVec2, DVec3};
use nalgebra::{DMatrix, Matrix3, SMatrix, SVector};

use super::pnp::{PnpOptions, PnpSolution, rotation_vector};
use super::sampler::{Sampler, next_subset, subsets_up_to};
use super::{CvPose, Degeneracy, MIN_CONSENSUS, SolveError, check_pairs};

/// When there are at most this many distinct minimal samples, each is tried once (in
/// order) instead of drawing samples at random: with six correspondences there is only
/// one, and random draws would repeat it up to `max_iterations` times.
const EXHAUSTIVE_SAMPLES: usize = 64;

/// World points whose smallest spread (singular value of the centred points) is below
/// this fraction of the largest are taken as planar.
pub const PLANAR_RATIO: f64 = 0.02;

/// The fewest correspondences a focal-length solve takes: six (a projection matrix)
/// when the points are not planar.
pub const MIN_POINTS_FOCAL: usize = 6;

/// The fewest correspondences on a plane: four (a homography).
pub const MIN_POINTS_FOCAL_PLANAR: usize = 4;

/// The largest standard deviation of the focal length, as a fraction of it, that an
/// answer may carry.
pub const MAX_FOCAL_SPREAD: f64 = 0.1;

/// The least reprojection noise, pixels, the observability test assumes (exact data
/// would otherwise pass any geometry).
pub const NOISE_FLOOR_PX: f64 = 0.5;

/// The most Levenberg–Marquardt iterations.
const MAX_LM_ITERATIONS: usize = 100;

/// A solved camera with its focal length.
#[derive(Debug, Clone, PartialEq)]
pub struct FocalSolution {
    /// The pose, inliers, RMS error (pixels) and iteration counts, as [`solve_pnp`]
    /// answers them.
    ///
    /// [`solve_pnp`]: super::solve_pnp
    pub solution: PnpSolution,
    /// The horizontal focal length, pixels.
    pub fx: f64,
    /// The vertical focal length, pixels (`fx` times the aspect given).
    pub fy: f64,
    /// The estimated standard deviation of `fx`, pixels.
    pub fx_std: f64,
}

/// A camera in the `q` frame: pose and focal length.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Model {
    pose: CvPose,
    f: f64,
}

/// The problem: world points, their `q`-frame observations and the pixel aspect.
struct Problem<'a> {
    world: &'a [DVec3],
    q: &'a [DVec2],
    aspect: f64,
}

impl Problem<'_> {
    /// The pixel error vector of correspondence `i` under `m`, or `None` behind the
    /// camera.
    fn residual(&self, m: &Model, i: usize) -> Option<DVec2> {
        let c = m.pose.transform(self.world[i]);
        if c.z <= 0.0 {
            return None;
        }
        let d = m.f * DVec2::new(c.x / c.z, c.y / c.z) - self.q[i];
        let r = DVec2::new(d.x, self.aspect * d.y);
        r.is_finite().then_some(r)
    }

    /// The indices within `threshold_px`.
    fn inliers(&self, m: &Model, threshold_px: f64) -> Vec<usize> {
        let t2 = threshold_px * threshold_px;
        (0..self.world.len())
            .filter(|&i| {
                self.residual(m, i)
                    .is_some_and(|r| r.length_squared() <= t2)
            })
            .collect()
    }

    /// Inlier count and the MSAC cost (errors capped at the threshold).
    fn score(&self, m: &Model, threshold_px: f64) -> (usize, f64) {
        let t2 = threshold_px * threshold_px;
        let mut count = 0;
        let mut cost = 0.0;
        for i in 0..self.world.len() {
            let e2 = self
                .residual(m, i)
                .map_or(f64::INFINITY, |r| r.length_squared());
            if e2 <= t2 {
                count += 1;
                cost += e2;
            } else {
                cost += t2;
            }
        }
        (count, cost)
    }
}

/// The camera that sees `world[i]` at pixel `pixels[i]`, with its focal length: the
/// principal point `principal` (pixels) and the pixel aspect `aspect = fy/fx` are known,
/// `fx` is not.
///
/// Preconditions, each refused with a typed error: equal lengths; finite numbers; a
/// positive aspect; at least [`MIN_POINTS_FOCAL`] correspondences (four when the world
/// points are planar) and at least `options.min_inliers`; a positive threshold.
///
/// Postconditions: the camera rests on at least `options.min_inliers` inliers within
/// `options.threshold_px`, its refinement converged, and the focal length is determined
/// to within [`MAX_FOCAL_SPREAD`]; otherwise an error ([`SolveError::NoConsensus`],
/// [`SolveError::Degenerate`] — collinear points, or [`Degeneracy::FocalUnobservable`] —
/// or [`SolveError::DidNotConverge`]), never a camera.
pub fn solve_pnp_focal(
    world: &[DVec3],
    pixels: &[DVec2],
    principal: DVec2,
    aspect: f64,
    options: &PnpOptions,
) -> Result<FocalSolution, SolveError> {
    check_pairs(world, pixels)?;
    if !principal.is_finite() {
        return Err(SolveError::NonFinite {
            what: "principal point",
        });
    }
    if !(aspect.is_finite() && aspect > 0.0) {
        return Err(SolveError::BadParameter {
            what: "the pixel aspect",
            value: aspect,
        });
    }
    let threshold = options.threshold_px;
    if !(threshold.is_finite() && threshold > 0.0) {
        return Err(SolveError::BadParameter {
            what: "the inlier threshold",
            value: threshold,
        });
    }
    if !(options.confidence > 0.0 && options.confidence < 1.0) {
        return Err(SolveError::BadParameter {
            what: "the confidence",
            value: options.confidence,
        });
    }
    let shape = Spread::of(world)?;
    let sample_size = if shape.planar() {
        MIN_POINTS_FOCAL_PLANAR
    } else {
        MIN_POINTS_FOCAL
    };
    let needed = sample_size.max(options.min_inliers).max(MIN_CONSENSUS);
    if world.len() < needed {
        return Err(SolveError::TooFewPoints {
            needed,
            got: world.len(),
        });
    }
    let q: Vec<DVec2> = pixels
        .iter()
        .map(|p| {
            let d = *p - principal;
            DVec2::new(d.x, d.y / aspect)
        })
        .collect();
    let problem = Problem {
        world,
        q: &q,
        aspect,
    };

    // LO-RANSAC; or, when there are few distinct samples, every one of them in turn.
    let n = world.len();
    let exhaustive = subsets_up_to(n, sample_size, EXHAUSTIVE_SAMPLES);
    let mut rng = Sampler::new(options.seed);
    let mut best: Option<(Model, usize, f64)> = None;
    let mut needed_iterations = exhaustive.unwrap_or(options.max_iterations);
    let mut iterations = 0;
    let mut sample: Vec<usize> = (0..sample_size).collect();
    while iterations < needed_iterations.min(options.max_iterations) {
        if exhaustive.is_none() {
            rng.distinct(n, &mut sample);
        } else if iterations > 0 && !next_subset(n, &mut sample) {
            break;
        }
        iterations += 1;
        let hypothesis = if shape.planar() {
            from_homography(&problem, &sample, &shape)
        } else {
            from_projection(&problem, &sample)
        };
        let Some(model) = hypothesis else { continue };
        let (count, cost) = problem.score(&model, threshold);
        let better = |b: &Option<(Model, usize, f64)>| {
            b.as_ref()
                .is_none_or(|&(_, c, k)| count > c || (count == c && cost < k))
        };
        if count < sample_size || !better(&best) {
            continue;
        }
        best = Some((model, count, cost));
        // Local optimisation on the consensus, kept when it scores better.
        let inliers = problem.inliers(&model, threshold);
        if let Some(refined) = refine(&problem, &model, &inliers, threshold)
            .ok()
            .map(|r| r.model)
        {
            let (c, k) = problem.score(&refined, threshold);
            if c > count || (c == count && k < cost) {
                best = Some((refined, c, k));
            }
        }
        if exhaustive.is_none() {
            let w = best.as_ref().map_or(0, |b| b.1) as f64 / n as f64;
            needed_iterations = iterations_needed(w, sample_size, options.confidence);
        }
    }
    let confident = iterations >= needed_iterations;
    let Some((model, count, _)) = best else {
        return Err(SolveError::NoConsensus {
            best_inliers: 0,
            needed,
        });
    };
    if count < needed {
        return Err(SolveError::NoConsensus {
            best_inliers: count,
            needed,
        });
    }

    // The final refinement on the consensus, then the inliers again.
    let consensus = problem.inliers(&model, threshold);
    let refined = refine(&problem, &model, &consensus, threshold)?;
    let model = refined.model;
    let inliers = problem.inliers(&model, threshold);
    if inliers.len() < needed {
        return Err(SolveError::NoConsensus {
            best_inliers: inliers.len(),
            needed,
        });
    }
    let sum2: f64 = inliers
        .iter()
        .filter_map(|&i| problem.residual(&model, i))
        .map(|r| r.length_squared())
        .sum();
    let rms_px = (sum2 / inliers.len() as f64).sqrt();
    // Unobservable first: along the valley of focal length against distance, the
    // refinement also wanders without converging, and this is the reason to give.
    let spread = focal_spread(&problem, &model, &inliers, rms_px)
        .ok_or(SolveError::Degenerate(Degeneracy::FocalUnobservable))?;
    if spread > MAX_FOCAL_SPREAD {
        return Err(SolveError::Degenerate(Degeneracy::FocalUnobservable));
    }
    if !refined.converged {
        return Err(SolveError::DidNotConverge {
            iterations: refined.iterations,
        });
    }
    let pose = model.pose;
    Ok(FocalSolution {
        solution: PnpSolution {
            rvec: rotation_vector(&pose.rotation),
            tvec: pose.translation,
            pose,
            rms_px,
            inliers,
            ransac_iterations: iterations,
            refine_iterations: refined.iterations,
            confident,
        },
        fx: model.f,
        fy: model.f * aspect,
        fx_std: model.f * spread,
    })
}

/// RANSAC's iterations for confidence `p` when a fraction `w` of the correspondences are
/// inliers and a sample takes `s`: `ln(1 − p) / ln(1 − wˢ)`.
fn iterations_needed(w: f64, s: usize, p: f64) -> usize {
    let ws = w.powi(s as i32);
    if ws >= 1.0 {
        return 1;
    }
    if ws <= 0.0 {
        return usize::MAX;
    }
    let k = (1.0 - p).ln() / (1.0 - ws).ln();
    if k.is_finite() {
        k.ceil().max(1.0) as usize
    } else {
        usize::MAX
    }
}

/// How the world points spread: their centroid and principal axes.
struct Spread {
    centroid: DVec3,
    /// Principal axes, largest spread first.
    axes: [DVec3; 3],
    /// Singular values of the centred points, largest first.
    sigma: [f64; 3],
}

impl Spread {
    /// The spread of `world`; refused when the points coincide or lie on a line.
    fn of(world: &[DVec3]) -> Result<Spread, SolveError> {
        if world.is_empty() {
            return Err(SolveError::TooFewPoints {
                needed: MIN_POINTS_FOCAL_PLANAR,
                got: 0,
            });
        }
        let centroid = world.iter().copied().sum::<DVec3>() / world.len() as f64;
        let mut s = Matrix3::<f64>::zeros();
        for p in world {
            let d = *p - centroid;
            let v = nalgebra::Vector3::new(d.x, d.y, d.z);
            s += v * v.transpose();
        }
        let eig = s.symmetric_eigen();
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let axis = |k: usize| {
            let c = eig.eigenvectors.column(order[k]);
            DVec3::new(c[0], c[1], c[2])
        };
        let sigma = order.map(|k| eig.eigenvalues[k].max(0.0).sqrt());
        if sigma[0].is_nan() || sigma[0] <= 0.0 || sigma[1] <= 1e-9 * sigma[0] {
            return Err(SolveError::Degenerate(if sigma[0] > 0.0 {
                Degeneracy::CollinearPoints
            } else {
                Degeneracy::CoincidentPoints
            }));
        }
        Ok(Spread {
            centroid,
            axes: [axis(0), axis(1), axis(2)],
            sigma,
        })
    }

    fn planar(&self) -> bool {
        self.sigma[2] < PLANAR_RATIO * self.sigma[0]
    }
}

/// The centroid of `points` and their mean distance from it (`length` measures a
/// difference), for Hartley's normalisation; `None` when the points coincide or a
/// coordinate is not finite.
fn centre_and_spread<T>(points: &[T], length: impl Fn(T) -> f64) -> Option<(T, f64)>
where
    T: Copy + std::iter::Sum + std::ops::Sub<Output = T> + std::ops::Div<f64, Output = T>,
{
    let n = points.len() as f64;
    let centre = points.iter().copied().sum::<T>() / n;
    let spread = points.iter().map(|&p| length(p - centre)).sum::<f64>() / n;
    (spread > 0.0).then_some((centre, spread))
}

/// The projection `P` (3×4, rows) of the sample by the direct linear transform, and the
/// camera it factors into; `None` for a degenerate sample or a camera that sees the
/// sample from behind.
fn from_projection(problem: &Problem<'_>, sample: &[usize]) -> Option<Model> {
    // Hartley normalisation of both sides.
    let w: Vec<DVec3> = sample.iter().map(|&i| problem.world[i]).collect();
    let q: Vec<DVec2> = sample.iter().map(|&i| problem.q[i]).collect();
    let (cw, sw) = centre_and_spread(&w, DVec3::length)?;
    let (cq, sq) = centre_and_spread(&q, DVec2::length)?;
    let (kw, kq) = (3f64.sqrt() / sw, 2f64.sqrt() / sq);
    let mut a = DMatrix::<f64>::zeros(2 * w.len(), 12);
    for (k, (p, m)) in w.iter().zip(&q).enumerate() {
        let x = (*p - cw) * kw;
        let xh = [x.x, x.y, x.z, 1.0];
        let u = (*m - cq) * kq;
        for j in 0..4 {
            a[(2 * k, j)] = xh[j];
            a[(2 * k, 8 + j)] = -u.x * xh[j];
            a[(2 * k + 1, 4 + j)] = xh[j];
            a[(2 * k + 1, 8 + j)] = -u.y * xh[j];
        }
    }
    let v = null_vector(a)?;
    // P = T_q⁻¹ · P̃ · T_w.
    let pn = SMatrix::<f64, 3, 4>::from_row_slice(v.as_slice());
    let tq_inv = Matrix3::new(1.0 / kq, 0.0, cq.x, 0.0, 1.0 / kq, cq.y, 0.0, 0.0, 1.0);
    let tw = SMatrix::<f64, 4, 4>::new(
        kw,
        0.0,
        0.0,
        -kw * cw.x,
        0.0,
        kw,
        0.0,
        -kw * cw.y,
        0.0,
        0.0,
        kw,
        -kw * cw.z,
        0.0,
        0.0,
        0.0,
        1.0,
    );
    let mut p = tq_inv * pn * tw;
    let m = p.fixed_view::<3, 3>(0, 0).into_owned();
    if m.determinant() < 0.0 {
        p = -p;
    }
    let row = |r: usize| DVec3::new(p[(r, 0)], p[(r, 1)], p[(r, 2)]);
    let s = row(2).length();
    if !s.is_finite() || s <= 0.0 {
        return None;
    }
    let (m1, m2, m3) = (row(0) / s, row(1) / s, row(2) / s);
    let (f1, f2) = (m1.length(), m2.length());
    let f = 0.5 * (f1 + f2);
    if !(f.is_finite() && f > 0.0) {
        return None;
    }
    let rotation = nearest_rotation(DMat3::from_cols(m1 / f1, m2 / f2, m3).transpose())?;
    let translation = DVec3::new(p[(0, 3)] / (s * f), p[(1, 3)] / (s * f), p[(2, 3)] / s);
    let model = Model {
        pose: CvPose::new(rotation, translation),
        f,
    };
    in_front(problem, sample, &model).then_some(model)
}

/// The plane-to-image homography of the sample and the camera it factors into (the
/// principal point is the `q` frame's origin); `None` for a degenerate sample, a sample
/// that does not fix the focal length, or a camera that sees it from behind.
fn from_homography(problem: &Problem<'_>, sample: &[usize], plane: &Spread) -> Option<Model> {
    let [e1, e2, _] = plane.axes;
    // A right-handed plane frame, so that world to plane is a rotation.
    let normal = e1.cross(e2);
    let on_plane = |p: DVec3| {
        let d = p - plane.centroid;
        DVec2::new(d.dot(e1), d.dot(e2))
    };
    let w: Vec<DVec2> = sample.iter().map(|&i| on_plane(problem.world[i])).collect();
    let q: Vec<DVec2> = sample.iter().map(|&i| problem.q[i]).collect();
    let (cw, sw) = centre_and_spread(&w, DVec2::length)?;
    let (cq, sq) = centre_and_spread(&q, DVec2::length)?;
    let (kw, kq) = (2f64.sqrt() / sw, 2f64.sqrt() / sq);
    let mut a = DMatrix::<f64>::zeros(2 * w.len(), 9);
    for (k, (p, m)) in w.iter().zip(&q).enumerate() {
        let x = (*p - cw) * kw;
        let xh = [x.x, x.y, 1.0];
        let u = (*m - cq) * kq;
        for j in 0..3 {
            a[(2 * k, j)] = xh[j];
            a[(2 * k, 6 + j)] = -u.x * xh[j];
            a[(2 * k + 1, 3 + j)] = xh[j];
            a[(2 * k + 1, 6 + j)] = -u.y * xh[j];
        }
    }
    let v = null_vector(a)?;
    let hn = Matrix3::from_row_slice(v.as_slice());
    let tq_inv = Matrix3::new(1.0 / kq, 0.0, cq.x, 0.0, 1.0 / kq, cq.y, 0.0, 0.0, 1.0);
    let tw = Matrix3::new(kw, 0.0, -kw * cw.x, 0.0, kw, -kw * cw.y, 0.0, 0.0, 1.0);
    let h = tq_inv * hn * tw;
    let col = |c: usize| DVec3::new(h[(0, c)], h[(1, c)], h[(2, c)]);
    let (h1, h2, h3) = (col(0), col(1), col(2));
    // 1/f² from r₁·r₂ = 0 and |r₁|² = |r₂|², least squares over the two.
    let (a1, b1) = (h1.x * h2.x + h1.y * h2.y, h1.z * h2.z);
    let (a2, b2) = (
        h1.x * h1.x + h1.y * h1.y - h2.x * h2.x - h2.y * h2.y,
        h1.z * h1.z - h2.z * h2.z,
    );
    let den = a1 * a1 + a2 * a2;
    if !den.is_finite() || den <= 0.0 {
        return None;
    }
    let inv_f2 = -(a1 * b1 + a2 * b2) / den;
    if !inv_f2.is_finite() || inv_f2 <= 0.0 {
        return None;
    }
    let f = inv_f2.sqrt().recip();
    let k_inv = |v: DVec3| DVec3::new(v.x / f, v.y / f, v.z);
    let (g1, g2, g3) = (k_inv(h1), k_inv(h2), k_inv(h3));
    let scale = 0.5 * (g1.length() + g2.length());
    if !(scale > 0.0 && f.is_finite()) {
        return None;
    }
    let sign = if g3.z < 0.0 { -1.0 } else { 1.0 };
    let (r1, r2, t) = (g1 * sign / scale, g2 * sign / scale, g3 * sign / scale);
    let r_plane = nearest_rotation(DMat3::from_cols(r1, r2, r1.cross(r2)))?;
    // World to plane coordinates: (e1·(p − c), e2·(p − c), n·(p − c)).
    let to_plane = DMat3::from_cols(e1, e2, normal).transpose();
    let rotation = r_plane * to_plane;
    let translation = t - rotation * plane.centroid;
    let model = Model {
        pose: CvPose::new(rotation, translation),
        f,
    };
    in_front(problem, sample, &model).then_some(model)
}

/// The unit vector `v` minimising `|A·v|` (the right singular vector of the least
/// singular value), or `None` when the decomposition fails.
fn null_vector(a: DMatrix<f64>) -> Option<nalgebra::DVector<f64>> {
    let cols = a.ncols();
    let ata = a.transpose() * a;
    let eig = ata.symmetric_eigen();
    let k = eig.eigenvalues.imin();
    let v = eig.eigenvectors.column(k).into_owned();
    (v.len() == cols && v.iter().all(|x| x.is_finite())).then_some(v)
}

/// The rotation nearest `m` (Frobenius), by SVD with the determinant's sign fixed; `None`
/// for a matrix with NaN or of rank below 2.
fn nearest_rotation(m: DMat3) -> Option<DMat3> {
    if !m.is_finite() {
        return None;
    }
    let a = Matrix3::from_column_slice(&m.to_cols_array());
    let svd = a.svd(true, true);
    let (u, vt) = (svd.u?, svd.v_t?);
    let mut r = u * vt;
    if r.determinant() < 0.0 {
        let mut d = Matrix3::identity();
        let k = svd.singular_values.imin();
        d[(k, k)] = -1.0;
        r = u * d * vt;
    }
    let out = DMat3::from_cols_slice(r.as_slice());
    out.is_finite().then_some(out)
}

/// Whether every sampled point is in front of the camera.
fn in_front(problem: &Problem<'_>, sample: &[usize], m: &Model) -> bool {
    sample
        .iter()
        .all(|&i| m.pose.transform(problem.world[i]).z > 0.0)
}

/// The outcome of [`refine`].
struct Refinement {
    model: Model,
    iterations: usize,
    converged: bool,
}

/// Seven parameters: rotation step, translation step, `ln f` step.
type Vec7 = SVector<f64, 7>;
type Mat7 = SMatrix<f64, 7, 7>;

/// The Jacobian rows (pixels per parameter) of correspondence `i`'s residual, with the
/// residual; `None` behind the camera.
fn jacobian(problem: &Problem<'_>, m: &Model, i: usize) -> Option<(DVec2, [Vec7; 2])> {
    let v = m.pose.rotation * problem.world[i];
    let c = v + m.pose.translation;
    if c.z <= 0.0 {
        return None;
    }
    let r = problem.residual(m, i)?;
    let (iz, f, a) = (1.0 / c.z, m.f, problem.aspect);
    // d(x/z, y/z)/dc, scaled to pixels.
    let du = DVec3::new(f * iz, 0.0, -f * c.x * iz * iz);
    let dv = DVec3::new(0.0, a * f * iz, -a * f * c.y * iz * iz);
    // c = exp([ω]×)·v + t, so dc/dω = −[v]×, and a gradient row dᵀ·(−[v]×) is (v × d)ᵀ.
    let row = |d: DVec3, df: f64| {
        let w = v.cross(d);
        Vec7::from_column_slice(&[w.x, w.y, w.z, d.x, d.y, d.z, df])
    };
    Some((r, [row(du, f * c.x * iz), row(dv, a * f * c.y * iz)]))
}

/// `m` moved by the step `d`.
fn step(m: &Model, d: &Vec7) -> Model {
    let w = DVec3::new(d[0], d[1], d[2]);
    let angle = w.length();
    let turn = if angle > 0.0 {
        DMat3::from_axis_angle(w / angle, angle)
    } else {
        DMat3::IDENTITY
    };
    Model {
        pose: CvPose::new(
            turn * m.pose.rotation,
            m.pose.translation + DVec3::new(d[3], d[4], d[5]),
        ),
        f: m.f * d[6].exp(),
    }
}

/// Huber weight and cost of a residual of length `e` with scale `k`.
fn huber(e: f64, k: f64) -> (f64, f64) {
    if e <= k {
        (1.0, e * e)
    } else {
        (k / e, 2.0 * k * e - k * k)
    }
}

/// The robust cost of `m` over `set`, infinite when a point is behind the camera.
fn cost(problem: &Problem<'_>, m: &Model, set: &[usize], k: f64) -> f64 {
    set.iter()
        .map(|&i| {
            problem
                .residual(m, i)
                .map_or(f64::INFINITY, |r| huber(r.length(), k).1)
        })
        .sum()
}

/// Levenberg–Marquardt from `start` over the correspondences `set`, Huber loss of scale
/// `k` pixels (iteratively reweighted). A step is kept only when it lowers the cost.
fn refine(
    problem: &Problem<'_>,
    start: &Model,
    set: &[usize],
    k: f64,
) -> Result<Refinement, SolveError> {
    if set.len() < MIN_POINTS_FOCAL_PLANAR {
        return Err(SolveError::TooFewPoints {
            needed: MIN_POINTS_FOCAL_PLANAR,
            got: set.len(),
        });
    }
    let mut m = *start;
    let mut current = cost(problem, &m, set, k);
    if !current.is_finite() {
        return Err(SolveError::NoPoseInFront);
    }
    let mut lambda = 1e-3;
    for iteration in 1..=MAX_LM_ITERATIONS {
        let mut jtj = Mat7::zeros();
        let mut jtr = Vec7::zeros();
        for &i in set {
            let Some((r, rows)) = jacobian(problem, &m, i) else {
                return Err(SolveError::NoPoseInFront);
            };
            let (w, _) = huber(r.length(), k);
            for (row, e) in rows.iter().zip([r.x, r.y]) {
                jtj += w * row * row.transpose();
                jtr += w * e * row;
            }
        }
        let mut improved = false;
        while lambda < 1e12 {
            let mut damped = jtj;
            for d in 0..7 {
                damped[(d, d)] += lambda * jtj[(d, d)].max(1e-12);
            }
            let Some(chol) = damped.cholesky() else {
                lambda *= 10.0;
                continue;
            };
            let delta = -chol.solve(&jtr);
            let next = step(&m, &delta);
            let c = cost(problem, &next, set, k);
            if c < current {
                let small = delta.norm() < 1e-12 || current - c <= 1e-14 * current;
                m = next;
                current = c;
                lambda = (lambda * 0.1).max(1e-12);
                improved = true;
                if small {
                    return Ok(Refinement {
                        model: m,
                        iterations: iteration,
                        converged: true,
                    });
                }
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            // No step lowers the cost: a minimum (to rounding).
            return Ok(Refinement {
                model: m,
                iterations: iteration,
                converged: true,
            });
        }
    }
    Ok(Refinement {
        model: m,
        iterations: MAX_LM_ITERATIONS,
        converged: false,
    })
}

/// The standard deviation of `ln f` (so, of `f` as a fraction of it) at `m` over the
/// inliers, from the Gauss–Newton covariance with the noise taken as the RMS error but at
/// least [`NOISE_FLOOR_PX`]; `None` when the normal matrix is singular.
fn focal_spread(problem: &Problem<'_>, m: &Model, inliers: &[usize], rms_px: f64) -> Option<f64> {
    let mut jtj = Mat7::zeros();
    for &i in inliers {
        let (_, rows) = jacobian(problem, m, i)?;
        for row in &rows {
            jtj += row * row.transpose();
        }
    }
    let cov = jtj.try_inverse()?;
    let sigma = rms_px.max(NOISE_FLOOR_PX);
    let var = cov[(6, 6)] * sigma * sigma;
    (var.is_finite() && var >= 0.0).then(|| var.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::testing::Rng;

    struct Scene {
        world: Vec<DVec3>,
        pixels: Vec<DVec2>,
        pose: CvPose,
        fx: f64,
        fy: f64,
        principal: DVec2,
    }

    /// The EPnP protocol's points ([-2,2]² × [4,8] in the camera), seen by a camera of
    /// focal length `fx`, aspect `aspect`, with pixel noise `sigma` and a fraction
    /// `outliers` of the pixels replaced by uniform ones.
    fn scene(rng: &mut Rng, n: usize, fx: f64, aspect: f64, sigma: f64, outliers: f64) -> Scene {
        let rotation = rng.uniform_rotation();
        let translation = rng.vector(-1.0, 1.0);
        let pose = CvPose::new(rotation, translation);
        let principal = DVec2::new(322.0, 237.5);
        let fy = fx * aspect;
        let mut world = Vec::new();
        let mut pixels = Vec::new();
        for _ in 0..n {
            let c = DVec3::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(4.0, 8.0),
            );
            world.push(rotation.transpose() * (c - translation));
            let px = principal + DVec2::new(fx * c.x / c.z, fy * c.y / c.z);
            pixels.push(px + sigma * DVec2::new(rng.normal(), rng.normal()));
        }
        for p in pixels.iter_mut().take((outliers * n as f64) as usize) {
            *p = DVec2::new(rng.range(0.0, 640.0), rng.range(0.0, 480.0));
        }
        Scene {
            world,
            pixels,
            pose,
            fx,
            fy,
            principal,
        }
    }

    /// A planar grid on the world's z = 0 plane, seen obliquely (tilted by `tilt`
    /// radians) from about 3 m.
    fn planar(rng: &mut Rng, fx: f64, tilt: f64, sigma: f64) -> Scene {
        let turn = DMat3::from_axis_angle(rng.unit_vector().with_z(0.0).normalize(), tilt);
        let rotation = turn * DMat3::from_rotation_z(rng.range(-3.0, 3.0));
        let translation = DVec3::new(rng.range(-0.2, 0.2), rng.range(-0.2, 0.2), 3.0);
        let pose = CvPose::new(rotation, translation);
        let principal = DVec2::new(320.0, 240.0);
        let mut world = Vec::new();
        let mut pixels = Vec::new();
        for i in 0..8 {
            for j in 0..6 {
                let p = DVec3::new(i as f64 * 0.2 - 0.7, j as f64 * 0.2 - 0.5, 0.0);
                let c = pose.transform(p);
                world.push(p);
                let px = principal + fx * DVec2::new(c.x / c.z, c.y / c.z);
                pixels.push(px + sigma * DVec2::new(rng.normal(), rng.normal()));
            }
        }
        Scene {
            world,
            pixels,
            pose,
            fx,
            fy: fx,
            principal,
        }
    }

    fn solve(s: &Scene, threshold_px: f64) -> Result<FocalSolution, SolveError> {
        let options = PnpOptions {
            threshold_px,
            ..PnpOptions::default()
        };
        solve_pnp_focal(&s.world, &s.pixels, s.principal, s.fy / s.fx, &options)
    }

    #[test]
    fn few_points_are_tried_as_every_minimal_set_once() {
        let mut rng = Rng(17);
        // Six exact points: one minimal set, one iteration, the true camera.
        let s = scene(&mut rng, 6, 800.0, 1.0, 0.0, 0.0);
        let out = solve(&s, 2.0).expect("a camera");
        assert_eq!(out.solution.ransac_iterations, 1);
        assert!(out.solution.confident);
        assert!((out.fx - 800.0).abs() < 1e-6 * 800.0, "{}", out.fx);
        // Eight points, one of them wrong: at most C(8, 6) = 28 sets, and the wrong one
        // is left out.
        let mut s = scene(&mut rng, 8, 800.0, 1.0, 0.0, 0.0);
        s.pixels[3] += DVec2::new(30.0, 20.0);
        let out = solve(&s, 2.0).expect("a camera");
        assert!(out.solution.ransac_iterations <= 28);
        assert_eq!(out.solution.inliers, [0, 1, 2, 4, 5, 6, 7]);
        assert!(out.solution.pose.rotation_angle_to(&s.pose) < 1e-6);
    }

    #[test]
    fn exact_correspondences_give_the_camera_and_its_focal_length() {
        let mut rng = Rng(1);
        for (k, fx) in [300.0, 800.0, 2500.0].iter().cycle().take(30).enumerate() {
            let aspect = if k % 2 == 0 { 1.0 } else { 1.1 };
            let s = scene(&mut rng, 6 + k * 3, *fx, aspect, 0.0, 0.0);
            let got = solve(&s, 1.0).unwrap_or_else(|e| panic!("{k}: {e}"));
            assert!((got.fx / s.fx - 1.0).abs() < 1e-7, "{k}: fx {}", got.fx);
            assert!((got.fy / s.fy - 1.0).abs() < 1e-7, "{k}: fy {}", got.fy);
            let p = &got.solution.pose;
            assert!(p.rotation_angle_to(&s.pose) < 1e-7, "{k}");
            assert!(p.translation.distance(s.pose.translation) < 1e-6, "{k}");
            assert_eq!(got.solution.inliers.len(), s.world.len());
            assert!(got.solution.rms_px < 1e-6);
        }
    }

    #[test]
    fn planar_points_seen_obliquely_give_the_focal_length() {
        let mut rng = Rng(2);
        for k in 0..10 {
            let s = planar(&mut rng, 700.0, 0.7, 0.0);
            let got = solve(&s, 1.0).unwrap_or_else(|e| panic!("{k}: {e}"));
            assert!((got.fx / 700.0 - 1.0).abs() < 1e-7, "{k}: {}", got.fx);
            assert!(got.solution.pose.rotation_angle_to(&s.pose) < 1e-7, "{k}");
            assert!(got.solution.pose.translation.distance(s.pose.translation) < 1e-6);
        }
        // With a pixel of noise, within a few percent.
        let mut errors = Vec::new();
        for k in 0..20 {
            let s = planar(&mut rng, 700.0, 0.7, 1.0);
            let got = solve(&s, 4.0).unwrap_or_else(|e| panic!("{k}: {e}"));
            errors.push((got.fx / 700.0 - 1.0).abs());
            assert!(got.fx_std > 0.0);
        }
        errors.sort_by(f64::total_cmp);
        assert!(errors[10] < 0.02, "median focal error {}", errors[10]);
    }

    #[test]
    fn noisy_correspondences_with_wrong_matches_give_a_close_focal_length() {
        let mut rng = Rng(3);
        let mut focal = Vec::new();
        let mut angle = Vec::new();
        for k in 0..20 {
            let s = scene(&mut rng, 100, 800.0, 1.0, 1.0, 0.4);
            let got = solve(&s, 4.0).unwrap_or_else(|e| panic!("{k}: {e}"));
            focal.push((got.fx / 800.0 - 1.0).abs());
            angle.push(got.solution.pose.rotation_angle_to(&s.pose).to_degrees());
            // The wrong matches are the first 40; few of them may fall near by chance.
            let wrong = got.solution.inliers.iter().filter(|&&i| i < 40).count();
            assert!(wrong <= 2, "{k}: {wrong} wrong matches kept");
            assert!(got.solution.inliers.len() >= 58, "{k}");
            // The stated spread covers the error most of the time: allow 4σ here.
            assert!(
                (got.fx - 800.0).abs() < 4.0 * got.fx_std.max(1.0),
                "{k}: fx {} ± {}",
                got.fx,
                got.fx_std
            );
        }
        focal.sort_by(f64::total_cmp);
        angle.sort_by(f64::total_cmp);
        assert!(focal[10] < 0.02, "median focal error {}", focal[10]);
        assert!(angle[10] < 0.3, "median rotation error {}°", angle[10]);
    }

    #[test]
    fn a_plane_seen_face_on_does_not_fix_the_focal_length() {
        let mut rng = Rng(4);
        let s = planar(&mut rng, 700.0, 0.0, 0.3);
        assert_eq!(
            solve(&s, 4.0),
            Err(SolveError::Degenerate(Degeneracy::FocalUnobservable))
        );
        // A distant small cluster: perspective too weak to tell focal length from depth.
        let mut s = scene(&mut rng, 50, 800.0, 1.0, 0.3, 0.0);
        let far = DVec3::new(0.0, 0.0, 400.0);
        let centre = s.pose.rotation.transpose() * (DVec3::new(0.0, 0.0, 6.0) - s.pose.translation);
        let shift = s.pose.rotation.transpose() * far;
        for (p, px) in s.world.iter_mut().zip(&mut s.pixels) {
            *p = centre + (*p - centre) * 0.01 + shift;
            let c = s.pose.transform(*p);
            *px = s.principal + 800.0 * DVec2::new(c.x / c.z, c.y / c.z);
        }
        assert_eq!(
            solve(&s, 4.0),
            Err(SolveError::Degenerate(Degeneracy::FocalUnobservable))
        );
    }

    #[test]
    fn bad_input_is_refused_with_typed_errors() {
        let mut rng = Rng(5);
        let s = scene(&mut rng, 20, 800.0, 1.0, 0.0, 0.0);
        let o = PnpOptions::default();
        let p = s.principal;
        assert!(matches!(
            solve_pnp_focal(&s.world[..5], &s.pixels[..5], p, 1.0, &o),
            Err(SolveError::TooFewPoints { needed: 6, got: 5 })
        ));
        assert!(matches!(
            solve_pnp_focal(&s.world, &s.pixels[..19], p, 1.0, &o),
            Err(SolveError::LengthMismatch { .. })
        ));
        assert!(matches!(
            solve_pnp_focal(&s.world, &s.pixels, p, 0.0, &o),
            Err(SolveError::BadParameter { .. })
        ));
        assert!(matches!(
            solve_pnp_focal(&s.world, &s.pixels, DVec2::new(f64::NAN, 0.0), 1.0, &o),
            Err(SolveError::NonFinite { .. })
        ));
        let mut nan = s.pixels.clone();
        nan[3].y = f64::INFINITY;
        assert!(matches!(
            solve_pnp_focal(&s.world, &nan, p, 1.0, &o),
            Err(SolveError::NonFinite { .. })
        ));
        let line: Vec<DVec3> = (0..10).map(|i| DVec3::splat(i as f64)).collect();
        assert_eq!(
            solve_pnp_focal(&line, &s.pixels[..10], p, 1.0, &o),
            Err(SolveError::Degenerate(Degeneracy::CollinearPoints))
        );
        // Pixels that no camera explains.
        let random: Vec<DVec2> = (0..20)
            .map(|_| DVec2::new(rng.range(0.0, 640.0), rng.range(0.0, 480.0)))
            .collect();
        assert!(matches!(
            solve_pnp_focal(&s.world, &random, p, 1.0, &o),
            Err(SolveError::NoConsensus { .. } | SolveError::Degenerate(_))
        ));
    }

    #[test]
    fn the_same_seed_gives_the_same_answer() {
        let mut rng = Rng(6);
        let s = scene(&mut rng, 60, 650.0, 1.0, 0.5, 0.3);
        assert_eq!(solve(&s, 3.0), solve(&s, 3.0));
    }
}
