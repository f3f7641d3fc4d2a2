//! 256-bit intermediates for the motion planner's fixed-point arithmetic:
//! products of two `u128`, quotients and square roots of such products.
//!
//! Every function is exact (floor) and total: a quotient that does not fit
//! a `u128` saturates at `u128::MAX` (the planner only takes minima of such
//! values, where a saturated term never wins), and a division by zero gives
//! `u128::MAX` too. Shifts, compares and subtractions only in the divisions
//! and roots, as [`crate::trig::isqrt`] (a Cortex-M4 has no 64-bit divide).

use crate::trig::isqrt;
use core::cmp::Ordering;

/// An unsigned 256-bit integer: `hi · 2¹²⁸ + lo`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct U256 {
    hi: u128,
    lo: u128,
}

impl PartialOrd for U256 {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for U256 {
    fn cmp(&self, other: &Self) -> Ordering {
        (self.hi, self.lo).cmp(&(other.hi, other.lo))
    }
}

const M64: u128 = (1 << 64) - 1;

impl U256 {
    /// `a · b`, exact.
    pub(crate) const fn mul(a: u128, b: u128) -> U256 {
        let (a1, a0) = (a >> 64, a & M64);
        let (b1, b0) = (b >> 64, b & M64);
        let p00 = a0 * b0;
        let p01 = a0 * b1;
        let p10 = a1 * b0;
        let p11 = a1 * b1;
        // Middle column: three terms below 2⁶⁴ each, the sum below 2⁶⁶.
        let mid = (p00 >> 64) + (p01 & M64) + (p10 & M64);
        let lo = (p00 & M64) | (mid << 64);
        let hi = p11 + (p01 >> 64) + (p10 >> 64) + (mid >> 64);
        U256 { hi, lo }
    }

    /// `n · 2^s` for `s < 128`, exact.
    pub(crate) const fn shl(n: u128, s: u32) -> U256 {
        if s == 0 {
            U256 { hi: 0, lo: n }
        } else {
            U256 {
                hi: n >> (128 - s),
                lo: n << s,
            }
        }
    }

    /// `self >> s` for `s < 128`, floor; `None` if it does not fit a `u128`.
    pub(crate) const fn shr(self, s: u32) -> Option<u128> {
        if s == 0 {
            return if self.hi == 0 { Some(self.lo) } else { None };
        }
        if self.hi >> s != 0 {
            return None;
        }
        Some((self.lo >> s) | (self.hi << (128 - s)))
    }

    /// `self · 2^s` for `s < 128`, or `None` on overflow.
    pub(crate) const fn shl_by(self, s: u32) -> Option<U256> {
        if s == 0 {
            return Some(self);
        }
        if self.hi >> (128 - s) != 0 {
            return None;
        }
        Some(U256 {
            hi: (self.hi << s) | (self.lo >> (128 - s)),
            lo: self.lo << s,
        })
    }

    /// `self + n`, or `None` on overflow.
    #[cfg(test)]
    pub(crate) const fn add(self, n: u128) -> Option<U256> {
        let (lo, carry) = self.lo.overflowing_add(n);
        match self.hi.checked_add(carry as u128) {
            Some(hi) => Some(U256 { hi, lo }),
            None => None,
        }
    }

    /// `⌊self / d⌋`, saturating at `u128::MAX` (and for `d = 0`).
    pub(crate) const fn div(self, d: u128) -> u128 {
        if d == 0 || self.hi >= d {
            return u128::MAX;
        }
        if self.hi == 0 {
            return self.lo / d;
        }
        // Restoring division, one quotient bit per step; the running
        // remainder stays below 2d, its 129th bit kept in `carry`.
        let mut r = self.hi;
        let mut q: u128 = 0;
        let mut i = 128;
        while i > 0 {
            i -= 1;
            let carry = r >> 127;
            r = (r << 1) | ((self.lo >> i) & 1);
            q <<= 1;
            if carry != 0 || r >= d {
                r = r.wrapping_sub(d);
                q |= 1;
            }
        }
        q
    }

    /// `⌊√self⌋`.
    pub(crate) const fn sqrt(self) -> u128 {
        if self.hi == 0 {
            return isqrt(self.lo) as u128;
        }
        // From above: (√hi + 1)·2⁶⁴ ≥ √self, and Newton's iteration
        // x ← ⌊(x + ⌊n/x⌋)/2⌋ decreases to ⌊√n⌋ from any x ≥ ⌊√n⌋.
        let top = isqrt(self.hi) as u128;
        let mut x = if top == u64::MAX as u128 {
            u128::MAX
        } else {
            (top + 1) << 64
        };
        loop {
            // x ≥ ⌊√n⌋ ≥ 2⁶⁴: n/x < 2¹²⁸ fits, and hi < x.
            let q = self.div(x);
            let y = (x >> 1) + (q >> 1) + (x & q & 1);
            if y >= x {
                return x;
            }
            x = y;
        }
    }
}

/// `⌊a · b / d⌋`, saturating at `u128::MAX`.
pub(crate) const fn mul_div(a: u128, b: u128, d: u128) -> u128 {
    U256::mul(a, b).div(d)
}

/// `⌊n · 2^s / d⌋` for `s < 128`, saturating at `u128::MAX`.
pub(crate) const fn shl_div(n: u128, s: u32, d: u128) -> u128 {
    U256::shl(n, s).div(d)
}

/// `⌊a · b / 2^s⌋` for `s < 128`, saturating at `u128::MAX`.
pub(crate) const fn mul_shr(a: u128, b: u128, s: u32) -> u128 {
    match U256::mul(a, b).shr(s) {
        Some(v) => v,
        None => u128::MAX,
    }
}

/// `⌊√(n · 2^s)⌋` for `s < 128` (`s` even keeps the root's binary point
/// whole: a Q`2f` square gives a Q`f` root).
pub(crate) const fn sqrt_shl(n: u128, s: u32) -> u128 {
    U256::shl(n, s).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A reference in four 64-bit limbs, by schoolbook long division.
    fn limbs(n: U256) -> [u64; 4] {
        [
            n.lo as u64,
            (n.lo >> 64) as u64,
            n.hi as u64,
            (n.hi >> 64) as u64,
        ]
    }

    #[test]
    fn products_and_extremes() {
        let m = U256::mul(u128::MAX, u128::MAX);
        // (2¹²⁸ − 1)² = 2²⁵⁶ − 2¹²⁹ + 1.
        assert_eq!(m.lo, 1);
        assert_eq!(m.hi, u128::MAX - 1);
        assert_eq!(limbs(U256::mul(1 << 64, 1 << 64)), [0, 0, 1, 0]);
        assert_eq!(U256::mul(3, 5), U256 { hi: 0, lo: 15 });
        assert_eq!(U256::shl(1, 127).shr(127), Some(1));
        assert_eq!(U256::shl(u128::MAX, 1).shr(0), None);
        assert_eq!(U256::shl(u128::MAX, 1).shr(1), Some(u128::MAX));
        assert_eq!(m.div(u128::MAX), u128::MAX);
        assert_eq!(U256::shl(1, 100).div(0), u128::MAX);
        assert_eq!(U256::mul(u128::MAX, 7).div(7), u128::MAX);
        assert_eq!(U256::mul(u128::MAX, 7).div(u128::MAX), 7);
        assert_eq!(U256::mul(u128::MAX, u128::MAX).sqrt(), u128::MAX);
        assert_eq!(U256::shl(1, 127).sqrt(), 13_043_817_825_332_782_212);
    }

    proptest! {
        #[test]
        fn division_is_the_floor(a in any::<u128>(), b in any::<u128>(), d in 1..=u128::MAX) {
            let n = U256::mul(a, b);
            let q = n.div(d);
            if n.hi >= d {
                prop_assert_eq!(q, u128::MAX);
            } else {
                // q·d ≤ n < (q+1)·d
                let qd = U256::mul(q, d);
                prop_assert!(qd <= n);
                let next = qd.add(d);
                prop_assert!(next.is_none_or(|v| v > n));
            }
        }

        #[test]
        fn root_is_the_floor(a in any::<u128>(), b in any::<u128>()) {
            let n = U256::mul(a, b);
            let r = n.sqrt();
            prop_assert!(U256::mul(r, r) <= n);
            if let Some(r1) = r.checked_add(1) {
                prop_assert!(U256::mul(r1, r1) > n);
            }
        }

        #[test]
        fn small_values_agree_with_u128(a in 0..(1u128 << 64), b in 0..(1u128 << 64), d in 1..u128::MAX) {
            prop_assert_eq!(mul_div(a, b, d), a * b / d);
            prop_assert_eq!(mul_shr(a, b, 7), (a * b) >> 7);
        }
    }
}
