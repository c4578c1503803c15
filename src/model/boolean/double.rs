//! The second filter: double-double arithmetic with a running error bound.
//!
//! A predicate the f64 filter ([`super::exact::Fx`]) cannot decide is evaluated again
//! in [`Dd`], an unevaluated sum `hi + lo` of two f64 (about 106 bits) carrying a bound
//! on its distance from the exact value. Its rounding errors are near 2⁻¹⁰⁶ of the
//! operands where the f64 filter's are near 2⁻⁵³, so it decides almost every sign the
//! first filter leaves open, at a small fraction of the cost of exact arithmetic, which
//! stays behind it for true zeros and the rest.

use std::ops::{Add, Mul, Neg, Sub};

use super::exact::Ring;

/// Unit roundoff of f64.
const U: f64 = f64::EPSILON / 2.0;
/// Growth applied to every bound, covering the rounding of the bound's own arithmetic.
const GROW: f64 = 1.0 + 8.0 * U;
/// Products smaller than this (about 2⁻⁷⁹⁷) give up: their low-order parts could be
/// subnormal, where the error-free transforms are not exact.
const TINY: f64 = 1e-240;
/// Magnitudes past which Dekker's product could overflow: the bound becomes unknown.
const HUGE: f64 = 1e290;

/// A value `hi + lo` (with `|lo| ≤ u |hi|`) whose exact counterpart lies within `e`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Dd {
    hi: f64,
    lo: f64,
    e: f64,
}

impl Dd {
    /// The sign of the exact value, when the bound decides it: −1, 0 (only for an exact
    /// zero with no error) or 1.
    pub fn sign(self) -> Option<i8> {
        if !self.hi.is_finite() || !self.lo.is_finite() || !self.e.is_finite() {
            None
        } else if self.hi - self.lo.abs() > self.e {
            Some(1)
        } else if -self.hi - self.lo.abs() > self.e {
            Some(-1)
        } else if self.hi == 0.0 && self.lo == 0.0 && self.e == 0.0 {
            Some(0)
        } else {
            None
        }
    }

    /// An upper bound on `|hi + lo|`.
    #[inline]
    fn size(self) -> f64 {
        self.hi.abs() + self.lo.abs()
    }
}

/// `a + b` as the rounded sum and its exact error (Knuth's TwoSum).
#[inline]
pub(super) fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bv = s - a;
    let av = s - bv;
    (s, (a - av) + (b - bv))
}

/// Dekker's split of `a` into two halves of 26 bits each.
#[inline]
fn split(a: f64) -> (f64, f64) {
    let c = 134_217_729.0 * a; // 2^27 + 1
    let hi = c - (c - a);
    (hi, a - hi)
}

/// `a · b` as the rounded product and its exact error (Dekker's TwoProduct); the error
/// is NaN where the split could overflow. Exact above the subnormal range (the caller
/// rules that out).
#[inline]
pub(super) fn two_product(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    if !p.is_finite() || a.abs() > HUGE || b.abs() > HUGE {
        return (p, f64::NAN);
    }
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    (p, al * bl - (((p - ah * bh) - al * bh) - ah * bl))
}

impl Ring for Dd {
    #[inline]
    fn of(x: f64) -> Self {
        Dd {
            hi: x,
            lo: 0.0,
            e: 0.0,
        }
    }
}

impl Add for Dd {
    type Output = Dd;
    #[inline]
    fn add(self, o: Dd) -> Dd {
        let (s, t) = two_sum(self.hi, o.hi);
        let (t, r1) = two_sum(t, self.lo);
        let (t, r2) = two_sum(t, o.lo);
        let (hi, lo) = two_sum(s, t);
        // Only the two low-order sums rounded, and by exactly r1 and r2.
        let e = (self.e + o.e + r1.abs() + r2.abs()) * GROW;
        Dd { hi, lo, e }
    }
}

impl Sub for Dd {
    type Output = Dd;
    #[inline]
    fn sub(self, o: Dd) -> Dd {
        self + (-o)
    }
}

impl Neg for Dd {
    type Output = Dd;
    #[inline]
    fn neg(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
            e: self.e,
        }
    }
}

impl Mul for Dd {
    type Output = Dd;
    #[inline]
    fn mul(self, o: Dd) -> Dd {
        let (p, pe) = two_product(self.hi, o.hi);
        if (p == 0.0 && self.hi != 0.0 && o.hi != 0.0) || (p != 0.0 && p.abs() < TINY) {
            // Near the subnormal range the error-free transforms are not: no bound.
            return Dd {
                hi: p,
                lo: 0.0,
                e: f64::INFINITY,
            };
        }
        let (c1, c2) = (self.hi * o.lo, self.lo * o.hi);
        let (c, r1) = two_sum(c1, c2);
        let (t, r2) = two_sum(pe, c);
        let (hi, lo) = two_sum(p, t);
        // Rounded: the two cross products (each by at most u of itself) and the two
        // sums (by exactly r1 and r2); left out: lo · lo.
        let rounding = U * (c1.abs() + c2.abs()) + r1.abs() + r2.abs() + self.lo.abs() * o.lo.abs();
        let (a, b) = (self.size(), o.size());
        let e = (a * o.e + b * self.e + self.e * o.e + rounding) * GROW;
        Dd { hi, lo, e }
    }
}

#[cfg(test)]
mod tests {
    use super::super::exact::Dy;
    use super::*;

    fn det2<R: Ring>(a: f64, b: f64, c: f64, d: f64) -> R {
        R::of(a) * R::of(d) - R::of(b) * R::of(c)
    }

    /// A cancellation the f64 filter cannot see through is decided here, and rightly.
    #[test]
    fn a_cancellation_below_f64_is_decided() {
        // (1 + 2^-52)(1 − 2^-52) − 1 = −2^-104.
        let a = 1.0 + f64::EPSILON;
        let b = 1.0 - f64::EPSILON;
        let d: Dd = det2(a, 1.0, 1.0, b);
        assert_eq!(d.sign(), Some(-1));
        let z: Dd = det2(2.0, 1.0, 4.0, 2.0);
        assert_eq!(z.sign(), Some(0));
    }

    /// Whenever the bound decides, it agrees with exact arithmetic: products of nearly
    /// equal sums, differences of them, at many scales.
    #[test]
    fn every_decided_sign_is_the_exact_sign() {
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut decided, mut open) = (0, 0);
        for k in 0..20_000 {
            let scale = 2f64.powi((k % 40) - 20);
            let a = (next() - 0.5) * scale;
            let b = (next() - 0.5) * scale;
            // c/d nearly equal to a/b, so the determinant nearly cancels.
            let t = next() * 4.0;
            let c = a * t * (1.0 + (next() - 0.5) * 1e-15);
            let d = b * t;
            let eval = |r: &mut dyn FnMut(f64, f64, f64, f64) -> i8| r(a, b, c, d);
            let exact = eval(&mut |a, b, c, d| {
                let v: Dy = (Dy::of(a) - Dy::of(c)) * (Dy::of(b) + Dy::of(d)) * Dy::of(a)
                    - det2::<Dy>(a, b, c, d) * Dy::of(b);
                v.sign()
            });
            let dd: Dd = (Dd::of(a) - Dd::of(c)) * (Dd::of(b) + Dd::of(d)) * Dd::of(a)
                - det2::<Dd>(a, b, c, d) * Dd::of(b);
            match dd.sign() {
                Some(s) => {
                    decided += 1;
                    assert_eq!(s, exact, "{a} {b} {c} {d}");
                }
                None => open += 1,
            }
        }
        assert!(decided > 19_000, "decided {decided}, open {open}");
    }
}
