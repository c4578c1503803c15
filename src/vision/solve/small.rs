//! Fixed-size dense linear algebra for the camera solution: symmetric eigen-decompositions
//! (3×3, 4×4, 9×9), symmetric positive definite 3×3 solves, the nearest rotation to a
//! 3×3 matrix and SQPnP's 9-vector algebra, on plain arrays, without allocation.
//!
//! Matrices are arrays of rows, `a[i][j]` the entry in row i and column j. These are the
//! inner loops of SQPnP (a 9×9 eigen-decomposition per solve, two nearest rotations and a
//! few 3×3 solves per SQP run); nalgebra's generic decompositions do the same work more
//! slowly at these sizes (its 3×3 SVD takes about twice as long as [`nearest_rotation`],
//! its 9×9 eigen-decomposition longer than [`symmetric_eigen`]).

/// Rounding unit of `f64`.
const EPS: f64 = f64::EPSILON;

/// QL sweeps allowed per eigenvalue before [`symmetric_eigen`] gives up (the usual number
/// is one or two).
pub(super) const MAX_QL_SWEEPS: usize = 60;

/// The eigen-decomposition of the symmetric matrix `a` (only symmetric input is meaningful:
/// the lower triangle and diagonal are read as given, the upper assumed to mirror them).
///
/// Returns the eigenvalues in ascending order and the matching orthonormal eigenvectors as
/// the *rows* of the second array (`v[j]`: the eigenvector of eigenvalue j), or `None` when
/// an entry is not finite or the iteration fails to converge (not seen for finite input).
///
/// Householder reduction to tridiagonal form followed by the implicit QL algorithm with
/// shifts (as EISPACK's `tred2` and `tql2`): backward stable, so each eigenvalue is exact
/// to within rounding of the largest, `|λ − λ̂| ≲ N·ε·max|λ|`.
pub(super) fn symmetric_eigen<const N: usize>(
    a: &[[f64; N]; N],
) -> Option<([f64; N], [[f64; N]; N])> {
    if N == 0 || a.iter().flatten().any(|x| !x.is_finite()) {
        return None;
    }
    // Scaled by a power of two to a largest entry near one (exactly undone below), so that
    // no square in the iteration overflows or underflows.
    let size = a.iter().flatten().fold(0.0_f64, |m, x| m.max(x.abs()));
    let scale = if size > 0.0 {
        2.0_f64.powi(-size.log2().round() as i32)
    } else {
        1.0
    };
    let mut v = a.map(|row| row.map(|x| x * scale));
    let mut d = [0.0; N];
    let mut e = [0.0; N];
    // The QL rotations combine pairs of columns of Q: as rows of Qᵀ they are contiguous.
    let mut vt = tridiagonalise(&mut v, &mut d, &mut e);
    ql_implicit(&mut vt, &mut d, &mut e)?;
    for x in d.iter_mut() {
        *x /= scale;
    }
    // Selection sort, ascending, keeping the vectors with their values.
    for i in 0..N.saturating_sub(1) {
        let mut k = i;
        for j in i + 1..N {
            if d[j] < d[k] {
                k = j;
            }
        }
        if k != i {
            d.swap(i, k);
            vt.swap(i, k);
        }
    }
    Some((d, vt))
}

/// Householder reduction of the symmetric `a` to tridiagonal form `T = Qᵀ·a·Q`: on return
/// `d` holds T's diagonal and `e[i]` (i ≥ 1) its subdiagonal entry `T[i][i−1]` (`e[0] = 0`);
/// the result is `Qᵀ` (whose rows are Q's columns). `a` is overwritten.
///
/// Each step `k` reflects row k's entries beyond the diagonal onto their first with
/// `H = I − β·v·vᵀ` and applies it on both sides as the rank-two update
/// `a ← a − v·wᵀ − w·vᵀ`, `w = p − (β/2)·(pᵀv)·v`, `p = β·a·v`. The loops run over whole
/// rows (`v` is zero where `H` does not act), which costs a few more multiplications than
/// the triangular loops of EISPACK's `tred2` but lets the compiler vectorise them.
fn tridiagonalise<const N: usize>(
    a: &mut [[f64; N]; N],
    d: &mut [f64; N],
    e: &mut [f64; N],
) -> [[f64; N]; N] {
    let mut qt = [[0.0; N]; N];
    for (i, row) in qt.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    *e = [0.0; N];
    for k in 0..N.saturating_sub(2) {
        let mut v = [0.0; N];
        v[k + 1..].copy_from_slice(&a[k][k + 1..]);
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let alpha = if v[k + 1] > 0.0 { -norm } else { norm };
        v[k + 1] -= alpha;
        let vv = v.iter().map(|x| x * x).sum::<f64>();
        e[k + 1] = alpha;
        if vv.is_nan() || vv <= 0.0 {
            // Already reduced: nothing to reflect.
            e[k + 1] = a[k][k + 1];
            continue;
        }
        let beta = 2.0 / vv;
        let p: [f64; N] = std::array::from_fn(|i| beta * dot(&a[i], &v));
        let half = 0.5 * beta * dot(&p, &v);
        let w: [f64; N] = std::array::from_fn(|i| p[i] - half * v[i]);
        for (i, row) in a.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x -= v[i] * w[j] + w[i] * v[j];
            }
        }
        // Qᵀ ← H·Qᵀ.
        let mut vq = [0.0; N];
        for (vi, row) in v.iter().zip(qt.iter()) {
            for (s, q) in vq.iter_mut().zip(row) {
                *s += vi * q;
            }
        }
        for (vi, row) in v.iter().zip(qt.iter_mut()) {
            for (q, s) in row.iter_mut().zip(&vq) {
                *q -= beta * vi * s;
            }
        }
    }
    if N >= 2 {
        e[N - 1] = a[N - 1][N - 2];
    }
    for (i, di) in d.iter_mut().enumerate() {
        *di = a[i][i];
    }
    qt
}

/// `a·b`.
pub(super) fn dot<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The implicit QL algorithm on the tridiagonal matrix (`d`, `e[1..]`) from
/// [`tridiagonalise`], accumulating the rotations into the rows of `vt` (the transpose of
/// its transformation); `None` if an eigenvalue needs more than [`MAX_QL_SWEEPS`] sweeps.
fn ql_implicit<const N: usize>(
    vt: &mut [[f64; N]; N],
    d: &mut [f64; N],
    e: &mut [f64; N],
) -> Option<()> {
    let n = N;
    for i in 1..n {
        e[i - 1] = e[i];
    }
    e[n - 1] = 0.0;
    let mut f = 0.0;
    let mut tst1 = 0.0_f64;
    for l in 0..n {
        tst1 = tst1.max(d[l].abs() + e[l].abs());
        let mut m = l;
        while m < n - 1 && e[m].abs() > EPS * tst1 {
            m += 1;
        }
        if m > l {
            let mut sweeps = 0;
            loop {
                sweeps += 1;
                if sweeps > MAX_QL_SWEEPS {
                    return None;
                }
                let g = d[l];
                let mut p = (d[l + 1] - g) / (2.0 * e[l]);
                let mut r = (p * p + 1.0).sqrt();
                if p < 0.0 {
                    r = -r;
                }
                d[l] = e[l] / (p + r);
                d[l + 1] = e[l] * (p + r);
                let dl1 = d[l + 1];
                let mut h = g - d[l];
                for di in d.iter_mut().skip(l + 2) {
                    *di -= h;
                }
                f += h;
                p = d[m];
                let (mut c, mut c2, mut c3) = (1.0, 1.0, 1.0);
                let el1 = e[l + 1];
                let (mut s, mut s2) = (0.0, 0.0);
                for i in (l..m).rev() {
                    c3 = c2;
                    c2 = c;
                    s2 = s;
                    let g = c * e[i];
                    h = c * p;
                    r = (p * p + e[i] * e[i]).sqrt();
                    e[i + 1] = s * r;
                    s = e[i] / r;
                    c = p / r;
                    p = c * d[i] - s * g;
                    d[i + 1] = h + s * (c * g + s * d[i]);
                    let (low, high) = vt.split_at_mut(i + 1);
                    let (x, y) = (&mut low[i], &mut high[0]);
                    for (xk, yk) in x.iter_mut().zip(y.iter_mut()) {
                        let h = *yk;
                        *yk = s * *xk + c * h;
                        *xk = c * *xk - s * h;
                    }
                }
                p = -s * s2 * c3 * el1 * e[l] / dl1;
                e[l] = s * p;
                d[l] = c * p;
                if e[l].abs() <= EPS * tst1 || e[l].is_nan() {
                    break;
                }
            }
        }
        d[l] += f;
        e[l] = 0.0;
    }
    d.iter().all(|x| x.is_finite()).then_some(())
}

/// The solution `x` of `a·x = b` for a symmetric positive definite 3×3 `a` (the upper
/// triangle is read), by its adjugate: `x = adj(a)·b / det a`. `None` unless `a` is
/// positive definite by Sylvester's criterion (its three leading principal minors above
/// zero) and the result finite. For the small, well-scaled systems of the SQP this is as
/// accurate as a factorisation and several times cheaper (one division, no square roots).
pub(super) fn solve_spd3(a: &[[f64; 3]; 3], b: &[f64; 3]) -> Option<[f64; 3]> {
    let [[a00, a01, a02], [_, a11, a12], [_, _, a22]] = *a;
    let c00 = a11 * a22 - a12 * a12;
    let c01 = a02 * a12 - a01 * a22;
    let c02 = a01 * a12 - a02 * a11;
    let c11 = a00 * a22 - a02 * a02;
    let c12 = a01 * a02 - a00 * a12;
    let c22 = a00 * a11 - a01 * a01;
    let det = a00 * c00 + a01 * c01 + a02 * c02;
    if !(a00 > 0.0 && c22 > 0.0 && det > 0.0) {
        return None;
    }
    let inv = 1.0 / det;
    let x = [
        (c00 * b[0] + c01 * b[1] + c02 * b[2]) * inv,
        (c01 * b[0] + c11 * b[1] + c12 * b[2]) * inv,
        (c02 * b[0] + c12 * b[1] + c22 * b[2]) * inv,
    ];
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The rotation (orthonormal, determinant +1) nearest to `m` in the Frobenius norm: the
/// `R` maximising `tr(Rᵀ·m)`, which is `U·diag(1, 1, det(U·Vᵀ))·Vᵀ` for the SVD
/// `m = U·Σ·Vᵀ`. `None` when an entry of `m` is not finite. When the nearest rotation is not
/// unique (`m` of rank one or less, or its two smallest singular values equal with
/// `det m < 0`) one of the nearest is returned.
///
/// `tr(R(q)ᵀ·m) = qᵀ·K·q` for the unit quaternion `q` of `R` and a symmetric, traceless 4×4
/// `K` built from `m` (Bar-Itzhack, "New method for extracting the quaternion from a
/// rotation matrix", J. Guidance 2000), so `R` is the rotation of `K`'s eigenvector of
/// largest eigenvalue. As in FOAM (Markley 1993; Lourakis and Terzakis's nearest-rotation
/// code for SQPnP), the eigenvalue is found by Newton's method on `K`'s characteristic
/// quartic from an upper bound (monotone: all roots are real and below the start), and the
/// eigenvector as a column of the adjugate of `K − λ·I`; when that column is too small to
/// be trusted (a repeated largest eigenvalue) the full eigen-decomposition of `K` is used.
/// The rotation built from a unit quaternion is orthonormal to rounding.
pub(super) fn nearest_rotation(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    if m.iter().flatten().any(|x| !x.is_finite()) {
        return None;
    }
    // Scaled to unit largest entry, so that K's entries are of order one.
    let size = m.iter().flatten().fold(0.0_f64, |s, x| s.max(x.abs()));
    if size == 0.0 {
        return Some([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    }
    let [[a, b, c], [d, e, f], [g, h, i]] = m.map(|row| row.map(|x| x / size));
    let k = [
        [a + e + i, h - f, c - g, d - b],
        [h - f, a - e - i, b + d, c + g],
        [c - g, b + d, e - a - i, f + h],
        [d - b, c + g, f + h, i - a - e],
    ];
    let q = largest_eigenvector_foam(&k).or_else(|| {
        let (_, vectors) = symmetric_eigen(&k)?;
        Some(vectors[3])
    })?;
    let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    let [w, x, y, z] = q.map(|c| c / norm);
    let r = [
        [
            w * w + x * x - y * y - z * z,
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            w * w - x * x + y * y - z * z,
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            w * w - x * x - y * y + z * z,
        ],
    ];
    r.iter().flatten().all(|v| v.is_finite()).then_some(r)
}

/// Newton steps on the characteristic quartic at most.
const FOAM_MAX_STEPS: usize = 50;

/// An adjugate column shorter than this (for `K`'s entries of order one) is not trusted.
const FOAM_MIN_ADJUGATE: f64 = 1e-6;

/// The eigenvector (not normalised) of the largest eigenvalue of the symmetric, traceless
/// 4×4 `k`, or `None` when it cannot be told reliably this way (see [`nearest_rotation`]).
fn largest_eigenvector_foam(k: &[[f64; 4]; 4]) -> Option<[f64; 4]> {
    // det(λ·I − K) = λ⁴ + c₂·λ² + c₁·λ + c₀ for traceless K: c₂ = −tr(K²)/2,
    // c₁ = −tr(K³)/3, c₀ = det K.
    let k2: [[f64; 4]; 4] =
        std::array::from_fn(|i| std::array::from_fn(|j| (0..4).map(|l| k[i][l] * k[l][j]).sum()));
    let tr2: f64 = (0..4).map(|i| k2[i][i]).sum();
    let tr3: f64 = (0..4)
        .map(|i| (0..4).map(|j| k2[i][j] * k[j][i]).sum::<f64>())
        .sum();
    let (c2, c1) = (-0.5 * tr2, -tr3 / 3.0);
    let c0 = (0..4)
        .map(|j| {
            let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
            sign * k[0][j] * minor(k, 0, j)
        })
        .sum::<f64>();
    // The largest eigenvalue, σ₁ + σ₂ ± σ₃ for m's singular values, is at most
    // √3·|m| = √(¾·tr(K²)) (tr(K²) = 4·|m|²).
    let mut lambda = (0.75 * tr2).sqrt();
    for _ in 0..FOAM_MAX_STEPS {
        let p = ((lambda * lambda + c2) * lambda + c1) * lambda + c0;
        let slope = (4.0 * lambda * lambda + 2.0 * c2) * lambda + c1;
        if slope.is_nan() || slope <= 0.0 {
            break;
        }
        let step = p / slope;
        lambda -= step;
        if step.abs() <= 4.0 * f64::EPSILON * lambda.abs().max(1.0) {
            break;
        }
    }
    let a: [[f64; 4]; 4] = std::array::from_fn(|i| {
        std::array::from_fn(|j| k[i][j] - if i == j { lambda } else { 0.0 })
    });
    // adj(A) = Π(λ − λⱼ)·q·qᵀ over the other eigenvalues: its largest diagonal entry picks
    // the best-conditioned column.
    let (best, diagonal) = (0..4)
        .map(|i| (i, minor(&a, i, i)))
        .max_by(|x, y| x.1.abs().total_cmp(&y.1.abs()))?;
    if diagonal.is_nan() || diagonal.abs() <= FOAM_MIN_ADJUGATE {
        return None;
    }
    let q: [f64; 4] = std::array::from_fn(|j| {
        let sign = if (best + j) % 2 == 0 { 1.0 } else { -1.0 };
        sign * minor(&a, best, j)
    });
    q.iter().all(|x| x.is_finite()).then_some(q)
}

/// The determinant of `a` without row `i` and column `j`.
fn minor(a: &[[f64; 4]; 4], i: usize, j: usize) -> f64 {
    let mut m = [[0.0; 3]; 3];
    for (r, row) in (0..4).filter(|&r| r != i).enumerate() {
        for (c, col) in (0..4).filter(|&c| c != j).enumerate() {
            m[r][c] = a[row][col];
        }
    }
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Polar iterations at most in [`orthonormalise`].
const POLAR_MAX_STEPS: usize = 8;

/// The nearest rotation to `m` when `m` is close to one (as after a converged SQP): Newton's
/// iteration for the polar factor, `X ← (X + X⁻ᵀ)/2`, which squares the distance from
/// orthonormality at each step (two or three steps from 1e-5). Falls back to
/// [`nearest_rotation`] when `det m ≤ 0` or the iteration has not settled after a few
/// steps; `None` when an entry is not finite.
pub(super) fn orthonormalise(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    use glam::DVec3;
    let mut x = m.map(DVec3::from_array);
    for _ in 0..POLAR_MAX_STEPS {
        let [a, b, c] = x;
        let cofactors = [b.cross(c), c.cross(a), a.cross(b)];
        let det = a.dot(cofactors[0]);
        if !(det > 0.0 && det.is_finite()) {
            break;
        }
        let next: [DVec3; 3] = std::array::from_fn(|k| 0.5 * (x[k] + cofactors[k] / det));
        let change = (0..3).fold(0.0_f64, |s, k| s.max((next[k] - x[k]).abs().max_element()));
        x = next;
        if change <= 1e-15 {
            return Some(x.map(|v| v.to_array()));
        }
    }
    nearest_rotation(m)
}

/// The nine entries of a 3×3 matrix, row by row: SQPnP's rotation as a vector.
pub(super) type Vec9 = [f64; 9];
/// A 9×9 matrix, as rows: SQPnP's quadratic form Ω.
pub(super) type Mat9 = [[f64; 9]; 9];

// SQPnP's 9-vector algebra is written here on arrays rather than with nalgebra's
// `SVector<f64, 9>` and `SMatrix<f64, 9, 9>`: with those, SQPnP took 5–17 % longer
// (6 points: 7.0–7.4 µs against 6.2–6.5 µs; 50 points: 8.1–8.4 against 7.3 µs; median
// of 300 solves in `examples/solve_bench`, the two builds run alternately twice,
// 2026-11-27), mostly in `Ω·v`, which the sum of rows below keeps in vector registers.

/// `|a − b|²`.
pub(super) fn distance_squared(a: &Vec9, b: &Vec9) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// `Ω·v` for a symmetric `Ω` (every `Ω` here is made exactly symmetric), as the sum of
/// its rows weighted by `v`'s entries: that runs in vector registers, where a dot product
/// per row, one chain of additions, would not.
pub(super) fn multiply(omega: &Mat9, v: &Vec9) -> Vec9 {
    let mut out = [0.0; 9];
    for (row, &s) in omega.iter().zip(v) {
        axpy(&mut out, s, row);
    }
    out
}

/// `out += s·x`.
#[inline(always)]
pub(super) fn axpy(out: &mut Vec9, s: f64, x: &Vec9) {
    for (o, x) in out.iter_mut().zip(x) {
        *o += s * x;
    }
}

/// `vᵀ·Ω·v` for a symmetric `Ω`.
pub(super) fn quadratic(omega: &Mat9, v: &Vec9) -> f64 {
    dot(&multiply(omega, v), v)
}

/// `s·v`.
pub(super) fn scaled(v: &Vec9, s: f64) -> Vec9 {
    v.map(|x| x * s)
}

#[cfg(test)]
// The reference routines below index matrices by row and column, as written in texts.
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    use crate::vision::testing::Rng;

    /// The solution `x` of `a·x = b` for a symmetric positive definite `a` (its lower triangle
    /// and diagonal are read), by Cholesky factorisation; `None` when `a` is not positive
    /// definite to working precision (a pivot at or below zero, or not finite).
    fn cholesky_solve<const N: usize>(a: &[[f64; N]; N], b: &[f64; N]) -> Option<[f64; N]> {
        let mut l = [[0.0; N]; N];
        for j in 0..N {
            let mut pivot = a[j][j];
            for k in 0..j {
                pivot -= l[j][k] * l[j][k];
            }
            if !(pivot > 0.0 && pivot.is_finite()) {
                return None;
            }
            let root = pivot.sqrt();
            l[j][j] = root;
            for i in j + 1..N {
                let mut s = a[i][j];
                for k in 0..j {
                    s -= l[i][k] * l[j][k];
                }
                l[i][j] = s / root;
            }
        }
        let mut y = [0.0; N];
        for i in 0..N {
            let mut s = b[i];
            for k in 0..i {
                s -= l[i][k] * y[k];
            }
            y[i] = s / l[i][i];
        }
        let mut x = [0.0; N];
        for i in (0..N).rev() {
            let mut s = y[i];
            for k in i + 1..N {
                s -= l[k][i] * x[k];
            }
            x[i] = s / l[i][i];
        }
        x.iter().all(|v| v.is_finite()).then_some(x)
    }

    fn random_symmetric<const N: usize>(rng: &mut Rng) -> [[f64; N]; N] {
        let mut a = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..=i {
                let x = rng.normal();
                a[i][j] = x;
                a[j][i] = x;
            }
        }
        a
    }

    /// `Σ λₖ·vₖ·vₖᵀ` for eigenvalues `l` and eigenvectors in the rows of `v`.
    fn compose<const N: usize>(l: &[f64; N], v: &[[f64; N]; N]) -> [[f64; N]; N] {
        let mut a = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                a[i][j] = (0..N).map(|k| v[k][i] * l[k] * v[k][j]).sum();
            }
        }
        a
    }

    fn largest_difference<const N: usize>(a: &[[f64; N]; N], b: &[[f64; N]; N]) -> f64 {
        a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .fold(0.0, |m, (x, y)| f64::max(m, (x - y).abs()))
    }

    /// Checks a decomposition of `a`: ascending values, orthonormal vectors, `V·Λ·Vᵀ = a`.
    fn check<const N: usize>(a: &[[f64; N]; N]) {
        let (l, v) = symmetric_eigen(a).expect("a decomposition");
        let scale = a.iter().flatten().fold(1e-300, |m: f64, x| m.max(x.abs()));
        assert!(l.windows(2).all(|w| w[0] <= w[1]), "{l:?}");
        let mut gram = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                gram[i][j] = (0..N).map(|k| v[i][k] * v[j][k]).sum();
            }
        }
        let mut identity = [[0.0; N]; N];
        for (i, row) in identity.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        assert!(largest_difference(&gram, &identity) < 1e-14, "{gram:?}");
        let back = compose(&l, &v);
        assert!(
            largest_difference(&back, a) < 1e-14 * scale,
            "{a:?} → {l:?}, {v:?}"
        );
    }

    #[test]
    fn eigen_decompositions_reproduce_random_symmetric_matrices() {
        let mut rng = Rng(31);
        for _ in 0..200 {
            check(&random_symmetric::<3>(&mut rng));
            check(&random_symmetric::<4>(&mut rng));
            check(&random_symmetric::<9>(&mut rng));
        }
    }

    #[test]
    fn eigen_decompositions_handle_repeated_and_zero_eigenvalues() {
        let mut rng = Rng(32);
        // Q·diag(λ)·Qᵀ with λ repeated, zero or tiny, and Q a random orthonormal matrix (the
        // eigenvectors of a random symmetric matrix).
        let spectra: [[f64; 9]; 4] = [
            [0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 3.0],
            [0.0; 9],
            [1e-12, 1e-9, 0.0, 5.0, 5.0, 7.0, 1.0, 1.0, 1.0],
            [-1.0, -1.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 4.0],
        ];
        for spectrum in spectra {
            let (_, q) = symmetric_eigen(&random_symmetric::<9>(&mut rng)).unwrap();
            let a = compose(&spectrum, &q);
            check(&a);
            let (l, _) = symmetric_eigen(&a).unwrap();
            let mut expected = spectrum;
            expected.sort_by(f64::total_cmp);
            for (got, want) in l.iter().zip(&expected) {
                assert!((got - want).abs() < 1e-14, "{l:?} vs {expected:?}");
            }
        }
        // Already diagonal, and the zero matrix.
        let mut diagonal = [[0.0; 9]; 9];
        for (i, row) in diagonal.iter_mut().enumerate() {
            row[i] = (i as f64 - 4.0).powi(2);
        }
        check(&diagonal);
        check(&[[0.0; 9]; 9]);
        let mut nan = diagonal;
        nan[3][5] = f64::NAN;
        assert!(symmetric_eigen(&nan).is_none());
    }

    #[test]
    fn positive_definite_systems_are_solved_and_others_refused() {
        let mut rng = Rng(33);
        for _ in 0..100 {
            // BᵀB + I is positive definite.
            let b = random_symmetric::<6>(&mut rng);
            let mut a = [[0.0; 6]; 6];
            for i in 0..6 {
                for j in 0..6 {
                    a[i][j] = (0..6).map(|k| b[k][i] * b[k][j]).sum::<f64>();
                }
                a[i][i] += 1.0;
            }
            let x_true: [f64; 6] = std::array::from_fn(|_| rng.normal());
            let rhs: [f64; 6] = std::array::from_fn(|i| (0..6).map(|k| a[i][k] * x_true[k]).sum());
            let x = cholesky_solve(&a, &rhs).unwrap();
            for (got, want) in x.iter().zip(&x_true) {
                assert!((got - want).abs() < 1e-10, "{x:?} vs {x_true:?}");
            }
        }
        for _ in 0..100 {
            let b = random_symmetric::<3>(&mut rng);
            let mut a = [[0.0; 3]; 3];
            for i in 0..3 {
                for j in 0..3 {
                    a[i][j] = (0..3).map(|k| b[k][i] * b[k][j]).sum::<f64>();
                }
                a[i][i] += 0.1;
            }
            let x_true: [f64; 3] = std::array::from_fn(|_| rng.normal());
            let rhs: [f64; 3] = std::array::from_fn(|i| (0..3).map(|k| a[i][k] * x_true[k]).sum());
            let by_adjugate = solve_spd3(&a, &rhs).unwrap();
            let by_cholesky = cholesky_solve(&a, &rhs).unwrap();
            for ((x, y), want) in by_adjugate.iter().zip(&by_cholesky).zip(&x_true) {
                assert!((x - want).abs() < 1e-9 && (y - want).abs() < 1e-9);
            }
        }
        let indefinite = [[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(cholesky_solve(&indefinite, &[1.0, 1.0, 1.0]).is_none());
        assert!(solve_spd3(&indefinite, &[1.0, 1.0, 1.0]).is_none());
        // Negative definite: the determinant of the whole is negative, the 2×2 minor positive.
        let negative = [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]];
        assert!(solve_spd3(&negative, &[1.0, 1.0, 1.0]).is_none());
        let singular = [[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(cholesky_solve(&singular, &[1.0, 1.0, 1.0]).is_none());
        assert!(solve_spd3(&singular, &[1.0, 1.0, 1.0]).is_none());
    }

    fn to_nalgebra(m: &[[f64; 3]; 3]) -> nalgebra::Matrix3<f64> {
        nalgebra::Matrix3::from_fn(|i, j| m[i][j])
    }

    /// The nearest rotation by SVD: `U·diag(1, 1, det(U·Vᵀ))·Vᵀ`.
    fn nearest_by_svd(m: &[[f64; 3]; 3]) -> nalgebra::Matrix3<f64> {
        let svd = to_nalgebra(m).svd(true, true);
        let (u, v_t) = (svd.u.unwrap(), svd.v_t.unwrap());
        let sign = (u.determinant() * v_t.determinant()).signum();
        u * nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, sign)) * v_t
    }

    #[test]
    fn nearest_rotations_match_the_svd_answer() {
        let mut rng = Rng(34);
        for trial in 0..500 {
            // Random matrices (either sign of determinant), and rotations with small noise.
            let m: [[f64; 3]; 3] = if trial % 2 == 0 {
                std::array::from_fn(|_| std::array::from_fn(|_| rng.normal()))
            } else {
                let r = rng.uniform_rotation().transpose().to_cols_array_2d();
                r.map(|row| row.map(|x| x + 1e-3 * rng.normal()))
            };
            let r = nearest_rotation(&m).unwrap();
            let got = to_nalgebra(&r);
            assert!((got * got.transpose() - nalgebra::Matrix3::identity()).amax() < 1e-15);
            assert!((got.determinant() - 1.0).abs() < 1e-14);
            // A tie (two nearly equal smallest singular values with det m < 0) makes the SVD
            // answer ill-determined; compare the objective there, the matrix elsewhere.
            let svd = to_nalgebra(&m).svd(false, false).singular_values;
            let mut sv: Vec<f64> = svd.iter().copied().collect();
            sv.sort_by(f64::total_cmp);
            let want = nearest_by_svd(&m);
            let objective = |x: &nalgebra::Matrix3<f64>| (x.transpose() * to_nalgebra(&m)).trace();
            assert!(
                objective(&got) >= objective(&want) - 1e-12,
                "trial {trial}: {} < {}",
                objective(&got),
                objective(&want)
            );
            if sv[1] - sv[0] > 1e-3 {
                assert!(
                    (got - want).amax() < 1e-10,
                    "trial {trial}: {got} vs {want}"
                );
            }
        }
        // A rotation is its own nearest rotation; a scaled one too.
        let r = rng.uniform_rotation().transpose().to_cols_array_2d();
        for scale in [1.0, 1e-200, 1e200] {
            let near = nearest_rotation(&r.map(|row| row.map(|x| x * scale))).unwrap();
            assert!(largest_difference(&near, &r) < 1e-15, "{scale}");
        }
        assert!(nearest_rotation(&[[f64::NAN, 0.0, 0.0], [0.0; 3], [0.0; 3]]).is_none());
        // A reflection: every rotation about the z axis by π, and others, tie (K's largest
        // eigenvalue is repeated, so the adjugate is zero and the eigen-decomposition
        // answers); one of them is given, with the largest tr(Rᵀ·m), 1.
        let reflection = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]];
        let r = to_nalgebra(&nearest_rotation(&reflection).unwrap());
        assert!((r * r.transpose() - nalgebra::Matrix3::identity()).amax() < 1e-15);
        assert!((r.determinant() - 1.0).abs() < 1e-14);
        assert!(((r.transpose() * to_nalgebra(&reflection)).trace() - 1.0).abs() < 1e-14);
        // The zero matrix: any rotation is nearest; one is given.
        assert!(nearest_rotation(&[[0.0; 3]; 3]).is_some());
    }
}
