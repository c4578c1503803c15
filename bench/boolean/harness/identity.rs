//! The volume identities between the three booleans of one pair:
//!
//! * V(A) + V(B) = V(A ∪ B) + V(A ∩ B);
//! * V(A − B) = V(A) − V(A ∩ B).
//!
//! Volumes are signed: an everted operand counts −V of the solid it was, and a result
//! whose interior is infinite counts the sum of its shells' (negative) volumes. The
//! identities still hold then: measure a set X that is bounded or has a bounded
//! complement by μ(X) = vol(X ∩ R) − vol(R)·[X unbounded] for any ball R holding every
//! surface. vol(· ∩ R) is additive, and the correction terms balance:
//! [A ∪ B unbounded] + [A ∩ B unbounded] = [A unbounded] + [B unbounded], and
//! [A − B unbounded] = [A unbounded] − [A ∩ B unbounded]. And μ is exactly what the
//! shells' signed volumes sum to. (The empty set and all of space both measure 0 and
//! both have no shells: the identities cannot tell them apart, nor can a `Solution`.)

/// The five signed volumes of one case.
#[derive(Clone, Copy, Debug)]
pub struct Volumes {
    /// V(A).
    pub a: f64,
    /// V(B).
    pub b: f64,
    /// V(A ∩ B).
    pub intersection: f64,
    /// V(A ∪ B).
    pub union: f64,
    /// V(A − B).
    pub difference: f64,
}

/// Checks both identities: exactly when `exact`, else to 1e-12 of the largest volume.
pub fn check(v: Volumes, exact: bool) -> Result<(), String> {
    let largest = [v.a, v.b, v.intersection, v.union, v.difference]
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let tolerance = if exact { 0.0 } else { 1e-12 * largest };
    let mut wrong = Vec::new();
    let sums = (v.a + v.b, v.union + v.intersection);
    if (sums.0 - sums.1).abs() > tolerance || sums.0.is_nan() || sums.1.is_nan() {
        wrong.push(format!(
            "V(A) + V(B) = {:e} but V(A∪B) + V(A∩B) = {:e} (off by {:e})",
            sums.0,
            sums.1,
            sums.0 - sums.1
        ));
    }
    let rest = v.a - v.intersection;
    if (v.difference - rest).abs() > tolerance || v.difference.is_nan() || rest.is_nan() {
        wrong.push(format!(
            "V(A−B) = {:e} but V(A) − V(A∩B) = {:e} (off by {:e})",
            v.difference,
            rest,
            v.difference - rest
        ));
    }
    if wrong.is_empty() {
        Ok(())
    } else {
        Err(format!("{wrong:?} with {v:?}, tolerance {tolerance:e}"))
    }
}
