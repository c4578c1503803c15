//! Lambda Twist P3P: every camera pose that puts three known world points on three
//! viewing rays.
//!
//! After M. Persson and K. Nordberg, "Lambda Twist: An Accurate Fast Robust Perspective
//! Three Point (P3P) Solver", ECCV 2018. The unknowns are the depths λᵢ > 0 along the unit
//! bearings yᵢ, so that the camera points are `λᵢ·yᵢ`. Keeping the three pairwise distances
//! gives three quadrics
//!
//! ```text
//! λᵢ² − 2·bᵢⱼ·λᵢ·λⱼ + λⱼ² = aᵢⱼ,   bᵢⱼ = yᵢ·yⱼ,   aᵢⱼ = |Xᵢ − Xⱼ|²,
//! ```
//!
//! that is `Λᵀ·Mᵢⱼ·Λ = aᵢⱼ`. Eliminating the right-hand sides gives two homogeneous
//! quadrics `Λᵀ·D₁·Λ = 0`, `Λᵀ·D₂·Λ = 0` with `D₁ = a₂₃·M₁₂ − a₁₂·M₂₃`,
//! `D₂ = a₂₃·M₁₃ − a₁₃·M₂₃`. A real root γ of the cubic `det(D₁ + γ·D₂) = 0` makes
//! `D₀ = D₁ + γ·D₂` singular and indefinite, so its quadric is a pair of planes through the
//! origin, read off its eigen-decomposition (one eigenvalue is known to be zero). On each
//! plane the remaining quadric has at most two lines of solutions, and the distances fix
//! their scale: at most four poses. A few Gauss–Newton steps on the three quadrics polish
//! the depths, and the rotation follows in closed form from the two triangles.

use glam::{DMat3, DVec2, DVec3};

use super::{CvPose, Degeneracy, ROTATION_TOL, SolveError, orthonormality_error};

/// The most poses [`p3p`] returns.
pub const MAX_P3P_SOLUTIONS: usize = 4;

/// World points closer than this fraction of the largest pairwise distance are taken to
/// coincide; a triangle whose height is below this fraction of its longest side is taken to
/// be a line.
const WORLD_DEGENERATE: f64 = 1e-9;

/// Bearings at less than this angle (radians) apart are taken to be parallel.
const BEARINGS_PARALLEL: f64 = 1e-10;

/// Gauss–Newton steps on the depths, at most (the paper finds two are nearly always enough).
const REFINE_STEPS: usize = 5;

/// All poses that see three world points along three viewing directions.
///
/// * `bearings[i]`: the direction, in OpenCV's camera frame (x right, y down, z forward),
///   from the camera centre toward the point whose world position is `world[i]`. Any finite
///   non-zero length is accepted; each is normalised. For a pixel `(u, v)` with intrinsics
///   `fx, fy, cx, cy` it is `((u − cx)/fx, (v − cy)/fy, 1)`.
/// * `world[i]`: the world points.
///
/// Returns every real solution, at most [`MAX_P3P_SOLUTIONS`], as poses with
/// `x_cam = R·x_world + t` that put each world point at a positive depth along its bearing
/// (so `R·world[i] + t` is a positive multiple of `bearings[i]`). Each has a proper rotation
/// (orthonormal to within [`ROTATION_TOL`], determinant +1) and finite numbers; a candidate
/// that fails this is dropped, not returned. The list may be empty: three noisy bearings
/// need not be consistent with any pose. The order of the solutions is unspecified.
///
/// # Errors
///
/// * [`SolveError::NonFinite`] when any coordinate is NaN or infinite.
/// * [`SolveError::Degenerate`] with [`Degeneracy::ParallelBearings`] when a bearing is zero
///   or two point the same way (within 1e-10 rad), [`Degeneracy::CoincidentPoints`] when two world points coincide,
///   [`Degeneracy::CollinearPoints`] when the three lie on a line (see the tolerances
///   above: relative to the triangle's size, about 1e-9).
pub fn p3p(bearings: &[DVec3; 3], world: &[DVec3; 3]) -> Result<Vec<CvPose>, SolveError> {
    if bearings.iter().any(|b| !b.is_finite()) {
        return Err(SolveError::NonFinite { what: "bearings" });
    }
    if world.iter().any(|x| !x.is_finite()) {
        return Err(SolveError::NonFinite {
            what: "world points",
        });
    }
    let y = unit_bearings(bearings)?;
    check_triangle(world)?;

    let d12 = world[0] - world[1];
    let d13 = world[0] - world[2];
    let d23 = world[1] - world[2];
    let q = Quadrics {
        a12: d12.length_squared(),
        a13: d13.length_squared(),
        a23: d23.length_squared(),
        b12: y[0].dot(y[1]),
        b13: y[0].dot(y[2]),
        b23: y[1].dot(y[2]),
    };

    let mut depths: Vec<DVec3> = Vec::with_capacity(MAX_P3P_SOLUTIONS);
    for lambda in q.depth_candidates() {
        let lambda = q.refine(lambda);
        if !lambda.is_finite() || lambda.min_element() <= 0.0 {
            continue;
        }
        let duplicate = depths
            .iter()
            .any(|d| (*d - lambda).abs().max_element() <= 1e-9 * lambda.max_element());
        if !duplicate {
            depths.push(lambda);
        }
    }

    // R maps the world triangle's frame (two sides and their normal) onto the camera's.
    let world_frame = DMat3::from_cols(d12, d13, d12.cross(d13));
    let world_inverse = world_frame.inverse();
    if !world_inverse.is_finite() {
        return Err(SolveError::Degenerate(Degeneracy::CollinearPoints));
    }
    let world_centroid = (world[0] + world[1] + world[2]) / 3.0;
    let mut poses = Vec::with_capacity(depths.len());
    for lambda in depths {
        let cam = [lambda.x * y[0], lambda.y * y[1], lambda.z * y[2]];
        let v12 = cam[0] - cam[1];
        let v13 = cam[0] - cam[2];
        let rotation = DMat3::from_cols(v12, v13, v12.cross(v13)) * world_inverse;
        let cam_centroid = (cam[0] + cam[1] + cam[2]) / 3.0;
        let pose = CvPose::new(rotation, cam_centroid - rotation * world_centroid);
        if pose.rotation.is_finite()
            && pose.translation.is_finite()
            && orthonormality_error(pose.rotation) <= ROTATION_TOL
            && pose.rotation.determinant() > 0.0
        {
            poses.push(pose);
        }
    }
    Ok(poses)
}

/// The bearings scaled to unit length; refused if one is zero or two are parallel.
fn unit_bearings(bearings: &[DVec3; 3]) -> Result<[DVec3; 3], SolveError> {
    let mut y = [DVec3::ZERO; 3];
    for (unit, b) in y.iter_mut().zip(bearings) {
        // Scale first so that tiny or huge (finite) vectors normalise without under- or
        // overflow.
        let m = b.abs().max_element();
        if m == 0.0 {
            return Err(SolveError::Degenerate(Degeneracy::ParallelBearings));
        }
        *unit = (*b / m).normalize();
    }
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        if y[i].cross(y[j]).length() < BEARINGS_PARALLEL && y[i].dot(y[j]) > 0.0 {
            return Err(SolveError::Degenerate(Degeneracy::ParallelBearings));
        }
    }
    Ok(y)
}

/// Refuses three world points that coincide or lie on a line.
fn check_triangle(world: &[DVec3; 3]) -> Result<(), SolveError> {
    let sides = [
        world[1] - world[0],
        world[2] - world[0],
        world[2] - world[1],
    ];
    let lengths = sides.map(DVec3::length);
    let longest = lengths.iter().copied().fold(0.0_f64, f64::max);
    let shortest = lengths.iter().copied().fold(f64::INFINITY, f64::min);
    if !longest.is_finite() {
        return Err(SolveError::NonFinite {
            what: "world points",
        });
    }
    if shortest <= WORLD_DEGENERATE * longest {
        return Err(SolveError::Degenerate(Degeneracy::CoincidentPoints));
    }
    // Twice the area over the longest side is the smallest height.
    let height = sides[0].cross(sides[1]).length() / longest;
    if height.is_nan() || height <= WORLD_DEGENERATE * longest {
        return Err(SolveError::Degenerate(Degeneracy::CollinearPoints));
    }
    Ok(())
}

/// The squared world distances `aᵢⱼ` and bearing cosines `bᵢⱼ` of one problem.
struct Quadrics {
    a12: f64,
    a13: f64,
    a23: f64,
    b12: f64,
    b13: f64,
    b23: f64,
}

impl Quadrics {
    /// `Mᵢⱼ` with `Λᵀ·M₁₂·Λ = λ₁² − 2·b₁₂·λ₁·λ₂ + λ₂²` and so on.
    fn m12(&self) -> DMat3 {
        symmetric([1.0, 1.0, 0.0], [-self.b12, 0.0, 0.0])
    }

    fn m13(&self) -> DMat3 {
        symmetric([1.0, 0.0, 1.0], [0.0, -self.b13, 0.0])
    }

    fn m23(&self) -> DMat3 {
        symmetric([0.0, 1.0, 1.0], [0.0, 0.0, -self.b23])
    }

    /// Depth triples, every entry positive, that satisfy the three quadrics up to rounding
    /// (before refinement); at most four.
    fn depth_candidates(&self) -> Vec<DVec3> {
        let mut out = Vec::with_capacity(MAX_P3P_SOLUTIONS);
        let d1 = self.a23 * self.m12() - self.a12 * self.m23();
        let d2 = self.a23 * self.m13() - self.a13 * self.m23();
        let Some(d0) = singular_combination(d1, d2) else {
            return out;
        };
        let Some((e1, e2, s)) = split_into_planes(d0) else {
            return out;
        };
        // The sum of the three distance quadrics is positive definite for distinct
        // bearings (a sum of squared lengths): it fixes each line's scale.
        let sum = self.m12() + self.m13() + self.m23();
        let total = self.a12 + self.a13 + self.a23;
        let signs: &[f64] = if s == 0.0 { &[1.0] } else { &[1.0, -1.0] };
        for &sign in signs {
            let normal = e1 - sign * s * e2;
            let Some(basis) = plane_basis(normal) else {
                continue;
            };
            // On the plane D₁ and D₂ vanish together (D₀ does); use the better scaled.
            let f1 = restrict(d1, basis) / frobenius(d1);
            let f2 = restrict(d2, basis) / frobenius(d2);
            let form = if norm2(f1) >= norm2(f2) { f1 } else { f2 };
            for dir in null_directions(form) {
                let lambda = basis * dir;
                let k2 = total / lambda.dot(sum * lambda);
                if !(k2 > 0.0 && k2.is_finite()) {
                    continue;
                }
                let mut lambda = lambda * k2.sqrt();
                if lambda.element_sum() < 0.0 {
                    lambda = -lambda;
                }
                if lambda.min_element() > 0.0 {
                    out.push(lambda);
                }
            }
        }
        out
    }

    /// The three quadric residuals `Λᵀ·Mᵢⱼ·Λ − aᵢⱼ`.
    fn residuals(&self, l: DVec3) -> DVec3 {
        DVec3::new(
            l.x * l.x - 2.0 * self.b12 * l.x * l.y + l.y * l.y - self.a12,
            l.x * l.x - 2.0 * self.b13 * l.x * l.z + l.z * l.z - self.a13,
            l.y * l.y - 2.0 * self.b23 * l.y * l.z + l.z * l.z - self.a23,
        )
    }

    /// Gauss–Newton (here Newton: three equations, three unknowns) on the depths; a step
    /// is kept only if it lowers the residual, so the result is never worse than `l`.
    fn refine(&self, mut l: DVec3) -> DVec3 {
        let mut r = self.residuals(l);
        let mut size = r.abs().element_sum();
        for _ in 0..REFINE_STEPS {
            if size == 0.0 {
                break;
            }
            // Rows: gradients of the three residuals (halved; the step below doubles back).
            let jacobian = DMat3::from_cols(
                DVec3::new(l.x - self.b12 * l.y, l.x - self.b13 * l.z, 0.0),
                DVec3::new(l.y - self.b12 * l.x, 0.0, l.y - self.b23 * l.z),
                DVec3::new(0.0, l.z - self.b13 * l.x, l.z - self.b23 * l.y),
            );
            let det = jacobian.determinant();
            if det == 0.0 || !det.is_finite() {
                break;
            }
            let next = l - 0.5 * (jacobian.inverse() * r);
            let next_r = self.residuals(next);
            let next_size = next_r.abs().element_sum();
            if next_size.is_nan() || next_size >= size {
                break;
            }
            (l, r, size) = (next, next_r, next_size);
        }
        l
    }
}

/// The symmetric matrix with the given diagonal and off-diagonal `(m01, m02, m12)`.
fn symmetric(diagonal: [f64; 3], off: [f64; 3]) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(diagonal[0], off[0], off[1]),
        DVec3::new(off[0], diagonal[1], off[2]),
        DVec3::new(off[1], off[2], diagonal[2]),
    )
}

fn frobenius(m: DMat3) -> f64 {
    (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt()
}

/// `D₁ + γ·D₂` for the largest real root γ of `det(D₁ + γ·D₂)`, or `D₂` itself when the
/// cubic's leading coefficient `det D₂` vanishes (the root at infinity).
fn singular_combination(d1: DMat3, d2: DMat3) -> Option<DMat3> {
    // det(A + γB) = det A + γ·tr(adj(A)·B) + γ²·tr(A·adj(B)) + γ³·det B, with the rows of
    // adj(A) the cross products of A's columns.
    let mixed = |a: DMat3, b: DMat3| {
        a.y_axis.cross(a.z_axis).dot(b.x_axis)
            + a.z_axis.cross(a.x_axis).dot(b.y_axis)
            + a.x_axis.cross(a.y_axis).dot(b.z_axis)
    };
    let c3 = d2.determinant();
    let c2 = mixed(d2, d1);
    let c1 = mixed(d1, d2);
    let c0 = d1.determinant();
    let scale = c3.abs().max(c2.abs()).max(c1.abs()).max(c0.abs());
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    if c3.abs() <= 1e-14 * scale {
        return Some(d2);
    }
    let gamma = largest_cubic_root(c2 / c3, c1 / c3, c0 / c3);
    gamma.is_finite().then(|| d1 + gamma * d2)
}

/// The largest real root of `γ³ + p2·γ² + p1·γ + p0`, polished by Newton steps.
fn largest_cubic_root(p2: f64, p1: f64, p0: f64) -> f64 {
    // Depressed cubic x³ + p·x + q with γ = x − p2/3.
    let shift = p2 / 3.0;
    let p = p1 - p2 * shift;
    let q = 2.0 * shift * shift * shift - shift * p1 + p0;
    let discriminant = q * q / 4.0 + p * p * p / 27.0;
    let x = if discriminant > 0.0 {
        let root = discriminant.sqrt();
        (-q / 2.0 + root).cbrt() + (-q / 2.0 - root).cbrt()
    } else if p < 0.0 {
        let m = (-p / 3.0).sqrt();
        let cos3 = (-q / (2.0 * m * m * m)).clamp(-1.0, 1.0);
        2.0 * m * (cos3.acos() / 3.0).cos()
    } else {
        0.0
    };
    let mut gamma = x - shift;
    for _ in 0..2 {
        let f = ((gamma + p2) * gamma + p1) * gamma + p0;
        let df = (3.0 * gamma + 2.0 * p2) * gamma + p1;
        if df == 0.0 || !df.is_finite() {
            break;
        }
        let next = gamma - f / df;
        if next.is_finite() {
            gamma = next;
        }
    }
    gamma
}

/// For a symmetric, singular, indefinite `d0 = σ₁·e₁e₁ᵀ + σ₂·e₂e₂ᵀ` (|σ₁| ≥ |σ₂|), the
/// unit eigenvectors `e₁, e₂` and `s = √(−σ₂/σ₁)`: its quadric is the plane pair
/// `(e₁ ∓ s·e₂)·Λ = 0`. `None` when the quadric has no real plane (d0 definite on its
/// range) or the decomposition fails.
fn split_into_planes(d0: DMat3) -> Option<(DVec3, DVec3, f64)> {
    // With one eigenvalue zero the characteristic polynomial is σ·(σ² − tr·σ + p), p the
    // sum of the principal 2×2 minors.
    let [m00, m11, m22] = [d0.x_axis.x, d0.y_axis.y, d0.z_axis.z];
    let [m01, m02, m12] = [d0.y_axis.x, d0.z_axis.x, d0.z_axis.y];
    let trace = m00 + m11 + m22;
    let p = m00 * m11 - m01 * m01 + m00 * m22 - m02 * m02 + m11 * m22 - m12 * m12;
    let half = trace / 2.0;
    let root = (half * half - p).max(0.0).sqrt();
    let (mut s1, mut s2) = (half + root, half - root);
    if s1.abs() < s2.abs() {
        std::mem::swap(&mut s1, &mut s2);
    }
    if s1 == 0.0 || !s1.is_finite() {
        return None;
    }
    let ratio = -s2 / s1;
    let s = if ratio >= 0.0 {
        ratio.sqrt()
    } else if ratio > -1e-12 {
        0.0
    } else {
        return None;
    };
    let e1 = eigenvector(d0, s1)?;
    let e2 = if s == 0.0 {
        // Only e₁ matters for a double plane; any vector will do.
        DVec3::ZERO
    } else {
        eigenvector(d0, s2)?
    };
    Some((e1, e2, s))
}

/// A unit vector spanning the null space of `m − σ·I` (assumed rank 2): the longest cross
/// product of two of its rows.
fn eigenvector(m: DMat3, sigma: f64) -> Option<DVec3> {
    let a = m - sigma * DMat3::IDENTITY;
    // Symmetric: columns are rows.
    let (r0, r1, r2) = (a.x_axis, a.y_axis, a.z_axis);
    let candidates = [r0.cross(r1), r0.cross(r2), r1.cross(r2)];
    let best = candidates
        .into_iter()
        .max_by(|u, v| u.length_squared().total_cmp(&v.length_squared()))?;
    let n = best.length();
    (n > 0.0 && n.is_finite()).then(|| best / n)
}

/// Two independent vectors spanning the plane `normal·Λ = 0`, as the columns of a 3×3
/// matrix whose third column is zero: the coordinate with the largest normal component is
/// eliminated, so the basis is well conditioned.
fn plane_basis(normal: DVec3) -> Option<DMat3> {
    let k = normal.abs().max_position();
    let nk = normal[k];
    if nk == 0.0 || !nk.is_finite() {
        return None;
    }
    let (i, j) = match k {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let mut bi = DVec3::ZERO;
    bi[i] = 1.0;
    bi[k] = -normal[i] / nk;
    let mut bj = DVec3::ZERO;
    bj[j] = 1.0;
    bj[k] = -normal[j] / nk;
    Some(DMat3::from_cols(bi, bj, DVec3::ZERO))
}

/// The 2×2 form `Bᵀ·Q·B` (as `(f00, f01, f11)`) of `q` on the plane spanned by the first
/// two columns of `basis`.
fn restrict(q: DMat3, basis: DMat3) -> DVec3 {
    let (u, v) = (basis.x_axis, basis.y_axis);
    DVec3::new(u.dot(q * u), u.dot(q * v), v.dot(q * v))
}

fn norm2(f: DVec3) -> f64 {
    f.x * f.x + 2.0 * f.y * f.y + f.z * f.z
}

/// Directions `d` (as the first two coordinates of a 3-vector, third zero) with
/// `dᵀ·F·d = 0` for the symmetric 2×2 form `F = (f00, f01, f11)`: two for an indefinite
/// form, one for a (numerically) semidefinite singular one, none otherwise.
fn null_directions(f: DVec3) -> Vec<DVec3> {
    let (a, b, c) = (f.x, f.y, f.z);
    // Eigenvectors (cos θ, sin θ) and (−sin θ, cos θ) of [[a, b], [b, c]].
    let theta = 0.5 * (2.0 * b).atan2(a - c);
    let (sin, cos) = theta.sin_cos();
    let u = DVec2::new(cos, sin);
    let v = DVec2::new(-sin, cos);
    let mu_u = a * cos * cos + 2.0 * b * sin * cos + c * sin * sin;
    let mu_v = a * sin * sin - 2.0 * b * sin * cos + c * cos * cos;
    let (big, small, mu_big, mu_small) = if mu_u.abs() >= mu_v.abs() {
        (u, v, mu_u, mu_v)
    } else {
        (v, u, mu_v, mu_u)
    };
    if mu_big == 0.0 || !mu_big.is_finite() {
        return Vec::new();
    }
    let ratio = -mu_small / mu_big;
    let to3 = |d: DVec2| DVec3::new(d.x, d.y, 0.0);
    if ratio > 0.0 {
        let r = ratio.sqrt();
        vec![to3(small + r * big), to3(small - r * big)]
    } else if ratio > -1e-12 {
        vec![to3(small)]
    } else {
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::vision::testing::Rng;

    /// A random pose and three points in front of it (camera frame in [-2,2]²×[2,8]),
    /// returned as (pose, bearings, world points).
    fn random_problem(rng: &mut Rng) -> (CvPose, [DVec3; 3], [DVec3; 3]) {
        let pose = CvPose::new(rng.axis_angle_rotation(), rng.vector(-3.0, 3.0));
        let cam = [(); 3].map(|_| {
            DVec3::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(2.0, 8.0),
            )
        });
        let world = cam.map(|c| pose.rotation.transpose() * (c - pose.translation));
        // Bearings of arbitrary length: the solver normalises.
        let bearings = cam.map(|c| c / c.z);
        (pose, bearings, world)
    }

    fn bearing_error(pose: &CvPose, bearing: DVec3, world: DVec3) -> f64 {
        let p = pose.transform(world);
        (p.normalize() - bearing.normalize()).length()
    }

    #[test]
    fn p3p_recovers_random_poses() {
        let mut rng = Rng(7);
        let mut counts = [0usize; MAX_P3P_SOLUTIONS + 1];
        for trial in 0..500 {
            let (truth, bearings, world) = random_problem(&mut rng);
            let solutions = p3p(&bearings, &world).unwrap();
            assert!(solutions.len() <= MAX_P3P_SOLUTIONS);
            counts[solutions.len()] += 1;
            for s in &solutions {
                assert!(orthonormality_error(s.rotation) < 1e-9, "trial {trial}");
                assert!(s.rotation.determinant() > 0.0);
                for i in 0..3 {
                    let p = s.transform(world[i]);
                    assert!(p.dot(bearings[i]) > 0.0, "trial {trial}: point behind");
                    let e = bearing_error(s, bearings[i], world[i]);
                    assert!(e <= 1e-9, "trial {trial}: point {i} off by {e:e}");
                }
            }
            let best = solutions
                .iter()
                .map(|s| {
                    let angle = s.rotation_angle_to(&truth);
                    let shift = (s.translation - truth.translation).length();
                    (angle, shift)
                })
                .min_by(|a, b| (a.0 + a.1).total_cmp(&(b.0 + b.1)));
            let (angle, shift) = best.unwrap_or((f64::INFINITY, f64::INFINITY));
            assert!(
                angle < 1e-8 && shift < 1e-8,
                "trial {trial}: best solution off by {angle:e} rad, {shift:e}"
            );
        }
        // Random triples have one to four solutions; more than one is common.
        assert_eq!(counts[0], 0);
        assert!(counts[2] > 0 && counts[4] > 0, "{counts:?}");
    }

    #[test]
    fn p3p_handles_a_symmetric_triangle_seen_head_on() {
        // An equilateral triangle centred on the optical axis: symmetric, several
        // solutions; the true one must be among them.
        let world = [0.0_f64, 2.0, 4.0].map(|k| {
            let a = k * std::f64::consts::PI / 3.0;
            DVec3::new(a.cos(), a.sin(), 5.0)
        });
        let bearings = world;
        let solutions = p3p(&bearings, &world).unwrap();
        assert!(solutions.iter().any(|s| {
            s.rotation_angle_to(&CvPose::new(DMat3::IDENTITY, DVec3::ZERO)) < 1e-8
                && s.translation.length() < 1e-8
        }));
    }

    #[test]
    fn p3p_refuses_degenerate_input() {
        let mut rng = Rng(11);
        let (_, bearings, world) = random_problem(&mut rng);
        let collinear = [world[0], world[1], world[0] + 0.3 * (world[1] - world[0])];
        assert_eq!(
            p3p(&bearings, &collinear),
            Err(SolveError::Degenerate(Degeneracy::CollinearPoints))
        );
        let coincident = [world[0], world[1], world[1]];
        assert_eq!(
            p3p(&bearings, &coincident),
            Err(SolveError::Degenerate(Degeneracy::CoincidentPoints))
        );
        let all_same = [world[0]; 3];
        assert_eq!(
            p3p(&bearings, &all_same),
            Err(SolveError::Degenerate(Degeneracy::CoincidentPoints))
        );
        let mut nan_world = world;
        nan_world[2].y = f64::NAN;
        assert!(matches!(
            p3p(&bearings, &nan_world),
            Err(SolveError::NonFinite { .. })
        ));
        let mut inf_bearing = bearings;
        inf_bearing[0].x = f64::INFINITY;
        assert!(matches!(
            p3p(&inf_bearing, &world),
            Err(SolveError::NonFinite { .. })
        ));
        let mut zero_bearing = bearings;
        zero_bearing[1] = DVec3::ZERO;
        assert_eq!(
            p3p(&zero_bearing, &world),
            Err(SolveError::Degenerate(Degeneracy::ParallelBearings))
        );
        let parallel = [bearings[0], bearings[0] * 2.0, bearings[2]];
        assert_eq!(
            p3p(&parallel, &world),
            Err(SolveError::Degenerate(Degeneracy::ParallelBearings))
        );
    }

    #[test]
    fn p3p_poses_for_a_tiny_triangle_seen_wide_still_see_it_exactly() {
        // A 1 cm triangle seen from 4 mm away, its points 50°–60° apart: the true camera
        // is among the answers, and whatever comes back puts the points on their rays.
        let world = [DVec3::ZERO, DVec3::X * 0.01, DVec3::Y * 0.01];
        let truth = CvPose::new(DMat3::IDENTITY, -DVec3::new(0.003, 0.003, -0.004));
        let bearings = world.map(|p| truth.transform(p).normalize());
        let solutions = p3p(&bearings, &world).unwrap();
        assert!(!solutions.is_empty(), "the true camera fits");
        for s in &solutions {
            for i in 0..3 {
                assert!(bearing_error(s, bearings[i], world[i]) < 1e-9);
            }
        }
        let best = solutions
            .iter()
            .map(|s| {
                (
                    s.rotation_angle_to(&truth),
                    (s.center() - truth.center()).length(),
                )
            })
            .fold((f64::INFINITY, f64::INFINITY), |a, b| {
                if b.0 < a.0 { b } else { a }
            });
        assert!(best.0 < 1e-7 && best.1 < 1e-9, "{best:?}");
    }
}
