//! Fixed-point trigonometry, integer-only (the Cortex-M4F has no
//! double-precision unit, and single precision is far too coarse).
//!
//! # Formats
//! - [`Turn`]: an angle as a `u64` fraction of a full turn (2⁶⁴ = 360°).
//!   Reduction is wrapping addition; the quadrant is the top two bits; 90°,
//!   180°, 270° and 45° are exact. Angles the protocol reads exactly (whole
//!   micro-arcseconds, so decimal degrees with 6 decimals and `D:M:S`) are
//!   converted with one rounding, at most 2⁻⁶⁵ turn.
//! - [`Q62`]: a signed `i64` with 62 fractional bits (`fixed::types::I2F62`),
//!   for sines and cosines in [−1, 1].
//!
//! # Methods
//! - [`sin_cos`]: exact octant reduction, then Taylor series of sin and cos
//!   on [0, π/4] to x¹⁹ and x²⁰ in Horner form, every product rounded in
//!   `i128` (the first omitted terms are below 2⁻⁷⁰).
//! - [`atan2`]: exact octant reduction of the integer vector, normalised to
//!   62 bits, then 62 CORDIC vectoring steps with a table of atan 2⁻ⁱ in turns
//!   computed at compile time (the series for i ≥ 1 holds exact powers of two
//!   in Q120).
//! - [`isqrt`]: exact integer square root (floor) of a `u128`.
//!
//! # Error bounds (each shown by a test in this module)
//! | function | bound |
//! |---|---|
//! | `sin_cos` | ≤ 2⁻⁵⁸ absolute (3.5·10⁻¹⁸), exact at multiples of 90° |
//! | `atan2` | ≤ 2⁻⁵⁴ turn (3.5·10⁻¹⁶ degrees), exact on the axes and diagonals |
//! | `isqrt` | exact floor |
//!
//! On a 100 m radius (10¹² Å) a sine error of 2⁻⁵⁸ is 3.5·10⁻⁶ Å: a chord end
//! lands within 10⁻¹² mm of its exact place.

use crate::wide::divrem_u128;
pub use crate::wide::isqrt;
use core::num::NonZeroU128;
use fixed::types::I2F62;

/// 2⁶² as a `Q62`: one.
pub const ONE_Q62: i64 = 1 << 62;

/// Sines and cosines: 62 fractional bits.
pub type Q62 = I2F62;

/// π/4 · 2⁶⁴, rounded.
const PI4_Q64: u128 = 14_488_038_916_154_245_685;
/// π · 2⁶¹, rounded.
pub(crate) const PI_Q61: u128 = 7_244_019_458_077_122_842;

/// Micro-arcseconds in a full turn (360 · 3600 · 10⁶).
pub const FULL_TURN_UAS: i64 = 1_296_000_000_000;

/// An angle as a fraction of a full turn: 2⁶⁴ = 360°, wrapping.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Turn(pub u64);

impl Turn {
    /// 90°.
    pub const QUARTER: Turn = Turn(1 << 62);
    /// 180°.
    pub const HALF: Turn = Turn(1 << 63);

    /// An angle from whole micro-arcseconds (any sign, any size), rounded to
    /// the nearest 2⁻⁶⁴ turn.
    ///
    /// ```
    /// use core_nostd::trig::Turn;
    /// assert_eq!(Turn::from_uas(90 * 3600 * 1_000_000), Turn::QUARTER);
    /// assert_eq!(Turn::from_uas(-180 * 3600 * 1_000_000), Turn::HALF);
    /// ```
    pub const fn from_uas(uas: i64) -> Turn {
        let r = uas.rem_euclid(FULL_TURN_UAS) as u128;
        let full = FULL_TURN_UAS as u128;
        // r < 2⁴¹: r·2⁶⁴ fits; a result of 2⁶⁴ wraps to 0 (= 360°).
        let full_nz = match NonZeroU128::new(full) {
            Some(f) => f,
            None => NonZeroU128::MIN,
        };
        Turn(divrem_u128((r << 64) + full / 2, full_nz).0 as u64)
    }

    /// An angle from whole arc-seconds.
    pub const fn from_arcsec(arcsec: i64) -> Turn {
        Turn::from_uas(arcsec.rem_euclid(1_296_000) * 1_000_000)
    }

    /// The angle in micro-arcseconds times 2⁶⁴ (an exact product, for exact
    /// comparisons with whole arc-seconds).
    pub const fn as_uas_q64(self) -> u128 {
        self.0 as u128 * FULL_TURN_UAS as u128
    }

    /// Wrapping sum.
    pub const fn wrapping_add(self, other: Turn) -> Turn {
        Turn(self.0.wrapping_add(other.0))
    }

    /// Wrapping difference.
    pub const fn wrapping_sub(self, other: Turn) -> Turn {
        Turn(self.0.wrapping_sub(other.0))
    }
}

/// `a·b` in Q62, rounded.
const fn mul_q62(a: i64, b: i64) -> i64 {
    ((a as i128 * b as i128 + (1 << 61)) >> 62) as i64
}

/// `a / d` for a small positive `d`, rounded half away from zero.
const fn div_small(a: i64, d: i64) -> i64 {
    // d is one of the series' constants, never zero; |a| ≤ 2⁶³ − 1.
    let h = d / 2;
    match (a.unsigned_abs() + h.unsigned_abs()).checked_div(d.unsigned_abs()) {
        Some(q) if a >= 0 => q as i64,
        Some(q) => -(q as i64),
        None => 0,
    }
}

/// sin and cos of `x` in Q62, `0 ≤ x ≤ π/4`.
const fn sin_cos_octant(x: i64) -> (i64, i64) {
    let x2 = mul_q62(x, x);
    // sin x = x(1 − x²/(2·3)(1 − x²/(4·5)(1 − …))), to the x¹⁹ term.
    let mut s = ONE_Q62;
    let mut k = 9;
    while k >= 1 {
        s = ONE_Q62 - div_small(mul_q62(x2, s), (2 * k) * (2 * k + 1));
        k -= 1;
    }
    // cos x = 1 − x²/(1·2)(1 − x²/(3·4)(1 − …)), to the x²⁰ term.
    let mut c = ONE_Q62;
    let mut k = 10;
    while k >= 1 {
        c = ONE_Q62 - div_small(mul_q62(x2, c), (2 * k - 1) * (2 * k));
        k -= 1;
    }
    (mul_q62(x, s), c)
}

/// Sine and cosine of an angle, in Q62 (raw `i64`).
///
/// ```
/// use core_nostd::trig::{sin_cos_raw, Turn, ONE_Q62};
/// assert_eq!(sin_cos_raw(Turn::QUARTER), (ONE_Q62, 0));
/// let (s, _) = sin_cos_raw(Turn::from_uas(30 * 3600 * 1_000_000));
/// assert!((s - ONE_Q62 / 2).abs() <= 16); // sin 30° = ½ within 2⁻⁵⁸
/// ```
pub const fn sin_cos_raw(a: Turn) -> (i64, i64) {
    let quadrant = a.0 >> 62;
    let r = a.0 & ((1 << 62) - 1);
    let flip = r > (1 << 61);
    let r = if flip { (1 << 62) - r } else { r };
    // θ = r·2π/2⁶⁴ rad; in Q62 that is r·π/2 = r·(π/4·2⁶⁴)/2⁶³.
    let x = ((r as u128 * PI4_Q64 + (1 << 62)) >> 63) as i64;
    let (s, c) = sin_cos_octant(x);
    let (s, c) = if flip { (c, s) } else { (s, c) };
    match quadrant {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// Sine and cosine of a whole number of arc-seconds, in Q62 (raw `i64`):
/// exact where they are rational (0, ±½, ±1 at multiples of 30°), so a
/// point that lies exactly on a rounding boundary is found on it; elsewhere
/// as [`sin_cos_raw`].
///
/// ```
/// use core_nostd::trig::{sin_cos_arcsec, ONE_Q62};
/// assert_eq!(sin_cos_arcsec(120 * 3600).1, -ONE_Q62 / 2); // cos 120° = −½
/// assert_eq!(sin_cos_arcsec(-30 * 3600).0, -ONE_Q62 / 2);
/// ```
pub const fn sin_cos_arcsec(arcsec: i64) -> (i64, i64) {
    const STEP: i64 = 30 * 3600;
    let a = arcsec.rem_euclid(1_296_000);
    let (s, c) = sin_cos_raw(Turn::from_arcsec(a));
    if a % STEP != 0 {
        return (s, c);
    }
    let k = a / STEP;
    (exact_at_30(k, s), exact_at_30(k + 3, c))
}

/// sin k·30°, exact where it is rational, else `computed`.
const fn exact_at_30(k: i64, computed: i64) -> i64 {
    // In halves; 3 marks √3/2.
    const HALVES: [i64; 12] = [0, 1, 3, 2, 3, 1, 0, -1, -3, -2, -3, -1];
    match HALVES[k.rem_euclid(12) as usize] {
        3 | -3 => computed,
        h => h * (ONE_Q62 / 2),
    }
}

/// Sine and cosine of an angle as [`Q62`] values.
pub fn sin_cos(a: Turn) -> (Q62, Q62) {
    let (s, c) = sin_cos_raw(a);
    (Q62::from_bits(s), Q62::from_bits(c))
}

/// atan 2⁻ⁱ in turns (2⁶⁴ = 360°), i = 0 … 63.
const ATAN_TURN: [i64; 64] = {
    let mut t = [0i64; 64];
    t[0] = 1 << 61; // 45°
    let mut i = 1;
    while i < 64 {
        // atan x = Σ (−1)ᵏ x²ᵏ⁺¹/(2k+1), x = 2⁻ⁱ, in Q120: the powers are exact.
        let mut sum: i128 = 0;
        let mut k = 0;
        while (2 * k + 1) * i < 120 {
            let term = (1i128 << (120 - (2 * k + 1) * i)) / (2 * k + 1) as i128;
            sum += if k % 2 == 0 { term } else { -term };
            k += 1;
        }
        // turns·2⁶⁴ = atan/(2π)·2⁶⁴ = atan_Q120·16/(π·2⁶¹).
        t[i] = ((sum as u128 * 16 + PI_Q61 / 2) / PI_Q61) as i64;
        i += 1;
    }
    t
};

/// The angle of the vector `(x, y)` from the positive x axis,
/// counter-clockwise, in `[0°, 360°)`; `(0, 0)` gives 0.
///
/// ```
/// use core_nostd::trig::{atan2, Turn};
/// assert_eq!(atan2(0, -5), Turn::HALF);
/// assert_eq!(atan2(-7, 7), Turn(7 << 61)); // 315°
/// ```
pub fn atan2(y: i128, x: i128) -> Turn {
    if x == 0 && y == 0 {
        return Turn(0);
    }
    let (ax, ay) = (x.unsigned_abs(), y.unsigned_abs());
    // First-octant angle of (big, small), then mirror back.
    let swapped = ay > ax;
    let (big, small) = if swapped { (ay, ax) } else { (ax, ay) };
    let octant = if small == 0 {
        0
    } else if small == big {
        1 << 61
    } else {
        cordic_octant(big, small)
    };
    let a = if swapped {
        (1u64 << 62) - octant
    } else {
        octant
    };
    Turn(match (x >= 0, y >= 0) {
        (true, true) => a,
        (false, true) => (1u64 << 63) - a,
        (false, false) => (1u64 << 63) + a,
        (true, false) => 0u64.wrapping_sub(a),
    })
}

/// atan(small/big) in turns for `0 < small < big`.
fn cordic_octant(big: u128, small: u128) -> u64 {
    // Normalise so that big lies in [2⁶⁰, 2⁶¹): x grows by the CORDIC gain
    // (< 1.65) and stays below 2⁶².
    let lz = big.leading_zeros() as i32; // big ≥ 1
    let shift = lz - (128 - 61);
    let (mut x, mut y) = if shift >= 0 {
        ((big << shift) as i64, (small << shift) as i64)
    } else {
        let s = (-shift) as u32;
        ((big >> s) as i64, (small >> s) as i64)
    };
    let mut z: i64 = 0;
    let mut i = 0;
    while i < 62 {
        let (dx, dy) = (y >> i, x >> i);
        if y > 0 {
            x += dx;
            y -= dy;
            z += ATAN_TURN[i];
        } else if y < 0 {
            x -= dx;
            y += dy;
            z -= ATAN_TURN[i];
        } else {
            break;
        }
        i += 1;
    }
    z.clamp(0, 1 << 61) as u64
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    #[test]
    fn whole_arc_seconds_are_exact_where_sine_and_cosine_are_rational() {
        let half = ONE_Q62 / 2;
        for k in -24i64..=24 {
            let (s, c) = sin_cos_arcsec(k * 30 * 3600);
            let (rs, rc) = sin_cos_raw(Turn::from_arcsec(k * 30 * 3600));
            // Within the series' error of the computed values everywhere.
            assert!((s - rs).abs() <= 16 && (c - rc).abs() <= 16, "{k}");
            let want = |m: i64| match m.rem_euclid(12) {
                0 | 6 => Some(0),
                1 | 5 => Some(half),
                7 | 11 => Some(-half),
                3 => Some(ONE_Q62),
                9 => Some(-ONE_Q62),
                _ => None,
            };
            if let Some(w) = want(k) {
                assert_eq!(s, w, "sin {}°", k * 30);
            }
            if let Some(w) = want(k + 3) {
                assert_eq!(c, w, "cos {}°", k * 30);
            }
        }
        // Off the 30° grid: the series.
        assert_eq!(sin_cos_arcsec(7), sin_cos_raw(Turn::from_arcsec(7)));
    }
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn isqrt_is_the_floor_square_root(n in any::<u128>()) {
            let r = u128::from(isqrt(n));
            prop_assert!(r * r <= n);
            prop_assert!((r + 1).checked_mul(r + 1).is_none_or(|s| s > n));
        }
    }

    const BOUND_SIN: i64 = 1 << 4; // 2⁻⁵⁸ in Q62 ulps
    const BOUND_TURN: u64 = 1 << 10; // 2⁻⁵⁴ turn

    fn turn_diff(a: Turn, b: Turn) -> u64 {
        let d = a.0.wrapping_sub(b.0);
        d.min(d.wrapping_neg())
    }

    #[test]
    fn exact_angles() {
        for (deg, s, c) in [
            (0, 0, ONE_Q62),
            (90, ONE_Q62, 0),
            (180, 0, -ONE_Q62),
            (270, -ONE_Q62, 0),
        ] {
            assert_eq!(
                sin_cos_raw(Turn::from_uas(deg * 3_600_000_000)),
                (s, c),
                "{deg}°"
            );
        }
        // sin 30° = cos 60° = ½; sin 45° = cos 45° = √2/2 = 2⁶¹·√2 (√ of 2¹²³).
        let half = ONE_Q62 / 2;
        let (s30, _) = sin_cos_raw(Turn::from_uas(30 * 3_600_000_000));
        let (_, c60) = sin_cos_raw(Turn::from_uas(60 * 3_600_000_000));
        assert!((s30 - half).abs() <= BOUND_SIN && (c60 - half).abs() <= BOUND_SIN);
        let root_half = isqrt(1u128 << 123) as i64;
        let (s45, c45) = sin_cos_raw(Turn(1 << 61));
        assert!((s45 - root_half).abs() <= BOUND_SIN, "{s45} {root_half}");
        assert!((c45 - root_half).abs() <= BOUND_SIN);
    }

    #[test]
    fn atan2_exact_directions() {
        assert_eq!(atan2(0, 3), Turn(0));
        assert_eq!(atan2(3, 0), Turn::QUARTER);
        assert_eq!(atan2(0, -3), Turn::HALF);
        assert_eq!(atan2(-3, 0), Turn(3 << 62));
        assert_eq!(atan2(5, 5), Turn(1 << 61));
        assert_eq!(atan2(5, -5), Turn(3 << 61));
        assert_eq!(atan2(-5, -5), Turn(5 << 61));
        assert_eq!(atan2(0, 0), Turn(0));
    }

    #[test]
    fn atan_table_matches_f64() {
        for (i, &t) in ATAN_TURN.iter().enumerate().take(40) {
            let f = libm::atan(libm::ldexp(1.0, -(i as i32))) / (2.0 * core::f64::consts::PI);
            let got = t as f64 / 18_446_744_073_709_551_616.0;
            // The table's own rounding is 2⁻⁶⁴ turn; f64's is about one ulp.
            assert!(
                (got - f).abs() <= 2.0 * f64::EPSILON * f + 1.0 / 18_446_744_073_709_551_616.0,
                "{i}"
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        /// sin² + cos² = 1 and the double-angle identities hold to the bound,
        /// which checks the result well beyond what an f64 comparison could.
        #[test]
        fn identities_hold_to_the_bound(t in any::<u64>()) {
            let (s, c) = sin_cos_raw(Turn(t));
            let one = mul_q62(s, s) + mul_q62(c, c);
            prop_assert!((one - ONE_Q62).abs() <= 4 * BOUND_SIN, "{}", one - ONE_Q62);
            let (s2, c2) = sin_cos_raw(Turn(t.wrapping_mul(2)));
            prop_assert!((s2 - 2 * mul_q62(s, c)).abs() <= 4 * BOUND_SIN);
            prop_assert!((c2 - (mul_q62(c, c) - mul_q62(s, s))).abs() <= 4 * BOUND_SIN);
        }

        /// Against f64, whose own error (the angle in radians rounded, then
        /// sin or cos) is about 10⁻¹⁵ here: a coarse cross-check of
        /// quadrants and signs; the identities above carry the bound.
        #[test]
        fn agrees_with_f64(uas in -FULL_TURN_UAS..FULL_TURN_UAS) {
            let (s, c) = sin_cos_raw(Turn::from_uas(uas));
            let rad = uas as f64 / FULL_TURN_UAS as f64 * 2.0 * core::f64::consts::PI;
            let q = ONE_Q62 as f64;
            prop_assert!((s as f64 / q - libm::sin(rad)).abs() < 2e-15);
            prop_assert!((c as f64 / q - libm::cos(rad)).abs() < 2e-15);
        }

        /// atan2 inverts sin_cos to the bound, at every scale of the vector.
        #[test]
        fn atan2_inverts(t in any::<u64>(), scale in 0u32..60) {
            let (s, c) = sin_cos_raw(Turn(t));
            let (y, x) = ((s as i128) << scale, (c as i128) << scale);
            let back = atan2(y, x);
            prop_assert!(turn_diff(back, Turn(t)) <= BOUND_TURN, "{}", turn_diff(back, Turn(t)));
        }

        #[test]
        fn isqrt_is_floor(n in any::<u128>()) {
            let r = isqrt(n) as u128;
            prop_assert!(r * r <= n);
            prop_assert!((r + 1).checked_mul(r + 1).is_none_or(|sq| sq > n));
        }
    }
}
