//! Double-double arithmetic (an unevaluated sum of two f64, about 106
//! bits) for the f64 references: the accurate double-word algorithms of
//! Joldes, Muller and Popescu (*ACM TOMS* 2017), and sine and cosine of
//! whole arc-seconds.

/// `a + b` exactly, as `(sum, error)`.
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// `a + b` exactly, as `(sum, error)`, when `|a| ≥ |b|` (or `a = 0`).
#[inline]
fn fast_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

/// `a·b` exactly, as `(product, error)` (the error by a fused multiply-add).
#[inline]
fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

/// A double-double number `hi + lo`, `|lo| ≤ ulp(hi)/2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Dd {
    pub(crate) hi: f64,
    pub(crate) lo: f64,
}

impl Dd {
    pub(crate) const ZERO: Dd = Dd { hi: 0.0, lo: 0.0 };

    #[inline]
    pub(crate) fn from_f64(x: f64) -> Dd {
        Dd { hi: x, lo: 0.0 }
    }

    #[inline]
    pub(crate) fn norm(hi: f64, lo: f64) -> Dd {
        let (hi, lo) = fast_two_sum(hi, lo);
        Dd { hi, lo }
    }

    /// Exact for `|x| < 2¹⁰⁶`.
    pub(crate) fn from_i128(x: i128) -> Dd {
        let hi = x as f64;
        let lo = (x - hi as i128) as f64;
        Dd::norm(hi, lo)
    }

    /// `a·b`, exact.
    #[inline]
    pub(crate) fn prod(a: f64, b: f64) -> Dd {
        let (hi, lo) = two_prod(a, b);
        Dd { hi, lo }
    }

    #[inline]
    pub(crate) fn to_f64(self) -> f64 {
        self.hi + self.lo
    }

    #[inline]
    pub(crate) fn is_zero(self) -> bool {
        self.hi == 0.0
    }

    #[inline]
    pub(crate) fn neg(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
        }
    }

    #[inline]
    pub(crate) fn abs(self) -> Dd {
        if self.is_neg() {
            self.neg()
        } else {
            self
        }
    }

    #[inline]
    pub(crate) fn is_neg(self) -> bool {
        self.hi < 0.0 || (self.hi == 0.0 && self.lo < 0.0)
    }

    #[inline]
    pub(crate) fn lt(self, y: Dd) -> bool {
        self.hi < y.hi || (self.hi == y.hi && self.lo < y.lo)
    }

    #[inline]
    pub(crate) fn le(self, y: Dd) -> bool {
        !y.lt(self)
    }

    #[inline]
    pub(crate) fn min(self, y: Dd) -> Dd {
        if y.lt(self) {
            y
        } else {
            self
        }
    }

    #[inline]
    pub(crate) fn max(self, y: Dd) -> Dd {
        if self.lt(y) {
            y
        } else {
            self
        }
    }

    /// Sum (accurate double-word addition, relative error ≤ 3u² + 13u³).
    #[inline]
    pub(crate) fn plus(self, y: Dd) -> Dd {
        let (sh, sl) = two_sum(self.hi, y.hi);
        let (th, tl) = two_sum(self.lo, y.lo);
        let c = sl + th;
        let (vh, vl) = fast_two_sum(sh, c);
        let w = tl + vl;
        Dd::norm(vh, w)
    }

    #[inline]
    pub(crate) fn minus(self, y: Dd) -> Dd {
        self.plus(y.neg())
    }

    /// Product (relative error ≤ 5u²).
    #[inline]
    pub(crate) fn times(self, y: Dd) -> Dd {
        let (ch, cl1) = two_prod(self.hi, y.hi);
        let tl0 = self.lo * y.lo;
        let tl1 = self.hi.mul_add(y.lo, tl0);
        let cl2 = self.lo.mul_add(y.hi, tl1);
        Dd::norm(ch, cl1 + cl2)
    }

    /// Product by an f64 (relative error ≤ 2u²).
    #[inline]
    pub(crate) fn times_f64(self, y: f64) -> Dd {
        let (ch, cl1) = two_prod(self.hi, y);
        let cl3 = self.lo.mul_add(y, cl1);
        Dd::norm(ch, cl3)
    }

    /// Quotient (relative error ≤ 15u² + 56u³). `y ≠ 0`.
    #[inline]
    pub(crate) fn over(self, y: Dd) -> Dd {
        let th = self.hi / y.hi;
        let r = y.times_f64(th);
        let pih = self.hi - r.hi;
        let dl = self.lo - r.lo;
        let tl = (pih + dl) / y.hi;
        Dd::norm(th, tl)
    }

    /// Square root (one Newton step with the exact residual; relative error
    /// below 4u²). Negative values (only rounding noise around 0) give 0.
    #[inline]
    pub(crate) fn sqrt(self) -> Dd {
        if self.hi <= 0.0 {
            return Dd::ZERO;
        }
        let s = self.hi.sqrt();
        let (p, e) = two_prod(s, s);
        let r = self.minus(Dd { hi: p, lo: e });
        Dd::norm(s, r.hi / (2.0 * s))
    }

    #[inline]
    pub(crate) fn half(self) -> Dd {
        Dd {
            hi: self.hi * 0.5,
            lo: self.lo * 0.5,
        }
    }
}

/// π as a double-double.
const PI: Dd = Dd {
    hi: std::f64::consts::PI,
    lo: 1.224_646_799_147_353_2e-16,
};

/// `(sin α, cos α)` of an angle in whole arc-seconds, relative error below
/// about 2⁻¹⁰⁰: reduced exactly to within 45° of a quarter turn, then
/// Taylor series in double-double.
pub(crate) fn sin_cos_arcsec(alpha: i64) -> (Dd, Dd) {
    const QUARTER: i64 = 324_000;
    let a = alpha.rem_euclid(4 * QUARTER);
    let k = (a + QUARTER / 2) / QUARTER;
    let r = a - k * QUARTER;
    // |r| ≤ 162 000″ (45°): x = r·π/648 000.
    let x = Dd::from_i128(i128::from(r))
        .times(PI)
        .over(Dd::from_f64(648_000.0));
    let x2 = x.times(x);
    // sin x = x − x³/3! + …, cos x = 1 − x²/2! + …; |x| ≤ π/4, 15 terms
    // each leave less than 10⁻³⁸.
    let mut s = Dd::ZERO;
    let mut c = Dd::ZERO;
    let mut term_s = x;
    let mut term_c = Dd::from_f64(1.0);
    for n in 0..15 {
        s = s.plus(term_s);
        c = c.plus(term_c);
        let (i, j) = (f64::from(2 * n + 2), f64::from(2 * n + 3));
        term_s = term_s.times(x2).over(Dd::from_f64(-i * j));
        term_c = term_c.times(x2).over(Dd::from_f64(-(i - 1.0) * i));
    }
    match k % 4 {
        0 => (s, c),
        1 => (c, s.neg()),
        2 => (s.neg(), c.neg()),
        _ => (c.neg(), s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sine_and_cosine_of_arc_seconds() {
        for alpha in [
            0i64, 1, 3600, 162_000, 324_000, 500_000, 648_000, 1_000_001, -7_777,
        ] {
            let (s, c) = sin_cos_arcsec(alpha);
            let x = alpha as f64 * std::f64::consts::PI / 648_000.0;
            assert!((s.to_f64() - x.sin()).abs() < 1e-15, "{alpha}");
            assert!((c.to_f64() - x.cos()).abs() < 1e-15, "{alpha}");
            // s² + c² = 1 far below f64 precision.
            let one = s.times(s).plus(c.times(c)).minus(Dd::from_f64(1.0));
            assert!(one.to_f64().abs() < 1e-30, "{alpha}: {}", one.to_f64());
        }
        // 30°: sin = ½ exactly.
        let (s, _) = sin_cos_arcsec(108_000);
        assert!(s.minus(Dd::from_f64(0.5)).to_f64().abs() < 1e-31);
    }
}
