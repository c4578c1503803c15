//! Exact signs of polynomials in f64 inputs: two filters with running error bounds, and
//! exact dyadic arithmetic behind them.
//!
//! Every predicate of the boolean is a polynomial in input coordinates (all f64, so all
//! dyadic rationals). It is written once, generic over [`Ring`], and evaluated first in
//! [`Fx`] (f64 with a bound on the absolute error of the value), which answers when the
//! value is farther from zero than its bound; otherwise in double-double with a bound
//! ([`super::double::Dd`]), which answers the same way with about twice the precision;
//! otherwise in [`Dy`] (an arbitrary-precision integer times a power of two), which is
//! exact. The answer is therefore always the sign of the exact value.

use std::ops::{Add, Mul, Neg, Sub};

use num_bigint::{BigInt, Sign};

use super::double::{Dd, two_product, two_sum};
use num_traits::{Signed, ToPrimitive, Zero};

/// The numbers a predicate is evaluated in: a commutative ring holding every f64.
pub(crate) trait Ring:
    Clone + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    /// The f64 `x`, exactly (precondition: finite).
    fn of(x: f64) -> Self;

    /// A value already computed in the filter, if this ring is the filter's.
    fn from_filter(_h: &[Fx; 4]) -> Option<[Self; 4]> {
        None
    }
}

/// Unit roundoff of f64.
const U: f64 = f64::EPSILON / 2.0;
/// Growth applied to every bound, covering the rounding of the bound's own arithmetic.
const GROW: f64 = 1.0 + 8.0 * U;
/// An absolute floor on every bound, covering underflow.
const FLOOR: f64 = f64::MIN_POSITIVE * 64.0;

/// An f64 value `v` whose exact counterpart lies within `e` of it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fx {
    pub v: f64,
    pub e: f64,
}

impl Fx {
    /// The sign of the exact value, when the bound decides it: −1, 0 (only for an exact
    /// zero with no error) or 1.
    #[inline]
    pub fn sign(self) -> Option<i8> {
        if !self.v.is_finite() || !self.e.is_finite() {
            None
        } else if self.v > self.e {
            Some(1)
        } else if -self.v > self.e {
            Some(-1)
        } else if self.v == 0.0 && self.e == 0.0 {
            Some(0)
        } else {
            None
        }
    }
}

impl Ring for Fx {
    #[inline]
    fn of(x: f64) -> Self {
        Fx { v: x, e: 0.0 }
    }

    #[inline]
    fn from_filter(h: &[Fx; 4]) -> Option<[Self; 4]> {
        Some(*h)
    }
}

impl Add for Fx {
    type Output = Fx;
    #[inline]
    fn add(self, o: Fx) -> Fx {
        let v = self.v + o.v;
        let e = if self.e == 0.0 && o.e == 0.0 && two_sum(self.v, o.v).1 == 0.0 {
            0.0
        } else {
            (self.e + o.e + v.abs() * U + FLOOR) * GROW
        };
        Fx { v, e }
    }
}

impl Sub for Fx {
    type Output = Fx;
    #[inline]
    fn sub(self, o: Fx) -> Fx {
        self + (-o)
    }
}

impl Neg for Fx {
    type Output = Fx;
    #[inline]
    fn neg(self) -> Fx {
        Fx {
            v: -self.v,
            e: self.e,
        }
    }
}

impl Mul for Fx {
    type Output = Fx;
    #[inline]
    fn mul(self, o: Fx) -> Fx {
        let v = self.v * o.v;
        let exact = self.e == 0.0
            && o.e == 0.0
            && (v == 0.0 || v.abs() >= f64::MIN_POSITIVE * 2f64.powi(54))
            && two_product(self.v, o.v).1 == 0.0;
        let e = if exact {
            0.0
        } else {
            (self.v.abs() * o.e + o.v.abs() * self.e + self.e * o.e + v.abs() * U + FLOOR) * GROW
        };
        Fx { v, e }
    }
}

/// An exact dyadic rational `m · 2^x`. The mantissa is held in an `i128` while it fits
/// (integer-grid inputs stay there through whole predicates) and in a `BigInt` past
/// that; both forms are exact.
#[derive(Clone, Debug)]
pub(crate) struct Dy {
    m: Mantissa,
    x: i32,
}

#[derive(Clone, Debug)]
enum Mantissa {
    Small(i128),
    Big(BigInt),
}

impl Mantissa {
    fn big(&self) -> BigInt {
        match self {
            Mantissa::Small(v) => BigInt::from(*v),
            Mantissa::Big(b) => b.clone(),
        }
    }

    fn sign(&self) -> i8 {
        match self {
            Mantissa::Small(v) => v.signum() as i8,
            Mantissa::Big(b) => match b.sign() {
                Sign::Minus => -1,
                Sign::NoSign => 0,
                Sign::Plus => 1,
            },
        }
    }

    fn is_zero(&self) -> bool {
        self.sign() == 0
    }

    /// `self · 2^s`, exactly.
    fn shl(&self, s: u32) -> Mantissa {
        if s == 0 {
            return self.clone();
        }
        if let Mantissa::Small(v) = self
            && (*v == 0 || (s < 126 && v.unsigned_abs().leading_zeros() > s + 1))
        {
            return Mantissa::Small(v << s);
        }
        Mantissa::Big(self.big() << (s as usize))
    }
}

impl Dy {
    /// −1, 0 or 1.
    pub fn sign(&self) -> i8 {
        self.m.sign()
    }

    /// Both numbers over one power of two: (self's mantissa, other's mantissa, exponent).
    fn aligned(&self, o: &Dy) -> (Mantissa, Mantissa, i32) {
        if self.m.is_zero() {
            return (Mantissa::Small(0), o.m.clone(), o.x);
        }
        if o.m.is_zero() {
            return (self.m.clone(), Mantissa::Small(0), self.x);
        }
        if self.x <= o.x {
            (self.m.clone(), o.m.shl((o.x - self.x) as u32), self.x)
        } else {
            (self.m.shl((self.x - o.x) as u32), o.m.clone(), o.x)
        }
    }

    fn big_mantissa(&self) -> BigInt {
        self.m.big()
    }
}

fn add_m(a: Mantissa, b: Mantissa) -> Mantissa {
    if let (Mantissa::Small(p), Mantissa::Small(q)) = (&a, &b)
        && let Some(r) = p.checked_add(*q)
    {
        return Mantissa::Small(r);
    }
    Mantissa::Big(a.big() + b.big())
}

impl Ring for Dy {
    fn of(x: f64) -> Self {
        debug_assert!(x.is_finite());
        if x == 0.0 {
            return Dy {
                m: Mantissa::Small(0),
                x: 0,
            };
        }
        let bits = x.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i32;
        let frac = bits & ((1u64 << 52) - 1);
        let (mant, e) = if exp == 0 {
            (frac, -1074)
        } else {
            (frac | (1u64 << 52), exp - 1075)
        };
        // Normalised: no trailing zero bits, so small numbers have small mantissas.
        let tz = mant.trailing_zeros();
        let m = (mant >> tz) as i128;
        Dy {
            m: Mantissa::Small(if x < 0.0 { -m } else { m }),
            x: e + tz as i32,
        }
    }
}

impl Add for Dy {
    type Output = Dy;
    fn add(self, o: Dy) -> Dy {
        let (a, b, x) = self.aligned(&o);
        Dy { m: add_m(a, b), x }
    }
}

impl Sub for Dy {
    type Output = Dy;
    fn sub(self, o: Dy) -> Dy {
        self + (-o)
    }
}

impl Neg for Dy {
    type Output = Dy;
    fn neg(self) -> Dy {
        let m = match self.m {
            Mantissa::Small(v) => match v.checked_neg() {
                Some(n) => Mantissa::Small(n),
                None => Mantissa::Big(-BigInt::from(v)),
            },
            Mantissa::Big(b) => Mantissa::Big(-b),
        };
        Dy { m, x: self.x }
    }
}

impl Mul for Dy {
    type Output = Dy;
    fn mul(self, o: Dy) -> Dy {
        let m = match (&self.m, &o.m) {
            (Mantissa::Small(p), Mantissa::Small(q)) => match p.checked_mul(*q) {
                Some(r) => Mantissa::Small(r),
                None => Mantissa::Big(BigInt::from(*p) * BigInt::from(*q)),
            },
            _ => Mantissa::Big(self.m.big() * o.m.big()),
        };
        Dy { m, x: self.x + o.x }
    }
}

/// The f64 nearest to `num / den` (ties to even). Precondition: `den` is not zero.
pub(crate) fn quotient_to_f64(num: &Dy, den: &Dy) -> f64 {
    if num.m.is_zero() {
        return 0.0;
    }
    let negative = (num.sign() < 0) != (den.sign() < 0);
    let (n, d) = (num.big_mantissa().abs(), den.big_mantissa().abs());
    // Scale the numerator so the integer quotient has at least 66 significant bits.
    let shift = (d.bits() as i64 - n.bits() as i64 + 66).max(0) as usize;
    let scaled = n << shift;
    let (q, r) = (&scaled / &d, &scaled % &d);
    // A sticky bit below the 64 bits the conversion keeps decides halfway cases.
    let q = if r.is_zero() {
        q
    } else {
        (q << 1usize) | BigInt::from(1)
    };
    let extra = if r.is_zero() { 0 } else { 1 };
    let top = q.bits() as i64;
    let drop = (top - 64).max(0);
    let low_nonzero = drop > 0 && q.trailing_zeros().is_some_and(|t| (t as i64) < drop);
    let mut mant = (&q >> (drop as usize)).to_u64().unwrap_or(u64::MAX);
    if low_nonzero {
        mant |= 1;
    }
    // mant · 2^(drop − shift − extra + num.x − den.x), mant < 2^64: `as f64` rounds to
    // nearest even, and the sticky bit keeps that rounding correct.
    let exp = drop - shift as i64 - extra + num.x as i64 - den.x as i64;
    let value = scale(mant as f64, exp);
    if negative { -value } else { value }
}

/// `x · 2^e`, exact unless the result overflows or underflows.
fn scale(mut x: f64, mut e: i64) -> f64 {
    while e > 1000 {
        x *= 2f64.powi(1000);
        e -= 1000;
    }
    while e < -1000 {
        x *= 2f64.powi(-1000);
        e += 1000;
    }
    x * 2f64.powi(e as i32)
}

/// A polynomial in input coordinates, written once over [`Ring`].
pub(crate) trait Poly {
    /// The polynomial's value in `R`.
    fn eval<R: Ring>(&self) -> R;

    /// Whether the value is known to be zero without evaluating it (a proof from the
    /// points' definitions; `false` means "not known").
    fn known_zero(&self) -> bool {
        false
    }

    /// The sign of the exact value: the f64 filter's answer when it is certain, else
    /// the double-double filter's ([`Dd`]) when it is, else 0 if it is known to be,
    /// else the exact arithmetic's.
    fn sign(&self) -> i8 {
        match self.eval::<Fx>().sign() {
            Some(s) => s,
            None => match self.eval::<Dd>().sign() {
                Some(s) => s,
                None if self.known_zero() => 0,
                None => self.eval::<Dy>().sign(),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn det2<R: Ring>(a: f64, b: f64, c: f64, d: f64) -> R {
        R::of(a) * R::of(d) - R::of(b) * R::of(c)
    }

    #[test]
    fn the_filter_defers_a_cancellation_and_the_exact_sign_is_found() {
        // (1 + 2^-52)(1 − 2^-52) − 1 = −2^-104: f64 rounds the product to 1.
        let a = 1.0 + f64::EPSILON;
        let b = 1.0 - f64::EPSILON;
        let f: Fx = det2(a, 1.0, 1.0, b);
        assert_eq!(f.v, 0.0);
        assert_eq!(f.sign(), None);
        let d: Dy = det2(a, 1.0, 1.0, b);
        assert_eq!(d.sign(), -1);
    }

    #[test]
    fn exact_products_outgrow_the_small_form_and_stay_exact() {
        // (1 + 2^-52)^3 − 1 − 3·2^-52 − 3·2^-104 = 2^-156: needs 157 bits.
        let a = 1.0 + f64::EPSILON;
        let e = f64::EPSILON;
        let cube = Dy::of(a) * Dy::of(a) * Dy::of(a);
        let rest =
            cube - Dy::of(1.0) - Dy::of(3.0) * Dy::of(e) - Dy::of(3.0) * Dy::of(e) * Dy::of(e);
        assert_eq!(rest.sign(), 1);
        let gone = rest - Dy::of(e) * Dy::of(e) * Dy::of(e);
        assert_eq!(gone.sign(), 0);
    }

    #[test]
    fn the_filter_answers_clear_signs() {
        let f: Fx = det2(3.0, 1.0, 1.0, 2.0);
        assert_eq!(f.sign(), Some(1));
        let z: Fx = det2(2.0, 1.0, 4.0, 2.0);
        assert_eq!(z.sign(), Some(0));
    }

    #[test]
    fn quotients_round_to_nearest() {
        let q = |a: f64, b: f64| quotient_to_f64(&Dy::of(a), &Dy::of(b));
        assert_eq!(q(1.0, 3.0), 1.0 / 3.0);
        assert_eq!(q(-2.0, 3.0), -2.0 / 3.0);
        assert_eq!(q(7.0, -1024.0), -7.0 / 1024.0);
        assert_eq!(q(0.1, 0.7), 0.1 / 0.7);
        assert_eq!(q(1e-300, 3e10), 1e-300 / 3e10);
        let third = Dy::of(1.0) * Dy::of(1.0) + Dy::of(0.0);
        assert_eq!(quotient_to_f64(&third, &Dy::of(4.0)), 0.25);
    }
}
