//! 256-bit intermediates for the motion planner's fixed-point arithmetic:
//! products of two `u128`, quotients and square roots of such products.
//!
//! Every function is exact (floor) and total: a quotient that does not fit
//! a `u128` saturates at `u128::MAX` (the planner only takes minima of such
//! values, where a saturated term never wins), and a division by zero gives
//! `u128::MAX` too. Shifts, compares and subtractions only in the divisions
//! and roots, as [`isqrt`] (a Cortex-M4 has no 64-bit divide).

use core::cmp::Ordering;
use core::num::NonZeroU128;

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

    /// `self >> s`, floor; `None` if it does not fit a `u128`.
    pub(crate) const fn shr(self, s: u32) -> Option<u128> {
        if s >= 256 {
            return Some(0);
        }
        if s >= 128 {
            return Some(self.hi >> (s - 128));
        }
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
    ///
    /// Long division in 32-bit digits (Knuth's algorithm D): each quotient
    /// digit is estimated from the top two digits of the remainder by one
    /// 64-by-32-bit division and corrected at most twice, so a quotient
    /// costs a handful of digit steps instead of 128 bit steps.
    pub(crate) const fn div(self, d: u128) -> u128 {
        if d == 0 || self.hi >= d {
            return u128::MAX;
        }
        if self.hi == 0 && self.lo >> 64 == 0 && d >> 64 == 0 {
            return ((self.lo as u64) / (d as u64)) as u128;
        }
        // Digits, least significant first: u has one spare digit on top
        // (indices are masked to the arrays' sizes, which they never exceed,
        // so that no bounds check remains).
        let mut u = [0u32; 16];
        let mut i = 0;
        while i < 4 {
            u[i] = (self.lo >> (32 * i)) as u32;
            u[i + 4] = (self.hi >> (32 * i)) as u32;
            i += 1;
        }
        let mut v = [0u32; 4];
        let mut n = 0;
        i = 0;
        while i < 4 {
            v[i] = (d >> (32 * i)) as u32;
            if v[i] != 0 {
                n = i + 1;
            }
            i += 1;
        }
        let mut m = 8;
        while m > 0 && u[(m - 1) & 15] == 0 {
            m -= 1;
        }
        if m < n {
            return 0;
        }
        if n == 1 {
            // One-digit divisor: short division.
            let dv = v[0] as u64;
            let mut q: u128 = 0;
            let mut r: u64 = 0;
            let mut j = m;
            while j > 0 {
                j -= 1;
                let num = (r << 32) | u[j & 15] as u64;
                // dv ≠ 0 (n = 1 counts its digit); no division by zero.
                let qd = match num.checked_div(dv) {
                    Some(q) => q,
                    None => return u128::MAX,
                };
                r = num - qd * dv;
                // Digits above the fourth are 0: the quotient fits.
                if j < 4 {
                    q |= (qd as u128) << (32 * j);
                }
            }
            return q;
        }
        // Normalise: the divisor's top digit gets its top bit set.
        let sh = v[(n - 1) & 3].leading_zeros();
        if sh > 0 {
            let mut k = n - 1;
            while k > 0 {
                v[k & 3] = (v[k & 3] << sh) | (v[(k - 1) & 3] >> (32 - sh));
                k -= 1;
            }
            v[0] <<= sh;
            u[m & 15] = u[(m - 1) & 15] >> (32 - sh);
            let mut k = m - 1;
            while k > 0 {
                u[k & 15] = (u[k & 15] << sh) | (u[(k - 1) & 15] >> (32 - sh));
                k -= 1;
            }
            u[0] <<= sh;
        } else {
            u[m & 15] = 0;
        }
        let top = v[(n - 1) & 3] as u64;
        let next = v[(n - 2) & 3] as u64;
        let mut q: u128 = 0;
        let mut j = m - n + 1;
        while j > 0 {
            j -= 1;
            let num = ((u[(j + n) & 15] as u64) << 32) | u[(j + n - 1) & 15] as u64;
            // top ≥ 2³¹ after normalising; no division by zero.
            let mut qhat = match num.checked_div(top) {
                Some(q) => q,
                None => return u128::MAX,
            };
            let mut rhat = num - qhat * top;
            while qhat >> 32 != 0 || qhat * next > ((rhat << 32) | u[(j + n - 2) & 15] as u64) {
                qhat -= 1;
                rhat += top;
                if rhat >> 32 != 0 {
                    break;
                }
            }
            // u[j ..= j+n] −= qhat · v
            let mut borrow: i64 = 0;
            let mut carry: u64 = 0;
            let mut k = 0;
            while k < n {
                let p = qhat * v[k & 3] as u64 + carry;
                carry = p >> 32;
                let t = u[(k + j) & 15] as i64 - borrow - (p & 0xFFFF_FFFF) as i64;
                u[(k + j) & 15] = t as u32;
                borrow = if t < 0 { 1 } else { 0 };
                k += 1;
            }
            let t = u[(j + n) & 15] as i64 - borrow - carry as i64;
            u[(j + n) & 15] = t as u32;
            if t < 0 {
                // One too many: add the divisor back.
                qhat -= 1;
                let mut c: u64 = 0;
                let mut k = 0;
                while k < n {
                    let s = u[(k + j) & 15] as u64 + v[k & 3] as u64 + c;
                    u[(k + j) & 15] = s as u32;
                    c = s >> 32;
                    k += 1;
                }
                u[(j + n) & 15] = u[(j + n) & 15].wrapping_add(c as u32);
            }
            if j < 4 {
                q |= (qhat as u128) << (32 * j);
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

/// `(n / d, n % d)`, by the long division of [`U256::div`]. Every 128-bit
/// quotient goes through here: a Cortex-M4 has no 128-bit divide, and each
/// `/` or `%` of a `u128` or `i128` would be expanded in place into a
/// bit-by-bit loop of some 700 bytes of flash.
#[inline(never)]
pub(crate) const fn divrem_u128(n: u128, d: NonZeroU128) -> (u128, u128) {
    let d = d.get();
    let q = if d as u64 == 0 {
        // d = e · 2⁶⁴ (a price in Å·2⁶⁴): ⌊n / d⌋ = ⌊⌊n / 2⁶⁴⌋ / e⌋, one
        // 64-bit division (e ≠ 0).
        match ((n >> 64) as u64).checked_div((d >> 64) as u64) {
            Some(q) => q as u128,
            None => 0,
        }
    } else {
        // The high half is 0 < d: the quotient fits and never saturates.
        U256 { hi: 0, lo: n }.div(d)
    };
    // q · d ≤ n.
    (q, n - q * d)
}

/// `(n / d, n % d)` truncated toward zero (the remainder takes the sign of
/// `n`), for a positive `d`: always defined.
#[inline(never)]
pub(crate) const fn divrem_i128(n: i128, d: NonZeroU128) -> (i128, i128) {
    let (q, r) = divrem_u128(n.unsigned_abs(), d);
    // r < |n| ≤ 2¹²⁷ fits. q = 2¹²⁷ only for n = i128::MIN, d = 1, whose
    // quotient is i128::MIN: the wrapping negation is exact there too.
    if n < 0 {
        ((q as i128).wrapping_neg(), (r as i128).wrapping_neg())
    } else {
        (q as i128, r as i128)
    }
}

/// `n.checked_div(d)` and `n.checked_rem(d)` together: `None` for `d = 0`
/// and for `i128::MIN / -1`.
pub(crate) const fn checked_divrem_i128(n: i128, d: i128) -> Option<(i128, i128)> {
    let Some(m) = NonZeroU128::new(d.unsigned_abs()) else {
        return None;
    };
    let (q, r) = divrem_i128(n, m);
    if d > 0 {
        return Some((q, r));
    }
    // n / d = −(n / |d|); n % d = n % |d|.
    match q.checked_neg() {
        Some(q) => Some((q, r)),
        None => None,
    }
}

/// `(n / d, n % d)`, `None` for `d = 0`: [`divrem_u128`] for a divisor
/// not known to be non-zero.
pub(crate) const fn udiv(n: u128, d: u128) -> Option<(u128, u128)> {
    match NonZeroU128::new(d) {
        Some(d) => Some(divrem_u128(n, d)),
        None => None,
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

/// `⌊a · b / 2^s⌋`, saturating at `u128::MAX`.
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

/// ⌊√n⌋, exact.
///
/// ```
/// use core_nostd::trig::isqrt;
/// assert_eq!(isqrt(0), 0);
/// assert_eq!(isqrt(99), 9);
/// assert_eq!(isqrt(u128::MAX), u64::MAX);
/// ```
#[inline(never)]
pub const fn isqrt(n: u128) -> u64 {
    // Digit by digit, two bits of `n` per result bit: shifts, compares and
    // subtractions only (a 128-bit division costs hundreds of instructions
    // on a Cortex-M4).
    let mut rest = n;
    let mut root: u128 = 0;
    let mut bit: u128 = if n == 0 {
        0
    } else {
        1 << ((127 - n.leading_zeros()) & !1)
    };
    while bit != 0 {
        if rest >= root + bit {
            rest -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    root as u64
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

    /// Restoring division, one bit per step: the reference for `div`.
    fn div_by_bits(n: U256, d: u128) -> u128 {
        if d == 0 || n.hi >= d {
            return u128::MAX;
        }
        let mut r = n.hi;
        let mut q: u128 = 0;
        let mut i = 128;
        while i > 0 {
            i -= 1;
            let carry = r >> 127;
            r = (r << 1) | ((n.lo >> i) & 1);
            q <<= 1;
            if carry != 0 || r >= d {
                r = r.wrapping_sub(d);
                q |= 1;
            }
        }
        q
    }

    #[test]
    fn long_division_on_digit_patterns() {
        // Digits that make the quotient estimate too large (and the rarer
        // add-back step) in every position.
        const D: [u32; 6] = [0, 1, 0x7FFF_FFFF, 0x8000_0000, 0xFFFF_FFFE, 0xFFFF_FFFF];
        let mut seed = 0x2545_F491_4F6C_DD1Du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let mut num = |digits: usize| {
            let mut v = [0u128; 2];
            for k in 0..digits {
                let dg = D[(next() % 6) as usize] as u128;
                v[k / 4] |= dg << (32 * (k % 4));
            }
            U256 { hi: v[1], lo: v[0] }
        };
        let mut full = 0;
        for k in 0..200_000 {
            let d = num(1 + k % 4).lo.max(1);
            let q = num(4).lo;
            let r = num(4).lo % d;
            // n = q·d + r: the quotient q fits, so every digit step runs.
            let Some(n) = U256::mul(q, d).add(r) else {
                continue;
            };
            full += usize::from(n.hi != 0);
            assert_eq!(n.div(d), q, "{n:?} / {d}");
            assert_eq!(n.div(d), div_by_bits(n, d), "{n:?} / {d}");
        }
        assert!(full > 50_000, "{full}");
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
        // Shifts of the high half and beyond.
        let n = U256::mul(u128::MAX, 3 << 100);
        assert_eq!(n.shr(128), Some((3 << 100) - 1));
        assert_eq!(n.shr(228), Some(2));
        assert_eq!(n.shr(255), Some(0));
        assert_eq!(n.shr(256), Some(0));
        assert_eq!(mul_shr(1 << 127, 1 << 127, 156), 1 << 98);
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
        fn long_division_equals_bit_division(a in any::<u128>(), b in any::<u128>(),
                                             shift in 0u32..128, d in 1..=u128::MAX, dsh in 0u32..127) {
            for n in [U256::mul(a, b), U256::mul(a >> shift, b >> (127 - shift.min(127)))] {
                for d in [d, d >> dsh, (d >> dsh).max(1), d | 1 << 127] {
                    prop_assert_eq!(n.div(d), div_by_bits(n, d), "{:?} / {}", n, d);
                }
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
        fn quotient_and_remainder_agree_with_the_operators(
            n in any::<i128>(), d in any::<i128>(), nsh in 0u32..127, dsh in 0u32..127,
        ) {
            for n in [n, n >> nsh, i128::MIN, i128::MAX, -1, 0, 1] {
                for d in [d, d >> dsh, d << 64, (d >> dsh) << 64, i128::MIN, i128::MAX, -1, 1, 2, -2] {
                    prop_assert_eq!(
                        checked_divrem_i128(n, d),
                        n.checked_div(d).zip(n.checked_rem(d)),
                        "{} / {}", n, d
                    );
                    let (un, ud) = (n as u128, d as u128);
                    if let Some(nz) = NonZeroU128::new(ud) {
                        prop_assert_eq!(divrem_u128(un, nz), (un / ud, un % ud));
                    }
                }
            }
        }

        #[test]
        fn small_values_agree_with_u128(a in 0..(1u128 << 64), b in 0..(1u128 << 64), d in 1..u128::MAX) {
            prop_assert_eq!(mul_div(a, b, d), a * b / d);
            prop_assert_eq!(mul_shr(a, b, 7), (a * b) >> 7);
        }
    }
}
