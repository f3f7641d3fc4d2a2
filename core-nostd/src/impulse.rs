//! Impulses, impulse prices and the quantizer with residual carry.
//!
//! The 1977 rule (Kosenko, ch. III §3) carries the remainder of every segment
//! into the next. Its closed form is what this module computes: the impulse
//! position of an axis at a point is `Q(P / h)`, `P` the exact commanded
//! coordinate since the program zero and `h` the axis price, `Q` rounding half
//! away from zero. A block issues the difference of two such positions, so the
//! error never exceeds half an impulse and never grows, however many blocks
//! follow.

use crate::length::{div_round_half_away, Length};
use core::fmt;

/// The largest impulse position an axis register may hold (either sign).
pub const MAX_POSITION: i32 = 999_999_999;

/// The largest number of impulses one axis may move in one linear block.
pub const MAX_BLOCK_IMPULSES: u32 = 1_000_000;

/// The smallest allowed impulse price: 0.000001 mm (1 nm).
pub const MIN_PRICE: ImpulsePrice = ImpulsePrice { angstrom: 10 };

/// The largest allowed impulse price: 1 mm.
pub const MAX_PRICE: ImpulsePrice = ImpulsePrice {
    angstrom: 10_000_000,
};

/// A result or a position beyond what the machine can hold (`ERR RANGE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RangeError;

impl fmt::Display for RangeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("beyond the machine's range")
    }
}

/// A signed count of impulses (axis steps).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Impulses(pub i32);

impl Impulses {
    /// The count as an integer.
    pub const fn get(self) -> i32 {
        self.0
    }
}

impl fmt::Display for Impulses {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.0, f)
    }
}

/// The length of one impulse of an axis (X on the radius), between
/// [`MIN_PRICE`] and [`MAX_PRICE`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ImpulsePrice {
    angstrom: i64,
}

impl ImpulsePrice {
    /// The seed machines' cross-slide price: 0.005 mm on the radius.
    pub const DEFAULT_X: ImpulsePrice = ImpulsePrice { angstrom: 50_000 };
    /// The seed machines' carriage price: 0.01 mm.
    pub const DEFAULT_Z: ImpulsePrice = ImpulsePrice { angstrom: 100_000 };

    /// A price from a length, if it lies between [`MIN_PRICE`] and
    /// [`MAX_PRICE`].
    ///
    /// ```
    /// use core_nostd::{impulse::ImpulsePrice, length::Length};
    /// let h = ImpulsePrice::from_length(Length::from_mm_str("0.005").unwrap()).unwrap();
    /// assert_eq!(h, ImpulsePrice::DEFAULT_X);
    /// assert!(ImpulsePrice::from_length(Length::ZERO).is_none());
    /// ```
    pub const fn from_length(length: Length) -> Option<ImpulsePrice> {
        let a = length.as_angstrom();
        if a >= MIN_PRICE.angstrom && a <= MAX_PRICE.angstrom {
            Some(ImpulsePrice { angstrom: a })
        } else {
            None
        }
    }

    /// The price as a length.
    pub const fn as_length(self) -> Length {
        // Within MAX_PRICE, always representable.
        match Length::from_angstrom(self.angstrom) {
            Some(l) => l,
            None => Length::ZERO,
        }
    }

    /// The price in ångström (10⁻⁷ mm).
    pub const fn as_angstrom(self) -> i64 {
        self.angstrom
    }
}

/// The impulse position of an axis at exact coordinate `p`: `Q(p / h)`,
/// rounded half away from zero, or [`RangeError`] beyond [`MAX_POSITION`].
///
/// ```
/// use core_nostd::{impulse::{quantize, ImpulsePrice, Impulses}, length::Length};
/// let mm = |s| Length::from_mm_str(s).unwrap();
/// let h = ImpulsePrice::DEFAULT_X;
/// assert_eq!(quantize(mm("0.0025"), h), Ok(Impulses(1)));   // a tie: away from zero
/// assert_eq!(quantize(mm("-0.0025"), h), Ok(Impulses(-1)));
/// assert_eq!(quantize(mm("0.002499"), h), Ok(Impulses(0)));
/// ```
pub const fn quantize(p: Length, h: ImpulsePrice) -> Result<Impulses, RangeError> {
    let n = div_round_half_away(p.as_angstrom(), h.angstrom);
    if n.unsigned_abs() <= MAX_POSITION as u64 {
        Ok(Impulses(n as i32))
    } else {
        Err(RangeError)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mm(s: &str) -> Length {
        Length::from_mm_str(s).unwrap()
    }

    #[test]
    fn seed_carry_example_never_accumulates() {
        // Kosenko: a run of 0.013 mm segments at 0.005 mm: 2.6 impulses each.
        // The carried remainder makes the k-th point land on Q(k·2.6).
        let h = ImpulsePrice::DEFAULT_X;
        let step = mm("0.013");
        let mut p = Length::ZERO;
        let mut issued = 0i64;
        for k in 1..=1000i64 {
            let before = quantize(p, h).unwrap().get();
            p = p.checked_add(step).unwrap();
            let after = quantize(p, h).unwrap().get();
            issued += i64::from(after - before);
            // Exact value: k·13/5 impulses; the error stays within half an impulse.
            let err2 = (issued * 5 - k * 13).abs() * 2;
            assert!(err2 <= 5, "k={k} issued={issued}");
        }
        assert_eq!(issued, 2600);
    }

    #[test]
    fn range_is_enforced() {
        let h = ImpulsePrice::from_length(mm("0.000001")).unwrap();
        assert_eq!(quantize(mm("999.999999"), h), Ok(Impulses(999_999_999)));
        assert_eq!(quantize(mm("1000"), h), Err(RangeError));
        assert_eq!(quantize(mm("-1000"), h), Err(RangeError));
        assert!(ImpulsePrice::from_length(mm("1.000001")).is_none());
        assert!(ImpulsePrice::from_length(mm("-0.005")).is_none());
    }
}
